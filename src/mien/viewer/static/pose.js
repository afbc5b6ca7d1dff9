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
