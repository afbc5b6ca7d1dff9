"""The viewer plays a ``say``'s sound in step with the face, in a real headless Chromium against ``mien serve``.

A ``say`` sent over UDP is announced on the stream; the page fetches the WAV and starts a Web Audio source on
its first sample (not skipped into) and, while it plays, the sound's position on the server clock matches the
time of the frame the page shows within two 60 Hz frames. The scheduling rule itself is checked in node.
"""

from __future__ import annotations

import json
import shutil
import socket
import subprocess
from collections.abc import Iterator

import numpy as np
import pytest

pytest.importorskip("fastapi", reason="the serve extra is not installed")
pytest.importorskip("mien.speech.espeak")
from tests.viewer.test_browser import READY_TIMEOUT_MS, Live, _serve

from mien.viewer.routes import STATIC_DIR

TALKER = "talker"
SENTENCE = "my mama made a map, and the map was made of paper"
FRAME_S = 1.0 / 60.0
SMALL_VIEWPORT = {"width": 560, "height": 260}
"""A small view: a software rasteriser draws it at the stream's rate, so the page shows frames as they come."""


@pytest.fixture(scope="module")
def live() -> Iterator[Live]:
    with _serve("--no-idle", "--character", TALKER) as server:
        yield server


@pytest.mark.slow
def test_the_sound_starts_with_the_utterance_and_keeps_step_with_the_frames(chromium: object, live: Live) -> None:
    page = chromium.new_page(viewport=SMALL_VIEWPORT)  # type: ignore[attr-defined]
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.on("console", lambda message: message.type == "error" and errors.append(message.text))
    try:
        page.goto(f"{live.url}/?character={TALKER}")
        page.wait_for_function(
            "document.body.dataset.ready === '1' && window.mienViewer.head !== null"
            " && window.mienViewer.ticksSeen > 10",
            timeout=READY_TIMEOUT_MS,
        )
        page.click("#panel header")  # a user gesture: the browser lets the page play sound
        page.wait_for_function(
            "window.mienViewer.speech.context && window.mienViewer.speech.context.state === 'running'"
        )
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            sock.sendto(json.dumps({"say": SENTENCE, "character": TALKER}).encode(), ("127.0.0.1", live.udp_port))
        page.wait_for_function("window.mienViewer.speech.played >= 1", timeout=20_000)
        started = page.evaluate(
            "(() => { const c = window.mienViewer.speech.current;"
            " return c && { startS: c.startS, durationS: c.durationS, skip: c.skip, text: c.text }; })()"
        )
        assert started is not None and started["text"] == SENTENCE
        assert started["skip"] < 2 * FRAME_S, f"the sound was started {started['skip']:.3f} s in, not with the face"
        # the sound plays to its end (bounded), logging (frame time, sound time) on each animation frame
        page.wait_for_function(
            "window.mienViewer.speech.current === null", timeout=int(started["durationS"] * 4000) + 10_000
        )
        log = page.evaluate("window.mienViewer.speechLog")
    finally:
        page.close()
    assert errors == []
    frame_s, sound_s = (np.array([entry[key] for entry in log]) for key in ("frameS", "soundS"))
    next_s = np.array([np.inf if entry["nextS"] is None else entry["nextS"] for entry in log])
    assert len(log) >= 5, f"only {len(log)} animation frames while the sound played"
    assert sound_s[-1] - sound_s[0] > 0.6 * started["durationS"]  # logged over most of the sound
    # the face shows the frame whose tick holds the sound's time: from its time to the next frame's (a loaded
    # machine's server may skip ticks, and a starved page may draw before the next frame came)
    arrived = np.isfinite(next_s)
    assert arrived.mean() >= 0.5, f"the frames came after the sound in {1 - arrived.mean():.0%} of the draws"
    half_tick = 0.5 * FRAME_S
    holds = (frame_s <= sound_s + half_tick) & (sound_s + half_tick < next_s + 1e-6)
    assert holds[arrived].mean() >= 0.9, list(zip(frame_s[~holds], sound_s[~holds], next_s[~holds], strict=True))
    lag = frame_s - sound_s
    assert abs(float(np.median(lag))) <= 2 * FRAME_S, f"face - sound: median {np.median(lag):.3f} s"


def test_schedule_rule_in_node() -> None:
    node = shutil.which("node")
    if node is None:
        pytest.skip("node is not installed")
    script = f"""
    import {{ frameAt, scheduleStart }} from "{(STATIC_DIR / "speech.js").as_posix()}";
    const frames = [0, 1, 2, 3].map((i) => ({{ timeS: i / 60 }}));
    const out = [
      scheduleStart(10.0, 2.0, 11.5, 100.0),        // due in 0.5 s
      scheduleStart(10.0, 2.0, 12.25, 100.0),       // 0.25 s late: skip in
      scheduleStart(10.0, 2.0, 11.5, 100.0, 0.05),  // output latency: start earlier
      [frameAt(frames, 1.4 / 60).timeS * 60, frameAt(frames, 1.6 / 60).timeS * 60,
       frameAt(frames, 9), frameAt(frames, -1)],
    ];
    console.log(JSON.stringify(out));
    """
    result = subprocess.run(
        [node, "--input-type=module", "-e", script], capture_output=True, text=True, timeout=30, check=True
    )
    first, late, latency, picked = json.loads(result.stdout)
    assert first == {"when": 100.5, "skip": 0}
    assert late == {"when": 100.0, "skip": 0.25}
    assert latency["when"] == pytest.approx(100.45) and latency["skip"] == 0
    assert picked[0] == pytest.approx(1) and picked[1] == pytest.approx(2)  # the frame nearest the sound
    assert picked[2]["timeS"] == pytest.approx(3 / 60) and picked[3] is None
