"""`mien validate compare`: human video vs character as AU activation maps (OpenFACS Fig. 5, closed loop)."""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError, MissingAssetError, UnknownNameError
from mien.validate.compare import CompareResult, MapComparison, run_compare

# Measured on single_face.mp4 (a smile), frontal-1m: AU12's closed-loop row r 0.9991 on the built-in head at
# 256x256 (0.9989 at 512x512, 0.9994 on ICT identity a at 512x512); the overall 2D r 0.95 (0.94; ICT a 0.84).
AU12_CLOSED_LOOP_MIN_R = 0.95
CLOSED_LOOP_MIN_R = 0.75


def _fake_result(aus: tuple[int, ...] = (1, 12, 25)) -> CompareResult:
    rng = np.random.default_rng(5)
    human = rng.uniform(0, 5, size=(len(aus), 20))
    character = human + rng.normal(0, 0.5, size=human.shape)
    character[0] = 0.0  # a constant row: its r is undefined
    loop = MapComparison("closed-loop", aus, human, character, 1.0)
    joy = MapComparison("joy", aus, human, human[:, ::-1].copy(), 0.9)
    return CompareResult(
        video="/x/v.mp4",
        duration_s=2.0,
        fps=30.0,
        n_frames=60,
        face_share=1.0,
        head="builtin",
        identity=None,
        camera="frontal-1m",
        size=(256, 256),
        length=20,
        detector="fake",
        closed_loop=loop,
        expression=joy,
    )


def test_write_gives_json_csv_and_figures(tmp_path: Path) -> None:
    result = _fake_result()
    paths = result.write(tmp_path / "out")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [
        "closed_loop.png",
        "compare.json",
        "expression_joy.png",
        "per_au.csv",
    ]
    data = json.loads(paths["compare"].read_text())
    assert data["closed_loop"]["per_au_r"]["AU1"] is None and data["closed_loop"]["constant_rows"] == ["AU1"]
    assert data["closed_loop"]["r"] == pytest.approx(result.closed_loop.r, abs=1e-4)
    assert np.asarray(data["expression"]["human_map"]).shape == (3, 20)
    rows = list(csv.DictReader(io.StringIO(paths["per_au"].read_text())))
    assert [row["au"] for row in rows] == ["AU1", "AU12", "AU25"]
    assert rows[0]["closed-loop_r"] == "" and float(rows[1]["closed-loop_r"]) > 0.9
    assert paths["closed_loop"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_failed_write_leaves_no_result_behind(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    result = _fake_result()
    result.write(tmp_path)  # an earlier, complete result

    def broken(*args: object, **kwargs: object) -> None:
        raise OSError("disk full")

    monkeypatch.setattr(CompareResult, "per_au_csv", broken)
    with pytest.raises(OSError, match="disk full"):
        result.write(tmp_path)
    names = sorted(p.name for p in tmp_path.iterdir())
    assert not any("partial" in name for name in names)
    assert "compare.json" in names  # the old result stays whole: nothing was renamed yet


@pytest.fixture
def single_face(shared_data: Path, landmarker_path: Path) -> Path:
    return shared_data / "video" / "single_face.mp4"


def test_closed_loop_on_a_smile_keeps_au12(single_face: Path, tmp_path: Path) -> None:
    result = run_compare(single_face, None, head="builtin", size=(256, 256), length=100, progress=False)
    loop = result.closed_loop
    assert result.expression is None and result.face_share == 1.0 and loop.character_face_share == 1.0
    assert loop.human.shape == loop.character.shape == (18, 100)
    au12 = loop.aus.index(12)
    assert loop.row_r[au12] > AU12_CLOSED_LOOP_MIN_R
    assert loop.r > CLOSED_LOOP_MIN_R
    # the smile starts about a quarter into the clip: AU12 low at the start, high at the end, on both sides
    for m in (loop.human, loop.character):
        assert m[au12, :10].mean() < 1.0 and m[au12, -30:].mean() > 3.0
    written = result.write(tmp_path)
    assert json.loads(written["compare"].read_text())["closed_loop"]["per_au_r"]["AU12"] > AU12_CLOSED_LOOP_MIN_R


def test_no_face_video_is_a_typed_error(shared_data: Path, landmarker_path: Path) -> None:
    video = shared_data / "video" / "no_face.mp4"
    with pytest.raises(InvalidValueError, match="none was found on any of its") as caught:
        run_compare(video, "joy", head="builtin", size=(128, 128), progress=False)
    assert caught.value.field == "video" and "no_face.mp4" in str(caught.value)


def test_face_on_too_few_frames_says_the_share(shared_data: Path, landmarker_path: Path) -> None:
    with pytest.raises(InvalidValueError, match=r"at least 80% of frames \(found on 43%"):
        run_compare(shared_data / "video" / "face_noface.mov", None, head="builtin", size=(128, 128), progress=False)


def test_expression_longer_than_the_video(single_face: Path) -> None:
    from mien.facs.envelope import Envelope

    with pytest.raises(InvalidValueError, match=r"at least as long as the expression \(4.00 s\); it lasts 2.40 s"):
        run_compare(single_face, "joy", head="builtin", envelope=Envelope(2.0, 1.0, 1.0), progress=False)


def test_missing_landmarker_model(single_face: Path, monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("MIEN_FACE_LANDMARKER", str(tmp_path / "nowhere.task"))
    with pytest.raises(MissingAssetError, match="face_landmarker not found"):
        run_compare(single_face, "joy", head="builtin", progress=False)
    monkeypatch.delenv("MIEN_FACE_LANDMARKER")
    monkeypatch.setenv("MIEN_CONFIG", str(tmp_path / "no-config.toml"))
    with pytest.raises(MissingAssetError, match="MIEN_FACE_LANDMARKER"):
        run_compare(single_face, "joy", head="builtin", progress=False)


def test_unknown_names_and_missing_head(single_face: Path, monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    with pytest.raises(UnknownNameError, match="head 'marble'"):
        run_compare(single_face, "joy", head="marble", progress=False)
    with pytest.raises(UnknownNameError, match="expression 'glee-ish'"):
        run_compare(single_face, "glee-ish", head="builtin", progress=False)
    with pytest.raises(InvalidValueError, match="length"):
        run_compare(single_face, "joy", head="builtin", length=1, progress=False)
    monkeypatch.setenv("MIEN_ICT_FACEKIT", str(tmp_path / "no-ict"))
    with pytest.raises(MissingAssetError):
        run_compare(single_face, "joy", head="ict", identity="a", progress=False)


def test_nan_is_not_written_as_nan(tmp_path: Path) -> None:
    text = _fake_result().to_json()
    assert "NaN" not in text and math.isnan(_fake_result().closed_loop.row_r[0])
