"""The textured renderer: sRGB textures, UV orientation, alpha modes, sidedness, per-frame updates, the glTF
adapter, and a VALID avatar's head drawn by mien and by three.js (GLTFLoader in headless Chromium) alike."""

from __future__ import annotations

import base64
import io
import json
import os
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError, MissingExtraError
from mien.render.camera import Camera
from mien.render.materials import (
    AlphaMode,
    Material,
    Part,
    TextureDecodeWarning,
    TexturedMesh,
    textured_mesh_from_gltf,
)
from mien.render.offscreen import EGLUnavailableError, OffscreenRenderer
from mien.render.shaders import LIGHTS
from mien.render.textured import TexturedRenderer

from .conftest import head_mesh

SIZE = 64
FRONT = Camera(distance_m=1.0, fov_deg=30.0, target=(0.0, 0.0, 0.0))
BACKGROUND = (200, 200, 200)


@pytest.fixture
def make_textured() -> Iterator[Callable[..., TexturedRenderer]]:
    """Build TexturedRenderers (closed after the test); skips when no EGL context can be created."""
    made: list[TexturedRenderer] = []

    def make(mesh: TexturedMesh, width: int = SIZE, height: int = SIZE, camera: Camera = FRONT,
             **kwargs: object) -> TexturedRenderer:  # fmt: skip
        try:
            renderer = TexturedRenderer(mesh, width, height, camera, **kwargs)  # type: ignore[arg-type]
        except (EGLUnavailableError, MissingExtraError) as error:
            pytest.skip(f"no headless OpenGL here: {error}")
        made.append(renderer)
        return renderer

    yield make
    for renderer in made:
        renderer.close()


def quad(z: float, half: float = 0.2, facing_camera: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A square at depth ``z`` (m): positions (4, 3), uvs (4, 2) with v = 0 at its top, triangles (2, 3)."""
    positions = np.array([[-half, half, z], [half, half, z], [half, -half, z], [-half, -half, z]], np.float32)
    uvs = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32)
    # Counter-clockwise seen from +z (the camera) when facing it.
    triangles = np.array([[0, 3, 2], [0, 2, 1]], np.int32)
    return positions, uvs, triangles if facing_camera else triangles[:, ::-1].copy()


def one_quad(material: Material, **quad_options: object) -> TexturedMesh:
    positions, uvs, triangles = quad(0.0, **quad_options)  # type: ignore[arg-type]
    return TexturedMesh(positions, uvs, (Part("quad", triangles, material),))


def srgb_to_linear(value: float) -> float:
    c = value / 255.0
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def test_texture_is_sampled_as_srgb_like_the_same_linear_factor(make_textured: Callable[..., TexturedRenderer]) -> None:
    level = 90
    texture = np.full((8, 8, 4), (level, level, level, 255), np.uint8)
    textured = make_textured(one_quad(Material(base_color_texture=texture))).render()
    linear = srgb_to_linear(level)
    factor = make_textured(one_quad(Material(base_color_factor=(linear, linear, linear, 1.0)))).render()
    centre = (slice(24, 40), slice(24, 40))
    assert np.abs(textured[centre].astype(int) - factor[centre].astype(int)).max() <= 2
    # Read as linear instead, 90/255 would be 3x brighter than its sRGB meaning: far from the factor image.
    wrong = make_textured(one_quad(Material(base_color_factor=(level / 255, level / 255, level / 255, 1.0)))).render()
    assert np.abs(wrong[centre].astype(int) - factor[centre].astype(int)).mean() > 20


def test_texture_row_zero_is_the_top_of_the_part(make_textured: Callable[..., TexturedRenderer]) -> None:
    texture = np.zeros((16, 16, 4), np.uint8)
    texture[..., 3] = 255
    texture[:8, :, 0] = 255  # top rows red
    texture[8:, :, 2] = 255  # bottom rows blue
    image = make_textured(one_quad(Material(base_color_texture=texture))).render().astype(int)
    top, bottom = image[22, 32], image[42, 32]
    assert top[0] > top[2] + 50 and bottom[2] > bottom[0] + 50


def test_mask_discards_below_the_cutoff_and_keeps_the_rest_opaque(
    make_textured: Callable[..., TexturedRenderer],
) -> None:
    texture = np.full((16, 16, 4), 255, np.uint8)
    texture[:, :8, 3] = 60  # left half below the cutoff
    texture[:, 8:, 3] = 160  # right half above it: drawn fully opaque
    image = make_textured(one_quad(Material(base_color_texture=texture, alpha_mode=AlphaMode.MASK,
                                            alpha_cutoff=0.5))).render()  # fmt: skip
    assert tuple(image[32, 22]) == BACKGROUND
    lit = make_textured(one_quad(Material(base_color_texture=np.full((16, 16, 4), 255, np.uint8)))).render()
    assert tuple(image[32, 42]) == tuple(lit[32, 42])


def test_blended_parts_are_drawn_back_to_front_whatever_their_order(
    make_textured: Callable[..., TexturedRenderer],
) -> None:
    back_p, uvs, tri = quad(-0.1)
    mid_p, _, _ = quad(0.0)
    front_p, _, _ = quad(0.1)
    positions = np.concatenate([back_p, mid_p, front_p])
    red = Material("red", base_color_factor=(1.0, 0.0, 0.0, 1.0))
    green = Material("green", base_color_factor=(0.0, 1.0, 0.0, 0.5), alpha_mode=AlphaMode.BLEND)
    blue = Material("blue", base_color_factor=(0.0, 0.0, 1.0, 0.5), alpha_mode=AlphaMode.BLEND)
    # Listed front first: a renderer drawing in list order would hide the green quad behind the blue one's depth.
    parts = (Part("front", tri + 8, blue), Part("mid", tri + 4, green), Part("back", tri, red))
    image = make_textured(TexturedMesh(positions, np.tile(uvs, (3, 1)), parts)).render().astype(int)
    pixel = image[32, 32]
    # Each layer lit on its own (opaque), then blended by hand in sRGB, back to front as three.js blends.
    lit = {}
    for name, rgb in (("red", (1.0, 0.0, 0.0)), ("green", (0.0, 1.0, 0.0)), ("blue", (0.0, 0.0, 1.0))):
        lit[name] = make_textured(one_quad(Material(base_color_factor=(*rgb, 1.0)))).render()[32, 32].astype(float)
    expected = 0.5 * lit["blue"] + 0.5 * (0.5 * lit["green"] + 0.5 * lit["red"])
    wrong_order = 0.5 * lit["green"] + 0.5 * (0.5 * lit["blue"] + 0.5 * lit["red"])
    assert np.abs(pixel - expected).max() <= 2
    assert np.abs(wrong_order - expected).max() > 30
    swapped = (Part("back", tri, red), Part("mid", tri + 4, green), Part("front", tri + 8, blue))
    again = make_textured(TexturedMesh(positions, np.tile(uvs, (3, 1)), swapped)).render().astype(int)
    assert np.abs(again[32, 32] - pixel).max() <= 1


def test_back_faces_are_culled_unless_double_sided(make_textured: Callable[..., TexturedRenderer]) -> None:
    white = (1.0, 1.0, 1.0, 1.0)
    single = make_textured(one_quad(Material(base_color_factor=white), facing_camera=False)).render()
    double = make_textured(one_quad(Material(base_color_factor=white, double_sided=True),
                                    facing_camera=False)).render()  # fmt: skip
    front = make_textured(one_quad(Material(base_color_factor=white))).render()
    assert tuple(single[32, 32]) == BACKGROUND
    # The back face is lit with its flipped normal: as bright as the front face.
    assert np.abs(double[32, 32].astype(int) - front[32, 32].astype(int)).max() <= 2


def test_positions_change_per_frame(make_textured: Callable[..., TexturedRenderer]) -> None:
    mesh = one_quad(Material(base_color_factor=(1.0, 1.0, 1.0, 1.0)), half=0.1)
    renderer = make_textured(mesh)
    first = renderer.render()
    moved = mesh.positions + np.array([0.15, 0.0, 0.0], np.float32)
    second = renderer.render(moved)
    assert tuple(first[32, 32]) != BACKGROUND and tuple(second[32, 32]) == BACKGROUND
    assert tuple(second[32, 52]) != BACKGROUND
    with pytest.raises(InvalidValueError):
        renderer.render(mesh.positions[:3])


@pytest.mark.parametrize(("per_pixel", "mean_bound", "p99_bound"), [(True, 0.1, 1), (False, 0.2, 2)])
def test_untextured_part_looks_like_the_untextured_renderer(
    make_textured: Callable[..., TexturedRenderer],
    make_renderer: Callable[..., OffscreenRenderer],
    per_pixel: bool,
    mean_bound: float,
    p99_bound: float,
) -> None:
    vertices, faces = head_mesh(80, 128)
    camera = Camera(distance_m=0.6)
    albedo = (0.62, 0.40, 0.30)
    colors = np.tile(albedo, (len(vertices), 1))
    reference = make_renderer(faces, 96, 96, camera, vertex_colors=colors).render(vertices)
    part = Part("head", faces, Material(base_color_factor=(*albedo, 1.0)))
    mesh = TexturedMesh(vertices, np.zeros((len(vertices), 2)), (part,))
    ours = make_textured(mesh, 96, 96, camera, weld_normals=False, per_pixel=per_pixel).render()
    difference = np.abs(ours.astype(int) - reference.astype(int))
    # Per pixel: the same shading (the gamma fit is within a level); per vertex: diffuse light interpolated.
    assert difference.mean() < mean_bound and np.percentile(difference, 99) <= p99_bound
    assert tuple(ours[48, 48]) != BACKGROUND


def test_materials_reject_bad_values() -> None:
    with pytest.raises(InvalidValueError):
        Material(base_color_texture=np.zeros((4, 4, 3), np.uint8))
    with pytest.raises(InvalidValueError):
        Material(base_color_factor=(1.0, 1.0, 2.0, 1.0))
    with pytest.raises(ValueError):
        Material(alpha_mode="SOMETIMES")  # type: ignore[arg-type]
    with pytest.raises(InvalidValueError):
        TexturedMesh(np.zeros((3, 3)), np.zeros((3, 2)), (Part("p", np.array([[0, 1, 3]])),))


# --- the glTF adapter -------------------------------------------------------------------------------------


def write_quad_gltf(path: Path, image: bytes, mime: str, material: dict[str, object]) -> Path:
    """A one-quad ``.gltf`` (data URIs) whose material samples ``image``."""
    positions, uvs, triangles = quad(0.0)
    blob = positions.tobytes() + uvs.tobytes() + triangles.astype(np.uint16).tobytes()
    n = len(positions)
    document = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [
            {
                "name": "card",
                "primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}],
            }
        ],
        "materials": [{"name": "m", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}, **material}],
        "textures": [{"source": 0}],
        "images": [{"uri": f"data:{mime};base64,{base64.b64encode(image).decode()}"}],
        "buffers": [
            {"byteLength": len(blob), "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": n * 12},
            {"buffer": 0, "byteOffset": n * 12, "byteLength": n * 8},
            {"buffer": 0, "byteOffset": n * 20, "byteLength": triangles.size * 2},
        ],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,
                "count": n,
                "type": "VEC3",
                "min": positions.min(0).tolist(),
                "max": positions.max(0).tolist(),
            },
            {"bufferView": 1, "componentType": 5126, "count": n, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": triangles.size, "type": "SCALAR"},
        ],
    }
    path.write_text(json.dumps(document))
    return path


def test_gltf_adapter_decodes_textures_and_reads_alpha_modes(tmp_path: Path) -> None:
    pil_image = pytest.importorskip("PIL.Image")
    from mien.rig.files.gltf import read_gltf

    pixels = np.zeros((4, 4, 4), np.uint8)
    pixels[..., 1] = 200
    pixels[..., 3] = 128
    encoded = io.BytesIO()
    pil_image.fromarray(pixels, "RGBA").save(encoded, format="WEBP", lossless=True)
    material = {"alphaMode": "MASK", "alphaCutoff": 0.25, "doubleSided": True}
    path = write_quad_gltf(tmp_path / "card.gltf", encoded.getvalue(), "image/webp", material)
    mesh = textured_mesh_from_gltf(read_gltf(path))
    (part,) = mesh.parts
    assert part.name == "card" and part.triangles.shape == (2, 3)
    assert part.material.alpha_mode is AlphaMode.MASK and part.material.alpha_cutoff == 0.25
    assert part.material.double_sided
    assert part.material.base_color_texture is not None
    assert part.material.base_color_texture.tolist() == pixels.tolist()
    assert mesh.uvs.tolist() == quad(0.0)[1].tolist()


def test_gltf_adapter_warns_on_an_undecodable_texture_and_keeps_the_factor(tmp_path: Path) -> None:
    pytest.importorskip("PIL.Image")
    from mien.rig.files.gltf import read_gltf

    material = {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "baseColorFactor": [0.5, 0.2, 0.1, 1.0]}}
    path = write_quad_gltf(tmp_path / "broken.gltf", b"not an image at all", "image/png", material)
    with pytest.warns(TextureDecodeWarning, match=r"broken\.gltf: texture image 0 of material .m. \(image/png\)"):
        mesh = textured_mesh_from_gltf(read_gltf(path))
    assert mesh.parts[0].material.base_color_texture is None
    assert mesh.parts[0].material.base_color_factor == (0.5, 0.2, 0.1, 1.0)


# --- a VALID avatar, drawn by mien and by three.js ---------------------------------------------------------

SHARED = Path(os.environ.get("MIEN_SHARED", Path(__file__).resolve().parents[3] / "shared"))
AVATAR = SHARED / "avatars" / "valid" / "White_F_1_Casual.glb"
HEAD_TARGET = (0.0, 1.58, 0.05)
"""Middle of the face of the VALID avatars, file frame (metres, y up, facing +z)."""
HEAD_CAMERA = Camera(distance_m=0.7, fov_deg=22.0, target=HEAD_TARGET)
COMPARE_SIZE = 384

THREE_PAGE = """<!doctype html><html><body style="margin:0">
<script type="importmap">{"imports": {"three": "/three/build/three.module.js", "three/addons/": "/three/examples/jsm/"}}
</script>
<script type="module">
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { MeshoptDecoder } from 'three/addons/libs/meshopt_decoder.module.js';
const setup = %s;
try {
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setSize(setup.size, setup.size);
  document.body.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color().setRGB(...setup.background.map(c => c / 255), THREE.SRGBColorSpace);
  const camera = new THREE.PerspectiveCamera(setup.fov, 1, setup.near, setup.far);
  camera.position.set(...setup.position);
  camera.lookAt(new THREE.Vector3(...setup.target));
  scene.add(camera);
  // mien's lights: eye-space directions, so they ride on the camera; intensities times pi because three.js's
  // Lambert BRDF divides by pi.
  for (const [direction, color] of setup.lights) {
    const light = new THREE.DirectionalLight(new THREE.Color().setRGB(...color, THREE.LinearSRGBColorSpace), Math.PI);
    light.position.set(...direction);
    camera.add(light);
    camera.add(light.target);
  }
  scene.add(new THREE.HemisphereLight(new THREE.Color().setRGB(0.16, 0.16, 0.17, THREE.LinearSRGBColorSpace),
    new THREE.Color().setRGB(0.05, 0.05, 0.06, THREE.LinearSRGBColorSpace), Math.PI));
  const loader = new GLTFLoader().setMeshoptDecoder(MeshoptDecoder);
  const gltf = await loader.loadAsync('/avatar.glb');
  gltf.scene.traverse((object) => {
    if (!object.isMesh) return;
    const m = object.material;
    // The file's own base colour, alpha and sides; Lambert shading so both renderers light alike.
    object.material = new THREE.MeshLambertMaterial({ map: m.map, color: m.color, opacity: m.opacity,
      transparent: m.transparent, alphaTest: m.alphaTest, side: m.side, depthWrite: m.depthWrite });
    object.frustumCulled = false;
  });
  scene.add(gltf.scene);
  renderer.render(scene, camera);
  window.__png = renderer.domElement.toDataURL('image/png');
} catch (error) {
  window.__error = String(error && error.stack || error);
}
</script></body></html>"""


def three_js_render(browser: object, avatar: Path, camera: Camera, size: int) -> np.ndarray:
    """(size, size, 3) uint8: ``avatar`` loaded by three.js's GLTFLoader and drawn under mien's lights."""
    from PIL import Image

    from mien.viewer.vendor import three_dir

    three = three_dir()
    if three is None:
        pytest.skip("node_modules/three missing: run `npm ci`")
    setup = {
        "size": size, "fov": camera.fov_deg, "near": camera.near_m, "far": camera.far_m,
        "position": camera.position.tolist(), "target": list(camera.target), "background": list(BACKGROUND),
        "lights": [[list(np.asarray(d) / np.linalg.norm(d)), list(c)] for d, c in LIGHTS.values()],
    }  # fmt: skip
    page_html = THREE_PAGE % json.dumps(setup)

    def serve(route: object) -> None:
        url = route.request.url  # type: ignore[attr-defined]
        local = url.split("://", 1)[1].split("/", 1)[1]
        if local == "" or local == "index.html":
            route.fulfill(body=page_html, content_type="text/html")  # type: ignore[attr-defined]
        elif local == "avatar.glb":
            route.fulfill(body=avatar.read_bytes(), content_type="model/gltf-binary")  # type: ignore[attr-defined]
        elif local.startswith("three/") and (three / local[6:]).is_file():
            route.fulfill(body=(three / local[6:]).read_bytes(), content_type="text/javascript")  # type: ignore[attr-defined]
        else:
            route.fulfill(status=404, body="")  # type: ignore[attr-defined]

    page = browser.new_page(viewport={"width": size, "height": size})  # type: ignore[attr-defined]
    try:
        page.route("http://mien.test/**", serve)
        page.goto("http://mien.test/index.html")
        page.wait_for_function("window.__png || window.__error", timeout=60_000)
        error = page.evaluate("window.__error")
        assert error is None, error
        data_url = page.evaluate("window.__png")
    finally:
        page.close()
    png = base64.b64decode(data_url.split(",", 1)[1])
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))


def foreground(image: np.ndarray) -> np.ndarray:
    """(h, w) bool: pixels that are not the background colour."""
    return np.abs(image.astype(int) - np.array(BACKGROUND)).max(axis=2) > 6


@pytest.mark.slow
def test_valid_avatar_head_looks_like_three_js(
    chromium: object, make_textured: Callable[..., TexturedRenderer]
) -> None:
    if not AVATAR.is_file():
        pytest.skip(f"VALID avatar not found at {AVATAR} (set MIEN_SHARED)")
    pytest.importorskip("meshopt", reason="the heads extra is not installed")
    from PIL import Image

    from mien.rig.files.gltf import read_gltf

    with warnings.catch_warnings():
        warnings.simplefilter("error", TextureDecodeWarning)
        mesh = textured_mesh_from_gltf(read_gltf(AVATAR))
    ours = make_textured(mesh, COMPARE_SIZE, COMPARE_SIZE, HEAD_CAMERA).render()
    theirs = three_js_render(chromium, AVATAR, HEAD_CAMERA, COMPARE_SIZE)
    Image.fromarray(ours).save("/tmp/mien_textured_valid.png")
    Image.fromarray(theirs).save("/tmp/threejs_valid.png")
    Image.fromarray(np.abs(ours.astype(int) - theirs.astype(int)).clip(0, 255).astype(np.uint8) * 4).save(
        "/tmp/textured_vs_threejs_diff.png"
    )
    ours_mask, theirs_mask = foreground(ours), foreground(theirs)
    iou = (ours_mask & theirs_mask).sum() / (ours_mask | theirs_mask).sum()
    # The face: a box 14 cm wide, from the brows to the chin, projected through the camera.
    corners = HEAD_CAMERA.project(np.array([[-0.05, 1.64, 0.12], [0.05, 1.50, 0.12]]), COMPARE_SIZE, COMPARE_SIZE)
    (left, top), (right, bottom) = np.round(corners).astype(int)
    face = (slice(int(top), int(bottom)), slice(int(left), int(right)))
    difference = np.abs(ours[face].astype(int) - theirs[face].astype(int))
    mean_abs = float(difference.mean())
    brightness = float(ours[face].mean()) - float(theirs[face].mean())
    print(
        f"mask IoU {iou:.4f}; face box rows {top}..{bottom} cols {left}..{right}: mean |diff| {mean_abs:.2f} / 255, "
        f"95th pct {np.percentile(difference, 95):.0f}, mean brightness mien - three.js {brightness:+.2f}"
    )
    assert ours_mask[face].mean() == 1.0 and theirs_mask[face].mean() == 1.0
    assert iou > 0.95
    # three.js's Lambert lacks mien's key specular and rim terms: that is most of the difference left.
    assert mean_abs < 6.0
    # Same brightness on average: a linear/sRGB slip would shift the skin by tens of levels.
    assert abs(brightness) < 4.0
