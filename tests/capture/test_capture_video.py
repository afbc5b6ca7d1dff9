"""Capture of the real videos in ../shared/data/video, and the captured clip replayed on ICT and a VALID avatar."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from tests.conftest import valid_avatar

from mien.capture import FACE_FOUND_CHANNEL, Capture, capture_video, strip_face_mask
from mien.cli import main
from mien.exchange import read_clip
from mien.facs.arkit import ARKIT_INDEX
from mien.facs.catalogue import FACE_CHANNELS, channel_index
from mien.tracking import track_video

SMILE = [ARKIT_INDEX["mouthSmileLeft"], ARKIT_INDEX["mouthSmileRight"]]
AU12 = [channel_index("AU12L"), channel_index("AU12R")]
AU_COLUMNS = [i for i, name in enumerate(FACE_CHANNELS) if name.startswith("AU")]
POSE_COLUMNS = [i for i, name in enumerate(FACE_CHANNELS) if name.endswith("_deg")]


@pytest.fixture(scope="module")
def captures(shared_data: Path, landmarker_path: Path) -> dict[str, Capture]:
    names = ("single_face.mp4", "no_face.mp4", "face_noface.mov", "noface_face.mov")
    return {
        name: capture_video(shared_data / "video" / name, model=landmarker_path, show_progress=False) for name in names
    }


def _onset(values: np.ndarray) -> int:
    """First frame above half of the curve's last second (the smile's plateau)."""
    return int(np.argmax(values > 0.5 * values[-30:].mean()))


def test_the_smile_onset_is_within_two_frames_of_the_tracked_one(
    captures: dict[str, Capture], shared_data: Path, landmarker_path: Path
) -> None:
    capture = captures["single_face.mp4"]
    track = track_video(shared_data / "video" / "single_face.mp4", landmarker_path, show_progress=False)
    tracked = _onset(track.blendshapes[:, SMILE].mean(axis=1))
    captured = _onset(capture.frames[:, AU12].mean(axis=1))
    assert 10 < tracked < 60  # the video's smile starts in its middle (frame 19 of 72)
    assert 0 <= captured - tracked <= 2
    clip = capture.clip()
    assert clip.n_frames == track.n_frames and clip.fps == pytest.approx(30.0)
    assert clip.channel(FACE_FOUND_CHANNEL).min() == 1.0
    assert clip.channel("AU12L")[: tracked - 2].max() < 0.3 and clip.channel("AU12L")[-12:-4].min() > 3.0


def test_a_video_without_a_face_is_all_marked_and_neutral(captures: dict[str, Capture]) -> None:
    capture = captures["no_face.mp4"]
    assert capture.n_frames == 95 and not capture.face_found.any()
    clip = capture.clip()
    assert clip.channel(FACE_FOUND_CHANNEL).max() == 0.0 and np.abs(clip.values).max() == 0.0


@pytest.mark.parametrize("name", ["face_noface.mov", "noface_face.mov"])
def test_a_face_leaving_or_entering_is_marked_without_jumps(captures: dict[str, Capture], name: str) -> None:
    capture = captures[name]
    found = capture.face_found
    assert 0 < found.sum() < len(found)
    assert np.any(np.diff(found.astype(int)))  # the face leaves or enters
    step = np.abs(np.diff(capture.frames, axis=0))
    faceless = ~(found[1:] & found[:-1])  # steps with a faceless frame on either side: the capture's own motion
    assert step[faceless][:, AU_COLUMNS].max() < 0.5 and step[faceless][:, POSE_COLUMNS].max() < 2.0
    if name == "face_noface.mov":  # the last pose is held, then eased to neutral
        last = int(np.flatnonzero(found)[-1])
        hold = int(0.9 * capture.settings.hold_s * capture.fps)
        assert np.allclose(capture.frames[last + 1 : last + hold], capture.frames[last])
        assert np.abs(capture.frames[last]).max() > 0.5 and np.abs(capture.frames[-1]).max() == 0.0
    clip, mask = strip_face_mask(capture.clip())
    assert mask is not None and mask.sum() <= found.sum() and FACE_FOUND_CHANNEL not in clip.channels


def test_the_cli_writes_the_clip_and_refuses_a_video_without_a_face(
    shared_data: Path, landmarker_path: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "smile.csv"
    video = str(shared_data / "video" / "single_face.mp4")
    assert main(["capture", video, "-o", str(out), "--landmarker", str(landmarker_path), "--quiet"]) == 0
    clip = read_clip(out)
    assert clip.channels == (*FACE_CHANNELS, FACE_FOUND_CHANNEL) and clip.channel("AU12R").max() > 3.0
    arkit = tmp_path / "smile_arkit.npz"
    assert main(["capture", video, "-o", str(arkit), "--route", "arkit", "--quiet"]) == 0
    assert read_clip(arkit).channel("mouthSmileLeft").max() > 0.7
    capsys.readouterr()
    no_face = str(shared_data / "video" / "no_face.mp4")
    assert main(["capture", no_face, "-o", str(tmp_path / "x.npz"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no_face.mp4" in err and "none was found on any of its 95 frames" in err


def _render(rig: object, clip: object, frames: tuple[int, ...], size: int) -> list[np.ndarray]:
    from mien.render.camera import camera_from_options
    from mien.render.clip_render import render_still
    from mien.rig.face_weights import clip_to_rig

    weights, poses = clip_to_rig(clip, rig)  # type: ignore[arg-type]
    camera = camera_from_options("frontal-1m")
    return [render_still(rig, weights[i], camera, (size, size), poses[i]) for i in frames]  # type: ignore[arg-type]


@pytest.mark.slow
def test_the_capture_replayed_on_ict_smiles_again(
    captures: dict[str, Capture], ict_dir: Path, landmarker_path: Path
) -> None:
    from mien.heads import load_head
    from mien.rig.au_solve import AUSolver
    from mien.validate.face_detector import MediaPipeDetector

    capture = captures["single_face.mp4"]
    rig = load_head("ict")
    solver = AUSolver()
    for route in ("au", "arkit"):  # ICT has the performer's ARKit names: both routes drive it
        clip, _ = strip_face_mask(capture.clip(route))
        neutral, smile = _render(rig, clip, (5, 60), 256)
        detector = MediaPipeDetector(landmarker_path)
        try:
            scores = [detector.detect(image).blendshapes for image in (neutral, smile)]
        finally:
            detector.close()
        assert all(s is not None for s in scores), f"{route}: no face found on the render"
        au12 = solver.solve(np.stack(scores))[:, solver.aus.index(12)]  # type: ignore[arg-type]
        assert au12[0] < 1.0 and au12[1] > au12[0] + 1.5, f"{route}: AU12 {au12}"


@pytest.mark.slow
def test_the_capture_replayed_on_a_valid_avatar_renders(captures: dict[str, Capture]) -> None:
    from mien.heads import load_head

    rig = load_head(str(valid_avatar()))
    clip, _ = strip_face_mask(captures["single_face.mp4"].clip("au"))
    with pytest.warns(UserWarning, match="lacks targets"):  # Rocketbox shapes: no mouthClose, mouthPress...
        neutral, smile = _render(rig, clip, (5, 60), 160)
    difference = np.abs(neutral.astype(float) - smile.astype(float)).max(axis=2)
    assert neutral.std() > 10  # a picture, not a blank
    assert (difference > 20).sum() > 30  # the mouth moved
