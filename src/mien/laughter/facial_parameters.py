"""Facial parameters FP1..FP15 (Mascaró et al. 2021, Tables 1-2) from iBUG-68 landmarks.

Each parameter is the distance between two landmarks (``data/fp_landmarks.csv``) divided by a face size, the
inter-ocular distance between the outer eye corners (iBUG 36 and 45) measured on the neutral reference, so
parameters are in "inter-ocular distances" and do not depend on the video's resolution or on how far the face
is from the camera. Distances use every coordinate given: pass (n, 68, 2) pixel points for the paper's 2-D
distances (what :func:`mien.learning.takes.controllers_from_track` does).

The neutral reference ``FP0`` is, by default, the mean of the first :data:`NEUTRAL_FRAMES` frames (5, about
0.17 s at 30 fps: the paper's performers start from a neutral face), or one chosen frame, or values given as
an array or read from a ``.npy`` / ``.json`` file (15 numbers).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from mien.errors import InvalidValueError
from mien.fileio.tables import read_table

__all__ = [
    "FP_NAMES",
    "NEUTRAL_FRAMES",
    "FacialParameter",
    "Neutral",
    "face_size",
    "facial_parameter_table",
    "facial_parameters",
    "neutral_reference",
]

NEUTRAL_FRAMES = 5
"""Default number of leading frames averaged into the neutral reference (about 0.17 s at 30 fps)."""

OUTER_EYE_CORNERS = (36, 45)
"""iBUG-68 points whose distance is the face size (outer corners of the right and left eye)."""

Neutral = int | np.ndarray | str | os.PathLike[str] | None
"""How the neutral reference is chosen: None (first NEUTRAL_FRAMES frames), a frame index, (15,) FP0 values,
or a .npy / .json file of 15 values."""


@dataclass(frozen=True)
class FacialParameter:
    """One row of the paper's Tables 1-2 (see ``data/fp_landmarks.csv``)."""

    name: str
    """``FP1`` .. ``FP15``."""
    landmarks: tuple[int, int]
    """The iBUG-68 (0-based) pair whose distance this parameter is."""
    meaning: str
    """The paper's description."""
    paper_side: str
    """Side word in the paper (the picture's side), or empty."""
    performer_side: str
    """The performer's own side of the landmarks, or empty."""
    controllers: tuple[tuple[str, float], ...]
    """(controller name, sign) pairs this parameter feeds, performer-sided names."""


@cache
def facial_parameter_table() -> tuple[FacialParameter, ...]:
    """The 15 facial parameters, read from ``data/fp_landmarks.csv``."""
    rows = read_table("mien.laughter", "data/fp_landmarks.csv")
    table = []
    for row in rows:
        controllers = tuple(
            (name, float(sign)) for name, sign in (item.split(":") for item in row["controllers"].split())
        )
        table.append(
            FacialParameter(
                name=f"FP{int(row['fp'])}",
                landmarks=(int(row["landmark_a"]), int(row["landmark_b"])),
                meaning=row["meaning"],
                paper_side=row["paper_side"],
                performer_side=row["performer_side"],
                controllers=controllers,
            )
        )
    if [p.name for p in table] != [f"FP{i}" for i in range(1, 16)]:
        raise InvalidValueError("fp_landmarks.csv", [p.name for p in table], "rows FP1..FP15 in order")
    return tuple(table)


FP_NAMES: tuple[str, ...] = tuple(p.name for p in facial_parameter_table())
"""``("FP1", ..., "FP15")``."""


def _check_points(points68: np.ndarray) -> np.ndarray:
    points = np.asarray(points68, dtype=np.float64)
    if points.ndim != 3 or points.shape[1] != 68 or points.shape[2] not in (2, 3):
        raise InvalidValueError("points68", f"array of shape {points.shape}", "(n_frames, 68, 2 or 3)")
    if points.shape[0] == 0:
        raise InvalidValueError("points68", "0 frames", "at least one frame")
    return points


def _neutral_frames(n_frames: int, neutral: Neutral) -> np.ndarray:
    """Frame indices of the neutral reference (the first NEUTRAL_FRAMES when ``neutral`` is not a frame)."""
    if isinstance(neutral, (int, np.integer)) and not isinstance(neutral, bool):
        if not -n_frames <= int(neutral) < n_frames:
            raise InvalidValueError("neutral", int(neutral), f"a frame index in [0, {n_frames})")
        return np.array([int(neutral) % n_frames])
    return np.arange(min(NEUTRAL_FRAMES, n_frames))


def face_size(points68: np.ndarray, neutral: Neutral = None) -> float:
    """Face size in the points' units: mean inter-ocular distance (iBUG 36-45) over the neutral frames.

    points68: (n, 68, 2|3). neutral: see :data:`Neutral` (a frame index selects that frame; otherwise the
    first :data:`NEUTRAL_FRAMES` frames are used).
    """
    points = _check_points(points68)
    frames = points[_neutral_frames(points.shape[0], neutral)]
    a, b = OUTER_EYE_CORNERS
    size = float(np.nanmean(np.linalg.norm(frames[:, a] - frames[:, b], axis=-1)))
    if not np.isfinite(size) or size <= 0:
        raise InvalidValueError("face size", size, "a positive inter-ocular distance on the neutral frames")
    return size


def facial_parameters(points68: np.ndarray, size: float | None = None, neutral: Neutral = None) -> np.ndarray:
    """(n, 15) facial parameters FP1..FP15 in inter-ocular distances from (n, 68, 2|3) iBUG-68 points.

    size: the face size in the points' units (default: :func:`face_size` on the neutral frames chosen by
    ``neutral``). Scaling or moving all points together leaves the result unchanged.

    >>> square = np.zeros((1, 68, 2)); square[0, 45] = (2.0, 0.0); square[0, 54] = (1.0, 0.0)
    >>> float(facial_parameters(square)[0, 6])  # FP7, mouth width 48-54, half the eye distance
    0.5
    """
    points = _check_points(points68)
    scale = face_size(points, neutral) if size is None else float(size)
    if not np.isfinite(scale) or scale <= 0:
        raise InvalidValueError("size", size, "a positive face size")
    pairs = np.array([p.landmarks for p in facial_parameter_table()], dtype=np.intp)
    distances = np.linalg.norm(points[:, pairs[:, 0]] - points[:, pairs[:, 1]], axis=-1)
    return distances / scale


def neutral_reference(parameters: np.ndarray, neutral: Neutral = None) -> np.ndarray:
    """(15,) neutral reference FP0 for (n, 15) ``parameters``.

    neutral: None (mean of the first :data:`NEUTRAL_FRAMES` frames), a frame index, (15,) values, or a
    ``.npy`` / ``.json`` file holding 15 values.
    """
    values = np.asarray(parameters, dtype=np.float64)
    if values.ndim != 2 or values.shape[1] != len(FP_NAMES) or values.shape[0] == 0:
        raise InvalidValueError("parameters", f"array of shape {values.shape}", "(n_frames >= 1, 15)")
    if isinstance(neutral, (str, os.PathLike)):
        reference = _read_reference(Path(neutral))
    elif isinstance(neutral, np.ndarray) and neutral.ndim > 0:
        reference = np.asarray(neutral, dtype=np.float64)
    else:
        reference = values[_neutral_frames(values.shape[0], neutral)].mean(axis=0)
    if reference.shape != (len(FP_NAMES),) or not np.all(np.isfinite(reference)):
        raise InvalidValueError("neutral", f"values of shape {reference.shape}", "15 finite FP0 values")
    return reference


def _read_reference(path: Path) -> np.ndarray:
    try:
        if path.suffix == ".npy":
            return np.asarray(np.load(path, allow_pickle=False), dtype=np.float64).reshape(-1)
        if path.suffix == ".json":
            data = json.loads(path.read_text("utf-8"))
            if isinstance(data, dict):
                data = [data[name] for name in FP_NAMES]
            return np.asarray(data, dtype=np.float64).reshape(-1)
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise InvalidValueError("neutral", str(path), f"a readable FP0 file ({exc})") from None
    raise InvalidValueError("neutral", str(path), "a .npy or .json file of 15 FP0 values")
