"""glTF rotations: unit quaternions ``(x, y, z, w)`` (glTF 2.0's order) of rotation matrices.

Shared by the writers of :mod:`mien.exchange.glb` (the head node), :mod:`mien.exchange.glb_user` (a file's head
and eye bones) and :mod:`mien.exchange.vrm`, so none of them imports another for it.

>>> matrix_quaternions(np.eye(3)[None]).tolist()
[[0.0, 0.0, 0.0, 1.0]]
"""

from __future__ import annotations

import numpy as np

__all__ = ["matrix_quaternions"]


def matrix_quaternions(r: np.ndarray) -> np.ndarray:
    """(n, 4) float32 unit quaternions (x, y, z, w), glTF's order, of (n, 3, 3) rotation matrices."""
    w = np.sqrt(np.maximum(0.0, 1.0 + r[:, 0, 0] + r[:, 1, 1] + r[:, 2, 2])) / 2.0
    x = np.sqrt(np.maximum(0.0, 1.0 + r[:, 0, 0] - r[:, 1, 1] - r[:, 2, 2])) / 2.0
    y = np.sqrt(np.maximum(0.0, 1.0 - r[:, 0, 0] + r[:, 1, 1] - r[:, 2, 2])) / 2.0
    z = np.sqrt(np.maximum(0.0, 1.0 - r[:, 0, 0] - r[:, 1, 1] + r[:, 2, 2])) / 2.0
    x = np.copysign(x, r[:, 2, 1] - r[:, 1, 2])
    y = np.copysign(y, r[:, 0, 2] - r[:, 2, 0])
    z = np.copysign(z, r[:, 1, 0] - r[:, 0, 1])
    q = np.stack([x, y, z, w], axis=1)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return np.asarray(q, np.float32)
