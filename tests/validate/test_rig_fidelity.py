"""Rig fidelity: the statistics on hand-computed numbers, and a small real run on the built-in head."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError, MissingAssetError, UnknownNameError
from mien.validate.rig_fidelity import RigFidelity, fidelity_stats, primary_blendshapes, run_rig_fidelity
from mien.validate.statistics import least_squares_slope, pearson_r


def test_pearson_and_slope_match_hand_computed_values() -> None:
    x = np.array([0.0, 1.0, 2.0, 3.0])
    y = np.array([0.0, 2.0, 4.0, 7.0])
    # mean x 1.5, mean y 3.25; sum dx*dy = 11.5, sum dx^2 = 5, sum dy^2 = 26.75
    assert least_squares_slope(x, y) == pytest.approx(2.3)
    assert pearson_r(x, y) == pytest.approx(11.5 / math.sqrt(5.0 * 26.75))
    assert math.isnan(pearson_r(x, np.full(4, 2.0)))  # constant response: undefined, not 0
    assert math.isnan(least_squares_slope(np.ones(4), y))
    # NaN pairs (no face found) are left out
    assert least_squares_slope(np.array([0.0, 1.0, 2.0, 9.0]), np.array([0.0, 1.0, 2.0, np.nan])) == pytest.approx(1.0)


def test_fidelity_stats_on_synthetic_detections() -> None:
    intensities = (1.0, 3.0, 5.0)
    neutral = np.array([0.5, 0.0, 0.2])
    detected = np.array(
        [
            # AU a: read back at half scale, leaking into c at a tenth
            [[1.0, 0.0, 0.3], [2.0, 0.0, 0.5], [3.0, 0.0, 0.7]],
            # AU b: barely moves itself (range 0.05 < MIN_RESPONSE); c dominates
            [[0.5, 0.0, 1.2], [0.5, 0.05, 3.2], [0.5, 0.05, 5.0]],
        ]
    )
    stats = fidelity_stats(intensities, neutral, detected, own=[0, 1])
    # x = 0, 1, 3, 5 (mean 2.25, sum dx^2 = 14.75); AU a: y = 0.5, 1, 2, 3 (sum dy^2 3.6875) -> sum dx*dy 7.375
    assert stats["slope"][0] == pytest.approx(7.375 / 14.75)
    assert stats["r"][0] == pytest.approx(7.375 / math.sqrt(14.75 * 3.6875))
    assert math.isnan(stats["r"][1])
    assert stats["crosstalk"].shape == (2, 3)
    assert stats["crosstalk"][0, 2] == pytest.approx(0.1)  # c: 0.2, 0.3, 0.5, 0.7
    assert stats["crosstalk"][0, 1] == 0.0
    assert stats["crosstalk"][1, 0] == 0.0
    assert stats["slope"][1] == stats["crosstalk"][1, 1]
    assert stats["strongest"].tolist() == [True, False]
    # minus the neutral: a's 3.0 - 0.5 = 2.5 still tops c's 0.7 - 0.2
    assert fidelity_stats(intensities, neutral, detected, [0, 1], subtract_neutral=True)["strongest"].tolist() == [
        True,
        False,
    ]
    with pytest.raises(InvalidValueError):
        fidelity_stats(intensities, neutral, detected[:, :2], own=[0, 1])


def test_primary_blendshapes_keep_targets_at_half_the_strongest_weight() -> None:
    matrix = np.array([[0.2, 0.1, 0.09, 0.0], [0.0, 0.0, 0.0, 0.3]])
    assert primary_blendshapes(matrix, [0]).tolist() == [0, 1]
    assert primary_blendshapes(matrix, [0, 1]).tolist() == [0, 3]


def test_bad_input_raises_typed_errors(monkeypatch: pytest.MonkeyPatch) -> None:
    with pytest.raises(UnknownNameError):
        run_rig_fidelity([("nohead", None)], aus=[12])
    with pytest.raises(UnknownNameError):
        run_rig_fidelity([("builtin", None)], aus=[99])
    with pytest.raises(InvalidValueError):
        run_rig_fidelity([("builtin", None)], aus=[12], intensities=(0, 6))
    monkeypatch.setenv("MIEN_ICT_FACEKIT", "/nonexistent/ict-facekit")
    with pytest.raises(MissingAssetError, match="MIEN_ICT_FACEKIT"):
        run_rig_fidelity([("ict", "a")], aus=[12])


def test_small_real_run_on_the_builtin_head(landmarker_path: Path, shared_data: Path, tmp_path: Path) -> None:
    try:
        result = run_rig_fidelity(
            [("builtin", None)], aus=[12, 26, 1], intensities=(1, 3, 5), progress=False, human_data=shared_data
        )
    except MissingAssetError as error:
        pytest.skip(f"an asset is missing: {error}")
    head = result.heads[0]
    assert head.aus == (12, 26, 1)
    assert head.detected.shape == (3, 3, len(head.detected_aus))
    assert np.all(np.isfinite(head.detected))  # MediaPipe finds the frontal built-in head on every render
    au12, au26, au1 = 0, 1, 2
    # measured: AU12 r 0.97, slope 0.89, E read back at 4.4; AU1 r 0.96, slope 0.59
    assert head.r[au12] > 0.9
    assert head.slope[au12] > 0.7
    assert head.r[au1] > 0.8
    assert head.strongest[au12] and head.strongest[au1]
    # AU26 on the built-in head: since the jaw's second pass (rotation + forward slide, an oval opening) the drop
    # reads as AU26 (measured r 0.99, slope 0.67), with some lips-parting (AU25) beside it
    assert head.strongest[au26] and head.r[au26] > 0.9 and head.slope[au26] > 0.4
    assert head.seen_on_human[au12] == "yes"  # the shared clip smiles
    assert head.seen_on_human[au26] == "untested"
    assert result.human.n_faces > 50

    paths = result.write(tmp_path)
    assert {p.name for p in paths.values()} == {
        "rig_fidelity.json",
        "builtin_scatter.png",
        "builtin_crosstalk.png",
        "builtin_contact_sheet.png",
    }
    assert all(p.stat().st_size > 1000 for p in paths.values())
    data = json.loads(paths["rig_fidelity"].read_text("utf-8"))
    assert data["heads"][0]["per_au"]["AU12"]["strongest"] is True
    assert RigFidelity.read(paths["rig_fidelity"]).to_dict() == data


def test_a_users_head_file_gets_its_rig_measured(landmarker_path: Path, tmp_path: Path) -> None:
    """`mien validate rig` and `report` take a character file (the head its path, as `load_head` does): AU12 on a
    VALID avatar, whose Rocketbox smile the calibration drives as far as ICT's, reads back as AU12."""
    from tests.conftest import valid_avatar

    path = valid_avatar("White_F_1_Casual.glb")
    with pytest.warns(UserWarning, match="lacks targets mouthClose"):
        result = run_rig_fidelity([("file", str(path))], aus=[12], intensities=(2, 5), progress=False)
    head = result.heads[0]
    assert head.label == "White_F_1_Casual.glb"
    assert head.strongest[0] and head.r[0] > 0.9, (head.r, head.slope)
    written = result.write(tmp_path / "rig")
    assert (tmp_path / "rig" / "white_f_1_casual_glb_scatter.png").is_file(), sorted(p.name for p in written.values())
