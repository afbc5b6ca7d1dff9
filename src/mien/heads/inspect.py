"""What mien makes of a head: its names, what it cannot show, its landmarks and scale, and a picture of them.

:func:`inspect_head` loads a head the way every job does (:func:`mien.heads.load_head`) and gathers what a user
checks before trusting it: the file's reading (format, eyes, unit, axes, naming convention, matched and
unmatched targets, the ARKit targets it lacks and the AUs that cost), the instrumenting (view, unit, axes, the
inter-ocular distance, how many landmark rays hit the mesh) and a frontal picture with the 68 landmarks drawn.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mien.extras import require
from mien.fileio.streams import atomic_path
from mien.heads.amplitude import MAX_GAIN, calibrate_amplitudes
from mien.heads.instrument import Instrumentation
from mien.heads.registry import file_fingerprint, instrument_head
from mien.heads.synthesize import synthesize_cached
from mien.render.camera import Camera
from mien.render.clip_render import render_still
from mien.rig.files.head import FileRig
from mien.rig.heads import open_head
from mien.rig.model import Rig

__all__ = ["HeadInspection", "inspect_head"]

_PICTURE_PX = 768
_LANDMARK_RGB = (255, 64, 32)


@dataclass(frozen=True, eq=False)
class HeadInspection:
    """A loaded head and what was found on it."""

    spec: str
    """The head as the user named it (a name, ``NAME:IDENTITY`` or a path)."""
    rig: Rig
    """The head in mien's frame, with its landmarks."""
    found: Instrumentation | None
    """What instrumenting found (None for mien's own heads, whose landmarks are built in)."""
    gains: dict[str, float]
    """Factors put on the head's timid targets (:mod:`mien.heads.amplitude`); empty when none."""
    synthesized: tuple[str, ...] = ()
    """ARKit targets the file lacked, made through the feature-point fields (:mod:`mien.heads.synthesize`)."""

    def report(self) -> str:
        """Lines for people: the file's reading, then landmarks and scale."""
        rig = self.rig
        lines = []
        if isinstance(rig, FileRig) and rig.info is not None:
            made = tuple(f"no {name}:" for name in self.synthesized)
            lines += [line for line in rig.info.report().splitlines() if not line.startswith(("landmarks:", *made))]
            if self.synthesized:
                lines.append(
                    f"synthesized ({len(self.synthesized)}, the reference head's moves through the feature-point "
                    f"fields): {', '.join(self.synthesized)}"
                )
        else:
            lines.append(f"head: {self.spec} ({rig.name}, built in: {len(rig.targets)} targets)")
        points = rig.neutral[rig.landmarks].astype(np.float64)
        interocular_mm = float(np.linalg.norm(points[45] - points[36])) * 1000.0
        lines.append(f"vertices: {rig.n_vertices:,}, triangles: {len(rig.faces):,}, morph targets: {len(rig.targets)}")
        if self.found is not None:
            found = self.found
            lines.append(
                f"landmarks: 68 iBUG points found on the head's render (seen from {found.view}, "
                f"{found.hits} of 478 MediaPipe rays hit the mesh)"
            )
            if found.lips_apart:
                lines.append(
                    f"mouth: modelled closed; {found.lips_apart} of 3 inner-lip pairs put one point on each lip, so "
                    "the jaw parts the lips"
                )
            lines.append(
                f"file frame: unit {found.unit}, up {_axis(found.up)}, forward {_axis(found.forward)} "
                f"(the face leans {found.tilt_deg:.1f} degrees from that up)"
            )
        else:
            lines.append("landmarks: 68 iBUG points built into the head")
        height_mm = float(points[27:, 1].max() - points[:17, 1].min()) * 1000.0
        lines.append(
            f"scale: outer eye corners {interocular_mm:.1f} mm apart (adults: about 90), "
            f"nose root to chin {height_mm:.1f} mm"
        )
        if self.gains:
            lines.append(
                f"driven harder, as far as the reference head ({len(self.gains)} targets, at most x{MAX_GAIN}): "
                + ", ".join(f"{name} x{gain:.2f}" for name, gain in sorted(self.gains.items()))
            )
        lines.append(
            "eye centres (m, +x the character's left): "
            + ", ".join(f"({', '.join(f'{v:+.4f}' for v in centre)})" for centre in rig.eye_centers)
        )
        return "\n".join(lines)

    def picture(self, size_px: int = _PICTURE_PX) -> np.ndarray:
        """(size, size, 3) uint8: the head from the front, its 68 landmarks numbered dots."""
        rig = self.rig
        points = rig.neutral[rig.landmarks].astype(np.float64)
        centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
        extent = float(np.ptp(points[:, :2], axis=0).max())
        fov_deg = 22.0
        distance = 0.5 * extent * 1.6 / np.tan(np.radians(fov_deg) / 2.0) + float(points[:, 2].max() - centre[2])
        target = (float(centre[0]), float(centre[1]), float(centre[2]))
        camera = Camera(distance_m=distance, fov_deg=fov_deg, target=target, near_m=0.01)
        image = render_still(rig, None, camera, (size_px, size_px))
        pil_image = require("PIL.Image", "render")
        pil_draw = require("PIL.ImageDraw", "render")
        picture = pil_image.fromarray(image)
        draw = pil_draw.Draw(picture)
        radius = max(2, size_px // 256)
        for number, (x, y) in enumerate(camera.project(points, size_px, size_px)):
            draw.ellipse([x - radius, y - radius, x + radius, y + radius], outline=_LANDMARK_RGB, width=2)
            if number in (0, 8, 16, 17, 26, 27, 30, 36, 45, 48, 54, 62, 66):
                draw.text((x + radius + 1, y - 3 * radius), str(number), fill=_LANDMARK_RGB)
        return np.asarray(picture)

    def save_picture(self, path: str | os.PathLike[str], size_px: int = _PICTURE_PX) -> Path:
        """Write :meth:`picture` as a PNG at ``path`` (atomically); returns the path."""
        pil_image = require("PIL.Image", "render")
        target = Path(path)
        with atomic_path(target) as temporary:
            pil_image.fromarray(self.picture(size_px)).save(temporary, format="PNG")
        return target


def _axis(vector: tuple[float, float, float]) -> str:
    k = int(np.argmax(np.abs(vector)))
    return f"{'+' if vector[k] > 0 else '-'}{'xyz'[k]}"


def inspect_head(
    spec: str, identity: str | None = None, landmarker_model: str | os.PathLike[str] | None = None
) -> HeadInspection:
    """Load the head ``spec`` (see :func:`mien.heads.load_head`) and gather what was found on it."""
    rig = open_head(spec, identity)
    found = None
    gains: dict[str, float] = {}
    made: tuple[str, ...] = ()
    if isinstance(rig, FileRig) and rig.info is not None:
        path = rig.info.path
        rig, found = instrument_head(rig, landmarker_model)
        rig, gains = calibrate_amplitudes(rig)
        rig, made = synthesize_cached(rig, file_fingerprint(path))
    return HeadInspection(spec, rig, found, gains, made)
