"""Mount the browser viewer on a FastAPI app: the page at ``/``, its files, three.js and the control lists.

Routes added by :func:`mount`:

- ``GET /``: ``static/index.html`` (or, when three.js is not installed, a 503 page that says how to get it).
- ``GET /viewer/controls.json``: :func:`mien.viewer.controls.viewer_controls` (AUs, emotions, laughter...).
- ``GET /viewer/{file}``: the page's own files under ``static/`` (``viewer.js``, ``viewer.css``).
- ``GET /vendor/three/{path}``: files of the npm ``three`` package, from the wheel or ``node_modules`` (see
  :mod:`mien.viewer.vendor`), which the page's import map names for ``three`` and ``three/addons/``.

The page itself talks to the server's WebSocket ``/ws`` and HTTP API ``/api`` (mounted by the server).
"""

from __future__ import annotations

import html
import logging
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from mien.viewer.controls import viewer_controls
from mien.viewer.vendor import THREE_ENTRY, THREE_INSTALL_HINT, three_candidates, three_dir

if TYPE_CHECKING:
    from fastapi import FastAPI

__all__ = ["STATIC_DIR", "mount"]

log = logging.getLogger(__name__)

STATIC_DIR = Path(str(resources.files("mien.viewer").joinpath("static")))
"""The page's own files: ``index.html``, ``viewer.js``, ``viewer.css``."""

_MISSING_PAGE = """<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>mien viewer: three.js missing</title>
<style>body{{background:#1e2124;color:#e6e6e6;font:16px system-ui,sans-serif;margin:3em}}
code{{background:#2c3035;padding:2px 5px;border-radius:3px}}</style></head>
<body><h1>The mien viewer cannot start</h1><p>{hint}.</p>
<p>Looked for <code>{where}</code>.</p>
<p>The server's WebSocket (<code>/ws</code>) and HTTP API (<code>/api</code>) still work.</p></body></html>
"""


def mount(app: FastAPI) -> None:
    """Add the viewer's routes to ``app`` (see the module doc). Logs a warning when three.js is missing."""
    from fastapi import HTTPException
    from fastapi.responses import FileResponse, HTMLResponse, JSONResponse
    from fastapi.staticfiles import StaticFiles

    three = three_dir()
    if three is None:
        where = " or ".join(str(folder / THREE_ENTRY) for folder in three_candidates())
        log.warning("mien viewer: %s (looked for %s); / answers 503 until it is installed", THREE_INSTALL_HINT, where)
        missing_page = _MISSING_PAGE.format(hint=html.escape(THREE_INSTALL_HINT), where=html.escape(str(where)))
    controls = viewer_controls()

    @app.get("/", include_in_schema=False)
    def viewer_page() -> FileResponse | HTMLResponse:
        """The viewer page, or a 503 page saying how to get three.js when it is not installed."""
        if three is None:
            return HTMLResponse(missing_page, status_code=503)
        return FileResponse(STATIC_DIR / "index.html", media_type="text/html", headers={"Cache-Control": "no-cache"})

    @app.get("/viewer/controls.json", include_in_schema=False)
    def viewer_controls_json() -> JSONResponse:
        """The control lists of the page, built from the FACS, emotion, laughter and camera catalogues."""
        return JSONResponse(controls)

    app.mount("/viewer", StaticFiles(directory=STATIC_DIR), name="viewer")
    if three is not None:
        app.mount("/vendor/three", StaticFiles(directory=three), name="vendor-three")
    else:

        @app.get("/vendor/three/{path:path}", include_in_schema=False)
        def vendor_missing(path: str) -> None:
            raise HTTPException(status_code=503, detail=THREE_INSTALL_HINT)
