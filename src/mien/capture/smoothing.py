"""The One Euro filter (Casiez, Roussel & Vogel, CHI 2012): a low-pass whose cut-off rises with speed.

At rest the cut-off is ``min_cutoff_hz``, so tracker jitter is smoothed away; as a value moves its cut-off
grows by ``beta`` per unit of (filtered) speed, so a blink or a smile onset passes with little lag. The speed
itself is low-passed at ``d_cutoff_hz``. Each channel is filtered on its own, on the samples' real times
(a variable frame rate or a dropped frame changes the smoothing factor, not the cut-off in Hz).

>>> f = OneEuroFilter(min_cutoff_hz=1.0, beta=0.0)
>>> [round(float(f(t, np.array([1.0]))[0]), 3) for t in (0.0, 0.1, 0.2)]
[1.0, 1.0, 1.0]
"""

from __future__ import annotations

import math

import numpy as np

from mien.errors import InvalidValueError

__all__ = ["OneEuroFilter"]


def _alpha(dt_s: float, cutoff_hz: np.ndarray | float) -> np.ndarray:
    """Smoothing factor of a first-order low-pass with ``cutoff_hz`` over a step of ``dt_s`` seconds."""
    tau = 1.0 / (2.0 * math.pi * np.asarray(cutoff_hz, dtype=np.float64))
    return np.asarray(1.0 / (1.0 + tau / dt_s))


class OneEuroFilter:
    """One Euro filter over a vector of channels.

    min_cutoff_hz: cut-off at rest, Hz (lower: smoother and laggier when still). beta: cut-off increase per
    unit of speed (channel units per second; higher: less lag on fast moves). d_cutoff_hz: cut-off of the
    speed estimate, Hz. Each may be a scalar or an (n,) array, one per channel.
    """

    def __init__(
        self,
        min_cutoff_hz: float | np.ndarray = 1.0,
        beta: float | np.ndarray = 0.0,
        d_cutoff_hz: float | np.ndarray = 1.0,
    ) -> None:
        for name, value in (("min_cutoff_hz", min_cutoff_hz), ("d_cutoff_hz", d_cutoff_hz)):
            if not np.all(np.isfinite(value)) or np.any(np.asarray(value) <= 0):
                raise InvalidValueError(name, value, "a positive cut-off frequency in Hz")
        if not np.all(np.isfinite(beta)) or np.any(np.asarray(beta) < 0):
            raise InvalidValueError("beta", beta, "a finite number >= 0")
        self.min_cutoff_hz = np.asarray(min_cutoff_hz, dtype=np.float64)
        self.beta = np.asarray(beta, dtype=np.float64)
        self.d_cutoff_hz = np.asarray(d_cutoff_hz, dtype=np.float64)
        self._t_s: float | None = None
        self._x: np.ndarray | None = None
        self._dx: np.ndarray | None = None

    def reset(self) -> None:
        """Forget the past: the next sample passes unfiltered."""
        self._t_s = self._x = self._dx = None

    def __call__(self, t_s: float, x: np.ndarray) -> np.ndarray:
        """The filtered value of sample ``x`` (n,) at time ``t_s`` seconds (a new array)."""
        value = np.asarray(x, dtype=np.float64)
        if self._x is None or self._t_s is None or self._dx is None:
            self._t_s, self._x, self._dx = float(t_s), value.copy(), np.zeros_like(value)
            return value.copy()
        dt_s = float(t_s) - self._t_s
        if dt_s <= 0.0:  # a repeated time stamp: keep the state, give the last value
            return self._x.copy()
        speed = (value - self._x) / dt_s
        self._dx += _alpha(dt_s, self.d_cutoff_hz) * (speed - self._dx)
        a = _alpha(dt_s, self.min_cutoff_hz + self.beta * np.abs(self._dx))
        self._x += a * (value - self._x)
        self._t_s = float(t_s)
        return self._x.copy()
