import math

import numpy as np
import pytest

from mien import InvalidValueError
from mien.facs.catalogue import FACE_CHANNELS
from mien.facs.dynamics import FacsEngine, time_constant_from_speed

AU12L = FACE_CHANNELS.index("AU12L")
AU4R = FACE_CHANNELS.index("AU4R")


def openfacs_ticks(speed: float, target: float, n_ticks: int) -> float:
    """OpenFACS's own update: each tick moves a fraction Speed of the way to the target."""
    x = 0.0
    for _ in range(n_ticks):
        x += speed * (target - x)
    return x


@pytest.mark.parametrize("speed", [0.05, 0.2, 0.5])
def test_speed_mode_same_pose_after_one_second_at_30_60_144_hz(speed):
    poses = []
    for hz in (30, 60, 144):
        engine = FacsEngine()
        engine.set_many({"AU12": 5, "AU4": 3}, speed=speed)
        for i in range(1, hz + 1):
            frame = engine.advance(i / hz)
        poses.append(frame.copy())
    np.testing.assert_allclose(poses[0], poses[1], atol=1e-9)
    np.testing.assert_allclose(poses[1], poses[2], atol=1e-9)
    # and it equals OpenFACS's per-tick behaviour at its nominal 60 Hz
    assert poses[1][AU12L] == pytest.approx(openfacs_ticks(speed, 5.0, 60), abs=1e-9)
    assert poses[1][AU4R] == pytest.approx(openfacs_ticks(speed, 3.0, 60), abs=1e-9)


def test_time_constant_from_speed_edges():
    assert time_constant_from_speed(1.0) == 0.0
    assert math.isinf(time_constant_from_speed(0.0))
    assert time_constant_from_speed(0.05, tick_hz=60) == pytest.approx(-1 / (60 * math.log(0.95)))
    with pytest.raises(InvalidValueError, match="Speed"):
        time_constant_from_speed(1.5)
    with pytest.raises(InvalidValueError, match="Speed"):
        time_constant_from_speed(float("nan"))


def test_exponential_approach_in_seconds():
    engine = FacsEngine()
    engine.set("AU12", 4.0, tau_s=0.2)
    assert engine.advance(0.2)[AU12L] == pytest.approx(4.0 * (1 - math.exp(-1)))
    assert engine.advance(3.0)[AU12L] == pytest.approx(4.0, abs=1e-4)


def test_timed_action_onset_apex_offset():
    engine = FacsEngine()
    engine.play("AU12E", onset_s=0.4, apex_s=0.3, offset_s=0.3, start_s=0.0)
    assert engine.advance(0.2)[AU12L] == pytest.approx(2.5)
    assert engine.advance(0.5)[AU12L] == pytest.approx(5.0)
    assert engine.advance(0.85)[AU12L] == pytest.approx(2.5)
    assert engine.advance(1.01)[AU12L] == 0.0
    assert engine.actions == []


def test_head_codes_turn_into_degrees():
    engine = FacsEngine()
    engine.set("AU51C", tau_s=0.0)
    assert engine.advance(0.1)[FACE_CHANNELS.index("head_yaw_deg")] == pytest.approx(18.0)


def test_bad_input_is_rejected_without_changing_state():
    engine = FacsEngine()
    with pytest.raises(InvalidValueError, match="AU4"):
        engine.set_many({"AU12": 3, "AU4": 7})
    assert not engine.target.any()
    with pytest.raises(InvalidValueError, match="onset_s"):
        engine.play("AU12", 3, onset_s=-1)
    engine.advance(1.0)
    with pytest.raises(InvalidValueError, match="t_s"):
        engine.advance(0.5)
    with pytest.raises(InvalidValueError, match="t_s"):
        engine.advance(float("nan"))


def test_batch_rows_are_independent_and_equal_the_single_engine():
    from mien.facs.dynamics import FacsBatch

    batch = FacsBatch(3)
    single = FacsEngine()
    batch.set_many(slice(None), {"AU4": 2.0})
    single.set_many({"AU4": 2.0})
    batch.set_speed(1, 0.1, au="AU12")
    single.set_speed(0.1, au="AU12")
    batch.set(1, "AU12", 4.0)
    single.set("AU12", 4.0)
    batch.play([1, 2], "AU6", 3.0, start_s=0.1, onset_s=0.2, apex_s=0.1, offset_s=0.2)
    single.play("AU6", 3.0, start_s=0.1, onset_s=0.2, apex_s=0.1, offset_s=0.2)
    assert len(batch.actions(1)) == 1 and batch.actions(0) == []
    for i in range(1, 61):
        frames = batch.advance(i / 60)
        np.testing.assert_allclose(frames[1], single.advance(i / 60), atol=1e-12)
    assert frames[0, AU12L] == 0.0 and frames[2, AU12L] == 0.0
    assert frames[1, AU12L] == pytest.approx(4.0 * (1 - 0.9**60), abs=1e-9)  # Speed 0.1 per 60 Hz tick
    assert single.actions == [] and batch.actions(2) == []
    batch.add_rows(1)
    batch.reset_rows(np.array([1]))
    frames = batch.advance(1.5)
    assert frames.shape == (4, len(FACE_CHANNELS)) and not frames[1].any() and not frames[3].any()
    assert frames[0, AU4R] == pytest.approx(2.0, abs=1e-4)
