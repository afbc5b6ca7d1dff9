"""Expression bases: how each of the six emotions moves the face at intensity 1.

An expression is ``intensities @ basis`` (Broekens' additive blending with geometric intensity: a blend is
the sum of its components, twice the intensity moves the face twice as far).

* :func:`feature_point_basis` (6, 54): Broekens' Table 1 in the rig frame, metres, flattened feature-major
  as ``fp_<Feature>_x/_y/_z`` (:func:`feature_target_names`): the weights of the feature-point rig's signed
  morph targets (one per feature and axis, 1 m unit moves).
* :func:`facs_basis` (6, 62): the EMFACS prototypes of :mod:`mien.facs.prototypes` over the face-frame
  channels (AU intensities 0..5 at emotion intensity 1; pose channels 0), so an emotion drives any ARKit
  rig or engine through the AU -> blendshape mapping.

**The intensity rule.** An expression is ``intensities @ basis``: linear, so a blend is the sum of its components
and twice the intensity moves the face twice as far (Broekens' geometric intensity). The feature-point basis stays
linear at every intensity (metres have no ceiling). The FACS basis has one: FACS ends at E (5). Clamping each AU at
E (mien 0.1) broke a prototype's proportions as soon as its largest AU reached E (at the study's intensity 2.4 every
AU of every prototype sat at 5). :func:`saturate` instead scales the whole AU expression by one common factor once
its largest AU passes :data:`SATURATION_KNEE`, with a smooth (tanh) approach to E: below the knee the expression is
exactly linear; above it every AU keeps its ratio to the others, and the face keeps growing toward E without ever
reaching a corner. With the version-2 prototypes (largest AU 3.5 at intensity 1) the study's 1.2 sits just above
the knee (largest AU 4.2) and 2.4 saturates to E with the same proportions.

``closed_mouth=True`` gives the variant used for the mood ("mood is expressed ... always with a closed
mouth (jaw feature)"): the Jaw feature row, or the mouth-opening AUs 25, 26 and 27, set to 0.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from mien.affect.emotions import EMOTIONS
from mien.affect.table1 import FEATURE_NAMES, table1_rig_vectors
from mien.errors import InvalidValueError

__all__ = [
    "MOUTH_OPENING_AUS",
    "SATURATION_KNEE",
    "expression",
    "facs_basis",
    "feature_point_basis",
    "feature_target_names",
    "saturate",
]

MOUTH_OPENING_AUS: tuple[str, ...] = ("AU25", "AU26", "AU27")
"""Lips part, jaw drop, mouth stretch: removed from the closed-mouth FACS basis."""

_AXES = ("x", "y", "z")

SATURATION_KNEE = 4.0
"""AU intensity (D) above which :func:`saturate` starts scaling a FACS-basis expression down, as one piece."""

_CEILING = 5.0  # FACS E


def saturate(expression: np.ndarray, knee: float = SATURATION_KNEE) -> np.ndarray:
    """Scale (..., n) AU expressions in place, each by one common factor, so no AU passes E (5); returns them.

    An expression whose largest AU ``m`` is at most ``knee`` is unchanged; otherwise every AU is multiplied by
    ``g(m) / m`` with ``g(m) = knee + (5 - knee) tanh((m - knee) / (5 - knee))`` (continuous, with a continuous
    slope at the knee, approaching 5). Ratios between AUs never change.

    >>> e = np.array([2.0, 8.0, 4.0])
    >>> out = saturate(e.copy())
    >>> round(float(out.max()), 3), round(float(out[0] / out[1]), 3)
    (4.999, 0.25)
    >>> saturate(np.array([1.0, 3.0])).tolist()
    [1.0, 3.0]
    """
    if not 0.0 < knee < _CEILING:
        raise InvalidValueError("knee", knee, f"an AU intensity in (0, {_CEILING:g})")
    peak = expression.max(axis=-1, keepdims=True) if expression.size else expression
    if np.all(peak <= knee):
        return expression
    span = _CEILING - knee
    with np.errstate(divide="ignore", invalid="ignore"):
        factor = np.where(peak > knee, (knee + span * np.tanh((peak - knee) / span)) / peak, 1.0)
    expression *= factor
    return expression


def feature_target_names() -> tuple[str, ...]:
    """The 54 morph-target names ``fp_<Feature>_<axis>`` in basis column order (18 features x (x, y, z)).

    >>> feature_target_names()[:4]
    ('fp_Jaw_x', 'fp_Jaw_y', 'fp_Jaw_z', 'fp_Nostrils_x')
    """
    return tuple(f"fp_{feature}_{axis}" for feature in FEATURE_NAMES for axis in _AXES)


@cache
def feature_point_basis(closed_mouth: bool = False) -> np.ndarray:
    """(6, 54) float64 read-only: rig-frame Table 1 (metres at intensity 1), rows in EMOTIONS order.

    Columns follow :func:`feature_target_names`. With ``closed_mouth`` the Jaw feature is 0.

    >>> b = feature_point_basis()
    >>> b[EMOTIONS.index("surprise"), feature_target_names().index("fp_Jaw_y")]   # the jaw drops 1 cm
    np.float64(-0.01)
    >>> float(feature_point_basis(closed_mouth=True)[:, :3].sum())
    0.0
    """
    basis = table1_rig_vectors().reshape(len(EMOTIONS), -1).copy()
    if closed_mouth:
        jaw = FEATURE_NAMES.index("Jaw")
        basis[:, 3 * jaw : 3 * jaw + 3] = 0.0
    basis.setflags(write=False)
    return basis


@cache
def facs_basis(closed_mouth: bool = False) -> np.ndarray:
    """(6, 62) float64 read-only: EMFACS prototype AU intensities per emotion over ``FACE_CHANNELS``.

    With ``closed_mouth`` the channels of AU25, AU26 and AU27 are 0.
    """
    from mien.facs.catalogue import FACE_CHANNELS
    from mien.facs.prototypes import prototype_vector

    basis = np.stack([np.asarray(prototype_vector(emotion), dtype=np.float64) for emotion in EMOTIONS])
    if closed_mouth:
        for channel in MOUTH_OPENING_AUS:
            if channel in FACE_CHANNELS:
                basis[:, FACE_CHANNELS.index(channel)] = 0.0
    basis.setflags(write=False)
    return basis


def expression(intensities: np.ndarray, basis: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """``intensities @ basis``: (6,) -> (n,), or (..., 6) -> (..., n) for a batch; into ``out`` if given.

    >>> from mien.affect.emotions import emotion_vector
    >>> b = feature_point_basis()
    >>> bool(np.allclose(expression(emotion_vector("evil"), b), b[0] + b[2]))
    True
    """
    values = np.asarray(intensities, dtype=np.float64)
    if values.shape[-1:] != (len(EMOTIONS),):
        raise InvalidValueError("intensities", f"array of shape {values.shape}", f"(..., {len(EMOTIONS)})")
    if out is None:
        return np.dot(values, basis)
    return np.dot(values, basis, out=out)  # out: C-contiguous float64 of the result's shape
