"""The emotion engine of Broekens, Qu & Brinkman: events, envelopes, emotion decaying to mood, PAD factors.

State
    *Emotion*: a (6,) vector of intensities (EMOTIONS order). In ``"categorical"`` mode it is the sum over
    active events of ``envelope(t - start) * intensity * weight`` per emotion (several emotions at once:
    happy and sad together), capped at 5. In ``"pad"`` mode a factor state set by :meth:`set_pad` is
    converted to intensities by :func:`~mien.affect.pad.pad_to_emotions`, and events still add on top.
    *Mood*: "a running average of the emotions over time": an exponential moving average of the emotion
    vector with time constant ``mood_time_constant_s``, scaled by ``mood_gain``
    (``d mood / dt = (mood_gain * emotion - mood) / tau``).

Expression ("the emotion decays to the mood")
    The emotion occludes the mood in proportion to its total intensity, saturating at the prototype
    magnitude 1: ``shown_mood = (1 - min(1, sum(emotion))) * mood``. While an event is at full strength only
    the emotion shows; as it decays the face cross-fades continuously to the mood; once every event is over
    only the mood is expressed. :meth:`EmotionEngine.expressed` returns ``(emotion, shown_mood)``: express the
    first with a full basis and the second with the closed-mouth basis (jaw off, see
    :mod:`mien.affect.basis`), and add them.

Time
    Time is in seconds and must be non-decreasing between calls for the mood to integrate: each query at a
    later time advances the mood incrementally (trapezoid rule on the exact exponential decay, sub-stepped
    at ``mood_max_step_s`` when calls are sparse, so it does not depend on the frame rate). A query at an
    earlier time returns the emotion at that time but does not rewind the mood, and events finished before
    the latest time queried have been pruned. An event triggered in the past enters the mood only from the
    latest time on.

One implementation: :class:`EmotionBatch` steps n characters (rows) with vectorised numpy; one character's
:class:`EmotionEngine` is a batch of one.
"""

from __future__ import annotations

import math

import numpy as np

from mien.affect.emotions import EMOTIONS, MAX_INTENSITY, Blend, blend_components, check_intensity
from mien.affect.pad import PAD_PROTOTYPES, PAD_RADIUS, check_pad, pad_intensities
from mien.errors import InvalidValueError
from mien.facs.dynamics import RowIndex
from mien.facs.envelope import Envelope, envelope_values

__all__ = ["MODES", "EmotionBatch", "EmotionEngine", "mood_step", "shown_mood"]

MODES: tuple[str, ...] = ("categorical", "pad")
"""Emotion representations: a vector of emotion intensities, or a PAD factor state."""

_N = len(EMOTIONS)


def _finite(field: str, value: object) -> float:
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InvalidValueError(field, value, "a finite number") from None
    if not math.isfinite(v):
        raise InvalidValueError(field, value, "a finite number")
    return v


def _write(values: np.ndarray, out: np.ndarray | None) -> np.ndarray:
    if out is None:
        return values.copy()
    out[...] = values
    return out


_PAD_UNIT = PAD_PROTOTYPES / np.linalg.norm(PAD_PROTOTYPES, axis=1, keepdims=True)  # (6, 3)
_PAD_NORM = np.linalg.norm(PAD_PROTOTYPES, axis=1)  # (6,)


def _pad_intensities_rows(pad: np.ndarray, radius: float) -> np.ndarray:
    """(k, 6) intensities of (k, 3) PAD states: :func:`~mien.affect.pad.pad_intensities` over rows."""
    length = np.sqrt(np.einsum("kf,kf->k", pad, pad))[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        unit = pad / length
    diff = unit[:, None, :] - _PAD_UNIT[None, :, :]
    dist = np.sqrt(np.einsum("kef,kef->ke", diff, diff))
    out = np.where(dist < radius, length / _PAD_NORM * (1.0 - dist / radius), 0.0)
    out[length[:, 0] == 0.0] = 0.0
    return out


class EmotionBatch:
    """The emotion layer of n characters (rows): events, PAD factor states and moods, vectorised.

    Rows are characters; ``rows`` arguments index the first axis (an int, a slice or an int array; callers
    validate them). Time semantics are those of the module doc: :meth:`advance` with non-decreasing times
    integrates the mood; an earlier time gives the emotion then without rewinding. A row is in PAD mode
    from its first :meth:`set_pad` on (its emotion is the PAD state's intensities, events add on top).

    >>> batch = EmotionBatch(2)
    >>> batch.trigger(1, "joy", 1.0, t_s=0.0)
    >>> batch.advance(0.2)[:, 0].round(3).tolist()      # half-way through row 1's onset
    [0.0, 0.5]
    """

    def __init__(
        self,
        n_rows: int = 0,
        envelope: Envelope | None = None,
        mood_time_constant_s: float = 10.0,
        mood_gain: float = 1.0,
        *,
        pad_radius: float = PAD_RADIUS,
        mood_max_step_s: float = 0.05,
    ) -> None:
        """Create ``n_rows`` neutral rows; the other parameters are those of :class:`EmotionEngine`."""
        if envelope is not None and not isinstance(envelope, Envelope):
            raise InvalidValueError("envelope", envelope, "an Envelope")
        tau = _finite("mood_time_constant_s", mood_time_constant_s)
        if tau <= 0.0:
            raise InvalidValueError("mood_time_constant_s", mood_time_constant_s, "a finite number > 0")
        gain = _finite("mood_gain", mood_gain)
        if gain < 0.0:
            raise InvalidValueError("mood_gain", mood_gain, "a finite number >= 0")
        radius = _finite("pad_radius", pad_radius)
        if not (0.0 < radius <= 2.0):
            raise InvalidValueError("pad_radius", pad_radius, "a number in (0, 2]")
        step = _finite("mood_max_step_s", mood_max_step_s)
        if step <= 0.0:
            raise InvalidValueError("mood_max_step_s", mood_max_step_s, "a finite number > 0")
        self.envelope = envelope if envelope is not None else Envelope()
        """Default envelope of events."""
        self.mood_time_constant_s = tau
        """Time constant of the mood's exponential moving average, seconds."""
        self.mood_gain = gain
        """Mood's steady state per unit of sustained emotion."""
        self.pad_radius = radius
        """Reach of a PAD prototype (chord distance of directions)."""
        self.mood_max_step_s = step
        """Longest mood integration step, seconds."""
        self.mood = np.zeros((n_rows, _N))
        """(n, 6) mood of each row at the latest time advanced to (change it with :meth:`set_mood`)."""
        self._mood_zero = True  # mood is known to be all 0
        self._emotion = np.zeros((n_rows, _N))  # emotion at _t_s
        self._emotion_zero = True  # _emotion is known to be all 0 (a flag, not a scan, on every step)
        self._t_s: float | None = None
        self._dirty = False
        # events: one row each in parallel arrays
        self._ev_row = np.zeros(0, np.int64)
        self._ev_time = np.zeros((0, 5))  # start_s, onset_s, hold_s, decay_s, end_s
        self._ev_amount = np.zeros((0, _N))
        # PAD: linear ramp from _pad_from (at _pad_t0_s) to _pad_to over _pad_ramp_s, per row
        self._pad_on = np.zeros(n_rows, bool)
        self._pad_any = False  # any(_pad_on), kept up to date by set_pad and reset_rows
        self._pad_from = np.zeros((n_rows, 3))
        self._pad_to = np.zeros((n_rows, 3))
        self._pad_t0_s = np.zeros(n_rows)
        self._pad_ramp_s = np.zeros(n_rows)
        self._pad_settled = np.zeros((n_rows, _N))

    @property
    def n_rows(self) -> int:
        """Number of rows."""
        return int(self.mood.shape[0])

    @property
    def time_s(self) -> float | None:
        """Latest time advanced to (None before the first :meth:`advance`)."""
        return self._t_s

    def add_rows(self, count: int) -> None:
        """Append ``count`` neutral rows."""
        self.mood = np.concatenate([self.mood, np.zeros((count, _N))])
        self._emotion = np.concatenate([self._emotion, np.zeros((count, _N))])
        self._pad_on = np.concatenate([self._pad_on, np.zeros(count, bool)])
        self._pad_from = np.concatenate([self._pad_from, np.zeros((count, 3))])
        self._pad_to = np.concatenate([self._pad_to, np.zeros((count, 3))])
        self._pad_t0_s = np.concatenate([self._pad_t0_s, np.zeros(count)])
        self._pad_ramp_s = np.concatenate([self._pad_ramp_s, np.zeros(count)])
        self._pad_settled = np.concatenate([self._pad_settled, np.zeros((count, _N))])

    def reset_rows(self, rows: np.ndarray) -> None:
        """Forget the events, PAD state and mood of ``rows``."""
        for array in (self.mood, self._emotion, self._pad_from, self._pad_to, self._pad_settled):
            array[rows] = 0.0
        self._pad_on[rows] = False
        self._pad_any = bool(self._pad_on.any())
        self._pad_t0_s[rows] = 0.0
        self._pad_ramp_s[rows] = 0.0
        if self._ev_row.size:
            self._keep_events(~np.isin(self._ev_row, np.atleast_1d(rows)))

    def _keep_events(self, keep: np.ndarray) -> None:
        self._ev_row = self._ev_row[keep]
        self._ev_time = self._ev_time[keep]
        self._ev_amount = self._ev_amount[keep]

    # ---------------------------------------------------------------- input

    def trigger(
        self,
        rows: RowIndex,
        emotion: str | Blend,
        intensity: float,
        t_s: float,
        envelope: Envelope | None = None,
    ) -> None:
        """Start an event on ``rows``: ``emotion`` (a name, alias, blend name or :class:`Blend`) at ``t_s``.

        ``intensity`` in [0, 5]: 1 is the prototype. ``envelope`` overrides the default for this event.
        Bad values raise :class:`~mien.errors.InvalidValueError` (:class:`~mien.errors.UnknownNameError`
        for names).
        """
        amounts = np.zeros(_N)
        components = blend_components(emotion)
        value = check_intensity(intensity)
        start = _finite("t_s", t_s)
        if envelope is not None and not isinstance(envelope, Envelope):
            raise InvalidValueError("envelope", envelope, "an Envelope")
        for index, weight in components:
            amounts[index] += weight * value
        env = envelope if envelope is not None else self.envelope
        row_ids = np.atleast_1d(np.arange(self.n_rows)[rows])
        times = (start, env.onset_s, env.hold_s, env.decay_s, start + env.total_s)
        self._ev_row = np.concatenate([self._ev_row, row_ids])
        self._ev_time = np.concatenate([self._ev_time, np.tile(times, (len(row_ids), 1))])
        self._ev_amount = np.concatenate([self._ev_amount, np.tile(amounts, (len(row_ids), 1))])
        self._dirty = True

    def set_pad(self, rows: RowIndex, pleasure: float, arousal: float, dominance: float, t_s: float) -> None:
        """Move the PAD state of ``rows`` (each factor in [-1, 1]), reached linearly over ``envelope.onset_s``.

        The state is held until the next call (set ``(0, 0, 0)`` to let the emotion decay to the mood).
        """
        target = check_pad(pleasure, arousal, dominance)
        start = _finite("t_s", t_s)
        row_ids = np.atleast_1d(np.arange(self.n_rows)[rows])
        self._pad_from[row_ids] = self._pad_rows(start, row_ids)
        self._pad_to[row_ids] = target
        self._pad_t0_s[row_ids] = start
        self._pad_ramp_s[row_ids] = self.envelope.onset_s
        self._pad_settled[row_ids] = pad_intensities(*target, radius=self.pad_radius)
        self._pad_on[row_ids] = True
        self._pad_any = bool(row_ids.size) or self._pad_any
        self._dirty = True

    def set_mood(self, rows: RowIndex, mood: object) -> None:
        """Set the mood of ``rows``: (6,) intensities, each finite in [0, 5]."""
        try:
            values = np.asarray(mood, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError):
            raise InvalidValueError("mood", mood, f"{_N} intensities in [0, {MAX_INTENSITY:g}]") from None
        if values.shape != (_N,):
            raise InvalidValueError("mood", mood, f"{_N} intensities in [0, {MAX_INTENSITY:g}] ({', '.join(EMOTIONS)})")
        checked = [check_intensity(v, f"mood[{name}]") for v, name in zip(values.tolist(), EMOTIONS, strict=True)]
        self.mood[rows] = checked
        self._mood_zero = False

    # ---------------------------------------------------------------- output

    def n_events(self, row: int | None = None) -> int:
        """Number of events not yet pruned, of ``row`` or of every row."""
        return int(self._ev_row.size if row is None else np.count_nonzero(self._ev_row == row))

    def pad_at(self, t_s: float) -> np.ndarray:
        """(n, 3) PAD factor states at ``t_s`` (zeros for rows never given one)."""
        return self._pad_rows(_finite("t_s", t_s), np.arange(self.n_rows))

    def _pad_rows(self, t_s: float, row_ids: np.ndarray) -> np.ndarray:
        elapsed = (t_s - self._pad_t0_s[row_ids])[:, None]
        ramp = self._pad_ramp_s[row_ids][:, None]
        start, end = self._pad_from[row_ids], self._pad_to[row_ids]
        with np.errstate(divide="ignore", invalid="ignore"):
            moving = start + (elapsed / ramp) * (end - start)
        return np.where(elapsed >= ramp, end, np.where(elapsed <= 0.0, start, moving))

    def emotion_at(self, t_s: float) -> np.ndarray:
        """(n, 6) emotion intensities at ``t_s`` (a new array), capped at 5; the mood is not touched."""
        emotion = np.zeros((self.n_rows, _N))
        if self._pad_any:
            rows = np.flatnonzero(self._pad_on)
            settled = t_s - self._pad_t0_s[rows] >= self._pad_ramp_s[rows]
            if settled.all():
                emotion[rows] = self._pad_settled[rows]
            else:
                emotion[rows] = np.where(
                    settled[:, None],
                    self._pad_settled[rows],
                    _pad_intensities_rows(self._pad_rows(t_s, rows), self.pad_radius),
                )
        if self._ev_row.size:
            times = self._ev_time
            levels = envelope_values(t_s - times[:, 0], times[:, 1], times[:, 2], times[:, 3])
            levels[(times[:, 0] > t_s) | (t_s >= times[:, 4])] = 0.0
            np.add.at(emotion, self._ev_row, levels[:, None] * self._ev_amount)
            np.minimum(emotion, MAX_INTENSITY, out=emotion)
        return emotion

    @property
    def quiet(self) -> bool:
        """True when no row has an event or a PAD state (every emotion is 0; moods may not be)."""
        return not self._ev_row.size and not self._pad_any

    @property
    def resting(self) -> bool:
        """True when there is nothing to express: :attr:`quiet`, and every emotion and mood is 0."""
        if self._ev_row.size or self._pad_any:
            return False
        if not self._emotion_zero:
            self._emotion_zero = not self._emotion.any()
        if not self._mood_zero:
            self._mood_zero = not self.mood.any()
        return self._emotion_zero and self._mood_zero

    def advance(self, t_s: float) -> np.ndarray:
        """Move to ``t_s``: integrate the moods and return the (n, 6) emotions there (do not modify them).

        An earlier time than the latest returns the emotions then, without rewinding the moods.
        """
        t = _finite("t_s", t_s)
        last = self._t_s
        if last is None:
            self._t_s = t
            self._emotion = self.emotion_at(t)
            self._emotion_zero = False
            self._dirty = False
            return self._emotion
        if t < last:
            return self.emotion_at(t)
        if self._dirty:
            self._emotion = self.emotion_at(last)
            self._emotion_zero = False
            self._dirty = False
        if t == last:
            return self._emotion
        dt = t - last
        n_steps = math.ceil(dt / self.mood_max_step_s) if dt > self.mood_max_step_s else 1
        step = dt / n_steps
        if self.quiet and (self._emotion_zero or not self._emotion.any()):
            self._emotion_zero = True
            if not self._mood_zero:
                self.mood *= math.exp(-dt / self.mood_time_constant_s)  # no emotion: a plain decay
        else:
            previous = self._emotion
            for s in range(1, n_steps + 1):
                current = self.emotion_at(t if s == n_steps else last + s * step)
                mood_step(self.mood, previous, current, step, self.mood_time_constant_s, self.mood_gain)
                previous = current
            self._emotion = previous
            self._emotion_zero = self._mood_zero = False
        self._t_s = t
        if self._ev_row.size:
            alive = self._ev_time[:, 4] > t
            if not alive.all():
                self._keep_events(alive)
        return self._emotion

    def expressed(self, t_s: float) -> tuple[np.ndarray, np.ndarray]:
        """``(emotion (n, 6), shown_mood (n, 6))`` to express at ``t_s`` (see :func:`shown_mood`)."""
        emotion = self.advance(t_s)
        return emotion, shown_mood(emotion, self.mood)


class EmotionEngine:
    """Emotion events with onset/hold/decay envelopes, a mood that averages them, optional PAD factors.

    One character's emotion layer: an :class:`EmotionBatch` of one row (one implementation of both).

    >>> engine = EmotionEngine()
    >>> engine.trigger("happy", 1.2, t_s=0.0)
    >>> engine.intensities(0.2).round(3).tolist()      # half-way through the 0.4 s onset
    [0.6, 0.0, 0.0, 0.0, 0.0, 0.0]
    >>> emotion, shown_mood = engine.expressed(2.0)     # the event is over: only the mood shows
    >>> emotion.tolist(), bool(shown_mood[0] > 0)
    ([0.0, 0.0, 0.0, 0.0, 0.0, 0.0], True)
    """

    def __init__(
        self,
        mode: str = "categorical",
        envelope: Envelope | None = None,
        mood_time_constant_s: float = 10.0,
        mood_gain: float = 1.0,
        *,
        pad_radius: float = PAD_RADIUS,
        mood_max_step_s: float = 0.05,
    ) -> None:
        """Create an engine.

        ``mode``: ``"categorical"`` or ``"pad"`` (:meth:`set_pad` only in ``"pad"``). ``envelope``: default
        onset/hold/decay of events (the study's 0.4/0.3/0.3 s); in PAD mode its ``onset_s`` is also the time a
        new PAD state takes to be reached. ``mood_time_constant_s`` (> 0): time constant of the mood's
        moving average. ``mood_gain`` (>= 0): mood's steady state per unit of sustained emotion.
        ``pad_radius``: see :func:`~mien.affect.pad.pad_to_emotions`. ``mood_max_step_s`` (> 0): longest
        integration step of the mood.
        """
        if mode not in MODES:
            raise InvalidValueError("mode", mode, f"one of {', '.join(MODES)}")
        self.mode = mode
        """``"categorical"`` or ``"pad"``."""
        self.batch = EmotionBatch(
            1, envelope, mood_time_constant_s, mood_gain, pad_radius=pad_radius, mood_max_step_s=mood_max_step_s
        )
        """The one-row batch doing the work."""

    @property
    def envelope(self) -> Envelope:
        """Default envelope of events."""
        return self.batch.envelope

    @property
    def mood_time_constant_s(self) -> float:
        """Time constant of the mood's exponential moving average, seconds."""
        return self.batch.mood_time_constant_s

    @property
    def mood_gain(self) -> float:
        """Mood's steady state per unit of sustained emotion."""
        return self.batch.mood_gain

    @property
    def pad_radius(self) -> float:
        """Reach of a PAD prototype (chord distance of directions)."""
        return self.batch.pad_radius

    @property
    def mood_max_step_s(self) -> float:
        """Longest mood integration step, seconds."""
        return self.batch.mood_max_step_s

    # ---------------------------------------------------------------- input

    def trigger(
        self,
        emotion: str | Blend,
        intensity: float,
        t_s: float,
        envelope: Envelope | None = None,
    ) -> None:
        """Start an event: ``emotion`` (a name, alias, blend name or :class:`Blend`) at ``intensity`` at ``t_s``.

        ``intensity`` in [0, 5]: 1 is the prototype / Table 1 magnitude (the study used 1.2 and 2.4).
        ``envelope`` overrides the engine's default for this event. Bad values raise
        :class:`~mien.errors.InvalidValueError` (:class:`~mien.errors.UnknownNameError` for names).
        """
        self.batch.trigger(0, emotion, intensity, t_s, envelope)

    def set_pad(self, pleasure: float, arousal: float, dominance: float, t_s: float) -> None:
        """Move the PAD factor state (each in [-1, 1]) to a new value, reached linearly over ``envelope.onset_s``.

        The state is held until the next call (the caller owns the factor dynamics; set ``(0, 0, 0)`` to let
        the emotion decay to the mood). Only in ``"pad"`` mode.
        """
        if self.mode != "pad":
            raise InvalidValueError("mode", self.mode, "'pad' to use set_pad (EmotionEngine(mode='pad'))")
        self.batch.set_pad(0, pleasure, arousal, dominance, t_s)

    def set_mood(self, mood: object) -> None:
        """Set the mood (6,) intensities, each finite in [0, 5] (e.g. a character's resting disposition)."""
        self.batch.set_mood(0, mood)

    def reset(self) -> None:
        """Forget every event, the PAD state, the mood and the time."""
        b = self.batch
        self.batch = EmotionBatch(
            1,
            b.envelope,
            b.mood_time_constant_s,
            b.mood_gain,
            pad_radius=b.pad_radius,
            mood_max_step_s=b.mood_max_step_s,
        )

    # ---------------------------------------------------------------- output

    @property
    def n_events(self) -> int:
        """Number of events not yet pruned (pruning happens when time advances past their end)."""
        return self.batch.n_events()

    def pad(self, t_s: float) -> np.ndarray:
        """(3,) PAD factor state at ``t_s`` (zeros in categorical mode)."""
        return self.batch.pad_at(t_s)[0]

    def intensities(self, t_s: float, out: np.ndarray | None = None) -> np.ndarray:
        """(6,) emotion intensities at ``t_s`` (EMOTIONS order; 0..5), written to ``out`` if given."""
        return _write(self.batch.advance(t_s)[0], out)

    def mood(self, t_s: float, out: np.ndarray | None = None) -> np.ndarray:
        """(6,) mood at ``t_s``: the moving average of the emotion, advanced incrementally to ``t_s``."""
        self.batch.advance(t_s)
        return _write(self.batch.mood[0], out)

    def state(self, t_s: float) -> tuple[np.ndarray, np.ndarray]:
        """``(emotion (6,), mood (6,))`` at ``t_s``."""
        emotion = self.batch.advance(t_s)
        return emotion[0].copy(), self.batch.mood[0].copy()

    def expressed(
        self, t_s: float, emotion_out: np.ndarray | None = None, mood_out: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """``(emotion (6,), shown_mood (6,))`` to express at ``t_s``.

        ``shown_mood = (1 - min(1, sum(emotion))) * mood``: express ``emotion`` with the full basis and
        ``shown_mood`` with the closed-mouth basis, and add the two.
        """
        emotion, shown = self.batch.expressed(t_s)
        return _write(emotion[0], emotion_out), _write(shown[0], mood_out)


def mood_step(
    mood: np.ndarray,
    previous: np.ndarray,
    current: np.ndarray,
    dt_s: float,
    time_constant_s: float,
    gain: float = 1.0,
) -> np.ndarray:
    """Vectorised mood update used by :class:`EmotionEngine`, for a batch of characters; updates ``mood`` in place.

    ``mood``, ``previous`` (emotion at the last time) and ``current`` (emotion now) are (..., 6); ``dt_s``
    >= 0 is the time since the last update (keep it below ~0.05 s for the trapezoid to be accurate).
    ``mood += (1 - exp(-dt / tau)) * (gain * (previous + current) / 2 - mood)``.

    >>> m = np.zeros((2, 6)); e = np.ones((2, 6))
    >>> mood_step(m, e, e, 0.1, 10.0)[0, 0].round(6).item()
    0.00995
    """
    k = -math.expm1(-dt_s / time_constant_s)
    target = np.add(previous, current)
    target *= 0.5 * gain
    target -= mood
    target *= k
    mood += target
    return mood


def shown_mood(emotion: np.ndarray, mood: np.ndarray) -> np.ndarray:
    """Vectorised occlusion of the mood by the emotion: ``(1 - min(1, sum(emotion))) * mood`` over (..., 6).

    >>> shown_mood(np.array([0.25, 0, 0, 0, 0, 0]), np.array([0, 0.4, 0, 0, 0, 0])).round(3).tolist()
    [0.0, 0.3, 0.0, 0.0, 0.0, 0.0]
    """
    occlusion = 1.0 - np.minimum(1.0, np.sum(emotion, axis=-1, keepdims=True))
    return occlusion * mood
