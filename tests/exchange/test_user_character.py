"""Exporting onto the user's own character: their file animated (.glb), Live Link CSV with their names, VRM 1.0."""

from __future__ import annotations

import json
import struct
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from tests.conftest import valid_avatar
from tests.exchange.test_glb import validate

from mien.exchange import arkit_csv, glb, vrm
from mien.exchange.file_shapes import file_shape_names, rig_shape_weights, shape_weights
from mien.exchange.glb_user import ANIMATION_NAME
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.clip import Clip
from mien.rig.files import load_head_file
from mien.rig.files.gltf import read_gltf
from mien.rig.heads import open_head
from mien.rig.pose import head_rotation
from mien.rig.vrm_presets import preset_arkit

pytest.importorskip("meshopt", reason="needs the heads extra: pip install 'mien[heads]'")

REQUIRED_BONES = ("hips", "spine", "head", "leftUpperArm", "leftLowerArm", "leftHand", "rightUpperArm",
                  "rightLowerArm", "rightHand", "leftUpperLeg", "leftLowerLeg", "leftFoot", "rightUpperLeg",
                  "rightLowerLeg", "rightFoot")  # fmt: skip
"""The humanoid bones VRM 1.0 requires (VRMC_vrm humanoid specification)."""


def _valid_avatar(name: str = "White_F_1_Casual.glb") -> Path:
    return valid_avatar(name)


def _document(path: Path) -> tuple[dict[str, Any], bytes]:
    return glb.split_glb(path.read_bytes(), str(path))


def _accessor(document: dict[str, Any], binary: bytes, index: int) -> np.ndarray:
    """A float accessor the writer added (plain, tightly packed)."""
    accessor = document["accessors"][index]
    view = document["bufferViews"][accessor["bufferView"]]
    width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[accessor["type"]]
    start = view.get("byteOffset", 0) + accessor.get("byteOffset", 0)
    return np.frombuffer(binary, np.float32, accessor["count"] * width, start).reshape(accessor["count"], width)


def smile_clip() -> Clip:
    """1 s at 30 fps: jaw and a symmetric smile open, the head turns 30 degrees left, the eyes 10 degrees left."""
    t = np.arange(30) / 29.0
    names = ("jawOpen", "mouthSmileLeft", "mouthSmileRight", "head_yaw_deg", "gaze_yaw_deg")
    return Clip(np.stack([0.6 * t, t, t, 30.0 * t, 10.0 * t], axis=1), 30.0, names)


@pytest.fixture(scope="module")
def avatar() -> Any:
    return open_head(str(_valid_avatar()))


@pytest.fixture(scope="module")
def animated(avatar: Any, tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("user") / "animated.glb"
    glb.write(smile_clip(), path, rig=avatar)
    return path


def test_the_users_file_is_kept_and_the_validator_finds_nothing_new(animated: Path) -> None:
    original, original_bin = _document(_valid_avatar())
    written, written_bin = _document(animated)
    for key in ("meshes", "materials", "images", "textures", "skins", "extensionsUsed", "extensionsRequired"):
        assert written[key] == original[key], key
    assert written_bin[: len(original_bin)] == original_bin  # the compressed chunk, byte for byte
    assert written["buffers"][1] == original["buffers"][1]  # the meshopt fallback buffer, without data
    assert [a["name"] for a in written["animations"]] == [ANIMATION_NAME]
    before, after = validate(_valid_avatar(), animated)
    assert after["errors"] == 0, after["messages"]
    # The avatar's own warnings (tangent space, skinned-mesh transforms) and nothing else.
    assert sorted(m["code"] for m in after["messages"]) == sorted(m["code"] for m in before["messages"])
    assert after["info"]["animationCount"] == 1


def test_the_files_shapes_at_the_written_weights_deform_it_as_the_rig(avatar: Any, animated: Path) -> None:
    document, binary = _document(animated)
    animation = document["animations"][0]
    last = {}
    for channel in animation["channels"]:
        if channel["target"]["path"] == "weights":
            values = _accessor(document, binary, animation["samplers"][channel["sampler"]]["output"])
            last[channel["target"]["node"]] = values.reshape(30, -1)[-1]
    mesh_names = {document["meshes"][document["nodes"][n]["mesh"]]["name"] for n in last}
    assert mesh_names == {"H_DDS_HighRes", "h_TeethDown"}  # same-named jaw shapes on the head and its teeth
    scene = read_gltf(animated)
    weights = np.zeros(len(avatar.targets))
    for name, value in (("jawOpen", 0.6), ("mouthSmileLeft", 1.0), ("mouthSmileRight", 1.0)):
        weights[avatar.target_index(name)] = value
    moved = sum(w * t.dense(avatar.n_vertices) for w, t in zip(weights, avatar.targets, strict=True) if w)
    compared = 0
    for primitive, part in zip(scene.primitives, avatar.info.materials, strict=True):
        if primitive.node not in last:
            continue
        names = document["meshes"][document["nodes"][primitive.node]["mesh"]]["extras"]["targetNames"]
        file_moved = sum(w * primitive.targets[n] for w, n in zip(last[primitive.node], names, strict=True) if w)
        expected = moved[part.vertex_ids]
        np.testing.assert_allclose(file_moved * avatar.info.unit_m, expected, atol=2e-6)
        compared += len(part.vertex_ids)
    assert compared > 10_000 and np.abs(moved).max() > 0.005  # the mouth moved millimetres, on both meshes


def test_the_head_bone_turns_the_head_as_mien_does(animated: Path) -> None:
    document, binary = _document(animated)
    animation = document["animations"][0]
    rotations = {document["nodes"][c["target"]["node"]]["name"]: c for c in animation["channels"]
                 if c["target"]["path"] == "rotation"}  # fmt: skip
    assert sorted(rotations) == ["Head", "LeftEye", "RightEye"]
    scene = read_gltf(_valid_avatar())
    head = next(i for i, node in enumerate(document["nodes"]) if node.get("name") == "Head")
    quaternion = _accessor(document, binary, animation["samplers"][rotations["Head"]["sampler"]]["output"])[-1]
    x, y, z, w = (float(v) for v in quaternion)
    local = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                      [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                      [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])  # fmt: skip
    parent = scene.nodes[scene.nodes[head].parent].world[:3, :3]
    rest = scene.nodes[head].world[:3, :3]
    scale = np.linalg.norm(parent, axis=0)
    turned = (parent / scale) @ local * np.linalg.norm(rest, axis=0)  # the head's world frame at the last key
    np.testing.assert_allclose(turned @ np.linalg.inv(rest), head_rotation(30.0, 0.0, 0.0), atol=1e-4)


def test_live_link_csv_with_the_files_own_names(avatar: Any, tmp_path: Path) -> None:
    path = arkit_csv.write(smile_clip(), tmp_path / "own.csv", rig=avatar, names="file")
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    columns = file_shape_names(avatar.info.source_names)
    assert header[2 : 2 + len(columns)] == list(columns) and header[2 + len(columns) :] == list(
        arkit_csv.ROTATION_COLUMNS
    )
    assert "h_expressions.MouthOpen_h" in columns and "h_teeth.t_MouthOpen_h" in columns
    last = np.array([float(v) for v in lines[-1].split(",")[2:]])
    assert int(lines[-1].split(",")[1]) == len(header) - 2
    weights = np.zeros((1, len(avatar.targets)), np.float32)
    for name, value in (("jawOpen", 0.6), ("mouthSmileLeft", 1.0), ("mouthSmileRight", 1.0)):
        weights[0, avatar.target_index(name)] = value
    expected = rig_shape_weights(weights, avatar)
    for j, name in enumerate(columns):
        assert last[j] == pytest.approx(float(expected[name][0]), abs=1e-6), name
    assert last[len(columns)] == pytest.approx(np.radians(30.0), abs=1e-9)  # HeadYaw, radians
    with pytest.raises(Exception, match="character file"):
        arkit_csv.write(smile_clip(), tmp_path / "x.csv", rig=open_head("builtin"), names="file")


def test_a_shape_split_in_halves_gets_the_mean_of_its_halves() -> None:
    rows = {"eyeBlinkLeft": (("blink", 1.0, "L"),), "eyeBlinkRight": (("blink", 1.0, "R"),),
            "jawOpen": (("Jaw", 0.5, ""), ("TeethJaw", 1.0, ""))}  # fmt: skip
    weights = np.array([[1.0, 0.0, 0.8], [0.4, 0.4, 0.0]], np.float32)
    shapes = shape_weights(weights, ("eyeBlinkLeft", "eyeBlinkRight", "jawOpen"), rows)
    np.testing.assert_allclose(shapes["blink"], [0.5, 0.4])
    np.testing.assert_allclose(shapes["Jaw"], [0.4, 0.0])
    np.testing.assert_allclose(shapes["TeethJaw"], [0.8, 0.0])


# --- a .gltf beside its .bin and texture ----------------------------------------------------------------------


def _gltf_folder(tmp_path: Path) -> Path:
    """A .gltf with an external .bin and PNG, a face mesh with two named shapes under a node named Head."""
    positions = np.array([[x, y, 0.0] for y in (-0.03, 0.0, 0.03) for x in (-0.045, 0.0, 0.045)], np.float32)
    faces = np.array([[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4], [3, 4, 7], [3, 7, 6], [4, 5, 8], [4, 8, 7]])
    jaw = np.zeros_like(positions)
    jaw[:3, 1] = -0.01
    smile = np.zeros_like(positions)
    smile[[3, 5], 1] = 0.004
    uv = (positions[:, :2] / 0.1 + 0.5).astype(np.float32)
    blobs = [positions.tobytes(), faces.astype(np.uint16).tobytes(), jaw.tobytes(), smile.tobytes(),
             uv.tobytes()]  # fmt: skip
    views, offset = [], 0
    for blob in blobs:
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(blob)})
        offset += len(blob)
    (tmp_path / "face.bin").write_bytes(b"".join(blobs))
    (tmp_path / "skin.png").write_bytes(glb._png(np.full((4, 4, 4), 200, np.uint8)))

    def vec3(view: int, array: np.ndarray) -> dict[str, Any]:
        return {"bufferView": view, "componentType": 5126, "count": 9, "type": "VEC3",
                "min": [float(v) for v in array.min(0)], "max": [float(v) for v in array.max(0)]}  # fmt: skip

    document = {
        "asset": {"version": "2.0", "generator": "hand"},
        "buffers": [{"uri": "face.bin", "byteLength": offset}],
        "bufferViews": views,
        "accessors": [vec3(0, positions), {"bufferView": 1, "componentType": 5123, "count": 24, "type": "SCALAR"},
                      vec3(2, jaw), vec3(3, smile),
                      {"bufferView": 4, "componentType": 5126, "count": 9, "type": "VEC2"}],
        "images": [{"uri": "skin.png"}],
        "textures": [{"source": 0}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "meshes": [{"name": "face", "primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 4}, "indices": 1,
                    "material": 0, "targets": [{"POSITION": 2}, {"POSITION": 3}]}],
                    "weights": [0.0, 0.0], "extras": {"targetNames": ["MouthOpen", "Smile"]}}],
        "nodes": [{"name": "Head", "translation": [0.0, 1.6, 0.0], "children": [1, 2, 3]},
                  {"name": "face", "mesh": 0},
                  {"name": "Eye_L", "translation": [0.032, 0.01, -0.01]},
                  {"name": "Eye_R", "translation": [-0.032, 0.01, -0.01]}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    }  # fmt: skip
    path = tmp_path / "face.gltf"
    path.write_text(json.dumps(document))
    return path


def test_a_gltf_with_external_files_becomes_one_standalone_glb(tmp_path: Path) -> None:
    (tmp_path / "in").mkdir()
    source = _gltf_folder(tmp_path / "in")
    overrides = tmp_path / "names.toml"
    overrides.write_text('[targets]\n"MouthOpen" = "jawOpen"\n"Smile" = [{arkit = "mouthSmileLeft", side = "L"}, '
                         '{arkit = "mouthSmileRight", side = "R"}]\n')  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rig = load_head_file(source, overrides=overrides)
    clip = Clip(np.array([[0.0, 0.0, 0.0, 0.0], [0.5, 1.0, 0.2, 10.0]]), 10.0,
                ("jawOpen", "mouthSmileLeft", "mouthSmileRight", "head_pitch_deg"))  # fmt: skip
    out = tmp_path / "out" / "face.glb"
    out.parent.mkdir()
    glb.write(clip, out, rig=rig)
    (report,) = validate(out)
    assert (report["errors"], report["warnings"]) == (0, 0), report["messages"]
    document, binary = _document(out)
    assert [b.get("uri") for b in document["buffers"]] == [None]
    image = document["images"][0]
    assert "uri" not in image and image["mimeType"] == "image/png"
    view = document["bufferViews"][image["bufferView"]]
    png = binary[view["byteOffset"] : view["byteOffset"] + view["byteLength"]]
    assert png == (tmp_path / "in" / "skin.png").read_bytes()
    animation = document["animations"][0]
    by_path = {c["target"]["path"]: c for c in animation["channels"]}
    assert set(by_path) == {"weights", "rotation"}  # eyes are not turned: the clip has no gaze
    weights = _accessor(document, binary, animation["samplers"][by_path["weights"]["sampler"]]["output"])
    np.testing.assert_allclose(weights.reshape(2, 2)[1], [0.5, 0.6], atol=1e-6)  # smile: mean of its halves
    assert document["nodes"][by_path["rotation"]["target"]["node"]]["name"] == "Head"
    assert struct.unpack_from("<I", out.read_bytes(), 8)[0] == out.stat().st_size


# --- VRM 1.0 from ICT's shapes --------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def ict_vrm(ict_dir: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("vrm") / "ict.vrm"
    vrm.write(smile_clip(), path, rig=open_head("ict"))
    return path


def test_the_vrm_passes_the_validator_and_holds_a_vrm_1_0_avatar(ict_vrm: Path) -> None:
    (report,) = validate(ict_vrm)
    assert (report["errors"], report["warnings"]) == (0, 0), report["messages"]
    document, _ = _document(ict_vrm)
    extension = document["extensions"]["VRMC_vrm"]
    assert extension["specVersion"] == "1.0" and "VRMC_vrm" in document["extensionsUsed"]
    meta = extension["meta"]
    assert meta["authors"] and meta["licenseUrl"] == "https://vrm.dev/licenses/1.0/"
    assert "MIT" in meta["copyrightInformation"] and "ICT-FaceKit" in meta["otherLicenseUrl"]
    bones = extension["humanoid"]["humanBones"]
    assert set(REQUIRED_BONES) <= set(bones)
    nodes = document["nodes"]
    assert document["scenes"][0]["nodes"] == [bones["hips"]["node"]]
    assert 1 in nodes[bones["head"]["node"]]["children"]  # the face mesh hangs from the head bone
    presets = extension["expressions"]["preset"]
    assert set(presets) == set(vrm.EXPRESSION_PRESETS) and len(presets) == 18
    rig = open_head("ict")
    happy = {rig.target_names[b["index"]]: b["weight"] for b in presets["happy"]["morphTargetBinds"]}
    assert happy["mouthSmileLeft"] == pytest.approx(happy["mouthSmileRight"]) and happy["mouthSmileLeft"] > 0.5
    assert "browDownLeft" not in happy and presets["neutral"]["morphTargetBinds"] == []
    angry = {rig.target_names[b["index"]] for b in presets["angry"]["morphTargetBinds"]}
    assert {"browDownLeft", "browDownRight"} <= angry
    custom = extension["expressions"]["custom"]
    assert set(custom) == {name for name in rig.target_names if name in ARKIT_NAMES}
    assert custom["jawOpen"]["morphTargetBinds"] == [{"node": 1, "index": rig.target_index("jawOpen"), "weight": 1.0}]


def test_the_vrm_reads_back_with_its_expressions_as_targets(ict_vrm: Path, landmarker_path: Path) -> None:
    from mien.heads import load_head

    rig = load_head(str(ict_vrm))
    assert rig.info.format == "vrm1"
    ict = open_head("ict")
    assert {"happy", "sad", "blinkLeft", "aa"} <= set(rig.target_names)
    assert set(ict.target_names) <= set(rig.target_names)
    # happy on the read head is the bound targets' weighted sum, as the file says (the reader welds seam
    # vertices, so compare where and how far the face moves most; both frames have the origin between the eyes)
    weights = vrm.expression_weights(ict)["happy"]
    expected = sum(w * t.dense(ict.n_vertices) for w, t in zip(weights, ict.targets, strict=True) if w >= 0.01)
    got = rig.target("happy").dense(rig.n_vertices)
    most, most_expected = np.linalg.norm(got, axis=1), np.linalg.norm(expected, axis=1)
    assert most.max() == pytest.approx(most_expected.max(), rel=1e-3) and most.max() > 0.003
    where = rig.neutral[np.argmax(most)]
    assert np.linalg.norm(where - ict.neutral[np.argmax(most_expected)]) < 1e-3
    # with the VRM 1.0 convention forced, the rig is driven through its emotion presets (the smile is mostly happy)
    forced = load_head_file(ict_vrm, convention="vrm1")
    assert forced.info.names.convention == "vrm1"
    assert forced.info.names.presets == ("happy", "angry", "sad", "surprised")
    smile = {shape: weight for shape, weight, _side in forced.info.source_names["mouthSmileLeft"]}
    assert max(smile, key=lambda shape: abs(smile[shape])) == "happy" and smile["happy"] > 0


def test_a_vrm_read_with_its_presets_drives_them_back_in_the_file(ict_vrm: Path, tmp_path: Path) -> None:
    rig = load_head_file(ict_vrm, convention="vrm1")
    face = preset_arkit("happy")  # happy's own ARKit face (its jaw left out: the aa viseme drives jawOpen)
    names = tuple(name for name, value in zip(ARKIT_NAMES, face, strict=True) if value > 0 and name != "jawOpen")
    values = np.stack([np.zeros(len(names)), [face[ARKIT_NAMES.index(name)] for name in names]])
    out = glb.write(Clip(values, 10.0, names), tmp_path / "again.vrm", rig=rig)
    document, binary = _document(out)
    assert "VRMC_vrm" in document["extensions"]
    (channel,) = document["animations"][-1]["channels"]
    sampler = document["animations"][-1]["samplers"][channel["sampler"]]
    weights = _accessor(document, binary, sampler["output"]).reshape(2, -1)[1]
    binds = document["extensions"]["VRMC_vrm"]["expressions"]["preset"]["happy"]["morphTargetBinds"]
    expected = np.zeros_like(weights)
    for bind in binds:
        expected[bind["index"]] = bind["weight"]  # happy at 1, the other presets at 0
    np.testing.assert_allclose(weights, expected, atol=2e-3)
