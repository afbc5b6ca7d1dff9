"""``mien serve --capture``: a video file played at its real rate drives characters through the live server (real
sockets on 127.0.0.1, the real MediaPipe landmarker); bad sources are refused or fall back visibly while every
other character stays on the clock."""

from __future__ import annotations

import json
from collections.abc import Iterator
from fractions import Fraction
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import pytest
from tests.server.conftest import wait_for
from tests.videos import encode_with_pts

from mien.cli import main
from mien.client import UdpClient, WebSocketClient
from mien.facs.arkit import ARKIT_INDEX
from mien.facs.catalogue import FACE_CHANNELS
from mien.server.app import ServeConfig, ServerThread
from mien.server.capture_source import CaptureConfig
from mien.server.registry import CharacterSpec

_AUS = [i for i, name in enumerate(FACE_CHANNELS) if name.startswith("AU")]


def _server(source: Path, landmarker: Path, **capture: Any) -> ServerThread:
    """Characters a (follows the capture), b and c (built-in head, no idle)."""
    characters = tuple(CharacterSpec(name, head="builtin", idle=False) for name in "abc")
    config = CaptureConfig(str(source), model=str(landmarker), **capture)
    return ServerThread(ServeConfig(udp_port=0, http_port=0, characters=characters, capture=config))


def _capture(server: ServerThread) -> dict[str, Any]:
    return httpx.get(f"{server.base_url}/api/capture", timeout=10).json()


@pytest.fixture(scope="module")
def smile_run(shared_data: Path, landmarker_path: Path) -> Iterator[dict[str, Any]]:
    """single_face.mp4 played once: a follows from the start, b is told to mirror it over its WebSocket, c gets
    AU4 over UDP; every frame of a's and b's streams (tick -> weights) and the capture's status at the end."""
    video = shared_data / "video" / "single_face.mp4"
    with _server(video, landmarker_path) as server:
        url = f"ws://127.0.0.1:{server.http_port}/ws"
        streams: dict[str, dict[int, np.ndarray]] = {"a": {}, "b": {}}
        registry = server.server.registry
        pairs = []  # a's and b's face frames at the same tick
        with WebSocketClient(url, "a") as a, WebSocketClient(url, "b") as b, UdpClient(port=server.udp_port) as udp:
            b.send({"capture": True})  # the second character mirrors the first
            udp.send({"AU4": 3}, speed=1.0, character="c")
            ended_at = None
            for _ in range(3000):  # bounded: ~50 s of 60 Hz frames
                for name, viewer in (("a", a), ("b", b)):
                    frame = viewer.recv_frame()
                    streams[name][frame.tick] = frame.weights
                faces, state = server.call(lambda: (registry.frames[[0, 1]].copy(), server.server.capture.state))
                pairs.append(faces)
                if ended_at is None and state == "ended":
                    ended_at = max(streams["a"])
                if ended_at is not None and max(streams["a"]) > ended_at + 100:  # 1.67 s more: held 0.5 s, eased 1 s
                    break
        status = _capture(server)
        health = httpx.get(f"{server.base_url}/api/health", timeout=10).json()
        c_frame = server.call(lambda: registry.frames[registry.get("c").row].copy())
        names = list(registry.get("a").rig.target_names)
    yield {"streams": streams, "pairs": pairs, "status": status, "health": health, "c": c_frame, "names": names,
           "video": video}  # fmt: skip


@pytest.mark.slow  # the video plays at its real rate: ~7 s with the server's start and the ease to neutral
def test_the_live_face_follows_the_video(smile_run: dict[str, Any], landmarker_path: Path) -> None:
    """Mouth weights streamed over the WebSocket follow the offline tracking of the same video."""
    from mien.tracking import track_video

    status, stream = smile_run["status"], smile_run["streams"]["a"]
    assert status["state"] == "ended" and status["error"] is None and status["followers"] == ["a", "b"]
    assert status["frames_read"] == 72 and status["frames_without_face"] == 0
    smile = smile_run["names"].index("mouthSmileLeft")
    offline = track_video(smile_run["video"], landmarker_path, use_cache=False, show_progress=False)
    scores = offline.blendshapes[:, [ARKIT_INDEX["mouthSmileLeft"], ARKIT_INDEX["mouthSmileRight"]]].mean(axis=1)
    timings = [t for t in status["timings"] if t["tick"] is not None]
    shown_from = np.array([t["tick"] for t in timings])
    live, tracked = [], []
    for tick in sorted(stream):  # each frame received shows the newest tracked frame a tick took by then
        i = int(np.searchsorted(shown_from, tick, side="right")) - 1
        if 0 <= i and tick <= shown_from[-1] + 1:
            live.append(float(stream[tick][smile]))
            tracked.append(float(scores[np.argmin(np.abs(offline.timestamps_s - timings[i]["source_s"]))]))
    assert len(live) >= 20
    assert np.corrcoef(live, tracked)[0, 1] > 0.9
    assert max(live) > 0.5 and min(live) < 0.1  # the smile shows, and the neutral start does not
    last = stream[max(stream)]
    assert np.abs(last).max() < 0.01  # after the video's end the face eased back to neutral


@pytest.mark.slow
def test_a_second_character_mirrors_the_first(smile_run: dict[str, Any]) -> None:
    smiling = [(a, b) for a, b in smile_run["pairs"] if a[FACE_CHANNELS.index("AU12L")] > 1.0]
    assert len(smiling) >= 5
    for a, b in smiling:
        assert np.array_equal(a, b)
    smile = smile_run["names"].index("mouthSmileLeft")
    assert max(frame[smile] for frame in smile_run["streams"]["b"].values()) > 0.5  # b's viewer shows it
    c = smile_run["c"]  # not a follower: only its own UDP command
    assert c[FACE_CHANNELS.index("AU4L")] == 3.0 and c[FACE_CHANNELS.index("AU12L")] == 0.0
    assert not {"tick_errors", "quarantined", "capture_failed"} & set(smile_run["health"]["degraded"])
    assert smile_run["health"]["capture"] == "ended"


def test_capture_messages_without_a_source_are_refused(live, wait_until) -> None:
    response = httpx.post(f"{live.base_url}/api/characters/a/capture", json={"follow": True})
    assert response.status_code == 400 and "no capture source" in response.json()["detail"]
    assert httpx.get(f"{live.base_url}/api/capture").status_code == 404
    with UdpClient(port=live.udp_port) as udp:
        udp.send_json({"capture": "yes"})
        udp.send_json({"capture": True})
    health = wait_until(
        lambda: (h := httpx.get(f"{live.base_url}/api/health").json())["rejections"].get("no_capture") and h,
        what="no_capture rejection",
    )
    assert health["rejections"]["wrong_type"] >= 1 and health["capture"] is None


def _track_some(server: ServerThread, frames: int) -> dict[str, Any]:
    return wait_for(lambda: (s := _capture(server))["frames_tracked"] >= frames and s, 30.0, f"{frames} frames tracked")


def test_a_video_without_a_face_leaves_the_face_neutral(shared_data: Path, landmarker_path: Path) -> None:
    with _server(shared_data / "video" / "no_face.mp4", landmarker_path) as server:
        followed = httpx.post(f"{server.base_url}/api/characters/b/capture", json={"follow": True}, timeout=10)
        assert followed.status_code == 202
        with UdpClient(port=server.udp_port) as udp:
            udp.send({"AU12": 4}, speed=1.0, character="b")
            status = _track_some(server, 15)
            registry = server.server.registry
            frames = server.call(lambda: registry.frames.copy())
    assert status["state"] == "no_face" and not status["has_face"] and status["followers"] == ["a", "b"]
    assert status["frames_without_face"] == status["frames_tracked"]
    assert np.abs(frames[0, _AUS]).max() == 0.0  # a: neutral, documented fallback
    assert frames[1, FACE_CHANNELS.index("AU12L")] == 4.0  # b: its own command on top of a neutral performance


def test_a_face_too_small_counts_as_no_face(shared_data: Path, landmarker_path: Path) -> None:
    with _server(shared_data / "video" / "single_face.mp4", landmarker_path, min_face_px=10_000) as server:
        status = _track_some(server, 10)
        frames = server.call(lambda: server.server.registry.frames.copy())
    assert status["frames_face_too_small"] == status["frames_tracked"] - status["frames_without_face"] > 0
    assert status["state"] == "no_face" and np.abs(frames[0, _AUS]).max() == 0.0


def _remux_faststart(source_path: Path, target: Path) -> None:
    import av

    with av.open(str(source_path)) as source, av.open(str(target), "w", options={"movflags": "faststart"}) as out:
        stream = out.add_stream_from_template(source.streams.video[0])
        for packet in source.demux(source.streams.video[0]):
            if packet.dts is not None:
                packet.stream = stream
                out.mux(packet)


def test_a_video_truncated_mid_play_fails_visibly(shared_data: Path, landmarker_path: Path, tmp_path: Path) -> None:
    """Index first, tail cut off: FFmpeg plays what is there, then the missing frames are noticed."""
    faststart = tmp_path / "faststart.mp4"
    _remux_faststart(shared_data / "video" / "single_face.mp4", faststart)
    truncated = tmp_path / "truncated.mp4"
    truncated.write_bytes(faststart.read_bytes()[: int(faststart.stat().st_size * 0.6)])
    with _server(truncated, landmarker_path) as server:
        status = wait_for(lambda: (s := _capture(server))["state"] == "failed" and s, 30.0, "the capture's failure")
        with UdpClient(port=server.udp_port) as udp:
            udp.send({"AU12": 2}, speed=1.0, character="b")
            wait_for(
                lambda: server.call(lambda: server.server.registry.state(server.server.registry.get("b"))["AU12L"]),
                10.0,
                "b's command after the failure",
            )
        health = httpx.get(f"{server.base_url}/api/health", timeout=10).json()
    assert "truncated.mp4" in status["error"] and "truncated: only" in status["error"]
    assert 0 < status["frames_read"] < 72
    assert "capture_failed" in health["degraded"] and "tick_errors" not in health["degraded"]


def test_a_variable_frame_rate_plays_on_its_own_time_stamps(
    shared_data: Path, landmarker_path: Path, tmp_path: Path
) -> None:

    from mien.tracking.video import iter_frames

    decoded = list(iter_frames(shared_data / "video" / "single_face.mp4"))[:20]
    pts_ms = np.concatenate([[0], np.cumsum([(30, 110, 50, 160, 70)[i % 5] for i in range(len(decoded) - 1)])])
    vfr = tmp_path / "vfr.mp4"
    encode_with_pts(vfr, [rgb for _, rgb in decoded], pts_ms.tolist(), Fraction(1, 1000))
    with _server(vfr, landmarker_path) as server:
        status = wait_for(lambda: (s := _capture(server))["state"] == "ended" and s, 30.0, "the end of the video")
    source_ms = np.round(np.array([t["source_s"] for t in status["timings"]]) * 1000).astype(int)
    assert status["frames_read"] == len(decoded) and len(source_ms) >= 5  # (a busy tracker skips frames)
    assert set((source_ms - source_ms[0]).tolist()) <= set(pts_ms.tolist())  # its own time stamps, not i / rate
    assert source_ms[-1] - source_ms[0] > 1000 * (len(decoded) - 1) / 30  # longer than at the average 30 fps


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["--capture", "/dev/video9"], "/dev/video9"),
        (["--capture", "camera:x"], "camera:N"),
        (["--capture", "/dev/null"], "a camera device"),
        (["--capture", "missing.mp4"], "missing.mp4"),
        (["--follow", "a"], "--capture SOURCE as well"),
        (["--capture-loop"], "--capture SOURCE as well"),
    ],
)
def test_bad_capture_options_exit_2(argv: list[str], words: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["serve", "--udp-port", "0", "--http-port", "0", "--check", *argv]) == 2
    error = capsys.readouterr().err
    assert error.startswith("mien serve: error:") and words in error and "Traceback" not in error


def test_an_unreadable_video_an_unknown_follower_and_a_bad_model_exit_2(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    corrupt = tmp_path / "corrupt.mp4"
    corrupt.write_bytes(np.random.default_rng(0).integers(0, 256, 4096, dtype=np.uint8).tobytes())
    assert main(["serve", "--check", "--capture", str(corrupt)]) == 2
    assert "corrupt.mp4" in capsys.readouterr().err
    video = str(shared_data / "video" / "single_face.mp4")
    assert main(["serve", "--check", "--capture", video, "--character", "a", "--follow", "z"]) == 2
    assert "--follow='z'" in capsys.readouterr().err
    not_a_model = tmp_path / "model.task"
    not_a_model.write_text("not a MediaPipe bundle\n")
    assert main(["serve", "--check", "--capture", video, "--landmarker", str(not_a_model)]) == 2
    assert "model.task" in capsys.readouterr().err


def test_the_capture_key_is_one_switch() -> None:
    from mien.server.protocol import MessageRejected, parse_message

    assert parse_message(json.dumps({"capture": True, "character": "b"}).encode()).capture is True
    assert parse_message(b'{"capture": false}').has_events
    with pytest.raises(MessageRejected, match="wrong_type"):
        parse_message(b'{"capture": 1}')
