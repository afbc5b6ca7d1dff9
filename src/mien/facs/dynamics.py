"""Time-based AU dynamics: held targets approached exponentially, and timed onset/apex/offset actions.

Timed actions share the linear onset/hold/offset envelope of the emotion engine
(:func:`mien.affect.envelope.envelope_value`).

OpenFACS moves every morph a fraction ``Speed`` (0..1) of the way to its target on each tick, so its motion
depends on the frame rate. mien integrates the same first-order system in continuous time,
``x(t + dt) = target + (x(t) - target) * exp(-dt / tau)``, which gives the same pose at any frame rate. A
``Speed`` s at a nominal tick rate f is the time constant ``tau = -1 / (f * ln(1 - s))``
(:func:`time_constant_from_speed`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from mien.affect.envelope import envelope_value
from mien.errors import InvalidValueError
from mien.facs.catalogue import ACTION_UNITS, FACE_CHANNELS, POSE_CHANNELS, au_channels
from mien.facs.intensity import AUSpec, check_intensity, parse_au

__all__ = [
    "DEFAULT_TIME_CONSTANT_S",
    "OPENFACS_TICK_HZ",
    "FacsEngine",
    "TimedAction",
    "check_duration",
    "time_constant_from_speed",
]

OPENFACS_TICK_HZ = 60.0
"""Nominal tick rate at which an OpenFACS ``Speed`` is interpreted (Unity's default frame rate)."""

DEFAULT_TIME_CONSTANT_S = 0.12
"""Default time constant of an AU: 95% of the way in ~0.36 s, in line with spontaneous AU onsets of
0.3-0.5 s (Schmidt, Cohn & Tian 2003)."""

_FAST_AUS = {43: 0.04, 45: 0.04, 46: 0.04}
"""Lid closures are fast (a blink closes in ~0.1-0.2 s)."""

_N_CHANNELS = len(FACE_CHANNELS)
_N_AU_CHANNELS = _N_CHANNELS - len(POSE_CHANNELS)


def check_duration(value: float, field: str) -> float:
    """``value`` as float if finite and >= 0 seconds, else :class:`InvalidValueError`."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InvalidValueError(field, value, "a duration in seconds") from None
    if not math.isfinite(number) or number < 0:
        raise InvalidValueError(field, value, "a finite, non-negative duration in seconds")
    return number


def time_constant_from_speed(speed: float, tick_hz: float = OPENFACS_TICK_HZ) -> float:
    """Time constant (s) equivalent to OpenFACS's per-tick ``speed`` (0..1) at ``tick_hz`` ticks per second.

    ``speed`` 1 is an instant jump (tau 0); ``speed`` 0 never moves (tau infinite).

    >>> round(time_constant_from_speed(0.05), 4)
    0.3249
    """
    try:
        s = float(speed)
    except (TypeError, ValueError):
        raise InvalidValueError("Speed", speed, "a number in 0..1") from None
    if not math.isfinite(s) or not 0.0 <= s <= 1.0:
        raise InvalidValueError("Speed", speed, "a finite number in 0..1")
    if not math.isfinite(tick_hz) or tick_hz <= 0:
        raise InvalidValueError("tick_hz", tick_hz, "a positive tick rate in Hz")
    if s >= 1.0:
        return 0.0
    if s <= 0.0:
        return math.inf
    return -1.0 / (tick_hz * math.log1p(-s))


@dataclass(frozen=True)
class TimedAction:
    """An AU played once with explicit onset, apex and offset durations (seconds)."""

    channels: tuple[int, ...]
    """Face-frame positions it drives."""
    intensity: float
    """Peak intensity, 0..5."""
    start_s: float
    """Time the onset begins."""
    onset_s: float
    """Linear rise duration."""
    apex_s: float
    """Hold duration at peak."""
    offset_s: float
    """Linear fall duration."""

    @property
    def end_s(self) -> float:
        """Time the action has fully decayed."""
        return self.start_s + self.onset_s + self.apex_s + self.offset_s


def _default_taus() -> np.ndarray:
    taus = np.full(_N_CHANNELS, DEFAULT_TIME_CONSTANT_S)
    for code, tau in _FAST_AUS.items():
        if code in ACTION_UNITS:
            taus[list(au_channels(code))] = tau
    taus[_N_AU_CHANNELS:] = 0.25  # head and gaze move more slowly than the face
    return taus


def _spec(au: str | AUSpec) -> AUSpec:
    return au if isinstance(au, AUSpec) else parse_au(au)


class FacsEngine:
    """Held AU targets with first-order dynamics in seconds, plus timed onset/apex/offset actions.

    Call :meth:`advance` with non-decreasing times; it returns the (62,) face frame (a view that the next
    call overwrites: copy it to keep it).

    >>> engine = FacsEngine()
    >>> engine.set("AU12", 3.0, tau_s=0.0)
    >>> float(engine.advance(0.1)[FACE_CHANNELS.index("AU12L")])
    3.0
    """

    def __init__(self, tick_hz: float = OPENFACS_TICK_HZ) -> None:
        self.tick_hz = float(tick_hz)
        self.target = np.zeros(_N_CHANNELS)
        """(62,) held targets (AU intensity 0..5, pose degrees)."""
        self.current = np.zeros(_N_CHANNELS)
        """(62,) smoothed state."""
        self.tau_s = _default_taus()
        """(62,) time constant per channel, seconds."""
        self.actions: list[TimedAction] = []
        self._out = np.zeros(_N_CHANNELS)
        self._decay = np.zeros(_N_CHANNELS)
        self._decay_dt = -1.0
        self._t_s = 0.0
        self._settled = True

    @property
    def time_s(self) -> float:
        """Time of the last :meth:`advance`."""
        return self._t_s

    def set(self, au: str | AUSpec, intensity: float | None = None, tau_s: float | None = None) -> None:
        """Hold ``au`` (e.g. ``"AU12"``, ``"L12C"``) at ``intensity`` (0..5; default: the string's letter, else C).

        ``tau_s`` sets the channel's time constant (0 = jump).
        """
        spec = _spec(au)
        value = check_intensity(intensity if intensity is not None else (spec.intensity or 3.0))
        channels = list(au_channels(spec.code, spec.side))
        action = ACTION_UNITS[spec.code]
        if action.kind != "face":
            value = value * action.degrees_per_unit
        self.target[channels] = value
        if tau_s is not None:
            self.tau_s[channels] = check_duration(tau_s, "tau_s")
            self._decay_dt = -1.0
        self._settled = False

    def set_many(self, intensities: Mapping[str, float], speed: float | None = None, replace: bool = False) -> None:
        """Hold several AUs at once; ``speed`` (OpenFACS, 0..1 per tick at :attr:`tick_hz`) sets their tau.

        With ``replace`` every AU not named goes back to 0 (OpenFACS sends the full state; a missing AU is 0).
        """
        specs = [(_spec(name), value) for name, value in intensities.items()]  # validate before changing state
        values = [check_intensity(value, field=spec.label) for spec, value in specs]
        tau = time_constant_from_speed(speed, self.tick_hz) if speed is not None else None
        if replace:
            self.target[:_N_AU_CHANNELS] = 0.0
        for (spec, _), value in zip(specs, values, strict=True):
            self.set(spec, value, tau_s=tau)
        if replace and tau is not None:
            self.tau_s[:_N_AU_CHANNELS] = tau
            self._decay_dt = -1.0
        self._settled = False

    def set_speed(self, speed: float) -> None:
        """Give every AU channel the time constant of OpenFACS ``speed`` at :attr:`tick_hz`."""
        self.tau_s[:_N_AU_CHANNELS] = time_constant_from_speed(speed, self.tick_hz)
        self._decay_dt = -1.0
        self._settled = False

    def release_all(self) -> None:
        """Set every held target back to neutral (the face relaxes with its time constants)."""
        self.target[:] = 0.0
        self._settled = False

    def play(
        self,
        au: str | AUSpec,
        intensity: float | None = None,
        start_s: float | None = None,
        onset_s: float = 0.4,
        apex_s: float = 0.3,
        offset_s: float = 0.3,
    ) -> TimedAction:
        """Play ``au`` once with an onset/apex/offset envelope starting at ``start_s`` (default: now)."""
        spec = _spec(au)
        value = check_intensity(intensity if intensity is not None else (spec.intensity or 3.0))
        kind = ACTION_UNITS[spec.code]
        if kind.kind != "face":
            value = value * kind.degrees_per_unit
        action = TimedAction(
            channels=au_channels(spec.code, spec.side),
            intensity=value,
            start_s=self._t_s if start_s is None else check_duration(start_s, "start_s"),
            onset_s=check_duration(onset_s, "onset_s"),
            apex_s=check_duration(apex_s, "apex_s"),
            offset_s=check_duration(offset_s, "offset_s"),
        )
        self.actions.append(action)
        return action

    def advance(self, t_s: float) -> np.ndarray:
        """Move to time ``t_s`` (>= the previous time) and return the (62,) frame (reused buffer)."""
        dt = t_s - self._t_s
        if not dt >= 0.0:  # also catches NaN
            raise InvalidValueError("t_s", t_s, f"a time >= the previous time {self._t_s}")
        self._t_s = t_s
        current = self.current
        if not self._settled and dt > 0.0:
            if dt != self._decay_dt:
                with np.errstate(divide="ignore", invalid="ignore"):
                    np.exp(-dt / self.tau_s, out=self._decay)
                np.nan_to_num(self._decay, copy=False, nan=0.0)
                self._decay_dt = dt
            # x <- target + (x - target) * exp(-dt / tau)
            current -= self.target
            current *= self._decay
            current += self.target
            if np.abs(current - self.target).max() < 1e-9:
                current[:] = self.target
                self._settled = True
        if not self.actions:
            return current
        out = self._out
        out[:] = current
        alive = []
        for action in self.actions:
            level = envelope_value(t_s - action.start_s, action.onset_s, action.apex_s, action.offset_s)
            if level > 0.0:
                for channel in action.channels:
                    out[channel] += level * action.intensity
            if t_s < action.end_s:
                alive.append(action)
        self.actions = alive
        return out
