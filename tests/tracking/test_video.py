"""Video decoding: frames, timestamps, and typed errors for unreadable files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError
from mien.tracking.video import iter_frames, prefetch, probe


def test_probe_reads_rate_size_and_count(single_face_video: Path) -> None:
    info = probe(single_face_video)
    assert (info.fps, info.width, info.height, info.n_frames) == (30.0, 640, 360, 72)


def test_frames_are_rgb_with_increasing_times(single_face_video: Path) -> None:
    frames = list(iter_frames(single_face_video))
    assert len(frames) == 72
    times = np.array([t for t, _ in frames])
    assert times[0] == 0.0
    assert np.allclose(np.diff(times), 1 / 30, atol=1e-3)
    rgb = frames[0][1]
    assert rgb.shape == (360, 640, 3) and rgb.dtype == np.uint8 and rgb.flags.c_contiguous


@pytest.mark.parametrize("name", ["face_noface.mov", "noface_face.mov"])
def test_mov_files_decode(shared_data: Path, name: str) -> None:
    info = probe(shared_data / "video" / name)
    assert (info.width, info.height) == (960, 540)
    assert sum(1 for _ in iter_frames(shared_data / "video" / name)) == 169


def test_garbage_bytes_name_the_file(tmp_path: Path) -> None:
    bad = tmp_path / "garbage.mp4"
    bad.write_bytes(bytes(range(256)) * 40)
    with pytest.raises(InvalidValueError, match=r"garbage\.mp4"):
        list(iter_frames(bad))
    with pytest.raises(InvalidValueError, match=r"garbage\.mp4"):
        probe(bad)


def test_empty_and_missing_files(tmp_path: Path) -> None:
    empty = tmp_path / "empty.mov"
    empty.touch()
    with pytest.raises(InvalidValueError, match="empty"):
        probe(empty)
    with pytest.raises(InvalidValueError, match=r"missing\.mp4"):
        list(iter_frames(tmp_path / "missing.mp4"))


def test_truncated_copy_is_rejected(single_face_video: Path, tmp_path: Path) -> None:
    """Cut at the front (index at the end is lost) or at the back (frames missing): both rejected."""
    data = single_face_video.read_bytes()
    cut = tmp_path / "cut.mp4"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(InvalidValueError, match=r"cut\.mp4"):
        list(iter_frames(cut))


def _remux(source_path: Path, target: Path, options: dict[str, str]) -> None:
    """Copy the video stream into another container without re-encoding."""
    import av

    with av.open(str(source_path)) as source, av.open(str(target), "w", options=options) as out:
        stream = out.add_stream_from_template(source.streams.video[0])
        for packet in source.demux(source.streams.video[0]):
            if packet.dts is not None:
                packet.stream = stream
                out.mux(packet)


def test_truncated_faststart_copy_is_rejected(single_face_video: Path, tmp_path: Path) -> None:
    """With the index first, FFmpeg decodes a truncated file quietly; the missing frames are still noticed."""
    faststart = tmp_path / "faststart.mp4"
    _remux(single_face_video, faststart, {"movflags": "faststart"})
    assert sum(1 for _ in iter_frames(faststart)) == 72
    truncated = tmp_path / "truncated.mp4"
    data = faststart.read_bytes()
    truncated.write_bytes(data[: int(len(data) * 0.6)])
    with pytest.raises(InvalidValueError, match=r"truncated\.mp4.*truncated: only"):
        list(iter_frames(truncated))


def test_other_containers(single_face_video: Path, tmp_path: Path) -> None:
    """The same stream remuxed to .mkv decodes the same frames."""
    mkv = tmp_path / "clip.mkv"
    _remux(single_face_video, mkv, {})
    first_mp4 = next(iter(iter_frames(single_face_video)))[1]
    first_mkv = next(iter(iter_frames(mkv)))[1]
    assert np.array_equal(first_mp4, first_mkv)


def test_prefetch_keeps_order_and_reraises() -> None:
    assert list(prefetch(iter(range(50)), depth=3)) == list(range(50))

    def failing():  # type: ignore[no-untyped-def]
        yield 1
        raise InvalidValueError("video", "x.mp4", "a readable video file")

    got = []
    with pytest.raises(InvalidValueError, match=r"x\.mp4"):
        for item in prefetch(failing()):
            got.append(item)
    assert got == [1]


def test_prefetch_stops_early() -> None:
    stream = prefetch(iter(range(1000)), depth=2)
    assert next(stream) == 0
    stream.close()  # must not hang on the producer blocked on a full queue
