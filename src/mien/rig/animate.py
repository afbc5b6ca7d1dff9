"""From face frames to a rig: AU channels -> morph-target weights, pose channels -> head and gaze angles."""

from __future__ import annotations

import numpy as np

from mien.errors import InvalidValueError, UnknownNameError
from mien.facs.catalogue import FACE_CHANNELS
from mien.facs.clip import Clip
from mien.rig.driver import RigDriver
from mien.rig.model import Rig

__all__ = ["face_to_rig"]


def face_to_rig(
    rig: Rig,
    frames: Clip | np.ndarray,
    feature_weights: np.ndarray | None = None,
    mapping_path: str | None = None,
    visemes: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """``(weights (n, n_targets) float32, poses (n, 5) float64)`` for ``rig`` from (n, 62) face frames.

    ``frames`` is an array over FACE_CHANNELS or a :class:`Clip` whose channels are any subset of them.

    Weights come from the AU -> ARKit mapping (the shipped table, or the user table at ``mapping_path``);
    ``feature_weights`` (n, 54) metres, from a character with the ``"feature_points"`` basis, drive the
    rig's ``fp_*`` targets when it has them; ``visemes`` (n, 15), the speech layer's viseme weights of the same
    frames (:attr:`mien.character.Character.last_viseme_weights`), drive the rig's own viseme targets when it has
    them (see :meth:`RigDriver.weights`). Poses are head yaw/pitch/roll and gaze yaw/pitch in degrees.
    One implementation with live streaming: this is :class:`mien.rig.driver.RigDriver` compiled for the call
    (keep a driver to map frames tick by tick).
    """

    if isinstance(frames, Clip):
        unknown = [name for name in frames.channels if name not in FACE_CHANNELS]
        if unknown:
            raise UnknownNameError("face channel", unknown[0], FACE_CHANNELS)
        values = np.zeros((frames.n_frames, len(FACE_CHANNELS)))  # channels not in the clip stay neutral
        values[:, [FACE_CHANNELS.index(name) for name in frames.channels]] = frames.values
    else:
        values = np.asarray(frames, dtype=np.float64)
    if values.ndim != 2 or values.shape[1] != len(FACE_CHANNELS):
        raise InvalidValueError("frames", values.shape, f"(n_frames, {len(FACE_CHANNELS)})")
    driver = RigDriver(rig, mapping_path)
    return driver.weights(values, feature_weights, visemes=visemes), driver.pose(values)
