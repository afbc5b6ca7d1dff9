"""Broekens' feature-point rig: 18 MPEG-4 feature points whose moves spread over the skin as one smooth field.

Broekens, Qu & Brinkman (*Dynamic Facial Expression of Emotion Made Easy*) model each feature as an anchor
"attached to a set of vertices" and each emotion as a displacement vector per feature (their Table 1). Here
each anchor is the face-surface vertex nearest the mean of some iBUG-68 landmarks (``data/mpeg4_features.csv``
says which, with the MPEG-4 feature point it stands for), so any mesh with a landmark map is instrumented
without hand rigging.

**The deformation rule.** Each feature's field is the smoothest surface function (biharmonic,
:mod:`mien.rig.harmonic`) that is 1 on the feature's plateau (the anchor and the skin within ``plateau_m``), holds
every other feature's anchor (the skin within :data:`CORE_M`) at that feature's share (0, or the csv ``rides``
share: the lower lip rides the jaw, the mouth corners half, the upper lip the nostrils' rise), each band
(``data/mpeg4_bands.csv``: a strip of skin within a few millimetres of a landmark chain) at the share of the
features on it by its place along the chain (each brow between its two ends, so it moves as a band, its middle never
sagging toward the lid; each lip's meeting line between its two lip points, held only up and down, so the lips part
only where Table 1 parts them; a feature's region reaches from all of a strip it moves) and every lid margin still
(a lid feature moves its own margin with a raised-cosine falloff along it), and is 0 beyond a geodesic radius. So
each anchor moves exactly by its own Table 1 vector (plus its shares of the features it rides), the skin between
anchors follows the smoothest interpolation of their moves (a lip keeps its curve; the glabella between two inner
brows closing in is compressed evenly, not folded), and the mouth slit and eye openings are natural boundaries (the
field couples only vertices joined by triangles). Off the face surface only the Jaw moves anything: it carries the
lower teeth and tongue by the head's own jaw-opening target's shares (:data:`JAW_TARGET`), so an open mouth shows
the teeth parted, not clenched behind the lips. The smoothest field overshoots a little beyond a held neighbour (at
most about 0.2 of a feature's move, the other way). Summed per-feature falloffs (mien 0.1) put a kink wherever a
region was capped or cut and bunched the skin between neighbouring anchors: creases, flaps, a bow-tie mouth.

Each region is wide enough for its largest design move ``D`` (over the six emotions and four blends at
:data:`DESIGN_INTENSITY`, after the limits below): ``R = P + SPREAD * D``, between the csv radius and
:data:`GROWTH_LIMIT` times it.

**Moves toward a barrier are softly limited** (:func:`feature_rooms`, :func:`limit_moves`, applied by
:class:`mien.rig.driver.RigDriver`). Table 1's vectors are metres on an unknown-scale FaceGen head; on ICT the
inner brows sit 12 mm from the midline and anger asks 31 mm inward at 2.4, so exact motion must fold. A move
toward a barrier (an inner brow, a lip point or a mouth corner toward the facial midline, a mouth corner out
toward the jaw line, a brow down onto its upper lid, a cheek up onto its lower lid, a lid onto the other lid,
the upper lip up to the nostrils, the lower lip back toward the teeth, whose depth the chin's front stands for)
becomes ``L tanh(w / L)`` with ``L = room * gap``, ``gap`` the neutral distance from the feature's landmarks
to the barrier along that axis and ``room`` from the csv (0.5; 0.4 for the lids, so two closing lids never
meet; a move that pushes its barrier ahead of it, :data:`LID_PUSHES`, the inner brows lowering the upper lids, gets
``room * gap / (1 - share)``, the gap closing that much more slowly). Small moves stay exact (slope 1 at 0), large
ones approach ``L``. Moves away from a barrier and every
other move are exact and linear: twice the intensity, twice the move. The compiled targets themselves stay
linear and exact at the anchor.

The rig compiles into 54 sparse morph targets ``fp_<Feature>_x/_y/_z``: weight 1 moves the region 1 m along
rig +x (the character's left), +y (up) or +z (forward) times its field. A Table 1 vector ``(z, x, y)`` (+x the
viewer's right = the character's left, +y down) at intensity ``s`` becomes the target weights
``(x s, -y s, z s)``: see :func:`table1_weights`.

>>> from mien.rig.builtin_head import builtin_head
>>> rig = builtin_head()
>>> fp = FeaturePointRig.build(rig)
>>> targets = fp.compile()
>>> len(targets), targets[0].name
(54, 'fp_Jaw_x')
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache

import numpy as np

from mien.affect.emotions import BLENDS, EMOTIONS, emotion_vector
from mien.affect.table1 import broekens_to_rig, table1_rig_vectors
from mien.errors import InvalidValueError, UnknownNameError
from mien.fileio.tables import read_table
from mien.rig.geodesic import EdgeGraph
from mien.rig.harmonic import BiharmonicSystem
from mien.rig.model import MorphTarget, Rig

__all__ = [
    "AXES",
    "BUNCHES",
    "BUNCH_ROOM",
    "EYE_SLIDE_FEATURES",
    "FEATURE_NAMES",
    "BandSpec",
    "FeaturePointRig",
    "FeatureSpec",
    "band_shares",
    "band_specs",
    "eye_slide",
    "feature_rooms",
    "feature_specs",
    "feature_target_names",
    "limit_moves",
    "table1_weights",
]

AXES = ("x", "y", "z")
"""Axis suffixes of the compiled targets (rig frame)."""
DESIGN_INTENSITY = 2.4
"""Emotion intensity the regions are shaped for: the strongest of Broekens' study (1.2 and 2.4)."""
SPREAD = 3.0
"""Region radius beyond the plateau per metre of design move: a biharmonic bump's steepest slope is about
1.5 / (R - P), so the skin in front of a moving anchor compresses by at most about half at :data:`DESIGN_INTENSITY`."""
GROWTH_LIMIT = 3.0
"""Largest factor by which a large design move widens a region beyond its csv radius."""
PLATEAU_SIDE_MARGIN_M = 0.006
"""How much closer (m) to its ``closer_to`` landmarks than to its ``than`` landmarks a plateau vertex must be."""
CORE_M = 0.003
"""Geodesic radius (m) of the patch around another feature's anchor that a feature's field holds at that
feature's share (its own plateau, e.g. the jaw's whole chin, binds only its own field)."""
JAW_TARGET = "jawOpen"
"""The head's own target whose off-surface moves (lower teeth, tongue) the Jaw feature carries."""
MIDLINE_LANDMARKS = (27, 28, 29, 30)
"""iBUG nose-bridge landmarks whose mean x is the facial midline."""
LID_PUSHES: tuple[tuple[str, str, str, float, float], ...] = (("BrowInner", "LidUpper", "-y", 0.5, 0.3),)
"""``(pusher, lid, toward, share, widen)``: a feature whose limited move heads for its lid (rig axis and sign
``toward``) pushes that lid the same way by ``share`` of the move, on both sides (:func:`limit_moves`), and its own
room toward the lid is ``room * gap / (1 - widen)`` (:func:`feature_rooms`: the lid goes ahead of it).

Every lid margin is held by every other feature's field, so a lowered brow left the upper lid where it was: Table 1
lowers anger's inner brows 14 mm at 1.2 and leaves the upper lids still, and ICT showed knitted brows over wide-open
eyes, with anger's parted lips a look of surprise (frontal feature-point anger at 2.4 read surprise in 2 of 4 renders
under the averaged judge) or of nothing (at 1.2 neutral in 3 of 4). The brow lowerer narrows the eye as it lowers
the brow (Ekman & Friesen, FACS manual: AU4 pushes the upper lid down). Now the upper lid goes down by half the inner
brow's limited fall (ICT a at 1.2: brow 10.8 mm, was 8.7; lid 3.0 mm, toward its room of 3.2), and ICT's frontal
feature-point anger reads anger in 7 of 8 renders (was 3 of 8; docs/VALIDATION.md). Only a fall pushes: a raised
brow (surprise, fear, sadness) leaves the lids as Table 1 sets them. ``widen`` 0.3, not the full share: at 0.35 the
built-in head's left upper lid turned 1-3 triangles over in anger, frustrated and evil at 2.4. A raised cheek pushing
its lower lid up the same way (0.3) made ICT a's joy at 1.2 read neutral more (happy 0.33 -> 0.28): not used."""
BUNCHES: tuple[tuple[str, str, str, float], ...] = (("Cheek", "+y", "+z", 0.4),)
"""``(feature, toward, into, share)``: what :func:`limit_moves` takes from a feature's move toward its barrier (rig
axis and sign ``toward``, both sides) moves that feature's skin along ``into`` by ``share`` of it, softly limited to
:data:`BUNCH_ROOM` times the move's own limit: the skin that cannot slide further bunches.

Table 1 raises the cheeks 11 mm per unit of joy (13.2 mm at 1.2), and the smoothest field slid the whole cheek up as
one piece (10.2 mm on ICT at 1.2, its room 0.5 of the gap to the lower lid): the cheek's mound rose toward the eye,
the skin below it turned hollow and a shadow ran from the inner eye corner down beside the nose, a gaunt face (ICT
a's frontal joy at 1.2 read neutral 0.55 over happy 0.33). Pasting the FACS basis's cheeks alone into that picture
(the band beside the nose between the eyes and the mouth) made it read happy 0.55; its mouth made it read less happy.
The cheek raiser does not slide the cheek onto the eye: it pushes the skin toward the eye, where it bunches and bags
below the lower lid (Ekman & Friesen, FACS manual: AU6), and ICT's own cheek raise and smile bring the cheek forward
0.4 mm per mm they raise it (cheekSquint 2.0 mm for 5.4 mm, mouthSmile 2.0 for 4.4, at the cheek's anchor). So the
cheek's room toward its lower lid is 0.2 of the gap (``data/mpeg4_features.csv``; 5.4 mm on ICT at 1.2 and at 2.4),
0.4 of what the limit takes comes forward (2.9 mm at 1.2, 5.7 at 2.4 on ICT), and the cheek raiser's skin detail
(``cheekSquint``, :mod:`mien.rig.fp_correctives`) follows that bunching. With the smile's detail driven by the
corner's move in the picture plane (``mpeg4_correctives.csv``) ICT's frontal feature-point joy at 1.2 reads happy at
1 m and 3 m on both identities (docs/VALIDATION.md). Room 0.1 read the same on ICT but turned one to five triangles
over beside the built-in head's mouth corners in joy at 2.4, where the cheek no longer rose with the corner."""
BUNCH_ROOM = 1.25
"""How far the skin of a :data:`BUNCHES` feature comes forward at most, in multiples of its move's own limit ``L``
(softly: ``R tanh(share * taken / R)``, ``R = BUNCH_ROOM * L``; 6.8 mm on ICT): uncapped, joy at 2.4 pushed ICT's
cheeks 9.5 mm forward."""
EYE_SLIDE_M = 0.008
"""Skin within this distance of an eyeball's surface slides over it (:func:`eye_slide`)."""
EYE_SLIDE_FULL = 0.5
"""Share of :data:`EYE_SLIDE_M` next to the eyeball where the slide is whole."""
EYE_SLIDE_FEATURES = ("LidUpper", "LidLower")
"""Features (both sides) whose moves slide over the eyeballs: the lids (a brow's or a cheek's large move turned
triangles over where its slide faded)."""


@dataclass(frozen=True)
class FeatureSpec:
    """One row of ``data/mpeg4_features.csv``."""

    name: str
    """Feature name as in Broekens' Table 1 (``LipCornerLeft``...)."""
    mpeg4_fp: str
    """MPEG-4 feature point(s) it stands for (``8.3``...)."""
    landmarks: tuple[int, ...]
    """0-based iBUG-68 landmarks whose mean places the anchor."""
    radius_m: float
    """Geodesic radius of the region, metres (widened for large design moves)."""
    plateau_m: float
    """Geodesic distance within which the feature moves the skin rigidly, metres."""
    closer_to: tuple[int, ...]
    """Landmarks a plateau vertex must be geodesically closer to than to :attr:`than` (empty = no cut)."""
    than: tuple[int, ...]
    """See :attr:`closer_to`."""
    rides: tuple[tuple[str, tuple[float, float, float]], ...]
    """Features whose moves this feature's anchor shares, each with its share along rig x, y and z
    (``("Jaw", (1, 1, 1))``: the lower lip goes with the jaw)."""
    margin: tuple[int, ...]
    """Lid margin (landmark chain joined along mesh edges) this lid feature moves; empty for the others."""
    barrier: tuple[int, ...]
    """Landmarks whose mean the move along :attr:`toward` heads for (empty = none)."""
    toward: str
    """Rig axis and sign of the move toward :attr:`barrier` (``"-y"`` down onto the upper lid, ``"+y"``, ``"+x"``
    out to the character's left); ``""``."""
    medial: bool
    """Whether the feature's x move toward the facial midline is limited (the inner brows)."""
    room: float
    """Fraction of the neutral gap to the barrier (or midline) that a limited move approaches; 0 = none."""


def _ints(text: str) -> tuple[int, ...]:
    return tuple(int(t) for t in text.split())


def _rides(text: str) -> tuple[tuple[str, tuple[float, float, float]], ...]:
    """``"Jaw 1; LipCornerLeft 0 0.35 0"`` -> per feature its share along rig x, y, z (one share: all three)."""
    rides = []
    for part in text.split(";"):
        words = part.split()
        if words:
            shares = [float(w) for w in words[1:]]
            x, y, z = (shares * 3)[:3] if len(shares) == 1 else shares
            rides.append((words[0], (float(x), float(y), float(z))))
    return tuple(rides)


def _data_rows(name: str) -> list[dict[str, str]]:
    return read_table("mien.rig", f"data/{name}")


@cache
def feature_specs() -> tuple[FeatureSpec, ...]:
    """The 18 feature specs from ``data/mpeg4_features.csv``, in Broekens' Table 1 order."""
    specs = []
    for row in _data_rows("mpeg4_features.csv"):
        specs.append(
            FeatureSpec(
                name=row["feature"],
                mpeg4_fp=row["mpeg4_fp"],
                landmarks=_ints(row["landmarks"]),
                radius_m=float(row["radius_m"]),
                plateau_m=float(row["plateau_m"]),
                closer_to=_ints(row["closer_to"]),
                than=_ints(row["than"]),
                rides=_rides(row["rides"]),
                margin=_ints(row["margin"]),
                barrier=_ints(row["barrier"]),
                toward=row["toward"].strip(),
                medial=row["medial"].strip() == "1",
                room=float(row["room"] or 0.0),
            )
        )
    return tuple(specs)


FEATURE_NAMES: tuple[str, ...] = tuple(spec.name for spec in feature_specs())
"""The 18 feature names in Table 1 order: ``Jaw``, ``Nostrils``, ``LipLowerLeft``, ... ``BrowOuterRight``."""


@dataclass(frozen=True)
class BandSpec:
    """One row of ``data/mpeg4_bands.csv``: a strip of skin that moves at the shares of the features on it."""

    name: str
    """Band name (``BrowLeft``...)."""
    mpeg4_fp: str
    """MPEG-4 feature points on it (``4.1 4.3 4.5``)."""
    chain: tuple[int, ...]
    """0-based iBUG-68 landmarks along it, from the first stop's landmark to the last's."""
    stops: tuple[tuple[str, int], ...]
    """The features whose shares the band takes, each with the chain landmark where its share is whole, in chain
    order; the first sits on the chain's first landmark, the last on its last."""
    half_width_m: float
    """Geodesic half-width of the strip held about the chain, metres."""
    axes: str
    """The rig axes along which the strip is held (``"xyz"``; ``"y"``: only up and down, free to slide)."""


@cache
def band_specs() -> tuple[BandSpec, ...]:
    """The bands from ``data/mpeg4_bands.csv`` (the two brows, the lips' meeting lines)."""
    bands = []
    for row in _data_rows("mpeg4_bands.csv"):
        stops = []
        for item in row["stops"].split():
            feature, _, at = item.partition(":")
            stops.append((feature, int(at)))
        chain = _ints(row["chain"])
        held = row["axes"].strip()
        band = BandSpec(row["band"], row["mpeg4_fp"], chain, tuple(stops), float(row["half_width_m"]), held)
        if not held or any(a not in AXES for a in held) or len(set(held)) != len(held) or list(held) != sorted(held):
            raise InvalidValueError(f"axes of band {band.name}", held, "some of x, y, z in that order, e.g. xyz or y")
        for feature, landmark in band.stops:
            if feature not in FEATURE_NAMES:
                raise UnknownNameError(f"feature on band {band.name}", feature, FEATURE_NAMES)
            if landmark not in chain:
                raise InvalidValueError(f"landmark of {feature} on band {band.name}", landmark, f"one of {chain}")
        places = [chain.index(landmark) for _, landmark in band.stops]
        if places[0] != 0 or places[-1] != len(chain) - 1 or places != sorted(set(places)):
            raise InvalidValueError(f"stops of band {band.name}", row["stops"], "stops in chain order, first to last")
        bands.append(band)
    return tuple(bands)


def feature_target_names() -> tuple[str, ...]:
    """The 54 compiled target names: ``fp_<Feature>_x``, ``_y``, ``_z`` per feature in Table 1 order."""
    return tuple(f"fp_{name}_{axis}" for name in FEATURE_NAMES for axis in AXES)


def _falloff(d: np.ndarray, plateau: float, radius: float) -> np.ndarray:
    """1 up to ``plateau``, a raised-cosine fall to 0 at ``radius`` (zero slope at both ends)."""
    t = np.clip((d - plateau) / max(radius - plateau, 1e-9), 0.0, 1.0)
    return np.asarray(0.5 * (1.0 + np.cos(np.pi * t)))


def feature_rooms(rig: Rig) -> np.ndarray:
    """(2, 54) float64 metres: per target column the limit ``L`` of its negative (row 0) and positive (row 1)
    weights (:func:`limit_moves`); ``inf`` where the move is exact.

    ``L = room * gap``: ``gap`` is the neutral distance along the move's axis from the mean of the feature's
    landmarks to the mean of its barrier landmarks (or, for a medial move, to the facial midline, the mean x
    of :data:`MIDLINE_LANDMARKS`). Landmarks only, so a driver computes it in microseconds. A rig without a
    (68,) landmark map, or whose landmarks coincide, gets no limits.
    """
    rooms = np.full((2, 3 * len(FEATURE_NAMES)), np.inf)
    landmarks = np.asarray(rig.landmarks, dtype=np.int64)
    if landmarks.shape != (68,) or landmarks.min() < 0 or landmarks.max() >= rig.n_vertices:
        return rooms
    points = np.asarray(rig.neutral, dtype=np.float64)[landmarks]
    midline = float(points[list(MIDLINE_LANDMARKS), 0].mean())
    for f, spec in enumerate(feature_specs()):
        if spec.room <= 0:
            continue
        own = points[list(spec.landmarks)].mean(axis=0)
        if spec.barrier and spec.toward:
            axis = AXES.index(spec.toward[1])
            gap = abs(float(points[list(spec.barrier), axis].mean()) - own[axis])
            if gap > 1e-6:
                # a feature that pushes its lid ahead of it (LID_PUSHES) closes the gap more slowly
                follow = sum(
                    widen
                    for pusher, _, toward, _, widen in LID_PUSHES
                    if spec.name.startswith(pusher) and spec.toward == toward
                )
                rooms[0 if spec.toward[0] == "-" else 1, 3 * f + axis] = spec.room * gap / (1.0 - follow)
        if spec.medial:
            gap = abs(own[0] - midline)
            if gap > 1e-6:
                rooms[0 if own[0] > midline else 1, 3 * f] = spec.room * gap
    return rooms


def limit_moves(weights: np.ndarray, rooms: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Softly limit (..., 54) feature weights (metres) by ``rooms`` (2, 54) from :func:`feature_rooms`.

    A weight ``w`` whose side has a finite limit ``L`` becomes ``L tanh(w / L)`` (exact for small moves,
    never past ``L``); the others are copied. With all 54 weights, a lowered inner brow then pushes its upper lid
    down by its share (:data:`LID_PUSHES`; the lid's own move plus the push, limited by the lid's room). ``out``
    may be ``weights`` itself.

    >>> rooms = np.full((2, 2), np.inf); rooms[0, 0] = 0.005
    >>> limit_moves(np.array([-0.001, -0.02]), rooms[:, :1].repeat(2, axis=1)).round(4).tolist()
    [-0.001, -0.005]
    >>> limit_moves(np.array([0.02, -0.02]), rooms).tolist()
    [0.02, -0.02]
    """
    values = np.asarray(weights, dtype=np.float64)
    if values.shape[-1] == 3 * len(FEATURE_NAMES):  # the lids' own moves, before ``out`` may overwrite them
        lids = np.array(values[..., _pushed_columns()], copy=True)
        asked = np.array(values[..., _bunched_columns()[0]], copy=True)
    result = np.array(values, copy=True) if out is None else out
    if out is not None and out is not weights:
        result[...] = values
    for side, sign in ((0, -1.0), (1, 1.0)):
        limit = rooms[side]
        cols = np.flatnonzero(np.isfinite(limit))
        if cols.size == 0:
            continue
        part = values[..., cols]
        bound = limit[cols]
        capped = sign * bound * np.tanh(sign * part / bound)
        result[..., cols] = np.where(sign * part > 0, capped, result[..., cols])
    if values.shape[-1] == 3 * len(FEATURE_NAMES):
        _push_lids(lids, rooms, result)
        _bunch(asked, rooms, result)
    return result


@cache
def _bunched_columns() -> tuple[list[int], list[int], list[float], list[float]]:
    """``(moved, bunched, signs, shares)``: per :data:`BUNCHES` row and side, the 54-weight column of the limited
    move, the column the skin bunches along, the sign of the move toward the barrier and the share."""
    moved, bunched, signs, shares = [], [], [], []
    for feature, toward, into, share in BUNCHES:
        for side in ("Left", "Right"):
            f = 3 * FEATURE_NAMES.index(feature + side)
            moved.append(f + AXES.index(toward[1]))
            bunched.append(f + AXES.index(into[1]))
            signs.append(1.0 if toward[0] == "+" else -1.0)
            shares.append(share if into[0] == "+" else -share)
    return moved, bunched, signs, shares


def _bunch(asked: np.ndarray, rooms: np.ndarray, result: np.ndarray) -> None:
    """What the limit took from each :data:`BUNCHES` move (``asked`` less its limited value in ``result``) moves
    the skin along the row's ``into`` axis by its share, softly limited to :data:`BUNCH_ROOM` times the move's own
    limit, in place."""
    moved, bunched, signs, shares = _bunched_columns()
    for k, (m, b, sign, share) in enumerate(zip(moved, bunched, signs, shares, strict=True)):
        bound = rooms[1 if sign > 0 else 0, m]
        if not np.isfinite(bound):
            continue
        taken = np.maximum(sign * (asked[..., k] - result[..., m]), 0.0)
        reach = BUNCH_ROOM * bound
        result[..., b] = result[..., b] + np.sign(share) * reach * np.tanh(abs(share) * taken / reach)


@cache
def _pushed_columns() -> list[int]:
    """The 54-weight columns of the lids :data:`LID_PUSHES` pushes, in its order (Left, Right for each)."""
    return [
        3 * FEATURE_NAMES.index(lid + side) + AXES.index(toward[1])
        for _, lid, toward, _, _ in LID_PUSHES
        for side in ("Left", "Right")
    ]


def _push_lids(lids: np.ndarray, rooms: np.ndarray, result: np.ndarray) -> None:
    """Each :data:`LID_PUSHES` feature's limited move toward its lid (in ``result``) moves the lid by its share:
    the lid's own move (``lids``, :func:`_pushed_columns`) plus the push, limited by the lid's room, in place."""
    columns = iter(enumerate(_pushed_columns()))
    for pusher, _, toward, share, _ in LID_PUSHES:
        axis = AXES.index(toward[1])
        sign = 1.0 if toward[0] == "+" else -1.0
        for side in ("Left", "Right"):
            k, lid = next(columns)
            push = result[..., 3 * FEATURE_NAMES.index(pusher + side) + axis]
            raw = lids[..., k] + share * sign * np.maximum(sign * push, 0.0)
            bound = rooms[1 if sign > 0 else 0, lid]
            if np.isfinite(bound):
                raw = np.where(sign * raw > 0, sign * bound * np.tanh(sign * raw / bound), raw)
            result[..., lid] = raw


def design_moves(rooms: np.ndarray | None = None) -> np.ndarray:
    """(18,) float64 metres: per feature the largest anchor move at :data:`DESIGN_INTENSITY` over Broekens' six
    emotions and four blends, each limited by ``rooms`` (2, 54) when given."""

    vectors = table1_rig_vectors()
    moves = np.stack(
        [np.tensordot(emotion_vector(name, DESIGN_INTENSITY), vectors, axes=1) for name in EMOTIONS + tuple(BLENDS)]
    )
    if rooms is not None:
        moves = limit_moves(moves.reshape(len(moves), -1), rooms).reshape(moves.shape)
    return np.asarray(np.linalg.norm(moves, axis=2).max(axis=0))


def eye_slide(rig: Rig, surface: np.ndarray) -> np.ndarray:
    """(n, 2, 3) float64: what each vertex moves besides a 1 m move along rig x (``[:, 0]``) or y (``[:, 1]``).

    A lid margin lies on a sphere about its eyeball; moved straight down (Table 1's disgust closes the lids
    6 mm at intensity 2.4) it went through the eyeball, which showed through the lid as blue patches. A vertex
    on ``surface`` within :data:`EYE_SLIDE_M` of an eyeball (``rig.regions["eye_L"]``/``"eye_R"`` about
    ``rig.eye_centers``) instead moves in the tangent plane of the sphere through it, so it never enters the
    sphere: in front of the eye (``n``, its direction from the eye centre, facing forward) its x and y moves stay
    exactly as asked and it moves forward by ``-(n_x dx + n_y dy) / n_z``; at the eye's sides, where the skin turns
    away, the move loses its part along ``n``. Both are linear in the move, so the targets stay morph targets;
    the slide fades out beyond :data:`EYE_SLIDE_FULL` of the band. Only the lids' moves slide
    (:data:`EYE_SLIDE_FEATURES`; a brow's or a cheek's large move turned triangles over where its slide faded).
    """
    out = np.zeros((rig.n_vertices, 2, 3))
    neutral = np.asarray(rig.neutral, dtype=np.float64)
    for side, centre in zip("LR", np.asarray(rig.eye_centers, dtype=np.float64), strict=True):
        ball = rig.regions.get(f"eye_{side}")
        if ball is None or len(ball) == 0:
            continue
        radius = float(np.median(np.linalg.norm(neutral[ball] - centre, axis=1)))
        d = neutral - centre
        r = np.linalg.norm(d, axis=1)
        near = np.flatnonzero(surface & (r < radius + EYE_SLIDE_M) & (r > 0.5 * radius))
        n = d[near] / r[near, None]
        share = np.clip((radius + EYE_SLIDE_M - r[near]) / ((1.0 - EYE_SLIDE_FULL) * EYE_SLIDE_M), 0.0, 1.0)
        nz = np.maximum(n[:, 2], 1e-3)
        forward = np.zeros((len(near), 2, 3))
        forward[:, :, 2] = -n[:, :2] / nz[:, None]  # e_a + this is tangent: (e_a - n_a / n_z e_z) . n = 0
        across = -n[:, :2, None] * n[:, None, :]  # e_a - n_a n
        front = np.clip((n[:, 2] - 0.3) / 0.3, 0.0, 1.0)[:, None, None]
        out[near] = (front * forward + (1.0 - front) * across) * share[:, None, None]
    return out


def _jaw_carried(rig: Rig, chin: int, surface: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(ids, shares)`` of the vertices off the face surface (lower teeth, tongue) that the jaw carries.

    The head's own jaw-opening target (:data:`JAW_TARGET`) says which: each moves with the Jaw feature by its
    displacement there relative to the chin's (1 for the lower teeth, less toward the back of the tongue). A rig
    without that target carries nothing, and its teeth stay put as the skin opens.
    """
    target = next((t for t in rig.targets if t.name == JAW_TARGET), None)
    if target is None:
        return np.zeros(0, np.int64), np.zeros(0)
    dense = target.dense(rig.n_vertices)
    chin_move = float(np.linalg.norm(dense[chin]))
    if chin_move <= 1e-6:
        return np.zeros(0, np.int64), np.zeros(0)
    ids = target.vertex_ids[~surface[target.vertex_ids]].astype(np.int64)
    shares = np.clip(np.linalg.norm(dense[ids], axis=1) / chin_move, 0.0, 1.0)
    return ids, shares


def _chain(graph: EdgeGraph, landmarks: np.ndarray, chain: tuple[int, ...]) -> np.ndarray:
    """Vertex ids in order along a chain of landmarks joined by shortest edge paths (a lid margin stays on its
    lid), from its first landmark to its last."""
    path = [np.asarray([landmarks[chain[0]]], dtype=np.int64)]
    for a, b in itertools.pairwise(chain):
        path.append(graph.path(int(landmarks[a]), int(landmarks[b]))[1:])
    return np.concatenate(path)


def _band(
    graph: EdgeGraph, neutral: np.ndarray, landmarks: np.ndarray, band: BandSpec
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(ids, along, stops)``: the surface vertices within ``band.half_width_m`` of ``band``'s landmark chain, each
    one's place along the chain (0 at its first landmark, 1 at its last, by the arc length of the nearest chain
    vertex) and the place of each of the band's stops."""
    chain = _chain(graph, landmarks, band.chain)
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(neutral[chain], axis=0), axis=1))])
    arc /= max(float(arc[-1]), 1e-9)
    ids = np.flatnonzero(graph.distances(chain, limit_m=band.half_width_m) <= band.half_width_m)
    nearest = np.argmin(np.linalg.norm(neutral[ids, None] - neutral[chain][None], axis=2), axis=1)
    along = arc[nearest]
    on_chain = np.isin(ids, chain)  # a chain vertex keeps its own place (a slit's two sides can coincide)
    along[on_chain] = arc[[int(np.flatnonzero(chain == i)[-1]) for i in ids[on_chain]]]
    stops = arc[[int(np.flatnonzero(chain == landmarks[landmark])[0]) for _, landmark in band.stops]]
    return ids, along, stops


def _same_columns(mask: np.ndarray) -> list[list[int]]:
    """Columns of the (n, k) ``mask`` grouped where they are equal, each group in ascending order."""
    groups: list[list[int]] = []
    for c in range(mask.shape[1]):
        for group in groups:
            if np.array_equal(mask[:, group[0]], mask[:, c]):
                group.append(c)
                break
        else:
            groups.append([c])
    return groups


def band_shares(band: BandSpec, along: np.ndarray, places: np.ndarray, feature: FeatureSpec) -> np.ndarray:
    """(k, 3) share of ``feature``'s move (rig x, y, z) at band places ``along``: each stop's own feature whole and
    the features its anchor rides by their share, interpolated linearly between neighbouring stops.

    >>> brow = band_specs()[0]
    >>> inner = feature_specs()[FEATURE_NAMES.index("BrowInnerLeft")]
    >>> band_shares(brow, np.array([0.0, 0.25, 1.0]), np.array([0.0, 1.0]), inner)[:, 1].tolist()
    [1.0, 0.75, 0.0]
    """
    specs = {spec.name: spec for spec in feature_specs()}
    out = np.zeros((len(along), 3))
    for s, (stop, _) in enumerate(band.stops):
        hat = np.zeros(len(places))
        hat[s] = 1.0
        weight = np.interp(along, places, hat)
        rides = dict(specs[stop].rides)
        share = np.ones(3) if stop == feature.name else np.asarray(rides.get(feature.name, (0.0, 0.0, 0.0)))
        out += weight[:, None] * share[None, :]
    return out


@dataclass(frozen=True, eq=False)
class FeaturePointRig:
    """Anchors and smooth fields of the 18 feature points on one mesh."""

    names: tuple[str, ...]
    """Feature names (:data:`FEATURE_NAMES`)."""
    anchors: np.ndarray
    """(18,) int32 anchor vertex of each feature."""
    region_ids: tuple[np.ndarray, ...]
    """Per feature, (k,) int32 ids of the vertices it moves, ascending."""
    region_weights: tuple[np.ndarray, ...]
    """Per feature, (k, 3) float32 field of its rig x, y and z moves (1 at the anchor)."""
    radii_m: np.ndarray
    """(18,) float64 geodesic radius of each region, metres."""
    rooms: np.ndarray
    """(2, 54) float64 move limits of the rig (:func:`feature_rooms`), metres."""
    slide: np.ndarray
    """(n_vertices, 2, 3) float64 extra move per metre of x and of y move of the skin over the eyeballs
    (:func:`eye_slide`)."""

    @classmethod
    def build(cls, rig: Rig, radii: Mapping[str, float] | None = None) -> FeaturePointRig:
        """Place the anchors on ``rig`` from its iBUG landmarks and solve each feature's field.

        ``radii`` overrides the csv radius (metres) of the named features: the smallest radius, which a large
        design move still widens (see the module docstring); the plateau is kept below it.
        """
        overrides = dict(radii or {})
        for name, value in overrides.items():
            if name not in FEATURE_NAMES:
                raise UnknownNameError("feature point", name, FEATURE_NAMES)
            if not np.isfinite(value) or value <= 0:
                raise InvalidValueError(f"radii[{name!r}]", value, "a radius > 0 metres")
        landmarks = np.asarray(rig.landmarks, dtype=np.int64)
        if landmarks.shape != (68,):
            raise InvalidValueError(f"{rig.name} landmarks", landmarks.shape, "(68,) iBUG vertex ids")
        neutral = np.asarray(rig.neutral, dtype=np.float64)
        graph = EdgeGraph.from_mesh(neutral, rig.faces)
        surface = graph.component(landmarks)
        candidates = np.flatnonzero(surface)
        rooms = feature_rooms(rig)
        reach = design_moves(rooms)
        specs = feature_specs()
        anchors = []
        for spec in specs:
            point = neutral[landmarks[list(spec.landmarks)]].mean(axis=0)
            anchors.append(int(candidates[np.argmin(np.linalg.norm(neutral[candidates] - point, axis=1))]))
        specs_b = band_specs()
        bands = [_band(graph, neutral, landmarks, band) for band in specs_b]
        plateaus, cores, radius, plateau_m = [], [], np.zeros(len(specs)), np.zeros(len(specs))
        for f, spec in enumerate(specs):
            small = float(overrides.get(spec.name, spec.radius_m))
            plateau = plateau_m[f] = min(spec.plateau_m, 0.5 * small)
            radius[f] = np.clip(plateau + SPREAD * reach[f], small, GROWTH_LIMIT * small)
            ids = np.flatnonzero(graph.distances([anchors[f]], limit_m=plateau) <= plateau)
            cores.append(ids[graph.distances([anchors[f]], limit_m=CORE_M)[ids] <= CORE_M])
            if spec.closer_to:
                far = plateau * 2 + 0.03
                d_own = graph.distances(landmarks[list(spec.closer_to)], limit_m=far)[ids]
                d_other = graph.distances(landmarks[list(spec.than)], limit_m=far)[ids]
                ids = ids[np.nan_to_num(d_own, posinf=far) + PLATEAU_SIDE_MARGIN_M < np.nan_to_num(d_other, posinf=far)]
            plateaus.append(np.union1d(ids, [anchors[f]]).astype(np.int64))
        # lid margins: held by every feature but their own lid, which moves them with a falloff along the margin
        margins = [(f, _chain(graph, landmarks, spec.margin)) for f, spec in enumerate(specs) if spec.margin]
        system = BiharmonicSystem(neutral, rig.faces)
        ids_out, weights_out = [], []
        for f, spec in enumerate(specs):
            dist = graph.distances([anchors[f]], limit_m=float(radius[f]))
            band_moves = [
                band_shares(band, along, stops, spec) for band, (_, along, stops) in zip(specs_b, bands, strict=True)
            ]
            for (ids, _, _), share in zip(bands, band_moves, strict=True):  # a region reaches along a band it moves
                moved = ids[np.abs(share).max(axis=1) > 0.0]
                if len(moved):
                    dist = np.minimum(dist, graph.distances(moved, limit_m=float(radius[f])) + plateau_m[f])
            region = np.flatnonzero(dist < radius[f])
            values = np.zeros((rig.n_vertices, 3))
            fixed = np.zeros((rig.n_vertices, 3), bool)  # held, per vertex and rig axis
            for f_margin, chain in margins:
                fixed[chain] = True
                if f_margin == f:
                    own = _falloff(dist[chain], spec.plateau_m, spec.radius_m)[:, None]
                    values[chain] = np.maximum(values[chain], own)
            for g, other in enumerate(specs):
                if g != f:  # the other anchors (their cores) hold still or ride this feature by their share
                    fixed[cores[g]] = True
                    values[cores[g]] = dict(other.rides).get(spec.name, (0.0, 0.0, 0.0))
            for band, (ids, _, _), share in zip(specs_b, bands, band_moves, strict=True):  # still, or its share
                cols = np.array([AXES.index(a) for a in band.axes])
                fixed[np.ix_(ids, cols)] = True
                values[np.ix_(ids, cols)] = share[:, cols]
            fixed[plateaus[f]] = True
            values[plateaus[f]] = 1.0
            field = np.zeros((rig.n_vertices, 3))
            # one solve per distinct set of held vertices in the region (beyond it, held or not, a vertex stays 0)
            for group in _same_columns(fixed[region]):
                held = np.flatnonzero(fixed[:, group[0]])
                field[:, group] = system.fill(held, values[np.ix_(held, np.array(group))], free=region)
            outside = np.ones(rig.n_vertices, bool)
            outside[region] = False
            field[(outside[:, None] & ~fixed) | ~surface[:, None]] = 0.0
            if spec.name == "Jaw":
                carried, shares = _jaw_carried(rig, anchors[f], surface)
                field[carried] = shares[:, None]
            keep = np.flatnonzero(np.abs(field).max(axis=1) > 1e-4)
            ids_out.append(keep.astype(np.int32))
            weights_out.append(field[keep].astype(np.float32))
        return cls(
            names=FEATURE_NAMES,
            anchors=np.asarray(anchors, dtype=np.int32),
            region_ids=tuple(ids_out),
            region_weights=tuple(weights_out),
            radii_m=radius,
            rooms=rooms,
            slide=eye_slide(rig, surface),
        )

    def weights(self, feature: str, n_vertices: int, axis: str | None = None) -> np.ndarray:
        """(n_vertices,) float32 dense field of ``feature`` along rig ``axis`` (None: the largest of the three)."""
        if feature not in self.names:
            raise UnknownNameError("feature point", feature, self.names)
        if axis is not None and axis not in AXES:
            raise UnknownNameError("axis", axis, AXES)
        i = self.names.index(feature)
        values = self.region_weights[i]
        out = np.zeros(n_vertices, np.float32)
        out[self.region_ids[i]] = values.max(axis=1) if axis is None else values[:, AXES.index(axis)]
        return out

    def compile(self) -> tuple[MorphTarget, ...]:
        """The 54 targets ``fp_<Feature>_<axis>``: weight 1 moves the region 1 m along that rig axis (the skin over
        an eyeball also forward, :attr:`slide`)."""
        targets = []
        for f, name in enumerate(self.names):
            for a, axis in enumerate(AXES):
                ids, deltas = self._unit_move(f, a)
                targets.append(MorphTarget(f"fp_{name}_{axis}", ids, deltas.astype(np.float32)))
        return tuple(targets)

    def _unit_move(self, f: int, a: int) -> tuple[np.ndarray, np.ndarray]:
        """``(ids, deltas)``: the vertices feature ``f`` moves and their (k, 3) float64 moves for 1 m along axis
        ``a``: its field along that axis, plus the slide over the eyeballs for a lid's x or y move."""
        field = self.region_weights[f][:, a]
        moved = field != 0
        ids = self.region_ids[f][moved]
        deltas = np.zeros((len(ids), 3))
        deltas[:, a] = field[moved]
        if a < 2 and self.names[f].startswith(EYE_SLIDE_FEATURES):
            deltas += field[moved, None] * self.slide[ids, a]
        return ids, deltas

    def displacement(
        self, vectors_zxy: np.ndarray, intensity: float, n_vertices: int, limited: bool = False
    ) -> np.ndarray:
        """(n_vertices, 3) float64 displacement (m) of Broekens vectors ``(18, 3)`` ``[z, x, y]`` at ``intensity``.

        ``limited``: the moves toward barriers limited as the driver shows them (:func:`limit_moves`);
        otherwise the compiled targets at exactly :func:`table1_weights`.
        """
        weights = table1_weights(vectors_zxy, intensity)
        values = np.array([weights[name] for name in feature_target_names()])
        if limited:
            values = limit_moves(values, self.rooms)
        out = np.zeros((n_vertices, 3))
        for f in range(len(self.names)):
            for a in range(3):
                ids, deltas = self._unit_move(f, a)
                out[ids] += values[3 * f + a] * deltas
        return out


def table1_weights(vectors_zxy: np.ndarray, intensity: float = 1.0) -> dict[str, float]:
    """Target weights of the compiled rig for Broekens vectors (18, 3) ``[z, x, y]`` (metres) at ``intensity``.

    Broekens' frame: +z toward the viewer, +x the viewer's right (the character's left), +y down; in the rig
    frame that is ``(dx, dy, dz) = (x, -y, z)``, so the ``fp_<F>_y`` weight is ``-y * intensity``.

    >>> v = np.zeros((18, 3)); v[FEATURE_NAMES.index("LipCornerLeft")] = [-0.005, 0.009, -0.007]
    >>> w = table1_weights(v, 2.0)
    >>> [round(w[f"fp_LipCornerLeft_{a}"], 6) for a in "xyz"]
    [0.018, 0.014, -0.01]
    """
    vectors = np.asarray(vectors_zxy, dtype=np.float64)
    if vectors.shape != (len(FEATURE_NAMES), 3) or not np.all(np.isfinite(vectors)):
        raise InvalidValueError("vectors_zxy", vectors.shape, f"({len(FEATURE_NAMES)}, 3) finite [z, x, y] metres")
    if not np.isfinite(intensity):
        raise InvalidValueError("intensity", intensity, "a finite number")

    rig_vectors = broekens_to_rig(vectors) * float(intensity)
    return {
        f"fp_{name}_{axis}": float(rig_vectors[f, a])
        for f, name in enumerate(FEATURE_NAMES)
        for a, axis in enumerate(AXES)
    }
