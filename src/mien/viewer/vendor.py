"""Where the viewer finds three.js: in the installed package, or in an npm ``node_modules`` folder; never a CDN.

A wheel carries the part of three.js the viewer loads, with its licence, in ``mien/viewer/three`` (copied from
``node_modules/three`` when the wheel is built, by ``scripts/vendor_three.py``; the repository never holds
three.js). Lookup order:

1. ``$MIEN_NODE_MODULES/three`` when ``MIEN_NODE_MODULES`` is set (and only there: an explicit choice);
2. ``three`` beside this module (``pip install 'mien[serve]'``);
3. the ``node_modules`` folder beside ``src/`` in a checkout (``npm ci``; ``Path(mien.__file__).parents[2]``).
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["PACKAGED_THREE", "THREE_ENTRY", "THREE_INSTALL_HINT", "node_modules_dir", "three_candidates", "three_dir"]

THREE_ENTRY = "build/three.module.js"
"""The ES module build of three.js, relative to the ``three`` package folder."""

PACKAGED_THREE = Path(__file__).resolve().with_name("three")
"""Where a wheel puts three.js (the npm package's layout, only the files the viewer loads)."""

THREE_INSTALL_HINT = (
    "three.js is not installed: this mien was installed without the viewer's files (reinstall it from a wheel: "
    "pip install 'mien[serve]'); in a mien checkout run `npm ci` (it installs node_modules/three from "
    "package-lock.json); or set MIEN_NODE_MODULES to a node_modules folder that holds three"
)
"""What to tell a user when no three.js is found."""


def node_modules_dir() -> Path:
    """The ``node_modules`` folder to look in (it may not exist): ``$MIEN_NODE_MODULES`` or the checkout's."""
    configured = os.environ.get("MIEN_NODE_MODULES")
    if configured:
        return Path(configured).expanduser()
    return Path(__file__).resolve().parents[3] / "node_modules"  # src/mien/viewer/vendor.py -> checkout


def three_candidates() -> list[Path]:
    """The ``three`` folders looked in, in order (see the module doc)."""
    if os.environ.get("MIEN_NODE_MODULES"):
        return [node_modules_dir() / "three"]
    return [PACKAGED_THREE, node_modules_dir() / "three"]


def three_dir() -> Path | None:
    """The first ``three`` folder holding ``build/three.module.js`` (see the module doc), or None when missing."""
    for folder in three_candidates():
        if (folder / THREE_ENTRY).is_file():
            return folder
    return None
