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

Per-frame cost is a few microseconds for a handful of events: plain Python floats, no array rebuilding; pass
``out=`` arrays to avoid even the small (6,) allocations.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mien.affect.emotions import EMOTIONS, MAX_INTENSITY, Blend, blend_components, check_intensity
from mien.affect.envelope import Envelope, envelope_value
from mien.affect.pad import PAD_RADIUS, check_pad, pad_intensities
from mien.errors import InvalidValueError

__all__ = ["MODES", "EmotionEngine", "mood_step", "shown_mood"]

MODES: tuple[str, ...] = ("categorical", "pad")
"""Emotion representations: a vector of emotion intensities, or a PAD factor state."""

_N = len(EMOTIONS)
_ZERO: list[float] = [0.0] * _N  # shared, never mutated


@dataclass(slots=True)
class _Event:
    start_s: float
    onset_s: float
    hold_s: float
    decay_s: float
    end_s: float
    amounts: tuple[tuple[int, float], ...]  # (emotion index, intensity * blend weight)


def _finite(field: str, value: object) -> float:
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InvalidValueError(field, value, "a finite number") from None
    if not math.isfinite(v):
        raise InvalidValueError(field, value, "a finite number")
    return v


def _write(values: list[float], out: np.ndarray | None) -> np.ndarray:
    if out is None:
        return np.array(values)
    out[...] = values
    return out


class EmotionEngine:
    """Emotion events with onset/hold/decay envelopes, a mood that averages them, optional PAD factors.

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
        self.mode = mode
        """``"categorical"`` or ``"pad"``."""
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
        self._events: list[_Event] = []
        self._next_end_s = math.inf
        self._t_s: float | None = None  # latest time advanced to
        self._emotion = [0.0] * _N  # emotion at _t_s
        self._dirty = False  # an event or PAD change since _emotion was computed
        self._mood = [0.0] * _N
        self._last_dt_s = -1.0
        self._last_k = 0.0
        # PAD state: linear ramp from _pad_from (at _pad_t0_s) to _pad_to over _pad_ramp_s
        self._pad_from = (0.0, 0.0, 0.0)
        self._pad_to = (0.0, 0.0, 0.0)
        self._pad_t0_s = 0.0
        self._pad_ramp_s = 0.0
        self._pad_settled = [0.0] * _N  # intensities of _pad_to

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
        amounts = tuple((i, w) for i, w in blend_components(emotion))
        value = check_intensity(intensity)
        start = _finite("t_s", t_s)
        if envelope is not None and not isinstance(envelope, Envelope):
            raise InvalidValueError("envelope", envelope, "an Envelope")
        env = envelope if envelope is not None else self.envelope
        end = start + env.total_s
        self._events.append(
            _Event(start, env.onset_s, env.hold_s, env.decay_s, end, tuple((i, w * value) for i, w in amounts))
        )
        self._next_end_s = min(self._next_end_s, end)
        self._dirty = True

    def set_pad(self, pleasure: float, arousal: float, dominance: float, t_s: float) -> None:
        """Move the PAD factor state (each in [-1, 1]) to a new value, reached linearly over ``envelope.onset_s``.

        The state is held until the next call (the caller owns the factor dynamics; set ``(0, 0, 0)`` to let
        the emotion decay to the mood). Only in ``"pad"`` mode.
        """
        if self.mode != "pad":
            raise InvalidValueError("mode", self.mode, "'pad' to use set_pad (EmotionEngine(mode='pad'))")
        target = check_pad(pleasure, arousal, dominance)
        start = _finite("t_s", t_s)
        self._pad_from = self._pad_at(start)
        self._pad_to = target
        self._pad_t0_s = start
        self._pad_ramp_s = self.envelope.onset_s
        self._pad_settled = pad_intensities(*target, radius=self.pad_radius)
        self._dirty = True

    def set_mood(self, mood: object) -> None:
        """Set the mood (6,) intensities, each finite in [0, 5] (e.g. a character's resting disposition)."""
        try:
            values = np.asarray(mood, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError):
            raise InvalidValueError("mood", mood, f"{_N} intensities in [0, 5]") from None
        if values.shape != (_N,):
            raise InvalidValueError("mood", mood, f"{_N} intensities in [0, 5] ({', '.join(EMOTIONS)})")
        self._mood = [check_intensity(v, f"mood[{name}]") for v, name in zip(values.tolist(), EMOTIONS, strict=True)]

    def reset(self) -> None:
        """Forget every event, the PAD state, the mood and the time."""
        self.__init__(  # type: ignore[misc]
            self.mode,
            self.envelope,
            self.mood_time_constant_s,
            self.mood_gain,
            pad_radius=self.pad_radius,
            mood_max_step_s=self.mood_max_step_s,
        )

    # ---------------------------------------------------------------- output

    @property
    def n_events(self) -> int:
        """Number of events not yet pruned (pruning happens when time advances past their end)."""
        return len(self._events)

    def pad(self, t_s: float) -> np.ndarray:
        """(3,) PAD factor state at ``t_s`` (zeros in categorical mode)."""
        return np.array(self._pad_at(_finite("t_s", t_s)))

    def intensities(self, t_s: float, out: np.ndarray | None = None) -> np.ndarray:
        """(6,) emotion intensities at ``t_s`` (EMOTIONS order; 0..5), written to ``out`` if given."""
        return _write(self._advance(t_s), out)

    def mood(self, t_s: float, out: np.ndarray | None = None) -> np.ndarray:
        """(6,) mood at ``t_s``: the moving average of the emotion, advanced incrementally to ``t_s``."""
        self._advance(t_s)
        return _write(self._mood, out)

    def state(self, t_s: float) -> tuple[np.ndarray, np.ndarray]:
        """``(emotion (6,), mood (6,))`` at ``t_s``."""
        emotion = self._advance(t_s)
        return np.array(emotion), np.array(self._mood)

    def expressed(
        self, t_s: float, emotion_out: np.ndarray | None = None, mood_out: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """``(emotion (6,), shown_mood (6,))`` to express at ``t_s``.

        ``shown_mood = (1 - min(1, sum(emotion))) * mood``: express ``emotion`` with the full basis and
        ``shown_mood`` with the closed-mouth basis, and add the two.
        """
        emotion = self._advance(t_s)
        occlusion = 1.0 - min(1.0, sum(emotion))
        shown = [occlusion * m for m in self._mood]
        return _write(emotion, emotion_out), _write(shown, mood_out)

    # ---------------------------------------------------------------- internals

    def _pad_at(self, t_s: float) -> tuple[float, float, float]:
        elapsed = t_s - self._pad_t0_s
        if elapsed >= self._pad_ramp_s:
            return self._pad_to
        if elapsed <= 0.0:
            return self._pad_from
        f = elapsed / self._pad_ramp_s
        a, b = self._pad_from, self._pad_to
        return (a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2]))

    def _emotion_at(self, t_s: float) -> list[float]:
        """Emotion at ``t_s`` as a list (may be the shared ``_ZERO``: never mutate the result)."""
        if self.mode == "pad":
            if t_s - self._pad_t0_s >= self._pad_ramp_s:
                e = self._pad_settled.copy()
            else:
                e = pad_intensities(*self._pad_at(t_s), radius=self.pad_radius)
        elif not self._events:
            return _ZERO
        else:
            e = [0.0] * _N
        for ev in self._events:
            if ev.start_s <= t_s < ev.end_s:
                v = envelope_value(t_s - ev.start_s, ev.onset_s, ev.hold_s, ev.decay_s)
                for index, amount in ev.amounts:
                    e[index] += v * amount
        if max(e) > MAX_INTENSITY:
            e = [min(x, MAX_INTENSITY) for x in e]
        return e

    def _advance(self, t_s: float) -> list[float]:
        t = float(t_s)
        if not math.isfinite(t):
            raise InvalidValueError("t_s", t_s, "a finite number of seconds")
        last = self._t_s
        if last is None:
            self._t_s = t
            self._emotion = self._emotion_at(t)
            self._dirty = False
            return self._emotion
        if t < last:  # no rewinding: the emotion at t, mood untouched
            return self._emotion_at(t)
        if self._dirty:
            self._emotion = self._emotion_at(last)
            self._dirty = False
        if t == last:
            return self._emotion
        dt = t - last
        n_steps = math.ceil(dt / self.mood_max_step_s) if dt > self.mood_max_step_s else 1
        step = dt / n_steps
        if step != self._last_dt_s:  # fixed frame rates reuse the factor
            self._last_dt_s = step
            self._last_k = -math.expm1(-step / self.mood_time_constant_s)
        k = self._last_k
        half_gain = 0.5 * self.mood_gain
        mood = self._mood
        previous = self._emotion
        for s in range(1, n_steps + 1):
            current = self._emotion_at(t if s == n_steps else last + s * step)
            if previous is _ZERO and current is _ZERO:
                keep = 1.0 - k
                mood = [keep * m for m in mood]
            else:
                mood = [m + k * (half_gain * (a + b) - m) for m, a, b in zip(mood, previous, current, strict=True)]
            previous = current
        self._mood = mood
        self._t_s = t
        self._emotion = previous
        if t >= self._next_end_s:
            self._events = [ev for ev in self._events if ev.end_s > t]
            self._next_end_s = min((ev.end_s for ev in self._events), default=math.inf)
        return previous


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
