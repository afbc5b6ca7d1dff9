"""`mien render` on the files other commands write, at the rate asked, under a name of its own, and stopped by
SIGTERM (issue 29, cases 12, 14 and 15)."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from mien.cli import main
from mien.exchange import read_clip

pytest.importorskip("moderngl", reason="rendering needs the render extra")
pytest.importorskip("imageio_ffmpeg", reason="MP4 needs the render extra")

SMALL = ["--head", "builtin", "--size", "64", "--quiet"]
"""A small render on the built-in head."""


def _video(path: Path) -> tuple[int, float]:
    """(frames, fps) of an MP4 as decoded."""
    pytest.importorskip("av", reason="reading the MP4 back needs PyAV (the track extra)")
    from mien.render.video import read_video_info

    info = read_video_info(path)
    return info.n_frames, info.fps


def _thousand_fps_csv(path: Path, rows: int = 100) -> Path:
    """A smile at 1000 fps for ``rows`` rows (a 0.099 s clip, like OpenFace's own test file)."""
    lines = ["time_s,AU6L,AU6R,AU12L,AU12R"]
    lines += [
        f"{i / 1000:.3f},{3 * i / rows:.3f},{3 * i / rows:.3f},{4 * i / rows:.3f},{4 * i / rows:.3f}"
        for i in range(rows)
    ]
    path.write_text("\n".join(lines) + "\n")
    return path


def _one_error_line(err: str) -> str:
    assert "Traceback" not in err, err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    return lines[0]


# ------------------------------------------------------------------------------------------------ case 12


def test_laugh_controller_curves_render_and_import(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from PIL import Image

    anim = tmp_path / "sly.anim"
    assert main(["laugh", "sly_smile", "-o", str(anim)]) == 0  # controller curves, as `mien laugh` writes them
    still = tmp_path / "sly.png"
    assert main(["render", str(anim), *SMALL, "-o", str(still)]) == 0
    assert "controllers' ARKit mapping" in capsys.readouterr().out
    neutral_clip = tmp_path / "neutral.csv"
    neutral_clip.write_text("time_s,AU12L\n0,0\n0.1,0\n")
    neutral = tmp_path / "neutral.png"
    assert main(["render", str(neutral_clip), *SMALL, "-o", str(neutral)]) == 0
    difference = np.abs(np.asarray(Image.open(still), float) - np.asarray(Image.open(neutral), float))
    assert difference.max() > 30  # the smile's strongest frame, not a neutral face
    imported = tmp_path / "sly.npz"
    assert main(["import", str(anim), "-o", str(imported), "--au"]) == 0
    clip = read_clip(imported)
    assert clip.channel("AU12L").max() > 0.5 and clip.channel("AU12R").max() > 0.5  # a smile, in AU intensities


def _track_file(path: Path) -> Path:
    from mien.facs.arkit import ARKIT_INDEX
    from mien.tracking.track import Track

    n = 30
    blendshapes = np.zeros((n, 52), np.float32)
    blendshapes[15:, [ARKIT_INDEX["mouthSmileLeft"], ARKIT_INDEX["mouthSmileRight"]]] = 0.8  # a smile from 0.5 s
    track = Track(
        source="/videos/take.mp4",
        fps=30.0,
        width=64,
        height=48,
        timestamps_s=np.arange(n) / 30.0,
        landmarks=np.zeros((n, 478, 3), np.float32),
        blendshapes=blendshapes,
        head_pose_deg=np.zeros((n, 3)),
        face_found=np.ones(n, bool),
        interpolated=np.zeros(n, bool),
        takes=((0, n),),
    )
    return track.save(path)


@pytest.mark.parametrize("suffix", [".npz", ".json"])
@pytest.mark.parametrize("command", ["render", "import", "export"])
def test_a_track_file_is_captured_into_a_face_clip(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str, suffix: str
) -> None:
    track = _track_file(tmp_path / f"take{suffix}")
    output = tmp_path / {"render": "x.png", "import": "x.npz", "export": "x.csv"}[command]
    assert main([command, str(track), "-o", str(output), *(SMALL if command == "render" else [])]) == 0
    printed = capsys.readouterr()
    assert "is a face track: captured as `mien capture` does" in printed.err + printed.out
    if command == "import":
        clip = read_clip(output)
        assert "face_found" not in clip.channels
        assert clip.channel("AU12L")[:14].max() == 0.0 and clip.channel("AU12L")[-1] > 2.0  # the smile, as AU12
    assert output.is_file() and output.stat().st_size > 0


# ------------------------------------------------------------------------------------------------ case 15


def test_a_1000_fps_clip_renders_at_30_fps_or_at_the_rate_asked(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    clip = _thousand_fps_csv(tmp_path / "smile.csv")
    default = tmp_path / "default.mp4"
    assert main(["render", str(clip), *SMALL, "-o", str(default)]) == 0
    assert "runs at 1000 fps: rendering at 30 fps" in capsys.readouterr().out
    assert _video(default) == (4, 30.0)  # 0.099 s: frames at 0, 1/30, 2/30 and 3/30 s (the last value held)
    asked = tmp_path / "asked.mp4"
    assert main(["render", str(clip), *SMALL, "--fps", "100", "-o", str(asked)]) == 0
    assert "100 frames at 1000 fps resampled to 11 at 100 fps" in capsys.readouterr().out
    assert _video(asked) == (11, 100.0)


def test_the_real_openface_file_renders_at_30_fps(shared_data: Path, tmp_path: Path) -> None:
    out = tmp_path / "openface.mp4"
    assert main(["render", str(shared_data / "formats" / "OpenFace_Test.csv"), *SMALL, "-o", str(out)]) == 0
    assert _video(out) == (4, 30.0)


def test_without_o_the_output_is_named_after_the_input_and_kept(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    clip = _thousand_fps_csv(tmp_path / "smile.csv", rows=40)
    assert main(["render", str(clip), *SMALL]) == 0
    made = tmp_path / "mien-output" / "smile.mp4"
    assert made.is_file() and "mien-output/smile.mp4" in capsys.readouterr().out
    before = made.stat().st_mtime_ns
    assert main(["render", str(clip), *SMALL]) == 2  # a second run does not overwrite it silently
    line = _one_error_line(capsys.readouterr().err)
    assert "mien-output/smile.mp4" in line and "--force" in line
    assert made.stat().st_mtime_ns == before
    assert main(["render", str(clip), *SMALL, "--force"]) == 0
    assert main(["render", "AU12C", *SMALL, "--duration", "0.2"]) == 0
    assert (tmp_path / "mien-output" / "AU12C.mp4").is_file()


# ------------------------------------------------------------------------------------------------ case 14


def test_sigterm_cleans_up_as_ctrl_c_does(tmp_path: Path) -> None:
    out = tmp_path / "long.mp4"
    argv = ["render", "joy", *SMALL, "--duration", "600", "--fps", "30", "-o", str(out)]
    process = subprocess.Popen(
        [sys.executable, "-m", "mien.cli", *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=tmp_path
    )
    try:
        deadline = time.monotonic() + 120.0
        while not list(tmp_path.glob(".long.*.tmp.mp4")):  # ffmpeg has started writing
            assert process.poll() is None, process.communicate()
            assert time.monotonic() < deadline, "the render never started writing"
            time.sleep(0.05)
        time.sleep(1.0)  # some frames
        process.send_signal(signal.SIGTERM)
        _, err = process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    assert process.returncode == 130, err
    assert b"interrupted" in err and b"Traceback" not in err
    assert not list(tmp_path.glob("*.tmp*")) and not list(tmp_path.glob(".*tmp*")), sorted(tmp_path.iterdir())
    partial = tmp_path / "long.partial.mp4"
    assert partial.is_file() and not out.exists()
    frames, fps = _video(partial)
    assert frames > 0 and fps == 30.0
