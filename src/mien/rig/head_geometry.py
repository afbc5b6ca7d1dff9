"""Geometry of mien's built-in stylised head: the neutral mesh, its colours and per-vertex attributes.

The skin is a lathe: one horizontal cross-section (an ellipse, front and back half-depths differing) per row
of a grid whose rows are heights ``Y`` and whose columns are azimuths ``u`` (0 = straight ahead, +x = the
character's left), closed by a pole at the crown and one under the neck. Facial relief (brows, nose, lips,
cheeks, chin) is a depth offset, a function of the frontal position ``(X, Y)``, so the face is a height field
seen from the front. Two slits cut the grid: the mouth (one row, lower-lip vertices duplicated so the lips
part) and each eye (one row, pushed apart into an almond-shaped opening whose lids lie on a sphere around the
eyeball). Separate closed parts: eyeballs, mouth cavity, upper and lower teeth, tongue, ears.

Everything is built in *design* coordinates (metres, the mien rig frame: +x left, +y up, +z forward, eyeball
centres at ``(+-eye_spacing/2, 0, 0)``); heights below the eyes are stretched by ``lower_face_scale`` so two
identities can differ in face length. Only numpy is used; generation is deterministic.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

__all__ = [
    "BROW_Y_D",
    "CAVITY",
    "EARS",
    "EYE_L",
    "EYE_R",
    "LID_FOLD_M",
    "LID_FOLD_OUTER",
    "LID_FOLD_RISE_M",
    "PART_NAMES",
    "SKIN",
    "TEETH_LOWER",
    "TEETH_UPPER",
    "TONGUE",
    "HeadMesh",
    "HeadShape",
    "brow_line",
    "build_head_mesh",
    "gauss",
    "lid_heights",
    "skin_masks",
    "smoothstep",
    "srgb_to_linear",
]

SKIN, EYE_L, EYE_R, CAVITY, TEETH_UPPER, TEETH_LOWER, TONGUE, EARS = range(8)
PART_NAMES: tuple[str, ...] = ("skin", "eye_L", "eye_R", "mouth_cavity", "teeth_upper", "teeth_lower", "tongue", "ears")
"""Name of each part code (index = code)."""

Y_MOUTH_D = -0.070
"""Design height of the mouth slit, metres (before ``lower_face_scale``)."""
Y_TOP_D = 0.118
"""Design height of the crown, metres."""
Y_NECK_D = -0.222
"""Design height of the bottom of the neck, metres."""
TEETH_DEPTH_M = 0.0075
"""Depth of the front teeth's labial faces behind the lips' front at the midline, metres."""
TEETH_SHOW_M = 0.0032
"""How far the upper central incisors' edges reach below the lip line, metres (seen when the lips part)."""
ARCH_DEPTH_M = 0.016
"""How far the dental arch curves back from the midline to ``x`` = the mouth's half-width, metres (shallower than a
real arch: the lips' slit curves back only about 7 mm, and a deeper arch leaves a dark void behind the far lip corner
of an open mouth seen at 45 degrees)."""
CAVITY_FLARE = (0.3, 0.3, 0.0)
"""How much wider and taller (x, y; 0.3 = 30 %) the mouth cavity's back is than its front: a pear lying behind the
lips. What is seen through the slit is the back, wide and tall enough for a smile's stretched, raised corners
(Table 1 joy at 2.4: 10 mm out, 17 mm up); the front is narrower than the lips' width (1.3 half-widths), so it
stays behind the cheeks that a smile pulls back (a wider front poked through them as dark creases)."""

# Teeth of one side of each row, midline outward: width along the arch, crown height, labio-lingual
# thickness, and how far the edge stands back from the central incisor's (toward the gum), all metres.
# Widths are adult mesio-distal crown widths (Wheeler's Dental Anatomy); heights include a hidden root part.
_UPPER_TEETH = np.array(
    [
        [0.0086, 0.0110, 0.0032, 0.0000],  # central incisor
        [0.0066, 0.0095, 0.0030, 0.0007],  # lateral incisor
        [0.0076, 0.0105, 0.0048, 0.0002],  # canine
        [0.0070, 0.0088, 0.0065, 0.0009],  # first premolar
        [0.0066, 0.0082, 0.0065, 0.0012],  # second premolar
    ]
)
_LOWER_TEETH = np.array(
    [
        [0.0054, 0.0095, 0.0030, 0.0000],
        [0.0059, 0.0095, 0.0030, 0.0000],
        [0.0069, 0.0105, 0.0045, -0.0003],
        [0.0070, 0.0088, 0.0065, 0.0006],
        [0.0071, 0.0085, 0.0065, 0.0009],
    ]
)
LID_FOLD_M = 0.0015
"""How much further off the eyeball than the lid (:attr:`HeadShape.lid_radius_m`) the skin above the upper lid's
margin stands, metres, reached :data:`LID_FOLD_RISE_M` above the margin and fading out toward the outer corner
(:data:`LID_FOLD_OUTER`): the fold of skin over the orbital fat between the lid and the brow. With none (mien
0.1..0.18) a lowered brow pushed that skin into the eyeball, which showed through as a grey cap above the lid (the
built-in head's anger at 2.4: 32 skin vertices up to 1.8 mm deep; with it, 18 up to 0.5 mm; docs/VALIDATION.md,
tenth pass)."""
LID_FOLD_RISE_M = 0.003
"""Height above the upper lid's margin over which :data:`LID_FOLD_M` builds up (a smoothstep), metres."""
LID_FOLD_OUTER = (0.6, 1.2)
"""Where the fold fades out toward the eye's outer corner, in eye half-widths from its centre: the brow lowerer pulls
the brow down medially, and a fold over the outer lid droops it, a sign of sadness (with it there, the classifier
read the built-in b head's smile at 1.2 as sad at both distances)."""
BROW_Y_D = 0.0150
"""Design height of the middle of the brow at its inner end, metres above the eye centres."""
Z_CENTRE = -0.07
"""Depth of the skull's vertical axis, metres."""


@dataclass(frozen=True)
class HeadShape:
    """Identity (morphology and colouring) of the built-in head. Lengths in metres, colours sRGB 0..1."""

    name: str = "default"
    """Identity name."""
    width_scale: float = 1.0
    """Multiplies every cross-section half-width."""
    lower_face_scale: float = 1.0
    """Stretches everything below the eyes vertically (longer face > 1)."""
    eye_spacing_m: float = 0.063
    """Distance between the eyeball centres."""
    eye_radius_m: float = 0.0120
    """Eyeball radius."""
    eye_half_width_m: float = 0.0122
    """Half the width of the eye opening (corner to corner / 2)."""
    nose_scale: float = 1.0
    """Multiplies the nose protrusion."""
    nose_width_scale: float = 1.0
    """Multiplies the nose width."""
    mouth_half_width_m: float = 0.0245
    """Half the mouth width (corner to corner / 2)."""
    lip_fullness: float = 1.0
    """Multiplies lip height and thickness."""
    chin_scale: float = 1.0
    """Multiplies the chin protrusion."""
    skin_srgb: tuple[float, float, float] = (0.88, 0.69, 0.58)
    """Skin colour."""
    lip_srgb: tuple[float, float, float] = (0.74, 0.42, 0.42)
    """Lip (vermilion) colour."""
    brow_srgb: tuple[float, float, float] = (0.30, 0.20, 0.14)
    """Eyebrow colour."""
    hair_srgb: tuple[float, float, float] = (0.26, 0.17, 0.11)
    """Hair (painted scalp) colour."""
    iris_srgb: tuple[float, float, float] = (0.32, 0.45, 0.58)
    """Iris colour."""

    def y(self, y_design: np.ndarray | float) -> np.ndarray:
        """Real height (m) of design height(s) ``y_design``: heights below the eyes are stretched."""
        yd = np.asarray(y_design, dtype=np.float64)
        return np.where(yd < 0.0, yd * self.lower_face_scale, yd)

    @property
    def y_mouth(self) -> float:
        """Height of the mouth slit, metres."""
        return float(self.y(Y_MOUTH_D))

    @property
    def eye_centers(self) -> np.ndarray:
        """(2, 3) centres of the left (+x) and right eyeballs, metres."""
        half = self.eye_spacing_m / 2
        return np.array([[half, 0.0, 0.0], [-half, 0.0, 0.0]])

    @property
    def lid_radius_m(self) -> float:
        """Radius of the sphere the eyelids lie on (1 mm clear of the eyeball, so a half blink clears it)."""
        return self.eye_radius_m + 0.001


@dataclass(frozen=True, eq=False)
class HeadMesh:
    """The neutral built-in head with the per-vertex attributes its morph targets are computed from."""

    shape: HeadShape
    """The identity it was built from."""
    vertices: np.ndarray
    """(n, 3) float64 rest positions, metres."""
    faces: np.ndarray
    """(m, 3) int32 triangles, counter-clockwise seen from outside."""
    colors: np.ndarray
    """(n, 3) float32 linear RGB albedo."""
    part: np.ndarray
    """(n,) int8 part code (:data:`SKIN`, :data:`EYE_L`...)."""
    material: np.ndarray
    """(n, 2) float64 design (X, Y) of each skin vertex before the eye opening was cut (lid and lip
    weights are smooth functions of it); for other parts their design rest (x, y)."""
    lower_side: np.ndarray
    """(n,) float64 in 0..1: membership of the lower jaw side of the mouth slit (1 = moves with the jaw)."""
    upper_lid_side: np.ndarray
    """(n, 2) float64 in 0..1: membership of the upper side of the left / right eye slit."""
    mouth_seam: dict[str, np.ndarray]
    """``upper``/``lower``: vertex ids along the mouth slit from the character's right corner to the left
    (corners shared, so both include them); ``upper_edge``/``lower_edge``: the vermilion borders."""
    eye_seams: tuple[dict[str, np.ndarray], dict[str, np.ndarray]]
    """Per eye (left, right): ``upper``/``lower`` lid margins from the -x corner to the +x corner."""
    grid: np.ndarray
    """(n_rows, n_cols) int32 skin vertex ids of the lathe grid (upper copies on the slits)."""


def srgb_to_linear(rgb: np.ndarray | tuple[float, float, float]) -> np.ndarray:
    """Convert sRGB 0..1 colour(s) to linear RGB (IEC 61966-2-1)."""
    c = np.asarray(rgb, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def smoothstep(edge0: float, edge1: float, x: np.ndarray) -> np.ndarray:
    """Hermite ramp: 0 at ``edge0``, 1 at ``edge1`` (either order), smooth in between."""
    t = np.clip((x - edge0) / (edge1 - edge0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def gauss(x: np.ndarray, y: np.ndarray, cx: float, cy: float, sx: float, sy: float) -> np.ndarray:
    """Axis-aligned 2-D Gaussian bump of height 1 at (cx, cy) with standard deviations (sx, sy)."""
    return np.exp(-0.5 * (((x - cx) / sx) ** 2 + ((y - cy) / sy) ** 2))


def _pchip(xk: np.ndarray, yk: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Monotone cubic (Fritsch-Carlson) interpolation; ``xk`` ascending; clamped outside."""
    xk = np.asarray(xk, float)
    yk = np.asarray(yk, float)
    h = np.diff(xk)
    d = np.diff(yk) / h
    m = np.zeros_like(yk)
    for i in range(1, len(xk) - 1):
        if d[i - 1] * d[i] > 0:
            w1, w2 = 2 * h[i] + h[i - 1], h[i] + 2 * h[i - 1]
            m[i] = (w1 + w2) / (w1 / d[i - 1] + w2 / d[i])
    m[0], m[-1] = d[0], d[-1]
    xc = np.clip(x, xk[0], xk[-1])
    i = np.clip(np.searchsorted(xk, xc) - 1, 0, len(h) - 1)
    t = (xc - xk[i]) / h[i]
    h00, h10, h01, h11 = 2 * t**3 - 3 * t**2 + 1, t**3 - 2 * t**2 + t, -2 * t**3 + 3 * t**2, t**3 - t**2
    return np.asarray(h00 * yk[i] + h10 * h[i] * m[i] + h01 * yk[i + 1] + h11 * h[i] * m[i + 1])


# Lathe keyframes below the skull dome: design height, half-width, front depth, back depth (metres).
_KEYS = np.array(
    [
        [-0.222, 0.050, -0.024, -0.118],
        [-0.150, 0.049, -0.026, -0.116],
        [-0.136, 0.052, -0.020, -0.117],
        [-0.122, 0.050, 0.002, -0.120],
        [-0.105, 0.058, 0.014, -0.126],
        [-0.080, 0.065, 0.020, -0.140],
        [-0.050, 0.071, 0.021, -0.158],
        [-0.020, 0.075, 0.019, -0.170],
        [0.000, 0.0758, 0.0175, -0.1745],
        [0.010, 0.0760, 0.0170, -0.1750],
    ]
)


def _cross_section(yd: np.ndarray, shape: HeadShape) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Half-width, front half-depth and back half-depth (about :data:`Z_CENTRE`) at design heights ``yd``."""
    s = np.sqrt(np.clip(1.0 - ((yd - 0.01) / (Y_TOP_D - 0.01)) ** 2, 0.0, 1.0))
    dome = yd >= 0.01
    half_w = np.where(dome, 0.076 * s, _pchip(_KEYS[:, 0], _KEYS[:, 1], yd))
    z_front = np.where(dome, Z_CENTRE + 0.087 * s, _pchip(_KEYS[:, 0], _KEYS[:, 2], yd))
    z_back = np.where(dome, Z_CENTRE - 0.105 * s, _pchip(_KEYS[:, 0], _KEYS[:, 3], yd))
    return half_w * shape.width_scale, z_front - Z_CENTRE, Z_CENTRE - z_back


def _rows() -> np.ndarray:
    """Design heights of the grid rows, top to bottom; includes 0 (eye slit) and the mouth slit exactly."""
    theta = np.linspace(0.16, 1.12, 12)
    top = 0.01 + (Y_TOP_D - 0.01) * np.cos(theta)
    face = 0.050 - 0.002 * np.arange(89)  # 0.050 .. -0.126, 2 mm apart
    neck = np.linspace(-0.134, Y_NECK_D + 0.004, 10)
    return np.concatenate([top, face, neck])


def _columns(n: int = 104, front_share: float = 0.45) -> np.ndarray:
    """Azimuths (rad) of the grid columns, ascending from -pi; dense in front (about 1.8 mm apart)."""
    s = np.linspace(-1.0, 1.0, n, endpoint=False)
    return np.pi * (front_share * s + (1.0 - front_share) * s**3)


def _relief(x: np.ndarray, yd: np.ndarray, shape: HeadShape) -> np.ndarray:
    """Forward depth offset (m) of the facial relief at frontal design position (x, yd)."""
    ax = np.abs(x)
    ym = Y_MOUTH_D
    z = 0.004 * gauss(ax, yd, 0.029, 0.016, 0.020, 0.007)  # brow ridge (supraorbital rim)
    z += 0.002 * gauss(x, yd, 0.0, 0.016, 0.010, 0.010)  # glabella
    z += 0.006 * gauss(ax, yd, 0.040, -0.032, 0.014, 0.015)  # cheekbones
    z -= 0.003 * gauss(ax, yd, 0.052, -0.002, 0.010, 0.014)  # temples / outer orbit
    # nose: a ridge whose height and width follow the profile keyframes, plus the alae
    prof_y = np.array([-0.054, -0.050, -0.045, -0.040, -0.035, -0.025, -0.010, 0.004, 0.014])
    prof_h = np.array([0.000, 0.007, 0.016, 0.0215, 0.0225, 0.017, 0.0090, 0.003, 0.000])
    wid_y = np.array([-0.050, -0.036, -0.020, 0.004])
    wid_s = np.array([0.0070, 0.0068, 0.0055, 0.0046])
    height = _pchip(prof_y, prof_h, yd) * shape.nose_scale
    width = _pchip(wid_y, wid_s, yd) * shape.nose_width_scale
    z += height * np.exp(-0.5 * (x / width) ** 2)
    z += 0.010 * shape.nose_scale * gauss(ax, yd, 0.0135 * shape.nose_width_scale, -0.041, 0.0050, 0.0048)
    # muzzle: the mouth region stands forward of the cheeks
    z += 0.007 * gauss(x, yd, 0.0, ym, 0.026, 0.022)
    # lips: vermilion bulges above and below the slit, recessed at the slit itself
    mw = shape.mouth_half_width_m
    across = np.clip(1.0 - (x / mw) ** 2, 0.0, 1.0)
    up_h = (0.0075 + 0.0012 * gauss(ax, yd, 0.006, 0.0, 0.004, 1.0)) * shape.lip_fullness * np.sqrt(across)
    lo_h = 0.0095 * shape.lip_fullness * np.sqrt(across)
    t_up = np.clip((yd - ym) / np.maximum(up_h, 1e-4), 0.0, 1.0)
    t_lo = np.clip((ym - yd) / np.maximum(lo_h, 1e-4), 0.0, 1.0)
    up = (yd >= ym) * np.sin(np.pi * (0.35 + 0.65 * t_up)) ** 0.8 * np.where(t_up < 1.0, 1.0, 0.0)
    lo = (yd < ym) * np.sin(np.pi * (0.35 + 0.65 * t_lo)) ** 0.8 * np.where(t_lo < 1.0, 1.0, 0.0)
    z += 0.0040 * shape.lip_fullness * up * across**0.5 + 0.0048 * shape.lip_fullness * lo * across**0.5
    z -= 0.0020 * gauss(ax, yd, mw, ym, 0.0030, 0.0030)  # corner crease
    z += 0.0012 * gauss(x, yd, 0.0, ym + 0.013, 0.005, 0.005) - 0.0008 * gauss(x, yd, 0.0, ym + 0.013, 0.0018, 0.01)
    z -= 0.0030 * gauss(x, yd, 0.0, -0.091, 0.016, 0.005)  # mentolabial sulcus
    z += 0.0065 * shape.chin_scale * gauss(x, yd, 0.0, -0.108, 0.014, 0.009)  # chin
    return np.asarray(z)


def lid_heights(t: np.ndarray, shape: HeadShape) -> tuple[np.ndarray, np.ndarray]:
    """Upper and lower lid margin heights (m) above / below the eye slit at relative position t in -1..1."""
    inside = np.clip(1.0 - t**2, 0.0, 1.0)
    scale = shape.eye_radius_m / 0.012
    return 0.0046 * scale * inside**0.6, 0.0046 * scale * inside**0.8


def _unit_sphere(n_rings: int, n_segments: int, polar: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """UV sphere about +z: (v, 3) unit points (front pole first, back pole last) and (f, 3) outward faces."""
    alpha = np.linspace(0, np.pi, n_rings + 1)[1:-1] if polar is None else polar
    phi = np.linspace(0, 2 * np.pi, n_segments, endpoint=False)
    a, p = np.meshgrid(alpha, phi, indexing="ij")
    ring = np.stack([np.sin(a) * np.cos(p), np.sin(a) * np.sin(p), np.cos(a)], axis=-1).reshape(-1, 3)
    points = np.vstack([[0, 0, 1.0], ring, [0, 0, -1.0]])
    n_r = len(alpha)
    ids = 1 + np.arange(n_r * n_segments).reshape(n_r, n_segments)
    nxt = np.roll(ids, -1, axis=1)
    faces = [np.stack([np.zeros(n_segments, int), ids[0], nxt[0]], 1)]
    for r in range(n_r - 1):
        faces += [np.stack([ids[r], ids[r + 1], nxt[r]], 1), np.stack([nxt[r], ids[r + 1], nxt[r + 1]], 1)]
    last = len(points) - 1
    faces.append(np.stack([np.full(n_segments, last), nxt[-1], ids[-1]], 1))
    return points, np.vstack(faces)


class _Builder:
    """Accumulates parts (vertices, faces, colours, attributes) into one mesh."""

    def __init__(self) -> None:
        self.vertices: list[np.ndarray] = []
        self.faces: list[np.ndarray] = []
        self.colors: list[np.ndarray] = []
        self.part: list[np.ndarray] = []
        self.material: list[np.ndarray] = []
        self.n = 0

    def add(self, vertices: np.ndarray, faces: np.ndarray, colors: np.ndarray, part: int, material: np.ndarray) -> int:
        offset = self.n
        self.vertices.append(vertices)
        self.faces.append(faces + offset)
        self.colors.append(np.broadcast_to(colors, vertices.shape).astype(np.float64))
        self.part.append(np.full(len(vertices), part, np.int8))
        self.material.append(material)
        self.n += len(vertices)
        return offset


def _grid_faces(rows: list[np.ndarray]) -> np.ndarray:
    """Triangles joining consecutive id rows (top to bottom, columns left to right); drops degenerate ones."""
    out = []
    for top, bottom in itertools.pairwise(rows):
        a, b, c, d = top[:-1], bottom[:-1], top[1:], bottom[1:]
        out += [np.stack([a, b, c], 1), np.stack([c, b, d], 1)]
    tri = np.vstack(out)
    keep = (tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 0] != tri[:, 2])
    return tri[keep]


def build_head_mesh(shape: HeadShape) -> HeadMesh:
    """Generate the neutral built-in head for ``shape`` (deterministic, numpy only, a few tens of ms)."""
    yd_rows = _rows()
    u = _columns()
    n_r, n_c = len(yd_rows), len(u)
    half_w, front, back = _cross_section(yd_rows, shape)
    cos_u, sin_u = np.cos(u), np.sin(u)
    x = half_w[:, None] * sin_u[None, :]
    z = Z_CENTRE + np.where(cos_u > 0, front[:, None], back[:, None]) * cos_u[None, :]
    yd = np.broadcast_to(yd_rows[:, None], (n_r, n_c)).copy()
    front_mask = smoothstep(0.15, 0.55, np.broadcast_to(cos_u[None, :], (n_r, n_c)))

    i_eye = int(np.argmin(np.abs(yd_rows)))
    i_mouth = int(np.argmin(np.abs(yd_rows - Y_MOUTH_D)))
    mw = shape.mouth_half_width_m
    mouth_cols = np.flatnonzero((np.abs(x[i_mouth]) < mw) & (cos_u > 0))
    centers = shape.eye_centers
    eye_cols = [np.flatnonzero((np.abs(x[i_eye] - c[0]) < shape.eye_half_width_m) & (cos_u > 0)) for c in centers]

    # The eye opening: push the rows above each eye slit up and the rows below down (monotone warp).
    dy = np.zeros((n_r, n_c))
    for c in centers:
        t = np.clip((x - c[0]) / shape.eye_half_width_m, -1.0, 1.0)
        h_up, h_lo = lid_heights(t, shape)
        reach = 0.015
        r_up = np.clip(yd / reach, 0.0, 1.0)
        r_lo = np.clip(-yd / reach, 0.0, 1.0)
        dy += np.where(yd >= 0, h_up * (1 - r_up) ** 2, -h_lo * (1 - r_lo) ** 2)
    # the slit row itself is the upper margin; its lower copies get the lower margin below
    y = shape.y(yd) + dy
    relief = _relief(x, yd, shape) * front_mask
    z = z + relief

    skin = np.stack([x, y, z], axis=-1)
    material = np.stack([x, yd], axis=-1)
    grid = np.arange(n_r * n_c).reshape(n_r, n_c)
    verts = [skin.reshape(-1, 3)]
    mats = [material.reshape(-1, 2)]
    n = n_r * n_c
    top_pole, bottom_pole = n, n + 1
    verts.append(np.array([[0.0, Y_TOP_D, Z_CENTRE], [0.0, float(shape.y(Y_NECK_D)), Z_CENTRE - 0.005]]))
    mats.append(np.array([[0.0, Y_TOP_D], [0.0, Y_NECK_D]]))
    n += 2

    # lower copies of the slit rows
    lower_rows: dict[int, np.ndarray] = {}
    lower_eye: list[np.ndarray] = []
    for c, cols in zip(centers, eye_cols, strict=True):
        t = np.clip((x[i_eye, cols] - c[0]) / shape.eye_half_width_m, -1.0, 1.0)
        h_up, h_lo = lid_heights(t, shape)
        low = skin[i_eye, cols].copy()
        low[:, 1] -= h_up + h_lo
        ids = np.arange(n, n + len(cols))
        verts.append(low)
        mats.append(material[i_eye, cols])
        n += len(cols)
        lower_eye.append(ids)
    low = skin[i_mouth, mouth_cols].copy()
    mouth_lower_ids = np.arange(n, n + len(mouth_cols))
    verts.append(low)
    mats.append(material[i_mouth, mouth_cols])
    n += len(mouth_cols)

    all_v = np.vstack(verts)
    # Eyelids: sink a socket round each eye and lay the skin on the lid sphere (1 mm clear of the eyeball; the fold
    # above the upper lid LID_FOLD_M further) wherever that sphere stands in front of it; a smooth maximum leaves a
    # soft lid crease.
    rc = shape.lid_radius_m
    margin = lid_heights(np.zeros(1), shape)[0][0]  # the upper lid's margin above the eye centre
    for c in centers:
        d = all_v - c
        d_ell = np.sqrt((d[:, 0] / 1.12) ** 2 + d[:, 1] ** 2)
        front_v = all_v[:, 2] > -0.02
        # shallow above and below the eye (a deep ring there reads as staring), deeper at the corners so the
        # skin by the nose lies on the lid sphere and a blink closes there too
        corner = (d[:, 0] / 1.12) ** 2 / np.maximum(d_ell**2, 1e-12)
        socket = (0.003 + 0.006 * corner) * (1.0 - smoothstep(0.008, 0.018, d_ell)) * front_v
        z_face = all_v[:, 2] - socket
        outward = d[:, 0] * np.sign(c[0]) / shape.eye_half_width_m  # toward the outer corner, in half-widths
        fold = smoothstep(margin, margin + LID_FOLD_RISE_M, d[:, 1]) * (1.0 - smoothstep(*LID_FOLD_OUTER, outward))
        r_fold = rc + LID_FOLD_M * fold
        r2 = r_fold**2 - d[:, 0] ** 2 - d[:, 1] ** 2
        z_sph = np.where((r2 > 0) & front_v, c[2] + np.sqrt(np.clip(r2, 0.0, None)), -1.0)
        k = 0.0012
        all_v[:, 2] = 0.5 * (z_face + z_sph + np.sqrt((z_face - z_sph) ** 2 + k**2))
        far = z_sph < -0.5
        all_v[far, 2] = z_face[far]
    all_mat = np.vstack(mats)

    row_ids = [grid[i].copy() for i in range(n_r)]
    below_rows = {i: grid[i].copy() for i in (i_eye, i_mouth)}
    for cols, ids in zip(eye_cols, lower_eye, strict=True):
        below_rows[i_eye][cols] = ids
    below_rows[i_mouth][mouth_cols] = mouth_lower_ids
    del lower_rows
    faces = []
    wrap = np.append(np.arange(n_c), 0)
    for i in range(n_r - 1):
        top = below_rows.get(i, row_ids[i])
        faces.append(_grid_faces([top[wrap], row_ids[i + 1][wrap]]))
    ring0, ring_last = grid[0][wrap], grid[-1][wrap]
    faces.append(np.stack([np.full(n_c, top_pole), ring0[:-1], ring0[1:]], 1))
    faces.append(np.stack([np.full(n_c, bottom_pole), ring_last[1:], ring_last[:-1]], 1))

    # Inner lips: two rows curling from each lip edge into the mouth; lid margins: one row tucked behind.
    extra_v: list[np.ndarray] = []
    extra_m: list[np.ndarray] = []

    def flap(seam_ids: np.ndarray, offsets: list[np.ndarray], upper: bool) -> list[np.ndarray]:
        nonlocal n
        rows = [seam_ids]
        interior = seam_ids[1:-1]
        for off in offsets:
            ids = seam_ids.copy()
            ids[1:-1] = np.arange(n, n + len(interior))
            extra_v.append(all_v[interior] + off[1:-1])
            extra_m.append(all_mat[interior])
            n += len(interior)
            rows.append(ids)
        return rows if upper else rows[::-1]

    corners_m = np.array([mouth_cols[0] - 1, mouth_cols[-1] + 1])
    m_up = np.concatenate([[grid[i_mouth, corners_m[0]]], grid[i_mouth, mouth_cols], [grid[i_mouth, corners_m[1]]]])
    m_lo = np.concatenate([[m_up[0]], mouth_lower_ids, [m_up[-1]]])
    k = len(m_up)
    mouth_all_cols = np.concatenate([[corners_m[0]], mouth_cols, [corners_m[1]]])
    across = 1.0 - (np.abs(all_v[m_up, 0]) / (mw * 1.1)) ** 2
    ones = np.ones(k)
    zeros = np.zeros(k)
    up_off = [
        np.stack([zeros, 0.0015 * ones, -0.0025 * across], 1),
        np.stack([zeros, 0.0050 * ones, -0.0040 * across], 1),
    ]
    lo_off = [
        np.stack([zeros, -0.0015 * ones, -0.0025 * across], 1),
        np.stack([zeros, -0.0055 * ones, -0.0045 * across], 1),
    ]
    up_rows = flap(m_up, up_off, upper=True)
    lo_rows = flap(m_lo, lo_off, upper=False)
    faces += [_grid_faces(up_rows), _grid_faces(lo_rows)]
    inner_up_ids, inner_lo_ids = up_rows[2][1:-1], lo_rows[0][1:-1]

    eye_seams = []
    lid_flap_ids = []
    for c, cols, low_ids in zip(centers, eye_cols, lower_eye, strict=True):
        corners = np.array([cols[0] - 1, cols[-1] + 1])
        e_up = np.concatenate([[grid[i_eye, corners[0]]], grid[i_eye, cols], [grid[i_eye, corners[1]]]])
        e_lo = np.concatenate([[e_up[0]], low_ids, [e_up[-1]]])
        for ids, upper in ((e_up, True), (e_lo, False)):
            d = all_v[ids] - c
            inward = -d / np.linalg.norm(d, axis=1, keepdims=True) * (rc - shape.eye_radius_m + 0.0006)
            rows = flap(ids, [inward], upper=upper)
            faces.append(_grid_faces(rows))
            lid_flap_ids.append((rows[1] if upper else rows[0])[1:-1])
        eye_seams.append({"upper": e_up, "lower": e_lo})

    skin_v = np.vstack([all_v, *extra_v])
    skin_m = np.vstack([all_mat, *extra_m])
    skin_f = np.vstack(faces)

    b = _Builder()
    b.add(skin_v, skin_f, np.zeros(3), SKIN, skin_m)

    # Eyeballs: dense rings at the front for a crisp pupil and iris.
    polar = np.concatenate([np.linspace(0.06, 0.52, 9), np.linspace(0.58, np.pi - 0.2, 12)])
    unit, sphere_faces = _unit_sphere(0, 32, polar)
    alpha = np.arccos(np.clip(unit[:, 2], -1, 1))
    iris = srgb_to_linear(shape.iris_srgb)
    ring = 0.6 + 0.4 * np.cos(np.arctan2(unit[:, 1], unit[:, 0]) * 9) ** 2
    eye_col = np.where(
        alpha[:, None] < 0.17,
        srgb_to_linear((0.03, 0.03, 0.035)),
        np.where(
            alpha[:, None] < 0.46,
            iris * (0.75 + 0.25 * ring[:, None]),
            np.where(alpha[:, None] < 0.53, iris * 0.35, srgb_to_linear((0.90, 0.87, 0.84))),
        ),
    )
    # Painted occlusion: the lids and the socket shade the white toward the corners, and the upper lid and
    # lashes shade the top of the eye, so the white does not glow as bright wedges (a staring look). At 45 degrees
    # the near eye's outer corner shows the eyeball's side, 60 degrees off its axis: shaded to a quarter there
    # (0.45 before the fourteenth pass, still a white wedge in the study's 45-degree view).
    toward_corner = smoothstep(0.55, 1.0, alpha)[:, None]
    eye_col = eye_col * (1.0 - 0.75 * toward_corner) * (1.0 - 0.15 * toward_corner * np.array([0.0, 1.0, 1.0]))
    eye_col = eye_col * (1.0 - 0.40 * smoothstep(0.05, 0.40, unit[:, 1]))[:, None]
    for part, c in ((EYE_L, centers[0]), (EYE_R, centers[1])):
        pts = c + unit * shape.eye_radius_m
        b.add(pts, sphere_faces, eye_col, part, pts[:, :2])

    # Mouth cavity: a dark ellipsoid behind the lips, faces pointing inward (seen from inside).
    ym = shape.y_mouth
    z_lips = float(skin_v[m_up[k // 2], 2])
    unit, sphere_faces = _unit_sphere(12, 20)
    back = (1.0 - unit[:, 2:3]) / 2.0  # 0 at the front, 1 at the back: a pear, wider the deeper
    radii = np.array([mw * 1.3, 0.016 * shape.lower_face_scale, 0.025]) * (1.0 + back * CAVITY_FLARE)
    cav = unit * radii + [0, ym - 0.001, z_lips - 0.031]
    dark = srgb_to_linear((0.22, 0.06, 0.07))
    b.add(cav, sphere_faces[:, ::-1], dark, CAVITY, cav[:, :2])

    # Teeth: one rounded block per tooth along a parabolic dental arch (incisors to second premolars), upper
    # incisal edges just below the lip line, lower incisors behind them (overjet) with their edges a little
    # higher than the upper edges (overbite), so parted lips show the upper row and an open jaw both rows.
    z_arch = z_lips - TEETH_DEPTH_M
    for part, teeth, y_edge, row_z, row_half_w in (
        (TEETH_UPPER, _UPPER_TEETH, float(ym - TEETH_SHOW_M), float(z_arch), float(mw * 1.02)),
        (TEETH_LOWER, _LOWER_TEETH, float(ym - TEETH_SHOW_M + 0.0016), float(z_arch - 0.0034), float(mw * 0.96)),
    ):
        upper = part == TEETH_UPPER
        pts, tri, col = _dental_row(teeth, row_z, row_half_w, y_edge, upper)
        b.add(pts, tri, col, part, pts[:, :2])

    # Tongue: a flattened ellipsoid lying on the floor of the mouth.
    unit, sphere_faces = _unit_sphere(8, 16)
    tongue = unit * np.array([0.015, 0.005, 0.018]) + [0, ym - 0.0085, z_lips - 0.027]
    b.add(tongue, sphere_faces, srgb_to_linear((0.72, 0.33, 0.34)), TONGUE, tongue[:, :2])

    # Ears: flattened ellipsoids pressed into the sides of the skull.
    unit, sphere_faces = _unit_sphere(8, 16)
    skin_lin = srgb_to_linear(shape.skin_srgb)
    for side in (1.0, -1.0):
        yc = float(shape.y(-0.018))
        hw_c, _, back_c = _cross_section(np.array([-0.018]), shape)
        ear = unit[:, [2, 0, 1]] * np.array([0.0065, 0.031, 0.016])
        tilt = 0.2
        ry = ear[:, 1] * np.cos(tilt) + ear[:, 2] * np.sin(tilt)
        rz = -ear[:, 1] * np.sin(tilt) + ear[:, 2] * np.cos(tilt)
        cz = -0.078
        cos_back = (cz - Z_CENTRE) / back_c[0]
        cx = hw_c[0] * np.sqrt(1 - cos_back**2) + 0.0015
        pts = np.stack([side * ear[:, 0] + side * cx, ry + yc, rz + cz], axis=1)
        faces_e = sphere_faces if side > 0 else sphere_faces[:, ::-1]
        shade = 1.0 - 0.35 * np.exp(-0.5 * ((ear[:, 1] / 0.014) ** 2 + (ear[:, 2] / 0.008) ** 2)) * (ear[:, 0] > 0)
        b.add(pts, faces_e, skin_lin * shade[:, None] * 0.97, EARS, pts[:, :2])

    vertices = np.vstack(b.vertices)
    part_arr = np.concatenate(b.part)
    mat = np.vstack(b.material)
    colors = np.vstack(b.colors)
    colors[: len(skin_v)] = _skin_colors(skin_v, skin_m, shape)
    skin_n = len(skin_v)
    inner_ids = np.concatenate([inner_up_ids, inner_lo_ids])
    colors[inner_ids] = dark * 1.4
    colors[np.concatenate(lid_flap_ids)] = srgb_to_linear((0.70, 0.42, 0.40))
    # lash line: the upper lid margin and its tucked-in rim dark, so the lid reads as resting on the iris
    lash = srgb_to_linear(shape.brow_srgb) * 0.45
    for e, cols in enumerate(eye_cols):
        colors[grid[i_eye, cols]] = lash
        colors[lid_flap_ids[2 * e]] = lash

    lower_side = np.zeros(len(vertices))
    lower_side[:skin_n] = _side_field(skin_m[:, 0], skin_m[:, 1], Y_MOUTH_D, mw, 1.2, 0.0, below=True)
    lower_side[mouth_lower_ids] = 1.0
    lower_side[grid[i_mouth, mouth_cols]] = 0.0
    for rows_, value in ((up_rows[1:], 0.0), (lo_rows[:-1], 1.0)):
        for r in rows_:
            lower_side[r[1:-1]] = value
    upper_lid = np.zeros((len(vertices), 2))
    for e, (c, cols, low_ids) in enumerate(zip(centers, eye_cols, lower_eye, strict=True)):
        field = _side_field(skin_m[:, 0], skin_m[:, 1], 0.0, shape.eye_half_width_m, 0.5, c[0], below=False)
        upper_lid[:skin_n, e] = field
        upper_lid[grid[i_eye, cols], e] = 1.0
        upper_lid[low_ids, e] = 0.0
    for e in range(2):
        upper_lid[lid_flap_ids[2 * e], e] = 1.0
        upper_lid[lid_flap_ids[2 * e + 1], e] = 0.0

    mouth_seam = {
        "upper": m_up,
        "lower": m_lo,
        "upper_edge": _edge_ids(grid, skin_m, mouth_all_cols, i_mouth, +1, shape),
        "lower_edge": _edge_ids(grid, skin_m, mouth_all_cols, i_mouth, -1, shape),
        "inner_upper": inner_up_ids,
        "inner_lower": inner_lo_ids,
    }
    return HeadMesh(
        shape=shape,
        vertices=vertices,
        faces=np.vstack(b.faces).astype(np.int32),
        colors=colors.astype(np.float32),
        part=part_arr,
        material=mat,
        lower_side=lower_side,
        upper_lid_side=upper_lid,
        mouth_seam=mouth_seam,
        eye_seams=(eye_seams[0], eye_seams[1]),
        grid=grid.astype(np.int32),
    )


def _dental_row(
    teeth: np.ndarray, z_front: float, half_width: float, y_edge: float, upper: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices (k, 3), outward faces and linear colours (k, 3) of one row of teeth (both sides).

    ``teeth`` rows are (width, height, thickness, edge set-back) in metres from the midline outward; the
    labial faces lie on the arch ``z = z_front - ARCH_DEPTH_M * (x / half_width)**2``; ``y_edge`` is the
    height of the central incisors' edges (the upper row hangs above it, the lower row stands below it).
    """
    gap = 0.00035  # dark seam between neighbouring teeth
    xs = np.linspace(0.0, 2.0 * half_width, 801)
    slope = -2.0 * ARCH_DEPTH_M * xs / half_width**2
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(xs), np.diff(xs) * slope[1:]))])
    unit, faces = _unit_sphere(6, 12)
    # rounded block: a superellipsoid, boxy across and along the tooth, rounder front to back
    boxy = np.sign(unit) * np.abs(unit) ** np.array([0.35, 0.3, 0.6])
    ivory = srgb_to_linear((0.94, 0.91, 0.83))
    pts, tri, col = [], [], []
    n = 0
    centres = np.cumsum(teeth[:, 0]) - teeth[:, 0] / 2
    for side in (1.0, -1.0):
        for (width, height, thick, set_back), s_mid in zip(teeth, centres, strict=True):
            x_mid = float(np.interp(s_mid, arc, xs))
            dzdx = -2.0 * ARCH_DEPTH_M * x_mid / half_width**2
            tangent = np.array([1.0, 0.0, dzdx]) / np.hypot(1.0, dzdx)
            normal = np.array([-dzdx, 0.0, 1.0]) / np.hypot(1.0, dzdx)  # toward the lips
            tangent[0] *= side
            normal[0] *= side
            edge = y_edge + set_back if upper else y_edge - set_back
            y_mid = edge + height / 2 if upper else edge - height / 2
            base = np.array([side * x_mid, y_mid, z_front - ARCH_DEPTH_M * (x_mid / half_width) ** 2])
            base -= normal * thick / 2
            local = boxy * np.array([(width - gap) / 2, height / 2, thick / 2])
            v = base + local[:, :1] * tangent + local[:, 1:2] * np.array([0.0, 1.0, 0.0]) + local[:, 2:] * normal
            pts.append(v)
            tri.append((faces if side > 0 else faces[:, ::-1]) + n)  # mirrored frame: flip the winding
            # darker toward the back of the mouth and toward the gum (light reaches the front edges)
            depth = (x_mid / half_width) ** 2
            toward_gum = np.clip((v[:, 1] - edge) / height * (1 if upper else -1), 0.0, 1.0)
            shade = (1.0 - 0.65 * depth) * (1.0 - 0.25 * toward_gum)
            col.append(ivory[None, :] * shade[:, None])
            n += len(v)
    return np.vstack(pts), np.vstack(tri), np.vstack(col)


def _side_field(
    x: np.ndarray, yd: np.ndarray, y_slit: float, half_width: float, spread: float, x_centre: float, below: bool
) -> np.ndarray:
    """Smooth 0..1 membership of one side of a slit: sharp along the slit, widening away from its ends."""
    width = 0.001 + spread * np.maximum(np.abs(x - x_centre) - half_width, 0.0)
    s = (y_slit - yd) / width if below else (yd - y_slit) / width
    return np.asarray(smoothstep(-1.0, 1.0, s))


def _edge_ids(
    grid: np.ndarray, material: np.ndarray, cols: np.ndarray, i_mouth: int, direction: int, shape: HeadShape
) -> np.ndarray:
    """Skin vertices on the upper (+1) or lower (-1) vermilion border, one per mouth column ``cols``."""
    x = material[grid[i_mouth, cols], 0]
    across = np.clip(1.0 - (x / shape.mouth_half_width_m) ** 2, 0.0, 1.0)
    height = (0.0080 if direction > 0 else 0.0095) * shape.lip_fullness * np.sqrt(across)
    steps = np.rint(height / 0.002).astype(int)
    return np.asarray(grid[i_mouth - direction * steps, cols], dtype=np.int32)


def skin_masks(v: np.ndarray, m: np.ndarray, shape: HeadShape) -> dict[str, np.ndarray]:
    """0..1 weights of the painted areas of skin vertices ``v`` (material coords ``m``): lips, brows, hair."""
    x, yd = m[:, 0], m[:, 1]
    ax = np.abs(x)
    mw = shape.mouth_half_width_m
    across = np.clip(1.0 - (x / (mw * 1.03)) ** 2, 0.0, 1.0)
    up_h = 0.0083 * shape.lip_fullness * np.sqrt(across)
    lo_h = 0.0098 * shape.lip_fullness * np.sqrt(across)
    above = yd - Y_MOUTH_D
    lip = np.where(above >= 0, smoothstep(0.0012, -0.0012, above - up_h), smoothstep(0.0012, -0.0012, -above - lo_h))
    lips = lip * smoothstep(0.0, 0.15, across) * (v[:, 2] > 0.0)
    # brows: a gently arched band over each eye, thicker at the inner end
    t = (ax - 0.012) / 0.044
    brow_y = brow_line(x)
    thick = 0.0048 * (1.0 - 0.45 * np.clip(t, 0, 1))
    brows = (1 - smoothstep(0.4, 1.1, np.abs(yd - brow_y) / thick)) * smoothstep(-0.08, 0.05, t)
    brows *= (1 - smoothstep(0.95, 1.08, t)) * (v[:, 2] > -0.03)
    # painted hair: above a hairline that drops from the forehead to the nape
    c = (v[:, 2] - Z_CENTRE) / np.maximum(np.hypot(v[:, 0], v[:, 2] - Z_CENTRE), 1e-9)
    line = np.where(c > 0, 0.024 + 0.044 * np.abs(c) ** 0.7, 0.024 + 0.085 * c)
    # the ramp widens where the line drops steeply across sparse columns: toward the nape, and round the temples
    # and the sides, where a 6 mm ramp drew steps at 45 and 90 degrees (the forehead's hairline stays crisp)
    soft = 0.006 + 0.006 * np.clip(-c, 0.0, 1.0) + 0.014 * (1.0 - c**4)
    hair = smoothstep(-soft, soft, v[:, 1] - line)
    return {"lips": lips, "brows": brows, "hair": hair}


def brow_line(x: np.ndarray | float) -> np.ndarray:
    """Design height (m) of the middle of the painted brow above frontal position ``x``.

    A relaxed brow: its lower edge about 1 cm above the upper lid margin, nearly flat, a low arch peaking
    two thirds of the way out (a high, round arch over a bare lid reads as surprise).
    """
    t = np.clip((np.abs(np.asarray(x, dtype=np.float64)) - 0.012) / 0.044, 0, 1)
    return np.asarray(BROW_Y_D + 0.0035 * np.sin(np.pi * t * 0.85) - 0.002 * t)


def _skin_colors(v: np.ndarray, m: np.ndarray, shape: HeadShape) -> np.ndarray:
    """(n, 3) linear colours of the skin vertices: skin, lips, brows, painted hair, cheeks."""
    x, yd = m[:, 0], m[:, 1]
    ax = np.abs(x)
    col = np.broadcast_to(srgb_to_linear(shape.skin_srgb), v.shape).copy()
    # warm cheeks and darker nostrils
    col *= 1.0 + 0.06 * gauss(ax, yd, 0.038, -0.038, 0.012, 0.012)[:, None] * np.array([0.5, -0.6, -0.6])
    col *= 1.0 - 0.30 * gauss(ax, yd, 0.0085, -0.0475, 0.0020, 0.0010)[:, None]
    masks = skin_masks(v, m, shape)
    for name, rgb in (("lips", shape.lip_srgb), ("brows", shape.brow_srgb), ("hair", shape.hair_srgb)):
        w = masks[name][:, None]
        col = col * (1 - w) + srgb_to_linear(rgb) * w
    return col
