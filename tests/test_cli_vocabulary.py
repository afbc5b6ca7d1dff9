"""The CLI vocabulary (README "CLI vocabulary", ``mien.commands._vocabulary``): each old spelling parses to
exactly what its new spelling parses to and leaves one deprecation note; the new spellings leave none; the old
spellings are hidden from ``--help``; every command with progress has ``--quiet``; one fps policy."""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import pytest

from mien.cli import build_parser, main
from mien.commands._checks import PENDING_OUTPUTS
from mien.commands._vocabulary import ANIMATION_FPS, PENDING_DEPRECATIONS, VIDEO_FPS, finish


@pytest.fixture
def d(tmp_path: Path) -> Path:
    """A folder with a clip file, a non-empty stand-in for a design, a video and a model."""
    (tmp_path / "smile.csv").write_text("time_s,AU12L,AU12R\n0,0,0\n0.5,4,4\n1.0,0,0\n")
    (tmp_path / "design.toml").write_text("[study]\n")
    (tmp_path / "clip.mp4").write_bytes(b"\0\0\0\x18ftypmp42" + b"\0" * 64)
    (tmp_path / "model.task").write_bytes(b"model")
    (tmp_path / "videos").mkdir()
    (tmp_path / "labels.csv").write_text("video,type,performer\nclip.mp4,laughter,p1\n")
    return tmp_path


def parsed(argv: str, d: Path) -> tuple[dict[str, object], list[str]]:
    """(the handler's namespace, the deprecation notes) of ``mien ARGV`` (``{d}``: the fixture's folder)."""
    PENDING_DEPRECATIONS.clear()
    args = build_parser().parse_args(argv.replace("{d}", str(d)).split())
    finish(args)
    PENDING_OUTPUTS.clear()  # parsing only: no folder is made
    notes = list(PENDING_DEPRECATIONS)
    PENDING_DEPRECATIONS.clear()
    return vars(args), notes


RENAMED = [
    # (old spelling, new spelling, words of the note)
    ("demo --out {d}/o", "demo -o {d}/o", "--out is deprecated, use -o/--output"),
    ("validate rig --out {d}/o", "validate rig -o {d}/o", "--out is deprecated, use -o/--output"),
    ("export {d}/smile.csv {d}/o.json", "export {d}/smile.csv -o {d}/o.json", "positional output"),
    ("import {d}/smile.csv {d}/o.npz", "import {d}/smile.csv --output {d}/o.npz", "positional output"),
    ("study stimuli {d}/design.toml --stimuli {d}/s", "study stimuli {d}/design.toml -o {d}/s", "--stimuli"),
    ("study export {d}/design.toml --out {d}/a.csv", "study export {d}/design.toml -o {d}/a.csv", "--out"),
    ("study analyze {d}/design.toml --out {d}/r", "study analyze {d}/design.toml -o {d}/r", "--out"),
    ("study serve {d}/design.toml --port 0", "study serve {d}/design.toml --http-port 0", "--port"),
    ("assets fetch ict-facekit --dest {d}/ict", "assets fetch ict-facekit -o {d}/ict", "--dest"),
    ("track {d}/clip.mp4 --model {d}/model.task", "track {d}/clip.mp4 --landmarker {d}/model.task", "--model"),
    (
        "learn {d}/videos --labels {d}/labels.csv -o {d}/l.npz --model {d}/model.task",
        "learn {d}/videos --labels {d}/labels.csv -o {d}/l.npz --landmarker {d}/model.task",
        "--model is deprecated, use --landmarker",
    ),
    ("render joy --head builtin --identity b", "render joy --head builtin:b", "use --head HEAD:IDENTITY"),
    ("demo --identity b", "demo --head default:b", "--identity is deprecated"),
    ("serve --identity b", "serve --head default:b", "--identity is deprecated"),
    ("render joy --basis feature-points", "render joy --basis feature_points", "use --basis feature_points"),
    (
        "validate emotions --basis facs,feature-points",
        "validate emotions --basis facs,feature_points",
        "--basis feature-points is deprecated",
    ),
    ("send --emotion joy --port 5001", "send --emotion joy --udp-port 5001", "use --udp-port, or --http-port"),
    ("send --emotion joy --ws --port 8001", "send --emotion joy --ws --http-port 8001", "--port is deprecated"),
]


@pytest.mark.parametrize(("old", "new", "words"), RENAMED, ids=[row[0].split(" {")[0] for row in RENAMED])
def test_an_old_spelling_parses_as_the_new_one_with_a_note(old: str, new: str, words: str, d: Path) -> None:
    old_args, old_notes = parsed(old, d)
    new_args, new_notes = parsed(new, d)
    assert old_args == new_args
    assert new_notes == []
    assert len(old_notes) == 1 and words in old_notes[0], old_notes
    assert old_notes[0].startswith("warning: ") and old_notes[0].endswith("; it will be removed in 0.2")


def test_the_note_is_one_line_on_stderr_and_the_command_runs(d: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = d / "o.json"
    assert main(["export", str(d / "smile.csv"), str(out)]) == 0
    captured = capsys.readouterr()
    assert captured.err == (
        f"mien export: warning: the positional output ({out}) is deprecated, use -o/--output; "
        "it will be removed in 0.2\n"
    )
    assert out.stat().st_size > 0 and str(out) in captured.out


def test_a_usage_error_prints_only_the_error(d: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["demo", "--out", str(d / "o"), "--fps", "0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "deprecated" not in err and "'0'" in err


def test_head_and_identity(d: Path) -> None:
    assert parsed("render joy --head ict:b", d)[0]["identity"] == "b"
    args, _ = parsed("render joy", d)
    assert (args["head"], args["identity"]) == ("default", None)
    args, _ = parsed("export {d}/smile.csv -o {d}/o.json", d)
    assert (args["head"], args["identity"]) == (None, None)
    heads = parsed("validate emotions --head ict:a,builtin --head builtin:b", d)[0]["head"]
    assert heads == ["ict:a,builtin", "builtin:b"]


def test_a_head_file_stays_one_spec(d: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A head file's path may hold no identity: ``--head face.glb`` and ``--head file:face.glb`` reach load_head
    whole."""
    head = d / "face.glb"
    assert main(["export", str(d / "smile.csv"), "-o", str(head), "--head", "builtin"]) == 0
    for spec in (str(head), f"file:{head}"):
        args, notes = parsed(f"render joy --head {spec}", d)
        assert (args["head"], args["identity"], notes) == (spec, None, [])


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    (action,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(action.choices)


def _help(*path: str) -> str:
    parser = build_parser()
    for name in path:
        parser = _subparsers(parser)[name]
    return parser.format_help()


@pytest.mark.parametrize(
    ("path", "hidden", "shown"),
    [
        (("demo",), "--out ", "-o DIR, --output DIR"),
        (("export",), "--identity", "--head HEAD[:IDENTITY]"),
        (("track",), "--model", "--landmarker PATH"),
        (("send",), "--port ", "--udp-port"),
        (("study", "stimuli"), "--stimuli", "-o DIR, --output DIR"),
        (("assets", "fetch"), "--dest", "-o DIR, --output DIR"),
    ],
)
def test_help_shows_only_the_new_spellings(path: tuple[str, ...], hidden: str, shown: str) -> None:
    text = _help(*path)
    assert hidden not in text and shown in text


WITH_PROGRESS = [
    "demo --quiet",
    "render joy --quiet",
    "track {d}/clip.mp4 --quiet",
    "learn {d}/videos --labels {d}/labels.csv -o {d}/l.npz --quiet",
    "validate rig --quiet",
    "validate emotions --quiet",
    "validate compare {d}/clip.mp4 --quiet",
    "validate report --quiet",
    "study stimuli {d}/design.toml --quiet",
    "study analyze {d}/design.toml --quiet",
    "assets fetch ict-facekit --quiet",
]


@pytest.mark.parametrize("argv", WITH_PROGRESS, ids=[argv.split(" {")[0] for argv in WITH_PROGRESS])
def test_every_command_with_progress_has_quiet(argv: str, d: Path) -> None:
    assert parsed(argv, d)[0]["quiet"] is True


def test_one_fps_policy(d: Path) -> None:
    """60 fps for animation data (curves, clips, laughs), 30 fps for video (demo, render)."""
    for argv in ("emote joy", "au AU12", "laugh sly_smile"):
        assert parsed(argv, d)[0]["fps"] == ANIMATION_FPS == 60.0, argv
    assert parsed("demo", d)[0]["fps"] == VIDEO_FPS == 30.0
    assert f"default {VIDEO_FPS:g}" in _help("render")


def test_a_library_warning_reads_as_one_line_of_the_command() -> None:
    """A warning raised inside a command (a user's head lacking mouthClose, say) is printed as the commands' own
    warnings are: ``mien CMD: warning: MESSAGE``, no source path, no code line; the format is put back after. Run in a
    fresh interpreter, as a user's is (pytest records warnings instead of printing them)."""
    program = """
import sys, warnings
from mien.cli import main
from mien.commands import emote

def warns(args):
    message = "rig 'Hispanic_M_1_Casual' lacks targets mouthClose\\nthe AUs driving them lose that motion"
    warnings.warn(message, UserWarning, stacklevel=2)
    return 0

emote.run = warns
before = warnings.formatwarning
code = main(["emote", "joy"])
sys.exit(code if warnings.formatwarning is before else 3)
"""
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stderr == (
        "mien emote: warning: rig 'Hispanic_M_1_Casual' lacks targets mouthClose; "
        "the AUs driving them lose that motion\n"
    )
