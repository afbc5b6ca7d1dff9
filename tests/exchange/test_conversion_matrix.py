"""Every file mien reads converts to every format it writes (issue 29, case 11): `mien export IN -o OUT` and
`mien import IN -o OUT [--au]` exit 0 or refuse in one line, never with a traceback.

The inputs are files mien wrote (a face clip in every writable format, on the built-in head, on ICT-FaceKit's
head with its 8 targets beyond ARKit's 52, on a VALID avatar's own file, laughter controller curves from `mien
laugh`) and a recorded OpenFace CSV. Inputs that need an asset skip, naming it, when it is absent.
"""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path

import numpy as np
import pytest

from mien.cli import main
from mien.exchange import read_clip

ICT_EXTRAS = ("browInnerUpLeft", "cheekPuffLeft", "cheekRaiserLeft", "pupilDilateLeft")
"""Some of ICT-FaceKit's targets that have no ARKit name (no Live Link column, no place in the AU solve)."""

OPENFACE_TEXT = (
    "frame, timestamp, confidence, success, pose_Rx, pose_Ry, pose_Rz, AU01_r, AU06_r, AU12_r, AU45_r, AU28_c\n"
    + "".join(
        f"{i + 1}, {i * 0.001:.3f}, 0.98, 1, 0.01, -0.02, 0.0, 0.5, {i / 40:.3f}, {i / 20:.3f}, 0.0, 0\n"
        for i in range(60)
    )
)
"""An OpenFace 2.x file at 1000 fps (OpenFace's own test file's rate), 60 rows."""

INPUTS: dict[str, tuple[str, list[str]]] = {
    # input name: (what writes it, extra arguments of `mien export face.npz -o NAME`)
    "face.csv": ("face", []),
    "face.json": ("face", []),
    "face.jsonl": ("face", []),
    "face.npz": ("face", []),
    "face.anim": ("face", []),
    "live_link.csv": ("face", ["--format", "arkit_csv"]),
    "builtin.glb": ("face", ["--head", "builtin"]),
    "builtin.vrm": ("face", ["--head", "builtin"]),
    "ict.glb": ("ict", ["--head", "ict"]),
    "valid.glb": ("valid", []),
    "controllers.anim": ("laugh", []),
    "openface.csv": ("openface", []),
}
"""The input files of the matrix."""

OUTPUTS: dict[str, list[str]] = {
    "out.csv": [],
    "out_live_link.csv": ["--format", "arkit_csv"],
    "out.json": [],
    "out.jsonl": [],
    "out.npz": [],
    "out.anim": [],
    "out_builtin.glb": ["--head", "builtin"],
    "out_builtin.vrm": ["--head", "builtin"],
    "out_ict.glb": ["--head", "ict"],
    "out_valid.glb": ["--head", "{avatar}"],
}
"""The outputs: every writable format, and a .glb on each kind of head."""


def _avatar() -> Path | None:
    root = Path(os.environ.get("MIEN_SHARED", Path(__file__).resolve().parents[3] / "shared"))
    avatar = root / "avatars" / "valid" / "Asian_F_1_Casual.glb"
    return avatar if avatar.is_file() else None


def _needs(name: str) -> str | None:
    """Why the matrix cells of ``name`` (an input or output) cannot run here, or None."""
    ict = os.environ.get("MIEN_ICT_FACEKIT", "")
    if "ict" in name and not (ict and Path(ict, "FaceXModel").is_dir()):
        return "ICT-FaceKit not available: set MIEN_ICT_FACEKIT to its folder"
    if "valid" in name:
        if _avatar() is None:
            return "VALID avatars not available: set MIEN_SHARED to the shared folder (needs avatars/valid)"
        landmarker = os.environ.get("MIEN_FACE_LANDMARKER", "")
        if not (landmarker and Path(landmarker).is_file()):
            return "a character file is placed by its landmarks: set MIEN_FACE_LANDMARKER"
        if importlib.util.find_spec("mediapipe") is None:
            return "a character file is placed by MediaPipe: install mien[track]"
    return None


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder holding the input files that can be made here."""
    folder = tmp_path_factory.mktemp("matrix-inputs")
    face = folder / "face.npz"
    assert main(["emote", "joy", "--duration", "0.5", "--fps", "30", "-o", str(face)]) == 0
    for name, (kind, extra) in INPUTS.items():
        if _needs(name) is not None or name == "face.npz":
            continue
        if kind == "laugh":
            argv = ["laugh", "sly_smile", "--duration", "0.6", "-o", str(folder / name)]
        elif kind == "openface":
            (folder / name).write_text(OPENFACE_TEXT)
            continue
        elif kind == "valid":
            argv = ["export", str(face), "-o", str(folder / name), "--head", str(_avatar())]
        else:
            argv = ["export", str(face), "-o", str(folder / name), *extra]
        assert main(argv) == 0, argv
    return folder


def _input(inputs: Path, name: str) -> Path:
    reason = _needs(name)
    if reason is not None:
        pytest.skip(reason)
    return inputs / name


def _one_line_error(err: str) -> str:
    assert "Traceback" not in err, err
    errors = [line for line in err.splitlines() if "error:" in line]
    assert len(errors) == 1, err
    return errors[0]


@pytest.mark.parametrize("output", OUTPUTS)
@pytest.mark.parametrize("source", INPUTS)
def test_every_input_converts_to_every_output(
    inputs: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], source: str, output: str
) -> None:
    path = _input(inputs, source)
    reason = _needs(output)
    if reason is not None:
        pytest.skip(reason)
    clip = read_clip(path)
    target = tmp_path / output
    extra = [a.replace("{avatar}", str(_avatar())) for a in OUTPUTS[output]]
    code = main(["export", str(path), "-o", str(target), *extra])
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err
    assert code == 0, captured.err
    back = read_clip(target)
    duration = (clip.n_frames - 1) / clip.fps
    assert abs((back.n_frames - 1) / back.fps - duration) <= 1.0 / min(clip.fps, back.fps) + 1e-6
    moving = [c for c in back.channels if not c.endswith("_deg") and np.abs(back.channel(c)).max() > 1e-3]
    assert moving, f"{source} -> {output}: nothing moves in {back.channels[:5]}"
    if source == "ict.glb" and output == "out_live_link.csv":
        assert "no Live Link Face column for browInnerUpLeft" in captured.out
        assert not set(ICT_EXTRAS) & set(back.channels)


@pytest.mark.parametrize("au", [False, True], ids=["as-is", "au"])
@pytest.mark.parametrize("source", INPUTS)
def test_every_input_imports(
    inputs: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], source: str, au: bool
) -> None:
    path = _input(inputs, source)
    kind = INPUTS[source][0]
    holds_aus = source.startswith("face.") or kind == "openface"
    target = tmp_path / "imported.npz"
    code = main(["import", str(path), "-o", str(target), *(["--au"] if au else [])])
    captured = capsys.readouterr()
    if au and holds_aus:  # nothing to solve: refused in one line
        assert code == 2 and "holds AU channels already" in _one_line_error(captured.err)
        return
    assert "Traceback" not in captured.err
    assert code == 0, captured.err
    clip = read_clip(target)
    if au:
        assert clip.channels[:2] == ("AU1L", "AU1R") and np.abs(clip.values).max() > 0.05
    if au and source == "ict.glb":
        assert "not ARKit blendshapes skipped: browInnerUpLeft" in captured.out


def test_ict_glb_to_live_link_keeps_the_52_weights(inputs: Path, tmp_path: Path) -> None:
    path = _input(inputs, "ict.glb")
    target = tmp_path / "take.csv"
    assert main(["export", str(path), "-o", str(target), "--format", "arkit_csv"]) == 0
    weights, live = read_clip(path), read_clip(target)
    for name in ("eyeBlinkLeft", "browDownLeft", "mouthSmileLeft"):
        np.testing.assert_allclose(live.channel(name), weights.channel(name), atol=1e-6)


def test_a_character_file_mien_animated_reads_back_as_the_heads_weights_and_angles(inputs: Path) -> None:
    valid = read_clip(_input(inputs, "valid.glb"))
    builtin, face = read_clip(inputs / "builtin.glb"), read_clip(inputs / "face.npz")
    assert "h_expressions.Kiss_h" not in valid.channels and "mouthSmileLeft" in valid.channels
    for name in ("mouthSmileLeft", "cheekSquintRight", "eyeSquintLeft"):  # the AU mapping, on either head
        assert valid.channel(name).max() > 0.1
        np.testing.assert_allclose(valid.channel(name), builtin.channel(name), atol=1e-5)
    for name in ("head_yaw_deg", "head_pitch_deg", "head_roll_deg"):  # mien's angles, not the bone's rotation
        np.testing.assert_allclose(valid.channel(name), face.channel(name), atol=1e-3)


def test_untrusted_extras_leave_a_files_own_shapes() -> None:
    from mien.exchange.glb_user import MAX_EXTRAS_ROWS, head_turns, target_clip
    from mien.facs.clip import Clip

    shapes = Clip(np.array([[0.2, 0.6], [0.4, 0.8]]), 30.0, ("smile", "Jaw.Open"))
    rows = {
        "mouthSmileLeft": [["smile", 1.0, "L"]],
        "mouthSmileRight": [["smile", 1.0, "R"]],
        "jawOpen": [["Jaw.Open", 2.0, ""]],
    }
    back = target_clip(shapes, {"mien": {"targets": rows}})
    assert back is not None and back.channels == ("mouthSmileLeft", "mouthSmileRight", "jawOpen")
    np.testing.assert_allclose(back.values, [[0.2, 0.2, 0.3], [0.4, 0.4, 0.4]])  # a shared shape: both halves
    nan_rows = {"jawOpen": [["Jaw.Open", float("nan"), ""]]}
    too_many = {f"t{i}": [["smile", 1.0, ""]] for i in range(MAX_EXTRAS_ROWS + 1)}
    for extras in (None, [], {"mien": []}, {"mien": {"targets": []}}, {"mien": {"targets": {"x": 3}}},
                   {"mien": {"targets": nan_rows}}, {"mien": {"targets": too_many}},
                   {"mien": {"targets": {"jawOpen": [["elsewhere", 1.0, ""]]}}}):  # fmt: skip
        assert target_clip(shapes, extras) is None, extras
    quaternions = np.array([[0.0, 0.0, 0.0, 1.0], [0.0, np.sin(0.25), 0.0, np.cos(0.25)]])
    identity = {"mien": {"head": {"node": 3, "left": np.eye(3).tolist(), "right": np.eye(3).tolist()}}}
    turns = head_turns(3, quaternions, identity)
    assert turns is not None and turns.shape == (2, 3, 3)
    np.testing.assert_allclose(turns[1] @ [0.0, 0.0, 1.0], [np.sin(0.5), 0.0, np.cos(0.5)], atol=1e-12)
    assert head_turns(4, quaternions, identity) is None  # another node
    bad = {"mien": {"head": {"node": 3, "left": [[float("nan")] * 3] * 3, "right": np.eye(3).tolist()}}}
    assert head_turns(3, quaternions, bad) is None and head_turns(3, quaternions, {"mien": 1}) is None
