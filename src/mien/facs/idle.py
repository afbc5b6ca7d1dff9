"""Idle behaviour: blinks, micro random walks (OpenFACS), gaze shifts and head wobble (Broekens).

Everything is a pure function of the seed and the time, drawn from :mod:`mien.facs.counter_random`, so a
face at time t is reproducible. :class:`IdleBatch` runs n characters; one character's :class:`Idle` is a
batch of one, so both are the same code.

- Blinks (OpenFACS): the time from one blink's start to the next ~ Normal(6 s, 2 s) (redrawn values below the
  blink duration are clamped to it), each 360 ms: 180 ms closing, 180 ms opening, AU45 peaking at E.
- Random walks (OpenFACS): on each tick (60 Hz nominal, :attr:`IdleSettings.tick_hz`) a walk moves with
  probability 0.8; at position m in [-1, 1] it steps up with probability ``p = 1 - (a + b m)`` and down
  otherwise, clamped to [-1, 1]. Mouth corners (one walk per side): a=0.5, b=0.5, step 0.02, m > 0 adds AU12
  and m < 0 adds AU15 on that side. Eyelids (one walk for both): a=0.8, b=0.2, step 0.02, m > 0 adds AU5 and
  m < 0 adds AU43 (this walk's drift is downward by its formula, so the lids rest slightly lowered and
  flutter). Neck twist and side: a=0.6, b=0.4, step 0.001, to head yaw and roll in degrees.
- Gaze shifts (Broekens): fixations left / straight / right, each held 1.5-4 s, with 60 ms saccades.
- Head wobble (Broekens): a slow sinusoidal yaw and roll with a seeded phase.
"""

from __future__ import annotations

import math
import operator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mien.errors import InvalidValueError
from mien.facs.catalogue import channel_index
from mien.facs.counter_random import normal, stream_keys, uniform, uniform_from_keys

__all__ = [
    "EYELID_WALK",
    "IDLE_COLUMNS",
    "MOUTH_WALK",
    "NECK_WALK",
    "Idle",
    "IdleBatch",
    "IdleSettings",
    "RandomWalk",
    "blink_level",
]


@dataclass(frozen=True)
class RandomWalk:
    """OpenFACS micro-motion: moves with ``move_probability`` per tick, up with ``p = 1 - (a + b m)``."""

    a: float
    """Constant term of the step-down probability."""
    b: float
    """Position term: a move in one direction makes that direction less likely next time."""
    step: float
    """Step size in position units (position is in [-1, 1])."""
    move_probability: float = 0.8
    """Probability that a move happens on a tick."""

    def up_probability(self, m: float) -> float:
        """Probability of stepping up at position ``m`` (given that a move happens)."""
        return 1.0 - (self.a + self.b * m)


MOUTH_WALK = RandomWalk(a=0.5, b=0.5, step=0.02)
EYELID_WALK = RandomWalk(a=0.8, b=0.2, step=0.02)
NECK_WALK = RandomWalk(a=0.6, b=0.4, step=0.001)

# walk index -> spec; streams 2i (move?) and 2i+1 (direction) of the counter-based generator
_WALKS = (MOUTH_WALK, MOUTH_WALK, EYELID_WALK, NECK_WALK, NECK_WALK)
_WALK_A = np.array([w.a for w in _WALKS])
_WALK_B = np.array([w.b for w in _WALKS])
_WALK_STEP = np.array([w.step for w in _WALKS])
_WALK_MOVE = np.array([w.move_probability for w in _WALKS])
_TICK_SLACK = 1e-6
"""Walk tick k is due from ``t * tick_hz >= k - 1e-6``: float rounding (123 / 60 * 60 = 122.99...) must not make a
60 Hz step advance no tick and the next one two."""
_BLINK_STREAM, _GAZE_STREAM, _GAZE_TIME_STREAM, _WOBBLE_STREAM = 100, 200, 201, 300


def _pair(au: str) -> slice:
    """The face-frame columns of ``au``'s left and right channels (adjacent, so a view, not a copy)."""
    left, right = channel_index(f"{au}L"), channel_index(f"{au}R")
    assert right == left + 1, au
    return slice(left, right + 1)


_AU12, _AU15, _AU5, _AU43, _AU45 = (_pair(au) for au in ("AU12", "AU15", "AU5", "AU43", "AU45"))
_YAW, _ROLL = channel_index("head_yaw_deg"), channel_index("head_roll_deg")
_GAZE_YAW = channel_index("gaze_yaw_deg")


@dataclass(frozen=True)
class IdleSettings:
    """Which idle motions run and how large they are. Every part can be switched off on its own."""

    blink: bool = True
    """Spontaneous blinks."""
    mouth: bool = True
    """Mouth-corner random walks."""
    eyelids: bool = True
    """Eyelid random walk."""
    neck: bool = True
    """Neck twist/side random walks."""
    gaze: bool = True
    """Gaze shifts left / straight / right."""
    wobble: bool = True
    """Slow head wobble."""
    tick_hz: float = 60.0
    """Rate of the random-walk ticks (OpenFACS ticks once per rendered frame; mien fixes the rate)."""
    blink_mean_s: float = 6.0
    """Mean time between blink starts."""
    blink_sd_s: float = 2.0
    """Standard deviation of the time between blink starts."""
    blink_duration_s: float = 0.36
    """Blink duration (half closing, half opening)."""
    mouth_au_at_1: float = 0.5
    """AU12/AU15 intensity added at walk position +1/-1."""
    eyelid_au_at_1: float = 0.3
    """AU5/AU43 intensity added at walk position +1/-1."""
    neck_yaw_deg_at_1: float = 10.0
    """Head yaw (degrees) at neck-twist position 1."""
    neck_roll_deg_at_1: float = 6.0
    """Head roll (degrees) at neck-side position 1."""
    gaze_yaw_deg: float = 12.0
    """Gaze yaw of a left/right fixation, degrees."""
    gaze_hold_s: tuple[float, float] = (1.5, 4.0)
    """Range of fixation durations, seconds (uniform)."""
    saccade_s: float = 0.06
    """Duration of a gaze shift."""
    wobble_yaw_deg: float = 3.0
    """Amplitude of the head wobble's yaw, degrees."""
    wobble_roll_deg: float = 1.0
    """Amplitude of the head wobble's roll, degrees."""
    wobble_period_s: float = 8.0
    """Period of the head wobble's yaw, seconds (roll uses 1.37x)."""
    enabled: tuple[str, ...] = field(init=False, default=())

    def __post_init__(self) -> None:
        parts = ("blink", "mouth", "eyelids", "neck", "gaze", "wobble")
        object.__setattr__(self, "enabled", tuple(p for p in parts if getattr(self, p)))


def blink_level(elapsed_s: float, duration_s: float) -> float:
    """Lid closure 0..1 of a blink ``elapsed_s`` after its start (triangle: close, then open)."""
    if elapsed_s <= 0.0 or elapsed_s >= duration_s:
        return 0.0
    half = 0.5 * duration_s
    return 1.0 - abs(elapsed_s - half) / half


def _wobble_phase(seed: np.ndarray | int) -> np.ndarray:
    return 2.0 * np.pi * uniform(seed, _WOBBLE_STREAM, np.arange(2))


_OFF = IdleSettings(blink=False, mouth=False, eyelids=False, neck=False, gaze=False, wobble=False)
"""Settings of a row without idle behaviour."""

_PARTS = ("blink", "mouth", "eyelids", "neck", "gaze", "wobble")
_NUMBERS = (
    "tick_hz",
    "blink_mean_s",
    "blink_sd_s",
    "blink_duration_s",
    "mouth_au_at_1",
    "eyelid_au_at_1",
    "neck_yaw_deg_at_1",
    "neck_roll_deg_at_1",
    "gaze_yaw_deg",
    "saccade_s",
    "wobble_yaw_deg",
    "wobble_roll_deg",
    "wobble_period_s",
)
_WALK_STREAMS = np.arange(2 * len(_WALKS), dtype=np.uint64)  # walk i: stream 2i (move?), 2i + 1 (direction)
_WALK_PARAMS = tuple((i, w.a, w.b, w.step, w.move_probability) for i, w in enumerate(_WALKS))
_DRAW_BLOCK = 16
"""Walk ticks a batch of one row draws at a time: one numpy call costs about the same for 1 or 16 draws, and
a block of 16 is a small step-time spike (about 40 us) every 16 ticks."""
_EVENT_BLOCK = 128
"""Blink intervals or fixations a batch of one row draws at a time: a refill costs about 150-250 us, so it
comes once every 128 blinks (minutes apart), well under one step in a thousand (bench/character_step.py)."""
_AU12L, _AU15L, _AU5L, _AU43L, _AU45L = (pair.start for pair in (_AU12, _AU15, _AU5, _AU43, _AU45))
IDLE_COLUMNS = np.r_[_AU5, _AU12, _AU15, _AU43, _AU45, _YAW, _ROLL, _GAZE_YAW]
"""(13,) face-frame columns idle motion writes (AU5, AU12, AU15, AU43, AU45 left and right, head yaw and roll,
gaze yaw): after :meth:`IdleBatch.apply_row` the rest of the frame is unchanged."""
_IDLE_VALUES = operator.itemgetter(*IDLE_COLUMNS.tolist())
_ONE_ROW_GAINS = ("mouth", "eyelids", "neck_yaw", "neck_roll", "blink", "gaze", "wobble_yaw", "wobble_roll")


@dataclass(frozen=True)
class _OneRow:
    """The gains and numbers of a batch of one row, as Python floats (see :meth:`IdleBatch.apply_row`)."""

    mouth: float
    eyelids: float
    neck_yaw: float
    neck_roll: float
    blink: float
    gaze: float
    wobble_yaw: float
    wobble_roll: float
    tick_hz: float
    blink_duration_s: float
    saccade_s: float
    wobble_frequency_hz: float
    yaw_phase: float
    roll_phase: float


@dataclass
class _Block:
    """Draws ``first``, ``first + 1``, ... of a one-row stream (blink intervals, fixations)."""

    first: int = 0
    values: list[Any] = field(default_factory=list)


@dataclass
class _OneRowEvents:
    """The blink and fixation state of a batch of one row as Python values, ahead of the arrays of the same names."""

    _blink_k: int
    _blink_start: float
    _fix_k: int
    _fix_start: float
    _fix_end: float
    _gaze_from: float
    _gaze_to: float


def _blink_interval(
    mean_s: np.ndarray | float,
    sd_s: np.ndarray | float,
    duration_s: np.ndarray | float,
    seed: np.ndarray,
    k: np.ndarray,
) -> np.ndarray:
    return np.maximum(duration_s, mean_s + sd_s * normal(seed, _BLINK_STREAM, k))


def _fixation(
    low_s: np.ndarray, high_s: np.ndarray, yaw_deg: np.ndarray, seed: np.ndarray, k: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(hold duration s, gaze yaw deg) of fixation k."""
    hold = low_s + (high_s - low_s) * uniform(seed, _GAZE_TIME_STREAM, k)
    side = np.floor(uniform(seed, _GAZE_STREAM, k) * 3.0) - 1.0  # -1, 0, +1
    return hold, side * yaw_deg


class IdleBatch:
    """Idle behaviour of n characters (rows, one seed and one :class:`IdleSettings` each), vectorised.

    Every step of a batch costs about the same: the random walks advance tick by tick (no block is
    precomputed), and blinks and fixations are drawn one at a time when due. A batch of one row runs on
    Python floats instead (:meth:`apply_row`; the same numbers) and draws 16 ticks, blinks or fixations at a
    time, since numpy costs it per call, not per number. A row's idle starts when the row is added (at
    ``t_s``; walks at 0, the first blink and fixation drawn from there); times must not decrease.

    >>> batch = IdleBatch(np.array([1, 2]))
    >>> frames = np.zeros((2, 62))
    >>> batch.apply(1.0, frames)
    >>> bool(np.any(frames[0] != frames[1]))
    True
    """

    def __init__(self, seeds: np.ndarray, settings: IdleSettings | None = None) -> None:
        """Rows for ``seeds`` ((n,) non-negative ints), all with ``settings`` (default :class:`IdleSettings`)."""
        seeds = np.atleast_1d(np.asarray(seeds))
        self.seeds = np.zeros(0, np.uint64)
        """(n,) seeds."""
        self.settings: list[IdleSettings] = []
        """Settings of each row."""
        self._on = {part: np.zeros(0) for part in _PARTS}  # 1.0 where the part runs
        self._num = {name: np.zeros(0) for name in _NUMBERS}
        self._hold_low = np.zeros(0)
        self._hold_high = np.zeros(0)
        self._tick = np.zeros(0, np.int64)
        self._m = np.zeros((0, len(_WALKS)))
        self._blink_k = np.zeros(0, np.uint64)
        self._blink_start = np.zeros(0)
        self._fix_k = np.zeros(0, np.uint64)
        self._fix_start = np.zeros(0)
        self._fix_end = np.zeros(0)
        self._gaze_from = np.zeros(0)
        self._gaze_to = np.zeros(0)
        self._phase = np.zeros((0, 2))
        self._walk_keys = np.zeros((0, len(_WALK_STREAMS)), np.uint64)  # stream_keys(seed, walk streams) per row
        self._amp: dict[str, np.ndarray] = {}
        self._walking = self._blinking = self._gazing = self._wobbling = False
        self._one: _OneRow | None = None  # the gains of a batch of one row, as Python floats
        self._events_one: _OneRowEvents | None = None  # its blink and fixation state (None: read the arrays)
        self._draws: list[list[float]] = []  # a batch of one: walk draws of ticks _draws_from, _draws_from + 1, ...
        self._walk_one_state: list | None = None  # a batch of one: [tick, positions] ahead of the arrays
        self._blink_block, self._fix_block = _Block(), _Block()  # a batch of one: blink intervals, fixations
        self._draws_from = 0
        self.add_rows(seeds, settings if settings is not None else IdleSettings())

    @property
    def n_rows(self) -> int:
        """Number of rows."""
        return int(self.seeds.shape[0])

    @property
    def moving(self) -> bool:
        """True when some row has some idle part on (else :meth:`apply` adds nothing)."""
        return self._walking or self._blinking or self._gazing or self._wobbling

    def add_rows(self, seeds: np.ndarray, settings: IdleSettings | None = None, t_s: float = 0.0) -> None:
        """Append rows for ``seeds`` ((k,) non-negative ints) with ``settings``, starting at ``t_s``."""
        self._store_walk_one()
        self._store_events_one()
        count = len(seeds)
        first = self.n_rows
        self.seeds = np.concatenate([self.seeds, np.zeros(count, np.uint64)])
        self.settings.extend([_OFF] * count)
        for table in (self._on, self._num):
            for key in table:
                table[key] = np.concatenate([table[key], np.zeros(count)])
        names = (
            "_hold_low _hold_high _tick _blink_k _blink_start _fix_k _fix_start _fix_end _gaze_from _gaze_to"
        ).split()
        for name in names:
            array = getattr(self, name)
            setattr(self, name, np.concatenate([array, np.zeros(count, array.dtype)]))
        self._m = np.concatenate([self._m, np.zeros((count, len(_WALKS)))])
        self._phase = np.concatenate([self._phase, np.zeros((count, 2))])
        self._walk_keys = np.concatenate([self._walk_keys, np.zeros((count, len(_WALK_STREAMS)), np.uint64)])
        self.reset_rows(np.arange(first, first + count), np.asarray(seeds), settings, t_s)

    def reset_rows(
        self, rows: np.ndarray, seeds: np.ndarray, settings: IdleSettings | None = None, t_s: float = 0.0
    ) -> None:
        """Restart ``rows`` with new ``seeds`` and ``settings`` (None: no idle) from time ``t_s``."""
        rows = np.atleast_1d(rows)
        if rows.size == 0:
            return
        self._store_walk_one()
        self._store_events_one()
        values = np.atleast_1d(np.asarray(seeds))
        if values.dtype.kind not in "iu" or np.any(values < 0):
            raise InvalidValueError("seed", seeds, "non-negative integers")
        s = settings if settings is not None else _OFF
        self.seeds[rows] = values.astype(np.uint64)
        for row in rows.tolist():
            self.settings[row] = s
        for part in _PARTS:
            self._on[part][rows] = float(getattr(s, part))
        for name in _NUMBERS:
            self._num[name][rows] = float(getattr(s, name))
        self._hold_low[rows], self._hold_high[rows] = s.gaze_hold_s
        seed = self.seeds[rows]
        zero = np.zeros(rows.size, np.uint64)
        self._tick[rows] = math.floor(t_s * s.tick_hz + _TICK_SLACK)
        self._m[rows] = 0.0
        self._blink_k[rows] = 0
        self._blink_start[rows] = t_s + _blink_interval(s.blink_mean_s, s.blink_sd_s, s.blink_duration_s, seed, zero)
        hold, yaw = _fixation(self._hold_low[rows], self._hold_high[rows], self._num["gaze_yaw_deg"][rows], seed, zero)
        self._fix_k[rows] = 0
        self._fix_start[rows] = t_s
        self._fix_end[rows] = t_s + hold
        self._gaze_from[rows] = 0.0
        self._gaze_to[rows] = yaw
        self._phase[rows] = _wobble_phase(seed[:, None])
        self._walk_keys[rows] = stream_keys(seed[:, None], _WALK_STREAMS[None, :])
        self._draws = []
        self._blink_block, self._fix_block = _Block(), _Block()
        self._update_amplitudes()

    def _update_amplitudes(self) -> None:
        """Per-row gains with the on/off switches folded in (0 for a part that is off)."""
        on, num = self._on, self._num
        num["wobble_frequency_hz"] = 1.0 / num["wobble_period_s"]
        self._amp = {
            "mouth": on["mouth"] * num["mouth_au_at_1"],
            "eyelids": on["eyelids"] * num["eyelid_au_at_1"],
            "neck_yaw": on["neck"] * num["neck_yaw_deg_at_1"],
            "neck_roll": on["neck"] * num["neck_roll_deg_at_1"],
            "blink": 5.0 * on["blink"],
            "gaze": on["gaze"],
            "wobble_yaw": on["wobble"] * num["wobble_yaw_deg"],
            "wobble_roll": on["wobble"] * num["wobble_roll_deg"],
        }
        self._walking = bool(np.any(on["mouth"] + on["eyelids"] + on["neck"]))
        self._blinking = bool(on["blink"].any())
        self._gazing = bool(on["gaze"].any())
        self._wobbling = bool(on["wobble"].any())
        self._one = None
        self._events_one = None
        if self.n_rows == 1:
            amp = self._amp
            self._one = _OneRow(
                *(float(amp[key][0]) for key in _ONE_ROW_GAINS),
                *(float(num[key][0]) for key in ("tick_hz", "blink_duration_s", "saccade_s", "wobble_frequency_hz")),
                *self._phase[0].tolist(),
            )

    def walk_positions(self, t_s: float) -> np.ndarray:
        """(n, 5) positions of the walks (mouth L, mouth R, eyelids, neck twist, neck side) at ``t_s``.

        Advances each row's walks tick by tick (``tick_hz``) up to ``t_s``; returns the batch's own array.
        """
        self._store_walk_one()
        target = np.floor(t_s * self._num["tick_hz"] + _TICK_SLACK).astype(np.int64)
        lag = target - self._tick
        if not lag.size:
            return self._m
        m = self._m
        keys = self._walk_keys
        for j in range(int(lag.max())):  # one pass per tick due (one at 60 Hz steps)
            u = uniform_from_keys(keys, (self._tick + j).astype(np.uint64)[:, None])
            move = u[:, 0::2] < _WALK_MOVE
            if j >= lag.min():
                move &= (lag > j)[:, None]  # rows with fewer ticks due stop here
            up = u[:, 1::2] < 1.0 - (_WALK_A + _WALK_B * m)
            stepped = np.where(up, m + _WALK_STEP, m - _WALK_STEP)
            np.minimum(stepped, 1.0, out=stepped)
            np.maximum(stepped, -1.0, out=stepped)
            np.copyto(m, stepped, where=move)
        np.maximum(self._tick, target, out=self._tick)
        return self._m

    def blink(self, t_s: float) -> np.ndarray:
        """(n,) lid closure 0..1 from spontaneous blinks at ``t_s`` (times must not decrease)."""
        self._store_events_one()
        duration = self._num["blink_duration_s"]
        due = t_s >= self._blink_start + duration
        while due.any():
            rows = np.flatnonzero(due)
            self._blink_k[rows] += np.uint64(1)
            self._blink_start[rows] += _blink_interval(
                self._num["blink_mean_s"][rows], self._num["blink_sd_s"][rows], duration[rows],
                self.seeds[rows], self._blink_k[rows],
            )  # fmt: skip
            due = t_s >= self._blink_start + duration
        elapsed = t_s - self._blink_start
        half = 0.5 * duration
        with np.errstate(divide="ignore", invalid="ignore"):
            level = 1.0 - np.abs(elapsed - half) / half
        return np.where((elapsed > 0.0) & (elapsed < duration), level, 0.0)

    def gaze_yaw(self, t_s: float) -> np.ndarray:
        """(n,) gaze yaw (degrees) from fixation shifts at ``t_s`` (times must not decrease)."""
        self._store_events_one()
        due = t_s >= self._fix_end
        while due.any():
            rows = np.flatnonzero(due)
            self._fix_k[rows] += np.uint64(1)
            self._gaze_from[rows] = self._gaze_to[rows]
            hold, yaw = _fixation(
                self._hold_low[rows], self._hold_high[rows], self._num["gaze_yaw_deg"][rows],
                self.seeds[rows], self._fix_k[rows],
            )  # fmt: skip
            self._fix_start[rows] = self._fix_end[rows]
            self._fix_end[rows] += hold
            self._gaze_to[rows] = yaw
            due = t_s >= self._fix_end
        with np.errstate(divide="ignore", invalid="ignore"):
            progress = np.minimum((t_s - self._fix_start) / self._num["saccade_s"], 1.0)
        return self._gaze_from + (self._gaze_to - self._gaze_from) * progress

    def apply(self, t_s: float, frames: np.ndarray, mouth_scale: np.ndarray | float = 1.0) -> None:
        """Add idle motion at ``t_s`` into (n, 62) ``frames`` in place.

        ``mouth_scale`` ((n,) or scalar, 0..1) lets idle mouth motion yield to a laughing or speaking mouth;
        blinks combine by max with the expression's AU45, so a blink during a smile still closes the eyes.
        """
        if self._one is not None and isinstance(mouth_scale, float | int):
            values = frames[0].tolist()
            self.apply_row(t_s, values, float(mouth_scale))
            frames[0, IDLE_COLUMNS] = _IDLE_VALUES(values)
            return
        amp = self._amp
        if self._walking:
            m = self.walk_positions(t_s)
            mouth = m[:, 0:2] * (amp["mouth"] * mouth_scale)[:, None]
            frames[:, _AU12] += np.maximum(mouth, 0.0)
            mouth *= -1.0
            frames[:, _AU15] += np.maximum(mouth, 0.0)
            lids = (m[:, 2] * amp["eyelids"])[:, None]
            frames[:, _AU5] += np.maximum(lids, 0.0)
            lids *= -1.0
            frames[:, _AU43] += np.maximum(lids, 0.0)
            frames[:, _YAW] += m[:, 3] * amp["neck_yaw"]
            frames[:, _ROLL] += m[:, 4] * amp["neck_roll"]
        if self._blinking:
            level = amp["blink"] * self.blink(t_s)
            np.maximum(frames[:, _AU45], level[:, None], out=frames[:, _AU45])
        if self._gazing:
            frames[:, _GAZE_YAW] += amp["gaze"] * self.gaze_yaw(t_s)
        if self._wobbling:
            angle = (2.0 * math.pi * t_s) * self._num["wobble_frequency_hz"]
            frames[:, _YAW] += amp["wobble_yaw"] * np.sin(angle + self._phase[:, 0])
            frames[:, _ROLL] += amp["wobble_roll"] * np.sin(angle / 1.37 + self._phase[:, 1])

    def apply_row(self, t_s: float, values: list[float], mouth_scale: float = 1.0) -> None:
        """:meth:`apply` for a batch of one row, into its (62,) face frame as a list of floats, in place.

        The same arithmetic on Python floats: numpy costs about a microsecond a call whatever the array's
        size, which for one row is most of the cost. Walk ticks, blink intervals and fixations are drawn
        :data:`_DRAW_BLOCK` at a time with the vectorised code's functions (the same numbers). The row's
        state runs ahead of the arrays until a vectorised method needs them.
        """
        one = self._one
        if one is None:
            raise InvalidValueError("rows", self.n_rows, "a batch of one row for apply_row (else apply)")
        if self._walking:
            m = self._walk_one(t_s, one.tick_hz)
            mouth_gain = one.mouth * mouth_scale
            left, right = m[0] * mouth_gain, m[1] * mouth_gain
            values[_AU12L] += max(left, 0.0)
            values[_AU12L + 1] += max(right, 0.0)
            values[_AU15L] += max(-left, 0.0)
            values[_AU15L + 1] += max(-right, 0.0)
            lids = m[2] * one.eyelids
            values[_AU5L] += max(lids, 0.0)
            values[_AU5L + 1] += max(lids, 0.0)
            values[_AU43L] += max(-lids, 0.0)
            values[_AU43L + 1] += max(-lids, 0.0)
            values[_YAW] += m[3] * one.neck_yaw
            values[_ROLL] += m[4] * one.neck_roll
        events = self._events_one
        if events is None:
            events = self._events_one = _OneRowEvents(
                *(getattr(self, name)[0].item() for name in _OneRowEvents.__dataclass_fields__)
            )
        if self._blinking:
            duration = one.blink_duration_s
            while t_s >= events._blink_start + duration:  # the next blink (blink())
                events._blink_k += 1
                events._blink_start += self._drawn_one(self._blink_block, events._blink_k)
            elapsed = t_s - events._blink_start
            half = 0.5 * duration
            level = 1.0 - abs(elapsed - half) / half if 0.0 < elapsed < duration else 0.0
            level *= one.blink
            values[_AU45L] = max(values[_AU45L], level)
            values[_AU45L + 1] = max(values[_AU45L + 1], level)
        if self._gazing:
            if one.saccade_s <= 0.0:
                gaze = float(self.gaze_yaw(t_s)[0])
            else:
                while t_s >= events._fix_end:  # the next fixation (gaze_yaw())
                    events._fix_k += 1
                    events._gaze_from = events._gaze_to
                    hold, yaw = self._drawn_one(self._fix_block, events._fix_k)
                    events._fix_start = events._fix_end
                    events._fix_end += hold
                    events._gaze_to = yaw
                progress = min((t_s - events._fix_start) / one.saccade_s, 1.0)
                gaze = events._gaze_from + (events._gaze_to - events._gaze_from) * progress
            values[_GAZE_YAW] += one.gaze * gaze
        if self._wobbling:
            angle = (2.0 * math.pi * t_s) * one.wobble_frequency_hz
            values[_YAW] += one.wobble_yaw * math.sin(angle + one.yaw_phase)
            values[_ROLL] += one.wobble_roll * math.sin(angle / 1.37 + one.roll_phase)

    def _walk_one(self, t_s: float, tick_hz: float) -> list[float]:
        """:meth:`walk_positions` of a batch of one row, on Python floats (the same steps and draws).

        The row's tick and positions live in :attr:`_walk_one_state` until a vectorised method needs the
        arrays (:meth:`_store_walk_one`).
        """
        state = self._walk_one_state
        if state is None:
            state = self._walk_one_state = [int(self._tick[0]), self._m[0].tolist()]
        tick, m = state
        target = math.floor(t_s * tick_hz + _TICK_SLACK)
        if target <= tick:
            return m
        draws, first = self._draws, self._draws_from
        for k in range(tick, target):
            if not first <= k < first + len(draws):
                ticks = np.arange(k, k + _DRAW_BLOCK, dtype=np.uint64)[:, None]
                draws = self._draws = uniform_from_keys(self._walk_keys[0][None, :], ticks).tolist()
                first = self._draws_from = k
            u = draws[k - first]
            for i, a, b, step, move in _WALK_PARAMS:
                if u[2 * i] < move:
                    x = m[i]
                    x = x + step if u[2 * i + 1] < 1.0 - (a + b * x) else x - step
                    m[i] = 1.0 if x > 1.0 else -1.0 if x < -1.0 else x  # np.minimum, np.maximum
        state[0] = target
        return m

    def _drawn_one(self, block: _Block, k: int) -> Any:
        """Draw ``k`` of a one-row block (blink intervals or fixations), drawing :data:`_EVENT_BLOCK` more when due."""
        if not block.first <= k < block.first + len(block.values):
            seed = np.full(_EVENT_BLOCK, self.seeds[0])
            ks = np.arange(k, k + _EVENT_BLOCK, dtype=np.uint64)
            num = {name: np.full(_EVENT_BLOCK, values[0]) for name, values in self._num.items()}
            if block is self._blink_block:
                intervals = _blink_interval(num["blink_mean_s"], num["blink_sd_s"], num["blink_duration_s"], seed, ks)
                block.values = intervals.tolist()
            else:
                low, high = np.full(_EVENT_BLOCK, self._hold_low[0]), np.full(_EVENT_BLOCK, self._hold_high[0])
                hold, yaw = _fixation(low, high, num["gaze_yaw_deg"], seed, ks)
                block.values = list(zip(hold.tolist(), yaw.tolist(), strict=True))
            block.first = k
        return block.values[k - block.first]

    def _store_events_one(self) -> None:
        """Write the one-row blink and fixation state back into the arrays (before a vectorised method reads them)."""
        events = self._events_one
        if events is not None:
            for name in _OneRowEvents.__dataclass_fields__:
                getattr(self, name)[0] = getattr(events, name)
            self._events_one = None

    def _store_walk_one(self) -> None:
        """Write the one-row walk state back into the arrays (before a vectorised method reads them)."""
        state = self._walk_one_state
        if state is not None:
            self._tick[0], self._m[0] = state
            self._walk_one_state = None


class Idle:
    """Idle behaviour of one character: an :class:`IdleBatch` of one row (one implementation of both)."""

    def __init__(self, seed: int = 0, settings: IdleSettings | None = None) -> None:
        self.seed = int(seed)
        """Seed of every random draw."""
        self.settings = settings or IdleSettings()
        """Which motions run and how large."""
        self.batch = IdleBatch(np.array([self.seed]), self.settings)
        """The one-row batch doing the work."""

    def walk_positions(self, t_s: float) -> list[float]:
        """Positions of the five walks (mouth L, mouth R, eyelids, neck twist, neck side) at ``t_s``.

        Times must not decrease.
        """
        return [float(x) for x in self.batch.walk_positions(t_s)[0]]

    def blink(self, t_s: float) -> float:
        """Lid closure 0..1 from spontaneous blinks at ``t_s`` (times must not decrease)."""
        return float(self.batch.blink(t_s)[0])

    def gaze_yaw(self, t_s: float) -> float:
        """Gaze yaw (degrees) from fixation shifts at ``t_s`` (times must not decrease)."""
        return float(self.batch.gaze_yaw(t_s)[0])

    def apply(self, t_s: float, frame: np.ndarray, mouth_scale: float = 1.0) -> None:
        """Add idle motion at ``t_s`` into the (62,) ``frame`` in place (see :meth:`IdleBatch.apply`)."""
        self.batch.apply(t_s, frame[None], mouth_scale)
