"""In a real headless Chromium: mien's VRM 1.0 of ICT loads with @pixiv/three-vrm and its expressions work; a VALID
avatar exported with a clip plays in three.js (meshopt decoder, WebP textures, skin) and its face moves."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from tests.exchange.test_user_character import _valid_avatar, smile_clip
from tests.loopback import serve_folder, three_page

from mien.exchange import glb, vrm
from mien.rig.heads import open_head

REPO = Path(__file__).resolve().parents[2]
MODULES = REPO / "node_modules"

COMMON = """
const camera = new THREE.PerspectiveCamera(30, 1, 0.01, 10);
function pixels() {
  renderer.render(scene, camera);
  const gl = renderer.getContext();
  const out = new Uint8Array(256 * 256 * 4);
  gl.readPixels(0, 0, 256, 256, gl.RGBA, gl.UNSIGNED_BYTE, out);
  return out;
}
function changed(a, b, rowFrom, rowTo) {  // rows counted from the top of the image
  let n = 0;
  for (let row = rowFrom; row < rowTo; row++) {
    for (let col = 0; col < 256; col++) {
      const i = ((255 - row) * 256 + col) * 4;
      if (Math.abs(a[i] - b[i]) + Math.abs(a[i + 1] - b[i + 1]) + Math.abs(a[i + 2] - b[i + 2]) > 30) n++;
    }
  }
  return n;
}
"""

VRM_PAGE = three_page(
    COMMON
    + """
import { VRMLoaderPlugin } from "@pixiv/three-vrm";
const loader = new GLTFLoader();
loader.register((parser) => new VRMLoaderPlugin(parser));
const gltf = await loader.loadAsync("/ict.vrm");
const vrm = gltf.userData.vrm;
scene.add(vrm.scene);
camera.position.set(0, -0.03, 0.55);
camera.lookAt(0, -0.03, 0);
let face = null;
vrm.scene.traverse((o) => { if (o.morphTargetDictionary) face = o; });
vrm.update(0.016);
const before = pixels();
vrm.expressionManager.setValue("happy", 1.0);
vrm.update(0.016);
const after = pixels();
window.result = {
  metaVersion: vrm.meta.metaVersion,
  presets: vrm.expressionManager.expressions.map((e) => e.expressionName),
  bones: Object.keys(vrm.humanoid.humanBones),
  happy: vrm.expressionManager.getValue("happy"),
  smileLeft: face.morphTargetInfluences[face.morphTargetDictionary["mouthSmileLeft"]],
  browDown: face.morphTargetInfluences[face.morphTargetDictionary["browDownLeft"]],
  mouth: changed(before, after, 150, 200),
  top: changed(before, after, 0, 60),
};
""",
    imports={"@pixiv/three-vrm": "/three-vrm/lib/three-vrm.module.js"},
)

AVATAR_PAGE = three_page(
    COMMON
    + """
import { MeshoptDecoder } from "three/addons/libs/meshopt_decoder.module.js";
const loader = new GLTFLoader();
loader.setMeshoptDecoder(MeshoptDecoder);
const gltf = await loader.loadAsync("/animated.glb");
scene.add(gltf.scene);
const head = new THREE.Vector3();
gltf.scene.updateMatrixWorld(true);
gltf.scene.getObjectByName("Head").getWorldPosition(head);
camera.position.set(head.x, head.y + 0.08, head.z + 0.6);
camera.lookAt(head.x, head.y + 0.08, head.z);
const clip = gltf.animations.find((a) => a.name === "mien");
const mixer = new THREE.AnimationMixer(gltf.scene);
const action = mixer.clipAction(clip);
action.setLoop(THREE.LoopOnce, 1);
action.clampWhenFinished = true;  // at the clip's end, hold its last key (a repeating action wraps to 0)
action.play();
mixer.setTime(0.0);
const start = pixels();
mixer.setTime(clip.duration);
const end = pixels();
let face = null;
gltf.scene.traverse((o) => { if (o.name === "H_DDS_HighRes" && o.morphTargetDictionary) face = o; });
window.result = {
  tracks: clip.tracks.map((t) => t.name),
  jaw: face.morphTargetInfluences[face.morphTargetDictionary["h_expressions.MouthOpen_h"]],
  changed: changed(start, end, 0, 256),
};
"""
)


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, Path]]:
    """A loopback HTTP server with the pages, three.js and three-vrm from node_modules; files go in the folder."""
    if not (MODULES / "three" / "build" / "three.module.js").is_file():
        pytest.skip("three.js not in node_modules: run scripts/install (npm ci)")
    if not (MODULES / "@pixiv" / "three-vrm" / "lib" / "three-vrm.module.js").is_file():
        pytest.skip("@pixiv/three-vrm not in node_modules: run scripts/install (npm ci)")
    folder = tmp_path_factory.mktemp("served")
    (folder / "vrm.html").write_text(VRM_PAGE)
    (folder / "avatar.html").write_text(AVATAR_PAGE)
    (folder / "three").symlink_to(MODULES / "three")
    (folder / "three-vrm").symlink_to(MODULES / "@pixiv" / "three-vrm")
    with serve_folder(folder) as url:
        yield url, folder


def _run(chromium: Any, url: str, screenshot: Path) -> dict[str, Any]:
    page = chromium.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.on(
        "console", lambda m: errors.append(m.text) if m.type == "error" and "Failed to load" not in m.text else None
    )
    page.on("response", lambda r: errors.append(f"{r.status} {r.url}") if r.status >= 400 and "favicon" not in r.url
            else None)  # fmt: skip
    try:
        page.goto(url)
        page.wait_for_function("window.result !== undefined", timeout=60_000)
        result: dict[str, Any] = page.evaluate("window.result")
        page.screenshot(path=str(screenshot))
    finally:
        page.close()
    assert not errors, errors
    return result


def test_three_vrm_loads_mien_vrm_and_happy_smiles(chromium: Any, served: tuple[str, Path], ict_dir: Path) -> None:
    url, folder = served
    rig = open_head("ict")
    vrm.write(smile_clip(), folder / "ict.vrm", rig=rig)
    result = _run(chromium, url + "/vrm.html", folder / "vrm.png")
    assert result["metaVersion"] == "1"
    assert set(vrm.EXPRESSION_PRESETS) <= set(result["presets"]) and "jawOpen" in result["presets"]
    assert {"hips", "spine", "neck", "head", "leftHand", "rightFoot"} <= set(result["bones"])
    happy = vrm.expression_weights(rig)["happy"]
    assert result["happy"] == pytest.approx(1.0)
    assert result["smileLeft"] == pytest.approx(float(happy[rig.target_index("mouthSmileLeft")]), abs=1e-3)
    assert result["browDown"] == pytest.approx(0.0, abs=1e-6)  # joy does not lower the brows
    assert result["mouth"] > 150 and result["mouth"] > 5 * result["top"]  # the mouth moved, the brows not


def test_three_js_plays_a_valid_avatar_exported_with_a_clip(chromium: Any, served: tuple[str, Path]) -> None:
    url, folder = served
    rig = open_head(str(_valid_avatar()))
    glb.write(smile_clip(), folder / "animated.glb", rig=rig)
    result = _run(chromium, url + "/avatar.html", folder / "avatar.png")
    assert {"H_DDS_HighRes.morphTargetInfluences", "h_TeethDown.morphTargetInfluences", "Head.quaternion",
            "LeftEye.quaternion", "RightEye.quaternion"} == set(result["tracks"])  # fmt: skip
    weights = np.zeros((1, len(rig.targets)), np.float32)
    weights[0, rig.target_index("jawOpen")] = 0.6
    from mien.exchange.file_shapes import rig_shape_weights

    expected = float(rig_shape_weights(weights, rig)["h_expressions.MouthOpen_h"][0])
    assert result["jaw"] == pytest.approx(expected, abs=1e-3) and expected > 0.1
    assert result["changed"] > 1000  # the head turned and the mouth opened
