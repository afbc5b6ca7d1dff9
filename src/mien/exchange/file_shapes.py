"""A rig's target weights as the weights of its head file's own shapes (the names the user's file uses).

A head read from a user's file (:class:`mien.rig.files.head.FileRig`) names its targets in mien's ARKit
vocabulary; :attr:`~mien.rig.files.head.HeadFileInfo.source_names` keeps, for each target, the rows it was built
from: ``(file shape, weight, side)``, the target being ``sum(weight * shape)`` over its rows, a row with side
``L`` / ``R`` taking only the character's left / right half of the shape. The way back, for writing the file's
own names, is linear:

- a row with no side gives its shape ``weight * target weight``;
- a row with a side gives ``weight * target weight / 2``: a file that can only weight the whole shape comes
  closest (least squares, for mirror-image halves) to its two halves at ``x_L`` and ``x_R`` with
  ``(x_L + x_R) / 2``, so a symmetric smile is exact and a one-sided one shows on both sides at half strength;
- several targets feeding one shape add up.

Shapes keep the rig's amplitude gains (:mod:`mien.heads.amplitude` writes them into the rows), so the file's
shapes at these weights show the face mien shows. A VRM file's shapes are its expressions (``happy``...), the
names its rows hold.

>>> from mien.rig.model import MorphTarget, Rig
>>> weights = np.array([[0.4, 0.8]], np.float32)
>>> rows = {"mouthSmileLeft": (("smile", 1.0, "L"),), "mouthSmileRight": (("smile", 1.0, "R"),)}
>>> shapes = shape_weights(weights, ("mouthSmileLeft", "mouthSmileRight"), rows)
>>> {name: round(float(w[0]), 6) for name, w in shapes.items()}
{'smile': 0.6}
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from mien.errors import InvalidValueError
from mien.rig.model import Rig

__all__ = ["file_shape_names", "rig_shape_weights", "shape_weights", "source_rows"]

SourceRows = Mapping[str, Sequence[tuple[str, float, str]]]
"""Rig target -> ``(file shape, weight, side)`` rows (:attr:`HeadFileInfo.source_names`)."""


def shape_weights(weights: np.ndarray, target_names: Sequence[str], rows: SourceRows) -> dict[str, np.ndarray]:
    """File shape -> (n,) float32 weights of (n, n_targets) target ``weights`` (see the module doc).

    Targets without rows (feature-point targets compiled onto the head) drive no shape; shapes come in the
    order of their first row (ARKit targets first, then the file's unmatched shapes).
    """
    values = np.asarray(weights, np.float64)
    if values.ndim != 2 or values.shape[1] != len(target_names):
        raise InvalidValueError("weights", values.shape, f"(n, {len(target_names)}) target weights")
    out: dict[str, np.ndarray] = {}
    for j, target in enumerate(target_names):
        for shape, weight, side in rows.get(target, ()):
            share = float(weight) * (0.5 if side else 1.0)
            column = values[:, j] * share
            out[shape] = out[shape] + column if shape in out else column
    return {name: column.astype(np.float32) for name, column in out.items()}


def file_shape_names(rows: SourceRows) -> tuple[str, ...]:
    """The file's shapes the rows name, each once, in the order of their first row."""
    return tuple(dict.fromkeys(shape for source in rows.values() for shape, _weight, _side in source))


def source_rows(rig: Rig) -> SourceRows:
    """The rows of a head read from a file; raises naming the head when it was not read from one."""
    info = getattr(rig, "info", None)
    if info is None or not getattr(info, "source_names", None):
        raise InvalidValueError(
            "head", rig.name, "a head read from a character file (--head face.glb): only it has names of its own"
        )
    rows: SourceRows = info.source_names
    return rows


def rig_shape_weights(weights: np.ndarray, rig: Rig) -> dict[str, np.ndarray]:
    """:func:`shape_weights` of (n, n_targets) ``weights`` on a head read from a file."""
    return shape_weights(weights, rig.target_names, source_rows(rig))
