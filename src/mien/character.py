"""Characters: FACS targets, emotion events, mood, laughter and idle behaviour combined into face frames.

One implementation for one character and for many: :class:`CharacterBatch` steps n characters (rows) with
vectorised numpy, and :class:`Character` is a batch of one, so a single character cannot drift from a row
of a crowd. Layers, added in this order into each (62,) face frame (see
:data:`~mien.facs.catalogue.FACE_CHANNELS`):

1. FACS: held AU targets with time-based dynamics and timed onset/apex/offset actions
   (:class:`~mien.facs.dynamics.FacsBatch`), plus a person's performance where one drives the row (a held
   (62,) face frame, :meth:`CharacterBatch.set_performance`: live capture, ``mien serve --capture``).
2. Emotions (Broekens): ``emotion @ basis + shown_mood @ closed_mouth_basis``
   (:class:`~mien.affect.engine.EmotionBatch`, events, PAD states, moods). With ``expression_basis="facs"``
   the basis is the EMFACS prototypes (AU channels, scaled by :func:`~mien.affect.basis.saturate`); with
   ``"feature_points"`` the emotion drives the 54 feature-point targets (:attr:`CharacterBatch.feature_weights`,
   metres) and leaves the AU channels alone.
3. Speech (:meth:`CharacterBatch.say`, :class:`~mien.speech.batch.SpeechBatch`): the coarticulated visemes
   take the lips' opening and rounding and the jaw by one rule (:func:`~mien.speech.arbitration.arbitrate`);
   emotion keeps brows, lids, cheeks, lip corners and upper lip; a laugh interrupts speech (which keeps its
   clock, in sync with its sound, and comes back after the laugh); idle mouth motion yields; blinks continue.
4. Laughter: the face clip of an active laugh or smile; while it plays, idle mouth motion yields.
5. Idle: blinks (combined by max, so a blink still closes smiling eyes), micro random walks, gaze, wobble
   (:class:`~mien.facs.idle.IdleBatch`).

AU channels are then clipped to 0..5 (a live stream must not break on an over-driven sum: the clamp is
documented, not an error). The face at time t depends only on the seed and the commands given, so runs are
reproducible; time must not go backwards. The per-step products go through
:func:`~mien.small_matmul.matmul_rows`, so no step waits on a multi-threaded BLAS on a busy machine.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from mien.affect.basis import facs_basis, feature_point_basis, saturate
from mien.affect.emotions import Blend, blend_components, check_intensity
from mien.affect.engine import MODES, EmotionBatch
from mien.errors import InvalidValueError
from mien.facs.catalogue import FACE_CHANNELS, POSE_CHANNELS
from mien.facs.clip import Clip
from mien.facs.dynamics import FacsBatch, RowIndex, TimedAction
from mien.facs.envelope import Envelope
from mien.facs.idle import IDLE_COLUMNS, IdleBatch, IdleSettings
from mien.facs.intensity import AUSpec
from mien.small_matmul import matmul_rows
from mien.speech.batch import SpeechBatch
from mien.speech.track import Utterance

__all__ = ["EXPRESSION_BASES", "MAX_SEED", "Character", "CharacterBatch", "check_basis", "check_seed"]

EXPRESSION_BASES = ("facs", "feature_points")
"""How emotions reach the face: EMFACS AU prototypes, or Broekens' feature-point vectors."""

_N = len(FACE_CHANNELS)
_N_AU = _N - len(POSE_CHANNELS)
_N_FEATURES = feature_point_basis().shape[1]


def _mouth_channel_ids() -> np.ndarray:
    mouth_codes = {8, 10, 12, 13, 14, 15, 16, 17, 18, 20, 22, 23, 24, 25, 26, 27, 28}
    return np.array([i for i, name in enumerate(FACE_CHANNELS[:_N_AU]) if int(name[2:].rstrip("LR")) in mouth_codes])


_MOUTH = _mouth_channel_ids()
_MOUTH_OF = operator.itemgetter(*_MOUTH.tolist())
_IDLE_VALUES = operator.itemgetter(*IDLE_COLUMNS.tolist())


def _idle_settings(idle: IdleSettings | bool) -> IdleSettings | None:
    if isinstance(idle, IdleSettings):
        return idle
    if isinstance(idle, bool | np.bool_):
        return IdleSettings() if idle else None
    raise InvalidValueError("idle", idle, "True, False or an IdleSettings")


MAX_SEED = 2**64 - 1
"""Largest seed: the counter-based random (:mod:`mien.facs.counter_random`) keys on a uint64."""


def check_seed(seed: object) -> int:
    """``seed`` as an int, or :class:`InvalidValueError` unless it is an integer 0..:data:`MAX_SEED`."""
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or not 0 <= int(seed) <= MAX_SEED:
        raise InvalidValueError("seed", seed, "an integer 0..2**64-1 (the uint64 key of the counter-based random)")
    return int(seed)


def _check_mode(emotion_mode: str) -> str:
    if emotion_mode not in MODES:
        raise InvalidValueError("emotion_mode", emotion_mode, f"one of {', '.join(MODES)}")
    return emotion_mode


def check_basis(expression_basis: str) -> str:
    """``expression_basis``, or :class:`InvalidValueError` unless it is one of :data:`EXPRESSION_BASES`."""
    if expression_basis not in EXPRESSION_BASES:
        raise InvalidValueError("expression_basis", expression_basis, f"one of {', '.join(EXPRESSION_BASES)}")
    return expression_basis


def _mood_vector(mood: Mapping[str, float] | np.ndarray) -> np.ndarray | Any:
    if isinstance(mood, Mapping):
        vector = np.zeros(6)
        for name, value in mood.items():
            for index, weight in blend_components(name):
                vector[index] += weight * check_intensity(value, f"mood[{name}]")
        return vector
    return mood


@dataclass(frozen=True, eq=False)
class _ActiveLaugh:
    start_s: float
    clip: Clip

    @property
    def end_s(self) -> float:
        return self.start_s + self.clip.duration_s

    def sample(self, t_s: float) -> np.ndarray:
        return self.clip.sample(t_s - self.start_s)


def _face_clip(clip: Clip) -> Clip:
    """``clip`` over every FACE_CHANNELS column (channels it lacks are 0)."""
    if not isinstance(clip, Clip):
        raise InvalidValueError("clip", clip, "a mien Clip over face channels")
    if clip.channels == FACE_CHANNELS:
        return clip
    unknown = [name for name in clip.channels if name not in FACE_CHANNELS]
    if unknown:
        raise InvalidValueError("clip channel", unknown[0], "face channels (FACE_CHANNELS: AU12L, head_yaw_deg...)")
    values = np.zeros((clip.n_frames, _N))
    for j, name in enumerate(clip.channels):
        values[:, FACE_CHANNELS.index(name)] = clip.values[:, j]
    return Clip(values, clip.fps, FACE_CHANNELS)


class CharacterBatch:
    """n characters stepped together (one row each): the one implementation of every layer.

    Rows are stable: :meth:`add_character` returns a row index (reusing a freed row first),
    :meth:`remove_character` frees it (a freed row's frame is zeros and costs next to nothing to step).
    ``rows`` arguments are an int, a slice or an int array over active rows; bad rows, names and values
    raise :class:`~mien.errors.InvalidValueError` / :class:`~mien.errors.UnknownNameError` before any
    state changes. Times are seconds and must not decrease; the FACS layer starts at t = 0.

    ``seeds``: (n,) seeds, or an int n for seeds ``0..n-1`` (``CharacterBatch(0)`` is empty). ``idle``,
    ``expression_basis`` and ``emotion_mode`` apply to these first rows; :meth:`add_character` chooses per row.
    A row in ``emotion_mode="categorical"`` refuses :meth:`set_pad`; in ``"pad"`` events still add on top.

    The command methods are those of :class:`Character` with ``rows`` first (a test holds them equal);
    timing arguments are keyword-only.

    >>> batch = CharacterBatch(0)
    >>> a = batch.add_character(seed=1, idle=False)
    >>> b = batch.add_character(seed=2, idle=False)
    >>> batch.set_aus(b, {"AU12": 4.0})
    >>> batch.set_speed(b, 1.0)                   # OpenFACS Speed 1: jump
    >>> batch.step(1 / 60)[:, FACE_CHANNELS.index("AU12L")].tolist()
    [0.0, 4.0]
    """

    def __init__(
        self,
        seeds: np.ndarray | int = 0,
        idle: IdleSettings | bool = True,
        envelope: Envelope | None = None,
        mood_time_constant_s: float = 10.0,
        mood_gain: float = 1.0,
        mood_max_step_s: float = 0.05,
        tick_hz: float = 60.0,
        expression_basis: str = "facs",
        emotion_mode: str = "categorical",
    ) -> None:
        if isinstance(seeds, int | np.integer) and not isinstance(seeds, bool):
            if seeds < 0:
                raise InvalidValueError("seeds", seeds, "a number of characters >= 0 or an array of seeds")
            seeds_array = np.arange(int(seeds))
        else:
            seeds_array = np.atleast_1d(np.asarray(seeds))
        if seeds_array.size and (seeds_array.dtype.kind not in "iu" or seeds_array.min() < 0):
            raise InvalidValueError("seeds", seeds, "integer seeds 0..2**64-1")
        basis = check_basis(expression_basis)
        mode = _check_mode(emotion_mode)
        settings = _idle_settings(idle)
        n = int(seeds_array.shape[0])
        self.tick_hz = float(tick_hz)
        """Nominal rate of OpenFACS ``Speed`` values, Hz."""
        self.facs = FacsBatch(n, tick_hz)
        """The FACS layer."""
        self.emotions = EmotionBatch(n, envelope, mood_time_constant_s, mood_gain, mood_max_step_s=mood_max_step_s)
        """The emotion layer (Broekens)."""
        self.idle = IdleBatch(np.zeros(0, np.int64))
        """The idle layer (rows without idle have every part off)."""
        self.idle.add_rows(seeds_array.astype(np.uint64), settings)
        self.speech = SpeechBatch(n)
        """The speech layer (:meth:`say`); ``speech.viseme_weights`` (n, 15) for heads with viseme shapes."""
        self.seeds = seeds_array.astype(np.uint64)
        """(n,) uint64 seed of each row (idle behaviour and default laughter seed)."""
        self._active = np.ones(n, bool)
        self._features = np.full(n, basis == "feature_points")
        self._pad_mode = np.full(n, mode == "pad")
        self._has_features = bool(self._features.any())
        self._free: list[int] = []
        self._laughs: dict[int, list[_ActiveLaugh]] = {}
        self._performance: dict[int, np.ndarray] = {}  # row -> held (62,) frame of a person's performance
        self._basis = facs_basis()
        self._mood_basis = facs_basis(closed_mouth=True)
        self._fp_basis = feature_point_basis()
        self._fp_mood_basis = feature_point_basis(closed_mouth=True)
        self._frames = np.zeros((n, _N))
        self._expression = np.zeros((n, _N))
        self._mood_expression = np.zeros((n, _N))
        self._fp_mood_expression = np.zeros((n, _N_FEATURES))
        self.feature_weights = np.zeros((n, _N_FEATURES))
        """(n, 54) feature-point target weights (metres) of the last step; zeros for ``"facs"`` rows."""
        self._t_s: float | None = None

    # ------------------------------------------------------------------ rows

    @property
    def n_characters(self) -> int:
        """Number of rows, freed ones included (the first axis of :meth:`step`'s frames)."""
        return int(self.seeds.shape[0])

    @property
    def time_s(self) -> float:
        """Time of the last :meth:`step`, seconds (0 before the first)."""
        return 0.0 if self._t_s is None else self._t_s

    def active_rows(self) -> np.ndarray:
        """(k,) int indices of the rows in use, ascending."""
        return np.flatnonzero(self._active)

    def expression_basis(self, row: int) -> str:
        """``"facs"`` or ``"feature_points"``: how emotions reach ``row``'s face."""
        return "feature_points" if self._features[self._rows(row)[0]] else "facs"

    def emotion_mode(self, row: int) -> str:
        """``"categorical"`` or ``"pad"`` (:meth:`set_pad` allowed): ``row``'s emotion mode."""
        return "pad" if self._pad_mode[self._rows(row)[0]] else "categorical"

    def add_character(
        self,
        seed: int = 0,
        idle: IdleSettings | bool = True,
        expression_basis: str = "facs",
        emotion_mode: str = "categorical",
    ) -> int:
        """Add a neutral character and return its row (a freed row is reused first).

        ``seed`` (int 0..2**64-1) seeds its idle behaviour and laughter; ``idle``: True, False or an
        :class:`IdleSettings`; ``expression_basis``: one of :data:`EXPRESSION_BASES`; ``emotion_mode``:
        ``"categorical"`` or ``"pad"`` (:meth:`set_pad` allowed). Its idle starts now.

        Atomic: every argument is checked before any row changes, so a refused character leaves the batch as
        it was (a half-added row would fail every later :meth:`step`).
        """
        value = check_seed(seed)
        settings = _idle_settings(idle)
        basis = check_basis(expression_basis)
        mode = _check_mode(emotion_mode)
        if isinstance(idle, IdleSettings):
            IdleBatch(np.array([value], np.uint64), settings)  # a dry run on a scratch row: refused settings fail here
        if self._free:
            row = self._free.pop(0)
            self.idle.reset_rows(np.array([row]), np.array([value]), settings, self.time_s)
        else:
            row = self.n_characters
            self.facs.add_rows(1)
            self.emotions.add_rows(1)
            self.idle.add_rows(np.array([value]), settings, self.time_s)
            self.speech.add_rows(1)
            self.seeds = np.concatenate([self.seeds, np.array([value], np.uint64)])
            self._active = np.append(self._active, False)
            self._features = np.append(self._features, False)
            self._pad_mode = np.append(self._pad_mode, False)
            self._frames = np.zeros((row + 1, _N))
            self._expression = np.zeros((row + 1, _N))
            self._mood_expression = np.zeros((row + 1, _N))
            self._fp_mood_expression = np.zeros((row + 1, _N_FEATURES))
            self.feature_weights = np.zeros((row + 1, _N_FEATURES))
        self.seeds[row] = value
        self._active[row] = True
        self._features[row] = basis == "feature_points"
        self._pad_mode[row] = mode == "pad"
        self._has_features = bool(self._features.any())
        return row

    def remove_character(self, row: int) -> None:
        """Free ``row``: its state is dropped, its frame is zeros, and the next :meth:`add_character` reuses it."""
        if isinstance(row, bool) or not isinstance(row, int | np.integer):
            raise InvalidValueError("row", row, "one active row index (int)")
        index = int(self._rows(row)[0])  # checked before any state changes
        rows = np.array([index])
        self.facs.reset_rows(rows)
        self.emotions.reset_rows(rows)
        self.idle.reset_rows(rows, np.array([0]), None, self.time_s)
        self.speech.reset_rows(rows)
        self._laughs.pop(index, None)
        self._performance.pop(index, None)
        self._active[index] = False
        self._features[index] = False
        self._pad_mode[index] = False
        self._has_features = bool(self._features.any())
        self._frames[index] = 0.0
        self.feature_weights[index] = 0.0
        self._free.append(index)
        self._free.sort()

    def _rows(self, rows: RowIndex) -> np.ndarray:
        """``rows`` as an int array of active rows, or :class:`InvalidValueError`."""
        n = self.n_characters
        if type(rows) is int and 0 <= rows < n and self._active[rows]:  # one row (a server's say): no array work
            return np.array([rows], np.intp)
        try:
            if isinstance(rows, slice):
                ids = np.arange(n)[rows]
            else:
                ids = np.atleast_1d(np.asarray(rows))
                if ids.dtype.kind not in "iu" or ids.ndim != 1:
                    raise TypeError
        except (TypeError, ValueError):
            raise InvalidValueError("rows", rows, "an int, a slice or an int array of character rows") from None
        if isinstance(rows, slice):
            return ids[self._active[ids]]  # a slice selects the active rows in it
        if ids.size and (ids.min() < 0 or ids.max() >= n or not self._active[ids].all()):
            raise InvalidValueError("rows", rows, f"active rows (see active_rows(): {self.active_rows().tolist()})")
        return ids.astype(np.intp)

    # ------------------------------------------------------------------ commands

    def set_aus(
        self, rows: RowIndex, intensities: Mapping[str, float], *, speed: float | None = None, replace: bool = False
    ) -> None:
        """Hold several AUs: ``{"AU12": 3.0, "L4": 1.0, ...}``, intensities 0..5.

        ``speed`` is OpenFACS's Speed (see :meth:`set_speed`) of the AUs named (of every AU with ``replace``);
        with ``replace`` (a full-state OpenFACS message) every AU not named goes to 0.
        """
        self.facs.set_many(self._rows(rows), intensities, speed=speed, replace=replace)

    def set_au(
        self, rows: RowIndex, au: str | AUSpec, intensity: float | None = None, *, tau_s: float | None = None
    ) -> None:
        """Hold ``au`` (``"AU12"``, ``"L12C"``...) at ``intensity`` 0..5; ``tau_s`` its time constant (0 jumps)."""
        self.facs.set(self._rows(rows), au, intensity, tau_s=tau_s)

    def set_speed(self, rows: RowIndex, speed: float, au: str | None = None) -> None:
        """OpenFACS Speed (fraction per tick at :attr:`tick_hz`, 0..1) of every AU channel, or of ``au``.

        Converted to a time constant, so the motion is the same at any step rate: each rendered frame of
        OpenFACS moves a morph ``Lerp(current, target, Speed)``; 0.05 at 60 Hz reaches 95% in ~0.97 s.
        """
        self.facs.set_speed(self._rows(rows), speed, au)

    def play_au(
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
        """Play an AU once with an onset/apex/offset envelope (seconds), starting now or at ``start_s``."""
        return self.facs.play(
            self._rows(rows), au, intensity, onset_s=onset_s, apex_s=apex_s, offset_s=offset_s, start_s=start_s
        )

    def emote(
        self,
        rows: RowIndex,
        emotion: str | Blend,
        intensity: float = 1.0,
        *,
        start_s: float | None = None,
        envelope: Envelope | None = None,
    ) -> None:
        """Trigger an emotion or blend event (intensity 0..5, 1 = the prototype) now or at ``start_s``."""
        self.emotions.trigger(
            self._rows(rows), emotion, intensity, self.time_s if start_s is None else start_s, envelope
        )

    def set_pad(
        self, rows: RowIndex, pleasure: float, arousal: float, dominance: float, *, start_s: float | None = None
    ) -> None:
        """Move the PAD state (each factor in [-1, 1]) now or at ``start_s``; the rows' emotion follows it.

        Only rows in ``emotion_mode="pad"`` (:meth:`add_character`, :class:`Character`).
        """
        ids = self._rows(rows)
        if not self._pad_mode[ids].all():
            raise InvalidValueError(
                "emotion_mode", "categorical", "'pad' to use set_pad (Character(emotion_mode='pad'))"
            )
        self.emotions.set_pad(ids, pleasure, arousal, dominance, self.time_s if start_s is None else start_s)

    def set_mood(self, rows: RowIndex, mood: Mapping[str, float] | np.ndarray) -> None:
        """Set the mood: a (6,) vector (EMOTIONS order) or ``{emotion or blend: intensity}``."""
        self.emotions.set_mood(self._rows(rows), _mood_vector(mood))

    def laugh(
        self,
        rows: RowIndex,
        laugh_type: str,
        intensity: float = 1.0,
        *,
        duration_s: float | None = None,
        seed: int | None = None,
        start_s: float | None = None,
    ) -> Clip:
        """Play a laugh or smile (one of the 13 types) on ``rows``; returns the face clip of the first row.

        Each row's laugh is generated with ``seed`` (default: the row's seed). The laugh drives the mouth.
        """
        from mien.laughter.generator import generate

        ids = self._rows(rows)
        if seed is not None:
            check_seed(seed)
        row_seeds = [int(self.seeds[row]) if seed is None else int(seed) for row in ids.tolist()]
        clips: dict[int, Clip] = {}
        for row_seed in row_seeds or [0 if seed is None else int(seed)]:
            if row_seed not in clips:
                result = generate(laugh_type, intensity=intensity, duration_s=duration_s, seed=row_seed)
                clips[row_seed] = _face_clip(result.face_clip)
        for row, row_seed in zip(ids.tolist(), row_seeds, strict=True):
            self._start_clip(row, clips[row_seed], start_s)
        return next(iter(clips.values()))

    def say(
        self, rows: RowIndex, speech: Utterance | str, *, language: str = "en", start_s: float | None = None
    ) -> Utterance:
        """Say ``speech`` on ``rows`` now or from ``start_s``; returns the :class:`~mien.speech.track.Utterance`.

        ``speech`` is an utterance (:mod:`mien.speech`: a timing file, OpenFaceFX track, audio) or text,
        spoken by espeak-ng in ``language`` (its sound is in the returned utterance's ``audio``: play it from
        the same start to stay in sync). It replaces what the rows were saying. See :mod:`mien.speech.arbitration`
        for which channels speech takes.
        """
        ids = self._rows(rows)
        if isinstance(speech, str):
            from mien.speech.espeak import speak

            speech = speak(speech, language)
        self.speech.say(ids, speech, self.time_s if start_s is None else start_s)
        return speech

    def play_clip(self, rows: RowIndex, clip: Clip, *, start_s: float | None = None) -> None:
        """Add a face clip (channels ⊂ FACE_CHANNELS: a laugh, an imported performance) as a layer on ``rows``."""
        ids = self._rows(rows)
        face = _face_clip(clip)
        for row in ids.tolist():
            self._start_clip(row, face, start_s)

    def set_performance(self, rows: RowIndex, frame: np.ndarray | None) -> None:
        """Hold a person's (62,) face frame (FACE_CHANNELS: AUs 0..5, pose degrees) as a layer on ``rows`` until the
        next call; ``None`` removes it. It adds to the FACS layer, so emotions, laughter and idle go on top."""
        ids = self._rows(rows)
        if frame is None:
            for row in ids.tolist():
                self._performance.pop(row, None)
            return
        values = np.array(frame, dtype=np.float64)
        if values.shape != (_N,) or not np.isfinite(values).all():
            raise InvalidValueError("frame", getattr(frame, "shape", frame), f"a finite ({_N},) face frame")
        for row in ids.tolist():
            self._performance[row] = values

    def _start_clip(self, row: int, clip: Clip, start_s: float | None) -> None:
        start = self.time_s if start_s is None else float(start_s)
        if not math.isfinite(start):
            raise InvalidValueError("start_s", start_s, "a finite time in seconds")
        self._laughs.setdefault(row, []).append(_ActiveLaugh(start, clip))

    # ------------------------------------------------------------------ output

    def step(self, t_s: float) -> np.ndarray:
        """(n, 62) face frames at ``t_s`` (>= the previous time); the array is reused by the next step.

        Freed rows are zeros. With a ``"feature_points"`` row, :attr:`feature_weights` holds its (54,)
        feature weights for this step.
        """
        try:
            t = float(t_s)
        except (TypeError, ValueError):
            raise InvalidValueError("t_s", t_s, "a time in seconds") from None
        if not math.isfinite(t) or not t >= self.time_s:
            raise InvalidValueError("t_s", t_s, f"a finite time >= the previous time {self.time_s}")
        frames = self._frames
        frames[:] = self.facs.advance(t)
        self._t_s = t
        for row, performance in self._performance.items():
            frames[row] += performance
        emotions = self.emotions
        emotions.advance(t)
        if not emotions.resting:
            emotion, shown = emotions.expressed(t)
            expression = matmul_rows(emotion, self._basis, self._expression)
            expression += matmul_rows(shown, self._mood_basis, self._mood_expression)
            if self._has_features:
                features = self._features
                matmul_rows(emotion, self._fp_basis, self.feature_weights)
                self.feature_weights += matmul_rows(shown, self._fp_mood_basis, self._fp_mood_expression)
                self.feature_weights[~features] = 0.0
                expression[features] = 0.0
            frames += saturate(expression)
        elif self._has_features:
            self.feature_weights[:] = 0.0
        quiet = self.speech.apply(t, frames, self._laughs)  # before the laughs, which add on top
        laughing = None
        if self._laughs:
            laughing = np.zeros(self.n_characters, bool)
            for row, laughs in list(self._laughs.items()):
                for laugh in laughs:
                    if laugh.start_s <= t < laugh.end_s:
                        frames[row] += laugh.sample(t)
                        laughing[row] = True
                alive = [laugh for laugh in laughs if t < laugh.end_s]
                if alive:
                    self._laughs[row] = alive
                else:
                    del self._laughs[row]
        # idle mouth motion yields to a laughing mouth, and in proportion to other mouth activity
        idle = self.idle
        if frames.shape[0] == 1:  # a batch of one: the idle layer's one-row path, on Python floats
            if idle.moving:
                values = frames[0].tolist()
                mouth = max(0.0, 1.0 - max(0.0, *_MOUTH_OF(values)) / 2.0)
                if quiet is not None:
                    mouth *= float(quiet[0])
                idle.apply_row(t, values, 0.0 if laughing is not None and laughing[0] else mouth)
                frames[0, IDLE_COLUMNS] = _IDLE_VALUES(values)  # the rest of the row is unchanged
        else:
            mouth_scale = np.maximum(0.0, 1.0 - frames[:, _MOUTH].max(axis=1, initial=0.0) / 2.0)
            if laughing is not None:
                mouth_scale[laughing] = 0.0
            if quiet is not None:
                mouth_scale *= quiet
            idle.apply(t, frames, mouth_scale)
        aus = frames[:, :_N_AU]
        np.maximum(aus, 0.0, out=aus)
        np.minimum(aus, 5.0, out=aus)
        if self._free:
            frames[self._free] = 0.0
        return frames

    def snapshot(self, row: int) -> dict[str, Any]:
        """A plain dict of ``row``'s last frame (channel -> value), for servers and logs."""
        index = int(self._rows(row)[0]) if isinstance(row, int | np.integer) else None
        if index is None:
            raise InvalidValueError("row", row, "one active row index (int)")
        return dict(zip(FACE_CHANNELS, self._frames[index].tolist(), strict=True))


class Character:
    """One animated face: a :class:`CharacterBatch` of one row. Give it commands, then :meth:`step`.

    Its commands are the batch's without ``rows`` (same names, order, defaults and keyword-only timing
    arguments: ``tests/character/test_batch.py`` fails when they drift), and each is one call to the batch.

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
        self.seed = check_seed(seed)
        """Seed of the idle behaviour (and default seed of laughter)."""
        self.expression_basis = check_basis(expression_basis)
        """``"facs"`` or ``"feature_points"``."""
        self.emotion_mode = _check_mode(emotion_mode)
        """``"categorical"`` or ``"pad"`` (:meth:`set_pad` only in ``"pad"``)."""
        self.batch = CharacterBatch(
            np.array([self.seed]),
            idle,
            envelope,
            mood_time_constant_s,
            mood_gain,
            tick_hz=tick_hz,
            expression_basis=expression_basis,
            emotion_mode=emotion_mode,
        )
        """The one-row batch that does the work."""
        self.last_feature_weights: np.ndarray | None = None
        """(n_frames, 54) feature weights of the last :meth:`run` (``"feature_points"`` basis only)."""
        self.last_viseme_weights: np.ndarray | None = None
        """(n_frames, 15) the speech layer's viseme weights of the last :meth:`run` (None if it said nothing):
        ``face_to_rig(rig, clip, visemes=...)`` shows them through a head's own viseme shapes."""

    @property
    def time_s(self) -> float:
        """Time of the last :meth:`step`, seconds."""
        return self.batch.time_s

    @property
    def feature_weights(self) -> np.ndarray:
        """(54,) feature-point target weights (metres) of the last step (``"feature_points"`` basis only)."""
        return self.batch.feature_weights[0]

    # ------------------------------------------------------------------ commands (see CharacterBatch)

    def set_aus(self, intensities: Mapping[str, float], *, speed: float | None = None, replace: bool = False) -> None:
        """Hold several AUs; ``speed`` is OpenFACS's per-tick Speed; ``replace`` zeroes the AUs not named."""
        self.batch.set_aus(0, intensities, speed=speed, replace=replace)

    def set_au(self, au: str | AUSpec, intensity: float | None = None, *, tau_s: float | None = None) -> None:
        """Hold an AU (``"AU12"``, ``"L12C"``...) at ``intensity`` 0..5; ``tau_s`` its time constant."""
        self.batch.set_au(0, au, intensity, tau_s=tau_s)

    def set_speed(self, speed: float, au: str | None = None) -> None:
        """OpenFACS Speed (per tick at the nominal rate) of every AU channel, or of ``au``."""
        self.batch.set_speed(0, speed, au)

    def play_au(
        self,
        au: str | AUSpec,
        intensity: float | None = None,
        *,
        onset_s: float = 0.4,
        apex_s: float = 0.3,
        offset_s: float = 0.3,
        start_s: float | None = None,
    ) -> TimedAction:
        """Play an AU once with an onset/apex/offset envelope, starting now or at ``start_s``."""
        return self.batch.play_au(0, au, intensity, onset_s=onset_s, apex_s=apex_s, offset_s=offset_s, start_s=start_s)

    def emote(
        self,
        emotion: str | Blend,
        intensity: float = 1.0,
        *,
        start_s: float | None = None,
        envelope: Envelope | None = None,
    ) -> None:
        """Trigger an emotion or blend event (intensity 0..5, 1 = the prototype) now or at ``start_s``."""
        self.batch.emote(0, emotion, intensity, start_s=start_s, envelope=envelope)

    def set_pad(self, pleasure: float, arousal: float, dominance: float, *, start_s: float | None = None) -> None:
        """Move the PAD state (each in [-1, 1]; needs ``emotion_mode="pad"``) now or at ``start_s``."""
        self.batch.set_pad(0, pleasure, arousal, dominance, start_s=start_s)

    def set_mood(self, mood: Mapping[str, float] | np.ndarray) -> None:
        """Set the mood: a (6,) vector or ``{emotion: intensity}``."""
        self.batch.set_mood(0, mood)

    def laugh(
        self,
        laugh_type: str,
        intensity: float = 1.0,
        *,
        duration_s: float | None = None,
        seed: int | None = None,
        start_s: float | None = None,
    ) -> Clip:
        """Play a laugh or smile (one of the 13 types); returns its face clip. The laugh drives the mouth."""
        return self.batch.laugh(0, laugh_type, intensity, duration_s=duration_s, seed=seed, start_s=start_s)

    def say(self, speech: Utterance | str, *, language: str = "en", start_s: float | None = None) -> Utterance:
        """Say an utterance or text (espeak-ng in ``language``) now or from ``start_s``; returns the utterance
        (its ``audio`` is the sound to play from the same start)."""
        return self.batch.say(0, speech, language=language, start_s=start_s)

    def play_clip(self, clip: Clip, *, start_s: float | None = None) -> None:
        """Add a face clip (channels ⊂ FACE_CHANNELS, e.g. a laugh or an imported performance) as a layer."""
        self.batch.play_clip(0, clip, start_s=start_s)

    def set_performance(self, frame: np.ndarray | None) -> None:
        """Hold a person's (62,) face frame as a layer under the others until the next call (``None``: remove it)."""
        self.batch.set_performance(0, frame)

    # ------------------------------------------------------------------ output

    def step(self, t_s: float) -> np.ndarray:
        """The (62,) face frame at ``t_s`` (>= the previous time). The array is reused by the next step."""
        return self.batch.step(t_s)[0]

    def run(self, duration_s: float, fps: float = 60.0) -> Clip:
        """Step from the current time for ``duration_s`` at ``fps`` and return the frames as a :class:`Clip`.

        The first frame is the current time (for a new character, t = 0).
        """
        if not (math.isfinite(duration_s) and duration_s > 0):
            raise InvalidValueError("duration_s", duration_s, "a positive number of seconds")
        if not (math.isfinite(fps) and fps > 0):
            raise InvalidValueError("fps", fps, "a positive frame rate")
        n_frames = max(1, round(duration_s * fps))
        start = self.time_s
        values = np.empty((n_frames, _N))
        features = np.empty((n_frames, _N_FEATURES)) if self.expression_basis != "facs" else None
        speech = self.batch.speech
        visemes = np.zeros((n_frames, speech.viseme_weights.shape[1])) if speech.utterance(0) else None
        for i in range(n_frames):
            values[i] = self.step(start + i / fps)
            if features is not None:
                features[i] = self.feature_weights
            if visemes is not None:
                visemes[i] = speech.viseme_weights[0]
        self.last_feature_weights = features
        self.last_viseme_weights = visemes
        return Clip(values, fps, FACE_CHANNELS)

    def snapshot(self) -> dict[str, Any]:
        """A plain dict of the current frame (channel -> value), for servers and logs."""
        return self.batch.snapshot(0)
