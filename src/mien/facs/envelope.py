"""Onset / hold / decay envelopes of emotion events (Broekens et al.: linear rise, flat hold, linear fall).

The study used onset 0.4 s, hold 0.3 s, decay 0.3 s (a deliberately short 1 s expression); the paper
recommends 1-2 s in total for real use, so all three durations are parameters.

Phases are half-open intervals of the time since the event started: onset ``[0, onset_s)`` rises linearly
from 0, hold ``[onset_s, onset_s + hold_s)`` is 1, decay ``[onset_s + hold_s, total_s)`` falls linearly to 0;
before 0 and from ``total_s`` on the value is 0. A zero-length phase is skipped (onset 0 starts at 1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mien.errors import InvalidValueError

__all__ = ["Envelope", "envelope_value", "envelope_values"]


def _check_duration(field: str, value: object) -> float:
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InvalidValueError(field, value, "a finite number of seconds >= 0") from None
    if not (0.0 <= v < math.inf):  # also false for NaN
        raise InvalidValueError(field, value, "a finite number of seconds >= 0")
    return v


@dataclass(frozen=True)
class Envelope:
    """Intensity profile of one emotion event over time (all durations in seconds).

    >>> env = Envelope()
    >>> round(env.value(0.2), 9), env.value(0.5), round(env.value(0.85), 9), env.value(1.0)
    (0.5, 1.0, 0.5, 0.0)
    """

    onset_s: float = 0.4
    """Linear rise from 0 to 1, seconds (>= 0)."""
    hold_s: float = 0.3
    """Flat at 1, seconds (>= 0)."""
    decay_s: float = 0.3
    """Linear fall from 1 to 0, seconds (>= 0)."""

    def __post_init__(self) -> None:
        onset = _check_duration("onset_s", self.onset_s)
        hold = _check_duration("hold_s", self.hold_s)
        decay = _check_duration("decay_s", self.decay_s)
        if onset + hold + decay <= 0.0:
            raise InvalidValueError("onset_s + hold_s + decay_s", 0.0, "a total duration > 0 s")
        object.__setattr__(self, "onset_s", onset)
        object.__setattr__(self, "hold_s", hold)
        object.__setattr__(self, "decay_s", decay)

    @property
    def total_s(self) -> float:
        """Whole duration, seconds."""
        return self.onset_s + self.hold_s + self.decay_s

    def value(self, elapsed_s: float) -> float:
        """Envelope (0..1) at ``elapsed_s`` seconds after the event started."""
        return envelope_value(elapsed_s, self.onset_s, self.hold_s, self.decay_s)


def envelope_value(elapsed_s: float, onset_s: float, hold_s: float, decay_s: float) -> float:
    """Scalar envelope (0..1) on plain floats, unvalidated (the per-frame path)."""
    if elapsed_s < 0.0:
        return 0.0
    if elapsed_s < onset_s:
        return elapsed_s / onset_s
    elapsed_s -= onset_s
    if elapsed_s < hold_s:
        return 1.0
    elapsed_s -= hold_s
    if elapsed_s < decay_s:
        return 1.0 - elapsed_s / decay_s
    return 0.0


def envelope_values(
    elapsed_s: np.ndarray | float,
    onset_s: np.ndarray | float,
    hold_s: np.ndarray | float,
    decay_s: np.ndarray | float,
) -> np.ndarray:
    """Vectorised :func:`envelope_value`: the four arguments broadcast together; returns float64 in [0, 1].

    For the batch character: e.g. ``elapsed_s`` (n_characters, n_events) with per-event durations of the
    same shape, or scalars. Durations are assumed valid (finite, >= 0), as :class:`Envelope` checks them.

    >>> envelope_values(np.array([-0.1, 0.0, 0.2, 0.4, 0.7, 0.85, 1.0]), 0.4, 0.3, 0.3).round(9).tolist()
    [0.0, 0.0, 0.5, 1.0, 1.0, 0.5, 0.0]
    """
    t = np.asarray(elapsed_s, dtype=np.float64)
    onset = np.asarray(onset_s, dtype=np.float64)
    hold = np.asarray(hold_s, dtype=np.float64)
    decay = np.asarray(decay_s, dtype=np.float64)
    tiny = np.finfo(np.float64).tiny
    # same arithmetic as envelope_value, so both agree to the last bit
    after_onset = t - onset
    after_hold = after_onset - hold
    with np.errstate(over="ignore"):
        rise = np.where(after_onset >= 0.0, 1.0, t / np.maximum(onset, tiny))
        falling = np.where(after_hold < decay, 1.0 - after_hold / np.maximum(decay, tiny), 0.0)
        fall = np.where(after_hold < 0.0, 1.0, falling)
    return np.asarray(np.clip(np.minimum(rise, fall), 0.0, 1.0))
