"""AU estimates from the rendered mesh's landmarks, for the AUs the detector cannot see.

The detector's AUs come from its blendshapes (:mod:`mien.validate.au_solve`), and MediaPipe's ``noseSneer``
never moves, on the rigs or on the real human media (the rig report: AU9 is "not seen"). Disgust's nose wrinkle
(AU9) is then invisible to the FACS reading, and a disgust whose other signs overlap anger's (Broekens' Table 1
disgust pulls the inner brows 13 mm together and lifts the lower lids) reads as anger. The issue "Faces that read"
asks for disgust's signs "by the detector where it can see them, else by landmark geometry on the render": this
module is that geometry.

Each AU here is measured by the rise of a few iBUG-68 landmarks on the deformed mesh (the rig's frame, before
head pose, so the view does not matter) above the same rig's neutral. Each is scaled by what the rig's own AU at E
(intensity 5, through the AU -> ARKit mapping) does, so that AU at E reads 5; AU9 is solved jointly with AU10, whose
upper-lip raise lifts the nostril wings too (:meth:`LandmarkAUs.estimate`):

* AU9 (nose wrinkler): the nostril wings, iBUG 31 and 35 (the FACS Manual's AU9 raises the nostril wings and
  the infraorbital triangle);
* AU10 (upper lip raiser): the top of the upper lip, iBUG 50, 51, 52.

:data:`FROM_LANDMARKS` names the AUs whose landmark estimate stands in for the detector's in the FACS reading.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["FROM_LANDMARKS", "LANDMARK_POINTS", "MIN_RISE_AT_E_MM", "SOLVED", "LandmarkAUs", "merged_aus"]

LANDMARK_POINTS: dict[str, tuple[int, ...]] = {"AU9": (31, 35), "AU10": (50, 51, 52)}
"""AU -> the 0-based iBUG-68 landmarks whose mean rise measures it."""

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
        from mien.facs.catalogue import FACE_CHANNELS, au_channels
        from mien.rig.deform import Deformer

        self._landmarks = np.asarray(rig.landmarks)
        self._neutral = self._heights(np.asarray(rig.neutral, np.float64))
        deformer = Deformer(rig)
        columns = []
        for name in LANDMARK_POINTS:
            frame = np.zeros(len(FACE_CHANNELS))
            frame[list(au_channels(int(name.removeprefix("AU"))))] = 5.0
            columns.append(self._rise(deformer.deform(np.asarray(weights_of(frame), np.float32))))
        self.rise_at_e_mm: np.ndarray = np.array(columns).T
        """(measures, AUs) millimetres: how far the rig's own AU at E (column, :data:`LANDMARK_POINTS` order)
        raises each landmark set (row, same order). Off the diagonal is the rig's cross-talk: on ICT-FaceKit the
        upper lip raiser lifts the nostril wings too."""
        self._usable = np.diag(self.rise_at_e_mm) >= MIN_RISE_AT_E_MM

    def _heights(self, vertices: np.ndarray) -> np.ndarray:
        return np.array([np.mean(vertices[self._landmarks[list(ids)], 1]) for ids in LANDMARK_POINTS.values()])

    def _rise(self, vertices: np.ndarray) -> np.ndarray:
        return (self._heights(np.asarray(vertices, np.float64)) - self._neutral) * 1e3

    def estimate(self, vertices: np.ndarray) -> dict[str, float]:
        """``{"AU9": 0..5, "AU10": 0..5}`` of a deformed mesh ((n_vertices, 3), the rig's frame, before head pose).

        AU10 is the upper lip's rise over the rig's own AU10 at E. The nostril wings also rise with the upper lip, so
        AU9 is solved from both rises through the rig's own response (:attr:`rise_at_e_mm`, non-negative least
        squares): an upper-lip raise alone is not read as a nose wrinkle. An AU the rig itself cannot raise its
        landmarks with by :data:`MIN_RISE_AT_E_MM` is left out.
        """
        from scipy.optimize import nnls

        if not self._usable.any():
            return {}
        rise = np.clip(self._rise(vertices), 0.0, None)
        own = rise / np.maximum(np.diag(self.rise_at_e_mm), 1e-9)  # each AU's landmarks over its own E
        solved = np.zeros(len(rise))
        solved[self._usable], _ = nnls(self.rise_at_e_mm[:, self._usable], rise)
        return {
            name: round(float(np.clip(5.0 * (solved[i] if name in SOLVED else own[i]), 0.0, 5.0)), 4)
            for i, name in enumerate(LANDMARK_POINTS)
            if self._usable[i]
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
