"""Between clips and a rig's morph-target weights: the one conversion every geometry format uses.

A clip reaches a rig in one of three vocabularies: face channels (AU intensities 0..5 and pose degrees,
:data:`~mien.facs.catalogue.FACE_CHANNELS`), sent through the AU -> ARKit mapping by
:func:`mien.rig.animate.face_to_rig`; the rig's own target names (weights 0..1, e.g. the 52 ARKit names), plus
optional pose channels, used as they are; or laughter-controller curves (``mien laugh -o x.anim``), which become
ARKit weights through :func:`mien.laughter.controllers.controllers_to_arkit`. The way back, ARKit weights -> AU
intensities, is the NNLS solve of :class:`mien.rig.au_solve.AUSolver`.
"""

from __future__ import annotations

import warnings

import numpy as np

from mien.errors import InvalidValueError
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.catalogue import FACE_CHANNELS, POSE_CHANNELS
from mien.facs.clip import Clip
from mien.laughter.controllers import controllers_to_arkit
from mien.laughter.names import CONTROLLER_NAMES
from mien.rig.animate import face_to_rig
from mien.rig.au_solve import AUSolver
from mien.rig.model import Rig

__all__ = ["clip_to_rig", "controller_weights", "is_controller_clip", "is_weight_clip", "weights_to_au"]


def is_weight_clip(clip: Clip, target_names: tuple[str, ...]) -> bool:
    """True when ``clip`` names some of ``target_names`` and no AU channel (pose channels may be there too)."""
    names = set(target_names)
    aus = set(FACE_CHANNELS) - set(POSE_CHANNELS)
    return any(c in names for c in clip.channels) and not any(c in aus for c in clip.channels)


def is_controller_clip(clip: Clip) -> bool:
    """True when ``clip`` holds laughter-controller curves (:data:`CONTROLLER_NAMES`, plus pose channels)."""
    known = set(CONTROLLER_NAMES) | set(POSE_CHANNELS)
    return any(c in CONTROLLER_NAMES for c in clip.channels) and all(c in known for c in clip.channels)


def controller_weights(clip: Clip) -> Clip:
    """An ARKit weight clip (0..1, pose channels kept) of a laughter-controller clip (missing controllers are 0)."""
    full = np.zeros((clip.n_frames, len(CONTROLLER_NAMES)))
    poses = [j for j, name in enumerate(clip.channels) if name in POSE_CHANNELS]
    for j, name in enumerate(clip.channels):
        if name in CONTROLLER_NAMES:
            full[:, CONTROLLER_NAMES.index(name)] = clip.values[:, j]
    arkit = controllers_to_arkit(Clip(full, clip.fps, CONTROLLER_NAMES))
    values = np.hstack([arkit.values, clip.values[:, poses]])
    return Clip(values, clip.fps, (*arkit.channels, *(clip.channels[j] for j in poses)))


def clip_to_rig(clip: Clip, rig: Rig) -> tuple[np.ndarray, np.ndarray]:
    """``(weights (n, n_targets) float32, poses (n, 5) float64 degrees)`` of ``clip`` on ``rig``.

    Weight clips (channels named after ``rig``'s targets) are used as they are; channels naming targets this
    head lacks (another head's extras) are skipped with a warning. Face-channel clips go through the AU mapping,
    laughter-controller clips through :func:`controller_weights`; anything else raises naming the first channel
    that is none of these.
    """
    if is_weight_clip(clip, rig.target_names):
        skipped = [c for c in clip.channels if c not in rig.target_names and c not in POSE_CHANNELS]
        if skipped:
            warnings.warn(f"targets not on head {rig.name!r} skipped: {', '.join(skipped)}", stacklevel=2)
        weights = np.zeros((clip.n_frames, len(rig.targets)), np.float32)
        poses = np.zeros((clip.n_frames, len(POSE_CHANNELS)))
        for j, name in enumerate(clip.channels):
            if name in POSE_CHANNELS:
                poses[:, POSE_CHANNELS.index(name)] = clip.values[:, j]
            elif name not in skipped:
                weights[:, rig.target_index(name)] = clip.values[:, j]
        return weights, poses
    if is_controller_clip(clip):
        return clip_to_rig(controller_weights(clip), rig)
    unknown = [c for c in clip.channels if c not in FACE_CHANNELS]
    if unknown:
        raise InvalidValueError(
            "clip channel",
            unknown[0],
            f"face channels (AU1L, AU12R, head_yaw_deg...) or target names of head {rig.name!r} (eyeBlinkLeft...)",
        )

    weights, poses = face_to_rig(rig, clip)
    return np.asarray(weights, np.float32), np.asarray(poses, np.float64)


def weights_to_au(clip: Clip) -> Clip:
    """A face-channel clip (AU intensities 0..5, pose degrees) from an ARKit weight clip, by NNLS.

    ``clip`` channels: ARKit names (weights 0..1; missing ones count as 0) and optional pose channels, which
    are kept; laughter-controller curves are turned into ARKit weights first (:func:`controller_weights`).
    Other channels (a head's targets beyond ARKit's 52, such as ICT's ``browInnerUpLeft``) are skipped with a
    warning. AUs the solver does not estimate stay 0.
    """
    if is_controller_clip(clip):
        clip = controller_weights(clip)
    if not any(c in ARKIT_NAMES for c in clip.channels):
        raise InvalidValueError("clip channels", ", ".join(clip.channels[:3]), "ARKit blendshape names")
    skipped = [c for c in clip.channels if c not in ARKIT_NAMES and c not in POSE_CHANNELS]
    if skipped:
        warnings.warn(f"channels that are not ARKit blendshapes skipped: {', '.join(skipped)}", stacklevel=2)
    scores = np.zeros((clip.n_frames, len(ARKIT_NAMES)))
    for j, name in enumerate(clip.channels):
        if name in ARKIT_NAMES:
            scores[:, ARKIT_NAMES.index(name)] = clip.values[:, j]
    solver = AUSolver()
    values = np.zeros((clip.n_frames, len(FACE_CHANNELS)))
    if clip.n_frames:
        values[:, solver.channels] = solver.solve_channels(scores)
    for j, name in enumerate(clip.channels):
        if name in POSE_CHANNELS:
            values[:, FACE_CHANNELS.index(name)] = clip.values[:, j]
    return Clip(values, clip.fps, FACE_CHANNELS)
