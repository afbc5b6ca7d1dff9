"""The speech layer of the character engine: n rows, each saying at most one utterance, stepped in one pass.

:class:`SpeechBatch` is what :class:`mien.character.CharacterBatch` holds as ``speech``. Each utterance is
compiled once (:func:`speech_frames`) into rows of a shared pool; a step gathers every speaking row's two
neighbouring frames from the pool and interpolates them with a few vectorised numpy operations, whatever the
number of rows, then applies :func:`~mien.speech.arbitration.arbitrate`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from mien.errors import InvalidValueError
from mien.speech.arbitration import LAUGH_FADE_S, SPEECH_CHANNELS, arbitrate
from mien.speech.track import Utterance
from mien.speech.visemes import VISEMES, viseme_aus

__all__ = ["EDGE_FADE_S", "SpeechBatch", "speech_frames"]

EDGE_FADE_S = 0.05
"""Seconds over which an utterance's hold on the mouth rises at its start and falls at its end (no jump)."""

_K = len(SPEECH_CHANNELS)
_N_VISEMES = len(VISEMES)
_COLUMNS = _K + 1 + _N_VISEMES


def speech_frames(utterance: Utterance) -> np.ndarray:
    """(n_frames, k + 1 + 15) the utterance compiled for the engine at its track's fps.

    Columns: the speech values on :data:`~mien.speech.arbitration.SPEECH_CHANNELS` (viseme weights @ shapes),
    the presence (1 - weight of ``sil``), the 15 viseme weights with ``sil`` excluded (zeros at rest). The
    first and last :data:`EDGE_FADE_S` fade in and out.
    """
    track = utterance.track
    weights = np.array(track.weights)
    weights[:, VISEMES.index("sil")] = 0.0
    n = track.n_frames
    ramp_frames = max(1.0, EDGE_FADE_S * track.fps)
    index = np.arange(n, dtype=np.float64)
    taper = np.clip(np.minimum(index, n - 1 - index) / ramp_frames, 0.0, 1.0)
    weights *= taper[:, None]
    out = np.empty((n, _COLUMNS))
    out[:, :_K] = weights @ viseme_aus()[:, SPEECH_CHANNELS]
    out[:, _K] = weights.sum(axis=1)
    out[:, _K + 1 :] = weights
    return out


class SpeechBatch:
    """The speech state of n character rows (see the module docstring)."""

    def __init__(self, n: int) -> None:
        self.fps = np.zeros(n)
        self._start = np.zeros(n)
        self._offset = np.zeros(n, np.int64)
        self._last = np.zeros(n, np.int64)
        self._utterances: dict[int, Utterance] = {}
        self._spans: dict[int, tuple[int, int]] = {}
        self._pool = np.zeros((0, _COLUMNS))
        self._used = 0
        self._speaking = np.zeros(0, np.intp)
        self.presence = np.zeros(n)
        """(n,) how much speech held each row's mouth at the last step, 0..1 (0: silent)."""
        self.viseme_weights = np.zeros((n, _N_VISEMES))
        """(n, 15) viseme weights of the last step (``sil`` column 0; zeros where a row is silent): for heads
        with their own viseme shapes (:func:`~mien.speech.visemes.rig_viseme_targets`)."""

    # ------------------------------------------------------------------ rows

    def add_rows(self, k: int) -> None:
        """Append ``k`` silent rows."""
        self.fps = np.concatenate([self.fps, np.zeros(k)])
        self._start = np.concatenate([self._start, np.zeros(k)])
        self._offset = np.concatenate([self._offset, np.zeros(k, np.int64)])
        self._last = np.concatenate([self._last, np.zeros(k, np.int64)])
        self.presence = np.concatenate([self.presence, np.zeros(k)])
        self.viseme_weights = np.concatenate([self.viseme_weights, np.zeros((k, _N_VISEMES))])

    def reset_rows(self, rows: np.ndarray) -> None:
        """Silence ``rows`` (their utterances are dropped)."""
        for row in np.asarray(rows).tolist():
            self._utterances.pop(row, None)
            self._spans.pop(row, None)
        self.presence[rows] = 0.0
        self.viseme_weights[rows] = 0.0
        self._speaking = np.array(sorted(self._spans), np.intp)

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
        frames = speech_frames(utterance)
        offset = self._store(frames)
        for row in np.asarray(rows).tolist():
            self._utterances[row] = utterance
            self._spans[row] = (offset, frames.shape[0])
            self._start[row] = start
            self._offset[row] = offset
            self._last[row] = frames.shape[0] - 1
            self.fps[row] = utterance.track.fps
        self._speaking = np.array(sorted(self._spans), np.intp)

    def _store(self, frames: np.ndarray) -> int:
        """Copy ``frames`` into the pool and return their first row (compacting or growing the pool)."""
        need = frames.shape[0]
        if self._used + need > self._pool.shape[0]:
            live = {span for span in self._spans.values()}
            size = sum(length for _, length in live) + need
            pool = np.zeros((max(2 * size, 1024), _COLUMNS))
            moved: dict[tuple[int, int], int] = {}
            used = 0
            for offset, length in sorted(live):
                pool[used : used + length] = self._pool[offset : offset + length]
                moved[(offset, length)] = used
                used += length
            for row, (offset, length) in list(self._spans.items()):
                self._spans[row] = (moved[(offset, length)], length)
                self._offset[row] = moved[(offset, length)]
            self._pool, self._used = pool, used
        offset = self._used
        self._pool[offset : offset + need] = frames
        self._used += need
        return offset

    # ------------------------------------------------------------------ step

    def apply(
        self, t_s: float, frames: np.ndarray, laughs: Mapping[int, Sequence[Any]] | None = None
    ) -> np.ndarray | None:
        """Blend the speaking rows' speech into ``frames`` (n, 62) at ``t_s``, in place.

        ``laughs``: row -> active laughs (objects with ``start_s`` and ``end_s``): speech fades out over
        :data:`~mien.speech.arbitration.LAUGH_FADE_S` around each. Returns :attr:`presence` (for the idle
        layer to yield), or None when no row is speaking. Finished utterances are dropped.
        """
        rows = self._speaking
        if rows.size == 0:
            return None
        position = (t_s - self._start[rows]) * self.fps[rows]
        last = self._last[rows]
        live = (position >= 0.0) & (position <= last)
        clipped = np.clip(position, 0.0, last)
        low = np.floor(clipped).astype(np.int64)
        high = np.minimum(low + 1, last)
        fraction = (clipped - low)[:, None]
        pool = self._pool
        base = self._offset[rows]
        before = pool[base + low]
        values = before + fraction * (pool[base + high] - before)
        values[~live] = 0.0
        if laughs:
            for i, row in enumerate(rows.tolist()):
                if row in laughs:
                    cover = max(_cover(t_s, laugh.start_s, laugh.end_s) for laugh in laughs[row])
                    values[i] *= 1.0 - cover
        presence = values[:, _K]
        block = np.ix_(rows, SPEECH_CHANNELS)
        frames[block] = arbitrate(frames[block], values[:, :_K], presence)
        self.presence[rows] = presence
        self.viseme_weights[rows] = values[:, _K + 1 :]
        if (position > last).any():
            self.reset_rows(rows[position > last])
        return self.presence


def _cover(t_s: float, start_s: float, end_s: float) -> float:
    """How much a laugh over [start_s, end_s) covers speech at t_s: 0..1 with :data:`LAUGH_FADE_S` ramps."""
    return max(0.0, min(1.0, (t_s - start_s) / LAUGH_FADE_S + 1.0, (end_s - t_s) / LAUGH_FADE_S))
