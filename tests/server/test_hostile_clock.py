"""Issue 29 case 1 and health: a refused character changes nothing, a failing character is quarantined while the
others keep moving, and ``/api/health`` says ``degraded`` while ticks fail or run late."""

from __future__ import annotations

import logging
import socket
import sys
import threading
import time

import httpx
import numpy as np
import pytest

from mien.character import CharacterBatch
from mien.errors import InvalidValueError
from mien.facs.catalogue import FACE_CHANNELS
from mien.facs.clip import Clip
from mien.server.protocol import MessageRejected, parse_message
from mien.server.registry import CharacterSpec, Registry

AU12L = FACE_CHANNELS.index("AU12L")


class _FailingClip(Clip):
    """A face clip whose every sample raises, as a reader bug or a hostile file might."""

    def sample(self, t_s: float) -> np.ndarray:
        raise RuntimeError("sample exploded")


def _failing_clip() -> Clip:
    return _FailingClip(np.zeros((10, len(FACE_CHANNELS))), 60.0, FACE_CHANNELS)


def _registry() -> Registry:
    registry = Registry()
    for character_id in ("a", "b", "c"):
        registry.add(CharacterSpec(character_id, head="builtin", idle=False))
    return registry


def _smile(registry: Registry, character_id: str) -> None:
    registry.submit(parse_message(f'{{"character": "{character_id}", "AU12": 4, "Speed": 1}}'.encode()))


def test_a_seed_past_uint64_is_refused_before_any_row_changes() -> None:
    batch = CharacterBatch(0)
    a = batch.add_character(seed=1, idle=False)
    freed = batch.add_character(seed=2, idle=False)
    batch.remove_character(freed)
    for seed in (2**64, -1, 1.5, True):
        with pytest.raises(InvalidValueError, match="seed"):
            batch.add_character(seed=seed)
    assert batch.n_characters == 2 and batch.active_rows().tolist() == [a]
    assert batch.facs.target.shape[0] == batch.idle.n_rows == batch.seeds.shape[0] == 2
    batch.set_aus(a, {"AU12": 4.0}, speed=1.0)
    assert batch.step(1 / 60)[a, AU12L] == 4.0  # the batch still steps
    # the whole uint64 range is a seed, kept exactly (it was a float64 past 2**63)
    top = batch.add_character(seed=2**64 - 1)
    assert batch.seeds.dtype == np.uint64 and int(batch.seeds[top]) == 2**64 - 1 == int(batch.idle.seeds[top])
    batch.step(2 / 60)


def test_a_spec_with_a_seed_past_uint64_is_refused() -> None:
    with pytest.raises(InvalidValueError, match="seed"):
        CharacterSpec("x", seed=2**64)
    with pytest.raises(InvalidValueError, match="idle"):
        CharacterSpec("x", idle="yes")  # type: ignore[arg-type]


def test_create_with_a_seed_past_uint64_is_a_400_and_the_clock_keeps_moving(live, wait_until) -> None:
    url = live.base_url
    response = httpx.post(f"{url}/api/characters", json={"id": "big", "head": "builtin", "seed": 2**64})
    assert response.status_code == 400 and "seed" in response.json()["detail"]
    assert [c["id"] for c in httpx.get(f"{url}/api/characters").json()] == ["a", "b"]
    ticks = httpx.get(f"{url}/api/health").json()["ticks"]
    assert httpx.post(f"{url}/api/characters/a/aus", json={"aus": {"AU12": 4}, "speed": 1}).status_code == 202
    wait_until(lambda: httpx.get(f"{url}/api/characters/a").json()["aus"]["AU12L"] == 4.0, what="a smiles")
    health = wait_until(lambda: (h := httpx.get(f"{url}/api/health").json())["ticks"] > ticks + 30 and h)
    assert health["tick_errors"] == 0 and health["step_failures"] == 0 and not health["quarantined"]
    assert "tick_errors" not in health["degraded"]  # ("late_ticks" is the machine's business)
    # the largest seed is a character like any other
    response = httpx.post(f"{url}/api/characters", json={"id": "top", "head": "builtin", "seed": 2**64 - 1})
    assert response.status_code == 201 and response.json()["seed"] == 2**64 - 1


def test_a_failing_character_is_quarantined_and_the_others_keep_moving(caplog) -> None:
    registry = _registry()
    registry.step(0.0)
    registry.entries["b"].clips.append(_failing_clip())
    _smile(registry, "a")
    _smile(registry, "c")
    with caplog.at_level(logging.WARNING, logger="mien.server"):
        for tick in range(1, 61):  # one second of ticks
            frames = registry.step(tick / 60)
    a, c = registry.get("a"), registry.get("c")
    assert frames[a.row, AU12L] == 4.0 and frames[c.row, AU12L] == 4.0
    assert list(registry.entries) == ["a", "c"] and "sample exploded" in registry.quarantined["b"]
    assert registry.counters.step_failures == 1 and registry.counters.quarantined == 1
    logged = [r.getMessage() for r in caplog.records]
    assert len(logged) == 2 and "b quarantined" in logged[1]  # the fault and the quarantine, not a line per tick
    with pytest.raises(MessageRejected, match="quarantined"):
        _smile(registry, "b")
    with pytest.raises(InvalidValueError, match="DELETE"):
        registry.add(CharacterSpec("b", head="builtin"))
    registry.remove("b")  # DELETE frees the id
    b = registry.add(CharacterSpec("b", head="builtin", idle=False))
    _smile(registry, "b")
    assert registry.step(61 / 60)[b.row, AU12L] == 4.0


def test_a_batch_no_single_character_explains_is_rebuilt() -> None:
    registry = _registry()
    registry.step(0.0)
    registry.batch.facs.add_rows(1)  # what a half-added character left behind: a layer one row longer
    _smile(registry, "a")
    frames = registry.step(1 / 60)
    assert registry.counters.rebuilds == 1 and not registry.quarantined
    assert list(registry.entries) == ["a", "b", "c"] and frames.shape[0] == 3
    _smile(registry, "c")
    frames = registry.step(2 / 60)
    assert frames[registry.get("c").row, AU12L] == 4.0 and registry.counters.step_failures == 1


def test_health_is_degraded_while_ticks_fail(live, wait_until, caplog) -> None:
    def explode(tick: int, t_s: float) -> None:
        raise RuntimeError("listener exploded")

    url = live.base_url
    assert "tick_errors" not in httpx.get(f"{url}/api/health").json()["degraded"]
    with caplog.at_level(logging.WARNING, logger="mien.server"):
        live.call(live.server.clock.listeners.append, explode)
        wait_until(lambda: httpx.get(f"{url}/api/health").json()["tick_errors"] >= 60, what="a second of failures")
        live.call(live.server.clock.listeners.remove, explode)
    health = httpx.get(f"{url}/api/health").json()
    assert health["status"] == "degraded" and "tick_errors" in health["degraded"]
    assert sum("listener exploded" in r.getMessage() for r in caplog.records) == 1  # rate-limited


def test_health_is_degraded_while_ticks_run_late(live) -> None:
    url = live.base_url
    live.call(time.sleep, 0.5)  # the loop stalls half a second: about 30 ticks skipped
    health = httpx.get(f"{url}/api/health").json()
    assert health["status"] == "degraded" and "late_ticks" in health["degraded"]
    assert "tick_errors" not in health["degraded"] and not health["quarantined"]
    assert health["skipped_ticks"] >= 20


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the OS reports its UDP drops in /proc on Linux")
def test_health_counts_the_datagrams_the_os_dropped(live, wait_until) -> None:
    url = live.base_url
    assert httpx.get(f"{url}/api/health").json()["datagrams_dropped_by_os"] == 0
    sender = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    datagram = b'{"AU12": 1, "Speed": 0.5, "pad": "' + b"x" * 900 + b'"}'
    stall = threading.Thread(target=live.call, args=(time.sleep, 1.0))  # the loop stops reading for 1 s
    try:
        stall.start()
        time.sleep(0.1)
        for _ in range(20_000):  # far more than a 4 MiB receive buffer holds
            sender.sendto(datagram, ("127.0.0.1", live.udp_port))
    finally:
        stall.join()
        sender.close()

    def all_counted() -> dict | None:
        health = httpx.get(f"{url}/api/health").json()
        return health if health["datagrams_received"] + health["datagrams_dropped_by_os"] == 20_000 else None

    health = wait_until(all_counted, what="every datagram received or counted as dropped")
    assert health["datagrams_dropped_by_os"] > 0
