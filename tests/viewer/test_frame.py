"""The page's frame decoder (static/frame.js, run in node) reads exactly what the server encodes."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from mien.server.protocol import encode_frame
from mien.viewer.routes import STATIC_DIR

DECODE = """
import { readFileSync } from "node:fs";
import { decodeFrame } from "%s";
const frames = JSON.parse(readFileSync(process.argv[2], "utf8"));
const out = frames.map((hex) => {
  const bytes = Buffer.from(hex, "hex");
  const frame = decodeFrame(bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.length));
  if (frame.error) return { error: frame.error };
  return { tick: frame.tick, row: frame.row, timeS: frame.timeS, pose: [...frame.pose],
           weights: [...frame.weights].map((w) => (Number.isNaN(w) ? "nan" : w)) };
});
console.log(JSON.stringify(out));
"""


def _decode_in_node(frames: list[bytes], tmp_path: Path) -> list[dict]:
    node = shutil.which("node")
    if node is None:
        pytest.skip("node not installed (scripts/install installs it)")
    script = tmp_path / "decode.mjs"
    script.write_text(DECODE % (STATIC_DIR / "frame.js").as_uri())
    data = tmp_path / "frames.json"
    data.write_text(json.dumps([f.hex() for f in frames]))
    result = subprocess.run([node, str(script), str(data)], capture_output=True, text=True, timeout=30, check=True)
    return json.loads(result.stdout)


def test_frames_decode_as_encoded(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    weights = rng.uniform(0.0, 1.0, 60).astype(np.float16)
    special = np.array([0.0, 1.0, -0.5, 6e-8, 2.0**-14, 65504.0, np.inf], np.float16)  # subnormal, min normal, max
    pose = np.array([12.5, -3.25, 0.5, 20.0, -7.75])
    frames = [
        encode_frame(4_000_000_000, 3, 1234.56789, pose, weights),
        encode_frame(0, 0, 0.0, np.zeros(5), special),
        encode_frame(7, 1, 0.5, np.zeros(5), np.zeros(0)),
    ]
    decoded = _decode_in_node(frames, tmp_path)
    first = decoded[0]
    assert (first["tick"], first["row"], first["timeS"]) == (4_000_000_000, 3, 1234.56789)
    assert first["pose"] == pytest.approx(pose.tolist())
    assert first["weights"] == weights.astype(float).tolist()  # exact: float16 -> double
    second = [np.inf if w is None else w for w in decoded[1]["weights"]]  # JSON writes Infinity as null
    assert second == special.astype(float).tolist()
    assert decoded[2]["weights"] == []


def test_bad_frames_are_named_not_thrown(tmp_path: Path) -> None:
    good = encode_frame(1, 0, 0.0, np.zeros(5), np.zeros(3, np.float16))
    bad = [good[:20], b"NOPE" + good[4:], good[:4] + b"\x02\x00" + good[6:], good[:-2]]
    decoded = _decode_in_node(bad, tmp_path)
    errors = [d.get("error", "") for d in decoded]
    assert "20 bytes" in errors[0]
    assert "MIEN" in errors[1]
    assert "version 2" in errors[2]
    assert "3 weights" in errors[3]
