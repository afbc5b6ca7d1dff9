"""Choosing a head: the built-in stylised head or ICT-FaceKit, with an identity and optional feature points."""

from __future__ import annotations

from mien.errors import UnknownNameError
from mien.rig.model import Rig

__all__ = ["HEADS", "ict_installed", "load_head"]

HEADS: tuple[str, ...] = ("default", "builtin", "ict")
"""Head names: ``default`` is ICT-FaceKit when installed, else the built-in head."""


def ict_installed() -> bool:
    """True when ICT-FaceKit is configured (``MIEN_ICT_FACEKIT`` or config) and complete."""
    from mien.paths import asset_path
    from mien.rig.ict_facekit import ict_missing_files

    path = asset_path("ict_facekit")
    return path is not None and path.is_dir() and not ict_missing_files(path)


def load_head(name: str = "default", identity: str | None = None, feature_points: bool = False) -> Rig:
    """The head ``name`` (see :data:`HEADS`) with ``identity`` (a preset name; None = the head's default).

    Built-in identities: :data:`mien.rig.builtin_head.BUILTIN_IDENTITIES`; ICT identities:
    :func:`mien.rig.ict_facekit.ict_identity_presets`. With ``feature_points`` the Broekens feature-point
    rig is compiled onto the head (54 extra targets ``fp_<Feature>_<axis>``) with its skin-detail correctives
    (``fpc_<shape>``, :mod:`mien.rig.fp_correctives`).
    """
    if name not in HEADS:
        raise UnknownNameError("head", name, HEADS)
    if name == "default":
        name = "ict" if ict_installed() else "builtin"
    if name == "ict":
        from mien.rig.ict_facekit import ict_identity_presets, load_ict_facekit

        presets = ict_identity_presets()
        if identity is not None and identity not in presets:
            raise UnknownNameError("ICT identity", identity, tuple(presets))
        rig = load_ict_facekit(identity=presets[identity] if identity is not None else None)
    else:
        from mien.rig.builtin_head import BUILTIN_IDENTITIES, builtin_head

        if identity is not None and identity not in BUILTIN_IDENTITIES:
            raise UnknownNameError("built-in identity", identity, tuple(BUILTIN_IDENTITIES))
        rig = builtin_head(identity or "default")
    if feature_points:
        from mien.rig.feature_points import FeaturePointRig
        from mien.rig.fp_correctives import corrective_targets

        fp = FeaturePointRig.build(rig)
        rig = rig.with_targets(fp.compile())
        rig = rig.with_targets(corrective_targets(fp, rig))
    return rig
