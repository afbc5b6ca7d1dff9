"""OpenFACS datagram -> visible change in the browser viewer, against datagram -> WebSocket frame.

``mien serve`` (built-in head, no idle) runs in a child process; the viewer page runs in headless Debian
Chromium (Playwright; WebGL on the CPU rasteriser SwiftShader here, no GPU). Each trial sends one datagram
that flips AU12 and AU4 between 0 and 5 (Speed 1) and times, on this machine's clock:

- baseline: the first WebSocket frame (a Python client in a thread, watching the same character) whose
  mouthSmileLeft weight shows the new value: what the server and the network take;
- page render: the first render of the page (a requestAnimationFrame logger in the page, wall clock) that
  drew a frame with the new weight: what the page's WebSocket handling and its WebGL render add;
- viewer: the first screenshot of the mouth box whose pixels changed (mean > 3 of 255): all of it, with the
  compositor and the screenshot itself, as a user would see it.

Repeats: 3 interleaved blocks of 8 trials (the two measures of one trial are paired); medians, with the
spread of the block medians. Run: ``python bench/viewer_latency.py`` (needs Chromium and ``npm ci``);
``--head FILE`` measures a user's character instead (a VALID avatar: the viewer loads the file itself, textured).
"""

from __future__ import annotations

import io
import os
import statistics
import sys
import threading
import time
from pathlib import Path

import numpy as np
from PIL import Image

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _live_server import live_server

from mien.client import UdpClient, WebSocketClient

CHROMIUM = os.environ.get("MIEN_CHROMIUM", "/usr/bin/chromium")
VIEWPORT = {"width": 800, "height": 540}
BLOCKS, TRIALS = 3, 8


class FrameLog:
    """Arrival times (perf_counter seconds) and one weight of every frame, recorded by a thread."""

    def __init__(self, url: str, character: str, weight_index: int) -> None:
        self.client = WebSocketClient(url, character=character)
        self.index = weight_index
        self.frames: list[tuple[float, float]] = []
        self.running = True
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while self.running:
            try:
                frame = self.client.recv_frame(timeout_s=1.0)
            except Exception:  # the server went away or a timeout at shutdown
                if not self.running:
                    return
                continue
            self.frames.append((time.perf_counter(), float(frame.weights[self.index])))

    def first_at(self, since: float, target: float) -> float | None:
        for arrived, weight in list(self.frames):
            # a file head's calibrated shape may be driven past 1 (its gain): "there" is past 0.95 then
            if arrived >= since and (abs(weight - target) < 0.05 or (target >= 1.0 and weight > 0.95)):
                return arrived
        return None

    def close(self) -> None:
        self.running = False
        self.thread.join(3)
        self.client.close()


def mouth_box(head: str, width: int, height: int) -> dict[str, float]:
    """Clip (CSS pixels within the canvas) around the head's mouth in the page's first camera."""
    from mien.heads import load_head
    from mien.render.camera import CAMERA_PRESETS

    rig = load_head(head)
    pixels = CAMERA_PRESETS["frontal-1m"].project(rig.neutral[rig.landmarks[48:68]], width, height)
    (x0, y0), (x1, y1) = pixels.min(0) - 8, pixels.max(0) + 8
    return {"x": float(x0), "y": float(y0), "width": float(x1 - x0), "height": float(y1 - y0)}


def main() -> None:
    import argparse

    from playwright.sync_api import sync_playwright

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--head", default="builtin", help="head name or file (default builtin)")
    head = parser.parse_args().head
    print(f"head: {head}")
    with live_server("--head", head, "--no-idle", "--character", "bench") as (udp, http):
        import httpx

        names = httpx.get(f"http://127.0.0.1:{http}/api/characters").json()[0]["target_names"]
        smile = next(i for i, n in enumerate(names) if n == "mouthSmileLeft" or n.endswith("LsmileClose_h"))
        log = FrameLog(f"ws://127.0.0.1:{http}/ws", "bench", smile)
        with sync_playwright() as playwright, UdpClient(port=udp) as sender:
            browser = playwright.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"], headless=True)
            page = browser.new_page(viewport=VIEWPORT)
            page.goto(f"http://127.0.0.1:{http}/?character=bench")
            page.wait_for_function(
                "document.body.dataset.ready === '1' && window.mienViewer.head && window.mienViewer.renders > 1",
                timeout=60_000,
            )
            page.evaluate(
                """index => { const s = window.mienViewer; window.renderLog = [];
                const log = () => {
                  window.renderLog.push([Date.now(), s.renders, s.frame ? s.frame.weights[index] : 0]);
                  requestAnimationFrame(log); };
                requestAnimationFrame(log); }""",
                smile,
            )
            canvas = page.locator("#view").bounding_box()
            assert canvas is not None
            box = mouth_box(head, int(canvas["width"]), int(canvas["height"]))
            clip = {**box, "x": canvas["x"] + box["x"], "y": canvas["y"] + box["y"]}

            def shot() -> np.ndarray:
                return np.asarray(Image.open(io.BytesIO(page.screenshot(clip=clip))).convert("RGB"), float)

            blocks: list[tuple[list[float], list[float], list[float]]] = []
            target = 0.0
            for _ in range(BLOCKS):
                frame_ms: list[float] = []
                view_ms: list[float] = []
                render_ms: list[float] = []
                for _ in range(TRIALS):
                    target = 5.0 - target
                    time.sleep(0.6)  # let the last change finish rendering
                    before = shot()
                    page.evaluate("window.renderLog.length = 0")
                    sent, sent_wall_ms = time.perf_counter(), time.time() * 1e3
                    sender.send({"AU12": target, "AU4": target}, speed=1.0, character="bench")
                    seen = None
                    while time.perf_counter() - sent < 5.0:
                        if np.abs(shot() - before).mean() > 3.0:
                            seen = time.perf_counter()
                            break
                    arrived = log.first_at(sent, target / 5.0)
                    if seen is None or arrived is None:
                        print(f"trial lost (frame {arrived}, pixels {seen})")
                        continue
                    rendered = next(
                        (
                            t
                            for t, _, w in page.evaluate("window.renderLog")
                            if abs(w - target / 5.0) < 0.05 or (target > 0 and w > 0.95)
                        ),
                        None,
                    )
                    frame_ms.append((arrived - sent) * 1e3)
                    view_ms.append((seen - sent) * 1e3)
                    if rendered is not None:
                        render_ms.append(rendered - sent_wall_ms)
                blocks.append((frame_ms, view_ms, render_ms))
            fps_renders = page.evaluate("window.mienViewer.renders")
            browser.close()
        log.close()
    frames = [ms for block in blocks for ms in block[0]]
    views = [ms for block in blocks for ms in block[1]]
    frame_medians = [statistics.median(b[0]) for b in blocks if b[0]]
    view_medians = [statistics.median(b[1]) for b in blocks if b[1]]
    print(f"{len(views)} trials in {BLOCKS} interleaved blocks, viewport {VIEWPORT['width']}x{VIEWPORT['height']}")
    print(
        f"baseline, datagram -> WebSocket frame: median {statistics.median(frames):.1f} ms "
        f"(block medians {min(frame_medians):.1f}..{max(frame_medians):.1f})"
    )
    renders = [ms for block in blocks for ms in block[2]]
    render_medians = [statistics.median(b[2]) for b in blocks if b[2]]
    print(
        f"page render, datagram -> first render of the new weights: median {statistics.median(renders):.1f} ms "
        f"(block medians {min(render_medians):.1f}..{max(render_medians):.1f})"
    )
    print(
        f"viewer, datagram -> changed mouth pixels: median {statistics.median(views):.1f} ms "
        f"(block medians {min(view_medians):.1f}..{max(view_medians):.1f}), max {max(views):.1f} ms"
    )
    baseline = statistics.median(frames)
    print(f"page render / baseline: {statistics.median(renders) / baseline:.1f}x")
    print(f"viewer / baseline: {statistics.median(views) / baseline:.1f}x (target: viewer < 1000 ms)")
    print(f"page renders during the run: {fps_renders}; load average now: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
