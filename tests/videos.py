"""Test videos written on the spot: RGB frames encoded with chosen presentation time stamps."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np


def encode_with_pts(path: Path, frames: list[np.ndarray], pts: list[int], time_base: Fraction) -> None:
    """Encode RGB frames with the given presentation time stamps (H.264 in MP4; PyAV)."""
    import av

    height, width = frames[0].shape[:2]
    with av.open(str(path), "w") as container:
        stream = container.add_stream("libx264", rate=30)
        stream.width, stream.height, stream.pix_fmt = width, height, "yuv420p"
        stream.time_base = stream.codec_context.time_base = time_base
        for rgb, stamp in zip(frames, pts, strict=True):
            frame = av.VideoFrame.from_ndarray(rgb, format="rgb24")
            frame.pts, frame.time_base = stamp, time_base
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
