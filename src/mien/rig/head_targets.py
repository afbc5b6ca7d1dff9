"""The 52 ARKit morph targets of the built-in head, computed from its per-vertex attributes.

Each target is a smooth weight field (Gaussians in the frontal design coordinates, cut by the mouth and eye
slits' side fields so an upper-lip target never drags the lower lip) times a displacement, or a rotation:
the jaw turns about a hinge in front of the ears, eyelids turn about the eyeball centre (so they slide over
the eyeball), eyeballs turn about their centres. Magnitudes follow a real adult face: a full smile lifts the
lip corner about 1 cm up and out; ``jawOpen`` = 1 opens the lips about 3 cm, the chin going down and a little back
(the condyle slides forward) and the corners drawn in, so the opening is an oval; a blink closes the lids.
``tongueOut`` pushes the tongue 2.6 cm forward (visible with the jaw open). Units: metres.
"""

from __future__ import annotations

import numpy as np

from mien.facs.arkit import ARKIT_NAMES
from mien.rig.head_geometry import (
    CAVITY,
    EYE_L,
    EYE_R,
    SKIN,
    TEETH_LOWER,
    TONGUE,
    Y_MOUTH_D,
    Z_CENTRE,
    HeadMesh,
    brow_line,
    gauss,
    lid_heights,
    smoothstep,
)

__all__ = [
    "BROW_LID_HOLD_M",
    "CORNER_CLOSE_M",
    "JAW_OPEN_RAD",
    "LIPS_PARTING",
    "arkit_deltas",
    "jaw_weights",
    "lid_weights",
    "margin_hold",
]

JAW_OPEN_RAD = 0.32
"""Jaw rotation at ``jawOpen`` = 1, radians (about 18 degrees)."""
EYE_YAW_RAD = np.radians(30.0)
"""Eyeball rotation at ``eyeLookIn``/``eyeLookOut`` = 1."""
EYE_PITCH_RAD = np.radians(25.0)
"""Eyeball rotation at ``eyeLookUp``/``eyeLookDown`` = 1."""
BROW_LID_HOLD_M = 0.009
"""``browInnerUp`` (AU1) leaves the upper lids' margins in place and lifts the lid fold above them fully only this
far (metres) above the margin (:func:`margin_hold`). The frontalis raises the brow and the skin under it; the lid's
margin is raised by the levator (AU5, ``eyeWide``), fear's sign, not sadness's. Before, AU1 lifted the inner
margin up to 1.5 mm and the built-in b head's sadness read fear in 3 of 8 frontal renders (now 0; sadness's
margin over the next label 0.03 -> 0.16 on b, 0.15 -> 0.27 on the default head; docs/VALIDATION.md). ``browOuterUp``
keeps lifting the lid with it: holding it too cost a frontal fear."""
CORNER_CLOSE_M = 0.008
"""Within this distance of a mouth corner the two lips' edges move together in :data:`LIPS_PARTING` (fully at the
corner, not at all this far in), so an opening mouth ends in closed, rounded corners inside the vermilion."""
LIPS_PARTING: tuple[str, ...] = (
    "jawOpen",
    "mouthUpperUpLeft",
    "mouthUpperUpRight",
    "mouthLowerDownLeft",
    "mouthLowerDownRight",
    "mouthStretchLeft",
    "mouthStretchRight",
)
"""The targets that part the lips by themselves. Before the corners were closed, each opened the slit right to the
corners, past where the vermilion ends, and an open mouth (anger, fear, surprise) showed dark wedges cutting into
the skin at its corners, at 45 degrees most (docs/VALIDATION.md, fourteenth pass). ``mouthSmile`` keeps its open
corners: a smile's corners open on the dark buccal corridor (closing them too turned three built-in smiles at 1.2
sad)."""


def _rot_x(p: np.ndarray, pivot: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotate points about the x axis through ``pivot``; positive angle turns +z toward +y (pitch up)."""
    d = p - pivot
    c, s = np.cos(angle), np.sin(angle)
    out = d.copy()
    out[:, 1] = d[:, 1] * c + d[:, 2] * s
    out[:, 2] = -d[:, 1] * s + d[:, 2] * c
    return out + pivot


def _rot_y(p: np.ndarray, pivot: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotate points about the y axis through ``pivot``; positive angle turns +z toward +x."""
    d = p - pivot
    c, s = np.cos(angle), np.sin(angle)
    out = d.copy()
    out[:, 0] = d[:, 0] * c + d[:, 2] * s
    out[:, 2] = -d[:, 0] * s + d[:, 2] * c
    return out + pivot


def _gauss_asym(
    x: np.ndarray, y: np.ndarray, cx: float, cy: float, sx: float, s_up: float, s_down: float
) -> np.ndarray:
    sy = np.where(y >= cy, s_up, s_down)
    return np.exp(-0.5 * (((x - cx) / sx) ** 2 + ((y - cy) / sy) ** 2))


def jaw_weights(mesh: HeadMesh) -> np.ndarray:
    """(n,) 0..1 share of each vertex in the jaw's motion (lower face, lower teeth, tongue, cavity floor)."""
    v, x, yd = mesh.vertices, mesh.material[:, 0], mesh.material[:, 1]
    w = np.zeros(len(v))
    skin = mesh.part == SKIN
    reach = (
        smoothstep(-0.165, -0.130, yd)
        * (1.0 - smoothstep(0.050, 0.078, np.abs(x)))
        * smoothstep(Z_CENTRE - 0.02, Z_CENTRE + 0.04, v[:, 2])
    )
    w[skin] = (mesh.lower_side * reach)[skin]
    w[(mesh.part == TEETH_LOWER) | (mesh.part == TONGUE)] = 1.0
    cavity = mesh.part == CAVITY
    w[cavity] = smoothstep(mesh.shape.y_mouth + 0.006, mesh.shape.y_mouth - 0.010, v[cavity, 1])
    return w


def lid_weights(mesh: HeadMesh, eye: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Upper-lid and lower-lid weights (n,) of eye 0 (left) or 1 (right), and the lid span (n,) in radians.

    The span is the angle about the eye centre between the upper and lower lid margins above each vertex's
    column (0 beyond the eye corners), so a rotation by ``weight * fraction * span`` closes a fraction of the
    opening.
    """
    shape = mesh.shape
    c = shape.eye_centers[eye]
    x, yd = mesh.material[:, 0], mesh.material[:, 1]
    skin = ((mesh.part == SKIN) & (mesh.vertices[:, 2] > -0.02)).astype(float)  # the face, not the back
    hw = shape.eye_half_width_m
    t = np.clip((x - c[0]) / hw, -1.0, 1.0)
    h_up, h_lo = lid_heights(t, shape)
    rho = np.sqrt(np.clip(shape.lid_radius_m**2 - (x - c[0]) ** 2, 1e-8, None))
    span = np.arcsin(np.clip(h_up / rho, -1, 1)) + np.arcsin(np.clip(h_lo / rho, -1, 1))
    lateral = 1.0 - smoothstep(hw, hw + 0.006, np.abs(x - c[0]))
    side = mesh.upper_lid_side[:, eye]
    upper = skin * side * (1.0 - smoothstep(0.0, 0.016, yd)) * lateral
    lower = skin * (1.0 - side) * (1.0 - smoothstep(0.0, 0.012, -yd)) * lateral
    return upper, lower, span


def arkit_deltas(mesh: HeadMesh) -> dict[str, np.ndarray]:
    """Dense (n, 3) float64 displacement (metres, weight 1) of every ARKit target, keyed by name."""
    shape = mesh.shape
    v = mesh.vertices
    n = len(v)
    x, yd = mesh.material[:, 0], mesh.material[:, 1]
    skin = (mesh.part == SKIN).astype(float)
    front = skin * smoothstep(Z_CENTRE + 0.02, Z_CENTRE + 0.07, v[:, 2])
    low = mesh.lower_side
    ym, mw = Y_MOUTH_D, shape.mouth_half_width_m
    out: dict[str, np.ndarray] = {}

    def vec(weight: np.ndarray, d: tuple[float, float, float] | np.ndarray) -> np.ndarray:
        return weight[:, None] * np.asarray(d, dtype=np.float64)

    # --- eyes: blink / squint / wide as lid rotations, look as eyeball rotations ---
    for e, (suffix, part, sgn) in enumerate((("Left", EYE_L, 1.0), ("Right", EYE_R, -1.0))):
        c = shape.eye_centers[e]
        upper, lower, span = lid_weights(mesh, e)

        def lids(up_frac: float, low_frac: float, c: np.ndarray = c, upper: np.ndarray = upper,
                 lower: np.ndarray = lower, span: np.ndarray = span) -> np.ndarray:  # fmt: skip
            angle = (upper * up_frac + lower * low_frac) * span
            return _rot_x(v, c, angle) - v

        out[f"eyeBlink{suffix}"] = lids(-0.88, 0.12)
        cheek = skin * gauss(x, yd, sgn * 0.034, -0.022, 0.012, 0.009) * (1.0 - lower) * (1.0 - upper)
        out[f"eyeSquint{suffix}"] = lids(-0.10, 0.30) + vec(cheek, (0.0, 0.0015, 0.0005))
        out[f"eyeWide{suffix}"] = lids(0.5, -0.08)
        ball = (mesh.part == part).astype(float)
        look_up = _rot_x(v, c, EYE_PITCH_RAD * ball) - v
        look_down = _rot_x(v, c, -EYE_PITCH_RAD * ball) - v
        out[f"eyeLookUp{suffix}"] = look_up + lids(0.20, 0.08)
        out[f"eyeLookDown{suffix}"] = look_down + lids(-0.35, -0.08)
        # "in" turns toward the nose: -x for the left eye, +x for the right eye
        out[f"eyeLookIn{suffix}"] = _rot_y(v, c, -sgn * EYE_YAW_RAD * ball) - v
        out[f"eyeLookOut{suffix}"] = _rot_y(v, c, sgn * EYE_YAW_RAD * ball) - v

    # --- jaw ---
    jaw = jaw_weights(mesh)
    hinge = np.array([0.0, float(shape.y(-0.02)), -0.075])
    # The lower lip is soft: its share of the jaw's turn falls off toward the corners, to nearly nothing at the
    # corners themselves, so the lips part as a rounded bowl with closed corners (as a relaxed human jaw drop
    # does), not a wide slot with square ends. A slot (share sqrt(1 - (x / 1.15 half-widths)^2), 0.49 at the
    # corners) made the built-in head's surprise a wide dark rectangle that read as fear in 5 of 8 frontal
    # renders; with this falloff 7 of 8 read surprise, fear and anger unchanged (docs/VALIDATION.md, eighth pass).
    lip_band = low * front * np.exp(-0.5 * ((yd - ym) / 0.010) ** 2)
    ellipse = np.clip(1.0 - (x / (mw * 1.05)) ** 2, 0.0, 1.0) ** 1.25
    jaw_lip = jaw * (1.0 - lip_band * (1.0 - ellipse))
    jaw_open = _rot_x(v, hinge, -JAW_OPEN_RAD * jaw_lip) - v
    # The condyle also slides forward as the jaw opens, so the chin goes mostly down, less back.
    out["jawOpen"] = jaw_open + vec(jaw_lip, (0.0, 0.0, 0.012))
    # A dropping jaw draws the lip corners in and down (the opening becomes an oval, not a wide slit).
    # The upper lip's outer part bends down with the corners (rounded ends, not a flat top with square
    # corners); its middle stays put.
    upper_follow = 0.85 * smoothstep(0.35 * mw, 0.75 * mw, np.abs(x))
    for sgn in (1.0, -1.0):
        corner = front * gauss(x, yd, sgn * mw, ym, 0.008, 0.011) * (low + (1.0 - low) * upper_follow)
        out["jawOpen"] += vec(corner, (-sgn * 0.0070, -0.0060, 0.0))
    out["jawForward"] = vec(jaw, (0.0, 0.0, 0.006))
    out["jawLeft"] = vec(jaw, (0.008, 0.0, 0.0))
    out["jawRight"] = vec(jaw, (-0.008, 0.0, 0.0))

    # --- mouth ---
    lip_foot = front * np.exp(-0.5 * (x / (mw + 0.003)) ** 6) * np.exp(-0.5 * ((yd - ym) / 0.009) ** 2)
    upper_lip, lower_lip = (1.0 - low) * lip_foot, low * lip_foot
    mouth_area = front * np.exp(-0.5 * (x / (mw + 0.008)) ** 4) * np.exp(-0.5 * ((yd - ym) / 0.016) ** 2)
    out["mouthClose"] = -jaw_open * (low * front * np.exp(-0.5 * (x / (mw + 0.003)) ** 6))[:, None] * np.exp(
        -0.5 * ((yd - ym) / 0.012) ** 2
    )[:, None] + vec(upper_lip, (0.0, -0.002, 0.0))
    out["mouthFunnel"] = (
        vec(lip_foot, (0.0, 0.0, 0.006))
        + lip_foot[:, None] * np.stack([-0.22 * x, 0 * x, 0 * x], 1)
        + vec(upper_lip, (0.0, 0.0025, 0.001))
        + vec(lower_lip, (0.0, -0.0035, 0.001))
    )
    out["mouthPucker"] = (
        vec(lip_foot, (0.0, 0.0, 0.008))
        + lip_foot[:, None] * np.stack([-0.30 * x, 0 * x, 0 * x], 1)
        + vec(upper_lip, (0.0, -0.0005, 0.0))
        + vec(lower_lip, (0.0, 0.0005, 0.0))
    )
    out["mouthLeft"] = vec(mouth_area, (0.0075, 0.0, -0.0015))
    out["mouthRight"] = vec(mouth_area, (-0.0075, 0.0, -0.0015))
    verm_up = (1.0 - low) * front * np.exp(-0.5 * (x / mw) ** 6) * np.exp(-0.5 * ((yd - ym - 0.0035) / 0.004) ** 2)
    verm_lo = low * front * np.exp(-0.5 * (x / mw) ** 6) * np.exp(-0.5 * ((yd - ym + 0.0045) / 0.0045) ** 2)
    out["mouthRollLower"] = vec(verm_lo, (0.0, 0.0015, -0.0045))
    out["mouthRollUpper"] = vec(verm_up, (0.0, -0.0015, -0.0040))
    out["mouthShrugLower"] = vec(low * front * gauss(x, yd, 0.0, -0.094, 0.018, 0.017), (0.0, 0.0035, 0.0025))
    out["mouthShrugUpper"] = vec((1.0 - low) * front * gauss(x, yd, 0.0, ym + 0.004, 0.020, 0.008), (0, 0.0025, 0.001))
    # Smile: the zygomatic major draws the corner up and out; the stretched upper lip rides up over the teeth
    # toward the corners, and the cheek lateral to the nasolabial furrow (ala to ~1 cm beyond the corner)
    # bunches up and forward, deepening the furrow (FACS Manual, AU12: "deepens the nasolabial furrow").
    ala = np.array([0.019, -0.046])
    beyond = np.array([mw + 0.009, ym - 0.011])
    along = (beyond - ala) / np.linalg.norm(beyond - ala)
    rel_x, rel_y = np.abs(x) - ala[0], yd - ala[1]
    lateral = rel_x * -along[1] + rel_y * along[0]  # signed distance from the furrow line, + toward the cheek
    s_line = np.clip(rel_x * along[0] + rel_y * along[1], -0.01, 0.06)
    nasolabial_w = (
        front
        * (1.0 - low)
        * smoothstep(-0.0005, 0.0045, lateral)
        * np.exp(-0.5 * (np.maximum(lateral - 0.004, 0.0) / 0.012) ** 2)
        * smoothstep(-0.004, 0.006, s_line)
        * (1.0 - smoothstep(0.030, 0.045, s_line))
    )
    smile_lip = smoothstep(0.2 * mw, 0.8 * mw, np.abs(x))
    for suffix, sgn in (("Left", 1.0), ("Right", -1.0)):
        corner = front * gauss(x, yd, sgn * mw, ym, 0.011, 0.010)
        half = 0.5 * (1.0 + np.tanh(sgn * x / 0.006))
        nasolabial = nasolabial_w * half
        cheek = front * gauss(x, yd, sgn * 0.035, -0.045, 0.013, 0.013)
        out[f"mouthSmile{suffix}"] = (
            vec(corner, (sgn * 0.0075, 0.0080, -0.003))
            + vec(cheek, (sgn * 0.001, 0.003, 0.002))
            + vec(upper_lip * half * smile_lip, (0.0, 0.0018, -0.0008))
            + vec(nasolabial, (sgn * 0.0008, 0.0025, 0.0028))
        )
        out[f"mouthFrown{suffix}"] = vec(corner, (sgn * 0.0015, -0.007, 0.0))
        out[f"mouthDimple{suffix}"] = vec(corner, (sgn * 0.0035, 0.001, -0.0045))
        out[f"mouthStretch{suffix}"] = vec(corner, (sgn * 0.0075, -0.0025, -0.002))
        out[f"mouthPress{suffix}"] = (
            vec(upper_lip * half, (0.0, -0.0012, -0.0008))
            + vec(lower_lip * half, (0.0, 0.0015, -0.0008))
            + vec(corner, (sgn * 0.001, 0.0, 0.0))
        )
        out[f"mouthLowerDown{suffix}"] = vec(lower_lip * half, (0.0, -0.0055, 0.0008))
        out[f"mouthUpperUp{suffix}"] = vec(upper_lip * half, (0.0, 0.0055, 0.0008))

    # --- brows (kept off the eyelids by the eye slits' side fields) ---
    # The brow moves as a band: rigid within 3 mm of its painted line, the forehead above following over ~2 cm
    # and the lid fold below over ~7 mm. Along the brow, AU1's (browInnerUp) share fades out as AU2's
    # (browOuterUp) fades in, the two summing to one, so raising both lifts the whole brow into a higher, rounder
    # arch (surprise) instead of a wavy, oblique line (inner alone stays oblique: sadness). Frontalis' medial
    # and lateral bellies: Ekman, Friesen & Hager (2002), FACS Manual ch. 3, AU1 and AU2.
    def brow_band(eye: int, s_up: float = 0.020, s_down: float = 0.0065) -> np.ndarray:
        dy = yd - brow_line(x)
        d = np.sign(dy) * np.maximum(np.abs(dy) - 0.003, 0.0)
        sy = np.where(d >= 0, s_up, s_down)
        return front * mesh.upper_lid_side[:, eye] * np.exp(-0.5 * (d / sy) ** 2)

    t_brow = (np.abs(x) - 0.012) / 0.044  # 0 at the brow's inner end, 1 at its tail (as brow_line)
    to_tail = smoothstep(0.15, 0.85, t_brow)
    lateral_fade = 1.0 - smoothstep(1.0, 1.6, t_brow)
    inner_share = (1.0 - to_tail) * (0.55 + 0.45 * smoothstep(0.0, 0.012, np.abs(x)))
    outer_share = (to_tail + 0.25 * np.exp(-0.5 * ((t_brow - 0.6) / 0.2) ** 2)) * lateral_fade
    left_half = 0.5 * (1.0 + np.tanh(x / 0.004))
    inner = brow_band(0) * left_half + brow_band(1) * (1.0 - left_half)
    # The inner brow's raise lifts the lid fold's skin, not the upper lid's margin (the levator, AU5, does that):
    # widened inner lids turned the built-in b head's sadness into fear (docs/VALIDATION.md, issue 31).
    hold = margin_hold(mesh, BROW_LID_HOLD_M)
    out["browInnerUp"] = vec(inner * inner_share * hold, (0.0, 0.012, 0.0005))

    def brow(cx: float, cy: float, sx: float, eye: int) -> np.ndarray:
        return front * mesh.upper_lid_side[:, eye] * _gauss_asym(x, yd, cx, cy, sx, 0.02, 0.0065)

    inner_y, mid_y = (float(brow_line(bx)) for bx in (0.017, 0.031))
    for suffix, sgn, eye in (("Left", 1.0, 0), ("Right", -1.0, 1)):
        whole = brow(sgn * 0.031, mid_y, 0.019, eye)
        inner_side = brow(sgn * 0.017, inner_y, 0.010, eye)
        out[f"browDown{suffix}"] = vec(whole, (-sgn * 0.0035, -0.0060, 0.0015)) + vec(
            inner_side, (-sgn * 0.002, -0.001, 0.001)
        )
        side = 0.5 * (1.0 + np.tanh(sgn * x / 0.004))
        out[f"browOuterUp{suffix}"] = vec(brow_band(eye) * side * outer_share, (0.0, 0.011, 0.0))

    # --- cheeks and nose ---
    ax = np.abs(x)
    puff = front * gauss(ax, yd, 0.042, -0.062, 0.014, 0.016)
    out["cheekPuff"] = puff[:, None] * np.stack([np.sign(x) * 0.006, 0 * x, 0.005 + 0 * x], 1)
    for suffix, sgn, eye in (("Left", 1.0, 0), ("Right", -1.0, 1)):
        upper, lower, span = lid_weights(mesh, eye)
        cheek = front * gauss(x, yd, sgn * 0.036, -0.027, 0.012, 0.011) * (1.0 - lower)
        lid = _rot_x(v, shape.eye_centers[eye], lower * 0.15 * span) - v
        out[f"cheekSquint{suffix}"] = vec(cheek, (sgn * 0.0005, 0.004, 0.0015)) + lid
        sneer = (
            vec(front * gauss(x, yd, sgn * 0.011, -0.038, 0.007, 0.011), (0.0, 0.004, 0.0005))
            + vec(front * gauss(x, yd, sgn * 0.009, -0.018, 0.006, 0.009), (0.0, 0.0015, -0.0005))
            + vec(front * (1.0 - low) * gauss(x, yd, sgn * 0.012, -0.057, 0.008, 0.006), (0.0, 0.002, 0.0))
        )
        out[f"noseSneer{suffix}"] = sneer

    # --- tongue: slides forward out of the mouth, the tip most ---
    tongue = mesh.part == TONGUE
    reach = np.zeros(n)
    if tongue.any():
        z_t = v[tongue, 2]
        reach[tongue] = 0.35 + 0.65 * (z_t - z_t.min()) / max(float(np.ptp(z_t)), 1e-9)
    out["tongueOut"] = vec(reach, (0.0, -0.004, 0.026))

    missing = [name for name in ARKIT_NAMES if name not in out]
    assert not missing, missing
    _close_corners(out, mesh)
    return {name: out[name] for name in ARKIT_NAMES}


def margin_hold(mesh: HeadMesh, reach_m: float) -> np.ndarray:
    """(n,) 0..1 share of a brow raise each vertex keeps: 0 on and below the upper lids' margins (the eye corners
    too), rising smoothly to 1 ``reach_m`` (metres) above them; 1 beside and away from the eyes."""
    shape = mesh.shape
    x, yd = mesh.material[:, 0], mesh.material[:, 1]
    hold = np.ones(len(x))
    for e in (0, 1):
        c = shape.eye_centers[e]
        t = np.clip((x - c[0]) / shape.eye_half_width_m, -1.0, 1.0)
        h_up, _ = lid_heights(t, shape)
        lateral = 1.0 - smoothstep(shape.eye_half_width_m, shape.eye_half_width_m + 0.006, np.abs(x - c[0]))
        hold *= 1.0 - lateral * (1.0 - smoothstep(0.0, reach_m, yd - h_up))
    return hold


def _close_corners(out: dict[str, np.ndarray], mesh: HeadMesh) -> None:
    """Move the two lips' edges near each mouth corner together in :data:`LIPS_PARTING` (in place)."""
    seam = mesh.mouth_seam
    half_width = mesh.shape.mouth_half_width_m
    for upper_key, lower_key in (("upper", "lower"), ("inner_upper", "inner_lower")):
        upper, lower = seam[upper_key], seam[lower_key]
        if len(upper) != len(lower):
            continue
        apart = smoothstep(0.0, CORNER_CLOSE_M, half_width - np.abs(mesh.material[upper, 0]))[:, None]
        for name in LIPS_PARTING:
            delta = out[name]
            middle = 0.5 * (delta[upper] + delta[lower])
            delta[upper] = middle + (delta[upper] - middle) * apart
            delta[lower] = middle + (delta[lower] - middle) * apart
