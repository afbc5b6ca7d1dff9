"""AU intensities from blendshape scores: the AU -> ARKit mapping solved in reverse.

The mapping (:class:`mien.rig.mapping.AUMapping`) says how much each AU channel drives each blendshape per
unit of intensity: ``weights = clip(aus @ M, 0, 1)``. Given detected scores ``b`` (52,), the AU estimate is
the non-negative least-squares solution of ``aus @ M = b`` over a chosen set of AU channels (those of
:data:`SOLVED_AUS`), capped at E (5). Left/right channels of one AU are solved separately and reported as
their mean, so results come back as FACS intensities per AU, 0..5.

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

from mien.errors import InvalidValueError, MissingExtraError
from mien.facs.catalogue import FACE_CHANNELS, OPENFACS_AUS, au_channels
from mien.rig.arkit import ARKIT_NAMES
from mien.rig.mapping import INTENSITY_E, AUMapping

__all__ = ["SOLVED_AUS", "AUSolver"]

SOLVED_AUS: tuple[int, ...] = OPENFACS_AUS
"""AUs estimated by default: the 18 OpenFACS AUs (1 2 4 5 6 7 9 10 12 14 15 17 20 23 25 26 28 45)."""


def _nnls() -> Any:
    try:
        from scipy.optimize import nnls
    except ImportError:
        raise MissingExtraError("scipy", "validate") from None
    return nnls


class AUSolver:
    """Reverse solve of an AU -> blendshape mapping by non-negative least squares.

    mapping: the forward table (targets must be the 52 ARKit names, as detectors report them).
    aus: AU numbers to estimate (default :data:`SOLVED_AUS`).
    """

    def __init__(self, mapping: AUMapping | None = None, aus: Sequence[int] = SOLVED_AUS) -> None:
        self.mapping = (mapping or AUMapping.default()).reordered(ARKIT_NAMES, rig_name="the ARKit vocabulary")
        self.aus: tuple[int, ...] = tuple(int(a) for a in aus)
        channels: list[int] = []
        owner: list[int] = []
        for k, code in enumerate(self.aus):
            for channel in au_channels(code):
                channels.append(channel)
                owner.append(k)
        self.channels = np.asarray(channels, dtype=np.intp)
        """Face-frame channel ids solved for (L and R separately)."""
        self._owner = np.asarray(owner, dtype=np.intp)
        self._design = np.ascontiguousarray(self.mapping.matrix[self.channels].T, dtype=np.float64)  # (52, n_ch)
        blind = [FACE_CHANNELS[c] for c in self.channels if not np.any(self._design[:, list(self.channels).index(c)])]
        if blind:
            raise InvalidValueError("aus", blind, "AUs the mapping drives (each must move some blendshape)")
        counts = np.bincount(self._owner, minlength=len(self.aus)).astype(np.float64)
        self._average = np.zeros((len(self.channels), len(self.aus)))
        self._average[np.arange(len(self.channels)), self._owner] = 1.0 / counts[self._owner]
        self._nnls = _nnls()

    def solve_channels(self, blendshapes: np.ndarray) -> np.ndarray:
        """(..., len(channels)) AU channel intensities 0..5 for (..., 52) blendshape scores."""
        scores = np.asarray(blendshapes, dtype=np.float64)
        if scores.shape[-1:] != (len(ARKIT_NAMES),) or not np.all(np.isfinite(scores)):
            raise InvalidValueError("blendshapes", scores.shape, "(..., 52) finite ARKit scores")
        flat = scores.reshape(-1, len(ARKIT_NAMES))
        out = np.empty((len(flat), len(self.channels)))
        for i, row in enumerate(flat):
            out[i] = self._nnls(self._design, row)[0]
        np.clip(out, 0.0, INTENSITY_E, out=out)
        return out.reshape(*scores.shape[:-1], len(self.channels))

    def solve(self, blendshapes: np.ndarray) -> np.ndarray:
        """(..., len(aus)) AU intensities 0..5 (left/right averaged) for (..., 52) blendshape scores."""
        return np.asarray(self.solve_channels(blendshapes) @ self._average)
