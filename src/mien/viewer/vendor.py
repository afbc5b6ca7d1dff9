"""Where the viewer finds three.js: the npm ``node_modules`` folder (installed by ``npm ci``), never a CDN.

Lookup order: ``$MIEN_NODE_MODULES`` if set, else the ``node_modules`` folder beside ``src/`` in a checkout
(``Path(mien.__file__).parents[2] / "node_modules"``).
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["THREE_ENTRY", "THREE_INSTALL_HINT", "node_modules_dir", "three_dir"]

THREE_ENTRY = "build/three.module.js"
"""The ES module build of three.js, relative to the ``three`` package folder."""

THREE_INSTALL_HINT = (
    "three.js is not installed: run `npm ci` in the mien checkout (it installs node_modules/three from "
    "package-lock.json), or set MIEN_NODE_MODULES to a node_modules folder that holds three"
)
"""What to tell a user whose node_modules lacks three.js."""


def node_modules_dir() -> Path:
    """The ``node_modules`` folder to look in (it may not exist): ``$MIEN_NODE_MODULES`` or the checkout's."""
    configured = os.environ.get("MIEN_NODE_MODULES")
    if configured:
        return Path(configured).expanduser()
    return Path(__file__).resolve().parents[3] / "node_modules"  # src/mien/viewer/vendor.py -> checkout


def three_dir() -> Path | None:
    """The installed ``three`` package folder (holding ``build/three.module.js``), or None when missing."""
    folder = node_modules_dir() / "three"
    return folder if (folder / THREE_ENTRY).is_file() else None
