"""A character: FACS targets, emotion events, mood, laughter and idle behaviour combined into face frames.

Layers, added in this order into the (62,) face frame (see :data:`~mien.facs.catalogue.FACE_CHANNELS`):

1. FACS: held AU targets with time-based dynamics and timed onset/apex/offset actions (:class:`FacsEngine`).
2. Emotions (Broekens): ``emotion @ basis + shown_mood @ closed_mouth_basis`` (:class:`EmotionEngine`).
   With ``expression_basis="facs"`` the basis is the EMFACS prototypes (AU channels); with
   ``"feature_points"`` the emotion drives the 54 feature-point targets (:attr:`Character.feature_weights`,
   metres) and leaves the AU channels alone.
3. Laughter: the face clip of an active laugh or smile; while it plays, idle mouth motion yields.
4. Idle: blinks (combined by max, so a blink still closes smiling eyes), micro random walks, gaze, wobble.

AU channels are then clipped to 0..5 (a live stream must not break on an over-driven sum: the clamp is
documented, not an error). The face at time t depends only on the seed and the commands given, so runs are
reproducible; time must not go backwards.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from mien.affect.basis import facs_basis, feature_point_basis, saturate
from mien.affect.emotions import Blend, blend_components, check_intensity
from mien.affect.engine import EmotionEngine, mood_step, shown_mood
from mien.affect.envelope import Envelope, envelope_values
from mien.errors import InvalidValueError
from mien.facs.catalogue import FACE_CHANNELS, POSE_CHANNELS, au_channels
from mien.facs.clip import Clip
from mien.facs.dynamics import FacsEngine, TimedAction, time_constant_from_speed
from mien.facs.idle import Idle, IdleBatch, IdleSettings
from mien.facs.intensity import AUSpec, parse_au

__all__ = ["EXPRESSION_BASES", "Character", "CharacterBatch"]

EXPRESSION_BASES = ("facs", "feature_points")
"""How emotions reach the face: EMFACS AU prototypes, or Broekens' feature-point vectors."""

_N = len(FACE_CHANNELS)
_N_AU = _N - len(POSE_CHANNELS)


def _mouth_channel_ids() -> np.ndarray:
    mouth_codes = {8, 10, 12, 13, 14, 15, 16, 17, 18, 20, 22, 23, 24, 25, 26, 27, 28}
    return np.array([i for i, name in enumerate(FACE_CHANNELS[:_N_AU]) if int(name[2:].rstrip("LR")) in mouth_codes])


def _idle_settings(idle: IdleSettings | bool) -> IdleSettings | None:
    if isinstance(idle, IdleSettings):
        return idle
    return IdleSettings() if idle else None


@dataclass(frozen=True, eq=False)
class _ActiveLaugh:
    start_s: float
    clip: Clip

    @property
    def end_s(self) -> float:
        return self.start_s + self.clip.duration_s

    def sample(self, t_s: float) -> np.ndarray:
        return self.clip.sample(t_s - self.start_s)


class Character:
    """One animated face. Give it commands, then call :meth:`step` with increasing times.

    >>> c = Character(seed=1, idle=False)
    >>> c.emote("joy", 1.0)
    >>> frame = c.step(0.5)                      # hold phase of the 0.4/0.3/0.3 s envelope
    >>> float(frame[FACE_CHANNELS.index("AU12L")])  # EMFACS joy: AU12 at 3.5 (prototypes v2)
    3.5
    """

    def __init__(
        self,
        seed: int = 0,
        idle: IdleSettings | bool = True,
        expression_basis: str = "facs",
        emotion_mode: str = "categorical",
        envelope: Envelope | None = None,
        mood_time_constant_s: float = 10.0,
        mood_gain: float = 1.0,
        tick_hz: float = 60.0,
    ) -> None:
        if expression_basis not in EXPRESSION_BASES:
            raise InvalidValueError("expression_basis", expression_basis, f"one of {', '.join(EXPRESSION_BASES)}")
        self.seed = int(seed)
        """Seed of the idle behaviour (and default seed of laughter)."""
        self.expression_basis = expression_basis
        """``"facs"`` or ``"feature_points"``."""
        self.facs = FacsEngine(tick_hz=tick_hz)
        """The FACS layer."""
        self.emotions = EmotionEngine(
            mode=emotion_mode, envelope=envelope, mood_time_constant_s=mood_time_constant_s, mood_gain=mood_gain
        )
        """The emotion layer (Broekens)."""
        settings = _idle_settings(idle)
        self.idle: Idle | None = Idle(self.seed, settings) if settings is not None else None
        """The idle layer, or None when switched off."""
        if expression_basis == "facs":
            self._basis, self._mood_basis = facs_basis(), facs_basis(closed_mouth=True)
        else:
            self._basis, self._mood_basis = feature_point_basis(), feature_point_basis(closed_mouth=True)
        self.feature_weights = np.zeros(feature_point_basis().shape[1])
        """(54,) feature-point target weights (metres) of the last step (``"feature_points"`` basis only)."""
        self.last_feature_weights: np.ndarray | None = None
        """(n_frames, 54) feature weights of the last :meth:`run` (``"feature_points"`` basis only)."""
        self._laughs: list[_ActiveLaugh] = []
        self._frame = np.zeros(_N)
        self._emotion = np.zeros(6)
        self._mood = np.zeros(6)
        self._expression = np.zeros(self._basis.shape[1])
        self._mood_expression = np.zeros(self._basis.shape[1])
        self._mouth = _mouth_channel_ids()
        self._t_s = 0.0

    @property
    def time_s(self) -> float:
        """Time of the last :meth:`step`, seconds."""
        return self._t_s

    # ------------------------------------------------------------------ commands

    def set_au(self, au: str | AUSpec, intensity: float | None = None, tau_s: float | None = None) -> None:
        """Hold an AU (``"AU12"``, ``"L12C"``...) at ``intensity`` 0..5 (see :meth:`FacsEngine.set`)."""
        self.facs.set(au, intensity, tau_s)

    def set_aus(self, intensities: Mapping[str, float], speed: float | None = None, replace: bool = False) -> None:
        """Hold several AUs; ``speed`` is OpenFACS's per-tick Speed; ``replace`` zeroes the AUs not named."""
        self.facs.set_many(intensities, speed=speed, replace=replace)

    def play_au(
        self,
        au: str | AUSpec,
        intensity: float | None = None,
        onset_s: float = 0.4,
        apex_s: float = 0.3,
        offset_s: float = 0.3,
        start_s: float | None = None,
    ) -> TimedAction:
        """Play an AU once with an onset/apex/offset envelope, starting now or at ``start_s``."""
        return self.facs.play(au, intensity, start_s if start_s is not None else self._t_s, onset_s, apex_s, offset_s)

    def emote(
        self,
        emotion: str | Blend,
        intensity: float = 1.0,
        start_s: float | None = None,
        envelope: Envelope | None = None,
    ) -> None:
        """Trigger an emotion or blend event (intensity 0..5, 1 = the prototype) now or at ``start_s``."""
        self.emotions.trigger(emotion, intensity, self._t_s if start_s is None else start_s, envelope)

    def set_pad(self, pleasure: float, arousal: float, dominance: float) -> None:
        """Move the PAD state (each in [-1, 1]; needs ``emotion_mode="pad"``)."""
        self.emotions.set_pad(pleasure, arousal, dominance, self._t_s)

    def set_mood(self, mood: Mapping[str, float] | np.ndarray) -> None:
        """Set the mood: a (6,) vector or ``{emotion: intensity}``."""
        if isinstance(mood, Mapping):
            vector = np.zeros(6)
            for name, value in mood.items():
                for index, weight in blend_components(name):
                    vector[index] += weight * check_intensity(value, f"mood[{name}]")
            mood = vector
        self.emotions.set_mood(mood)

    def laugh(
        self,
        laugh_type: str,
        intensity: float = 1.0,
        duration_s: float | None = None,
        seed: int | None = None,
        start_s: float | None = None,
    ) -> Clip:
        """Play a laugh or smile (one of the 13 types); returns its face clip. The laugh drives the mouth."""
        from mien.laughter.generator import generate

        result = generate(
            laugh_type, intensity=intensity, duration_s=duration_s, seed=self.seed if seed is None else seed
        )
        self.play_clip(result.face_clip, start_s)
        return result.face_clip

    def play_clip(self, clip: Clip, start_s: float | None = None) -> None:
        """Add a face clip (channels ⊂ FACE_CHANNELS, e.g. a laugh or an imported performance) as a layer."""
        if clip.channels != FACE_CHANNELS:
            values = np.zeros((clip.n_frames, _N))
            for j, name in enumerate(clip.channels):
                values[:, FACE_CHANNELS.index(name)] = clip.values[:, j]
            clip = Clip(values, clip.fps, FACE_CHANNELS)
        self._laughs.append(_ActiveLaugh(self._t_s if start_s is None else float(start_s), clip))

    # ------------------------------------------------------------------ output

    def step(self, t_s: float) -> np.ndarray:
        """The (62,) face frame at ``t_s`` (>= the previous time). The array is reused by the next step."""
        frame = self._frame
        frame[:] = self.facs.advance(t_s)
        self._t_s = t_s
        emotion, mood = self.emotions.expressed(t_s, self._emotion, self._mood)
        expression = np.dot(emotion, self._basis, out=self._expression)
        expression += np.dot(mood, self._mood_basis, out=self._mood_expression)
        if self.expression_basis == "facs":
            frame += saturate(expression)
        else:
            self.feature_weights[:] = expression
        laughing = False
        if self._laughs:
            for laugh in self._laughs:
                if laugh.start_s <= t_s < laugh.end_s:
                    frame += laugh.sample(t_s)
                    laughing = True
            self._laughs = [laugh for laugh in self._laughs if t_s < laugh.end_s]
        # idle mouth motion yields to a laughing mouth, and in proportion to other mouth activity
        mouth_scale = 0.0 if laughing else max(0.0, 1.0 - float(frame[self._mouth].max()) / 2.0)
        if self.idle is not None:
            self.idle.apply(t_s, frame, mouth_scale)
        np.clip(frame[:_N_AU], 0.0, 5.0, out=frame[:_N_AU])
        return frame

    def run(self, duration_s: float, fps: float = 60.0) -> Clip:
        """Step from the current time for ``duration_s`` at ``fps`` and return the frames as a :class:`Clip`.

        The first frame is the current time (for a new character, t = 0).
        """
        if not (math.isfinite(duration_s) and duration_s > 0):
            raise InvalidValueError("duration_s", duration_s, "a positive number of seconds")
        if not (math.isfinite(fps) and fps > 0):
            raise InvalidValueError("fps", fps, "a positive frame rate")
        n_frames = max(1, round(duration_s * fps))
        start = self._t_s
        values = np.empty((n_frames, _N))
        features = np.empty((n_frames, self.feature_weights.shape[0])) if self.expression_basis != "facs" else None
        for i in range(n_frames):
            values[i] = self.step(start + i / fps)
            if features is not None:
                features[i] = self.feature_weights
        self.last_feature_weights = features
        return Clip(values, fps, FACE_CHANNELS)

    def snapshot(self) -> dict[str, Any]:
        """A plain dict of the current frame (channel -> value), for servers and logs."""
        return dict(zip(FACE_CHANNELS, self._frame.tolist(), strict=True))


class CharacterBatch:
    """Many characters stepped together with vectorised numpy (one seed each).

    Supports what crowds need: held AU targets with time constants, emotion and blend events with
    envelopes, mood and idle behaviour, with the same results as single :class:`Character` objects given
    the same seeds and commands (to float rounding). Timed AU actions, PAD mode, laughter and the
    feature-point basis are single-character features.
    """

    def __init__(
        self,
        seeds: np.ndarray | int,
        idle: IdleSettings | bool = True,
        envelope: Envelope | None = None,
        mood_time_constant_s: float = 10.0,
        mood_gain: float = 1.0,
        mood_max_step_s: float = 0.05,
        tick_hz: float = 60.0,
    ) -> None:
        seeds_array = np.arange(seeds) if isinstance(seeds, int) else np.asarray(seeds)
        self.seeds = seeds_array.astype(np.int64)
        """(n,) seeds."""
        n = self.seeds.shape[0]
        self.tick_hz = float(tick_hz)
        self.envelope = envelope or Envelope()
        self.mood_time_constant_s = float(mood_time_constant_s)
        self.mood_gain = float(mood_gain)
        self.mood_max_step_s = float(mood_max_step_s)
        settings = _idle_settings(idle)
        self.idle = IdleBatch(self.seeds, settings) if settings is not None else None
        single = FacsEngine(tick_hz=tick_hz)
        self.target = np.zeros((n, _N))
        """(n, 62) held targets."""
        self.current = np.zeros((n, _N))
        """(n, 62) smoothed FACS state."""
        self.tau_s = np.tile(single.tau_s, (n, 1))
        """(n, 62) time constants, seconds."""
        self._decay = np.zeros((n, _N))
        self._decay_dt = -1.0
        self._capacity = 4
        self._ev_start = np.full((n, self._capacity), np.inf)
        self._ev_onset = np.ones((n, self._capacity))
        self._ev_hold = np.zeros((n, self._capacity))
        self._ev_decay = np.ones((n, self._capacity))
        self._ev_amount = np.zeros((n, self._capacity, 6))
        self._mood = np.zeros((n, 6))
        self._emotion = np.zeros((n, 6))
        self._basis = facs_basis()
        self._mood_basis = facs_basis(closed_mouth=True)
        self._frames = np.zeros((n, _N))
        self._mouth = _mouth_channel_ids()
        self._t_s: float | None = None

    @property
    def n_characters(self) -> int:
        """Number of characters."""
        return int(self.seeds.shape[0])

    def set_au(
        self, characters: np.ndarray | slice | int, au: str, intensity: float, tau_s: float | None = None
    ) -> None:
        """Hold ``au`` at ``intensity`` on the selected characters (index array, slice or int)."""
        spec = parse_au(au)
        probe = FacsEngine(tick_hz=self.tick_hz)
        probe.set(spec, intensity, tau_s)  # validates and converts head/eye codes to degrees
        channels = np.array(au_channels(spec.code, spec.side))
        rows = np.atleast_1d(np.arange(self.n_characters)[characters])[:, None]
        self.target[rows, channels] = probe.target[channels]
        if tau_s is not None:
            self.tau_s[rows, channels] = probe.tau_s[channels]
            self._decay_dt = -1.0

    def set_speed(self, characters: np.ndarray | slice | int, speed: float) -> None:
        """OpenFACS Speed (per tick at the nominal rate) for every AU channel of the selected characters."""
        self.tau_s[characters, :_N_AU] = time_constant_from_speed(speed, self.tick_hz)
        self._decay_dt = -1.0

    def emote(
        self,
        characters: np.ndarray | slice | int,
        emotion: str | Blend,
        intensity: float,
        t_s: float,
        envelope: Envelope | None = None,
    ) -> None:
        """Trigger an emotion event on the selected characters at ``t_s``."""
        value = check_intensity(intensity)
        env = envelope or self.envelope
        amounts = np.zeros(6)
        for index, weight in blend_components(emotion):
            amounts[index] += weight * value
        rows = np.arange(self.n_characters)[characters]
        rows = np.atleast_1d(rows)
        free = ~np.isfinite(self._ev_start[rows]) | (self._ev_start[rows] + self._ev_total()[rows] <= (self._t_s or -1))
        if not free.any(axis=1).all():
            self._grow()
            free = ~np.isfinite(self._ev_start[rows])
        slots = free.argmax(axis=1)
        self._ev_start[rows, slots] = float(t_s)
        self._ev_onset[rows, slots] = env.onset_s
        self._ev_hold[rows, slots] = env.hold_s
        self._ev_decay[rows, slots] = env.decay_s
        self._ev_amount[rows, slots] = amounts

    def _ev_total(self) -> np.ndarray:
        return self._ev_onset + self._ev_hold + self._ev_decay

    def _grow(self) -> None:
        extra = self._capacity
        n = self.n_characters
        self._ev_start = np.concatenate([self._ev_start, np.full((n, extra), np.inf)], axis=1)
        self._ev_onset = np.concatenate([self._ev_onset, np.ones((n, extra))], axis=1)
        self._ev_hold = np.concatenate([self._ev_hold, np.zeros((n, extra))], axis=1)
        self._ev_decay = np.concatenate([self._ev_decay, np.ones((n, extra))], axis=1)
        self._ev_amount = np.concatenate([self._ev_amount, np.zeros((n, extra, 6))], axis=1)
        self._capacity += extra

    def _emotion_at(self, t_s: float) -> np.ndarray:
        levels = envelope_values(t_s - self._ev_start, self._ev_onset, self._ev_hold, self._ev_decay)
        emotion = np.einsum("nk,nke->ne", levels, self._ev_amount)
        np.minimum(emotion, 5.0, out=emotion)
        return emotion

    def _advance_affect(self, t_s: float) -> None:
        last = self._t_s
        if last is None or t_s == last:
            self._emotion = self._emotion_at(t_s)
            return
        dt = t_s - last
        n_steps = math.ceil(dt / self.mood_max_step_s) if dt > self.mood_max_step_s else 1
        step = dt / n_steps
        previous = self._emotion
        for s in range(1, n_steps + 1):
            current = self._emotion_at(t_s if s == n_steps else last + s * step)
            mood_step(self._mood, previous, current, step, self.mood_time_constant_s, self.mood_gain)
            previous = current
        self._emotion = previous
        finished = self._ev_start + self._ev_total() <= t_s
        if finished.any():
            self._ev_start[finished] = np.inf

    def step(self, t_s: float) -> np.ndarray:
        """(n, 62) face frames at ``t_s`` (>= the previous time); the array is reused by the next step."""
        last = self._t_s
        dt = t_s - (0.0 if last is None else last)  # the FACS layer starts at t = 0, like Character's
        if not dt >= 0.0:
            raise InvalidValueError("t_s", t_s, f"a time >= the previous time {last}")
        if dt > 0.0:
            if dt != self._decay_dt:
                with np.errstate(divide="ignore", invalid="ignore"):
                    np.exp(-dt / self.tau_s, out=self._decay)
                np.nan_to_num(self._decay, copy=False, nan=0.0)
                self._decay_dt = dt
            self.current -= self.target
            self.current *= self._decay
            self.current += self.target
        self._advance_affect(t_s)
        self._t_s = t_s
        frames = self._frames
        np.dot(self._emotion, self._basis, out=frames)
        frames += np.dot(shown_mood(self._emotion, self._mood), self._mood_basis)
        saturate(frames)  # the emotion layer only: the FACS layer is added after
        frames += self.current
        if self.idle is not None:
            mouth = frames[:, self._mouth].max(axis=1)
            self.idle.apply(t_s, frames, np.maximum(0.0, 1.0 - mouth / 2.0))
        np.clip(frames[:, :_N_AU], 0.0, 5.0, out=frames[:, :_N_AU])
        return frames
