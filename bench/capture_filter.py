"""Measurement: the capture's jitter filter (One Euro) on the real videos, for a grid of cut-offs.

For each setting, on the frames with a face of data/video/single_face.mp4, face_noface.mov and noface_face.mov
(cached tracking), against the same capture unfiltered (the named baseline):
- jitter: RMS second difference (x[t+1] - 2 x[t] + x[t-1], the frame-rate wobble a slow trend does not
  have) of the AU channels, and of the head rotation, on still frames (where no raw blendshape score moves by
  more than 0.03 over the surrounding 5 frames), as a share of the unfiltered one (lower is smoother);
- smile onset lag: frames between the unfiltered and filtered AU12 crossing half its plateau (0: as sharp);
- blink: the filtered AU45 peak as a share of the unfiltered peak, and its delay in frames.
The default of :class:`mien.capture.CaptureSettings` is marked with ``*``.

Run: .venv/bin/python bench/capture_filter.py (needs the shared data and face_landmarker.task).
"""

from __future__ import annotations

import os
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

VIDEOS = ("single_face.mp4", "face_noface.mov", "noface_face.mov")
GRID = [(c, b) for c in (0.5, 1.0, 2.0, 4.0) for b in (0.0, 0.5, 2.0, 4.0, 8.0)]


def _shared() -> Path:
    return Path(os.environ.get("MIEN_SHARED", Path(__file__).resolve().parents[1].parent / "shared"))


def main() -> int:
    """Run the measurement and print one row per setting."""
    from mien.capture import CaptureSettings, capture_track
    from mien.facs.catalogue import FACE_CHANNELS, au_channels
    from mien.tracking.track import track_video

    tracks = [track_video(_shared() / "data" / "video" / name, show_progress=False) for name in VIDEOS]
    aus = [i for i, name in enumerate(FACE_CHANNELS) if name.startswith("AU")]
    pose = [i for i, name in enumerate(FACE_CHANNELS) if name.startswith("head_")]
    au12, au45 = list(au_channels(12)), list(au_channels(45))
    default = CaptureSettings()

    def measure(settings: CaptureSettings) -> tuple[float, float, float, float, float]:
        jitter: tuple[list, list] = ([], [])
        lags, peaks, delays = [], [], []
        for track in tracks:
            found = track.face_found
            raw = capture_track(track, replace(settings, filter=False)).frames[found]
            out = capture_track(track, settings).frames[found]
            scores = track.blendshapes[found].astype(np.float64)
            moving = np.abs(np.diff(scores, axis=0)).max(axis=1)
            still = np.flatnonzero(np.convolve(moving > 0.03, np.ones(5), mode="same") == 0)
            still = still[still < len(moving) - 1]
            for k, columns in enumerate((aus, pose)):
                jitter[k].append(
                    (np.diff(out[:, columns], 2, axis=0)[still] ** 2, np.diff(raw[:, columns], 2, axis=0)[still] ** 2)
                )
            smile_raw, smile = raw[:, au12].mean(axis=1), out[:, au12].mean(axis=1)
            half = 0.5 * np.median(smile_raw[smile_raw > 0.5 * smile_raw.max()])
            lags.append(int(np.argmax(smile > half)) - int(np.argmax(smile_raw > half)))
            blink_raw, blink = raw[:, au45].mean(axis=1), out[:, au45].mean(axis=1)
            peak = int(np.argmax(blink_raw))
            near = slice(max(peak - 3, 0), peak + 6)
            peaks.append(blink[near].max() / blink_raw[peak])
            delays.append(int(np.argmax(blink[near])) + near.start - peak)
        shares = [
            np.sqrt(np.mean(np.concatenate([j[0].ravel() for j in group])))
            / np.sqrt(np.mean(np.concatenate([j[1].ravel() for j in group])))
            for group in jitter
        ]
        return shares[0], shares[1], float(np.mean(lags)), float(np.mean(peaks)), float(np.mean(delays))

    print(
        f"{len(tracks)} videos, {sum(int(t.face_found.sum()) for t in tracks)} frames with a face; baseline: unfiltered"
    )
    print(" min_cutoff_hz  beta  AU jitter  head jitter  smile lag(frames)  blink peak(share)  blink delay(frames)")
    for cutoff, beta in GRID:
        au_jitter, head_jitter, lag, peak, delay = measure(replace(default, min_cutoff_hz=cutoff, beta=beta))
        mark = "*" if (cutoff, beta) == (default.min_cutoff_hz, default.beta) else " "
        print(
            f"{mark}{cutoff:13.1f} {beta:5.1f}  {au_jitter:9.2f}  {head_jitter:11.2f}  {lag:17.2f}  {peak:17.2f}  "
            f"{delay:19.2f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
