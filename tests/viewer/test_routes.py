"""The viewer's routes on a bare FastAPI app: the page, its control lists, three.js from node_modules."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import pytest

pytest.importorskip("fastapi", reason="the serve extra is not installed")

from fastapi import FastAPI
from fastapi.testclient import TestClient

from mien.affect.emotions import BLENDS, EMOTIONS
from mien.facs.catalogue import ACTION_UNITS
from mien.laughter.names import LAUGH_TYPES
from mien.viewer.controls import viewer_controls
from mien.viewer.routes import mount
from mien.viewer.vendor import three_dir


def _client() -> TestClient:
    app = FastAPI()
    mount(app)
    return TestClient(app)


@pytest.fixture()
def client() -> TestClient:
    if three_dir() is None:
        pytest.skip("node_modules/three missing: run `npm ci`")
    return _client()


def test_controls_come_from_the_catalogues() -> None:
    controls = viewer_controls()
    face_aus = [f"AU{code}" for code, au in ACTION_UNITS.items() if au.kind == "face"]
    assert [au["label"] for au in controls["aus"]] == face_aus
    assert {au["code"] for au in controls["aus"] if au["openfacs"]} >= {1, 2, 4, 6, 12, 45}
    assert controls["emotions"] == list(EMOTIONS)
    assert controls["blends"] == list(BLENDS)
    assert [t["type"] for t in controls["laughter"]] == list(LAUGH_TYPES)
    assert controls["intensity_letters"] == ["A", "B", "C", "D", "E"]
    assert [c["name"] for c in controls["cameras"]] == ["frontal-1m", "lateral-1m", "frontal-3m", "lateral-3m"]
    lateral = controls["cameras"][1]
    assert lateral["position_m"][0] == pytest.approx(1.0)  # seen from the character's left (+x)
    assert sorted(flag for toggle in controls["idle"] for flag in toggle["flags"]) == sorted(
        ["blink", "mouth", "eyelids", "neck", "wobble", "gaze"]
    )


def test_page_import_map_and_three(client: TestClient) -> None:
    page = client.get("/")
    assert page.status_code == 200
    assert page.headers["content-type"].startswith("text/html")
    imports = json.loads(page.text.split('<script type="importmap">')[1].split("</script>")[0])["imports"]
    assert imports == {
        "three": "/vendor/three/build/three.module.js",
        "three/addons/": "/vendor/three/examples/jsm/",
    }
    assert "http://" not in page.text and "https://" not in page.text  # nothing from the internet
    for path in (
        imports["three"],
        imports["three/addons/"] + "loaders/GLTFLoader.js",
        "/viewer/viewer.js",
        "/viewer/frame.js",
        "/viewer/pose.js",
    ):
        response = client.get(path)
        assert response.status_code == 200, path
        assert "javascript" in response.headers["content-type"]
    assert client.get("/viewer/viewer.css").status_code == 200
    served = client.get("/viewer/controls.json").json()
    assert served == json.loads(json.dumps(viewer_controls()))
    assert client.get("/vendor/three/..%2F..%2Fpackage.json").status_code == 404  # no way out of three/
    assert client.get("/viewer/..%2Froutes.py").status_code == 404
    assert client.get("/viewer/nothing.js").status_code == 404


def test_missing_three_answers_503_naming_npm_ci(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    monkeypatch.setenv("MIEN_NODE_MODULES", str(tmp_path))
    with caplog.at_level(logging.WARNING, logger="mien.viewer.routes"):
        client = _client()
    assert any("npm ci" in record.getMessage() for record in caplog.records)
    page = client.get("/")
    assert page.status_code == 503
    assert "npm ci" in page.text and str(tmp_path) in page.text
    vendor = client.get("/vendor/three/build/three.module.js")
    assert vendor.status_code == 503 and "npm ci" in vendor.json()["detail"]
    assert client.get("/viewer/controls.json").status_code == 200
