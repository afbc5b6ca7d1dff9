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
