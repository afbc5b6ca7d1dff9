"""Numbers in the validation JSON files: rounded to 1e-4, NaN written as null and read back as NaN.

>>> rounded(float("nan")), rounded(0.123456), unrounded(None)
(None, 0.1235, nan)
>>> rounded_array(np.array([[1.0, np.nan]]))
[[1.0, None]]
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["array_of", "rounded", "rounded_array", "unrounded"]


def rounded(value: float) -> float | None:
    """``value`` rounded to 4 decimals, or None for NaN."""
    value = float(value)
    return None if math.isnan(value) else round(value, 4)


def unrounded(value: float | None) -> float:
    """Inverse of :func:`rounded`: None -> NaN."""
    return math.nan if value is None else float(value)


def rounded_array(values: np.ndarray) -> Any:
    """Nested lists of ``values`` rounded to 4 decimals, NaN as None."""
    values = np.asarray(values, dtype=np.float64)
    out = np.round(values, 4).astype(object)
    out[np.isnan(values)] = None
    return out.tolist()


def array_of(values: Any) -> np.ndarray:
    """Inverse of :func:`rounded_array`: a float64 array, None -> NaN."""
    return np.array(values, dtype=np.float64)
