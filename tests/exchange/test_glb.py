"""glTF binary: the Khronos validator on written files, round trips, the head alone, bad input."""

from __future__ import annotations

import io
import json
import shutil
import struct
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mien.errors import InvalidValueError
from mien.exchange import glb
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.catalogue import FACE_CHANNELS
from mien.facs.clip import Clip
from mien.rig.builtin_head import builtin_head

REPO = Path(__file__).resolve().parents[2]
VALIDATOR_SCRIPT = Path(__file__).parent / "validate_gltf.mjs"


def validate(*paths: Path) -> list[dict[str, Any]]:
    """Khronos gltf-validator reports (npm package in node_modules), one per file."""
    node = shutil.which("node")
    if node is None or not (REPO / "node_modules" / "gltf-validator").is_dir():
        pytest.skip("node and node_modules/gltf-validator needed: run scripts/install (npm ci)")
    result = subprocess.run(
        [node, str(VALIDATOR_SCRIPT), *map(str, paths)], cwd=REPO, capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
    return [json.loads(line) for line in result.stdout.splitlines()]


def weight_clip(n_frames: int = 30, fps: float = 30.0) -> Clip:
    """ARKit weights 0..1 (smile and blink) with a head turn."""
    t = np.arange(n_frames) / fps
    names = ("mouthSmileLeft", "mouthSmileRight", "eyeBlinkLeft", "jawOpen", "head_yaw_deg", "head_pitch_deg")
    smile = 0.5 - 0.5 * np.cos(2 * np.pi * t)
    values = np.stack([smile, smile, np.abs(np.sin(3 * t)), 0.3 * smile, 20 * np.sin(t), -10 * smile], axis=1)
    return Clip(values, fps, names)


@pytest.fixture(scope="module")
def head():
    return builtin_head()


def test_head_and_animation_pass_the_khronos_validator(tmp_path: Path, head) -> None:
    still = tmp_path / "head.glb"
    still.write_bytes(glb.head_glb_bytes(head))
    animated = glb.write(weight_clip(), tmp_path / "anim.glb", rig=head)
    au_clip = Clip(np.full((10, 2), 3.0), 25.0, ("AU12L", "AU12R"))
    from_au = glb.write(au_clip, tmp_path / "au.glb", rig=head)
    reports = validate(still, animated, from_au)
    for report in reports:
        assert (report["errors"], report["warnings"]) == (0, 0), report["messages"]
    info = reports[1]["info"]
    assert info["animationCount"] == 1 and info["hasMorphTargets"] is True


def test_head_bytes_hold_named_sparse_targets(head) -> None:
    data = glb.head_glb_bytes(head)
    assert glb.head_glb_bytes(head) is data  # cached per rig
    magic, version, total = struct.unpack_from("<III", data)
    assert (magic, version, total) == (0x46546C67, 2, len(data))
    length = struct.unpack_from("<I", data, 12)[0]
    document = json.loads(data[20 : 20 + length])
    mesh = document["meshes"][0]
    assert mesh["extras"]["targetNames"] == list(head.target_names)
    assert "animations" not in document
    primitive = mesh["primitives"][0]
    assert {"POSITION", "NORMAL", "COLOR_0"} <= set(primitive["attributes"])
    sparse = [t for t in primitive["targets"] if "sparse" in document["accessors"][t["POSITION"]]]
    assert len(sparse) >= len(primitive["targets"]) // 2  # ARKit targets are local: most are sparse
    # The reader rebuilds every target's deltas exactly from its (sparse) accessor.
    document_binary = data[20 + length + 8 :]
    for target, accessor in zip(head.targets, primitive["targets"], strict=True):
        dense = glb._read_accessor(document, document_binary, accessor["POSITION"], "head")
        np.testing.assert_array_equal(dense, target.dense(head.n_vertices))


def test_round_trip_weights_and_head_rotation(tmp_path: Path, head) -> None:
    clip = weight_clip(45, 30.0)
    back = glb.read(glb.write(clip, tmp_path / "x.glb", rig=head))
    assert back.fps == 30.0 and back.n_frames == 45
    assert back.channels[:52] == ARKIT_NAMES and back.channels[-3:] == FACE_CHANNELS[-5:-2]
    for name in clip.channels:
        # float32 storage: weights within 1e-6, angles within 1e-3 degree
        np.testing.assert_allclose(back.channel(name), clip.channel(name), atol=1e-3 if "deg" in name else 1e-6)
    np.testing.assert_allclose(back.channel("head_roll_deg"), 0.0, atol=1e-3)
    untouched = back.channel("browDownLeft")
    assert np.all(untouched == 0.0)


def test_writes_into_a_binary_stream(head) -> None:
    buffer = io.BytesIO()
    glb.write(weight_clip(5), buffer, rig=head)
    buffer.seek(0)
    assert glb.read(buffer).n_frames == 5


def test_bad_input_names_the_file(tmp_path: Path, head) -> None:
    path = glb.write(weight_clip(10), tmp_path / "good.glb", rig=head)
    data = path.read_bytes()
    truncated = tmp_path / "truncated.glb"
    truncated.write_bytes(data[: len(data) // 2])
    with pytest.raises(InvalidValueError, match=r"truncated\.glb.*truncated"):
        glb.read(truncated)
    wrong = tmp_path / "wrong.glb"
    wrong.write_bytes(b"PK\x03\x04" + data[4:])
    with pytest.raises(InvalidValueError, match=r"wrong\.glb header"):
        glb.read(wrong)
    still = tmp_path / "still.glb"
    still.write_bytes(glb.head_glb_bytes(head))
    with pytest.raises(InvalidValueError, match=r"still\.glb animations"):
        glb.read(still)
    with pytest.raises(InvalidValueError, match=r"clip channel.*grinWide"):  # smileFrown: a laughter controller
        glb.write(Clip(np.zeros((3, 1)), 30.0, ("grinWide",)), tmp_path / "bad.glb", rig=head)
    assert not (tmp_path / "bad.glb").exists()


def test_ict_head_with_paint_texture_passes_the_validator(tmp_path: Path, ict_dir: Path) -> None:
    from mien.heads import load_head

    rig = load_head("ict")
    path = tmp_path / "ict.glb"
    path.write_bytes(glb.head_glb_bytes(rig))
    (report,) = validate(path)
    assert (report["errors"], report["warnings"]) == (0, 0), report["messages"]
    info = report["info"]
    assert info["hasTextures"] is True and info["maxUVs"] == 1 and info["totalVertexCount"] == rig.n_vertices
    image = next(r for r in info["resources"] if r["pointer"] == "/images/0")["image"]
    assert image["format"] == "rgba" and image["transfer"] == "srgb"  # the PNG paint, sRGB-encoded


def test_another_heads_extra_targets_are_skipped_with_a_warning(tmp_path: Path, head) -> None:
    clip = Clip(np.array([[0.0, 0.2], [0.5, 0.4]]), 30.0, ("jawOpen", "someOtherHeadTarget"))
    with pytest.warns(UserWarning, match="not on head 'builtin' skipped: someOtherHeadTarget"):
        back = glb.read(glb.write(clip, tmp_path / "x.glb", rig=head))
    np.testing.assert_allclose(back.channel("jawOpen"), [0.0, 0.5], atol=1e-6)
