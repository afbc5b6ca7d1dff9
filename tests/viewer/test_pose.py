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


NODES = """
import { Group, Matrix4, Quaternion, Vector3 } from "three";
import { framedTurn, poseNodeRole, poseQuaternion, vrmPoseNodes } from "%s";
const names = JSON.parse(process.argv[2]);
const roles = Object.fromEntries(names.map((name) => [name, poseNodeRole(name)]));
// a bone whose parent is turned 90 degrees about z (a Biped spine): yaw 30 must turn it about mien's +y
const parent = new Group();
parent.quaternion.setFromAxisAngle(new Vector3(0, 0, 1), Math.PI / 2);
const bone = new Group();
bone.quaternion.setFromAxisAngle(new Vector3(1, 0, 0), 0.3);
parent.add(bone);
parent.updateMatrixWorld(true);
const before = bone.getWorldQuaternion(new Quaternion());
framedTurn(bone, parent.getWorldQuaternion(new Quaternion()))(poseQuaternion(30, 0, 0));
parent.updateMatrixWorld(true);
const after = bone.getWorldQuaternion(new Quaternion());
const expected = poseQuaternion(30, 0, 0).multiply(before);
const bones1 = { head: { node: 5 }, leftEye: { node: 7 }, rightEye: { node: 8 } };
const vrm1 = vrmPoseNodes({ extensions: { VRMC_vrm: { humanoid: { humanBones: bones1 } } } });
const bones0 = [{ bone: "head", node: 3 }, { bone: "rightEye", node: 4 }, { bone: "neck", node: 2 }];
const vrm0 = vrmPoseNodes({ extensions: { VRM: { humanoid: { humanBones: bones0 } } } });
console.log(JSON.stringify({ roles, angle: after.angleTo(expected), vrm1, vrm0 }));
"""

ROLES = {
    "head": "head", "Head": "head", "mixamorig:Head": "head", "mixamorig1:Head": "head", "Bip01 Head": "head",
    "Bip001 Head": "head", "CC_Base_Head": "head", "J_Bip_C_Head": "head", "DEF-head": "head",
    "LeftEye": "eye", "RightEye": "eye", "mixamorig:LeftEye": "eye", "Bip01 L Eye": "eye", "CC_Base_R_Eye": "eye",
    "J_Adj_L_FaceEye": "eye", "DEF-eye.L": "eye", "Eye_L": "eye", "eye.r": "eye", "EyeLeft": "eye",
    "HeadEnd": None, "HeadTop_End": None, "h_L_eye": None, "Eyes": None, "Neck": None, "eyebrow_L": None,
}  # fmt: skip


def test_pose_nodes_are_found_by_name_and_vrm_bones_and_turned_in_mien_axes(tmp_path: Path) -> None:
    node, three = shutil.which("node"), three_dir()
    if node is None or three is None:
        pytest.skip("node and node_modules/three needed (scripts/install, npm ci)")
    script = tmp_path / "nodes.mjs"
    script.write_text(NODES % (STATIC_DIR / "pose.js").as_uri())
    (tmp_path / "node_modules").symlink_to(three.parent, target_is_directory=True)
    result = subprocess.run(
        [node, str(script), json.dumps(list(ROLES))], capture_output=True, text=True, timeout=30, cwd=tmp_path
    )
    assert result.returncode == 0, result.stderr
    out = json.loads(result.stdout)
    assert out["roles"] == ROLES
    assert out["angle"] < 1e-6  # the bone turned by yaw 30 about mien's +y, whatever its parent's axes
    assert out["vrm1"] == {"head": 5, "eyes": [7, 8]} and out["vrm0"] == {"head": 3, "eyes": [4]}
