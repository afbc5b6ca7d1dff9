"""Time-based AU dynamics: held targets approached exponentially, and timed onset/apex/offset actions.

Timed actions share the linear onset/hold/offset envelope of the emotion engine
(:func:`mien.facs.envelope.envelope_values`). :class:`FacsBatch` holds the layer of n characters (one
row each); :class:`FacsEngine`, one character, is a batch of one, so both run the same code.

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

from mien.errors import InvalidValueError
from mien.facs.catalogue import ACTION_UNITS, FACE_CHANNELS, POSE_CHANNELS, au_channels
from mien.facs.envelope import envelope_values
from mien.facs.intensity import AUSpec, check_intensity, parse_au

RowIndex = int | slice | np.ndarray | list[int]
"""Rows of a batch: an int, a slice or an int array."""

__all__ = [
    "DEFAULT_TIME_CONSTANT_S",
    "OPENFACS_TICK_HZ",
    "FacsBatch",
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


_DEFAULT_TAUS = _default_taus()


def _spec(au: str | AUSpec) -> AUSpec:
    return au if isinstance(au, AUSpec) else parse_au(au)


def _au_value(spec: AUSpec, intensity: float | None, field: str = "intensity") -> float:
    """Checked intensity 0..5 of ``spec`` (default: its letter, else C), in degrees for head and eye codes."""
    value = check_intensity(intensity if intensity is not None else (spec.intensity or 3.0), field=field)
    action = ACTION_UNITS[spec.code]
    return value * action.degrees_per_unit if action.kind != "face" else value


class FacsBatch:
    """The FACS layer of n characters: held AU targets with first-order dynamics, plus timed actions.

    Rows are characters. ``rows`` arguments are anything that indexes the first axis of a numpy array (an
    int, a slice, an int array); callers validate them. :meth:`advance` writes (n, 62) frames.

    >>> batch = FacsBatch(2)
    >>> batch.set(1, "AU12", 3.0, tau_s=0.0)
    >>> batch.advance(0.1)[:, FACE_CHANNELS.index("AU12L")].tolist()
    [0.0, 3.0]
    """

    def __init__(self, n_rows: int = 0, tick_hz: float = OPENFACS_TICK_HZ) -> None:
        if not (math.isfinite(tick_hz) and tick_hz > 0):
            raise InvalidValueError("tick_hz", tick_hz, "a positive tick rate in Hz")
        self.tick_hz = float(tick_hz)
        """Nominal tick rate at which an OpenFACS ``Speed`` is interpreted, Hz."""
        self.target = np.zeros((n_rows, _N_CHANNELS))
        """(n, 62) held targets (AU intensity 0..5, pose degrees)."""
        self.current = np.zeros((n_rows, _N_CHANNELS))
        """(n, 62) smoothed state."""
        self.tau_s = np.tile(_DEFAULT_TAUS, (n_rows, 1))
        """(n, 62) time constant per channel, seconds."""
        self._out = np.zeros((n_rows, _N_CHANNELS))
        self._decay = np.zeros((n_rows, _N_CHANNELS))
        self._decay_dt = -1.0
        self._t_s = 0.0
        self._settled = True
        # timed actions, one entry per (action, channel): parallel 1-D arrays
        self._act_id = np.zeros(0, np.int64)
        self._act_row = np.zeros(0, np.int64)
        self._act_channel = np.zeros(0, np.int64)
        self._act = np.zeros((0, 5))  # start_s, onset_s, apex_s, offset_s, intensity
        self._next_id = 0

    @property
    def n_rows(self) -> int:
        """Number of rows."""
        return int(self.target.shape[0])

    @property
    def time_s(self) -> float:
        """Time of the last :meth:`advance`, seconds."""
        return self._t_s

    def add_rows(self, count: int) -> None:
        """Append ``count`` neutral rows (default time constants, no actions)."""
        self.target = np.concatenate([self.target, np.zeros((count, _N_CHANNELS))])
        self.current = np.concatenate([self.current, np.zeros((count, _N_CHANNELS))])
        self.tau_s = np.concatenate([self.tau_s, np.tile(_DEFAULT_TAUS, (count, 1))])
        self._out = np.zeros_like(self.target)
        self._decay = np.zeros_like(self.target)
        self._decay_dt = -1.0

    def reset_rows(self, rows: np.ndarray) -> None:
        """Put ``rows`` back to neutral at once (targets, state, time constants) and drop their actions."""
        self.target[rows] = 0.0
        self.current[rows] = 0.0
        self.tau_s[rows] = _DEFAULT_TAUS
        self._decay_dt = -1.0
        if self._act_row.size:
            self._keep_actions(~np.isin(self._act_row, np.atleast_1d(rows)))

    def set(
        self, rows: RowIndex, au: str | AUSpec, intensity: float | None = None, *, tau_s: float | None = None
    ) -> None:
        """Hold ``au`` (e.g. ``"AU12"``, ``"L12C"``) at ``intensity`` (0..5; default: the string's letter, else C).

        ``tau_s`` sets the channels' time constant (0 = jump).
        """
        spec = _spec(au)
        value = _au_value(spec, intensity)
        tau = check_duration(tau_s, "tau_s") if tau_s is not None else None
        channels = list(au_channels(spec.code, spec.side))
        row_ids = np.atleast_1d(np.arange(self.n_rows)[rows])[:, None]
        self.target[row_ids, channels] = value
        if tau is not None:
            self.tau_s[row_ids, channels] = tau
            self._decay_dt = -1.0
        self._settled = False

    def set_many(
        self, rows: RowIndex, intensities: Mapping[str, float], *, speed: float | None = None, replace: bool = False
    ) -> None:
        """Hold several AUs at once; ``speed`` (OpenFACS, 0..1 per tick at :attr:`tick_hz`) sets their tau.

        With ``replace`` every AU not named goes back to 0 (OpenFACS sends the full state; a missing AU is 0)
        and ``speed`` applies to every AU channel. Nothing changes when any value is bad.
        """
        if not isinstance(intensities, Mapping):
            raise InvalidValueError("intensities", intensities, "a mapping of AU name -> intensity 0..5")
        specs = [(_spec(name), value) for name, value in intensities.items()]  # validate before changing state
        values = [_au_value(spec, value, field=spec.label) for spec, value in specs]
        tau = time_constant_from_speed(speed, self.tick_hz) if speed is not None else None
        row_ids = np.atleast_1d(np.arange(self.n_rows)[rows])[:, None]
        if replace:
            self.target[row_ids, np.arange(_N_AU_CHANNELS)] = 0.0
            if tau is not None:
                self.tau_s[row_ids, np.arange(_N_AU_CHANNELS)] = tau
        for (spec, _), value in zip(specs, values, strict=True):
            channels = list(au_channels(spec.code, spec.side))
            self.target[row_ids, channels] = value
            if tau is not None:
                self.tau_s[row_ids, channels] = tau
        self._decay_dt = -1.0
        self._settled = False

    def set_targets(self, rows: np.ndarray, targets: np.ndarray, tau_s: np.ndarray | None = None) -> None:
        """Hold full AU states in one write (the server's OpenFACS messages, names resolved once by the caller).

        ``rows`` (k,) distinct int rows; ``targets`` (k, n_au_channels) intensities 0..5 in
        :data:`~mien.facs.catalogue.FACE_CHANNELS` order (every AU channel; head and gaze are left alone);
        ``tau_s`` (k,) time constant in seconds of every AU channel of each row, NaN keeps that row's. The
        same state as :meth:`set_many` with ``replace``. Nothing changes when any value is bad.
        """
        targets = np.asarray(targets, dtype=np.float64)
        if targets.shape != (len(rows), _N_AU_CHANNELS) or not (
            targets.size == 0 or (targets.min() >= 0.0 and targets.max() <= 5.0)  # also false for NaN
        ):
            raise InvalidValueError("targets", targets, f"({len(rows)}, {_N_AU_CHANNELS}) intensities in [0, 5]")
        taus = None if tau_s is None else np.asarray(tau_s, dtype=np.float64)
        if taus is not None and (taus.shape != (len(rows),) or bool((taus < 0.0).any())):
            raise InvalidValueError("tau_s", tau_s, f"({len(rows)},) time constants >= 0 s (NaN: keep)")
        self.target[rows, :_N_AU_CHANNELS] = targets
        if taus is not None:
            given = ~np.isnan(taus)
            self.tau_s[rows[given], :_N_AU_CHANNELS] = taus[given, None]
        self._decay_dt = -1.0
        self._settled = False

    def set_speed(self, rows: RowIndex, speed: float, au: str | AUSpec | None = None) -> None:
        """Give every AU channel (or only ``au``'s) of ``rows`` the time constant of OpenFACS ``speed``."""
        tau = time_constant_from_speed(speed, self.tick_hz)
        if au is None:
            channels = list(range(_N_AU_CHANNELS))
        else:
            spec = _spec(au)
            channels = list(au_channels(spec.code, spec.side))
        row_ids = np.atleast_1d(np.arange(self.n_rows)[rows])[:, None]
        self.tau_s[row_ids, channels] = tau
        self._decay_dt = -1.0
        self._settled = False

    def release_all(self, rows: RowIndex) -> None:
        """Set every held target of ``rows`` back to neutral (the face relaxes with its time constants)."""
        self.target[rows] = 0.0
        self._settled = False

    def play(
        self,
        rows: RowIndex,
        au: str | AUSpec,
        intensity: float | None = None,
        *,
        onset_s: float = 0.4,
        apex_s: float = 0.3,
        offset_s: float = 0.3,
        start_s: float | None = None,
    ) -> TimedAction:
        """Play ``au`` once on ``rows`` with an onset/apex/offset envelope from ``start_s`` (default: now)."""
        spec = _spec(au)
        value = _au_value(spec, intensity)
        action = TimedAction(
            channels=au_channels(spec.code, spec.side),
            intensity=value,
            start_s=self._t_s if start_s is None else check_duration(start_s, "start_s"),
            onset_s=check_duration(onset_s, "onset_s"),
            apex_s=check_duration(apex_s, "apex_s"),
            offset_s=check_duration(offset_s, "offset_s"),
        )
        row_ids = np.atleast_1d(np.arange(self.n_rows)[rows])
        rows_rep = np.repeat(row_ids, len(action.channels))
        channels = np.tile(np.array(action.channels), len(row_ids))
        ids = self._next_id + np.repeat(np.arange(len(row_ids)), len(action.channels))
        self._next_id += len(row_ids)
        params = (action.start_s, action.onset_s, action.apex_s, action.offset_s, action.intensity)
        self._act_id = np.concatenate([self._act_id, ids])
        self._act_row = np.concatenate([self._act_row, rows_rep])
        self._act_channel = np.concatenate([self._act_channel, channels])
        self._act = np.concatenate([self._act, np.tile(params, (len(rows_rep), 1))])
        return action

    def actions(self, row: int) -> list[TimedAction]:
        """The timed actions of ``row`` not yet finished (as of the last :meth:`advance`)."""
        out = []
        mine = np.flatnonzero(self._act_row == row)
        for action_id in dict.fromkeys(self._act_id[mine].tolist()):
            entries = mine[self._act_id[mine] == action_id]
            start, onset, apex, offset, value = self._act[entries[0]].tolist()
            channels = tuple(int(c) for c in self._act_channel[entries])
            out.append(TimedAction(channels, value, start, onset, apex, offset))
        return out

    def _keep_actions(self, keep: np.ndarray) -> None:
        self._act_id = self._act_id[keep]
        self._act_row = self._act_row[keep]
        self._act_channel = self._act_channel[keep]
        self._act = self._act[keep]

    def advance(self, t_s: float) -> np.ndarray:
        """Move to time ``t_s`` (>= the previous time) and return the (n, 62) frames (a reused buffer)."""
        dt = t_s - self._t_s
        if not dt >= 0.0:  # also catches NaN
            raise InvalidValueError("t_s", t_s, f"a time >= the previous time {self._t_s}")
        self._t_s = t_s
        current = self.current
        if not self._settled and dt > 0.0:
            # a fixed tick rate gives dt that differ in the last bits: reuse the factors then
            if abs(dt - self._decay_dt) > 1e-9 * dt:
                with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                    np.divide(-dt, self.tau_s, out=self._decay)
                    np.exp(self._decay, out=self._decay)
                np.nan_to_num(self._decay, copy=False, nan=0.0)
                self._decay_dt = dt
            # x <- target + (x - target) * exp(-dt / tau)
            current -= self.target
            current *= self._decay
            if current.size == 0 or np.abs(current).max() < 1e-9:
                current[:] = self.target
                self._settled = True
            else:
                current += self.target
        if not self._act_row.size:
            return current
        out = self._out
        out[:] = current
        act = self._act
        levels = envelope_values(t_s - act[:, 0], act[:, 1], act[:, 2], act[:, 3])
        levels *= act[:, 4]
        np.add.at(out, (self._act_row, self._act_channel), levels)
        alive = t_s < act[:, 0] + act[:, 1] + act[:, 2] + act[:, 3]
        if not alive.all():
            self._keep_actions(alive)
        return out


class FacsEngine:
    """The FACS layer of one character: a :class:`FacsBatch` of one row (one implementation of both).

    Call :meth:`advance` with non-decreasing times; it returns the (62,) face frame (a view that the next
    call overwrites: copy it to keep it).

    >>> engine = FacsEngine()
    >>> engine.set("AU12", 3.0, tau_s=0.0)
    >>> float(engine.advance(0.1)[FACE_CHANNELS.index("AU12L")])
    3.0
    """

    def __init__(self, tick_hz: float = OPENFACS_TICK_HZ) -> None:
        self.batch = FacsBatch(1, tick_hz)
        """The one-row batch doing the work."""

    @property
    def tick_hz(self) -> float:
        """Nominal tick rate of OpenFACS ``Speed`` values, Hz."""
        return self.batch.tick_hz

    @property
    def target(self) -> np.ndarray:
        """(62,) held targets (AU intensity 0..5, pose degrees)."""
        return self.batch.target[0]

    @property
    def current(self) -> np.ndarray:
        """(62,) smoothed state."""
        return self.batch.current[0]

    @property
    def tau_s(self) -> np.ndarray:
        """(62,) time constant per channel, seconds."""
        return self.batch.tau_s[0]

    @property
    def actions(self) -> list[TimedAction]:
        """Timed actions not yet finished."""
        return self.batch.actions(0)

    @property
    def time_s(self) -> float:
        """Time of the last :meth:`advance`."""
        return self.batch.time_s

    def set(self, au: str | AUSpec, intensity: float | None = None, *, tau_s: float | None = None) -> None:
        """Hold ``au`` at ``intensity`` (see :meth:`FacsBatch.set`)."""
        self.batch.set(0, au, intensity, tau_s=tau_s)

    def set_many(self, intensities: Mapping[str, float], *, speed: float | None = None, replace: bool = False) -> None:
        """Hold several AUs at once (see :meth:`FacsBatch.set_many`)."""
        self.batch.set_many(0, intensities, speed=speed, replace=replace)

    def set_speed(self, speed: float, au: str | AUSpec | None = None) -> None:
        """Give every AU channel (or ``au``'s) the time constant of OpenFACS ``speed`` at :attr:`tick_hz`."""
        self.batch.set_speed(0, speed, au)

    def release_all(self) -> None:
        """Set every held target back to neutral (the face relaxes with its time constants)."""
        self.batch.release_all(0)

    def play(
        self,
        au: str | AUSpec,
        intensity: float | None = None,
        *,
        onset_s: float = 0.4,
        apex_s: float = 0.3,
        offset_s: float = 0.3,
        start_s: float | None = None,
    ) -> TimedAction:
        """Play ``au`` once with an onset/apex/offset envelope starting at ``start_s`` (default: now)."""
        return self.batch.play(0, au, intensity, onset_s=onset_s, apex_s=apex_s, offset_s=offset_s, start_s=start_s)

    def advance(self, t_s: float) -> np.ndarray:
        """Move to time ``t_s`` (>= the previous time) and return the (62,) frame (reused buffer)."""
        return self.batch.advance(t_s)[0]
