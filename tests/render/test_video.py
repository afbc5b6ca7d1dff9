"""MP4 and PNG writing: valid files, right frame count, fps and size; partial videos after a failure."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from mien.errors import InvalidValueError
from mien.render.video import Mp4Writer, partial_path, read_video_info, write_mp4, write_png


def frames(n: int, width: int = 64, height: int = 48) -> Iterator[np.ndarray]:
    """A grey ramp that brightens frame by frame, with a moving white square."""
    for index in range(n):
        frame = np.full((height, width, 3), 20 + 10 * index, np.uint8)
        frame[8:16, index * 2 : index * 2 + 8] = 255
        yield frame


def test_mp4_decodes_with_the_right_count_fps_and_size(tmp_path: Path) -> None:
    path = write_mp4(frames(12), tmp_path / "clip.mp4", fps=24, preset="ultrafast")
    info = read_video_info(path)
    assert (info.n_frames, info.fps, info.width, info.height) == (12, 24.0, 64, 48)
    assert (info.codec, info.pixel_format) == ("h264", "yuv420p")
    assert info.duration_s == pytest.approx(0.5)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["clip.mp4"]  # no temporary file left


def test_failure_midway_leaves_a_playable_partial_mp4(tmp_path: Path) -> None:
    def failing() -> Iterator[np.ndarray]:
        yield from frames(7)
        raise RuntimeError("renderer crashed")

    target = tmp_path / "long.mp4"
    with pytest.raises(RuntimeError, match="renderer crashed"):
        write_mp4(failing(), target, fps=30)
    assert not target.exists()
    partial = partial_path(target)
    assert partial.name == "long.partial.mp4"
    info = read_video_info(partial)
    assert (info.n_frames, info.fps, info.width) == (7, 30.0, 64)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["long.partial.mp4"]


def test_bad_frames_and_settings_are_rejected(tmp_path: Path) -> None:
    with pytest.raises(InvalidValueError, match="frame size"):
        write_mp4(frames(2, width=63), tmp_path / "odd.mp4", fps=25)
    with pytest.raises(InvalidValueError, match="fps"):
        Mp4Writer(tmp_path / "a.mp4", fps=0)
    with pytest.raises(InvalidValueError, match="crf"):
        Mp4Writer(tmp_path / "a.mp4", fps=25, crf=60)
    with pytest.raises(InvalidValueError, match="preset"):
        Mp4Writer(tmp_path / "a.mp4", fps=25, preset="warp")
    with pytest.raises(InvalidValueError, match="path"):
        Mp4Writer(tmp_path / "a.avi", fps=25)
    mixed = [np.zeros((48, 64, 3), np.uint8), np.zeros((48, 32, 3), np.uint8)]
    with pytest.raises(InvalidValueError, match="frame size"):
        write_mp4(mixed, tmp_path / "mixed.mp4", fps=25)
    with pytest.raises(InvalidValueError, match="frames"):
        write_mp4([], tmp_path / "empty.mp4", fps=25)
    with pytest.raises(InvalidValueError, match="frame"):
        write_mp4([np.zeros((48, 64, 3), np.float32)], tmp_path / "float.mp4", fps=25)


def test_png_round_trips(tmp_path: Path) -> None:
    image = next(frames(1))
    path = write_png(image, tmp_path / "sub" / "frame.png")
    np.testing.assert_array_equal(np.asarray(Image.open(path)), image)
    with pytest.raises(InvalidValueError, match="image"):
        write_png(np.zeros((4, 4, 3), np.float64), tmp_path / "bad.png")
