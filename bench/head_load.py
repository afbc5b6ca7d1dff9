"""Time to load a VALID avatar as a mien head (decode included) against three.js's GLTFLoader in Chromium.

    python bench/head_load.py [PATH.glb ...] [--repeats N] [--no-browser]

Issue 28's target: loading a VALID avatar (decode included) costs at most 2x what three.js's loader takes for
the same file in Chromium. Per avatar (default: every ``.glb`` in ``$MIEN_SHARED/avatars/valid``), interleaved
repeats of three timings, each printed as median (min..max):

- ``mien load_head_file``: :func:`mien.rig.files.load_head_file` from the path in a warm process (the first
  call of the process, which imports Pillow, meshopt and the name tables, is timed once and printed apart, then
  excluded). It reads the file, the GLB container and JSON, decodes meshopt and quantization, skins, welds,
  finds the eyes, matches names, builds sparse targets and checks that each base-colour image is a readable
  image (Pillow's ``verify``: its header and structure, not its pixels; textures are decoded when rendering).
- ``three.js parseAsync``: ``GLTFLoader.parseAsync(arrayBuffer)`` with ``MeshoptDecoder`` in headless Chromium
  (``/usr/bin/chromium``, never a downloaded browser), timed in the page with ``performance.now()``. The file's
  bytes are fetched once before timing (from a loopback ``http.server`` the bench starts), so both sides time
  parse + decode from memory-or-page-cache, not the network; the meshopt WASM is compiled before timing and the
  first parse is a warm-up. parseAsync resolves after every texture's image is decoded into an
  ``ImageBitmap`` (GLTFLoader's ImageBitmapLoader; WebP through ``EXT_texture_webp``): the page checks every
  texture has its bitmap, so three.js's time includes full texture decoding and mien's does not.
- ``pygltflib parse``: ``GLTF2.load_from_bytes`` alone (its JSON document model, no buffer decoded), the
  library the issue suggested, for scale.

Ratios of medians: mien / three.js against the 2x target, and mien / pygltflib.
"""

from __future__ import annotations

import argparse
import functools
import http.server
import os
import statistics
import threading
import time
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking"]
TARGET_RATIO = 2.0
"""Issue 28: mien's load at most this many times three.js's."""

PAGE = """<!doctype html><meta charset="utf-8"><title>three.js GLTFLoader timing</title>
<script type="importmap">
{"imports": {"three": "/three/build/three.module.js", "three/addons/": "/three/examples/jsm/"}}
</script>
<script type="module">
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";
import { MeshoptDecoder } from "three/addons/libs/meshopt_decoder.module.js";
await MeshoptDecoder.ready;  // WASM compiled before any timing
const loader = new GLTFLoader();
loader.setMeshoptDecoder(MeshoptDecoder);
const files = {};
window.fetchFile = async (name) => {
  files[name] = await (await fetch("/files/" + name)).arrayBuffer();
  return files[name].byteLength;
};
window.parseOnce = async (name) => {
  const start = performance.now();
  const gltf = await loader.parseAsync(files[name], "/files/");
  const ms = performance.now() - start;
  const textures = new Set(), morphs = new Set();
  let vertices = 0;
  gltf.scene.traverse((o) => {
    if (o.isMesh) {
      vertices += o.geometry.attributes.position.count;
      for (const k of Object.keys(o.morphTargetDictionary || {})) morphs.add(k);
      for (const m of [].concat(o.material)) for (const v of Object.values(m)) if (v && v.isTexture) textures.add(v);
    }
  });
  const decoded = [...textures].filter((t) => t.image && t.image.width > 0 && (t.image instanceof ImageBitmap)).length;
  gltf.scene.traverse((o) => { if (o.isMesh) o.geometry.dispose(); });
  for (const t of textures) { t.dispose(); if (t.image && t.image.close) t.image.close(); }
  return { ms, vertices, morphs: morphs.size, textures: textures.size, decoded };
};
window.benchReady = true;
</script>
"""


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    extensions_map = {  # noqa: RUF012 (the base class declares it as an instance attribute)
        **http.server.SimpleHTTPRequestHandler.extensions_map,
        ".js": "text/javascript",
        ".glb": "model/gltf-binary",
    }

    def log_message(self, format: str, *args: object) -> None:
        pass


@contextmanager
def _served(folder: Path) -> Iterator[str]:
    handler = functools.partial(_QuietHandler, directory=str(folder))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()
        thread.join(timeout=5)


@contextmanager
def _browser_page(paths: list[Path], folder: Path) -> Iterator[object]:
    """A Chromium page with three.js loaded and each file's bytes fetched (None when no browser is usable)."""
    three = REPO / "node_modules" / "three"
    if not (three / "build" / "three.module.js").is_file() or not Path(CHROMIUM).exists():
        print(f"three.js baseline skipped: needs {three} (npm ci) and {CHROMIUM}")
        yield None
        return
    from playwright.sync_api import sync_playwright

    (folder / "index.html").write_text(PAGE)
    (folder / "three").symlink_to(three)
    (folder / "files").mkdir()
    for path in paths:
        (folder / "files" / path.name).symlink_to(path.resolve())
    with _served(folder) as url, sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS, headless=True)
        try:
            page = browser.new_page()
            errors: list[str] = []
            page.on("pageerror", lambda exc: errors.append(str(exc)))
            page.goto(url + "/index.html")
            page.wait_for_function("window.benchReady === true", timeout=30_000)
            if errors:
                raise SystemExit(f"the timing page failed: {errors}")
            for path in paths:
                page.evaluate("(name) => window.fetchFile(name)", path.name)
            yield page
        finally:
            browser.close()


def _spread(values: list[float]) -> str:
    low, high = min(values) * 1e3, max(values) * 1e3
    return f"median {statistics.median(values) * 1e3:7.1f} ms  (min {low:.1f}, max {high:.1f})"


def main() -> None:
    shared = Path(os.environ.get("MIEN_SHARED", REPO.parent / "shared"))
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("paths", nargs="*", help="avatar files (default: every VALID avatar)")
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--no-browser", action="store_true", help="skip the three.js baseline")
    args = parser.parse_args()
    paths = [Path(p) for p in args.paths] or sorted((shared / "avatars" / "valid").glob("*.glb"))
    if not paths or not all(p.is_file() for p in paths):
        raise SystemExit(f"no avatar at {paths or shared / 'avatars' / 'valid'}: pass .glb paths or set MIEN_SHARED")
    import tempfile

    import pygltflib

    from mien.rig.files import load_head_file

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        start = time.perf_counter()
        load_head_file(paths[0])
        first = time.perf_counter() - start
    print(f"mien first load_head_file of the process ({paths[0].name}, imports included, excluded below): "
          f"{first * 1e3:.1f} ms")  # fmt: skip
    with tempfile.TemporaryDirectory() as folder, _browser_page(paths, Path(folder)) as page:
        for path in paths:
            data = path.read_bytes()
            ours: list[float] = []
            three: list[float] = []
            parse: list[float] = []
            info: dict[str, object] = {}
            if page is not None:
                info = page.evaluate("(name) => window.parseOnce(name)", path.name)  # type: ignore[attr-defined]
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                load_head_file(path)  # this file's first load (page cache), as three.js's warm-up parse
                for _ in range(args.repeats):
                    start = time.perf_counter()
                    rig = load_head_file(path)
                    ours.append(time.perf_counter() - start)
                    if page is not None:
                        info = page.evaluate("(name) => window.parseOnce(name)", path.name)  # type: ignore[attr-defined]
                        three.append(float(info["ms"]) / 1e3)  # type: ignore[arg-type]
                    start = time.perf_counter()
                    pygltflib.GLTF2.load_from_bytes(data)
                    parse.append(time.perf_counter() - start)
            print(f"\n{path.name}: {len(data) / 1e6:.2f} MB; mien: {rig.n_vertices} welded vertices, "
                  f"{len(rig.targets)} targets")  # fmt: skip
            if info:
                print(f"  three.js: {info['vertices']} vertices, {info['morphs']} morph names, "
                      f"{info['decoded']} of {info['textures']} textures decoded to ImageBitmap")  # fmt: skip
            print(f"  mien load_head_file (warm)     {_spread(ours)}")
            if three:
                print(f"  three.js parseAsync (Chromium) {_spread(three)}")
            print(f"  pygltflib parse only           {_spread(parse)}")
            m_ours = statistics.median(ours)
            if three:
                ratio = m_ours / statistics.median(three)
                verdict = "within" if ratio <= TARGET_RATIO else "OVER"
                print(f"  ratio mien / three.js = {ratio:.2f}  (target <= {TARGET_RATIO:.1f}: {verdict})")
            print(f"  ratio mien / pygltflib_parse_only = {m_ours / statistics.median(parse):.2f}"
                  f"  ({args.repeats} interleaved repeats)")  # fmt: skip


if __name__ == "__main__":
    main()
