"""Head rotation and eye gaze: rigid rotations applied after the morph targets.

Sign conventions (docs/ARCHITECTURE.md, :mod:`mien.facs.catalogue`), in the rig frame (+x character's left,
+y up, +z forward):

- ``yaw`` > 0 turns toward the character's left: a rotation about +y by ``+yaw`` (forward +z swings to +x);
- ``pitch`` > 0 raises the chin / looks up: a rotation about +x by ``-pitch`` (forward swings to +y);
- ``roll`` > 0 tilts the head toward the character's left shoulder: a rotation about +z by ``-roll`` (the top
  of the head swings to +x).

The head rotation is ``R = R_yaw @ R_pitch @ R_roll`` (turn, then nod, then tilt, in the head's own frame)
about ``rig.neck_pivot``, applied to ``rig.regions["head"]`` (every vertex when the rig has no such region).
Gaze rotates ``rig.regions["eye_L"]`` and ``["eye_R"]`` about ``rig.eye_centers`` by ``R_yaw @ R_pitch``
first (in the head frame), so the eyes then turn with the head.
"""

from __future__ import annotations

import numpy as np

from mien.errors import InvalidValueError
from mien.rig.model import Rig

__all__ = ["apply_pose", "apply_pose_batch", "gaze_rotation", "head_rotation"]


def _rotations(yaw_deg: np.ndarray, pitch_deg: np.ndarray, roll_deg: np.ndarray) -> np.ndarray:
    """(..., 3, 3) float64 ``R_y(yaw) @ R_x(-pitch) @ R_z(-roll)`` for angles in degrees."""
    y, p, r = np.radians(yaw_deg), -np.radians(pitch_deg), -np.radians(roll_deg)
    cy, sy, cp, sp, cr, sr = np.cos(y), np.sin(y), np.cos(p), np.sin(p), np.cos(r), np.sin(r)
    zero, one = np.zeros_like(cy), np.ones_like(cy)
    ry = np.stack([np.stack([cy, zero, sy], -1), np.stack([zero, one, zero], -1), np.stack([-sy, zero, cy], -1)], -2)
    rx = np.stack([np.stack([one, zero, zero], -1), np.stack([zero, cp, -sp], -1), np.stack([zero, sp, cp], -1)], -2)
    rz = np.stack([np.stack([cr, -sr, zero], -1), np.stack([sr, cr, zero], -1), np.stack([zero, zero, one], -1)], -2)
    result: np.ndarray = ry @ rx @ rz
    return result


def head_rotation(yaw_deg: float, pitch_deg: float, roll_deg: float) -> np.ndarray:
    """(3, 3) float64 head rotation for the given angles in degrees (signs in the module doc).

    >>> np.round(head_rotation(90.0, 0.0, 0.0) @ [0.0, 0.0, 1.0], 6).tolist()  # yaw left: forward -> +x
    [1.0, 0.0, 0.0]
    """
    return _rotations(np.asarray(yaw_deg, float), np.asarray(pitch_deg, float), np.asarray(roll_deg, float))


def gaze_rotation(yaw_deg: float, pitch_deg: float) -> np.ndarray:
    """(3, 3) float64 eyeball rotation for gaze angles in degrees (yaw > 0 left, pitch > 0 up)."""
    return head_rotation(yaw_deg, pitch_deg, 0.0)


def _angles(value: np.ndarray, size: int, name: str, batch: int | None) -> np.ndarray:
    array = np.asarray(value, dtype=np.float64)
    shape = (size,) if batch is None else (batch, size)
    if array.shape != shape or not np.all(np.isfinite(array)):
        raise InvalidValueError(name, value, f"finite degrees of shape {shape}")
    return array


def _check_vertices(rig: Rig, vertices: np.ndarray, batch: bool) -> np.ndarray:
    v = np.asarray(vertices, dtype=np.float32)
    expected = (rig.n_vertices, 3)
    if v.shape[-2:] != expected or v.ndim != (3 if batch else 2):
        shape = "(B, n_vertices, 3)" if batch else "(n_vertices, 3)"
        raise InvalidValueError("vertices", v.shape, f"{shape} with n_vertices={rig.n_vertices}")
    return v


def apply_pose_batch(rig: Rig, vertices: np.ndarray, head_ypr_deg: np.ndarray, gaze_yp_deg: np.ndarray) -> np.ndarray:
    """Rotate eyes and head for B frames.

    ``vertices``: (B, n_vertices, 3) deformed positions, metres; ``head_ypr_deg``: (B, 3) yaw, pitch, roll;
    ``gaze_yp_deg``: (B, 2) yaw, pitch. Returns a new (B, n_vertices, 3) float32 array.
    """
    v = _check_vertices(rig, vertices, batch=True)
    n_frames = v.shape[0]
    head = _angles(head_ypr_deg, 3, "head_ypr_deg", n_frames)
    gaze = _angles(gaze_yp_deg, 2, "gaze_yp_deg", n_frames)
    out = v.copy()
    if np.any(gaze):
        _rotate_eyes(rig, out, gaze)
    if np.any(head):
        out = _rotate_head(rig, out, head)
    return np.ascontiguousarray(out, dtype=np.float32)


def _rotate_eyes(rig: Rig, out: np.ndarray, gaze: np.ndarray) -> None:
    n_frames = len(gaze)
    gaze_r = _rotations(gaze[:, 0], gaze[:, 1], np.zeros(n_frames)).astype(np.float32)  # (B, 3, 3)
    for side, centre in (("eye_L", rig.eye_centers[0]), ("eye_R", rig.eye_centers[1])):
        ids = rig.regions.get(side)
        if ids is None or len(ids) == 0:
            continue
        local = out[:, ids] - centre
        out[:, ids] = np.einsum("bij,bkj->bki", gaze_r, local) + centre


def _rotate_head(rig: Rig, out: np.ndarray, head: np.ndarray) -> np.ndarray:
    head_r = _rotations(head[:, 0], head[:, 1], head[:, 2]).astype(np.float32)
    pivot = np.asarray(rig.neck_pivot, np.float32)
    ids = rig.regions.get("head")
    if ids is None:
        out = np.einsum("bij,bkj->bki", head_r, out - pivot) + pivot
    else:
        out[:, ids] = np.einsum("bij,bkj->bki", head_r, out[:, ids] - pivot) + pivot
    return out


def apply_pose(rig: Rig, vertices: np.ndarray, head_ypr_deg: np.ndarray, gaze_yp_deg: np.ndarray) -> np.ndarray:
    """Rotate the eyeballs by gaze and the head about the neck pivot, for one frame.

    ``vertices``: (n_vertices, 3) deformed positions, metres; ``head_ypr_deg``: (3,) yaw, pitch, roll degrees;
    ``gaze_yp_deg``: (2,) yaw, pitch degrees. Returns a new (n_vertices, 3) float32 array; ``vertices`` is not
    changed. Signs are in the module doc.
    """
    v = _check_vertices(rig, vertices, batch=False)
    head = _angles(head_ypr_deg, 3, "head_ypr_deg", None)
    gaze = _angles(gaze_yp_deg, 2, "gaze_yp_deg", None)
    return apply_pose_batch(rig, v[None], head[None], gaze[None])[0]
