"""AU intensities from blendshape scores: the AU -> ARKit mapping solved in reverse.

The mapping (:class:`mien.rig.mapping.AUMapping`) says how much each AU channel drives each blendshape per
unit of intensity: ``weights = clip(aus @ M, 0, 1)``. Given detected scores ``b`` (52,), the AU estimate is
the non-negative least-squares solution of ``aus @ M = b`` over a chosen set of AU channels (those of
:data:`SOLVED_AUS`), capped at E (5). Left/right channels of one AU are solved separately and reported as
their mean, so results come back as FACS intensities per AU, 0..5; where both sides drive the same targets
alike (AU1's one ``browInnerUp``) they are one column, since no detector output can tell them apart.

>>> import numpy as np
>>> from mien.rig.mapping import AUMapping
>>> from mien.facs.catalogue import FACE_CHANNELS, au_channels
>>> solver = AUSolver(AUMapping.default())
>>> frame = np.zeros(len(FACE_CHANNELS))
>>> frame[list(au_channels(12))] = 3.0; frame[list(au_channels(6))] = 2.0
>>> aus = solver.solve(AUMapping.default().to_weights(frame))
>>> round(float(aus[solver.aus.index(12)]), 3), round(float(aus[solver.aus.index(6)]), 3)
(3.0, 2.0)
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from mien.errors import InvalidValueError
from mien.extras import require
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.catalogue import OPENFACS_AUS, au_channels
from mien.rig.mapping import INTENSITY_E, AUMapping

__all__ = ["SOLVED_AUS", "AUSolver"]

SOLVED_AUS: tuple[int, ...] = OPENFACS_AUS
"""AUs estimated by default: the 18 OpenFACS AUs (1 2 4 5 6 7 9 10 12 14 15 17 20 23 25 26 28 45)."""


def _nnls() -> Any:
    # scipy only: converting blendshape weights to AUs must not ask for the video extras (mediapipe)
    return require("scipy.optimize", "au").nnls


class AUSolver:
    """Reverse solve of an AU -> blendshape mapping by non-negative least squares.

    mapping: the forward table (targets must be the 52 ARKit names, as detectors report them).
    aus: AU numbers to estimate (default :data:`SOLVED_AUS`).
    """

    def __init__(self, mapping: AUMapping | None = None, aus: Sequence[int] = SOLVED_AUS) -> None:
        self.mapping = (mapping or AUMapping.default()).reordered(ARKIT_NAMES, rig_name="the ARKit vocabulary")
        self.aus: tuple[int, ...] = tuple(int(a) for a in aus)
        # One column per AU side, except where the two sides drive the same targets in the same proportions
        # (AU1: one shared browInnerUp): the sides cannot be told apart there, so they are solved as one column
        # (their sum) and the AU reads their common intensity.
        design = self.mapping.matrix.T.astype(np.float64)  # (52, 62)
        columns: list[np.ndarray] = []
        owner: list[int] = []
        channels: list[int] = []
        column_of: list[int] = []
        for k, code in enumerate(self.aus):
            sides = [design[:, c] for c in au_channels(code)]
            if not any(np.any(side) for side in sides):
                raise InvalidValueError("aus", f"AU{code}", "AUs the mapping drives (each must move some blendshape)")
            ids = au_channels(code)
            shared = len(sides) == 2 and np.linalg.matrix_rank(np.stack(sides, axis=1), tol=1e-9) < 2
            if shared:
                sides = [sides[0] + sides[1]]
            for n, channel in enumerate(ids):
                channels.append(channel)
                column_of.append(len(columns) + (0 if shared else n))
            for side in sides:
                columns.append(side)
                owner.append(k)
        self.channels = np.asarray(channels, dtype=np.intp)
        """Face-frame channel ids the solve reports (both sides of lateral AUs)."""
        self._column_of = np.asarray(column_of, dtype=np.intp)
        self._owner = np.asarray(owner, dtype=np.intp)
        self._design = np.ascontiguousarray(np.stack(columns, axis=1))  # (52, n_columns)
        counts = np.bincount(self._owner, minlength=len(self.aus)).astype(np.float64)
        self._average = np.zeros((len(columns), len(self.aus)))
        self._average[np.arange(len(columns)), self._owner] = 1.0 / counts[self._owner]
        self._nnls = _nnls()

    def solve_columns(self, blendshapes: np.ndarray) -> np.ndarray:
        """(..., n_columns) intensities 0..5 of the solved columns (an AU's sides, or its shared column)."""
        scores = np.asarray(blendshapes, dtype=np.float64)
        if scores.shape[-1:] != (len(ARKIT_NAMES),) or not np.all(np.isfinite(scores)):
            raise InvalidValueError("blendshapes", scores.shape, "(..., 52) finite ARKit scores")
        flat = scores.reshape(-1, len(ARKIT_NAMES))
        out = np.empty((len(flat), self._design.shape[1]))
        for i, row in enumerate(flat):
            out[i] = self._nnls(self._design, row)[0]
        np.clip(out, 0.0, INTENSITY_E, out=out)
        return out.reshape(*scores.shape[:-1], self._design.shape[1])

    def solve_channels(self, blendshapes: np.ndarray) -> np.ndarray:
        """(..., len(channels)) AU channel intensities 0..5 (a shared column gives both sides its value)."""
        return np.asarray(self.solve_columns(blendshapes)[..., self._column_of])

    def solve(self, blendshapes: np.ndarray) -> np.ndarray:
        """(..., len(aus)) AU intensities 0..5 (left/right averaged) for (..., 52) blendshape scores."""
        return np.asarray(self.solve_columns(blendshapes) @ self._average)
