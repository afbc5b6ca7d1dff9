"""Whole clips: rig + weights -> MP4 or PNG frames, and single stills; the shipped heads when present."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError, MissingExtraError
from mien.render.appearance import rig_vertex_colors, visible_faces
from mien.render.camera import CAMERA_PRESETS
from mien.render.clip_render import render_clip, render_still
from mien.render.offscreen import DEFAULT_BACKGROUND, EGLUnavailableError, OffscreenRenderer
from mien.render.video import read_video_info
from mien.rig.builtin_head import builtin_head
from mien.rig.model import Rig
from mien.rig.pose import apply_pose

Image = pytest.importorskip("PIL.Image", reason="pillow is not installed (pip install 'mien[render]')")


@pytest.fixture(autouse=True)
def _needs_gl() -> None:
    """Skip (with the reason) where no headless OpenGL context can be made."""
    try:
        OffscreenRenderer(np.array([[0, 1, 2]]), 2, 2, CAMERA_PRESETS["portrait"]).close()
    except (EGLUnavailableError, MissingExtraError) as error:
        pytest.skip(f"no headless OpenGL here: {error}")


def jaw_weights(rig: Rig, n_frames: int) -> np.ndarray:
    """(n_frames, n_targets): jawOpen ramping 0 -> 1."""
    weights = np.zeros((n_frames, len(rig.targets)), np.float32)
    weights[:, rig.target_index("jawOpen")] = np.linspace(0.0, 1.0, n_frames)
    return weights


def test_clip_to_mp4(rig: Rig, tmp_path: Path) -> None:
    out = render_clip(rig, jaw_weights(rig, 9), tmp_path / "jaw.mp4", 15, CAMERA_PRESETS["frontal-1m"], (96, 80))
    info = read_video_info(out)
    assert (info.n_frames, info.fps, info.width, info.height) == (9, 15.0, 96, 80)


def test_clip_to_png_frames_follows_the_weights(rig: Rig, tmp_path: Path) -> None:
    folder = render_clip(rig, jaw_weights(rig, 3), tmp_path / "frames", 30, CAMERA_PRESETS["frontal-1m"], (64, 64))
    names = sorted(p.name for p in folder.iterdir())
    assert names == ["frame_000000.png", "frame_000001.png", "frame_000002.png"]
    first, last = (np.asarray(Image.open(folder / name)) for name in (names[0], names[-1]))
    assert first.shape == (64, 64, 3)

    def lowest_row(image: np.ndarray) -> int:
        return int(np.flatnonzero((np.abs(image.astype(int) - DEFAULT_BACKGROUND).max(axis=2) > 3).any(axis=1))[-1])

    assert lowest_row(last) > lowest_row(first)  # the jaw dropped


def test_still_matches_the_clips_first_frame(rig: Rig, tmp_path: Path) -> None:
    weights = jaw_weights(rig, 2)
    still = render_still(rig, weights[0], CAMERA_PRESETS["frontal-1m"], (64, 64), samples=0)
    folder = render_clip(rig, weights, tmp_path / "f", 30, CAMERA_PRESETS["frontal-1m"], (64, 64), progress=False)
    np.testing.assert_array_equal(np.asarray(Image.open(folder / "frame_000000.png")), still)
    neutral = render_still(rig, None, CAMERA_PRESETS["frontal-1m"], (64, 64), samples=0)
    np.testing.assert_array_equal(neutral, still)  # weight 0 is the neutral face


def test_bad_clip_input_is_rejected(rig: Rig, tmp_path: Path) -> None:
    camera = CAMERA_PRESETS["frontal-1m"]
    with pytest.raises(InvalidValueError, match="weights"):
        render_clip(rig, np.zeros((4, 7)), tmp_path / "a.mp4", 30, camera, (64, 64))
    with pytest.raises(InvalidValueError, match="poses"):
        render_clip(rig, jaw_weights(rig, 4), tmp_path / "a.mp4", 30, camera, (64, 64), poses=np.zeros((3, 5)))
    with pytest.raises(InvalidValueError, match="size"):
        render_clip(rig, jaw_weights(rig, 4), tmp_path / "a.mp4", 30, camera, (65, 64))
    with pytest.raises(InvalidValueError, match="out_path"):
        render_clip(rig, jaw_weights(rig, 4), tmp_path / "a.gif", 30, camera, (64, 64))
    with pytest.raises(InvalidValueError, match="fps"):
        render_clip(rig, jaw_weights(rig, 4), tmp_path / "a.mp4", 0, camera, (64, 64))
    assert list(tmp_path.iterdir()) == []


def test_poses_go_through_apply_pose(rig: Rig, tmp_path: Path) -> None:
    camera = CAMERA_PRESETS["frontal-1m"]
    pose = np.array([40.0, 10.0, 0.0, 0.0, 0.0])
    turned = render_still(rig, None, camera, (96, 96), pose=pose, samples=0)
    with OffscreenRenderer(visible_faces(rig), 96, 96, camera, rig_vertex_colors(rig), samples=0) as renderer:
        expected = renderer.render(apply_pose(rig, rig.neutral, pose[:3], pose[3:]))
    np.testing.assert_array_equal(turned, expected)
    assert np.abs(render_still(rig, None, camera, (96, 96)).astype(int) - turned).mean() > 1
    poses = np.tile(pose, (2, 1))
    out = render_clip(rig, jaw_weights(rig, 2), tmp_path / "p", 30, camera, (96, 96), poses=poses)
    np.testing.assert_array_equal(np.asarray(Image.open(out / "frame_000000.png")), turned)


def test_builtin_head_renders_centred_and_lit() -> None:
    image = render_still(builtin_head(), None, CAMERA_PRESETS["portrait"], (128, 128))
    mask = np.abs(image.astype(int) - DEFAULT_BACKGROUND).max(axis=2) > 3
    columns = np.flatnonzero(mask.any(axis=0))
    assert (columns[0] + columns[-1]) / 2 == pytest.approx(64, abs=6)
    assert np.ptp(image[mask].mean(axis=1)) > 60


def test_ict_head_renders_with_eyes_and_lips(ict_dir: Path) -> None:
    from mien.rig.ict_facekit import load_ict_facekit

    rig = load_ict_facekit(ict_dir)
    camera = CAMERA_PRESETS["portrait"]
    image = render_still(rig, None, camera, (256, 256))
    mask = np.abs(image.astype(int) - DEFAULT_BACKGROUND).max(axis=2) > 3
    columns = np.flatnonzero(mask.any(axis=0))
    assert (columns[0] + columns[-1]) / 2 == pytest.approx(128, abs=4)
    # The pupils are dark, straight ahead of each eye centre.
    for center in rig.eye_centers:
        x, y = np.rint(camera.project(center + np.float32([0, 0, 0.02]), 256, 256)[0]).astype(int)
        assert image[y - 1 : y + 2, x - 1 : x + 2].min() < 60
    # The lips are redder than the cheeks.
    lip_x, lip_y = camera.project(rig.neutral[rig.landmarks[51]], 256, 256)[0]
    lip = image[int(lip_y) + 2, int(lip_x)].astype(int)
    cheek_x, cheek_y = camera.project(rig.neutral[rig.landmarks[2]] * np.float32([0.7, 1, 1]), 256, 256)[0]
    cheek = image[int(cheek_y), int(cheek_x)].astype(int)
    assert lip[0] - lip[1] > cheek[0] - cheek[1]


def test_render_failure_midway_keeps_a_partial_mp4(rig: Rig, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:

    original = OffscreenRenderer.render
    calls = []

    def flaky(self: OffscreenRenderer, vertices: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        calls.append(1)
        if len(calls) == 5:
            raise MemoryError("out of memory at frame 5")
        return original(self, vertices, out)

    monkeypatch.setattr(OffscreenRenderer, "render", flaky)
    with pytest.raises(MemoryError):
        render_clip(rig, jaw_weights(rig, 10), tmp_path / "clip.mp4", 25, CAMERA_PRESETS["frontal-1m"], (64, 64))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["clip.partial.mp4"]
    assert read_video_info(tmp_path / "clip.partial.mp4").n_frames == 4
