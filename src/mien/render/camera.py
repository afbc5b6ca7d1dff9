"""Cameras for offline rendering, and the presets of the Broekens perception study.

A :class:`Camera` orbits a target point in the mien rig frame (metres; +x the character's left, +y up, +z
out of the face toward a frontal viewer; origin between the eyeball centres). ``yaw_deg = 0`` looks at the
face from the front (from +z along -z); ``yaw_deg > 0`` swings the camera toward the character's left (so
``yaw_deg = 90`` sees the left profile, the nose pointing to the image's left); ``pitch_deg > 0`` raises the
camera so it looks down. Matrices follow the OpenGL convention (right-handed eye space looking along -z,
clip space -1..1) and are row-major numpy arrays: transpose before uploading them to a column-major GL
uniform.

Broekens, Qu & Brinkman showed one face at 1 m and 3 m, frontally and in a 90-degree lateral view, at one
field of view; mien adds a 45-degree oblique view. :data:`VIEWS` is the one registry of these viewing
conditions (every other module imports it); :data:`CAMERA_PRESETS` is built from it. The presets use a
vertical field of view of 22 degrees: the angle a 15-inch 4:3 screen (22.9 cm tall, the study's required
screen) subtends at a 60 cm viewing distance, so a full-screen stimulus shows the face in natural
perspective, and the 3 m face is a third the size of the 1 m face.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from mien.errors import InvalidValueError, UnknownNameError

__all__ = [
    "CAMERA_PRESETS",
    "STUDY_ANGLES",
    "STUDY_FOV_DEG",
    "VIEWS",
    "VIEW_ANGLES_DEG",
    "VIEW_DISTANCES_M",
    "Camera",
    "View",
    "camera_from_options",
]

STUDY_FOV_DEG = 22.0
"""Vertical field of view (degrees) shared by all presets: 2 * atan(11.45 cm / 60 cm), a 15-inch 4:3 screen
seen from 60 cm."""

FACE_CENTRE_M = (0.0, -0.03, 0.0)
"""Point the frontal presets look at: 3 cm below the eyes, about the middle of the face (hairline to chin)."""

HEAD_CENTRE_M = (0.0, -0.03, -0.06)
"""Point the lateral presets look at: the middle of the head seen in profile (6 cm behind the eyes)."""


def _finite(field: str, value: float) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InvalidValueError(field, value, "a finite number") from None
    if not math.isfinite(number):
        raise InvalidValueError(field, value, "a finite number")
    return number


@dataclass(frozen=True)
class Camera:
    """A perspective camera orbiting ``target`` at ``distance_m`` (see the module doc for the angles).

    >>> camera = Camera(distance_m=2.0)
    >>> [round(float(c), 3) for c in camera.position]
    [0.0, -0.03, 2.0]
    """

    yaw_deg: float = 0.0
    """Orbit angle about the vertical axis, degrees; 0 = frontal, +90 = from the character's left side."""
    pitch_deg: float = 0.0
    """Elevation, degrees in (-90, 90); positive = camera above the target, looking down."""
    distance_m: float = 1.0
    """Distance from the camera to ``target``, metres (> 0)."""
    fov_deg: float = STUDY_FOV_DEG
    """Vertical field of view, degrees in (0, 180)."""
    target: tuple[float, float, float] = FACE_CENTRE_M
    """Point looked at, metres in the rig frame."""
    near_m: float = 0.05
    """Near clipping distance, metres (> 0)."""
    far_m: float = 50.0
    """Far clipping distance, metres (> ``near_m``)."""

    def __post_init__(self) -> None:
        for name in ("yaw_deg", "pitch_deg", "distance_m", "fov_deg", "near_m", "far_m"):
            object.__setattr__(self, name, _finite(name, getattr(self, name)))
        try:
            target = tuple(_finite("target", t) for t in self.target)
        except TypeError:
            raise InvalidValueError("target", self.target, "three finite numbers (metres)") from None
        if len(target) != 3:
            raise InvalidValueError("target", self.target, "three finite numbers (metres)")
        object.__setattr__(self, "target", target)
        if not 0.0 < self.fov_deg < 180.0:
            raise InvalidValueError("fov_deg", self.fov_deg, "a vertical field of view in (0, 180) degrees")
        if self.distance_m <= 0.0:
            raise InvalidValueError("distance_m", self.distance_m, "a distance > 0 metres")
        if not -90.0 < self.pitch_deg < 90.0:
            raise InvalidValueError("pitch_deg", self.pitch_deg, "an elevation in (-90, 90) degrees")
        if self.near_m <= 0.0:
            raise InvalidValueError("near_m", self.near_m, "a near plane > 0 metres")
        if self.far_m <= self.near_m:
            raise InvalidValueError("far_m", self.far_m, f"a far plane > near_m ({self.near_m} m)")

    @property
    def position(self) -> np.ndarray:
        """(3,) float64 camera position, metres in the rig frame."""
        yaw, pitch = math.radians(self.yaw_deg), math.radians(self.pitch_deg)
        offset = np.array([math.cos(pitch) * math.sin(yaw), math.sin(pitch), math.cos(pitch) * math.cos(yaw)])
        return np.asarray(self.target, dtype=np.float64) + self.distance_m * offset

    def view_matrix(self) -> np.ndarray:
        """(4, 4) float32 world-to-eye matrix (row-major; eye space looks along -z with +y up)."""
        eye = self.position
        forward = np.asarray(self.target, dtype=np.float64) - eye
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, (0.0, 1.0, 0.0))
        right /= np.linalg.norm(right)  # never zero: |pitch| < 90
        up = np.cross(right, forward)
        view = np.eye(4)
        view[0, :3], view[1, :3], view[2, :3] = right, up, -forward
        view[:3, 3] = -view[:3, :3] @ eye
        return view.astype(np.float32)

    def depth_m(self, points: np.ndarray) -> np.ndarray:
        """(n,) float64 distance in front of the camera (along its view axis), metres, of (n, 3) ``points``.

        >>> Camera(distance_m=2.0).depth_m(np.array([[0.0, -0.03, 0.0]])).tolist()
        [2.0]
        """
        points = np.asarray(points, np.float64).reshape(-1, 3)
        return -(np.c_[points, np.ones(len(points))] @ self.view_matrix().astype(np.float64)[2])

    def projection_matrix(self, aspect: float) -> np.ndarray:
        """(4, 4) float32 OpenGL perspective matrix for an image of ``aspect`` = width / height (> 0)."""
        aspect = _finite("aspect", aspect)
        if aspect <= 0.0:
            raise InvalidValueError("aspect", aspect, "width / height > 0")
        focal = 1.0 / math.tan(math.radians(self.fov_deg) / 2.0)
        near, far = self.near_m, self.far_m
        projection = np.zeros((4, 4))
        projection[0, 0] = focal / aspect
        projection[1, 1] = focal
        projection[2, 2] = (far + near) / (near - far)
        projection[2, 3] = 2.0 * far * near / (near - far)
        projection[3, 2] = -1.0
        return projection.astype(np.float32)

    def project(self, points: np.ndarray, width: int, height: int) -> np.ndarray:
        """Pixel coordinates (x right, y down; (m, 2) float64) of (m, 3) rig-frame ``points`` in metres."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        homogeneous = np.c_[points, np.ones(len(points))]
        clip = homogeneous @ (self.projection_matrix(width / height) @ self.view_matrix()).T.astype(np.float64)
        ndc = clip[:, :2] / clip[:, 3:4]
        return np.c_[(ndc[:, 0] + 1.0) * 0.5 * width, (1.0 - ndc[:, 1]) * 0.5 * height]


VIEW_ANGLES_DEG: dict[str, float] = {"frontal": 0.0, "oblique": 45.0, "lateral": 90.0}
"""View angle name -> camera yaw in degrees toward the character's left."""

STUDY_ANGLES: tuple[str, ...] = ("frontal", "lateral")
"""The view angles of the Broekens study (``oblique`` is mien's addition)."""

VIEW_DISTANCES_M: tuple[float, ...] = (1.0, 3.0)
"""Viewing distances of the Broekens study, metres."""


@dataclass(frozen=True)
class View:
    """One named viewing condition: a view angle at a distance, at :data:`STUDY_FOV_DEG`.

    >>> VIEWS["oblique-3m"].yaw_deg, VIEWS["oblique-3m"].distance_m
    (45.0, 3.0)
    """

    angle: str
    """A key of :data:`VIEW_ANGLES_DEG`: ``"frontal"``, ``"oblique"`` or ``"lateral"``."""
    distance_m: float
    """Camera distance from the target, metres (> 0)."""

    def __post_init__(self) -> None:
        if self.angle not in VIEW_ANGLES_DEG:
            raise UnknownNameError("view angle", self.angle, tuple(VIEW_ANGLES_DEG))
        object.__setattr__(self, "distance_m", _finite("distance_m", self.distance_m))
        if self.distance_m <= 0.0:
            raise InvalidValueError("distance_m", self.distance_m, "a distance > 0 metres")

    @property
    def name(self) -> str:
        """``"<angle>-<distance>m"``, e.g. ``"frontal-1m"``."""
        return f"{self.angle}-{self.distance_m:g}m"

    @property
    def yaw_deg(self) -> float:
        """Camera yaw, degrees toward the character's left."""
        return VIEW_ANGLES_DEG[self.angle]

    @property
    def in_study(self) -> bool:
        """Whether the Broekens study showed this view (frontal or lateral)."""
        return self.angle in STUDY_ANGLES

    @property
    def camera(self) -> Camera:
        """The camera of this view: the profile looks at the middle of the head, the others at the face."""
        target = HEAD_CENTRE_M if self.yaw_deg >= 90.0 else FACE_CENTRE_M
        return Camera(yaw_deg=self.yaw_deg, distance_m=self.distance_m, target=target)


VIEWS: dict[str, View] = {
    view.name: view for view in (View(angle, distance) for angle in VIEW_ANGLES_DEG for distance in VIEW_DISTANCES_M)
}
"""View name -> :class:`View`: ``frontal-1m``, ``frontal-3m``, ``oblique-1m``, ``oblique-3m``, ``lateral-1m``,
``lateral-3m``, all at the study's field of view."""

CAMERA_PRESETS: dict[str, Camera] = {
    **{name: view.camera for name, view in VIEWS.items()},
    "portrait": Camera(yaw_deg=0.0, pitch_deg=0.0, distance_m=0.85, target=(0.0, -0.01, 0.0)),
}
"""Named cameras: one per :data:`VIEWS` entry (the Broekens conditions, frontal / 90-degree lateral from the
character's left at 1 m / 3 m, and the 45-degree oblique views, all at :data:`STUDY_FOV_DEG`) and
``"portrait"``, which frames the whole head for stimuli and contact sheets."""


def camera_from_options(
    preset: str = "frontal-1m",
    yaw_deg: float | None = None,
    pitch_deg: float | None = None,
    distance_m: float | None = None,
    fov_deg: float | None = None,
) -> Camera:
    """The camera ``preset`` (a key of :data:`CAMERA_PRESETS`) with any given parameter overriding it.

    >>> camera_from_options("lateral-1m", distance_m=2.0).distance_m
    2.0
    """
    if preset not in CAMERA_PRESETS:
        raise UnknownNameError("camera preset", preset, tuple(CAMERA_PRESETS))
    overrides: dict[str, Any] = {
        "yaw_deg": yaw_deg,
        "pitch_deg": pitch_deg,
        "distance_m": distance_m,
        "fov_deg": fov_deg,
    }
    return replace(CAMERA_PRESETS[preset], **{k: v for k, v in overrides.items() if v is not None})
