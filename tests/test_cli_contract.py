"""The CLI contract, swept over every subcommand: a user's mistake is exit code 2 and one line on stderr that
names the value, never a traceback.

Every subcommand registered by ``mien.commands.COMMAND_MODULES`` must have rows in :data:`CASES` (a new
command that has none fails :func:`test_every_subcommand_has_rows`). Placeholders in an argv: ``{d}`` is a
folder prepared by :func:`inputs` (good and bad input files, and ``some_file.txt``, a file under which no
output can be written, even as root).
"""

from __future__ import annotations

import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from mien.cli import build_parser, main


@dataclass(frozen=True)
class Case:
    """One bad input of one subcommand."""

    command: str
    """The subcommand (first word after ``mien``)."""
    kind: str
    """What is wrong (missing file, typo, zero fps...)."""
    argv: tuple[str, ...]
    """Arguments after ``mien``; ``{d}`` is the prepared folder."""
    expect: tuple[str, ...]
    """Substrings of the one-line message (the value named, the suggestion...)."""


def case(command: str, kind: str, argv: str, *expect: str) -> Case:
    """A row: ``argv`` is split on spaces."""
    return Case(command, kind, tuple(argv.split()), expect)


UNDER_FILE = "{d}/some_file.txt/out"
"""A destination under a regular file: no folder can be made there, not even by root."""

CASES: list[Case] = [
    # demo
    case("demo", "zero fps", "demo --fps 0 -o {d}/demo", "--fps", "'0'", "> 0"),
    case("demo", "negative fps", "demo --fps -30 -o {d}/demo", "'-30'"),
    case("demo", "nan fps", "demo --fps nan -o {d}/demo", "'nan'", "not finite"),
    case("demo", "output under a file", f"demo -o {UNDER_FILE}", "some_file.txt is a file"),
    case("demo", "output folder is a file", "demo -o {d}/some_file.txt", "some_file.txt is a file: give a folder"),
    case("demo", "read-only destination", "demo -o /proc/mien-test/out", "cannot write in /proc/mien-test"),
    case("demo", "huge request", "demo --fps 1e9 -o {d}/demo", "fps 1e+09", "2 GiB", "MIEN_MAX_REQUEST_BYTES"),
    case("demo", "unknown option", "demo --fsp 30", "--fsp"),
    # emote
    case("emote", "zero fps", "emote joy --fps 0", "--fps", "'0'"),
    case("emote", "negative fps", "emote joy --fps -1", "'-1'"),
    case("emote", "infinite fps", "emote joy --fps inf", "'inf'"),
    case("emote", "zero duration", "emote joy --duration 0", "--duration", "'0'"),
    case("emote", "negative duration", "emote joy --duration -2", "'-2'"),
    case("emote", "negative hold", "emote joy --hold -1", "--hold", "'-1'"),
    case("emote", "not a number", "emote joy --onset soon", "'soon'"),
    case("emote", "output under a file", f"emote joy -o {UNDER_FILE}.csv", "some_file.txt is a file"),
    case("emote", "read-only destination", "emote joy -o /proc/mien-test/joy.csv", "/proc/mien-test"),
    case("emote", "output is a folder", "emote joy -o {d}", "is an existing folder"),
    case("emote", "plot under a file", f"emote joy --plot {UNDER_FILE}.png", "--plot", "some_file.txt"),
    case("emote", "huge request", "emote joy --duration 1e7 --fps 1000", "--duration 1e+07", "2 GiB"),
    case("emote", "unknown emotion", "emote glee", "unknown emotion 'glee'"),
    case("emote", "intensity out of range", "emote joy --intensity 7", "intensity=7.0"),
    # au
    case("au", "zero fps", "au AU12 --fps 0", "'0'"),
    case("au", "negative duration", "au AU12 --duration -1", "'-1'"),
    case("au", "zero time constant", "au AU12 --tau 0", "--tau", "'0'"),
    case("au", "negative play time", "au AU12 --play 0.2 -1 0.2", "--play", "'-1'"),
    case("au", "huge request", "au AU12 --duration 1e8", "2 GiB"),
    case("au", "output under a file", f"au AU12 -o {UNDER_FILE}.json", "some_file.txt is a file"),
    case("au", "unknown action unit", "au AU99", "AU99"),
    # render
    case("render", "typo in a file name", "render {d}/smlie.csv", "no such clip file", "did you mean", "smile.csv"),
    case("render", "missing folder", "render {d}/nofolder/smile.csv", "folder", "nofolder", "does not exist"),
    case("render", "empty file", "render {d}/empty.csv -o {d}/r.png", "empty.csv"),
    case("render", "header-only CSV", "render {d}/header_only.csv -o {d}/r.png", "header_only.csv"),
    case("render", "NaN cell", "render {d}/nan.csv -o {d}/r.png", "nan.csv", "line 3"),
    case("render", "unsorted time", "render {d}/unsorted.csv -o {d}/r.png", "unsorted.csv", "line 4"),
    case("render", "zero fps", "render joy --fps 0", "--fps", "'0'"),
    case("render", "negative duration", "render joy --duration -1", "'-1'"),
    case("render", "duration with a clip file", "render {d}/smile.csv --duration 3 -o {d}/r.png", "own length"),
    case("render", "output under a file", f"render joy -o {UNDER_FILE}.png", "some_file.txt is a file"),
    case("render", "huge request", "render joy --duration 1e9", "2 GiB"),
    # export
    case("export", "typo in a file name", "export {d}/smlie.csv -o {d}/o.json", "did you mean", "smile.csv"),
    case("export", "empty file", "export {d}/empty.csv -o {d}/o.json", "empty.csv is empty"),
    case("export", "header-only CSV", "export {d}/header_only.csv -o {d}/o.json", "header_only.csv", "no frames"),
    case("export", "NaN cell", "export {d}/nan.csv -o {d}/o.json", "nan.csv line 3", "'nan'"),
    case("export", "unsorted time", "export {d}/unsorted.csv -o {d}/o.json", "unsorted.csv line 4", "increasing"),
    case("export", "zero fps", "export {d}/smile.csv -o {d}/o.json --fps 0", "--fps", "'0'"),
    case("export", "output under a file", f"export {{d}}/smile.csv -o {UNDER_FILE}.json", "some_file.txt is a file"),
    case("export", "unknown format", "export {d}/smile.csv -o {d}/o.xyz", "'.xyz'"),
    case("export", "option that does not apply", "export {d}/smile.csv -o {d}/o.json --head builtin", "--head"),
    case("export", "names the head lacks", "export {d}/odd_names.csv -o {d}/o.glb --head builtin", "'fooBar'"),
    case("export", "missing head file", "export {d}/smile.csv -o {d}/o.glb --head {d}/nohead.glb", "nohead.glb"),
    case("export", "corrupt head file", "export {d}/smile.csv -o {d}/o.vrm --head {d}/text.glb", "text.glb", "glTF"),
    case("export", "unsupported head file", "export {d}/smile.csv -o {d}/o.glb --head {d}/face.fbx", "face.fbx"),
    case("export", "own names, no head", "export {d}/smile.csv -o {d}/o.csv --format arkit_csv --names file", "--head"),
    case(
        "export",
        "own names of a built-in head",
        "export {d}/smile.csv -o {d}/o.csv --format arkit_csv --names file --head builtin",
        "'builtin'",
        "character file",
    ),
    case("export", "own names in JSON", "export {d}/smile.csv -o {d}/o.json --names file --head builtin", "--names"),
    case("export", "undecodable audio", "export {d}/smile.csv -o {d}/o.json --audio {d}/speech_noise.wav",
         "speech_noise.wav", "decode"),
    case("export", "missing audio", "export {d}/smile.csv -o {d}/o.json --audio {d}/nope.wav", "nope.wav"),
    # import
    case("import", "typo in a file name", "import {d}/smlie.csv -o {d}/o.npz", "did you mean", "smile.csv"),
    case("import", "empty file", "import {d}/empty.csv -o {d}/o.npz", "empty.csv is empty"),
    case("import", "header-only CSV", "import {d}/header_only.csv -o {d}/o.npz", "header_only.csv", "no frames"),
    case("import", "NaN cell", "import {d}/nan.csv -o {d}/o.npz", "nan.csv line 3"),
    case("import", "unsorted time", "import {d}/unsorted.csv -o {d}/o.npz", "unsorted.csv line 4"),
    case("import", "output under a file", f"import {{d}}/smile.csv -o {UNDER_FILE}.npz", "some_file.txt is a file"),
    case("import", "wrong output format", "import {d}/smile.csv -o {d}/o.csv", "o.csv", ".npz or .json"),
    # assets
    case("assets", "unknown asset", "assets fetch ict-facekti", "ict-facekti", "ict-facekit"),
    case("assets", "zero timeout", "assets fetch ict-facekit --timeout 0", "--timeout", "'0'"),
    case("assets", "no longer an option", "assets fetch ict-facekit --sha256 00 -o {d}/ict", "--sha256"),
    case("assets", "not a URL", "assets fetch ict-facekit --url 127.0.0.1:1/ict -o {d}/ict", "127.0.0.1:1/ict", "http"),
    case("assets", "destination under a file", f"assets fetch ict-facekit -o {UNDER_FILE}", "some_file.txt is a file"),
    case("assets", "destination exists", "assets fetch ict-facekit -o {d}/some_file.txt", "some_file.txt", "--force"),
    case(
        "assets",
        "unreachable URL",
        "assets fetch ict-facekit --url http://127.0.0.1:1/ict -o {d}/ict",
        "127.0.0.1:1/ict/LICENSE",
        "--url",
        "nothing was installed",
    ),
    # track
    # head
    case("head", "no action", "head", "required", "ACTION"),
    case("head", "missing head file", "head inspect {d}/nothing.glb", "nothing.glb", "no such file"),
    case("head", "unsupported head file", "head inspect {d}/face.fbx", "face.fbx", ".glb", "Blender"),
    case("head", "truncated head file", "head inspect {d}/truncated.glb", "truncated.glb", "truncated"),
    case("head", "not a glTF file", "head inspect {d}/text.glb", "text.glb", "not a readable glTF"),
    case("head", "unknown named head", "head inspect robot", "unknown head 'robot'"),
    case("head", "picture not a png", "head inspect builtin -o {d}/landmarks.jpg", "landmarks.jpg", ".png"),
    case("track", "missing file", "track {d}/nothing.mp4", "no such file", "nothing.mp4"),
    case("track", "typo in a file name", "track {d}/clpi.mp4", "did you mean", "clip.mp4"),
    case("track", "empty file", "track {d}/empty.mp4", "empty.mp4 is empty"),
    case("track", "negative gap", "track {d}/clip.mp4 --max-gap-s -1", "--max-gap-s", "'-1'"),
    case("track", "output under a file", f"track {{d}}/clip.mp4 -o {UNDER_FILE}.npz", "some_file.txt is a file"),
    case("track", "wrong output format", "track {d}/clip.mp4 -o {d}/track.txt", "track.txt", ".npz or .json"),
    case("track", "zero workers", "track {d}/clip.mp4 --workers 0", "--workers", "'0'", ">= 1"),
    case("track", "workers not a number", "track {d}/clip.mp4 --workers two", "--workers", "'two'", "whole number"),
    # capture
    case("capture", "missing file", "capture {d}/nothing.mp4 -o {d}/c.npz", "no such file", "nothing.mp4"),
    case("capture", "typo in a file name", "capture {d}/clpi.mp4 -o {d}/c.npz", "did you mean", "clip.mp4"),
    case("capture", "empty file", "capture {d}/empty.mp4 -o {d}/c.npz", "empty.mp4 is empty"),
    case("capture", "no output", "capture {d}/clip.mp4", "-o/--output"),
    case("capture", "corrupt video", "capture {d}/clip.mp4 -o {d}/c.npz", "clip.mp4", "a readable video file"),
    case("capture", "not a track file", "capture {d}/library.npz -o {d}/c.npz", "library.npz", "corrupt or truncated"),
    case("capture", "reversed neutral", "capture {d}/clip.mp4 -o {d}/c.npz --neutral 2:1", "'2:1'", "START:END"),
    case("capture", "neutral interval not numbers", "capture {d}/clip.mp4 -o {d}/c.npz --neutral a:b", "'a:b'"),
    case("capture", "negative neutral seconds", "capture {d}/clip.mp4 -o {d}/c.npz --neutral-first-s -1", "'-1'"),
    case("capture", "missing neutral image", "capture {d}/clip.mp4 -o {d}/c.npz --neutral-image {d}/n.png", "n.png"),
    case("capture", "zero cut-off", "capture {d}/clip.mp4 -o {d}/c.npz --cutoff-hz 0", "--cutoff-hz", "'0'"),
    case("capture", "negative workers", "capture {d}/clip.mp4 -o {d}/c.npz --workers -2", "--workers", "'-2'"),
    case("capture", "fractional workers", "capture {d}/clip.mp4 -o {d}/c.npz --workers 1.5", "--workers", "'1.5'"),
    case("capture", "unknown route", "capture {d}/clip.mp4 -o {d}/c.npz --route blend", "--route", "'blend'"),
    case("capture", "output format", "capture {d}/clip.mp4 -o {d}/c.anim", "c.anim", ".csv, .json or .npz"),
    case("capture", "output under a file", f"capture {{d}}/clip.mp4 -o {UNDER_FILE}.npz", "some_file.txt is a file"),
    case("capture", "a clip, not a recording", "capture {d}/smile.csv -o {d}/c.npz", "smile.csv", "Live Link"),
    # learn
    case(
        "learn",
        "typo in a folder name",
        "learn {d}/vidoes --labels {d}/labels.csv -o {d}/lib.npz",
        "no such folder",
        "did you mean",
        "videos",
    ),
    case(
        "learn",
        "typo in the labels",
        "learn {d}/videos --labels {d}/lables.csv -o {d}/lib.npz",
        "did you mean",
        "labels.csv",
    ),
    case("learn", "empty labels", "learn {d}/videos --labels {d}/empty.csv -o {d}/lib.npz", "empty.csv is empty"),
    case(
        "learn",
        "header-only labels",
        "learn {d}/videos --labels {d}/labels_header.csv -o {d}/lib.npz --workers 0",
        "labels",
        "no rows",
    ),
    case(
        "learn",
        "unreachable Dask scheduler",
        "learn {d}/videos --labels {d}/labels.csv -o {d}/lib.npz --scheduler tcp://127.0.0.1:1",
        "tcp://127.0.0.1:1",
        "reachable Dask scheduler",
    ),
    case(
        "learn",
        "malformed scheduler address",
        "learn {d}/videos --labels {d}/labels.csv -o {d}/lib.npz --scheduler nowhere",
        "'nowhere'",
    ),
    case(
        "learn",
        "workers with a scheduler",
        "learn {d}/videos --labels {d}/labels.csv -o {d}/lib.npz --scheduler tcp://127.0.0.1:1 --workers 2",
        "--workers",
    ),
    case(
        "learn",
        "output under a file",
        f"learn {{d}}/videos --labels {{d}}/labels.csv -o {UNDER_FILE}.npz",
        "some_file.txt is a file",
    ),
    # laugh
    case("laugh", "zero fps", "laugh sly_smile --fps 0", "'0'"),
    case("laugh", "negative duration", "laugh sly_smile --duration -3", "'-3'"),
    case("laugh", "typo in a file name", "laugh sly_smile --library {d}/libary.npz", "did you mean", "library.npz"),
    case("laugh", "empty file", "laugh sly_smile --library {d}/empty.csv", "empty.csv is empty"),
    case("laugh", "not a library", "laugh sly_smile --library {d}/smile.csv", "smile.csv"),
    case("laugh", "huge request", "laugh sly_smile --duration 1e8", "2 GiB"),
    case("laugh", "output under a file", f"laugh sly_smile -o {UNDER_FILE}.csv", "some_file.txt is a file"),
    case("laugh", "option that does not apply", "laugh sly_smile --curves controllers", "--curves", "-o FILE"),
    case("laugh", "unknown type", "laugh giggle_fit", "giggle_fit"),
    # validate
    case("validate", "typo in a file name", "validate compare {d}/clpi.mp4", "did you mean", "clip.mp4"),
    case("validate", "missing folder", "validate rig --human-data {d}/humans", "no such folder", "humans"),
    case("validate", "output under a file", f"validate rig -o {UNDER_FILE}", "some_file.txt is a file"),
    case("validate", "bad list", "validate emotions --intensities 1.2,lots", "intensities", "1.2,lots"),
    # serve
    case("serve", "zero tick rate", "serve --tick-hz 0 --check", "--tick-hz", "0"),
    case("serve", "negative tick rate", "serve --tick-hz -5 --check", "-5"),
    case("serve", "bad port", "serve --udp-port -1 --check", "--udp-port", "-1"),
    case("serve", "port out of range", "serve --http-port 70000 --check", "--http-port", "70000"),
    case("serve", "missing camera", "serve --capture /dev/video9 --check", "camera='/dev/video9'", "existing camera"),
    case("serve", "capture no video", "serve --capture {d}/some_file.txt --check", "some_file.txt", "readable video"),
    case("serve", "follow without a capture", "serve --follow a --check", "--follow", "--capture SOURCE"),
    # send
    case("send", "NaN intensity", "send --au AU12=nan", "AU12=nan"),
    case("send", "unreachable server", "send --au AU12=3 --ws --http-port 1", "127.0.0.1:1"),
    case("send", "NaN PAD", "send --pad nan 0 0", "nan"),
    case("send", "negative speed", "send --speed -1 --au AU12=1", "Speed=-1.0"),
    # say
    Case("say", "empty text", ("say", " ", "-o", "{d}/s.mp4"), ("text=' '", "empty")),
    case("say", "nothing to say", "say -o {d}/s.mp4", "TEXT to say, a --timing file, or --audio"),
    case("say", "language the TTS lacks", "say hello --language xx-nope -o {d}/s.mp4", "espeak-ng"),
    case("say", "rate out of range", "say hello --rate 5 -o {d}/s.mp4", "rate_wpm=5", "80..450"),
    case("say", "not an mp4", "say hello -o {d}/s.avi", "s.avi", ".mp4"),
    case("say", "a sound as the clip", "say hello -o {d}/s.wav", "s.wav", "clip file"),
    case("say", "text and audio", "say hello --audio {d}/speech_noise.wav -o {d}/s.mp4", "--audio", "one of them"),
    case("say", "timing overlaps", "say --timing {d}/overlap.csv -o {d}/s.mp4", "segment 2", "no overlap"),
    case("say", "timing gap", "say --timing {d}/gap.json -o {d}/s.mp4", "segment 2", "no gap"),
    case("say", "timing unknown units", "say --timing {d}/frames.csv -o {d}/s.mp4", "start_frames", "start_s,end_s"),
    case("say", "timing unknown phoneme", "say --timing {d}/unknown.csv -o {d}/s.mp4", "unknown espeak phoneme 'Q!x'"),
    case("say", "undecodable audio", "say --audio {d}/speech_noise.wav -o {d}/s.mp4", "speech_noise.wav", "decode"),
    case("say", "missing timing file", "say --timing {d}/nope.json -o {d}/s.mp4", "nope.json"),
    case("say", "unknown emotion", "say hello --emotion glee -o {d}/s.mp4", "unknown emotion 'glee'"),
    # study
    case("study", "missing design", "study stimuli {d}/desing.toml", "desing.toml"),
    case("study", "not a design", "study stimuli {d}/smile.csv", "smile.csv"),
    case("study", "output under a file", f"study stimuli {{d}}/smile.csv -o {UNDER_FILE}", "some_file.txt is a file"),
    # the vocabulary (README "CLI vocabulary"): output, head, models, ports, basis, and old spellings in conflict
    case("export", "no output", "export {d}/smile.csv", "required", "-o/--output"),
    case("export", "output given twice", "export {d}/smile.csv {d}/a.json -o {d}/b.json", "given twice", "keep -o"),
    case("import", "no output", "import {d}/smile.csv", "required", "-o/--output"),
    case("export", "unknown head", "export {d}/smile.csv -o {d}/o.glb --head robot", "unknown head 'robot'", "builtin"),
    case("export", "empty identity", "export {d}/smile.csv -o {d}/o.glb --head ict:", "'ict:'", "HEAD:IDENTITY"),
    case(
        "export",
        "two identities",
        "export {d}/smile.csv -o {d}/o.glb --head builtin:b --identity c",
        "identity 'b'",
        "--identity 'c'",
        "--head HEAD:ID",
    ),
    case("render", "unknown head", "render joy --head robot:a", "unknown head 'robot'"),
    case("render", "unknown basis", "render joy --basis feature-point", "'feature-point'", "feature_points"),
    case("demo", "identity with two colons", "demo --head ict:a:b -o {d}/demo", "'ict:a:b'", "HEAD:IDENTITY"),
    case("serve", "unknown head", "serve --head robot --check", "unknown head 'robot'"),
    case("send", "UDP port with --ws", "send --emotion joy --ws --udp-port 5000", "--udp-port", "--http-port"),
    case("send", "HTTP port without --ws", "send --emotion joy --http-port 8000", "--http-port", "--ws"),
    case("send", "old and new port", "send --emotion joy --port 5001 --udp-port 5002", "--port 5001", "--udp-port"),
    case("track", "typo in the landmarker", "track {d}/clip.mp4 --landmarker {d}/libary.npz", "library.npz"),
    case("validate", "unknown basis", "validate emotions --basis facs,fp", "unknown basis 'fp'", "feature_points"),
    case("validate", "unknown head", "validate emotions --head builtin,robot", "unknown head 'robot'"),
    case("validate", "typo in the emotion model", "validate emotions --emotion-model {d}/libary.npz", "library.npz"),
]
"""The table of bad inputs (see the module docstring)."""


@pytest.fixture
def inputs(tmp_path: Path) -> Path:
    """A folder of good and bad input files."""
    (tmp_path / "smile.csv").write_text("time_s,AU12L,AU12R\n0,0,0\n0.5,4,4\n1.0,0,0\n")
    (tmp_path / "empty.csv").touch()
    (tmp_path / "header_only.csv").write_text("time_s,AU12L,AU12R\n")
    (tmp_path / "nan.csv").write_text("time_s,AU12L\n0,0\n0.5,nan\n1.0,0\n")
    (tmp_path / "unsorted.csv").write_text("time_s,AU12L\n0,0\n1.0,1\n0.5,0\n")
    (tmp_path / "odd_names.csv").write_text("time_s,fooBar\n0,0\n1.0,1\n")
    (tmp_path / "some_file.txt").write_text("a file, not a folder\n")
    (tmp_path / "clip.mp4").write_bytes(b"\0\0\0\x18ftypmp42" + b"\0" * 64)  # named right; never decoded here
    (tmp_path / "empty.mp4").touch()
    (tmp_path / "library.npz").write_bytes(b"PK\x03\x04")
    (tmp_path / "videos").mkdir()
    (tmp_path / "labels.csv").write_text("video,type,performer\nclip.mp4,laughter,p1\n")
    (tmp_path / "labels_header.csv").write_text("video,type,performer\n")
    (tmp_path / "face.fbx").write_text("Kaydara FBX Binary\n")
    (tmp_path / "truncated.glb").write_bytes(b"glTF\x02\x00\x00\x00")
    (tmp_path / "text.glb").write_text("not a glTF file\n")
    (tmp_path / "overlap.csv").write_text("start_s,end_s,espeak\n0,0.1,m\n0.05,0.2,a\n")
    (tmp_path / "gap.json").write_text(
        '{"alphabet": "viseme", "segments": [{"start_s": 0, "end_s": 0.1, "unit": "PP"}, '
        '{"start_s": 0.3, "end_s": 0.4, "unit": "aa"}]}'
    )
    (tmp_path / "frames.csv").write_text("start_frames,end_frames,viseme\n0,3,PP\n")
    (tmp_path / "unknown.csv").write_text("start_s,end_s,espeak\n0,0.1,m\n0.1,0.2,Q!x\n")
    (tmp_path / "speech_noise.wav").write_bytes(b"RIFF\x10\x00\x00\x00WAVEjunk" + bytes(range(256)) * 4)
    return tmp_path


def _registered() -> set[str]:
    import argparse

    parser = build_parser()
    (action,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return set(action.choices)


def test_every_subcommand_has_rows() -> None:
    """A subcommand without a row in the table fails here: new commands must join the sweep."""
    missing = _registered() - {c.command for c in CASES}
    assert not missing, f"add bad-input rows to CASES for: {', '.join(sorted(missing))}"


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    code = main(argv)
    return code, capsys.readouterr().err


@pytest.mark.parametrize("row", CASES, ids=[f"{c.command}-{c.kind.replace(' ', '_')}" for c in CASES])
def test_bad_input_is_exit_2_and_one_line(row: Case, inputs: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert row.command in _registered(), f"a row names mien {row.command}, which the CLI no longer registers"
    argv = [part.replace("{d}", str(inputs)) for part in row.argv]
    code, err = _run(argv, capsys)
    assert code == 2, f"exit {code} for mien {' '.join(argv)}; stderr: {err}"
    assert "Traceback" not in err
    assert err.endswith("\n") and err.count("\n") == 1, f"not one line: {err!r}"
    assert err.startswith("mien"), err
    for text in row.expect:
        assert text.replace("{d}", str(inputs)) in err, f"{text!r} not in {err!r}"


def test_output_folders_are_created(inputs: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The output policy: missing output folders are made, in every command that writes files."""
    targets = {
        "emote": [
            "emote",
            "joy",
            "--duration",
            "0.5",
            "-o",
            f"{inputs}/a/b/joy.csv",
            "--plot",
            f"{inputs}/p/q/joy.png",
        ],
        "au": ["au", "AU12", "--duration", "0.5", "-o", f"{inputs}/c/d/au.json"],
        "laugh": ["laugh", "sly_smile", "--duration", "0.5", "-o", f"{inputs}/e/f/laugh.npz"],
    }
    for argv in targets.values():
        assert main(argv) == 0, capsys.readouterr().err
    for path in ("a/b/joy.csv", "p/q/joy.png", "c/d/au.json", "e/f/laugh.npz"):
        assert (inputs / path).stat().st_size > 0, path
    # A usage error anywhere on the line makes no folder at all.
    assert main(["emote", "joy", "-o", f"{inputs}/never/joy.csv", "--fps", "0"]) == 2
    assert main(["demo", "-o", f"{inputs}/never2", "--fps", "-1"]) == 2
    assert not (inputs / "never").exists() and not (inputs / "never2").exists()


def test_the_request_limit_can_be_raised(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setenv("MIEN_MAX_REQUEST_BYTES", "1MiB")
    assert main(["emote", "joy", "--duration", "60", "--fps", "60", "-o", "/dev/null.csv"]) == 2
    err = capsys.readouterr().err
    assert "at most 1 MiB" in err
    monkeypatch.setenv("MIEN_MAX_REQUEST_BYTES", "lots")
    assert main(["emote", "joy"]) == 2
    assert "MIEN_MAX_REQUEST_BYTES='lots'" in capsys.readouterr().err


def _mien(*argv: str) -> subprocess.Popen[bytes]:
    return subprocess.Popen([sys.executable, "-m", "mien.cli", *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def test_closed_pipe_as_a_real_pipe() -> None:
    """``mien emote joy --duration 300 | head -1``: exit 2, one line naming the pipe, no traceback."""
    process = _mien("emote", "joy", "--duration", "300", "--no-idle")  # 18,000 lines overflow the pipe buffer
    assert process.stdout is not None and process.stderr is not None
    assert process.stdout.readline().startswith(b"time_s")
    process.stdout.close()
    with process.stderr:
        err = process.stderr.read().decode()
    assert process.wait(timeout=60) == 2
    assert err == "mien emote: error: output pipe closed; files already written are kept\n"


def test_smoke_subprocess_bad_fps() -> None:
    """The installed entry point behaves as in-process: exit 2, one line, nothing on stdout."""
    out, err = _mien("emote", "joy", "--fps", "0").communicate(timeout=60)
    assert out == b""
    assert err.decode().count("\n") == 1 and "argument --fps: fps '0' must be > 0" in err.decode()
