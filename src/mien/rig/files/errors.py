"""Errors and warnings of head files: each names the file and what is missing or wrong."""

from __future__ import annotations

import os

from mien.errors import MienError

__all__ = ["HeadFileError", "HeadFileWarning", "NoMorphTargetsError"]


class HeadFileError(MienError, ValueError):
    """A head file (or OBJ folder) cannot be read as a head: truncated, corrupt, unsupported or incomplete."""

    def __init__(self, path: str | os.PathLike[str], problem: str) -> None:
        self.path = str(path)
        self.problem = problem
        super().__init__(f"head file {self.path}: {problem}")


class NoMorphTargetsError(HeadFileError):
    """The file holds meshes but not one morph target to animate."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        super().__init__(
            path,
            "no morph targets (blend shapes) in any mesh, so no ARKit target can be driven; the Broekens "
            "feature-point basis alone can still animate this mesh once it is instrumented (load_head(..., "
            "feature_points=True))",
        )


class HeadFileWarning(UserWarning):
    """Something in a head file was skipped (a texture that does not decode...); the head still loads."""
