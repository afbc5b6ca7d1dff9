"""A written .glb plays in three.js (headless Chromium) and imports into Blender with its animated shape keys."""

from __future__ import annotations

import json
import shutil
import subprocess
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from tests.loopback import serve_folder, three_page

from mien.exchange import glb
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.clip import Clip
from mien.rig.builtin_head import builtin_head

REPO = Path(__file__).resolve().parents[2]
THREE = REPO / "node_modules" / "three"

PAGE = three_page(
    """
const camera = new THREE.PerspectiveCamera(30, 1, 0.01, 10);
camera.position.set(0, -0.02, 0.55);
const gltf = await new GLTFLoader().loadAsync("/clip.glb");
scene.add(gltf.scene);
const mixer = new THREE.AnimationMixer(gltf.scene);
mixer.clipAction(gltf.animations[0]).play();
let face = null;
gltf.scene.traverse((o) => { if (o.morphTargetDictionary) face = o; });
function frame(t) {
  mixer.setTime(t);
  renderer.render(scene, camera);
  const gl = renderer.getContext();
  const pixels = new Uint8Array(256 * 256 * 4);
  gl.readPixels(0, 0, 256, 256, gl.RGBA, gl.UNSIGNED_BYTE, pixels);
  return pixels;
}
const start = frame(0.0);
const jaw = face.morphTargetInfluences[face.morphTargetDictionary["jawOpen"]];
const end = frame(0.9);
let changed = 0;
for (let i = 0; i < start.length; i += 4) {
  const d = Math.abs(start[i] - end[i]) + Math.abs(start[i + 1] - end[i + 1]) + Math.abs(start[i + 2] - end[i + 2]);
  if (d > 30) changed++;
}
window.result = {
  changed, jawAtStart: jaw,
  jawAtEnd: face.morphTargetInfluences[face.morphTargetDictionary["jawOpen"]],
  names: Object.keys(face.morphTargetDictionary).length,
  duration: gltf.animations[0].duration,
  tracks: gltf.animations[0].tracks.map((t) => t.name),
};
"""
)


def open_jaw_clip() -> Clip:
    """1 s at 30 fps: the jaw opens and the head turns left."""
    t = np.arange(30) / 30.0
    values = np.zeros((30, 53))
    values[:, ARKIT_NAMES.index("jawOpen")] = t / t[-1]
    values[:, ARKIT_NAMES.index("mouthSmileLeft")] = t / t[-1]
    values[:, 52] = 25.0 * t / t[-1]
    return Clip(values, 30.0, (*ARKIT_NAMES, "head_yaw_deg"))


@pytest.fixture
def served(tmp_path: Path) -> Iterator[str]:
    """A loopback HTTP server (ephemeral port) with the page, the .glb and three.js from node_modules."""
    if not (THREE / "build" / "three.module.js").is_file():
        pytest.skip("three.js not in node_modules: run scripts/install (npm ci)")
    (tmp_path / "index.html").write_text(PAGE)
    (tmp_path / "three").symlink_to(THREE)
    glb.write(open_jaw_clip(), tmp_path / "clip.glb", rig=builtin_head())
    with serve_folder(tmp_path) as url:
        yield url


def test_three_js_plays_the_animation_and_pixels_change(chromium, served: str, tmp_path: Path) -> None:
    page = chromium.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    try:
        page.goto(served + "/index.html")
        page.wait_for_function("window.result !== undefined || false", timeout=20_000)
        result = page.evaluate("window.result")
        page.screenshot(path=str(tmp_path / "three.png"))
    finally:
        page.close()
    assert not errors, errors
    assert result["names"] == len(builtin_head().targets)
    assert result["duration"] == pytest.approx(29 / 30, abs=1e-4)
    assert sorted(result["tracks"]) == ["face.morphTargetInfluences", "head.quaternion"]
    assert result["jawAtStart"] == pytest.approx(0.0, abs=1e-6)
    assert result["jawAtEnd"] == pytest.approx(0.9 / (29 / 30), abs=1e-3)
    assert result["changed"] > 500  # the jaw opened and the head turned: many pixels changed


BLENDER_SCRIPT = """
import bpy, json, sys
import numpy
# Debian's Blender 3.4 glTF importer still uses numpy.bool, which numpy 1.24 (Debian's) removed; alias it back.
if "bool" not in vars(numpy):
    numpy.bool = bool
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=sys.argv[-1])
out = {}
for obj in bpy.data.objects:
    keys = obj.data.shape_keys if obj.type == "MESH" else None
    if keys is None:
        continue
    action = keys.animation_data.action if keys.animation_data else None
    curves = {fc.data_path: len(fc.keyframe_points) for fc in action.fcurves} if action else {}
    jaw = [fc for fc in action.fcurves if "jawOpen" in fc.data_path][0] if action else None
    values = [jaw.keyframe_points[0].co[1], jaw.keyframe_points[-1].co[1]] if jaw else []
    seconds = (jaw.keyframe_points[-1].co[0] - jaw.keyframe_points[0].co[0]) / bpy.context.scene.render.fps
    out = {"names": [k.name for k in keys.key_blocks], "curves": curves, "jaw": values, "seconds": seconds,
           "vertices": len(obj.data.vertices)}
print("MIEN_RESULT " + json.dumps(out))
"""


@pytest.mark.blender
def test_blender_imports_shape_keys_and_their_animation(tmp_path: Path) -> None:
    blender = shutil.which("blender")
    if blender is None:
        pytest.skip("blender not installed (apt install blender; scripts/install does)")
    path = tmp_path / "clip.glb"
    head = builtin_head()
    glb.write(open_jaw_clip(), path, rig=head)
    script = tmp_path / "inspect.py"
    script.write_text(BLENDER_SCRIPT)
    run = subprocess.run(
        [blender, "-b", "--factory-startup", "--python", str(script), "--", str(path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    line = next((x for x in run.stdout.splitlines() if x.startswith("MIEN_RESULT ")), None)
    assert line is not None, run.stdout[-2000:] + run.stderr[-2000:]
    result = json.loads(line.removeprefix("MIEN_RESULT "))
    assert result["names"][0] == "Basis" and result["names"][1:] == list(head.target_names)
    animated = [path for path in result["curves"] if "jawOpen" in path]
    assert animated and result["curves"][animated[0]] >= 2
    assert result["jaw"][0] == pytest.approx(0.0, abs=1e-4) and result["jaw"][1] == pytest.approx(1.0, abs=1e-3)
    assert result["seconds"] == pytest.approx(29 / 30, abs=0.05)  # keys span the clip (at Blender's scene rate)
