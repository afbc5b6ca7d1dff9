"""A static-file HTTP server on 127.0.0.1 (ephemeral port) for tests that load pages or files over HTTP."""

from __future__ import annotations

import functools
import http.server
import json
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    extensions_map = {  # noqa: RUF012 (the base class declares it as an instance attribute)
        **http.server.SimpleHTTPRequestHandler.extensions_map,
        ".js": "text/javascript",
    }

    def log_message(self, format: str, *args: object) -> None:
        pass


@contextmanager
def serve_folder(
    folder: Path, handler_class: type[http.server.SimpleHTTPRequestHandler] | None = None
) -> Iterator[str]:
    """Serve ``folder`` on 127.0.0.1 while the block runs; yields the base URL (no trailing slash).
    ``handler_class``: a request handler of one's own (faults, ranges) instead of the plain quiet one."""
    handler = functools.partial(handler_class or _QuietHandler, directory=str(folder))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()
        thread.join(timeout=5)


def three_page(body: str, size: int = 256, antialias: bool = False, imports: dict[str, str] | None = None) -> str:
    """An HTML page that runs ``body`` (a JavaScript module) after setting up three.js as every browser test does:
    the import map (``/three/`` served from node_modules, plus ``imports``), a ``size`` x ``size`` WebGL
    ``renderer`` on a dark background, a ``scene`` lit by a hemisphere light and a key light, ``GLTFLoader``
    imported. ``body`` makes the camera, renders and sets ``window.result`` or ``window.done``."""
    mapping = {"three": "/three/build/three.module.js", "three/addons/": "/three/examples/jsm/", **(imports or {})}
    return f"""<!doctype html>
<html><body style="margin:0;background:#202020">
<script type="importmap">{{"imports": {json.dumps(mapping)}}}</script>
<script type="module">
import * as THREE from "three";
import {{ GLTFLoader }} from "three/addons/loaders/GLTFLoader.js";
const SIZE = {size};
const renderer = new THREE.WebGLRenderer({{ antialias: {str(antialias).lower()}, preserveDrawingBuffer: true }});
renderer.setSize(SIZE, SIZE);
renderer.setClearColor(0x202020);
document.body.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.add(new THREE.HemisphereLight(0xffffff, 0x404040, 2.0));
const light = new THREE.DirectionalLight(0xffffff, 2.0);
light.position.set(0.3, 0.5, 1.0);
scene.add(light);
{body}
</script></body></html>
"""
