"""MediaPipe's and TensorFlow Lite's routine C++ log lines stay off the terminal; their errors do not (issue 29
case 16). Before: every ``mien track`` printed five lines to stderr (``WARNING: Logging before InitGoogle()``,
``W0000 ... face_landmarker_graph.cc:181] ...``, ``INFO: Created TensorFlow Lite XNNPACK delegate for CPU.``)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from mien.tracking.native_logs import kept_lines, quiet_native_logs

ROUTINE = (
    b"WARNING: Logging before InitGoogle() is written to STDERR\n"
    b"W0000 00:00:1795735372.449535   10299 face_landmarker_graph.cc:181] Sets FaceBlendshapesGraph acceleration\n"
    b"I0000 00:00:1795735372.449535   10299 gl_context.cc:369] GL version: 3.2\n"
    b"INFO: Created TensorFlow Lite XNNPACK delegate for CPU.\n"
)
ERROR = b"E0000 00:00:1795735372.5   10299 calculator_graph.cc:887] INTERNAL: the model is broken\n"


def test_routine_lines_are_dropped_and_errors_kept() -> None:
    assert kept_lines(ROUTINE) == b""
    assert kept_lines(ROUTINE + ERROR + b"a Python warning\n") == ERROR + b"a Python warning\n"


def test_the_block_holds_descriptor_2_and_writes_back_what_matters(capfd: pytest.CaptureFixture[str]) -> None:
    with quiet_native_logs(), quiet_native_logs():  # re-entrant: the inner block runs inside the outer one
        os.write(2, ROUTINE)
        os.write(2, ERROR)
        os.write(1, b"stdout untouched\n")
    os.write(2, b"after\n")
    captured = capfd.readouterr()
    assert captured.err == (ERROR + b"after\n").decode()
    assert captured.out == "stdout untouched\n"


def test_an_exception_in_the_block_restores_descriptor_2(capfd: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(RuntimeError), quiet_native_logs():
        os.write(2, ERROR)
        raise RuntimeError("model failed")
    os.write(2, b"restored\n")
    assert capfd.readouterr().err == (ERROR + b"restored\n").decode()


def _fresh_python(code: str) -> subprocess.CompletedProcess[str]:
    """``code`` in a new interpreter (MediaPipe's one-time 'Logging before InitGoogle' line comes once a process)."""
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=False)


def test_track_prints_no_native_log_lines(single_face_video: Path, landmarker_path: Path, tmp_path: Path) -> None:
    pytest.importorskip("mediapipe")
    out = tmp_path / "smile.npz"
    argv = [
        "track",
        str(single_face_video),
        "--landmarker",
        str(landmarker_path),
        "-o",
        str(out),
        "--quiet",
        "--no-cache",
    ]
    done = _fresh_python(f"from mien.cli import main; raise SystemExit(main({argv!r}))")
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
    assert "72 frames" in done.stdout and out.is_file()


def test_the_emotion_classifier_prints_no_native_log_lines(emotion_model_path: Path) -> None:
    pytest.importorskip("ai_edge_litert")
    code = (
        "import numpy as np\n"
        "from mien.validate.emotion_classifier import EmotionClassifier\n"
        f"probabilities = EmotionClassifier({str(emotion_model_path)!r}).classify_crop(np.zeros((64, 64)))\n"
        "print(round(float(probabilities.sum()), 3))\n"
    )
    done = _fresh_python(code)
    assert (done.returncode, done.stderr, done.stdout) == (0, "", "1.0\n")


def test_a_broken_model_is_still_reported(single_face_video: Path, tmp_path: Path) -> None:
    pytest.importorskip("mediapipe")
    broken = tmp_path / "broken.task"
    broken.write_bytes(b"not a zip")
    argv = ["track", str(single_face_video), "--landmarker", str(broken), "--no-cache"]
    done = _fresh_python(f"from mien.cli import main; raise SystemExit(main({argv!r}))")
    assert done.returncode == 2
    assert "broken.task" in done.stderr and "Traceback" not in done.stderr
