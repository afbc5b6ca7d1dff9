"""AU intensities -> morph-target weights, from a versioned table (data, not code).

The shipped table is ``data/au_to_arkit.csv`` (sources cited in its comments). A table has the columns
``channel,target,weight_at_E``: the weight ``target`` reaches when ``channel`` is at FACS intensity E (5);
weights are linear in intensity, summed over channels and clipped to [0, 1]. Channels are the AU channels of
:data:`mien.facs.catalogue.FACE_CHANNELS` (``AU12L``/``AU12R`` for the character's left/right, ``AU25`` for a
midline AU). Head and gaze channels map to nothing here: :mod:`mien.rig.pose` applies them.

>>> import numpy as np
>>> from mien.facs.catalogue import FACE_CHANNELS, au_channels
>>> mapping = AUMapping.default()
>>> frame = np.zeros(len(FACE_CHANNELS))
>>> frame[list(au_channels(12))] = 5.0
>>> weights = mapping.to_weights(frame)
>>> float(weights[mapping.target_names.index("mouthSmileLeft")])
1.0
"""

from __future__ import annotations

import csv
import math
import os
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from mien.errors import InvalidValueError, UnknownNameError
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.catalogue import FACE_CHANNELS, POSE_CHANNELS
from mien.facs.intensity import MAX_INTENSITY
from mien.rig.model import Rig

__all__ = ["INTENSITY_E", "AUMapping"]

INTENSITY_E = MAX_INTENSITY
"""FACS intensity E, the top of mien's 0..5 scale (:data:`mien.facs.intensity.MAX_INTENSITY`): where a table's
``weight_at_E`` is reached."""

_AU_CHANNELS = tuple(name for name in FACE_CHANNELS if name not in POSE_CHANNELS)
_COLUMNS = ("channel", "target", "weight_at_E")


@dataclass(frozen=True, eq=False)
class AUMapping:
    """A linear map from face-frame AU intensities to morph-target weights."""

    target_names: tuple[str, ...]
    """Morph-target names, one per column of :attr:`matrix`."""
    matrix: np.ndarray
    """(len(FACE_CHANNELS), n_targets) float32 weight per unit of intensity (``weight_at_E / 5``); the pose
    channels' rows are zero."""
    version: str = ""
    """The table's ``# version:`` line (empty when it has none)."""
    source: str = ""
    """Where the table came from (a file path, or ``"mien:rig/data/au_to_arkit.csv"``)."""

    def __post_init__(self) -> None:
        matrix = np.ascontiguousarray(self.matrix, dtype=np.float32)
        if matrix.shape != (len(FACE_CHANNELS), len(self.target_names)):
            raise InvalidValueError(
                "AUMapping matrix", matrix.shape, f"({len(FACE_CHANNELS)}, {len(self.target_names)})"
            )
        object.__setattr__(self, "target_names", tuple(self.target_names))
        object.__setattr__(self, "matrix", matrix)

    @classmethod
    def default(cls) -> AUMapping:
        """The shipped AU -> ARKit table (targets: the 52 :data:`ARKIT_NAMES`, in ARKit order)."""
        text = resources.files("mien.rig").joinpath("data/au_to_arkit.csv").read_text(encoding="utf-8")
        return cls._parse(text, "mien:rig/data/au_to_arkit.csv", ARKIT_NAMES)

    @classmethod
    def from_file(cls, path: str | os.PathLike[str], known_targets: Sequence[str] | None = ARKIT_NAMES) -> AUMapping:
        """Read a user's table (same columns and comment syntax as the shipped one).

        ``known_targets``: the allowed target names, which become :attr:`target_names` in that order (default
        the ARKit names); ``None`` accepts any name, in order of first appearance. An unknown channel or target
        raises :class:`UnknownNameError` naming the file, line and name; a bad weight or header raises
        :class:`InvalidValueError`.
        """
        text = Path(path).read_text(encoding="utf-8")
        return cls._parse(text, str(path), None if known_targets is None else tuple(known_targets))

    @classmethod
    def _parse(cls, text: str, source: str, known_targets: tuple[str, ...] | None) -> AUMapping:
        version = ""
        rows: list[tuple[int, list[str]]] = []
        for number, line in enumerate(text.splitlines(), 1):
            stripped = line.strip()
            if stripped.startswith("#"):
                if stripped[1:].strip().lower().startswith("version:"):
                    version = stripped.split(":", 1)[1].strip()
                continue
            if stripped:
                rows.append((number, next(csv.reader([stripped]))))
        if not rows or tuple(cell.strip() for cell in rows[0][1]) != _COLUMNS:
            header = rows[0][1] if rows else []
            raise InvalidValueError(f"{source} header", header, ",".join(_COLUMNS))
        entries: dict[tuple[str, str], float] = {}
        order: list[str] = []
        for number, cells in rows[1:]:
            where = f"{source} line {number}"
            if len(cells) != 3:
                raise InvalidValueError(where, ",".join(cells), "3 columns: channel,target,weight_at_E")
            channel, target, raw = (cell.strip() for cell in cells)
            if channel not in _AU_CHANNELS:
                raise UnknownNameError(f"AU channel ({where})", channel, _AU_CHANNELS)
            if known_targets is not None and target not in known_targets:
                raise UnknownNameError(f"target ({where})", target, known_targets)
            try:
                weight = float(raw)
            except ValueError:
                weight = math.nan
            if not math.isfinite(weight):
                raise InvalidValueError(f"weight_at_E ({where})", raw, "a finite number")
            if (channel, target) in entries:
                raise InvalidValueError(where, f"{channel},{target}", "each channel,target pair once")
            entries[(channel, target)] = weight
            if target not in order:
                order.append(target)
        names = known_targets if known_targets is not None else tuple(order)
        column = {name: i for i, name in enumerate(names)}
        matrix = np.zeros((len(FACE_CHANNELS), len(names)), np.float32)
        for (channel, target), weight in entries.items():
            matrix[FACE_CHANNELS.index(channel), column[target]] = weight / INTENSITY_E
        return cls(names, matrix, version, source)

    @property
    def n_targets(self) -> int:
        """Number of targets (columns)."""
        return len(self.target_names)

    def to_weights(self, au_frames: np.ndarray) -> np.ndarray:
        """Morph-target weights for face frames.

        ``au_frames``: (..., len(FACE_CHANNELS)) intensities 0..5 (pose channels are ignored).
        Returns (..., n_targets) float32 weights clipped to [0, 1].
        """
        frames = np.asarray(au_frames, dtype=np.float32)
        if frames.ndim == 0 or frames.shape[-1] != len(FACE_CHANNELS):
            raise InvalidValueError("au_frames", frames.shape, f"(..., {len(FACE_CHANNELS)}) face frames")
        # Pose rows of the matrix are zero, so head/gaze degrees contribute nothing.
        weights: np.ndarray = np.clip(frames @ self.matrix, 0.0, 1.0)
        return weights

    def reordered(self, target_names: Sequence[str], rig_name: str = "the rig") -> AUMapping:
        """This mapping with columns for ``target_names`` (in that order).

        Targets the mapping drives but ``target_names`` lacks are dropped with a :class:`UserWarning` listing
        them; names the mapping does not drive get zero columns.
        """
        names = tuple(target_names)
        used = [name for j, name in enumerate(self.target_names) if np.any(self.matrix[:, j])]
        dropped = [name for name in used if name not in names]
        if dropped:
            warnings.warn(
                f"AU mapping {self.source or '(unnamed)'}: {rig_name} lacks targets {', '.join(dropped)}; "
                "the AUs driving them lose that motion",
                UserWarning,
                stacklevel=2,
            )
        own = {name: j for j, name in enumerate(self.target_names)}
        matrix = np.zeros((len(FACE_CHANNELS), len(names)), np.float32)
        for i, name in enumerate(names):
            if name in own:
                matrix[:, i] = self.matrix[:, own[name]]
        return AUMapping(names, matrix, self.version, self.source)

    def weights_for(self, rig: Rig) -> AUMapping:
        """This mapping reordered to ``rig.target_names`` (see :meth:`reordered`): its :meth:`to_weights` then
        returns (..., len(rig.targets)) weights ready for :class:`mien.rig.deform.Deformer`."""
        return self.reordered(rig.target_names, rig_name=f"rig {rig.name!r}")
