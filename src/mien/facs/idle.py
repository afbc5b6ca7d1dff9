"""Idle behaviour: blinks, micro random walks (OpenFACS), gaze shifts and head wobble (Broekens).

Everything is a pure function of the seed and the time, drawn from :mod:`mien.facs.counter_random`, so a
face at time t is reproducible and a batch of characters (:class:`IdleBatch`) matches single characters
(:class:`Idle`) exactly.

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
from dataclasses import dataclass, field

import numpy as np

from mien.facs.catalogue import channel_index
from mien.facs.counter_random import normal, uniform

__all__ = [
    "EYELID_WALK",
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
_BLINK_STREAM, _GAZE_STREAM, _GAZE_TIME_STREAM, _WOBBLE_STREAM = 100, 200, 201, 300
_BLOCK_TICKS = 512

_AU12 = (channel_index("AU12L"), channel_index("AU12R"))
_AU15 = (channel_index("AU15L"), channel_index("AU15R"))
_AU5 = (channel_index("AU5L"), channel_index("AU5R"))
_AU43 = (channel_index("AU43L"), channel_index("AU43R"))
_AU45 = (channel_index("AU45L"), channel_index("AU45R"))
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


def _blink_interval(settings: IdleSettings, seed: np.ndarray | int, k: np.ndarray | int) -> np.ndarray:
    return np.maximum(
        settings.blink_duration_s, settings.blink_mean_s + settings.blink_sd_s * normal(seed, _BLINK_STREAM, k)
    )


def _fixation(settings: IdleSettings, seed: np.ndarray | int, k: np.ndarray | int) -> tuple[np.ndarray, np.ndarray]:
    """(hold duration s, gaze yaw deg) of fixation k."""
    low, high = settings.gaze_hold_s
    hold = low + (high - low) * uniform(seed, _GAZE_TIME_STREAM, k)
    side = np.floor(uniform(seed, _GAZE_STREAM, k) * 3.0) - 1.0  # -1, 0, +1
    return hold, side * settings.gaze_yaw_deg


def _wobble_phase(seed: np.ndarray | int) -> np.ndarray:
    return 2.0 * np.pi * uniform(seed, _WOBBLE_STREAM, np.arange(2))


def _walk_ticks(seed: int, first_tick: int, n_ticks: int, start: list[float]) -> np.ndarray:
    """(n_ticks, 5) walk positions after each tick, starting from positions ``start``."""
    ticks = np.arange(first_tick, first_tick + n_ticks)[:, None]
    streams = np.arange(len(_WALKS))[None, :] * 2
    moves = (uniform(seed, streams, ticks) < _WALK_MOVE).tolist()
    dirs = uniform(seed, streams + 1, ticks).tolist()
    a, b, step = _WALK_A.tolist(), _WALK_B.tolist(), _WALK_STEP.tolist()
    out = np.empty((n_ticks, len(_WALKS)))
    m = list(start)
    for i in range(n_ticks):
        move_row, dir_row = moves[i], dirs[i]
        for w in range(len(_WALKS)):
            if move_row[w]:
                x = m[w]
                x = x + step[w] if dir_row[w] < 1.0 - (a[w] + b[w] * x) else x - step[w]
                m[w] = min(1.0, max(-1.0, x))
        out[i] = m
    return out


class Idle:
    """Idle behaviour of one character; :meth:`apply` adds it into a face frame at time t."""

    def __init__(self, seed: int = 0, settings: IdleSettings | None = None) -> None:
        self.seed = int(seed)
        self.settings = settings or IdleSettings()
        self._block_index = -1
        self._block: list[list[float]] = []
        self._block_ends: list[list[float]] = [[0.0] * len(_WALKS)]  # positions at the start of each block
        self._blink_k = 0
        self._blink_start = float(_blink_interval(self.settings, self.seed, 0))
        self._fix_k = 0
        self._fix_start = 0.0
        hold, yaw = _fixation(self.settings, self.seed, 0)
        self._fix_end = float(hold)
        self._gaze_from = 0.0
        self._gaze_to = float(yaw)
        self._phase = _wobble_phase(self.seed).tolist()
        self._t_s = 0.0

    def walk_positions(self, t_s: float) -> list[float]:
        """Positions of the five walks (mouth L, mouth R, eyelids, neck twist, neck side) at ``t_s``."""
        tick = int(t_s * self.settings.tick_hz)
        if tick == 0:
            return self._block_ends[0]
        block, row = divmod(tick - 1, _BLOCK_TICKS)
        if block != self._block_index:
            while len(self._block_ends) <= block:  # walks are sequential: fill earlier blocks first
                k = len(self._block_ends) - 1
                data = _walk_ticks(self.seed, k * _BLOCK_TICKS, _BLOCK_TICKS, self._block_ends[k])
                self._block_ends.append(data[-1].tolist())
            self._block = _walk_ticks(self.seed, block * _BLOCK_TICKS, _BLOCK_TICKS, self._block_ends[block]).tolist()
            self._block_index = block
        return self._block[row]

    def blink(self, t_s: float) -> float:
        """Lid closure 0..1 from spontaneous blinks at ``t_s`` (times must not decrease)."""
        settings = self.settings
        while t_s >= self._blink_start + settings.blink_duration_s:
            self._blink_k += 1
            self._blink_start += float(_blink_interval(settings, self.seed, self._blink_k))
        return blink_level(t_s - self._blink_start, settings.blink_duration_s)

    def gaze_yaw(self, t_s: float) -> float:
        """Gaze yaw (degrees) from fixation shifts at ``t_s`` (times must not decrease)."""
        while t_s >= self._fix_end:
            self._fix_k += 1
            self._gaze_from = self._gaze_to
            hold, yaw = _fixation(self.settings, self.seed, self._fix_k)
            self._fix_start = self._fix_end
            self._fix_end += float(hold)
            self._gaze_to = float(yaw)
        progress = (t_s - self._fix_start) / self.settings.saccade_s
        if progress >= 1.0:
            return self._gaze_to
        return self._gaze_from + (self._gaze_to - self._gaze_from) * progress

    def apply(self, t_s: float, frame: np.ndarray, mouth_scale: float = 1.0) -> None:
        """Add idle motion at ``t_s`` into the (62,) ``frame`` in place.

        ``mouth_scale`` (0..1) lets idle mouth motion yield to a laughing or speaking mouth; blinks combine
        by max with the expression's AU45, so a blink during a smile still closes the eyes.
        """
        s = self.settings
        if s.mouth or s.eyelids or s.neck:
            m = self.walk_positions(t_s)
            if s.mouth and mouth_scale > 0.0:
                for side in (0, 1):
                    value = m[side] * s.mouth_au_at_1 * mouth_scale
                    if value > 0.0:
                        frame[_AU12[side]] += value
                    else:
                        frame[_AU15[side]] -= value
            if s.eyelids:
                value = m[2] * s.eyelid_au_at_1
                channels = _AU5 if value > 0.0 else _AU43
                frame[channels[0]] += abs(value)
                frame[channels[1]] += abs(value)
            if s.neck:
                frame[_YAW] += m[3] * s.neck_yaw_deg_at_1
                frame[_ROLL] += m[4] * s.neck_roll_deg_at_1
        if s.blink:
            level = 5.0 * self.blink(t_s)
            if level > 0.0:
                for channel in _AU45:
                    if frame[channel] < level:
                        frame[channel] = level
        if s.gaze:
            frame[_GAZE_YAW] += self.gaze_yaw(t_s)
        if s.wobble:
            angle = 2.0 * math.pi * t_s / s.wobble_period_s
            frame[_YAW] += s.wobble_yaw_deg * math.sin(angle + self._phase[0])
            frame[_ROLL] += s.wobble_roll_deg * math.sin(angle / 1.37 + self._phase[1])


class IdleBatch:
    """Idle behaviour of many characters at once (one seed each), equal to :class:`Idle` per character."""

    def __init__(self, seeds: np.ndarray, settings: IdleSettings | None = None) -> None:
        self.seeds = np.asarray(seeds, dtype=np.uint64)
        self.settings = settings or IdleSettings()
        n = self.seeds.shape[0]
        self._tick = 0
        self._m = np.zeros((n, len(_WALKS)))
        self._streams = np.arange(len(_WALKS))[None, :] * 2
        self._blink_k = np.zeros(n, dtype=np.uint64)
        self._blink_start = _blink_interval(self.settings, self.seeds, self._blink_k)
        self._fix_k = np.zeros(n, dtype=np.uint64)
        self._fix_start = np.zeros(n)
        hold, yaw = _fixation(self.settings, self.seeds, self._fix_k)
        self._fix_end = hold
        self._gaze_from = np.zeros(n)
        self._gaze_to = yaw
        phases = _wobble_phase(self.seeds[:, None])
        self._phase0, self._phase1 = phases[:, 0], phases[:, 1]

    def _advance_walks(self, t_s: float) -> np.ndarray:
        target_tick = int(t_s * self.settings.tick_hz)
        seeds = self.seeds[:, None]
        while self._tick < target_tick:
            move = uniform(seeds, self._streams, self._tick) < _WALK_MOVE
            up = uniform(seeds, self._streams + 1, self._tick) < 1.0 - (_WALK_A + _WALK_B * self._m)
            stepped = np.where(up, self._m + _WALK_STEP, self._m - _WALK_STEP)
            np.clip(stepped, -1.0, 1.0, out=stepped)
            self._m = np.where(move, stepped, self._m)
            self._tick += 1
        return self._m

    def _blink(self, t_s: float) -> np.ndarray:
        duration = self.settings.blink_duration_s
        due = t_s >= self._blink_start + duration
        while due.any():
            self._blink_k[due] += np.uint64(1)
            self._blink_start[due] += _blink_interval(self.settings, self.seeds[due], self._blink_k[due])
            due = t_s >= self._blink_start + duration
        elapsed = t_s - self._blink_start
        half = 0.5 * duration
        level = 1.0 - np.abs(elapsed - half) / half
        return np.where((elapsed > 0.0) & (elapsed < duration), level, 0.0)

    def _gaze(self, t_s: float) -> np.ndarray:
        due = t_s >= self._fix_end
        while due.any():
            self._fix_k[due] += np.uint64(1)
            self._gaze_from[due] = self._gaze_to[due]
            hold, yaw = _fixation(self.settings, self.seeds[due], self._fix_k[due])
            self._fix_start[due] = self._fix_end[due]
            self._fix_end[due] += hold
            self._gaze_to[due] = yaw
            due = t_s >= self._fix_end
        progress = np.minimum((t_s - self._fix_start) / self.settings.saccade_s, 1.0)
        return self._gaze_from + (self._gaze_to - self._gaze_from) * progress

    def apply(self, t_s: float, frames: np.ndarray, mouth_scale: np.ndarray | float = 1.0) -> None:
        """Add idle motion at ``t_s`` into (n_characters, 62) ``frames`` in place (see :meth:`Idle.apply`)."""
        s = self.settings
        if s.mouth or s.eyelids or s.neck:
            m = self._advance_walks(t_s)
            if s.mouth:
                value = m[:, 0:2] * s.mouth_au_at_1 * np.asarray(mouth_scale, dtype=float).reshape(-1, 1)
                frames[:, _AU12] += np.maximum(value, 0.0)
                frames[:, _AU15] += np.maximum(-value, 0.0)
            if s.eyelids:
                value = (m[:, 2] * s.eyelid_au_at_1)[:, None]
                frames[:, _AU5] += np.maximum(value, 0.0)
                frames[:, _AU43] += np.maximum(-value, 0.0)
            if s.neck:
                frames[:, _YAW] += m[:, 3] * s.neck_yaw_deg_at_1
                frames[:, _ROLL] += m[:, 4] * s.neck_roll_deg_at_1
        if s.blink:
            frames[:, _AU45] = np.maximum(frames[:, _AU45], (5.0 * self._blink(t_s))[:, None])
        if s.gaze:
            frames[:, _GAZE_YAW] += self._gaze(t_s)
        if s.wobble:
            angle = 2.0 * math.pi * t_s / s.wobble_period_s
            frames[:, _YAW] += s.wobble_yaw_deg * np.sin(angle + self._phase0)
            frames[:, _ROLL] += s.wobble_roll_deg * np.sin(angle / 1.37 + self._phase1)
