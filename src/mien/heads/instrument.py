"""Instrumenting a head nobody measured: landmarks, size, axes and unit found on the mesh itself.

A user's character arrives without the facts mien's jobs need: where its face landmarks are, how big the face
is, which way is up and forward, and whether the file is in metres or centimetres. :func:`instrument` finds
them the way a person would look: it renders the bare mesh, finds MediaPipe's 478 face landmarks on the
picture, casts each back onto the mesh (the nearest surface hit along the camera ray), and derives

- the iBUG-68 landmark points and vertices (:mod:`mien.tracking.ibug68`), which drive the feature-point rig
  (Table 1 on the user's face), the validation crops and the camera presets;
- the face's size: the inter-ocular distance (outer eye corners, iBUG 36 and 45) in file units;
- its up and forward axes, measured from the landmarks and snapped to the file's nearest axes;
- its unit: the one of metres, centimetres, millimetres or inches that makes the inter-ocular distance human
  (:data:`HUMAN_INTEROCULAR_M`), or an error when none does.

The search tries the six axis-aligned viewing directions (glTF's +z forward / +y up first), frames the whole
mesh, then re-frames on the face it found for a precise second look. Results are cached per file hash
(:func:`instrument_cached`), written atomically, so a second call costs a file read.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass

import numpy as np

from mien.errors import InvalidValueError, MienError
from mien.fileio.streams import write_bytes
from mien.paths import cache_dir
from mien.render.camera import Camera
from mien.render.clip_render import FrameRenderer
from mien.render.offscreen import OffscreenRenderer
from mien.rig.topology import vertex_components
from mien.tracking.ibug68 import ibug68
from mien.tracking.landmarker import Landmarker

__all__ = [
    "HUMAN_INTEROCULAR_M",
    "INSTRUMENT_VERSION",
    "UNITS",
    "FaceNotFoundError",
    "Instrumentation",
    "instrument",
    "instrument_cached",
]

INSTRUMENT_VERSION = 9
"""Bumped when the method changes, so cached results of an older method are recomputed."""

HUMAN_INTEROCULAR_M = 0.090
"""Adult distance between the outer eye corners (exocanthion to exocanthion), metres: about 86-94 mm
(Farkas, *Anthropometry of the Head and Face*, 1994); the yardstick that tells a file's unit."""

UNITS: dict[str, float] = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}
"""Units a head file may be written in, and the factor that turns one of them into metres."""

_UNIT_TOLERANCE = 1.6
"""A unit is accepted when the face's inter-ocular distance in it is within this factor of the human one."""

_RENDER_PX = 640
_OUTLINE_DEPTH = 1.2
"""How far behind the nose tip a face's outline (the jaw line seen from the front) may lie, as a fraction of the
outer eye corners' distance: ICT-FaceKit's ear-level jaw points lie 1.06 of it behind."""
_CLOSE_MARGINS = (0.12, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4)
"""Margins of the closer looks around the face first found, as fractions of its size. MediaPipe places a bare
face's landmarks a little differently at each framing; the medoid (:func:`_medoid`) of seven looks rather than
the mean of three (0.15, 0.25, 0.35) takes the found iBUG-68 vertices of ICT written by Blender from 2.56 to
2.54 mm from ICT's own (median; eyes 1.99 to 0.90), of ICT's identity b from 2.55 to 2.49 mm and of the built-in
head from 6.05 to 5.34 mm. (Seven looks' mean: 2.40, 2.54 and 5.44 mm, but points off the surface.)"""
_FOV_DEG = 20.0
_SKIN_REACH = 0.15
"""How far behind a landmark ray's first hit its skin hit may lie to be taken instead, as a fraction of the
outer eye corners' distance: 13.5 mm on an adult, further than lashes stand off the lids (ICT-FaceKit's outer
lashes: 10.6 mm in front of the eye corner), nearer than the socket behind an eyeball. On ICT written by Blender
it moves the eye corners from 4.2 and 6.8 mm off ICT's own to 1.9 and 0.9 mm."""
_AXES = {"+x": (1, 0, 0), "-x": (-1, 0, 0), "+y": (0, 1, 0), "-y": (0, -1, 0), "+z": (0, 0, 1), "-z": (0, 0, -1)}
_VIEWS: tuple[tuple[str, str], ...] = (
    ("+z", "+y"), ("-z", "+y"), ("-y", "+z"), ("+y", "+z"), ("+x", "+y"), ("-x", "+y"),
    ("+x", "+z"), ("-x", "+z"), ("+z", "-y"), ("-z", "-y"), ("-y", "-z"), ("+y", "-z"),
)  # fmt: skip
"""(forward, up) pairs tried in turn: glTF/VRM (+z forward, +y up), then Blender-style Z-up files, then sideways."""


class FaceNotFoundError(MienError, ValueError):
    """No face was found on the mesh from any direction."""


@dataclass(frozen=True)
class Instrumentation:
    """What :func:`instrument` found on a head, in the file's own frame and unit."""

    landmarks478: np.ndarray
    """(478, 3) float32 surface points of MediaPipe's landmarks, file units and axes."""
    ibug68_points: np.ndarray
    """(68, 3) float32 iBUG-68 points (:func:`mien.tracking.ibug68.ibug68` of the 478), file units."""
    ibug68_vertices: np.ndarray
    """(68,) int32 the mesh vertex nearest each iBUG-68 point."""
    interocular: float
    """Distance between the outer eye corners (iBUG 36 and 45), file units."""
    unit: str
    """The file's unit, a key of :data:`UNITS`."""
    up: tuple[float, float, float]
    """The face's up axis, snapped to the nearest file axis (unit vector)."""
    forward: tuple[float, float, float]
    """The direction the face looks, snapped to the nearest file axis (unit vector)."""
    tilt_deg: float
    """Angle between the measured face up (chin to brow) and the snapped up axis, degrees (a head modelled
    looking slightly down shows a few degrees)."""
    hits: int
    """How many of the 478 landmark rays hit the mesh (the rest are taken from their neighbours)."""
    view: str
    """The viewing direction that found the face, ``"forward/up"`` (e.g. ``"+z/+y"``)."""
    lips_apart: int = 0
    """How many inner-lip pairs of a mouth modelled closed were put on their own lips (0..3; :func:`_lip_sides`)."""

    @property
    def metres_per_unit(self) -> float:
        """Factor from file units to metres."""
        return UNITS[self.unit]

    def rotation(self) -> np.ndarray:
        """(3, 3) float64 rotation from the file's axes to mien's (+x character's left, +y up, +z forward)."""
        up = np.asarray(self.up, np.float64)
        forward = np.asarray(self.forward, np.float64)
        left = np.cross(up, forward)  # the character's left = up x forward in a right-handed frame
        return np.stack([left, up, forward])

    def to_json(self) -> str:
        """A JSON text of every field (arrays as lists)."""
        values = {key: v.tolist() if isinstance(v, np.ndarray) else v for key, v in asdict(self).items()}
        return json.dumps({"version": INSTRUMENT_VERSION, **values})

    @classmethod
    def from_json(cls, text: str) -> Instrumentation:
        """Read what :meth:`to_json` wrote; :class:`InvalidValueError` for another version or a broken text."""
        try:
            data = json.loads(text)
            if data.pop("version") != INSTRUMENT_VERSION:
                raise InvalidValueError("instrumentation cache", "an older version", "recomputed")
            return cls(
                landmarks478=np.asarray(data["landmarks478"], np.float32).reshape(478, 3),
                ibug68_points=np.asarray(data["ibug68_points"], np.float32).reshape(68, 3),
                ibug68_vertices=np.asarray(data["ibug68_vertices"], np.int32).reshape(68),
                interocular=float(data["interocular"]),
                unit=str(data["unit"]),
                up=tuple(float(v) for v in data["up"]),  # type: ignore[arg-type]
                forward=tuple(float(v) for v in data["forward"]),  # type: ignore[arg-type]
                tilt_deg=float(data["tilt_deg"]),
                hits=int(data["hits"]),
                view=str(data["view"]),
                lips_apart=int(data["lips_apart"]),
            )
        except (KeyError, TypeError, ValueError) as error:
            if isinstance(error, InvalidValueError):
                raise
            raise InvalidValueError("instrumentation cache", type(error).__name__, "a complete JSON record") from None


def _frame(forward: str, up: str) -> np.ndarray:
    """(3, 3) rotation taking file axes to a viewing frame whose +z is ``forward`` and +y is ``up``."""
    f = np.asarray(_AXES[forward], np.float64)
    u = np.asarray(_AXES[up], np.float64)
    return np.stack([np.cross(u, f), u, f])


_CAMERA = Camera(
    distance_m=0.5 * 0.25 * 1.15 / math.tan(math.radians(_FOV_DEG) / 2.0),
    fov_deg=_FOV_DEG,
    target=(0.0, 0.0, 0.0),
    near_m=0.01,
)
"""The one camera of every look: a head 0.25 m across fills most of the picture (the head is moved to it)."""


def _placement(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Where to put ``points`` (viewing frame) before :data:`_CAMERA`: ``(offset, scale)``, the points moved to
    ``(points - offset) * scale`` so that their larger extent is 0.25 m (a head) centred on the camera's axis,
    with their front where the camera's target is (one camera and renderer serve every framing)."""
    low, high = points.min(axis=0), points.max(axis=0)
    centre = 0.5 * (low + high)
    extent = float(max(high[0] - low[0], high[1] - low[1], 1e-12))
    scale = 0.25 / extent
    return np.array([centre[0], centre[1], high[2]]), scale


_CELL_PX = 8.0
"""Side of the picture's grid cells that :func:`_cast` files the triangles under, pixels."""


def _cast(pixels: np.ndarray, faces: np.ndarray, targets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each (k, 2) target pixel, the nearest triangle covering it: ``(face ids (k,), barycentric (k, 3))``.

    Screen-space barycentric coordinates with a depth test (the triangles are small on the picture, so the
    missing perspective correction is far below a pixel). A pixel no triangle covers gets face id -1. The
    triangles are filed under the grid cells (:data:`_CELL_PX`) their bounding boxes overlap, so each target is
    tested against its own cell's few triangles, all targets at once; of equally near triangles the first wins.
    """
    targets = np.asarray(targets, np.float64).reshape(-1, 2)
    ids = np.full(len(targets), -1, np.int64)
    weights = np.zeros((len(targets), 3))
    if not len(targets) or not len(faces):
        return ids, weights
    a, b, c = pixels[faces[:, 0]], pixels[faces[:, 1]], pixels[faces[:, 2]]
    low = np.minimum(np.minimum(a[:, :2], b[:, :2]), c[:, :2])
    high = np.maximum(np.maximum(a[:, :2], b[:, :2]), c[:, :2])

    def cell_of(xy: np.ndarray) -> np.ndarray:
        return np.floor(xy / _CELL_PX).astype(np.int64)

    target_cells = cell_of(targets)
    first, last = target_cells.min(axis=0), target_cells.max(axis=0)
    # triangles' cell ranges, clipped to the targets' cells (a triangle far off the picture files nowhere)
    from_cell = np.maximum(cell_of(np.nan_to_num(low, nan=np.inf)), first)
    to_cell = np.minimum(cell_of(np.nan_to_num(high, nan=-np.inf)), last)
    span = to_cell - from_cell + 1
    filed = np.flatnonzero((span > 0).all(axis=1))
    if not len(filed):
        return ids, weights
    width, height = span[filed, 0], span[filed, 1]
    counts = width * height
    triangle = np.repeat(filed, counts)
    step = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
    columns = last[1] - first[1] + 1
    cell_x = from_cell[triangle, 0] + step % np.repeat(width, counts) - first[0]
    cell_y = from_cell[triangle, 1] + step // np.repeat(width, counts) - first[1]
    order = np.lexsort((triangle, cell_x * columns + cell_y))
    keys, triangle = (cell_x * columns + cell_y)[order], triangle[order]
    wanted = (target_cells[:, 0] - first[0]) * columns + (target_cells[:, 1] - first[1])
    start, stop = np.searchsorted(keys, wanted, "left"), np.searchsorted(keys, wanted, "right")
    n = stop - start
    pair_target = np.repeat(np.arange(len(targets)), n)
    pair_face = triangle[np.repeat(start, n) + np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)]
    # the bounding-box test of the triangle against its target, then barycentric coordinates
    x, y = targets[pair_target, 0], targets[pair_target, 1]
    box = (low[pair_face, 0] <= x) & (x <= high[pair_face, 0]) & (low[pair_face, 1] <= y) & (y <= high[pair_face, 1])
    pair_target, pair_face = pair_target[box], pair_face[box]
    pa, pb, pc = a[pair_face], b[pair_face], c[pair_face]
    v0, v1 = pb[:, :2] - pa[:, :2], pc[:, :2] - pa[:, :2]
    v2 = targets[pair_target] - pa[:, :2]
    det = v0[:, 0] * v1[:, 1] - v1[:, 0] * v0[:, 1]
    ok = np.abs(det) > 1e-12
    safe = np.where(ok, det, 1.0)
    w1 = (v2[:, 0] * v1[:, 1] - v1[:, 0] * v2[:, 1]) / safe
    w2 = (v0[:, 0] * v2[:, 1] - v2[:, 0] * v0[:, 1]) / safe
    w0 = 1.0 - w1 - w2
    inside = ok & (w0 >= -1e-6) & (w1 >= -1e-6) & (w2 >= -1e-6)
    depth = w0 * pa[:, 2] + w1 * pb[:, 2] + w2 * pc[:, 2]
    hit = np.flatnonzero(inside & (depth > 0) & np.isfinite(depth))
    if not len(hit):
        return ids, weights
    # per target, the nearest hit (ties: the lowest face id)
    best = hit[np.lexsort((pair_face[hit], depth[hit], pair_target[hit]))]
    best = best[np.r_[True, np.diff(pair_target[best]) != 0]]
    ids[pair_target[best]] = pair_face[best]
    weights[pair_target[best]] = np.stack([w0[best], w1[best], w2[best]], axis=1)
    return ids, weights


RendererFactory = Callable[[Camera, int], FrameRenderer]
"""Makes the renderer of the looks: ``(camera, size in pixels) -> OffscreenRenderer`` of the head's faces."""


def _bare(faces: np.ndarray) -> RendererFactory:
    def make(camera: Camera, size: int) -> FrameRenderer:
        return OffscreenRenderer(faces, size, size, camera, samples=4, cull_back_faces=False)

    return make


def _prefer_skin(
    pixels: np.ndarray,
    placed: np.ndarray,
    faces: np.ndarray,
    targets: np.ndarray,
    skin: np.ndarray,
    ids: np.ndarray,
    weights: np.ndarray,
) -> None:
    """Move the hits of landmark rays that met a see-through part in front of the skin (lashes, an eye's
    occlusion shell, a tear line) onto the skin just behind it, in place.

    ``pixels`` (n, 3) are the vertices on the picture with their depth, ``placed`` (n, 3) the same vertices in
    the camera's space (the depth's unit); ``skin`` (m,) bool marks the skin's triangles. A ray's skin hit is
    taken when it lies at most :data:`_SKIN_REACH` of the face's size (outer eye corners, MediaPipe 33 and 263)
    behind its first hit, so a lid point seen on the lashes lands on the lid, and one seen on the eyeball (whose
    skin lies far behind, in the socket) stays where it is.
    """
    first = ids >= 0
    if not first[[33, 263]].all():
        return
    depth = np.einsum("kj,kj->k", weights, pixels[faces[np.maximum(ids, 0)], 2])
    corners = np.einsum("kj,kjd->kd", weights[[33, 263]], placed[faces[ids[[33, 263]]]])
    reach = _SKIN_REACH * float(np.linalg.norm(corners[0] - corners[1]))
    off_skin = np.flatnonzero(first & ~skin[np.maximum(ids, 0)])
    if not len(off_skin):
        return
    skin_ids = np.flatnonzero(skin)
    found, found_weights = _cast(pixels, faces[skin_ids], targets[off_skin])
    found_depth = np.einsum("kj,kj->k", found_weights, pixels[faces[skin_ids[np.maximum(found, 0)]], 2])
    take = (found >= 0) & (found_depth - depth[off_skin] <= reach)
    ids[off_skin[take]] = skin_ids[found[take]]
    weights[off_skin[take]] = found_weights[take]


def _jaw_on_skin(
    pixels: np.ndarray,
    placed: np.ndarray,
    faces: np.ndarray,
    targets: np.ndarray,
    skin: np.ndarray,
    ids: np.ndarray,
    weights: np.ndarray,
) -> None:
    """Move the iBUG jaw points (rows 478 to 494 of ``targets``) whose ray passed the face's outline onto it, in
    place (arguments as :func:`_prefer_skin`).

    The jaw line is the face's outline, so its rays graze the skin: one drawn a pixel outside it meets the hair or
    the back of the head far behind (on a VALID avatar 18 cm behind the cheek). A jaw point whose hit is not skin,
    or lies more than :data:`_OUTLINE_DEPTH` of the face's size behind the nose tip, is walked a pixel at a time
    toward the nose tip (iBUG 30) to the first skin within that depth: the outline seen from the front.
    """
    jaw = 478 + np.arange(17)
    tip, corners = 478 + 30, [33, 263]
    if ids[tip] < 0 or (ids[corners] < 0).any():
        return
    depth_of = lambda k: float(weights[k] @ pixels[faces[ids[k]], 2])  # noqa: E731
    corner_points = np.einsum("kj,kjd->kd", weights[corners], placed[faces[ids[corners]]])
    deepest = depth_of(tip) + _OUTLINE_DEPTH * float(np.linalg.norm(corner_points[0] - corner_points[1]))
    skin_ids = np.flatnonzero(skin)
    skin_faces = faces[skin_ids]
    for k in jaw:
        if ids[k] >= 0 and skin[ids[k]] and depth_of(k) <= deepest:
            continue
        inward = targets[tip] - targets[k]
        steps = int(np.ceil(np.linalg.norm(inward)))
        path = targets[k] + np.outer(np.arange(1, steps) / max(steps, 1), inward)
        found, found_weights = _cast(pixels, skin_faces, path)
        depth = np.einsum("kj,kj->k", found_weights, pixels[skin_faces[np.maximum(found, 0)], 2])
        near = np.flatnonzero((found >= 0) & (depth <= deepest))
        if len(near):
            ids[k] = skin_ids[found[near[0]]]
            weights[k] = found_weights[near[0]]


def _look(
    landmarker: Landmarker,
    vertices: np.ndarray,
    faces: np.ndarray,
    rotation: np.ndarray,
    around: np.ndarray,
    drawing: FrameRenderer,
    skin: np.ndarray | None = None,
) -> tuple[np.ndarray, int] | None:
    """Draw ``vertices`` with ``drawing`` (made for :data:`_CAMERA`) seen along ``rotation`` framing the points
    ``around`` (file frame) and find the face.

    ``skin`` (m,) bool, the skin's triangles when known: rays that meet a see-through part first land on the
    skin behind it (:func:`_prefer_skin`). Returns ``(surface points in the file frame, rays that hit)``: the
    478 landmarks' then the 68 iBUG points' (546, 3), and how many of the 478 rays hit; or None when no face is
    on the picture.
    """
    viewed = vertices @ rotation.T
    camera = _CAMERA
    offset, scale = _placement(around @ rotation.T)
    placed = ((viewed - offset) * scale).astype(np.float32)
    image = drawing.render(placed)
    found = landmarker.detect(image)
    if found is None:
        return None
    marks = found.landmarks[:, :2].astype(np.float64) * _RENDER_PX
    # the iBUG points are placed on the picture (where 300-W spaces them, along the contours drawn) and cast
    # themselves, rather than averaged from the 478's surface points (a mean of two may lie inside the head)
    targets = np.vstack([marks, ibug68(marks)])
    pixels = np.c_[camera.project(placed, _RENDER_PX, _RENDER_PX), camera.depth_m(placed)]
    face_ids, weights = _cast(pixels, faces, targets)
    hit = face_ids >= 0
    if hit[:478].sum() < 400:  # most of the face missed: the picture showed something else (or a very open mesh)
        return None
    if skin is not None:
        _prefer_skin(pixels, placed, faces, targets, skin, face_ids, weights)
        _jaw_on_skin(pixels, placed, faces, targets, skin, face_ids, weights)
        hit = face_ids >= 0
    points = np.zeros((len(targets), 3))
    points[hit] = np.einsum("kj,kjd->kd", weights[hit], vertices[faces[face_ids[hit]]])
    if not hit.all():  # a landmark off the mesh (a hole, an eye with no cornea): take the nearest hit one's
        from_pixels = targets[hit]
        for k in np.flatnonzero(~hit):
            points[k] = points[hit][int(np.argmin(np.linalg.norm(from_pixels - targets[k], axis=1)))]
    return points, int(hit[:478].sum())


def _medoid(looks: np.ndarray) -> np.ndarray:
    """(k, 3) of (n, k, 3) points found by n looks: for each point the look's that lies nearest the other looks'
    (least summed distance). A found point stays a point on the surface: a mean of the looks' may lie inside it
    (seven looks' mean put a VALID avatar's mouth corners 1 mm into the crease between the lips)."""
    spread = np.linalg.norm(looks[:, None] - looks[None, :], axis=-1).sum(axis=1)  # (n, k)
    return looks[np.argmin(spread, axis=0), np.arange(looks.shape[1])]


_INNER_LIPS: tuple[tuple[int, int], ...] = ((61, 67), (62, 66), (63, 65))
"""The iBUG inner-lip pairs that face each other across the mouth slit: (upper lip point, lower lip point)."""
_SEAM_REACH = 0.1
"""Radius of the skin looked at around a closed mouth's seam, as a share of the inter-ocular distance (9 mm on an
adult face: both lips, and not the nose or the chin)."""


def _lip_sides(
    vertices: np.ndarray, faces: np.ndarray, skin: np.ndarray, points68: np.ndarray, ids: np.ndarray, up: np.ndarray
) -> int:
    """Put each inner-lip landmark vertex of ``ids`` (68,) on its own lip, in place; returns how many pairs moved.

    A mouth modelled closed (every VALID avatar) has its lips meeting: MediaPipe puts the upper and lower inner-lip
    points on the same spot of the picture, and the nearest vertex to both is one vertex of one lip. The
    feature-point rig then moves that vertex with both lips, and an opening jaw stretches the lips shut into a
    balloon instead of parting them. Around the seam (within :data:`_SEAM_REACH` of the face's size) the skin
    falls into pieces joined by no triangle: the upper lip, the lower lip. When a pair's two vertices lie on one
    piece, the upper point takes the nearest vertex of the nearest piece above the seam (along ``up``) and the
    lower point that of the nearest piece below. A mouth modelled open (ICT-FaceKit) already has its points on
    two pieces and is left as it is; so is one whose lips are welded into one piece (nothing parts them).
    """
    reach = _SEAM_REACH * float(np.linalg.norm(points68[45] - points68[36]))
    moved = 0
    for upper, lower in _INNER_LIPS:
        seam = (points68[upper] + points68[lower]) / 2
        distance = np.linalg.norm(vertices - seam, axis=1)
        near = skin & (distance < reach)
        pieces = vertex_components(len(vertices), faces[near[faces].all(axis=1)])
        if not (near[ids[upper]] and near[ids[lower]]) or pieces[ids[upper]] != pieces[ids[lower]]:
            continue
        sides: dict[bool, int] = {}
        for piece in np.unique(pieces[near]):
            members = np.flatnonzero(near & (pieces == piece))
            if len(members) < 3:
                continue
            above = bool((vertices[members] - seam).mean(axis=0) @ up > 0)
            nearest = int(members[np.argmin(distance[members])])
            if above not in sides or distance[nearest] < distance[sides[above]]:
                sides[above] = nearest
        if len(sides) == 2:
            ids[upper], ids[lower] = sides[True], sides[False]
            moved += 1
    return moved


def _skin_part(vertices: np.ndarray, parts: np.ndarray, points: np.ndarray) -> int:
    """The connected part (label of ``parts``) whose vertices are nearest most of ``points``: the skin."""
    nearest = np.argmin(np.linalg.norm(vertices[None, :, :] - points[:, None, :], axis=2), axis=1)
    return int(np.bincount(parts[nearest]).argmax())


def _skin_faces(vertices: np.ndarray, faces: np.ndarray, parts: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(m,) bool: the triangles of the skin, the part nearest most of the iBUG points of ``points`` (546, 3)
    (:func:`_look`'s, file frame)."""
    return parts[faces[:, 0]] == _skin_part(vertices, parts, points[478:])


def _face_box(points: np.ndarray, rotation: np.ndarray, margin: float) -> np.ndarray:
    """Two corner points (file frame) of the landmarks' box widened by ``margin`` of its size on every side."""
    viewed = points @ rotation.T
    low, high = viewed.min(axis=0), viewed.max(axis=0)
    pad = margin * (high - low)
    return np.stack([low - pad, high + pad]) @ rotation


def _search_regions(vertices: np.ndarray, rotation: np.ndarray, eyes: np.ndarray | None) -> Iterator[np.ndarray]:
    """Where to look for the face from one direction, most likely first (points to frame, file frame).

    Around the eyes when the loader knows them (a box three eye-distances wide); the whole mesh; then the top
    quarter of it along the view's up (the head of a standing body seen whole is too small to be found).
    """
    if eyes is not None:
        centre = eyes.mean(axis=0)
        reach = 1.5 * max(float(np.linalg.norm(eyes[0] - eyes[1])), 1e-9)
        yield np.stack([centre - reach, centre + reach])
    yield vertices
    height = (vertices @ rotation.T)[:, 1]
    top = height >= height.max() - 0.25 * float(np.ptp(height))
    if 3 <= top.sum() < len(vertices):
        yield vertices[top]


def _views() -> Iterator[tuple[str, np.ndarray]]:
    for forward, up in _VIEWS:
        yield f"{forward}/{up}", _frame(forward, up)


def _snap(direction: np.ndarray) -> tuple[np.ndarray, float]:
    """The file axis nearest ``direction`` and the angle between them, degrees."""
    unit = direction / np.linalg.norm(direction)
    axis = np.zeros(3)
    k = int(np.argmax(np.abs(unit)))
    axis[k] = math.copysign(1.0, unit[k])
    return axis, math.degrees(math.acos(min(1.0, abs(float(unit[k])))))


def _unit(interocular: float, name: str) -> str:
    ratios = {unit: interocular * factor / HUMAN_INTEROCULAR_M for unit, factor in UNITS.items()}
    unit = min(ratios, key=lambda u: abs(math.log(ratios[u])))
    if not 1.0 / _UNIT_TOLERANCE <= ratios[unit] <= _UNIT_TOLERANCE:
        raise InvalidValueError(
            f"{name} unit",
            f"an inter-ocular distance of {interocular:.4g} file units",
            f"a face whose eyes are about {HUMAN_INTEROCULAR_M * 1000:.0f} mm apart in metres, centimetres, "
            "millimetres or inches; rescale the file or say its unit",
        )
    return unit


def instrument(
    vertices: np.ndarray,
    faces: np.ndarray,
    landmarker_model: str | os.PathLike[str] | None = None,
    name: str = "head",
    renderer: RendererFactory | None = None,
    eyes: np.ndarray | None = None,
) -> Instrumentation:
    """Find the face on the mesh ``vertices`` (n, 3) file units, ``faces`` (m, 3) triangles (see module doc).

    ``landmarker_model`` is the MediaPipe ``face_landmarker.task`` (None: the configured asset). ``name`` (the
    file's name) goes into errors. ``renderer`` draws the head's own look (textures, face paint); None draws
    the bare mesh in one skin tone. ``eyes`` (2, 3), the eye centres when a loader found them (file units),
    is where the face is looked for first. Raises :class:`FaceNotFoundError` when no direction shows a face, and
    :class:`InvalidValueError` for an empty mesh or a unit that cannot be told.
    """
    vertices = np.asarray(vertices, np.float64)
    faces = np.ascontiguousarray(faces, np.int32)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or len(vertices) < 3 or not np.isfinite(vertices).all():
        raise InvalidValueError(f"{name} vertices", vertices.shape, "(n, 3) finite positions, n >= 3")
    if faces.ndim != 2 or faces.shape[1] != 3 or not len(faces) or faces.min() < 0 or faces.max() >= len(vertices):
        raise InvalidValueError(f"{name} faces", faces.shape, "(m, 3) ids of existing vertices, m > 0")
    draw = renderer or _bare(faces)
    parts = vertex_components(len(vertices), faces)
    # one renderer for every look (the head is moved before one camera): a textured head's textures are decoded once
    with Landmarker(landmarker_model, mode="image") as landmarker, draw(_CAMERA, _RENDER_PX) as drawing:
        for view, rotation in _views():
            first = None
            for region in _search_regions(vertices, rotation, eyes):
                if (first := _look(landmarker, vertices, faces, rotation, region, drawing)) is not None:
                    break
            if first is None:
                continue
            # Closer looks, framed on the face found (a full body or a head with shoulders showed it small), at a
            # few framings: the medoid of their landmarks sets MediaPipe's frame-to-frame jitter aside. Their rays land
            # on the skin, not on lashes in front of it.
            skin = _skin_faces(vertices, faces, parts, first[0])
            boxes = [_face_box(first[0][:478], rotation, margin) for margin in _CLOSE_MARGINS]
            looks = [
                found for box in boxes if (found := _look(landmarker, vertices, faces, rotation, box, drawing, skin))
            ] or [first]
            points = _medoid(np.stack([look[0] for look in looks]))
            found_view = view
            hits = min(look[1] for look in looks)
            break
        else:
            raise FaceNotFoundError(
                f"no face found on {name} from any of {len(_VIEWS)} directions: the mesh may not be a head, or "
                "its face may be hidden (hair or a helmet over it); pass the head mesh alone"
            )
    points, points68 = points[:478], points[478:]
    interocular = float(np.linalg.norm(points68[45] - points68[36]))
    unit = _unit(interocular, name)
    # Axes from the face itself: up from the chin (8) to the nose root (27), left from the subject's right
    # outer eye corner (36) to the left one (45); forward completes the frame.
    left = points68[45] - points68[36]
    up_measured = points68[27] - points68[8]
    up_measured = up_measured - left * (up_measured @ left) / (left @ left)
    forward_measured = np.cross(left, up_measured)
    up, tilt = _snap(up_measured)
    forward, _ = _snap(forward_measured)
    if abs(float(up @ forward)) > 0.5:
        raise InvalidValueError(f"{name} axes", found_view, "a face whose up and forward axes can be told apart")
    # Landmark vertices on the skin (not an eyeball or a tooth that a ray met first), so paths between landmarks
    # (the feature-point rig's geodesics) stay on one surface.
    on_skin = parts == _skin_part(vertices, parts, points68)
    skin = np.flatnonzero(on_skin)
    distances = np.full((68, len(vertices)), np.inf)
    distances[:, skin] = np.linalg.norm(vertices[None, skin, :] - points68[:, None, :], axis=2)
    ids = np.argmin(distances, axis=1)
    lips_apart = _lip_sides(vertices, faces, on_skin, points68, ids, up_measured / np.linalg.norm(up_measured))
    return Instrumentation(
        landmarks478=points.astype(np.float32),
        ibug68_points=points68.astype(np.float32),
        ibug68_vertices=ids.astype(np.int32),
        interocular=interocular,
        unit=unit,
        up=tuple(float(v) for v in up),  # type: ignore[arg-type]
        forward=tuple(float(v) for v in forward),  # type: ignore[arg-type]
        tilt_deg=round(tilt, 2),
        hits=hits,
        view=found_view,
        lips_apart=lips_apart,
    )


def instrument_cached(
    vertices: np.ndarray,
    faces: np.ndarray,
    file_sha256: str,
    landmarker_model: str | os.PathLike[str] | None = None,
    name: str = "head",
    renderer: RendererFactory | None = None,
    eyes: np.ndarray | None = None,
) -> Instrumentation:
    """:func:`instrument`, cached per ``file_sha256`` in ``$MIEN_CACHE_DIR/heads`` (written atomically).

    A cache entry of another :data:`INSTRUMENT_VERSION` or an unreadable one is recomputed, never trusted.
    """
    path = cache_dir("heads") / f"{file_sha256}.instrument.json"
    if path.is_file():
        try:
            return Instrumentation.from_json(path.read_text(encoding="utf-8"))
        except InvalidValueError:
            pass
    found = instrument(vertices, faces, landmarker_model, name, renderer, eyes)
    write_bytes(found.to_json().encode("utf-8"), path)
    return found
