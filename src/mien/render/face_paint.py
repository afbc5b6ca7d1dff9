"""Eyebrows, lash lines and lip colour painted on a head from its 68 iBUG landmarks, as a small texture.

The paint lives in the head's own frontal plane: texel (u, v) is the rest position (x, y) of the skin seen
from the front, so every vertex gets texture coordinates from its neutral position and the paint moves with
the skin (a lowered brow carries its brow down). Near 3 mm vertex spacing on the brow ridge (ICT-FaceKit)
is too coarse for per-vertex colours to draw a brow; a texture at :data:`TEXEL_M` is not.

Shapes, all measured from the landmarks (iBUG 17-21 right brow outer -> inner, 22-26 left brow inner ->
outer, 36-47 eye contours, 48-59 outer lip contour):

- brows: a band along a smooth curve through the brow landmarks, thickest at the inner end and tapering to
  the tail (:data:`BROW_HEIGHT_M`), its top edge on the landmarks (iBUG marks a brow's upper contour), with
  soft edges, a softer inner head and fine hair strokes (seeded, so every render is the same);
- lash lines: a dark band on the upper lid margin, widest toward the outer corner, and a faint lower one;
- lips: the vermilion inside the outer lip contour in :data:`LIP_ALBEDO`, with a soft edge.

Only the front of the face takes paint: vertices of region ``face`` (or ``skin``) in front of the jaw
landmarks' depth, so the back of the head, which shares the frontal (x, y), stays bare.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mien.render.cavity import INTERIOR_REGIONS
from mien.rig.model import Rig
from mien.rig.polygon import inside_polygon

__all__ = [
    "BROW_ALBEDO",
    "BROW_HEIGHT_M",
    "LASH_ALBEDO",
    "LIP_ALBEDO",
    "TEXEL_M",
    "FacePaint",
    "face_paint",
]

TEXEL_M = 0.00025
"""Texel size of the paint texture, metres (0.25 mm: about 3 texels per pixel at 1 m, 512 px)."""

BROW_ALBEDO = (0.030, 0.020, 0.014)
"""Linear RGB albedo of brow hair (dark brown)."""

LASH_ALBEDO = (0.015, 0.011, 0.009)
"""Linear RGB albedo of the lash line (near black)."""

LIP_ALBEDO = (0.46, 0.15, 0.14)
"""Linear RGB albedo of the lips' vermilion."""

BROW_HEIGHT_M = ((0.0, 0.0085), (0.2, 0.0085), (0.55, 0.0068), (0.85, 0.0040), (1.0, 0.0018))
"""Brow height along the brow, (fraction of its length from the inner end, height in metres)."""

UPPER_LASH_HEIGHT_M = ((0.0, 0.0005), (0.3, 0.0013), (0.75, 0.0021), (1.0, 0.0019))
"""Upper lash-line width above the lid margin, (fraction from the inner corner, metres)."""

LOWER_LASH_HEIGHT_M = 0.0005
"""Lower lash-line width below the lid margin, metres."""

BROW_EDGE_M = 0.0005
"""Half-width of the soft edge of a brow, metres."""

LASH_EDGE_M = 0.0002
"""Half-width of the soft edge of a lash line, metres."""

LIP_EDGE_M = 0.0006
"""Half-width of the soft edge of the lips' vermilion, metres."""

BROW_HEAD_FRACTION = 0.12
"""Fraction of a brow's length, from its inner end, over which its opacity rises to full and its top edge
rounds off."""

Height = float | Callable[[np.ndarray], np.ndarray]
"""A band's height in metres: constant, or a function of the (k,) fractions along its curve."""

Detail = Callable[[np.ndarray, np.ndarray], np.ndarray]
"""Opacity factors (k,) of (k, 2) texel centres (metres) at (k,) fractions along a band's curve."""

_CACHE: weakref.WeakKeyDictionary[Rig, dict[int, FacePaint | None]] = weakref.WeakKeyDictionary()
"""Paint already made for a rig (rigs are immutable), by seed: painting takes a few tenths of a second."""

_PAINT_DEPTH_RAMP_M = 0.01
"""Paint fades in over this depth in front of the jaw landmarks (iBUG 0 and 16)."""


@dataclass(frozen=True, eq=False)
class FacePaint:
    """A paint texture over a rig's skin and where each vertex samples it."""

    texture: np.ndarray
    """(height, width, 4) float32 premultiplied linear RGB albedo and opacity, 0..1; row 0 is v = 0."""
    texcoords: np.ndarray
    """(n_vertices, 3) float32: u, v in 0..1 and how strongly the paint applies at the vertex, 0..1."""


def _smoothstep(edge0: float, edge1: float, x: np.ndarray) -> np.ndarray:
    t = np.clip((x - edge0) / (edge1 - edge0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def _catmull_rom(points: np.ndarray, n_samples: int, closed: bool = False) -> np.ndarray:
    """(n_samples, 2) points on a uniform Catmull-Rom spline through (k, 2) ``points``."""
    if closed:
        padded = np.vstack([points[-1:], points, points[:2]])
    else:
        padded = np.vstack([2 * points[0] - points[1], points, 2 * points[-1] - points[-2]])
    n_segments = len(points) if closed else len(points) - 1
    s = np.linspace(0.0, n_segments, n_samples, endpoint=not closed)
    index = np.minimum(s.astype(np.int64), n_segments - 1)
    t = (s - index)[:, None]
    p0, p1, p2, p3 = (padded[index + k] for k in range(4))
    return 0.5 * (2 * p1 + (p2 - p0) * t + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t**2 + (3 * p1 - p0 - 3 * p2 + p3) * t**3)


def _nearest_on_curve(points: np.ndarray, curve: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For (k, 2) points and an (m, 2) sampled curve: (fraction along the curve (k,), signed offset along the
    curve's left normal (k,), signed distance past the curve's nearer end (k,), negative inside), metres."""
    segment = np.diff(curve, axis=0)
    length = np.linalg.norm(segment, axis=1)
    cumulative = np.concatenate([[0.0], np.cumsum(length)])
    best = np.full(len(points), np.inf)
    fraction = np.zeros(len(points))
    offset = np.zeros(len(points))
    beyond = np.zeros(len(points))
    for i in range(len(segment)):
        direction = segment[i] / max(length[i], 1e-12)
        relative = points - curve[i]
        along = relative @ direction
        clamped = np.clip(along, 0.0, length[i])
        across = relative[:, 1] * direction[0] - relative[:, 0] * direction[1]
        distance = np.hypot(along - clamped, across)
        closer = distance < best
        best[closer] = distance[closer]
        fraction[closer] = (cumulative[i] + clamped[closer]) / cumulative[-1]
        offset[closer] = across[closer]
        if i == 0:
            beyond[closer] = -along[closer]
        elif i == len(segment) - 1:
            beyond[closer] = along[closer] - length[i]
        else:
            beyond[closer] = -np.inf
    return fraction, offset, beyond


def _profile(table: tuple[tuple[float, float], ...], fraction: np.ndarray) -> np.ndarray:
    xs, ys = zip(*table, strict=True)
    return np.interp(fraction, xs, ys)


class _Canvas:
    """A premultiplied RGBA float texture over a frontal (x, y) window, painted back to front."""

    def __init__(self, lower: np.ndarray, upper: np.ndarray) -> None:
        self.origin = lower
        self.shape = (int(np.ceil((upper[1] - lower[1]) / TEXEL_M)), int(np.ceil((upper[0] - lower[0]) / TEXEL_M)))
        self.rgba = np.zeros((*self.shape, 4), np.float32)

    def window(self, lower: np.ndarray, upper: np.ndarray) -> tuple[tuple[slice, slice], np.ndarray]:
        """Texel slices covering the (x, y) box and the (k, 2) centres of those texels, metres."""
        i0, j0 = np.floor((lower - self.origin) / TEXEL_M).astype(int)
        i1, j1 = np.ceil((upper - self.origin) / TEXEL_M).astype(int)
        cols = slice(max(i0, 0), min(i1, self.shape[1]))
        rows = slice(max(j0, 0), min(j1, self.shape[0]))
        x = self.origin[0] + (np.arange(cols.start, cols.stop) + 0.5) * TEXEL_M
        y = self.origin[1] + (np.arange(rows.start, rows.stop) + 0.5) * TEXEL_M
        gx, gy = np.meshgrid(x, y)
        return (rows, cols), np.column_stack([gx.ravel(), gy.ravel()])

    def over(self, region: tuple[slice, slice], alpha: np.ndarray, albedo: tuple[float, float, float]) -> None:
        """Composite ``albedo`` at opacity ``alpha`` (flat, per texel of ``region``) over the canvas."""
        target = self.rgba[region]
        a = alpha.reshape(target.shape[:2])[..., None].astype(np.float32)
        color = np.append(np.asarray(albedo, np.float32), 1.0)
        target *= 1.0 - a
        target += a * color


def _paint_band(
    canvas: _Canvas,
    curve: np.ndarray,
    above: Height,
    below: Height,
    albedo: tuple[float, float, float],
    opacity: float,
    edge: float,
    detail: Detail | None = None,
) -> None:
    """Paint a band ``above`` / ``below`` the (m, 2) ``curve`` (heights in metres, or functions of the
    fraction along the curve giving them), with soft edges ``edge`` metres wide on either side."""
    margin = 0.011
    region, points = canvas.window(curve.min(axis=0) - margin, curve.max(axis=0) + margin)
    fraction, offset, beyond = _nearest_on_curve(points, curve)
    # Offsets are positive to the curve's left; make them positive upward (+y) whichever way it runs.
    offset = offset * (1.0 if np.mean(np.diff(curve[:, 0])) > 0 else -1.0)
    top = above(fraction) if callable(above) else np.full(len(points), above)
    bottom = below(fraction) if callable(below) else np.full(len(points), below)
    inside = np.minimum(top - offset, offset + bottom)
    alpha = _smoothstep(-edge, edge, inside) * _smoothstep(edge, -edge, beyond) * opacity
    if detail is not None:
        alpha = alpha * detail(points, fraction)
    canvas.over(region, alpha, albedo)


def _brow_hairs(curve: np.ndarray, rng: np.random.Generator) -> Detail:
    """A detail function: opacity 0.8..1 from short hair strokes slanting up and outward at the inner end and
    lying along the brow toward the tail."""

    def detail(points: np.ndarray, fraction: np.ndarray) -> np.ndarray:
        tangent = np.gradient(curve, axis=0)
        tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
        sample = np.clip((fraction * (len(curve) - 1)).astype(int), 0, len(curve) - 1)
        along = tangent[sample]
        # Hair direction: rotate the tangent (inner -> outer) up by 70 degrees at the head, 10 at the tail.
        angle = np.radians(70.0 - 60.0 * np.clip(fraction / 0.5, 0.0, 1.0))
        up_sign = 1.0 if np.mean(np.diff(curve[:, 0])) > 0 else -1.0
        cos, sin = np.cos(angle * up_sign), np.sin(angle * up_sign)
        hair = np.column_stack([along[:, 0] * cos - along[:, 1] * sin, along[:, 0] * sin + along[:, 1] * cos])
        phase = rng.uniform(0.0, 2 * np.pi, 3)
        across = points[:, 0] * -hair[:, 1] + points[:, 1] * hair[:, 0]
        stripes = np.sin(across * 2 * np.pi / 0.0006 + phase[0]) + 0.6 * np.sin(across * 2 * np.pi / 0.00043 + phase[1])
        head = 0.35 + 0.65 * _smoothstep(0.0, BROW_HEAD_FRACTION, fraction)
        return np.asarray(head * (0.9 + 0.1 * np.tanh(1.5 * stripes)))

    return detail


def face_paint(rig: Rig, seed: int = 0) -> FacePaint | None:
    """Brows, lash lines and lip colour for ``rig`` (see the module doc), or None when it has none to get.

    None when the rig paints itself (``vertex_colors``) or its landmarks are degenerate (brows less than 2 cm
    wide). ``seed`` fixes the brows' hair strokes. The result is cached per rig and seed (its arrays are read-only).
    """
    cached = _CACHE.setdefault(rig, {})
    if seed not in cached:
        cached[seed] = _paint(rig, seed)
    return cached[seed]


def _paint(rig: Rig, seed: int) -> FacePaint | None:
    if rig.vertex_colors is not None or len(rig.landmarks) != 68:
        return None
    points = rig.neutral[np.asarray(rig.landmarks, np.int64)].astype(np.float64)
    xy = points[:, :2]
    if np.ptp(xy[17:22, 0]) < 0.02 or np.ptp(xy[22:27, 0]) < 0.02 or np.ptp(xy[48:60, 0]) < 0.01:
        return None
    rng = np.random.default_rng(seed)
    brows = [_catmull_rom(xy[21:16:-1], 48), _catmull_rom(xy[22:27], 48)]  # inner -> outer
    upper_lids = [_catmull_rom(xy[[39, 38, 37, 36]], 32), _catmull_rom(xy[[42, 43, 44, 45]], 32)]
    lower_lids = [_catmull_rom(xy[[39, 40, 41, 36]], 32), _catmull_rom(xy[[42, 47, 46, 45]], 32)]
    lips = _catmull_rom(xy[48:60], 96, closed=True)
    margin = 0.01
    lower = np.minimum.reduce([c.min(axis=0) for c in (*brows, lips)]) - margin
    upper = np.maximum.reduce([c.max(axis=0) for c in (*brows, lips)]) + margin
    canvas = _Canvas(lower, upper)

    region, texels = canvas.window(lips.min(axis=0) - 0.004, lips.max(axis=0) + 0.004)
    distance = np.min(np.linalg.norm(texels[:, None] - lips[None], axis=2), axis=1)
    signed = np.where(inside_polygon(texels, lips), distance, -distance)
    canvas.over(region, _smoothstep(-LIP_EDGE_M, LIP_EDGE_M, signed), LIP_ALBEDO)

    for lid in upper_lids:
        _paint_band(canvas, lid, lambda f: _profile(UPPER_LASH_HEIGHT_M, f), 0.0003, LASH_ALBEDO, 0.95, LASH_EDGE_M)
    for lid in lower_lids:
        _paint_band(canvas, lid, 0.0001, LOWER_LASH_HEIGHT_M, LASH_ALBEDO, 0.4, LASH_EDGE_M)
    for brow in brows:
        # iBUG's brow points trace the brow's upper contour: the band hangs below them.
        _paint_band(
            canvas,
            brow,
            # The top edge rounds down into the inner end (a brow's head is not cut square).
            lambda f: 0.0006 - 0.0025 * (1.0 - _smoothstep(0.0, BROW_HEAD_FRACTION, f)) ** 2,
            lambda f: _profile(BROW_HEIGHT_M, f) - 0.0006,
            BROW_ALBEDO,
            0.97,
            BROW_EDGE_M,
            detail=_brow_hairs(brow, rng),
        )

    texcoords = np.zeros((rig.n_vertices, 3), np.float32)
    size = np.array(canvas.shape[::-1], np.float64) * TEXEL_M
    texcoords[:, :2] = (rig.neutral[:, :2] - canvas.origin) / size
    paintable = rig.regions.get("face", rig.regions.get("skin"))
    if paintable is not None:
        ids = np.asarray(paintable, np.int64)
        jaw_depth = float(min(points[0, 2], points[16, 2]))
        texcoords[ids, 2] = _smoothstep(jaw_depth, jaw_depth + _PAINT_DEPTH_RAMP_M, rig.neutral[ids, 2])
    for name in INTERIOR_REGIONS:  # a head file's "skin" holds its mouth socket: paint stays on the lips' face
        if name in rig.regions:
            texcoords[np.asarray(rig.regions[name], np.int64), 2] = 0.0
    # Transparent border texels: clamping outside the canvas samples nothing.
    canvas.rgba[[0, -1]] = 0.0
    canvas.rgba[:, [0, -1]] = 0.0
    canvas.rgba.flags.writeable = False
    texcoords.flags.writeable = False
    return FacePaint(texture=canvas.rgba, texcoords=texcoords)
