"""Heads from users' files: glTF / GLB / VRM and OBJ folders, read into mien's frame and ARKit names.

>>> from mien.rig.files import is_head_file
>>> is_head_file("no/such/file.glb")
False
"""

from __future__ import annotations

from mien.rig.files.errors import HeadFileError, HeadFileWarning, NoMorphTargetsError
from mien.rig.files.head import FILE_SUFFIXES, FileRig, HeadFileInfo, PrimitiveMaterial, is_head_file, load_head_file

__all__ = [
    "FILE_SUFFIXES",
    "FileRig",
    "HeadFileError",
    "HeadFileInfo",
    "HeadFileWarning",
    "NoMorphTargetsError",
    "PrimitiveMaterial",
    "is_head_file",
    "load_head_file",
]
