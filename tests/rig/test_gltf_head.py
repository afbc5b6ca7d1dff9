"""Heads from files: synthetic glTF covering the decoders, bad input, the VALID avatars, ICT through Blender."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest
from tests.conftest import valid_avatars

from mien.facs.arkit import ARKIT_NAMES
from mien.rig.files import FileRig, HeadFileError, HeadFileWarning, NoMorphTargetsError, load_head_file
from mien.rig.heads import open_head, parse_head_spec

pytest.importorskip("meshopt", reason="needs the heads extra: pip install 'mien[heads]'")


# --- a small GLB writer for the tests -------------------------------------------------------------------------


class _Glb:
    def __init__(self) -> None:
        self.blob = bytearray()
        self.doc: dict = {"asset": {"version": "2.0"}, "buffers": [], "bufferViews": [], "accessors": [],
                          "meshes": [], "nodes": [], "scenes": [{"nodes": []}], "scene": 0}  # fmt: skip

    def view(self, data: bytes) -> int:
        while len(self.blob) % 4:
            self.blob.append(0)
        self.doc["bufferViews"].append({"buffer": 0, "byteOffset": len(self.blob), "byteLength": len(data)})
        self.blob.extend(data)
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, array: np.ndarray, kind: str, normalized: bool = False, **extra) -> int:
        component = {np.float32: 5126, np.int16: 5122, np.uint16: 5123, np.uint32: 5125, np.uint8: 5121}
        acc = {"bufferView": self.view(array.tobytes()), "componentType": component[array.dtype.type],
               "count": len(array), "type": kind, **extra}  # fmt: skip
        if normalized:
            acc["normalized"] = True
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def bytes(self) -> bytes:
        self.doc["buffers"] = [{"byteLength": len(self.blob)}]
        text = json.dumps(self.doc).encode()
        text += b" " * (-len(text) % 4)
        blob = bytes(self.blob) + b"\0" * (-len(self.blob) % 4)
        total = 12 + 8 + len(text) + 8 + len(blob)
        return (b"glTF" + (2).to_bytes(4, "little") + total.to_bytes(4, "little")
                + len(text).to_bytes(4, "little") + b"JSON" + text
                + len(blob).to_bytes(4, "little") + b"BIN\0" + blob)  # fmt: skip


GRID = np.array([[x, y, 0.0] for y in (-0.05, 0.0, 0.05) for x in (-0.05, 0.0, 0.05)], np.float64)
GRID_FACES = np.array([[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4], [3, 4, 7], [3, 7, 6], [4, 5, 8], [4, 8, 7]])


def _synthetic(tmp_path: Path, with_targets: bool = True, required: tuple[str, ...] = ()) -> Path:
    """A head of two meshes: a quantized, scaled 'face' grid and a float 'teeth' grid, eye nodes, a bad texture."""
    glb = _Glb()
    scale = 0.05  # KHR_mesh_quantization: int16 normalized positions, node scale restores metres
    quantized = np.round(GRID / scale * 32767).astype(np.int16)
    face_pos = glb.accessor(quantized, "VEC3", normalized=True)
    ids = glb.accessor(GRID_FACES.astype(np.uint16).ravel(), "SCALAR")
    face_attrs = {"POSITION": face_pos, "TEXCOORD_0": glb.accessor((GRID[:, :2] + 0.5).astype(np.float32), "VEC2")}
    teeth = GRID * 0.5 + [0.0, -0.05, -0.01]
    face_prim: dict = {"attributes": face_attrs, "indices": ids, "material": 0}
    teeth_prim: dict = {"attributes": {"POSITION": glb.accessor(teeth.astype(np.float32), "VEC3")}, "indices": ids}
    names = {"face": [], "teeth": []}
    if with_targets:
        # jawOpen on the face: a sparse accessor moving vertices 0..2 (the bottom row) down by 1 unit = 5 cm.
        sparse_ids = glb.view(np.array([0, 1, 2], np.uint16).tobytes())
        sparse_values = glb.view(np.tile(np.array([0, -32767, 0], np.int16), 3).tobytes())
        sparse = {"count": 3, "indices": {"bufferView": sparse_ids, "componentType": 5123},
                  "values": {"bufferView": sparse_values}}  # fmt: skip
        glb.doc["accessors"].append({"componentType": 5122, "normalized": True, "count": 9, "type": "VEC3",
                                     "sparse": sparse})  # fmt: skip
        jaw_face = len(glb.doc["accessors"]) - 1
        blink = np.zeros((9, 3), np.float32)
        blink[8] = [0.0, -0.2, 0.0]  # moves the +x top corner: the character's left
        face_prim["targets"] = [{"POSITION": jaw_face}, {"POSITION": glb.accessor(blink, "VEC3")}]
        teeth_jaw = np.zeros((9, 3), np.float32)
        teeth_jaw[:3, 1] = -0.01
        teeth_prim["targets"] = [{"POSITION": glb.accessor(teeth_jaw, "VEC3")}]
        names = {"face": ["jawOpen", "eyeBlinkLeft"], "teeth": ["jawOpen"]}
    glb.doc["meshes"] = [
        {"name": "face", "primitives": [face_prim], "extras": {"targetNames": names["face"]}},
        {"name": "teeth", "primitives": [teeth_prim], "extras": {"targetNames": names["teeth"]}},
    ]
    glb.doc["nodes"] = [
        {"name": "Armature", "translation": [0.0, 1.6, 0.0], "children": [1, 2, 3, 4]},
        {"name": "face", "mesh": 0, "scale": [scale, scale, scale]},
        {"name": "teeth", "mesh": 1},
        {"name": "LeftEye", "translation": [0.032, 0.03, -0.01]},
        {"name": "RightEye", "translation": [-0.032, 0.03, -0.01]},
    ]
    glb.doc["scenes"] = [{"nodes": [0]}]
    glb.doc["images"] = [{"bufferView": glb.view(b"definitely not a PNG"), "mimeType": "image/png"}]
    glb.doc["textures"] = [{"source": 0}]
    glb.doc["materials"] = [{"name": "skin", "alphaMode": "BLEND",
                             "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]  # fmt: skip
    if required:
        glb.doc["extensionsUsed"] = glb.doc["extensionsRequired"] = list(required)
    path = tmp_path / "head.glb"
    path.write_bytes(glb.bytes())
    return path


def test_a_synthetic_file_loads_in_mien_frame_with_combined_targets(tmp_path: Path) -> None:
    path = _synthetic(tmp_path)
    with pytest.warns(HeadFileWarning, match=r"head\.glb.*cannot be decoded"):
        rig = load_head_file(path)
    assert isinstance(rig, FileRig) and rig.n_vertices == 18 and len(rig.faces) == 16
    origin = np.array([0.0, 1.63, -0.01])  # midway between the eye nodes
    assert rig.info is not None and rig.info.eyes.startswith("eye joints LeftEye, RightEye")
    np.testing.assert_allclose(rig.eye_centers, [[0.032, 0, 0], [-0.032, 0, 0]], atol=1e-6)
    # Dequantized and scaled by the node, moved by its parent.
    np.testing.assert_allclose(rig.neutral[:9], GRID + np.array([0.0, 1.6, 0.0]) - origin, atol=2e-6)
    assert rig.info.unit_m == 1.0 and rig.info.names.convention == "arkit"
    assert rig.target_names == ("eyeBlinkLeft", "jawOpen")  # ARKit order
    jaw = rig.target("jawOpen")
    np.testing.assert_array_equal(jaw.vertex_ids, [0, 1, 2, 9, 10, 11])  # face (sparse) and teeth together
    np.testing.assert_allclose(jaw.deltas[:3, 1], -0.05, atol=1e-6)
    np.testing.assert_allclose(jaw.deltas[3:, 1], -0.01, atol=1e-7)
    np.testing.assert_allclose(rig.target("eyeBlinkLeft").deltas, [[0.0, -0.01, 0.0]], atol=1e-7)
    material = rig.info.materials[0]
    assert material.alpha_mode == "BLEND" and material.base_color_image is None and material.uvs is not None
    assert rig.info.source_names["jawOpen"] == (("jawOpen", 1.0, ""),)
    assert "AU1 cannot show" in rig.info.report()


def test_a_file_path_is_a_head_spec(tmp_path: Path) -> None:
    path = _synthetic(tmp_path)
    assert parse_head_spec(str(path)) == ("file", str(path))
    assert parse_head_spec(f"file:{path}") == ("file", str(path))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", HeadFileWarning)
        rig = open_head(str(path))
    assert rig.target_names == ("eyeBlinkLeft", "jawOpen")


def test_a_model_facing_minus_z_is_turned(tmp_path: Path) -> None:
    path = _synthetic(tmp_path)
    data = bytearray(path.read_bytes())
    text = data[20 : 20 + int.from_bytes(data[12:16], "little")].decode()
    swapped = text.replace('"LeftEye"', '"TMP"').replace('"RightEye"', '"LeftEye"').replace('"TMP"', '"RightEye"')
    data[20 : 20 + len(swapped)] = swapped.encode()
    path.write_bytes(bytes(data))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", HeadFileWarning)
        rig = load_head_file(path)
    assert rig.info is not None and rig.info.axes.startswith("turned 180 degrees")
    assert rig.eye_centers[0, 0] > 0
    # The shape that moved file +x now moves the rig's -x side.
    assert rig.neutral[rig.target("eyeBlinkLeft").vertex_ids[0], 0] < 0


def test_draco_primitives_decode(tmp_path: Path) -> None:
    dracopy = pytest.importorskip("DracoPy")
    path = _synthetic(tmp_path)
    data = path.read_bytes()
    length = int.from_bytes(data[12:16], "little")
    doc = json.loads(data[20 : 20 + length])
    blob = bytearray(data[20 + length + 8 :])
    encoded = dracopy.encode(GRID.astype(np.float32) * 0.3, faces=GRID_FACES.astype(np.uint32))
    position_id = next(a["unique_id"] for a in dracopy.decode(encoded).attributes if a["attribute_type"] == 0)
    doc["bufferViews"].append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(encoded)})
    blob.extend(encoded)
    blob.extend(b"\0" * (-len(blob) % 4))
    doc["buffers"][0]["byteLength"] = len(blob)
    doc["meshes"].append({"name": "hair", "primitives": [{"attributes": {}, "extensions": {
        "KHR_draco_mesh_compression": {"bufferView": len(doc["bufferViews"]) - 1,
                                       "attributes": {"POSITION": position_id}}}}]})  # fmt: skip
    doc["nodes"].append({"name": "hair", "mesh": 2})
    doc["nodes"][0]["children"].append(len(doc["nodes"]) - 1)
    doc["extensionsUsed"] = doc["extensionsRequired"] = ["KHR_draco_mesh_compression"]
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    total = 28 + len(text) + len(blob)
    path.write_bytes(b"glTF" + (2).to_bytes(4, "little") + total.to_bytes(4, "little") + len(text).to_bytes(4, "little")
                     + b"JSON" + text + len(blob).to_bytes(4, "little") + b"BIN\0" + bytes(blob))  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", HeadFileWarning)
        rig = load_head_file(path)
    start, stop = rig.info.meshes["hair"]  # type: ignore[union-attr]
    hair = rig.neutral[start:stop] + np.array([0.0, 0.03, -0.01])
    assert stop - start == 9
    np.testing.assert_allclose(np.sort(hair[:, 0]), np.sort(GRID[:, 0] * 0.3), atol=1e-4)


def test_bad_files_raise_typed_errors_naming_the_file(tmp_path: Path) -> None:
    good = _synthetic(tmp_path).read_bytes()
    truncated = tmp_path / "truncated.glb"
    truncated.write_bytes(good[: len(good) // 2])
    with pytest.raises(HeadFileError, match=r"truncated\.glb: truncated"):
        load_head_file(truncated)
    corrupt = tmp_path / "corrupt.glb"
    corrupt.write_bytes(good[:20] + b"{" * 40 + good[60:])
    with pytest.raises(HeadFileError, match=r"corrupt\.glb: not a readable glTF"):
        load_head_file(corrupt)
    with pytest.raises(HeadFileError, match=r"requires extension.*KHR_unknown_thing"):
        load_head_file(_synthetic(tmp_path, required=("KHR_unknown_thing",)))
    with pytest.raises(NoMorphTargetsError, match=r"no morph targets.*feature-point basis"), warnings.catch_warnings():
        warnings.simplefilter("ignore", HeadFileWarning)
        load_head_file(_synthetic(tmp_path, with_targets=False))
    fbx = tmp_path / "head.fbx"
    fbx.write_bytes(b"Kaydara FBX Binary")
    with pytest.raises(HeadFileError, match=r"head\.fbx: unsupported file type"):
        load_head_file(fbx)
    with pytest.raises(HeadFileError, match="no such file"):
        load_head_file(tmp_path / "missing.glb")


def test_an_obj_folder_loads(tmp_path: Path) -> None:
    folder = tmp_path / "head"
    folder.mkdir()
    faces = "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in GRID_FACES)

    def write(name: str, vertices: np.ndarray) -> None:
        (folder / name).write_text("".join(f"v {x} {y} {z}\n" for x, y, z in vertices) + faces)

    write("neutral.obj", GRID * 100)  # centimetres
    smile = GRID * 100
    smile[[2, 5, 8], 1] += 1.0
    write("Mouth_Smile_L.obj", smile)
    write("Eye_Blink_L.obj", GRID * 100)
    write("broken.obj", GRID[:4] * 100)
    with pytest.warns(HeadFileWarning, match="broken.obj has 4 vertices"):
        rig = load_head_file(folder)
    assert rig.info is not None and rig.info.format == "obj-folder" and rig.info.names.convention == "cc4"
    assert rig.info.eyes.startswith("estimated")
    assert rig.target_names == ("eyeBlinkLeft", "mouthSmileLeft")
    assert len(rig.target("eyeBlinkLeft").vertex_ids) == 0


# --- the VALID avatars ---------------------------------------------------------------------------------------


def _valid() -> list[Path]:
    return valid_avatars()


@pytest.mark.slow
def test_valid_avatars_load_in_mien_frame() -> None:
    for path in _valid():
        rig = open_head(str(path))
        assert isinstance(rig, FileRig) and rig.info is not None, path.name
        info = rig.info
        assert info.names.convention == "rocketbox" and info.eyes.startswith("eye meshes h_L_eye, h_R_eye")
        assert len(rig.targets) == 36 + 52 and rig.target_names[:3] == ("eyeBlinkLeft", "eyeSquintLeft", "eyeWideLeft")
        assert set(rig.target_names[:36]) <= set(ARKIT_NAMES)
        distance_mm = float(np.linalg.norm(rig.eye_centers[0] - rig.eye_centers[1])) * 1e3
        assert 55 < distance_mm < 70 and rig.eye_centers[0, 0] > 0 and info.unit_m == 1.0, path.name
        # Upright, facing +z: the nose tip (most forward head vertex near the midline) is below the eyes, in front.
        head = rig.neutral[rig.regions["head"]]
        near_mid = head[np.abs(head[:, 0]) < 0.01]
        nose = near_mid[np.argmax(near_mid[:, 2])]
        assert -0.08 < nose[1] < 0.0 and nose[2] > 0.01, (path.name, nose)
        # jawOpen moves the head mesh and the lower teeth together, down.
        jaw = rig.target("jawOpen")
        teeth = set(rig.regions["teeth"].tolist())
        in_teeth = np.array([i in teeth for i in jaw.vertex_ids])
        assert in_teeth.any() and (~in_teeth).any()
        assert jaw.deltas[in_teeth, 1].mean() < -0.003
        # eyeBlinkLeft moves the character's left (+x) lid.
        assert rig.neutral[rig.target("eyeBlinkLeft").vertex_ids, 0].mean() > 0.02
        assert "no mouthPressLeft: AU8, AU24 cannot show" in info.report()
        skin = next(m for m in info.materials if m.mesh_name == "H_DDS_HighRes")
        assert skin.base_color_mime == "image/webp" and skin.base_color_image and skin.uvs is not None
        assert len(skin.vertex_ids) == len(skin.uvs) and skin.vertex_ids.max() < rig.n_vertices


# --- ICT-FaceKit through Blender's glTF exporter (the ict_glb fixture is in tests/conftest.py) ----------------------


def test_ict_through_blender_matches_the_native_ict_loader(ict_glb: Path) -> None:
    from scipy.spatial import cKDTree

    from mien.rig.ict_facekit import load_ict_facekit

    rig = load_head_file(ict_glb)
    ict = load_ict_facekit()
    assert rig.info is not None and rig.info.names.convention == "ict"
    assert rig.info.unit_m == 0.01 and rig.info.eyes.startswith("eyeball-like parts")
    names = [t for t in ARKIT_NAMES if t != "tongueOut"]
    assert [t for t in rig.target_names if t in ARKIT_NAMES] == names
    assert rig.info.names.missing == ("tongueOut",)
    # Eye centres: ICT fits its sclerae, the file loader sclera and iris together: well under a millimetre apart.
    np.testing.assert_allclose(rig.eye_centers, ict.eye_centers, atol=5e-4)
    # Match vertices by position and motion (the mesh has coincident vertices that move differently).
    rng = np.random.default_rng(0)
    mix = {t: rng.standard_normal((3, 3)) for t in names}

    def features(r, gains: dict[str, float]) -> np.ndarray:
        motion = sum(r.target(t).dense(r.n_vertices).astype(np.float64) / gains.get(t, 1.0) @ mix[t] for t in names)
        return np.concatenate([r.neutral, motion], axis=1)

    _, nearest = cKDTree(rig.neutral).query(ict.neutral)
    offset = np.median(ict.neutral - rig.neutral[nearest], axis=0)
    assert np.linalg.norm(offset) < 5e-4
    ours = features(rig, {})
    ours[:, :3] += offset
    distance, index = cKDTree(ours).query(features(ict, ict.shape_gains))
    assert distance.max() < 5e-4
    np.testing.assert_allclose(rig.neutral[index] + offset, ict.neutral, atol=1e-4)  # 0.1 mm
    for name in names:
        native = ict.target(name).dense(ict.n_vertices) / ict.shape_gains.get(name, 1.0)
        np.testing.assert_allclose(rig.target(name).dense(rig.n_vertices)[index], native, atol=1e-4, err_msg=name)
