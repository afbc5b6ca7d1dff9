"""Onset / hold / decay envelopes, scalar and vectorised."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from mien.errors import InvalidValueError
from mien.facs.envelope import Envelope, envelope_value, envelope_values


def test_study_timings() -> None:
    env = Envelope()
    assert (env.onset_s, env.hold_s, env.decay_s, env.total_s) == (0.4, 0.3, 0.3, pytest.approx(1.0))
    assert env.value(-0.01) == 0.0
    assert env.value(0.0) == 0.0
    assert env.value(0.1) == pytest.approx(0.25)
    assert env.value(0.2) == pytest.approx(0.5)  # 0.2 s into a 0.4 s onset: half intensity
    assert [env.value(t) for t in (0.4, 0.5, 0.6, 0.69)] == [1.0, 1.0, 1.0, 1.0]  # flat hold
    assert env.value(0.85) == pytest.approx(0.5)
    assert env.value(1.0) == 0.0 and env.value(5.0) == 0.0  # zero after decay


def test_zero_phases_and_longer_envelopes() -> None:
    assert Envelope(0.0, 0.5, 0.0).value(0.0) == 1.0
    assert Envelope(0.0, 0.5, 0.0).value(0.5) == 0.0
    assert Envelope(0.5, 0.0, 0.5).value(0.5) == 1.0
    slow = Envelope(0.5, 0.8, 0.7)
    assert slow.total_s == pytest.approx(2.0)
    assert slow.value(1.65) == pytest.approx(0.5)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"onset_s": -0.1}, "onset_s"),
        ({"hold_s": float("nan")}, "hold_s"),
        ({"decay_s": float("inf")}, "decay_s"),
        ({"onset_s": "x"}, "onset_s"),
        ({"onset_s": 0.0, "hold_s": 0.0, "decay_s": 0.0}, "onset_s + hold_s + decay_s"),
    ],
)
def test_validation(kwargs: dict[str, Any], field: str) -> None:
    with pytest.raises(InvalidValueError) as info:
        Envelope(**kwargs)
    assert info.value.field == field


@pytest.mark.parametrize("durations", [(0.4, 0.3, 0.3), (0.0, 0.3, 0.3), (0.4, 0.0, 0.0), (0.0, 0.0, 1.0)])
def test_vectorised_matches_scalar(durations: tuple[float, float, float]) -> None:
    t = np.concatenate([np.linspace(-0.5, 1.5, 401), [0.0, 0.2, 0.4, 0.7, 1.0]])
    expected = [envelope_value(float(x), *durations) for x in t]
    np.testing.assert_array_equal(envelope_values(t, *durations), expected)


def test_vectorised_broadcasts_per_event_durations() -> None:
    elapsed = np.array([[0.2, 0.2], [0.9, 0.9]])  # (characters, events)
    onset = np.array([0.4, 0.2])
    values = envelope_values(elapsed, onset, 0.3, np.array([0.3, 1.0]))
    np.testing.assert_allclose(values, [[0.5, 1.0], [1 / 3, 0.6]])
    assert envelope_values(0.2, 0.4, 0.3, 0.3).shape == ()
