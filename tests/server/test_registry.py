"""The server core without sockets: registry + clock ticks driven by hand (deterministic)."""

from __future__ import annotations

import numpy as np
import pytest

from mien.client import openfacs_message
from mien.facs.catalogue import FACE_CHANNELS
from mien.server.protocol import MessageRejected, Rejection, decode_frame, parse_message
from mien.server.registry import CharacterSpec, Registry
from mien.server.scheduler import Clock
from mien.server.websocket import Hub, Viewer

AU12L = FACE_CHANNELS.index("AU12L")


def _registry(*ids: str) -> Registry:
    registry = Registry()
    for i, character_id in enumerate(ids):
        registry.add(CharacterSpec(character_id, head="builtin", seed=i, idle=False))
    return registry


@pytest.mark.parametrize("tick_hz", [60.0, 24.0, 144.0])
def test_speed_is_the_same_motion_at_any_tick_rate(tick_hz: float) -> None:
    registry = _registry("a")
    clock = Clock(registry, tick_hz)
    clock.run_tick(0, 0.0)
    registry.submit(parse_message(openfacs_message({"AU12": 5}, 0.05)))
    for k in range(1, int(tick_hz) + 1):  # one second
        clock.run_tick(k, k / tick_hz)
        expected = 5.0 * (1.0 - 0.95 ** (60.0 * k / tick_hz))
        assert registry.frames[0, AU12L] == pytest.approx(expected, abs=1e-9)
    assert registry.frames[0, AU12L] > 0.95 * 5  # 95 % is reached at about 0.97 s


def test_newest_state_wins_and_no_event_is_lost() -> None:
    registry = _registry("a", "b")
    registry.step(0.0)
    for value in (1, 2, 3):
        registry.submit(parse_message(openfacs_message({"AU12": value}, 1)))
    registry.submit(parse_message(b'{"emotion": "joy", "character": "b"}'))
    registry.submit(parse_message(b'{"emotion": "anger", "character": "b"}'))
    assert registry.counters.coalesced == 2 and len(registry.get("b").events) == 2
    frames = registry.step(0.5)  # commands apply at this tick; events start now
    assert frames[0, AU12L] == 3.0
    frames = registry.step(1.0)  # in the hold of both events (0.4 s onset, 0.3 s hold)
    assert frames[1, FACE_CHANNELS.index("AU4L")] > 0.5 and frames[1, AU12L] > 0.5  # anger and joy both played
    with pytest.raises(MessageRejected) as caught:
        registry.submit(parse_message(b'{"AU1": 1, "character": "c"}'))
    assert caught.value.reason is Rejection.UNKNOWN_CHARACTER


def test_removed_rows_are_reused_and_viewers_get_the_right_row() -> None:
    registry = _registry("a", "b", "c")
    registry.remove("b")
    entry = registry.add(CharacterSpec("d", head="builtin", idle=False))
    assert entry.row == 1 and list(registry.entries) == ["a", "c", "d"]
    hub = Hub(registry)
    viewer = Viewer("d")
    hub.viewers.add(viewer)
    registry.submit(parse_message(openfacs_message({"AU12": 5}, 1, character="d")))
    registry.step(1 / 60)
    hub.on_tick(1, 1 / 60)
    assert viewer.latest is not None
    frame = decode_frame(viewer.latest)
    smile = list(entry.rig.target_names).index("mouthSmileLeft")
    assert frame.row == 1 and frame.weights[smile] == 1.0 and frame.tick == 1
    hub.on_tick(2, 2 / 60)  # the viewer did not take the first frame: only the newest is kept
    assert decode_frame(viewer.latest).tick == 2 and registry.counters.frames_dropped == 1
    assert np.all(registry.frames[2] >= 0)
