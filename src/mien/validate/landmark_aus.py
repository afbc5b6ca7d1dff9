"""AU estimates from the rendered mesh's landmarks, for the AUs the detector cannot see.

The detector's AUs come from its blendshapes (:mod:`mien.rig.au_solve`), and MediaPipe's ``noseSneer``
never moves, on the rigs or on the real human media (the rig report: AU9 is "not seen"). Disgust's nose wrinkle
(AU9) is then invisible to the FACS reading, and a disgust whose other signs overlap anger's (Broekens' Table 1
disgust pulls the inner brows 13 mm together and lifts the lower lids) reads as anger. The issue "Faces that read"
asks for disgust's signs "by the detector where it can see them, else by landmark geometry on the render": this
module is that geometry.

Four measures, each the rise of a few iBUG-68 landmarks on the deformed mesh (the rig's frame, before head pose,
so the view does not matter) above the same rig's neutral, a fall counting as 0 (:data:`LANDMARK_POINTS`):

* the nostril wings, iBUG 31 and 35 (the FACS Manual's AU9 raises the nostril wings and the infraorbital
  triangle; AU10 raises them a little);
* the top of the upper lip, iBUG 50, 51, 52 (AU10's own sign; AU9 raises it too);
* the nose's ridge, iBUG 29 and 30 (AU9 pulls the skin along the sides of the nose up toward its root; AU10 hardly
  moves it: on ICT-FaceKit 3.1 mm against 0.15 mm at E, where the other two measures move almost alike with both);
* the nose's root, iBUG 27 (AU1's: on ICT-FaceKit the inner brow raiser drags the skin of the nose up with it).

Each is scaled by what the rig's own AUs at E (intensity 5, through the AU -> ARKit mapping) do to it, so that an
AU at E reads 5 (:meth:`LandmarkAUs.estimate`): AU10 is the upper lip's rise over its own at E; AU9 is solved jointly
with AU10 and AU1 from all four measures, so neither an upper-lip raise nor a raised brow is a nose wrinkle.

:data:`FROM_LANDMARKS` names the AUs whose landmark estimate stands in for the detector's in the FACS reading.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from mien.extras import require
from mien.facs.catalogue import FACE_CHANNELS, au_channels
from mien.rig.deform import Deformer

__all__ = [
    "FROM_LANDMARKS",
    "LANDMARK_POINTS",
    "MEASURED_BY",
    "MIN_RISE_AT_E_MM",
    "REPORTED",
    "SOLVED",
    "LandmarkAUs",
    "merged_aus",
]

LANDMARK_POINTS: dict[str, tuple[int, ...]] = {
    "nostril_wings": (31, 35),
    "upper_lip": (50, 51, 52),
    "nose_ridge": (29, 30),
    "nose_root": (27,),
}
"""Measure -> the 0-based iBUG-68 landmarks whose mean rise it is."""

MEASURED_BY: dict[str, str] = {"AU9": "nostril_wings", "AU10": "upper_lip", "AU1": "nose_root"}
"""AU -> its own measure in :data:`LANDMARK_POINTS`: the AUs whose response at E is measured, in this order. AU1
is there because on ICT-FaceKit the inner brow raiser drags the nose's ridge up (1.2 mm at E): solved with the
others, a sad or surprised brow is not read as a nose wrinkle."""

REPORTED: tuple[str, ...] = ("AU9", "AU10")
"""The AUs :meth:`LandmarkAUs.estimate` returns (AU1 is the detector's to see)."""

SOLVED: tuple[str, ...] = ("AU9",)
"""AUs estimated jointly with the others (their landmarks also move with another AU); the rest are their own
landmarks' rise over the rig's own AU at E."""

FROM_LANDMARKS: tuple[str, ...] = ("AU9",)
"""AUs the FACS reading takes from the landmarks instead of the detector: those the rig report finds MediaPipe
cannot see (its ``noseSneer`` is flat on the human media and on every rig; docs/VALIDATION.md, rig fidelity)."""

MIN_RISE_AT_E_MM = 0.5
"""A rig whose own AU at E raises its landmarks less than this (millimetres) gives no estimate of that AU."""


class LandmarkAUs:
    """Landmark AU estimates for one rig: :meth:`estimate` maps a deformed mesh to ``{"AU9": 0..5, ...}``.

    ``rig``: the :class:`~mien.rig.model.Rig`; ``weights_of``: a function from a (62,) face frame to the rig's
    morph weights (:meth:`mien.validate.stimuli.StimulusRenderer.weights`), used once per AU to find what the
    rig's own AU at E does.

    >>> from mien.rig.builtin_head import builtin_head
    >>> from mien.rig.mapping import AUMapping
    >>> rig = builtin_head()
    >>> estimator = LandmarkAUs(rig, AUMapping.default().weights_for(rig).to_weights)
    >>> estimator.estimate(rig.neutral)
    {'AU9': 0.0, 'AU10': 0.0}
    """

    def __init__(self, rig: Any, weights_of: Any) -> None:
        self._landmarks = np.asarray(rig.landmarks)
        self._neutral = self._heights(np.asarray(rig.neutral, np.float64))
        deformer = Deformer(rig)
        columns = []
        for name in MEASURED_BY:
            frame = np.zeros(len(FACE_CHANNELS))
            frame[list(au_channels(int(name.removeprefix("AU"))))] = 5.0
            columns.append(self._rise(deformer.deform(np.asarray(weights_of(frame), np.float32))))
        self.rise_at_e_mm: np.ndarray = np.array(columns).T
        """(measures, AUs) millimetres: how far the rig's own AU at E (column, :data:`MEASURED_BY` order) raises
        each landmark set (row, :data:`LANDMARK_POINTS` order; a fall counts as 0, as in :meth:`estimate`). On
        ICT-FaceKit the upper lip raiser lifts the nostril wings too, and the nose wrinkler the upper lip."""
        self._own = np.array([list(LANDMARK_POINTS).index(m) for m in MEASURED_BY.values()])
        own_at_e = self.rise_at_e_mm[self._own, np.arange(len(MEASURED_BY))]
        self._usable = own_at_e >= MIN_RISE_AT_E_MM
        self._own_at_e = np.maximum(own_at_e, 1e-9)
        self._row_scale = 1.0 / np.maximum(self.rise_at_e_mm.max(axis=1), MIN_RISE_AT_E_MM)

    def _heights(self, vertices: np.ndarray) -> np.ndarray:
        return np.array([np.mean(vertices[self._landmarks[list(ids)], 1]) for ids in LANDMARK_POINTS.values()])

    def _rise(self, vertices: np.ndarray) -> np.ndarray:
        """Millimetres each landmark set rose above the neutral (0 where it fell: a lowered lip or brow is not
        evidence against a raiser, and the jaw's drop lowers the lip of a snarl that still wrinkles the nose)."""
        return np.clip((self._heights(np.asarray(vertices, np.float64)) - self._neutral) * 1e3, 0.0, None)

    def estimate(self, vertices: np.ndarray) -> dict[str, float]:
        """``{"AU9": 0..5, "AU10": 0..5}`` of a deformed mesh ((n_vertices, 3), the rig's frame, before head pose).

        AU10 is the upper lip's rise over the rig's own AU10 at E. The nostril wings and the upper lip rise with
        AU9 and AU10 alike, and AU1 lifts the nose's ridge, so AU9 is solved with AU10 and AU1 from all four
        measures through the rig's own response (:attr:`rise_at_e_mm`, non-negative least squares, each measure
        scaled by its largest response at E so each counts alike): an upper-lip raise or a raised brow alone is not
        read as a nose wrinkle. An AU the rig itself cannot raise its own measure with by :data:`MIN_RISE_AT_E_MM`
        is left out of the solve and of the result.
        """
        nnls = require("scipy.optimize", "validate").nnls
        if not any(self._usable[i] for i, name in enumerate(MEASURED_BY) if name in REPORTED):
            return {}
        rise = self._rise(vertices)
        own = rise[self._own] / self._own_at_e  # each AU's own measure over its own E
        solved = np.zeros(len(MEASURED_BY))
        response = self.rise_at_e_mm[:, self._usable] * self._row_scale[:, None]
        solved[self._usable], _ = nnls(response, rise * self._row_scale)
        return {
            name: round(float(np.clip(5.0 * (solved[i] if name in SOLVED else own[i]), 0.0, 5.0)), 4)
            for i, name in enumerate(MEASURED_BY)
            if self._usable[i] and name in REPORTED
        }


def merged_aus(detected: Mapping[str, float], from_landmarks: Mapping[str, float]) -> dict[str, float]:
    """The detector's AUs with those of :data:`FROM_LANDMARKS` replaced by their landmark estimates (where given).

    >>> merged_aus({"AU4": 1.0, "AU9": 0.0}, {"AU9": 3.2, "AU10": 2.0})
    {'AU4': 1.0, 'AU9': 3.2}
    """
    out = dict(detected)
    for name in FROM_LANDMARKS:
        if name in from_landmarks and name in out:
            out[name] = float(from_landmarks[name])
    return out
