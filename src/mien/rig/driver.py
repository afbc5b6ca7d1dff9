"""A compiled rig driver: face frames -> morph-target weights and head/gaze pose, every tick.

:class:`RigDriver` parses the AU -> blendshape table once (:class:`~mien.rig.mapping.AUMapping`, reordered to
the rig's targets) into one float32 matrix. A tick is a product in row chunks that BLAS keeps on the calling
thread (:func:`mien.small_matmul.matmul_rows`: a busy machine's threads cannot slow it down) and a clip, into
buffers kept between calls (nothing allocated once the batch size is stable). :func:`mien.rig.animate.face_to_rig`
uses it, so offline rendering and live streaming share one implementation. A head with its own viseme shapes
(:func:`mien.speech.visemes.rig_viseme_targets`, e.g. the VALID avatars' ``h_expressions.*``) shows speech through
them when a tick passes the speech layer's viseme weights (``visemes``): the AU route keeps the rest of the face.

>>> import numpy as np
>>> from mien.facs.catalogue import FACE_CHANNELS, au_channels
>>> driver = RigDriver()                       # no rig: the 52 ARKit targets
>>> frames = np.zeros((2, len(FACE_CHANNELS)))
>>> frames[1, list(au_channels(12))] = 5.0
>>> weights = driver.weights(frames)
>>> weights.shape, float(weights[1, driver.target_names.index("mouthSmileLeft")])
((2, 52), 1.0)
"""

from __future__ import annotations

import os

import numpy as np

from mien.affect.basis import feature_target_names
from mien.errors import InvalidValueError
from mien.facs.catalogue import FACE_CHANNELS, POSE_CHANNELS
from mien.rig.feature_points import feature_rooms, limit_moves
from mien.rig.fp_correctives import Corrective, corrective_matrix, correctives, drive_correctives
from mien.rig.mapping import AUMapping
from mien.rig.model import Rig
from mien.small_matmul import matmul_rows
from mien.speech.arbitration import SPEECH_CHANNELS
from mien.speech.visemes import VISEMES, rig_viseme_targets, viseme_aus

__all__ = ["POSE_COLUMNS", "RigDriver"]

POSE_COLUMNS: tuple[str, ...] = POSE_CHANNELS
"""Columns of :meth:`RigDriver.pose`: head yaw, pitch, roll and gaze yaw, pitch, in degrees."""

_N = len(FACE_CHANNELS)
_POSE = np.array([FACE_CHANNELS.index(name) for name in POSE_CHANNELS], np.intp)
_N_VISEMES = len(VISEMES)


class RigDriver:
    """Face frames -> (weights, pose) for one rig, with the mapping parsed once.

    ``rig``: the :class:`~mien.rig.model.Rig` whose ``target_names`` order the weight columns (targets the
    mapping drives but the rig lacks are dropped with a warning, once); ``None`` gives the mapping's own targets
    (the 52 ARKit names for the shipped table). ``mapping_path``: a user's AU -> target table (see
    :meth:`AUMapping.from_file`); default the shipped table.
    """

    def __init__(self, rig: Rig | None = None, mapping_path: str | os.PathLike[str] | None = None) -> None:
        mapping = AUMapping.from_file(mapping_path) if mapping_path else AUMapping.default()
        if rig is not None:
            mapping = mapping.weights_for(rig)
        self.mapping = mapping
        """The parsed mapping, columns in :attr:`target_names` order."""
        self.rig_name = rig.name if rig is not None else ""
        """Name of the rig (empty without one)."""
        self.target_names = mapping.target_names
        """Weight columns, one per target."""
        self._matrix = np.ascontiguousarray(mapping.matrix, dtype=np.float32)

        names = self.target_names
        columns = [names.index(name) if name in names else -1 for name in feature_target_names()]
        self._feature_columns = np.array(columns, np.intp) if min(columns) >= 0 else None
        self._feature_rooms: np.ndarray | None = None
        self._correctives: tuple[Corrective, ...] = ()
        if self._feature_columns is not None and rig is not None:
            self._feature_rooms = feature_rooms(rig)
            self._correctives = tuple(c for c in correctives(rig) if c.target in names)
        self._corrective_columns = np.array([names.index(c.target) for c in self._correctives], np.intp)
        self._corrective_matrix = corrective_matrix(self._correctives)
        self._frames32 = np.zeros((0, _N), np.float32)

        self.viseme_targets: dict[str, str] = rig_viseme_targets(names)
        """``{viseme: target}``: the rig's own viseme shapes (empty: speech goes through the AU mapping alone)."""
        own = [VISEMES.index(viseme) for viseme in self.viseme_targets]
        self._own_visemes = np.array(own, np.intp)
        # the speech channels' share of those visemes, which their own targets show instead of the AU route
        shapes = np.zeros((len(own), _N), np.float32)
        shapes[:, SPEECH_CHANNELS] = viseme_aus()[np.ix_(self._own_visemes, SPEECH_CHANNELS)]
        self._own_shapes = shapes
        self._own_targets = np.zeros((len(own), self.n_targets), np.float32)  # viseme -> target (two may share)
        self._own_targets[np.arange(len(own)), [names.index(t) for t in self.viseme_targets.values()]] = 1.0

    @property
    def n_targets(self) -> int:
        """Number of weight columns."""
        return len(self.target_names)

    @property
    def has_feature_targets(self) -> bool:
        """Whether the rig has the 54 feature-point targets ``fp_*`` (driven by ``feature_weights``)."""
        return self._feature_columns is not None

    def _check_frames(self, frames: np.ndarray) -> np.ndarray:
        values = np.asarray(frames, dtype=np.float64)
        if values.ndim != 2 or values.shape[1] != _N:
            raise InvalidValueError("frames", f"array of shape {values.shape}", f"(n_frames, {_N}) face frames")
        return values

    def weights(
        self,
        frames: np.ndarray,
        feature_weights: np.ndarray | None = None,
        out: np.ndarray | None = None,
        visemes: np.ndarray | None = None,
    ) -> np.ndarray:
        """(n, n_targets) float32 weights in [0, 1] for (n, 62) face frames (pose channels ignored).

        Each target is ``sum(intensity * weight_at_E / 5)`` over its AU channels, clipped to [0, 1] (see
        :mod:`mien.rig.mapping`). ``feature_weights`` (n, 54) metres, from ``"feature_points"`` characters, are
        written to the rig's ``fp_*`` targets (unclipped: they are signed distances), moves toward a barrier
        softly limited to the room this rig has (:func:`mien.rig.feature_points.limit_moves`), and drive the rig's
        skin-detail correctives ``fpc_*`` (:func:`mien.rig.fp_correctives.drive_correctives`). ``out``: a C-contiguous
        (n, n_targets) float32 array to fill (nothing is allocated then, once the batch size is stable).
        ``visemes`` (n, 15): the speech layer's viseme weights of these frames
        (:attr:`mien.speech.batch.SpeechBatch.viseme_weights`, :attr:`mien.character.Character.last_viseme_weights`);
        on a rig with its own viseme targets (:attr:`viseme_targets`) each viseme it has drives its target by its
        weight and its AU shape is taken out of the speech channels (the speech-owned lips and jaw, and the spread
        speech adds to AU20: :mod:`mien.speech.arbitration`), so the AU route keeps the emotion's share there, the
        visemes the rig lacks and every other channel. Ignored on a rig without viseme targets.
        """
        values = self._check_frames(frames)
        n = values.shape[0]
        if out is None:
            out = np.empty((n, self.n_targets), np.float32)
        elif out.shape != (n, self.n_targets) or out.dtype != np.float32:
            raise InvalidValueError(
                "out", f"{out.dtype} array of shape {out.shape}", f"float32 ({n}, {self.n_targets})"
            )
        if self._frames32.shape[0] != n:
            self._frames32 = np.empty((n, _N), np.float32)
        np.copyto(self._frames32, values, casting="same_kind")
        own = None
        if visemes is not None and self._own_visemes.size:
            spoken = np.asarray(visemes, dtype=np.float32)
            if spoken.shape != (n, _N_VISEMES):
                raise InvalidValueError(
                    "visemes", f"array of shape {spoken.shape}", f"({n}, {_N_VISEMES}) viseme weights"
                )
            own = spoken[:, self._own_visemes]
            self._frames32 -= own @ self._own_shapes  # the AU route's share of the visemes the rig shows itself
            np.maximum(self._frames32, 0.0, out=self._frames32)
        matmul_rows(self._frames32, self._matrix, out)  # pose rows of the matrix are zero
        if own is not None:
            out += own @ self._own_targets
        np.clip(out, 0.0, 1.0, out=out)
        if feature_weights is not None:
            if self._feature_columns is None:
                raise InvalidValueError(
                    "rig", self.rig_name or "(none)", "a rig with the feature-point targets (feature_points=True)"
                )
            features = np.asarray(feature_weights)
            if features.shape != (n, self._feature_columns.size):
                raise InvalidValueError(
                    "feature_weights", f"array of shape {features.shape}", f"({n}, {self._feature_columns.size}) metres"
                )
            if self._feature_rooms is not None:
                features = limit_moves(features, self._feature_rooms)
            out[:, self._feature_columns] = features
            drive_correctives(features, self._corrective_matrix, self._corrective_columns, out)
        return out

    @property
    def feature_rooms(self) -> np.ndarray | None:
        """(2, 54) metres: the limits of the feature moves toward a barrier on this rig (negative, positive
        weights; inf = exact), see :func:`mien.rig.feature_points.feature_rooms`; None without feature targets."""
        return self._feature_rooms

    def pose(self, frames: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """(n, 5) float64 head yaw/pitch/roll and gaze yaw/pitch in degrees (:data:`POSE_COLUMNS`), into ``out``."""
        values = self._check_frames(frames)
        if out is None:
            out = np.empty((values.shape[0], _POSE.size))
        elif out.shape != (values.shape[0], _POSE.size) or out.dtype != np.float64:
            raise InvalidValueError("out", f"{out.dtype} array of shape {out.shape}", f"float64 ({values.shape[0]}, 5)")
        return np.take(values, _POSE, axis=1, out=out)
