"""The speech layer of the character engine: n rows, each saying at most one utterance, stepped in one pass.

:class:`SpeechBatch` is what :class:`mien.character.CharacterBatch` holds as ``speech``. Each utterance is
compiled once (:func:`speech_frames`, at :data:`ENGINE_FPS`) into rows of a shared pool; a step gathers every
speaking row's nearest frame from the pool and applies the rule of :func:`~mien.speech.arbitration.arbitrate` in
place, with a handful of vectorised numpy operations whatever the number of rows.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from mien.errors import InvalidValueError
from mien.facs.clip import interpolate_frames
from mien.speech.arbitration import LAUGH_FADE_S, SPAN, SPEECH_CHANNELS, keep_fraction
from mien.speech.track import Utterance
from mien.speech.visemes import VISEMES, viseme_aus

__all__ = ["EDGE_FADE_S", "ENGINE_FPS", "SpeechBatch", "speech_frames"]

EDGE_FADE_S = 0.05
"""Seconds over which an utterance's hold on the mouth rises at its start and falls at its end (no jump)."""

ENGINE_FPS = 200.0
"""Rate (Hz) an utterance is compiled at for the engine, which takes the nearest frame at each step (within
2.5 ms of the step's time: no interpolation, so a step is one gather and two in-place operations)."""

_W = SPAN.stop - SPAN.start
_N_VISEMES = len(VISEMES)
_STEP_COLUMNS = 2 * _W + 1
"""What a step reads: speech values and keep fractions over SPAN, and the presence."""
_COLUMNS = _STEP_COLUMNS + _N_VISEMES
_POOL_COLUMNS = -(-_STEP_COLUMNS // 16) * 16
"""A pool row: the speech values and keep fractions over SPAN and the quiet (1 - presence), float32, padded to
a whole number of 64-byte cache lines."""
_SILENT = np.zeros(_POOL_COLUMNS, np.float32)
_SILENT[_W : 2 * _W + 1] = 1.0
"""A pool row of silence: nothing added, everything kept, quiet."""
"""A pool row: the step columns, their slope to the next frame, the viseme weights."""
_N_FACE = viseme_aus().shape[1]
_IN_SPAN = SPEECH_CHANNELS - SPAN.start
_SHAPES = np.ascontiguousarray(viseme_aus()[:, SPEECH_CHANNELS])
"""(15, k) the visemes' shapes on the speech channels (C order: the product is 10x faster)."""
_QUIET = 2 * _W
"""The step column of ``1 - presence`` (how much the idle mouth may move)."""
_COMPILED: weakref.WeakKeyDictionary[Utterance, np.ndarray] = weakref.WeakKeyDictionary()
"""Each utterance compiled once (a server says the same utterance to many rows, or again and again)."""


def speech_frames(utterance: Utterance) -> np.ndarray:
    """(n_frames, 2 w + 1 + 15) the utterance compiled for the engine at :data:`ENGINE_FPS` (w: the columns of
    :data:`~mien.speech.arbitration.SPAN`), its track linearly resampled.

    Columns: the speech values over SPAN (viseme weights @ shapes; 0 where speech writes nothing), the
    fraction each column keeps of the other layers (:func:`~mien.speech.arbitration.keep_fraction`),
    ``1 - presence`` (the weight of ``sil``: how much the idle mouth may move), the 15 viseme weights with
    ``sil`` excluded (zeros at rest). The first and last :data:`EDGE_FADE_S` fade in and out.
    """
    track = utterance.track
    n = max(1, math.floor((track.n_frames - 1) / track.fps * ENGINE_FPS + 1e-9) + 1)
    weights = interpolate_frames(track.weights, track.fps, np.arange(n) / ENGINE_FPS)
    weights[:, VISEMES.index("sil")] = 0.0
    ramp_frames = max(1.0, EDGE_FADE_S * ENGINE_FPS)
    index = np.arange(n, dtype=np.float64)
    taper = np.clip(np.minimum(index, n - 1 - index) / ramp_frames, 0.0, 1.0)
    weights *= taper[:, None]
    presence = weights.sum(axis=1)
    out = np.zeros((n, _COLUMNS))
    out[:, _IN_SPAN] = weights @ _SHAPES
    out[:, _W : 2 * _W] = keep_fraction(presence)
    out[:, _QUIET] = 1.0 - presence
    out[:, _STEP_COLUMNS:] = weights
    return out


class SpeechBatch:
    """The speech state of n character rows (see the module docstring).

    Each utterance is compiled once (:func:`speech_frames`, cached per utterance, shared by every row that says
    it) into a pool: one float32 row per frame at :data:`ENGINE_FPS` (the speech values and keep fractions over
    :data:`~mien.speech.arbitration.SPAN` and the quiet), and a parallel pool of viseme weights read only
    when :attr:`viseme_weights` is. An utterance's first and last frames are silence, so a row before its start
    or after its end only clamps. Pool row 0 is silence: when half the rows or more speak, every row takes part
    in the pass (the silent ones read row 0) and the rule is applied in place on ``frames[:, SPAN]``.
    """

    def __init__(self, n: int) -> None:
        self.fps = np.zeros(n)
        """(n,) frame rate of each row's utterance track (0: silent)."""
        self._start = np.zeros(n)
        self._offset = np.zeros(n, np.int64)
        self._last = np.zeros(n, np.int64)
        self._utterances: dict[int, Utterance] = {}
        self._spans: dict[int, tuple[int, int]] = {}
        self._stored: dict[Utterance, tuple[int, int]] = {}
        self._pool, self._pool_visemes = _empty_pools(1024)
        self._used = 1
        self._quiet = np.ones(n)
        self._live_from = np.full(n, -math.inf)
        self._live_to = np.full(n, math.inf)
        self._visemes = np.zeros((n, _N_VISEMES))
        self._last_step: tuple[np.ndarray, np.ndarray, list[tuple[int, float]]] | None = None
        self._visemes_read = False
        self._every_row = False
        self._rows = np.zeros(0, np.intp)
        self._position_of: dict[int, int] | None = {}
        self._rows_fps = self._rows_shift = np.zeros(0)
        self._rows_low = self._rows_high = np.zeros(0, np.int64)
        self._all_live = (0.0, -1.0)
        self._buffers = _step_buffers(0)
        self._block: tuple[np.ndarray | None, np.ndarray] = (None, np.zeros((0, _W)))
        self._refresh()

    @property
    def presence(self) -> np.ndarray:
        """(n,) how much speech held each row's mouth at the last step, 0..1 (0: silent)."""
        return np.asarray(1.0 - self._quiet, dtype=np.float64)

    @property
    def viseme_weights(self) -> np.ndarray:
        """(n, 15) viseme weights of the last step (``sil`` column 0; zeros where a row is silent): for heads
        with their own viseme shapes (:func:`~mien.speech.visemes.rig_viseme_targets`, driven by
        :meth:`mien.rig.driver.RigDriver.weights`); a laugh fades them as it fades the AU shapes. Built when read."""
        self._visemes_read = True
        if self._last_step is not None:
            rows, index, holds = self._last_step
            self._last_step = None
            weights = self._pool_visemes[index]  # the first and last frames of an utterance are silence
            for i, hold in holds:
                weights[i] *= hold
            self._visemes[:] = 0.0
            self._visemes[rows] = weights
        return self._visemes

    def _settle(self) -> None:
        """Fix the last step's viseme weights before rows or the pool change (only once someone reads them)."""
        if self._visemes_read:
            _ = self.viseme_weights
        self._last_step = None

    # ------------------------------------------------------------------ rows

    def add_rows(self, k: int) -> None:
        """Append ``k`` silent rows."""
        self._settle()
        self.fps = np.concatenate([self.fps, np.zeros(k)])
        self._start = np.concatenate([self._start, np.zeros(k)])
        self._offset = np.concatenate([self._offset, np.zeros(k, np.int64)])
        self._last = np.concatenate([self._last, np.zeros(k, np.int64)])
        self._quiet = np.concatenate([self._quiet, np.ones(k)])
        self._live_from = np.concatenate([self._live_from, np.full(k, -math.inf)])
        self._live_to = np.concatenate([self._live_to, np.full(k, math.inf)])
        self._visemes = np.concatenate([self._visemes, np.zeros((k, _N_VISEMES))])
        self._refresh()

    def reset_rows(self, rows: np.ndarray) -> None:
        """Silence ``rows`` (their utterances are dropped)."""
        self._settle()
        changed = np.asarray(rows).ravel().tolist()
        for row in changed:
            self._utterances.pop(row, None)
            self._spans.pop(row, None)
            self.fps[row] = self._start[row] = 0.0
            self._offset[row] = self._last[row] = 0  # a silent row reads pool row 0
            self._live_from[row], self._live_to[row] = -math.inf, math.inf
            self._visemes[row] = 0.0
            self._quiet[row] = 1.0
        self._refresh(changed)

    def utterance(self, row: int) -> Utterance | None:
        """The utterance ``row`` is saying (or will say), if any."""
        return self._utterances.get(int(row))

    def say(self, rows: np.ndarray, utterance: Utterance, start_s: float) -> None:
        """``rows`` say ``utterance`` from ``start_s`` (seconds); it replaces what they were saying."""
        if not isinstance(utterance, Utterance):
            raise InvalidValueError("utterance", utterance, "a mien.speech Utterance (or text to speak)")
        start = float(start_s)
        if not math.isfinite(start):
            raise InvalidValueError("start_s", start_s, "a finite time in seconds")
        self._settle()  # the pool may move
        stored = self._stored.get(utterance)
        # an utterance already in the pool is shared (compaction keeps _stored to the spans it keeps)
        if stored is None:
            frames = _COMPILED.get(utterance)
            if frames is None:
                frames = _COMPILED[utterance] = speech_frames(utterance)
            stored = self._stored[utterance] = (self._store(frames), frames.shape[0])
        offset, last = stored[0], stored[1] - 1
        changed = np.asarray(rows).ravel().tolist()
        end = start + last / ENGINE_FPS
        for row in changed:
            self._utterances[row] = utterance
            self._spans[row] = (offset, last + 1)
            self._start[row] = start
            self._offset[row] = offset
            self._last[row] = last
            self.fps[row] = ENGINE_FPS
            self._live_from[row], self._live_to[row] = start, end
        self._refresh(changed, (start, end), (ENGINE_FPS, offset, last, start))

    def _store(self, frames: np.ndarray) -> int:
        """Copy ``frames`` into the pools and return their first row (compacting or growing the pools)."""
        need = frames.shape[0]
        if self._used + need > self._pool.shape[0]:
            live = set(self._spans.values())
            size = 1 + sum(length for _, length in live) + need
            pool, visemes = _empty_pools(max(2 * size, 1024))
            moved: dict[tuple[int, int], int] = {}
            used = 1
            for offset, length in sorted(live):
                pool[used : used + length] = self._pool[offset : offset + length]
                visemes[used : used + length] = self._pool_visemes[offset : offset + length]
                moved[(offset, length)] = used
                used += length
            for row, (offset, length) in list(self._spans.items()):
                self._spans[row] = (moved[(offset, length)], length)
                self._offset[row] = moved[(offset, length)]
            self._stored = {u: (moved[span], span[1]) for u, span in self._stored.items() if span in moved}
            self._pool, self._pool_visemes, self._used = pool, visemes, used
            self._rows = np.zeros(0, np.intp)  # offsets moved: the next _refresh rebuilds every cache
        offset = self._used
        self._pool[offset : offset + need, :_STEP_COLUMNS] = frames[:, :_STEP_COLUMNS]
        self._pool_visemes[offset : offset + need] = frames[:, _STEP_COLUMNS:]
        self._used += need
        return offset

    def _refresh(
        self,
        changed: list[int] | None = None,
        live: tuple[float, float] | None = None,
        given: tuple[float, int, int, float] = (0.0, 0, 0, 0.0),
    ) -> None:
        """Cache the taking-part rows' arrays (in row order) for :meth:`apply`; only the ``changed`` rows when
        every row already takes part and still does (one say or one finished utterance costs O(1)). ``live``: the
        (start, end) the ``changed`` rows have just been given (a say), which narrows the all-live window;
        ``given``: the (fps, offset, last, start) they were given (silence by default)."""
        n = self._quiet.shape[0]
        every_row = 0 < 2 * len(self._spans) and 2 * len(self._spans) >= n
        if changed is not None and every_row and self._every_row and self._rows.size == n:
            fps, offset, last, start = given
            for row in changed:  # row i is row i: a few scalar writes
                self._rows_fps[row], self._rows_low[row], self._rows_high[row] = fps, offset, offset + last
                self._rows_shift[row] = start * fps - offset - 0.5
            if live is not None and self._all_live[0] <= self._all_live[1]:
                # a say only narrows the window (what the rows said before can only have widened it: keeping
                # it is safe, as a row outside the window is merely clamped and checked for its end)
                self._all_live = (max(self._all_live[0], live[0]), min(self._all_live[1], live[1]))
                return
        else:
            self._every_row = every_row
            # with half the rows or more speaking, every row takes part (a silent one reads pool row 0):
            # frames[:, SPAN] is then a view, updated in place, with no gather and scatter of rows
            rows = np.arange(n) if every_row else np.array(sorted(self._spans), np.intp)
            self._rows = rows
            self._position_of = None if every_row else {row: i for i, row in enumerate(rows.tolist())}
            self._rows_fps = self.fps[rows]
            self._rows_low = self._offset[rows]  # an utterance's first and last pool rows
            self._rows_high = self._rows_low + self._last[rows]
            # nearest pool row at t: floor(t * fps - (start * fps - offset - 0.5)), one multiply and one subtract
            self._rows_shift = self._start[rows] * self._rows_fps - self._rows_low - 0.5
        self._window()

    def _window(self) -> None:
        """Every speaking row has started and none has ended between these times (silent rows: -inf, +inf)."""
        self._all_live = (float(self._live_from.max()), float(self._live_to.min())) if self._spans else (0.0, -1.0)

    def _position(self, row: int) -> int | None:
        """Index of a speaking ``row`` among the rows taking part in a step (None if it is silent)."""
        if self.fps[row] <= 0:
            return None
        return row if self._position_of is None else self._position_of.get(row)

    # ------------------------------------------------------------------ step

    def apply(
        self, t_s: float, frames: np.ndarray, laughs: Mapping[int, Sequence[Any]] | None = None
    ) -> np.ndarray | None:
        """Blend the speaking rows' speech into ``frames`` (n, 62) at ``t_s``, in place.

        The rule is :func:`~mien.speech.arbitration.arbitrate`'s, compiled: ``face * keep + speech`` over
        :data:`~mien.speech.arbitration.SPAN`, both read from the utterance's frames and interpolated.
        ``laughs``: row -> active laughs (objects with ``start_s`` and ``end_s``): speech fades out over
        :data:`~mien.speech.arbitration.LAUGH_FADE_S` around each. Returns (n,) ``1 - presence`` per row (how
        much the idle mouth may move), or None when no row is speaking. Finished utterances are dropped.
        """
        rows = self._rows
        if not self._spans:
            return None
        buffers = self._buffers
        if buffers[0].shape[0] != rows.size:  # gathered into buffers kept between steps, with their views
            buffers = self._buffers = _step_buffers(rows.size)
        position, index, values, keep, speech, quiet = buffers
        np.multiply(t_s, self._rows_fps, out=position)
        # pool row + 0.5, truncated: the nearest row (floor where it is >= 0; a row before its start is clamped below)
        np.subtract(position, self._rows_shift, out=index, casting="unsafe")
        if not self._all_live[0] <= t_s <= self._all_live[1]:
            # some row has not started or has ended: it reads its first or last frame, which are silence (the
            # edge fade ends at 0), so clamping is all it takes (on whole rows: the same as before truncating)
            np.minimum(np.maximum(index, self._rows_low, out=index), self._rows_high, out=index)
        self._pool.take(index, axis=0, out=values, mode="wrap")  # = self._pool[index] (every index is in range)
        holds: list[tuple[int, float]] = []
        if laughs:
            for row, active in laughs.items():
                i = self._position(row)
                if i is None:
                    continue
                hold = 1.0 - max(_cover(t_s, laugh.start_s, laugh.end_s) for laugh in active)
                if hold < 1.0:
                    holds.append((i, hold))
                    # every column is affine in the presence and equals _SILENT at 0: scaling the presence by
                    # hold is _SILENT + hold * (values - _SILENT), for the speech, the keep and the quiet alike
                    if hold <= 0.0:  # inside the laugh: silence (what the three operations below give at 0)
                        values[i] = _SILENT
                        continue
                    held = values[i]
                    held -= _SILENT
                    held *= hold
                    held += _SILENT
        # the rule, compiled: face * keep + speech over SPAN (arbitrate's, in place)
        if self._every_row and frames.shape[0] == rows.size:
            if frames is not self._block[0]:  # the engine reuses its frames: so does the view
                self._block = (frames, frames[:, SPAN])
            block = self._block[1]  # a view: the rule applied in place
            block *= keep
            block += speech
            self._quiet = quiet
        else:
            block = frames[rows, SPAN]
            block *= keep
            block += speech
            frames[rows, SPAN] = block
            self._quiet[rows] = quiet
        self._last_step = (rows, index, holds)
        if t_s > self._all_live[1]:  # some utterance has ended: drop it
            finished = np.flatnonzero(self._live_to < t_s)
            if finished.size:
                self.reset_rows(finished)
            else:  # the window was narrower than the rows' (a say replaced an utterance): widen it
                self._window()
        return self._quiet


def _step_buffers(n_rows: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """What a step of ``n_rows`` rows writes: positions, pool rows, the gathered pool rows, and the latter's
    speech values, keep fractions and quiet (views)."""
    values = np.empty((n_rows, _POOL_COLUMNS), np.float32)
    return (
        np.empty(n_rows),
        np.empty(n_rows, np.int64),
        values,
        values[:, _W : 2 * _W],
        values[:, :_W],
        values[:, _QUIET],
    )


def _empty_pools(n_rows: int) -> tuple[np.ndarray, np.ndarray]:
    """Pools of ``n_rows`` rows (step columns, float32; viseme weights) whose row 0 is silence."""
    pool = np.zeros((n_rows, _POOL_COLUMNS), np.float32)
    pool[0] = _SILENT
    return pool, np.zeros((n_rows, _N_VISEMES))


def _cover(t_s: float, start_s: float, end_s: float) -> float:
    """How much a laugh over [start_s, end_s) covers speech at t_s: 0..1 with :data:`LAUGH_FADE_S` ramps."""
    return max(0.0, min(1.0, (t_s - start_s) / LAUGH_FADE_S + 1.0, (end_s - t_s) / LAUGH_FADE_S))
