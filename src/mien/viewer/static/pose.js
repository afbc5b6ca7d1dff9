// Head and eye rotations of a frame's pose angles, in three.js terms (+y up, +z toward a frontal viewer,
// +x the character's left: the mien rig frame, which is glTF's).
// mien: yaw > 0 turns to the character's left, pitch > 0 raises the chin, roll > 0 tilts toward the left
// shoulder; the rotation is R_y(yaw) R_x(-pitch) R_z(-roll) (mien.rig.pose.head_rotation), which is a
// three.js Euler(-pitch, yaw, -roll) in "YXZ" order. Checked against mien.rig.pose in tests/viewer/test_pose.py.
import { Euler, Quaternion } from "three";

const DEG = Math.PI / 180;
const euler = new Euler();

/** Write into `out` (a three.js Quaternion) the head rotation of yaw, pitch, roll in degrees; returns it. */
export function poseQuaternion(yawDeg, pitchDeg, rollDeg, out = new Quaternion()) {
  return out.setFromEuler(euler.set(-pitchDeg * DEG, yawDeg * DEG, -rollDeg * DEG, "YXZ"));
}

// Which nodes of a glTF the head pose and the gaze turn, by name. A name is compared in lower case without a
// "namespace:" prefix (mixamorig:, mixamorig1:) and without spaces, "_", "." and "-"; the first node found in
// scene order with a matching name wins for the head, every matching node is an eye. Mesh nodes are never
// turned (an eyeball mesh moves with its eye joint). A VRM file's humanoid bones (head, leftEye, rightEye) are
// taken before any name. Covers mien's own glTF ("head"), Rocketbox and VALID (Head, LeftEye, RightEye; 3ds Max
// Biped "Bip01 Head", "Bip01 L Eye"), Mixamo (mixamorig:Head, mixamorig:LeftEye), Character Creator
// (CC_Base_Head, CC_Base_L_Eye), VRoid (J_Bip_C_Head, J_Adj_L_FaceEye), Rigify (DEF-head, DEF-eye.L) and the
// common Eye_L / eye.R / EyeLeft spellings. Add a rig's names here.
export const POSE_NODE_PATTERNS = {
  head: [/^(bip\d*|ccbase|jbipc|def|rl)?head$/],
  eye: [/^(bip\d*|ccbase|jadj|def|rl)?((l|r|left|right)(face)?eye|eye(l|r|left|right))$/],
};

/** The name of a node as POSE_NODE_PATTERNS compares it. */
export function normaliseNodeName(name) {
  return String(name || "").replace(/^[^:]*:/, "").replace(/[\s_.\-]/g, "").toLowerCase();
}

/** "head", "eye" or null: what a node called `name` is turned by. */
export function poseNodeRole(name) {
  const key = normaliseNodeName(name);
  for (const [role, patterns] of Object.entries(POSE_NODE_PATTERNS)) {
    if (patterns.some((pattern) => pattern.test(key))) return role;
  }
  return null;
}

/** The glTF node indices of a VRM file's humanoid head and eyes ({ head, eyes: [] }), from the parsed JSON. */
export function vrmPoseNodes(json) {
  const extensions = (json && json.extensions) || {};
  const out = { head: null, eyes: [] };
  const vrm1 = extensions.VRMC_vrm && extensions.VRMC_vrm.humanoid && extensions.VRMC_vrm.humanoid.humanBones;
  if (vrm1) {
    if (vrm1.head && Number.isInteger(vrm1.head.node)) out.head = vrm1.head.node;
    for (const bone of ["leftEye", "rightEye"]) if (vrm1[bone] && Number.isInteger(vrm1[bone].node)) out.eyes.push(vrm1[bone].node);
    return out;
  }
  const vrm0 = extensions.VRM && extensions.VRM.humanoid && extensions.VRM.humanoid.humanBones;
  for (const bone of Array.isArray(vrm0) ? vrm0 : []) {
    if (bone.bone === "head" && Number.isInteger(bone.node)) out.head = bone.node;
    if ((bone.bone === "leftEye" || bone.bone === "rightEye") && Number.isInteger(bone.node)) out.eyes.push(bone.node);
  }
  return out;
}

/**
 * A node turned in mien's frame instead of its own: `frame` is its parent's rotation (relative to the head's
 * frame, at rest), so `turn(q)` writes into the node's local quaternion F^-1 q F rest, which turns it by `q`
 * (mien's axes) about its own origin, whatever the bone's local axes are (a Biped head's x runs along the spine).
 */
export function framedTurn(node, frame) {
  const rest = node.quaternion.clone();
  const inverse = frame.clone().invert();
  return (q) => node.quaternion.copy(inverse).multiply(q).multiply(frame).multiply(rest);
}
