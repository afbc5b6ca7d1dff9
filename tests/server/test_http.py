"""The HTTP API against its own OpenAPI description (validated), and the access token."""

from __future__ import annotations

import io
from typing import Any

import httpx
import jsonschema
import numpy as np
import pytest
from openapi_spec_validator import validate
from tests.server.conftest import assert_unharmed

from mien.server.app import LiveServer, ServeConfig


def _schema(doc: dict[str, Any], path: str, method: str, code: int) -> dict[str, Any]:
    response = doc["paths"][path][method]["responses"][str(code)]
    return {**response["content"]["application/json"]["schema"], "components": doc["components"]}


def _check(doc: dict[str, Any], path: str, method: str, response: httpx.Response, code: int) -> Any:
    assert response.status_code == code, response.text
    body = response.json()
    jsonschema.Draft202012Validator(_schema(doc, path, method, code)).validate(body)
    return body


def test_openapi_document_is_valid_and_responses_match_it(live, wait_until) -> None:
    base = live.base_url
    doc = httpx.get(f"{base}/openapi.json").json()
    validate(doc)
    for path in (
        "/api/health",
        "/api/characters",
        "/api/characters/{character_id}",
        "/api/characters/{character_id}/pad",
    ):
        assert path in doc["paths"]
    c = "/api/characters/{character_id}"
    health = _check(doc, "/api/health", "get", httpx.get(f"{base}/api/health"), 200)
    assert health["characters"] == 2 and health["tick_hz"] == 60.0
    listed = _check(doc, "/api/characters", "get", httpx.get(f"{base}/api/characters"), 200)
    assert [item["id"] for item in listed] == ["a", "b"] and listed[0]["frame_bytes"] == 44 + 2 * 52
    created = _check(
        doc, "/api/characters", "post",
        httpx.post(f"{base}/api/characters", json={"id": "c", "head": "builtin", "seed": 3, "idle": True}), 201,
    )  # fmt: skip
    assert created["row"] == 2 and created["idle"] is True
    _check(
        doc, f"{c}/aus", "post", httpx.post(f"{base}/api/characters/c/aus", json={"aus": {"AU4": 4}, "speed": 1}), 202
    )
    _check(
        doc, f"{c}/emotion", "post", httpx.post(f"{base}/api/characters/a/emotion", json={"emotion": "surprise"}), 202
    )
    wait_until(lambda: httpx.get(f"{base}/api/characters/a").json()["aus"]["AU2L"] > 0.5, what="surprise on a")
    _check(
        doc, f"{c}/laughter", "post", httpx.post(f"{base}/api/characters/b/laughter", json={"type": "laughter"}), 202
    )
    state = wait_until(
        lambda: (s := httpx.get(f"{base}/api/characters/c")).json()["aus"]["AU4L"] == 4.0 and s, what="AU4 on c"
    )
    body = _check(doc, c, "get", state, 200)
    assert set(body["pose_deg"]) == {
        "head_yaw_deg",
        "head_pitch_deg",
        "head_roll_deg",
        "gaze_yaw_deg",
        "gaze_pitch_deg",
    }
    assert body["weights"]["browDownLeft"] > 0.5
    assert httpx.delete(f"{base}/api/characters/c").status_code == 204
    assert httpx.get(f"{base}/api/characters/c").status_code == 404
    health = _check(doc, "/api/health", "get", httpx.get(f"{base}/api/health"), 200)
    assert health["http_commands"] == 3 and health["characters"] == 2


@pytest.mark.parametrize(
    ("method", "path", "body", "code", "words"),
    [
        ("post", "/api/characters/zz/emotion", {"emotion": "joy"}, 404, "unknown character 'zz'"),
        ("post", "/api/characters/a/emotion", {"emotion": "bliss"}, 400, "bliss"),
        ("post", "/api/characters/a/emotion", {"emotion": "joy", "intensity": 9}, 400, "intensity=9"),
        ("post", "/api/characters/a/aus", {"aus": {"AU99": 1}}, 400, "AU99"),
        ("post", "/api/characters/a/pad", {"pleasure": 3, "arousal": 0, "dominance": 0}, 400, "pad[0]=3"),
        ("post", "/api/characters/a/laughter", {"type": "guffaw"}, 400, "guffaw"),
        ("post", "/api/characters", {"id": "a", "head": "builtin"}, 400, "'a'"),
        ("post", "/api/characters", {"id": "x", "head": "marble"}, 400, "marble"),
        ("post", "/api/characters", {"id": "bad id"}, 422, "id"),
        ("delete", "/api/characters/nobody", None, 404, "nobody"),
    ],
)
def test_bad_requests_get_clear_errors(live, method, path, body, code, words) -> None:
    response = httpx.request(method, f"{live.base_url}{path}", json=body)
    assert response.status_code == code
    assert words in response.text
    assert_unharmed(live)  # still serving, no tick lost


def test_clip_upload_plays_on_the_character(live, wait_until) -> None:
    from mien.exchange.clip_json import write
    from mien.facs.clip import Clip

    values = np.zeros((30, 1))
    values[:, 0] = 4.0
    clip = Clip(values, 30.0, ("AU12L",))
    buffer = io.BytesIO()
    write(clip, buffer)
    data = buffer.getvalue()
    url = f"{live.base_url}/api/characters/b/clip"
    binary = {"content-type": "application/octet-stream"}  # the upload's one content type (docs/SERVER.md)
    reply = httpx.post(url, params={"suffix": ".json"}, content=data, headers=binary, timeout=30.0)  # a worker reads it
    assert reply.status_code == 202
    wait_until(lambda: httpx.get(f"{live.base_url}/api/characters/b").json()["aus"]["AU12L"] > 3.9, what="clip")
    bad = httpx.post(url, params={"suffix": ".json"}, content=b"\x00\x01 not a clip", headers=binary, timeout=30.0)
    assert bad.status_code == 400 and "clip" in bad.text
    assert httpx.post(url, params={"suffix": ".exe"}, content=data, headers=binary).status_code == 400


def test_head_glb_route_matches_the_frame_weight_order(live) -> None:
    import json
    import struct

    response = httpx.get(f"{live.base_url}/api/characters/a/head.glb")
    assert response.status_code == 200 and response.headers["content-type"] == "model/gltf-binary"
    data = response.content
    magic, version, length = struct.unpack_from("<4sII", data)
    assert magic == b"glTF" and version == 2 and length == len(data)
    chunk_length, chunk_type = struct.unpack_from("<I4s", data, 12)
    assert chunk_type == b"JSON"
    gltf = json.loads(data[20 : 20 + chunk_length])
    names = [mesh.get("extras", {}).get("targetNames") for mesh in gltf["meshes"]]
    info = httpx.get(f"{live.base_url}/api/characters").json()[0]
    assert info["target_names"] in names  # the frame's weights are in the glb's targetNames order


def test_access_token(server_factory) -> None:
    with server_factory(token="s3cret-token") as live:
        base = live.base_url
        assert httpx.get(f"{base}/api/health").status_code == 401
        assert httpx.get(f"{base}/api/health", headers={"Authorization": "Bearer wrong-token"}).status_code == 401
        assert httpx.get(f"{base}/api/health", headers={"Authorization": "Bearer s3cret-token"}).status_code == 200
        assert httpx.get(f"{base}/api/characters", params={"token": "s3cret-token"}).status_code == 200
        from mien.client import WebSocketClient
        from mien.errors import MienError

        with pytest.raises(MienError, match="token"):
            WebSocketClient(f"ws://127.0.0.1:{live.http_port}/ws")
        with WebSocketClient(f"ws://127.0.0.1:{live.http_port}/ws", token="s3cret-token") as client:
            assert client.recv_frame().weights.shape == (52,)


def test_a_token_is_generated_beyond_loopback() -> None:
    server = LiveServer(ServeConfig(host="0.0.0.0", udp_port=0, http_port=0))
    assert server.token is not None and len(server.token) >= 16
    assert LiveServer(ServeConfig(host="127.0.0.1")).token is None


def test_pad_and_feature_point_characters(live, wait_until) -> None:
    base = live.base_url
    assert (
        httpx.post(f"{base}/api/characters/a/pad", json={"pleasure": 0.8, "arousal": 0.5, "dominance": 0.2}).status_code
        == 202
    )
    wait_until(lambda: httpx.get(f"{base}/api/characters/a").json()["aus"]["AU12L"] > 0.5, what="PAD joy on a")
    body = {"id": "fp", "head": "builtin", "idle": False, "expression_basis": "feature_points"}
    created = httpx.post(f"{base}/api/characters", json=body).json()
    assert any(name.startswith("fp_") for name in created["target_names"])
    assert httpx.post(f"{base}/api/characters/fp/emotion", json={"emotion": "joy", "intensity": 2}).status_code == 202
    state = wait_until(
        lambda: (
            (s := httpx.get(f"{base}/api/characters/fp").json())
            and max(abs(v) for k, v in s["weights"].items() if k.startswith("fp_")) > 1e-4
            and s
        ),
        what="feature-point targets moving",
    )
    assert state["aus"]["AU12L"] == 0.0  # the feature-point basis leaves the AU channels alone
    assert httpx.get(f"{base}/api/characters/b").json()["aus"]["AU12L"] == 0.0


def test_idle_switches(live, wait_until) -> None:
    base = live.base_url
    info = lambda: {c["id"]: c for c in httpx.get(f"{base}/api/characters").json()}  # noqa: E731
    assert info()["a"]["idle"] is False
    assert httpx.post(f"{base}/api/characters/a/idle", json={"blink": True}).status_code == 202
    parts = wait_until(lambda: info()["a"]["idle"] and info()["a"]["idle_parts"], what="blink on")
    assert parts["blink"] is True and parts["gaze"] is False
    # a blink closes the eyes within the first blink interval (Normal(6 s, 2 s) is long; the server time moves on)
    assert httpx.post(f"{base}/api/characters/a/idle", json={"on": True}).status_code == 202
    wait_until(lambda: all(info()["a"]["idle_parts"].values()), what="all idle on")
    wait_until(
        lambda: (
            abs(httpx.get(f"{base}/api/characters/a").json()["pose_deg"]["gaze_yaw_deg"]) > 0.01
            or httpx.get(f"{base}/api/characters/a").json()["aus"]["AU12L"] > 0.0
        ),
        timeout_s=5.0,
        what="idle motion",
    )
    assert httpx.post(f"{base}/api/characters/a/idle", json={"on": False}).status_code == 202
    wait_until(lambda: info()["a"]["idle"] is False, what="idle off")
    assert info()["b"]["idle"] is False


def test_no_page_that_downloads_from_a_cdn(live) -> None:
    for path in ("/docs", "/redoc"):
        response = httpx.get(f"{live.base_url}{path}")
        assert response.status_code == 404 or "cdn" not in response.text.lower()
