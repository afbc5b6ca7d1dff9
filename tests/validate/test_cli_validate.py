"""``mien validate``: each user mistake answers exit code 2 and one message naming the value; a real run writes its
files (and nothing that looks complete when it fails)."""

from __future__ import annotations

import json

import pytest

from mien.cli import main


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["validate", "emotions", "--head", "robot"], "unknown head 'robot'"),
        (["validate", "emotions", "--head", "builtin:zz"], "built-in identity 'zz'"),
        (["validate", "emotions", "--head", "builtin", "--views", "sideways"], "unknown view 'sideways'"),
        (["validate", "emotions", "--head", "builtin", "--intensities", "big"], "intensities='big'"),
        (["validate", "emotions", "--head", "builtin", "--intensities", "9"], "intensity=9.0"),
        (["validate", "emotions", "--head", "builtin", "--expressions", "bored"], "unknown expression 'bored'"),
        (["validate", "emotions", "--head", "builtin", "--size", "0x5"], "size='0x5'"),
        (["validate", "emotions", "--head", "builtin", "--framing", "haar"], "invalid choice: 'haar'"),
        (["validate", "rig", "--head", "builtin", "--aus", "x"], "aus='x'"),
        (["validate", "report", "--head", "builtin", "--video", "/no/such/video.mp4"], "/no/such/video.mp4"),
    ],
)
def test_bad_values_exit_2_with_a_message(argv, message, capsys, tmp_path):
    assert main([*argv, "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_missing_models_and_heads_are_named(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("MIEN_EMOTION_MODEL", str(tmp_path / "missing.tflite"))
    assert main(["validate", "emotions", "--head", "builtin", "-o", str(tmp_path / "a")]) == 2
    assert "missing.tflite" in capsys.readouterr().err
    monkeypatch.setenv("MIEN_ICT_FACEKIT", str(tmp_path / "no-ict"))
    assert main(["validate", "emotions", "--head", "ict:a", "-o", str(tmp_path / "b")]) == 2
    assert "MIEN_ICT_FACEKIT" in capsys.readouterr().err
    assert not (tmp_path / "a" / "recognition.json").exists()


def test_compare_refuses_a_video_without_a_face(shared_data, landmarker_path, capsys, tmp_path):
    pytest.importorskip("mediapipe")
    out = tmp_path / "cmp"
    assert main(["validate", "compare", str(shared_data / "video" / "no_face.mp4"), "--head", "builtin",
                 "--size", "128x128", "-o", str(out), "--quiet"]) == 2  # fmt: skip
    err = capsys.readouterr().err
    assert "no_face.mp4" in err and "face" in err
    assert not (out / "compare.json").exists()


def test_emotions_writes_json_sheets_and_figures(landmarker_path, emotion_model_path, tmp_path, capsys):
    pytest.importorskip("moderngl")
    pytest.importorskip("ai_edge_litert")
    out = tmp_path / "emo"
    argv = ["validate", "emotions", "--head", "builtin", "--views", "frontal-1m", "--basis", "facs", "--expressions",
            "joy,evil", "--intensities", "1.2", "--size", "256x256", "--quiet", "-o", str(out)]  # fmt: skip
    assert main(argv) == 0
    data = json.loads((out / "recognition.json").read_text())
    assert [s["expression"] for s in data["stimuli"]] == ["neutral", "joy", "evil"]
    assert data["quality"]["joy"]["human"] == 0.806
    for name in ("confusion.png", "quality.png", "sheet_builtin_default_facs_frontal-1m.png"):
        assert (out / name).read_bytes()[:4] == b"\x89PNG"
    assert not list(out.glob(".*partial*"))
    assert "joy" in capsys.readouterr().out
