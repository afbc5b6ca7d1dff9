"""Rig-controller curves from facial parameters (Mascaró et al. 2021, Eq. 1 and Table 2), and ARKit weights.

Per frame, ``C = (FP - FP0) * eps * CONTROLLER_GAIN`` for each controller of
:data:`~mien.laughter.names.CONTROLLER_NAMES`, with the facial-parameter -> controller table of
``data/fp_landmarks.csv``:

- sides are the performer's own (the paper's "right" parameters lie on the picture's right, the performer's
  left; see the CSV header), so ``leftBlink`` follows the performer's left eye and maps to ``eyeBlinkLeft``;
- a controller fed by several parameters is the mean of their signed deltas: ``upsetSad`` and ``shocked``
  both take the mean of the inner-brow deltas FP2 and FP4 (the paper gives nothing that tells them apart;
  their ARKit mappings differ), ``jaw`` the mean of mouth height FP10 and chin-to-nose FP14;
- signs make a positive value mean the name: brow raise / upsetSad / shocked > 0 = inner brows raised,
  blink > 0 = closing (brow-to-eye-corner distance shrinking), twich > 0 = lower-lid segment lengthening (as
  in the Duchenne smile of the test clip), smileFrown > 0 = mouth widening (smile), side smileFrown > 0 =
  mouth corner moving away from the nose (smile), jaw > 0 = opening, sneer > 0 = upper lip / mouth corner
  rising toward the nose, neck > 0 = face oval wider (turning to frontal or leaning in).

``eps`` keeps the paper's meaning, the animator's hardness (0.1 soft .. 0.3 hard, default
:data:`DEFAULT_EPS` = 0.2). The paper applied it to pixel distances at 640x490; mien's parameters are in
inter-ocular distances, so :data:`CONTROLLER_GAIN` (20 per inter-ocular distance) restores a usable scale: the
full smile of the shared test clip widens the mouth by ~0.26 inter-ocular distances, giving smileFrown ~1.0 at
eps = 0.2.

Some of the paper's landmark pairs barely move: the lower-lid segment (FP1, FP3) and the brow-to-eye-corner
"eye opening" (FP5, FP6, which follows the brow more than the lid), so twich and blink curves stay small.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from mien.errors import InvalidValueError, UnknownNameError
from mien.facs.arkit import ARKIT_INDEX, ARKIT_NAMES
from mien.facs.clip import Clip
from mien.fileio.tables import read_table
from mien.laughter.facial_parameters import (
    FP_NAMES,
    Neutral,
    facial_parameter_table,
    facial_parameters,
    neutral_reference,
)
from mien.laughter.names import CONTROLLER_NAMES

__all__ = [
    "CONTROLLER_GAIN",
    "DEFAULT_EPS",
    "ArkitRow",
    "arkit_mapping",
    "controller_matrix",
    "controllers",
    "controllers_from_points",
    "controllers_to_arkit",
]

DEFAULT_EPS = 0.2
"""Default hardness factor eps (the paper's range is 0.1-0.3)."""

CONTROLLER_GAIN = 20.0
"""Controller units per inter-ocular distance of parameter change at eps = 1 (see module doc)."""


@cache
def controller_matrix() -> np.ndarray:
    """(15, 16) matrix ``W`` with ``C = (FP - FP0) @ W * eps * CONTROLLER_GAIN`` (signs and means folded in)."""
    weights = np.zeros((len(FP_NAMES), len(CONTROLLER_NAMES)))
    for row, parameter in enumerate(facial_parameter_table()):
        for name, sign in parameter.controllers:
            if name not in CONTROLLER_NAMES:
                raise UnknownNameError("controller", name, CONTROLLER_NAMES)
            weights[row, CONTROLLER_NAMES.index(name)] = sign
    counts = np.count_nonzero(weights, axis=0)
    if np.any(counts == 0):
        missing = [n for n, c in zip(CONTROLLER_NAMES, counts, strict=True) if c == 0]
        raise InvalidValueError("fp_landmarks.csv controllers", missing, "every controller fed by a parameter")
    weights /= counts
    weights.setflags(write=False)
    return weights


def _check_eps(eps: float) -> float:
    value = float(eps)
    if not np.isfinite(value) or value <= 0:
        raise InvalidValueError("eps", eps, "a positive hardness factor (the paper uses 0.1-0.3)")
    return value


def controllers(parameters: np.ndarray, fps: float, eps: float = DEFAULT_EPS, neutral: Neutral = None) -> Clip:
    """Controller curves from (n, 15) facial parameters: a :class:`Clip` with channels CONTROLLER_NAMES.

    neutral: the neutral reference FP0 (see :func:`~mien.laughter.facial_parameters.neutral_reference`).
    """
    values = np.asarray(parameters, dtype=np.float64)
    reference = neutral_reference(values, neutral)
    curves = (values - reference) @ controller_matrix() * (_check_eps(eps) * CONTROLLER_GAIN)
    return Clip(curves, fps, CONTROLLER_NAMES)


def controllers_from_points(
    points68: np.ndarray, fps: float, eps: float = DEFAULT_EPS, neutral: Neutral = None
) -> Clip:
    """Controller curves from (n, 68, 2|3) iBUG-68 points (any units), normalised by the neutral face size."""
    return controllers(facial_parameters(points68, neutral=neutral), fps, eps, neutral)


@dataclass(frozen=True)
class ArkitRow:
    """One row of ``data/controllers_to_arkit.csv``: ``arkit += weight * max(direction * controller, 0)``."""

    controller: str
    """A name in CONTROLLER_NAMES."""
    direction: float
    """+1 or -1: which sign of the controller drives the target."""
    arkit: str
    """A name in ARKIT_NAMES."""
    weight: float
    """ARKit weight per controller unit."""


@cache
def arkit_mapping() -> tuple[int, tuple[ArkitRow, ...]]:
    """``(version, rows)`` of the controller -> ARKit mapping table."""
    rows = read_table("mien.laughter", "data/controllers_to_arkit.csv")
    versions = {int(r["version"]) for r in rows}
    if len(versions) != 1:
        raise InvalidValueError("controllers_to_arkit.csv version", sorted(versions), "one mapping version")
    mapping = []
    for r in rows:
        if r["controller"] not in CONTROLLER_NAMES:
            raise UnknownNameError("controller", r["controller"], CONTROLLER_NAMES)
        if r["arkit"] not in ARKIT_INDEX:
            raise UnknownNameError("ARKit blendshape", r["arkit"], ARKIT_NAMES)
        mapping.append(ArkitRow(r["controller"], float(r["direction"]), r["arkit"], float(r["weight"])))
    return versions.pop(), tuple(mapping)


def controllers_to_arkit(clip: Clip) -> Clip:
    """ARKit weight clip ((n, 52), values in [0, 1], channels ARKIT_NAMES) from a controller clip.

    ``clip`` must hold the controller channels the mapping uses (any order; extra channels are ignored).
    """
    _, rows = arkit_mapping()
    out = np.zeros((clip.n_frames, len(ARKIT_NAMES)))
    for row in rows:
        drive = np.maximum(row.direction * clip.channel(row.controller), 0.0)
        out[:, ARKIT_INDEX[row.arkit]] += row.weight * drive
    return Clip(np.clip(out, 0.0, 1.0), clip.fps, ARKIT_NAMES)
