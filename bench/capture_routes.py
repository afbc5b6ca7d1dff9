"""Measurement: the AU route against the ARKit pass-through route of a capture, per face region and head.

The person in data/video/single_face.mp4 (a smile and a blink, 72 frames) is captured once
(:func:`mien.capture.capture_video`); each route's clip is replayed on a head with ARKit-named targets
(the built-in head, ICT-FaceKit), rendered at 256x256 frontal, re-detected by MediaPipe and put through the same
capture stream with the head's rendered neutral subtracted (as ``mien validate compare`` does). Printed per
route and head: the correlation over time between the person's and the character's scores, averaged over the
scores that move in the person (peak > 0.1) of each region, the AU rows' correlation (AUs whose peak > 0.5),
and the character's peak over the person's for the smile and the blink (1 = the same amplitude). The baseline
is the AU route. A head without the performer's ARKit names (a VALID avatar) has only the AU route.

Run: .venv/bin/python bench/capture_routes.py (needs the shared data, face_landmarker.task and ICT-FaceKit).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

REGIONS = {
    "brows": ("brow",),
    "eyes": ("eyeBlink", "eyeSquint", "eyeWide", "cheekSquint"),
    "mouth": ("mouth", "cheekPuff"),
    "jaw": ("jaw",),
}


def _shared() -> Path:
    return Path(os.environ.get("MIEN_SHARED", Path(__file__).resolve().parents[1].parent / "shared"))


def _r(a: np.ndarray, b: np.ndarray) -> float:
    if a.std() < 1e-9 or b.std() < 1e-9:
        return float("nan")
    return float(np.corrcoef(a, b)[0, 1])


def main() -> int:
    """Run the measurement and print one block per head."""
    from mien.capture import capture_frames, capture_video, strip_face_mask
    from mien.facs.arkit import ARKIT_NAMES
    from mien.facs.catalogue import au_channels
    from mien.heads import load_head
    from mien.render.camera import camera_from_options
    from mien.rig.face_weights import clip_to_rig
    from mien.validate.face_detector import MediaPipeDetector
    from mien.validate.stimuli import StimulusRenderer

    video = _shared() / "data" / "video" / "single_face.mp4"
    person = capture_video(video, show_progress=False)
    found = person.face_found
    aus = (1, 2, 4, 6, 7, 12, 25, 26, 45)
    smile = [ARKIT_NAMES.index("mouthSmileLeft"), ARKIT_NAMES.index("mouthSmileRight")]
    blink = [ARKIT_NAMES.index("eyeBlinkLeft"), ARKIT_NAMES.index("eyeBlinkRight")]
    detector = MediaPipeDetector()
    print(f"{video.name}: {person.n_frames} frames; the person's moving scores per region:")
    for region, prefixes in REGIONS.items():
        names = [n for i, n in enumerate(ARKIT_NAMES) if n.startswith(prefixes) and person.weights[:, i].max() > 0.1]
        print(f"  {region:6s}: {', '.join(names) or '-'}")
    try:
        for head in ("builtin", "ict"):
            rig = load_head(head)
            with StimulusRenderer(rig, camera_from_options("frontal-1m"), (256, 256)) as renderer:
                rest = detector.detect(renderer.render(np.zeros(62))[0]).blendshapes
                neutral = np.r_[rest, np.zeros(3)]
                print(f"\n{rig.name}: r(person, character) over time      smile peak  blink peak")
                for route in ("au", "arkit"):
                    clip, _ = strip_face_mask(person.clip(route))
                    weights, poses = clip_to_rig(clip, rig)
                    scores = np.stack([detector.detect(renderer.render_weights(w, p)[0]).blendshapes
                                       for w, p in zip(weights, poses, strict=True)])  # fmt: skip
                    n = len(scores)
                    character = capture_frames(
                        "render", clip.fps, clip.times_s, scores, np.zeros((n, 3)), np.ones(n, bool), neutral=neutral
                    )
                    cells = []
                    for prefixes in REGIONS.values():
                        rs = [_r(person.weights[found, i], character.weights[found, i])
                              for i, name in enumerate(ARKIT_NAMES)
                              if name.startswith(prefixes) and person.weights[:, i].max() > 0.1]  # fmt: skip
                        rs = [r for r in rs if np.isfinite(r)]
                        cells.append(f"{np.mean(rs):.2f}" if rs else "  - ")
                    au_rs = []
                    for code in aus:
                        columns = list(au_channels(code))
                        a, b = person.frames[found][:, columns].mean(1), character.frames[found][:, columns].mean(1)
                        if a.max() > 0.5 and np.isfinite(_r(a, b)):
                            au_rs.append(_r(a, b))
                    regions = "  ".join(f"{name} {cell}" for name, cell in zip(REGIONS, cells, strict=True))
                    peak = [
                        character.weights[:, k].max() / max(person.weights[:, k].max(), 1e-9) for k in (smile, blink)
                    ]
                    print(
                        f"  {route:5s} {regions}  AUs {np.mean(au_rs):.2f} (n={len(au_rs)})"
                        f"  {peak[0]:5.2f}  {peak[1]:9.2f}"
                    )
    finally:
        detector.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
