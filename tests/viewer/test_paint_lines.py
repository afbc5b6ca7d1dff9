"""No thin red lines on ICT's neck and chest in the viewer (issue 29 case 16).

The head glb parks unpainted vertices' ``TEXCOORD_0`` on the paint texture's border, so each triangle from a
painted vertex to a parked one spans the whole texture; three.js then samples the texture's coarsest mipmap
(its average: the lips' red, the brows' brown) along the paint's edge. Before the fix a frontal screenshot had
388 pixels on the neck and chest that stood out in red from their neighbourhood (see ``_red_specks``); mien's
renderer, which blends the paint by each vertex's strength, draws none. The glb now carries every vertex's own
paint texcoords and strength (``_PAINT``), and the viewer paints with them as the renderer does.
"""

from __future__ import annotations

import io
import os
import re
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from mien.exchange.glb import head_glb_bytes
from mien.fileio.glb import read_accessor, unpack_glb
from mien.render.appearance import visible_faces
from mien.render.face_paint import face_paint


@pytest.fixture(scope="module")
def ict_rig(ict_dir: Path):  # type: ignore[no-untyped-def]
    from mien.rig.heads import open_head

    return open_head("ict")


def _attribute(document: dict, binary: bytes, name: str) -> np.ndarray:
    index = document["meshes"][0]["primitives"][0]["attributes"][name]

    def view_bytes(i: int) -> bytes:
        view = document["bufferViews"][i]
        start = view.get("byteOffset", 0)
        return binary[start : start + view["byteLength"]]

    return read_accessor(document, index, view_bytes, "head.glb")


def test_the_head_glb_carries_each_vertex_paint_texcoords_and_strength(ict_rig) -> None:  # type: ignore[no-untyped-def]
    document, binary = unpack_glb(head_glb_bytes(ict_rig), "head.glb")
    assert binary is not None
    paint = face_paint(ict_rig)
    assert paint is not None
    own = _attribute(document, binary, "_PAINT")
    np.testing.assert_array_equal(own, paint.texcoords)
    parked = _attribute(document, binary, "TEXCOORD_0")  # what other glTF viewers read: unchanged
    height, width = paint.texture.shape[:2]
    faces = visible_faces(ict_rig)

    def texels_spanned(uv: np.ndarray) -> np.ndarray:
        return ((uv[faces].max(axis=1) - uv[faces].min(axis=1)) * (width, height)).max(axis=1)

    # A triangle's own texcoords span what its rest shape spans (under 100 texels: 25 mm); the parked ones
    # span the texture along the paint's edge, the triangles that drew the lines.
    assert texels_spanned(own[:, :2]).max() < 100
    assert (texels_spanned(parked) > 100).sum() > 500


def _red_specks(png: bytes) -> int:
    """Pixels of the neck and chest (the lower middle of the view) redder, by more than 8 levels of red minus
    green, than the median of the 11 x 11 pixels around them: thin lines, not the skin's shading."""
    from numpy.lib.stride_tricks import sliding_window_view
    from PIL import Image

    image = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(np.float64)
    height, width = image.shape[:2]
    crop = image[int(0.70 * height) : int(0.975 * height), int(0.28 * width) : int(0.72 * width)]
    red = crop[..., 0] - crop[..., 1]
    around = np.median(sliding_window_view(np.pad(red, 5, mode="edge"), (11, 11)), axis=(-2, -1))
    return int((red - around > 8).sum())


@pytest.fixture(scope="module")
def ict_server(ict_dir: Path) -> Iterator[str]:
    """``mien serve --head ict`` (no idle motion) on ephemeral ports: the viewer's address."""
    pytest.importorskip("fastapi", reason="the serve extra is not installed")
    from mien.viewer.vendor import three_dir

    if three_dir() is None:
        pytest.skip("three.js missing: run `npm ci`")
    command = [sys.executable, "-m", "mien.cli", "serve", "--udp-port", "0", "--http-port", "0", "--head", "ict"]
    process = subprocess.Popen(
        [*command, "--no-idle"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    found: list[str] = []

    def read() -> None:
        assert process.stdout is not None
        for line in process.stdout:
            if not found and (match := re.search(r"HTTP on (http://\S+:\d+)/", line)):
                found.append(match.group(1))

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    deadline = time.monotonic() + 60
    while not found and time.monotonic() < deadline and process.poll() is None:
        time.sleep(0.1)
    try:
        assert found, "mien serve --head ict did not start in 60 s"
        yield found[0]
    finally:
        process.terminate()
        try:
            process.wait(10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(5)
        reader.join(5)
        if process.stdout is not None:
            process.stdout.close()


@pytest.mark.slow
def test_the_viewer_draws_no_lines_on_the_ict_neck_and_chest(chromium: object, ict_server: str) -> None:
    page = chromium.new_page(viewport={"width": 1000, "height": 800})  # type: ignore[attr-defined]
    try:
        errors: list[str] = []
        page.on("pageerror", lambda error: errors.append(str(error)))
        page.goto(f"{ict_server}/")
        page.wait_for_function(
            "document.body.dataset.ready === '1' && window.mienViewer.head !== null && window.mienViewer.renders > 1",
            timeout=60_000,
        )
        time.sleep(1.0)
        png = page.locator("#view").screenshot()
    finally:
        page.close()
    assert errors == []
    assert _red_specks(png) < 20
