// The WebSocket frame of mien serve (see mien.server.protocol), little-endian:
//   0-3 "MIEN", 4-5 u16 version 1, 6-7 u16 n_weights, 8-11 u32 tick, 12-15 u32 character row,
//   16-23 f64 time_s, 24-43 5 x f32 pose degrees (head yaw, pitch, roll, gaze yaw, pitch), 44.. f16 weights.
// A plain ES module with no dependencies, so node can import it too (tests/viewer/test_frame.py).
export const FRAME_HEADER_BYTES = 44;
const FRAME_MAGIC = [0x4d, 0x49, 0x45, 0x4e]; // "MIEN"

/** The number of an IEEE 754 half-precision bit pattern (DataView.getFloat16 is not everywhere yet). */
export function halfToFloat(h) {
  const sign = h & 0x8000 ? -1 : 1;
  const exponent = (h >> 10) & 0x1f;
  const fraction = h & 0x3ff;
  if (exponent === 0) return sign * fraction * 2 ** -24;
  if (exponent === 31) return fraction ? NaN : sign * Infinity;
  return sign * (1 + fraction / 1024) * 2 ** (exponent - 15);
}

/**
 * Decode one binary frame (an ArrayBuffer): { tick, row, timeS, pose: Float32Array(5) degrees,
 * weights: Float32Array(n_weights) }, or { error } saying why it is not a version-1 frame.
 */
export function decodeFrame(buffer) {
  if (buffer.byteLength < FRAME_HEADER_BYTES) return { error: `frame of ${buffer.byteLength} bytes` };
  const view = new DataView(buffer);
  for (let i = 0; i < 4; i++) {
    if (view.getUint8(i) !== FRAME_MAGIC[i]) return { error: "frame without the MIEN magic" };
  }
  const version = view.getUint16(4, true);
  if (version !== 1) return { error: `frame version ${version} (this page reads version 1)` };
  const n = view.getUint16(6, true);
  if (buffer.byteLength !== FRAME_HEADER_BYTES + 2 * n) return { error: `frame of ${n} weights has ${buffer.byteLength} bytes` };
  const pose = new Float32Array(5);
  for (let i = 0; i < 5; i++) pose[i] = view.getFloat32(24 + 4 * i, true);
  const weights = new Float32Array(n);
  for (let i = 0; i < n; i++) weights[i] = halfToFloat(view.getUint16(FRAME_HEADER_BYTES + 2 * i, true));
  return {
    tick: view.getUint32(8, true),
    row: view.getUint32(12, true),
    timeS: view.getFloat64(16, true),
    pose,
    weights,
  };
}
