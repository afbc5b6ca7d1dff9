"""``mien track`` on the command line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mien.cli import main
from mien.tracking.track import load_track


def test_track_command_writes_json(
    single_face_video: Path, landmarker_path: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "smile.json"
    code = main(["track", str(single_face_video), "--landmarker", str(landmarker_path), "-o", str(out), "--quiet"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "72 frames" in printed and "1 take(s)" in printed and str(out) in printed
    track = load_track(out)
    assert track.takes == ((0, 72),) and np.isfinite(track.blendshapes).all()


def test_track_command_reports_no_face(
    shared_data: Path, landmarker_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    video = shared_data / "video" / "no_face.mp4"
    assert main(["track", str(video), "--landmarker", str(landmarker_path), "--quiet", "--no-cache"]) == 0
    assert "no face found on any frame: 0 takes" in capsys.readouterr().out


def test_track_command_errors(tmp_path: Path, landmarker_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "broken.webm"
    bad.write_bytes(b"\x1a\x45\xdf\xa3" + b"\0" * 100)
    assert main(["track", str(bad), "--landmarker", str(landmarker_path), "--quiet"]) == 2
    assert "broken.webm" in capsys.readouterr().err
    assert main(["track", str(bad), "-o", str(tmp_path / "out.txt")]) == 2
    assert "out.txt" in capsys.readouterr().err


@pytest.mark.slow
def test_track_command_workers(shared_data: Path, landmarker_path: Path, tmp_path: Path) -> None:
    """--workers 2 on no_face.mp4 (an edit list drops its first packets): the same frames and times as one
    process, no face on any."""
    video = shared_data / "video" / "no_face.mp4"
    outputs = []
    for workers in ("1", "2"):
        out = tmp_path / f"track_{workers}.npz"
        args = ["track", str(video), "--landmarker", str(landmarker_path), "--no-cache", "--quiet", "-o", str(out)]
        assert main([*args, "--workers", workers]) == 0
        outputs.append(load_track(out))
    one, two = outputs
    assert two.n_frames == one.n_frames > 90 and np.array_equal(two.timestamps_s, one.timestamps_s)
    assert not two.face_found.any() and not one.face_found.any()
