"""The page turns the head as mien does: static/pose.js (three.js, run in node) against mien.rig.pose."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from mien.rig.pose import head_rotation
from mien.viewer.routes import STATIC_DIR
from mien.viewer.vendor import three_dir

ANGLES = [(0, 0, 0), (30, 0, 0), (0, 20, 0), (0, 0, 15), (25, -10, 8), (-40, 15, -12), (90, 0, 0)]

ROTATE = """
import { Matrix4 } from "three";
import { poseQuaternion } from "%s";
const out = JSON.parse(process.argv[2]).map(([yaw, pitch, roll]) => {
  const m = new Matrix4().makeRotationFromQuaternion(poseQuaternion(yaw, pitch, roll)).elements;
  return [[m[0], m[4], m[8]], [m[1], m[5], m[9]], [m[2], m[6], m[10]]];  // column-major -> rows
});
console.log(JSON.stringify(out));
"""


def test_head_rotation_matches_mien(tmp_path: Path) -> None:
    node, three = shutil.which("node"), three_dir()
    if node is None or three is None:
        pytest.skip("node and node_modules/three needed (scripts/install, npm ci)")
    script = tmp_path / "rotate.mjs"
    script.write_text(ROTATE % (STATIC_DIR / "pose.js").as_uri())
    # node resolves the bare "three" from the node_modules beside the script's folder chain
    (tmp_path / "node_modules").symlink_to(three.parent, target_is_directory=True)
    result = subprocess.run(
        [node, str(script), json.dumps(ANGLES)], capture_output=True, text=True, timeout=30, cwd=tmp_path
    )
    assert result.returncode == 0, result.stderr
    matrices = np.array(json.loads(result.stdout))
    expected = np.array([head_rotation(*angles) for angles in ANGLES])
    np.testing.assert_allclose(matrices, expected, atol=1e-6)
    forward = matrices[1] @ [0.0, 0.0, 1.0]  # yaw 30: the face turns toward the character's left (+x)
    assert forward[0] > 0.4
