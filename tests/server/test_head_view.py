"""How a viewer shows a head: mien's glTF of a named head, the user's own file for a head file, and the rig ->
file weight matrix the frames go through."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from tests.conftest import valid_avatar

from mien.rig.heads import open_head
from mien.rig.model import MorphTarget
from mien.server.head_view import _weight_matrix, frame_weights, head_view, referenced_files


def _valid_avatar() -> Path:
    return valid_avatar("Asian_F_1_Casual.glb")


def test_a_named_head_is_shown_as_mien_glb_with_the_rig_weights() -> None:
    rig = open_head("builtin")
    view = head_view(rig)
    assert view.frame_names == tuple(rig.target_names)
    assert view.matrix is None and view.source is None and view.file_to_rig is None and view.note == ""
    weights = np.linspace(0.0, 1.0, len(rig.target_names), dtype=np.float32)
    assert frame_weights(view, weights) is weights


def test_rows_sum_per_file_shape_halve_a_side_and_expand_vrm_expressions() -> None:
    names = ("browInnerUp", "browOuterUpLeft", "eyeBlinkLeft", "eyeBlinkRight", "mouthSmileLeft")
    source_names = {
        "browInnerUp": (("BrowsUp", 1.0, ""),),
        "browOuterUpLeft": (("BrowsUp", 0.5, ""), ("BrowOuterL", 1.0, "")),  # one file shape, two rig targets
        "eyeBlinkLeft": (("Blink", 1.0, "L"),),  # a both-sided file shape split at the midline
        "eyeBlinkRight": (("Blink", 1.0, "R"),),
        "mouthSmileLeft": (("happy", 1.0, ""),),  # a VRM expression
    }
    expansions = {"happy": [("Fcl_MTH_Joy", 0.8), ("Fcl_EYE_Joy", 1.0)]}
    frame_names, matrix = _weight_matrix(names, source_names, expansions)
    assert frame_names == ("BrowsUp", "BrowOuterL", "Blink", "Fcl_MTH_Joy", "Fcl_EYE_Joy")
    expected = np.array(
        [[1.0, 0.5, 0, 0, 0], [0, 1.0, 0, 0, 0], [0, 0, 0.5, 0.5, 0], [0, 0, 0, 0, 0.8], [0, 0, 0, 0, 1.0]], np.float32
    )
    np.testing.assert_array_equal(matrix, expected)


def test_file_weights_are_the_rows_applied_to_the_rig_weights_and_clipped(tmp_path: Path) -> None:
    from mien.rig.files.head import load_head_file

    rig = load_head_file(_valid_avatar())
    view = head_view(rig)
    assert view.source == Path(rig.info.path) and view.media_type == "model/gltf-binary"  # type: ignore[union-attr]
    assert len(view.frame_names) == 96  # the file's 65 head and 31 teeth shapes, each once
    assert len(set(view.frame_names)) == 96
    assert view.matrix is not None and view.matrix.shape == (96, len(rig.target_names))
    names = list(rig.target_names)
    weights = np.zeros(len(names), np.float32)
    weights[names.index("jawOpen")] = 0.25
    weights[names.index("browInnerUp")] = 0.4
    weights[names.index("h_expressions.Shout_h")] = 0.7  # a shape kept under its own name drives itself
    out = dict(zip(view.frame_names, frame_weights(view, weights).tolist(), strict=True))
    (head_row,) = [row for row in rig.info.source_names["jawOpen"] if row[0] == "h_expressions.MouthOpen_h"]
    jaw = min(1.0, 0.25 * head_row[1])
    assert out["h_expressions.MouthOpen_h"] == pytest.approx(jaw) and out["t_MouthOpen_h"] == pytest.approx(jaw)
    assert out["h_expressions.LbrowUp_h"] == pytest.approx(0.4) and out["h_expressions.RbrowUp_h"] == pytest.approx(0.4)
    assert out["h_expressions.Shout_h"] == pytest.approx(0.7)
    assert sum(1 for value in out.values() if value > 0) == 5
    weights[names.index("jawOpen")] = 1.0
    assert frame_weights(view, weights).max() == 1.0  # a row weight above 1 saturates the file's shape


def test_a_file_head_is_placed_in_mien_frame_by_a_fitted_similarity() -> None:
    from mien.rig.files.gltf import read_gltf
    from mien.rig.files.head import load_head_file

    rig = load_head_file(_valid_avatar())
    view = head_view(rig)
    assert view.file_to_rig is not None and view.fit_rms_m < 1e-6
    linear = view.file_to_rig[:3, :3]
    np.testing.assert_allclose(linear @ linear.T, np.eye(3), atol=1e-6)  # metres already: a rotation, scale 1
    assert view.file_to_rig[1, 3] < -1.4  # the head of a standing body is lifted down to the eyes' height
    primitive, material = read_gltf(rig.info.path).primitives[0], rig.info.materials[0]  # type: ignore[union-attr]
    placed = primitive.positions @ linear.T + view.file_to_rig[:3, 3]
    np.testing.assert_allclose(placed, rig.neutral[material.vertex_ids], atol=1e-5)


def test_a_file_head_with_targets_its_file_lacks_is_shown_as_mien_glb() -> None:
    from mien.rig.files.head import load_head_file

    rig = load_head_file(_valid_avatar())
    extra = MorphTarget("fp_MouthCornerL_x", np.array([0], np.int32), np.array([[0.001, 0, 0]], np.float32))
    view = head_view(rig.with_targets((extra,)))
    assert view.source is None and view.matrix is None
    assert view.frame_names[-1] == "fp_MouthCornerL_x"
    assert "mien's glTF" in view.note and "fp_MouthCornerL_x" in view.note


def test_a_gltf_points_only_at_files_inside_its_folder(tmp_path: Path) -> None:
    folder = tmp_path / "head"
    (folder / "textures").mkdir(parents=True)
    for name in ("mesh data.bin", "textures/skin.webp"):
        (folder / name).write_bytes(b"x")
    (tmp_path / "secret.bin").write_bytes(b"x")
    data = {"uri": "data:application/octet-stream;base64,AA=="}
    buffers = [{"uri": "mesh%20data.bin"}, {"uri": "../secret.bin"}, data]
    images = [{"uri": "textures/skin.webp"}, {"uri": "missing.png"}, {"uri": "file:///etc/passwd"}, {"bufferView": 0}]
    document = {"buffers": buffers, "images": images}
    (folder / "face.gltf").write_text(json.dumps(document))
    found = referenced_files(folder / "face.gltf")
    assert found == {"mesh data.bin": folder / "mesh data.bin", "textures/skin.webp": folder / "textures" / "skin.webp"}


@pytest.mark.filterwarnings("ignore:AU mapping .* lacks targets:UserWarning")  # a VALID head has no mouthClose
def test_a_server_serves_the_users_file_and_streams_its_shape_weights_by_name(landmarker_path: Path) -> None:
    httpx = pytest.importorskip("httpx")
    pytest.importorskip("mediapipe", reason="instrumenting a head file needs the track extra")
    pytest.importorskip("moderngl", reason="instrumenting a head file needs the render extra")
    from tests.server.conftest import make_server

    from mien.client import UdpClient, WebSocketClient
    from mien.server.registry import CharacterSpec

    path = _valid_avatar()
    characters = (CharacterSpec("me", head="file", identity=str(path), idle=False), CharacterSpec("b", "builtin"))
    with make_server(characters=characters) as server:
        info = {c["id"]: c for c in httpx.get(f"{server.base_url}/api/characters").json()}
        me = info["me"]
        assert me["head_file"] == path.name and me["head_url"] == "/api/characters/me/head.glb"
        assert len(me["target_names"]) == 96 and me["frame_bytes"] == 44 + 2 * 96
        assert "h_expressions.MouthOpen_h" in me["target_names"] and "t_MouthOpen_h" in me["target_names"]
        assert len(me["file_to_rig"]) == 16 and "7 shapes mien synthesized" in me["head_note"]  # shown as its file
        builtin = info["b"]
        assert builtin["head_file"] is None and builtin["file_to_rig"] is None and len(builtin["target_names"]) == 52
        head = httpx.get(f"{server.base_url}{me['head_url']}")
        assert head.headers["content-type"] == "model/gltf-binary" and head.content == path.read_bytes()
        assert httpx.get(f"{server.base_url}/api/characters/me/head/face.gltf").status_code == 404
        mouth = me["target_names"].index("h_expressions.MouthOpen_h"), me["target_names"].index("t_MouthOpen_h")
        with WebSocketClient(f"ws://127.0.0.1:{server.http_port}/ws?character=me") as viewer:
            assert viewer.recv_frame().weights.shape == (96,)
            with UdpClient("127.0.0.1", server.udp_port) as udp:
                udp.send({"AU26": 5}, speed=1.0, character="me")  # jaw drop: jawOpen on the head AND the teeth
                frames = [viewer.recv_frame() for _ in range(30)]
        last = frames[-1].weights
        assert last[mouth[0]] > 0.5 and last[mouth[1]] == last[mouth[0]]
        state = httpx.get(f"{server.base_url}/api/characters/me").json()
        assert state["weights"]["jawOpen"] > 0.2  # the state endpoint keeps the rig's own (ARKit) names
