"""The OpenFACS UDP API on a real socket: exact datagrams, Lerp timing, extensions, bad input, a flood."""

from __future__ import annotations

import json
import math
import os
import socket
import time

import httpx

from mien.client import UdpClient


def _send_fresh(port: int, data: bytes) -> None:
    """Like the original client: a fresh socket for each message."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.sendto(data, ("127.0.0.1", port))


def _record(live, character: str, channel: str) -> list[tuple[float, float]]:
    """Attach a tick listener recording (time_s, value) of one channel; returns the list it fills."""
    from mien.facs.catalogue import FACE_CHANNELS

    registry = live.server.registry
    row = registry.get(character).row
    column = FACE_CHANNELS.index(channel)
    samples: list[tuple[float, float]] = []
    live.call(
        lambda: live.server.clock.listeners.append(lambda tick, t: samples.append((t, registry.frames[row, column])))
    )
    deadline = time.monotonic() + 3.0
    while len(samples) < 3 and time.monotonic() < deadline:  # a few still ticks first
        time.sleep(0.01)
    return samples


def _check_lerp(samples: list[tuple[float, float]], target: float, speed: float, nominal_hz: float = 60.0) -> float:
    """The curve follows Lerp(current, target, speed) per nominal tick, in time; returns the time to 95 %."""
    moving = [i for i, (_, v) in enumerate(samples) if v > 0]
    assert moving, "the face never moved"
    first = moving[0]
    assert first > 0, "recording started after the move"
    t0 = samples[first - 1][0]  # the datagram was applied at the tick where it started moving, from t0
    for t, value in samples[first:]:
        expected = target * (1.0 - (1.0 - speed) ** ((t - t0) * nominal_hz))
        assert abs(value - expected) < 1e-6 * max(1.0, target), (t - t0, value, expected)
    return math.log(0.05) / math.log(1.0 - speed) / nominal_hz


def test_exact_openfacs_datagram_moves_the_face_with_lerp_timing(live, openfacs_datagram, wait_until) -> None:
    samples = _record(live, "a", "AU12L")
    data = openfacs_datagram({12: 5, 6: 3}, speed=0.05)
    assert len(data) in range(195, 215)
    _send_fresh(live.udp_port, data)
    wait_until(lambda: len(samples) > 10 and samples[-1][1] > 4.75, timeout_s=4.0, what="AU12 at 95 %")
    time_to_95 = _check_lerp(samples, 5.0, 0.05)
    reached = next(t for t, v in samples if v >= 4.75) - samples[[v > 0 for _, v in samples].index(True) - 1][0]
    # measured on the server's ticks: OpenFACS (Lerp 0.05 a frame at 60 Hz) is at 95 % after 59 frames
    # (0.95 ** 59 < 0.05 < 0.95 ** 58); one tick later at most if the busy machine made the clock skip it
    assert 59 / 60 - 1e-9 <= reached <= 60 / 60 + 1e-9
    assert abs(reached - time_to_95) <= 1 / 60 + 1e-9


def test_lerp_timing_is_tick_rate_independent(server_factory, openfacs_datagram, wait_until) -> None:
    with server_factory(tick_hz=25.0) as live:
        samples = _record(live, "a", "AU12L")
        _send_fresh(live.udp_port, openfacs_datagram({12: 4}, speed=0.1))
        wait_until(lambda: samples and samples[-1][1] > 3.9, timeout_s=4.0, what="AU12 near 4")
        _check_lerp(samples, 4.0, 0.1)  # the same curve in time as at 60 Hz


def test_speed_one_jumps_and_missing_aus_go_to_zero(live, openfacs_datagram, au_value, wait_until) -> None:
    _send_fresh(live.udp_port, openfacs_datagram({4: 5, 15: 3}, speed=1))
    wait_until(lambda: au_value(live, "a", "AU4L") == 5.0, what="AU4 at 5")
    assert au_value(live, "a", "AU15L") == 3.0
    _send_fresh(live.udp_port, openfacs_datagram({15: 2}, speed=1))  # full state: AU4 missing -> 0
    wait_until(lambda: au_value(live, "a", "AU4L") == 0.0, what="AU4 back to 0")
    assert au_value(live, "a", "AU15L") == 2.0


def test_fractional_and_extended_messages(live, au_value, wait_until) -> None:
    with UdpClient("127.0.0.1", live.udp_port) as client:
        client.send({"AU12": 2.75, "AU6L": 1.5, "AU43": 1.25}, speed=1.0)
        wait_until(lambda: au_value(live, "a", "AU12R") == 2.75, what="fractional AU12")
        assert au_value(live, "a", "AU6L") == 1.5 and au_value(live, "a", "AU6R") == 0.0
        assert au_value(live, "a", "AU43L") == 1.25
        client.send({}, speed=1.0, character="b")
        client.emote("joy", 1.0, character="b")
        wait_until(lambda: au_value(live, "b", "AU12L") > 1.0, what="joy on b")
        assert au_value(live, "a", "AU12R") == 2.75  # a did not move
        client.laugh("laughter", 1.0, character="a")
        client.send_json({"play": {"au": "AU45", "intensity": 5, "onset_s": 0.05, "apex_s": 0.2}, "character": "b"})
        wait_until(lambda: au_value(live, "b", "AU45L") > 4.0, what="a blink played on b")


def test_two_characters_are_independent(live, openfacs_datagram, au_value, wait_until) -> None:
    with UdpClient("127.0.0.1", live.udp_port) as client:
        client.send({"AU4": 5}, speed=1.0, character="a")
        client.send({"AU26": 3}, speed=1.0, character="b")
        wait_until(lambda: au_value(live, "b", "AU26") == 3.0 and au_value(live, "a", "AU4L") == 5.0)
        assert au_value(live, "a", "AU26") == 0.0 and au_value(live, "b", "AU4L") == 0.0
    # an old client (no character id) drives the first character only
    _send_fresh(live.udp_port, openfacs_datagram({1: 2}, speed=1))
    wait_until(lambda: au_value(live, "a", "AU1L") == 2.0)
    assert au_value(live, "b", "AU26") == 3.0 and au_value(live, "b", "AU1L") == 0.0


def test_bad_input_is_counted_per_reason_and_the_last_good_state_kept(live, au_value, wait_until) -> None:
    with UdpClient("127.0.0.1", live.udp_port) as client:
        client.send({"AU12": 3}, speed=1.0)
        wait_until(lambda: au_value(live, "a", "AU12L") == 3.0)
        bad = {
            "malformed_json": [b"{", b'{"AU12": 3,}', os.urandom(64).replace(b"{", b"x").replace(b"[", b"x")],
            "not_object": [b"[1, 2, 3]", b"42"],
            "wrong_type": [b'{"AU12": "3"}'],
            "unknown_au": [b'{"AU99": 3}'],
            "unknown_field": [b'{"hello": 3}'],
            "out_of_range": [b'{"AU12": 50}', b'{"AU12": 1, "Speed": -0.5}'],
            "oversized": [json.dumps({"AU12": 1, "pad_": "x" * 2000}).encode()],
            "unknown_character": [b'{"AU12": 1, "character": "nobody"}'],
            "unknown_name": [b'{"emotion": "bliss"}'],
        }
        for datagrams in bad.values():
            for data in datagrams:
                client.send_raw(data)
        expected = {reason: len(datagrams) for reason, datagrams in bad.items()}
        ticks_before = httpx.get(f"{live.base_url}/api/health").json()["ticks"]
        health = wait_until(
            lambda: (h := httpx.get(f"{live.base_url}/api/health").json())["rejections"] == expected and h,
            what=f"rejections {expected}",
        )
        time.sleep(0.1)
        health = httpx.get(f"{live.base_url}/api/health").json()
    assert health["ticks"] > ticks_before  # the clock kept ticking
    assert health["datagrams_received"] == 1 + sum(expected.values()) and health["datagrams_accepted"] == 1
    assert health["tick_errors"] == 0
    assert au_value(live, "a", "AU12L") == 3.0  # the face kept its last good state (OpenFACS froze at 0)


def test_bounded_flood_keeps_the_clock_and_ends_on_the_last_state(live, wait_until, au_value) -> None:
    n = 5000
    start = time.monotonic()
    ticks_before = live.server.clock.stats.ticks
    with UdpClient("127.0.0.1", live.udp_port) as client:
        for i in range(n):
            if i % 10 == 9:
                client.send_raw(b"\x00garbage")
            else:
                client.send({"AU12": (i % 50) / 10}, speed=1.0, character="a" if i % 2 else "b")
        client.send({"AU12": 4.5}, speed=1.0, character="a")
        client.send({"AU12": 1.5}, speed=1.0, character="b")
    elapsed = time.monotonic() - start
    health = wait_until(
        lambda: (h := httpx.get(f"{live.base_url}/api/health").json())["datagrams_received"] >= n + 2 and h,
        what="every datagram received",
    )
    assert health["datagrams_received"] == health["datagrams_accepted"] + sum(health["rejections"].values())
    assert health["rejections"] == {"malformed_json": n // 10}
    assert health["datagrams_accepted"] == n + 2 - n // 10  # nothing valid lost on loopback
    wait_until(lambda: au_value(live, "a", "AU12L") == 4.5 and au_value(live, "b", "AU12L") == 1.5)
    # the clock went on during the flood (at least half its ticks, on a shared 2-core machine)
    assert live.server.clock.stats.ticks - ticks_before >= 0.5 * elapsed * 60


def test_a_laugh_without_its_extra_is_a_counted_rejection_in_health(live, au_value, wait_until) -> None:
    from mien.errors import MissingExtraError

    def no_extra(*args, **kwargs):
        raise MissingExtraError("scipy", "laughter")  # what the library raises on an install without the extra

    registry = live.server.registry
    live.call(lambda: setattr(registry.batch, "laugh", no_extra))
    with UdpClient("127.0.0.1", live.udp_port) as client:
        client.laugh("laughter", 1.0, character="a")
        client.send({"AU12": 3}, speed=1.0, character="b")
        wait_until(lambda: au_value(live, "b", "AU12L") == 3.0, what="b's state applied")
        health = wait_until(
            lambda: (h := httpx.get(f"{live.base_url}/api/health").json())["rejections"] and h, what="a rejection"
        )
        assert health["rejections"] == {"missing_extra": 1} and health["tick_errors"] == 0
        client.laugh("laughter", 1.0, character="b")  # now refused on arrival, before any tick
        wait_until(
            lambda: httpx.get(f"{live.base_url}/api/health").json()["rejections"] == {"missing_extra": 2},
            what="the second laugh refused",
        )
    health = httpx.get(f"{live.base_url}/api/health").json()
    assert health["datagrams_accepted"] == 2 and health["datagrams_received"] == 3


def test_a_bug_hit_by_every_datagram_logs_once_per_interval(live, wait_until, monkeypatch, caplog) -> None:
    """A fault in handling (a bug, simulated) costs each datagram a counted rejection and the log one line per
    5 s, not one traceback per datagram (a flood would write megabytes a second)."""
    import mien.server.udp as udp_module

    def broken(data: bytes) -> object:
        raise RuntimeError("simulated bug")

    monkeypatch.setattr(udp_module, "parse_message", broken)
    counters = live.server.registry.counters
    before, rejected = counters.datagrams_received, counters.rejections["internal_error"]
    with caplog.at_level("WARNING", logger="mien.server"), socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        for _ in range(50):
            sock.sendto(b'{"AU12": 1}', ("127.0.0.1", live.udp_port))
        wait_until(lambda: counters.datagrams_received - before >= 50, what="50 datagrams read")
    faults = [r for r in caplog.records if "datagram handling failed" in r.getMessage()]
    assert len(faults) == 1 and faults[0].exc_info is not None and "simulated bug" in faults[0].getMessage()
    assert counters.rejections["internal_error"] - rejected >= 50
