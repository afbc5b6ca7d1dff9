"""The server core without sockets: registry + clock ticks driven by hand (deterministic)."""

from __future__ import annotations

from typing import NoReturn

import numpy as np
import orjson
import pytest

from mien.character import CharacterBatch
from mien.client import openfacs_message
from mien.errors import MissingExtraError
from mien.facs.catalogue import FACE_CHANNELS
from mien.server.protocol import AU_KEYS, Message, MessageRejected, Rejection, decode_frame, parse_message
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


def _per_au_reference(batch: CharacterBatch, row: int, message: Message) -> None:
    """The per-AU path the registry used before state messages were written in one go (the reference)."""
    aus = dict(message.aus or ())
    batch.set_aus(row, aus, replace=True)
    if message.speed is not None:
        batch.set_speed(row, message.speed)
    for au, speed in message.speeds:
        batch.set_speed(row, speed, au=au)
    for au, tau_s in message.tau_s:
        batch.set_au(row, au, aus.get(au, 0.0), tau_s=tau_s)


def _random_state(rng: np.random.Generator, character: str) -> bytes:
    keys = sorted(AU_KEYS)
    picked = rng.choice(keys, size=int(rng.integers(0, 8)), replace=False).tolist()
    aus = {key: int(rng.integers(0, 6)) if rng.random() < 0.3 else round(float(rng.uniform(0, 5)), 3) for key in picked}
    extensions: dict[str, object] = {"character": character}
    if rng.random() < 0.15:
        extensions["speeds"] = {str(rng.choice(keys)): round(float(rng.uniform(0, 1)), 3)}
    if rng.random() < 0.15:
        extensions["tau_s"] = {str(rng.choice(keys)): round(float(rng.uniform(0, 0.5)), 3)}
    speed = [0.05, 0.2, 1, 0, round(float(rng.uniform(0, 1)), 4)][int(rng.integers(0, 5))]
    if rng.random() < 0.2:  # no Speed: the held time constants stay
        return orjson.dumps({**aus, **extensions})
    return openfacs_message(aus, speed, **extensions)


def test_state_messages_give_the_frames_of_the_per_au_path() -> None:
    ids = [f"c{i}" for i in range(7)]
    registry = Registry()
    reference = CharacterBatch(0)
    for i, character_id in enumerate(ids):
        entry = registry.add(CharacterSpec(character_id, head="builtin", seed=i, idle=i % 2 == 0))
        assert reference.add_character(seed=i, idle=i % 2 == 0) == entry.row
    rng = np.random.default_rng(27)
    moved = 0.0
    for tick in range(240):
        t_s = tick / 60
        newest: dict[str, Message] = {}
        for _ in range(int(rng.integers(0, 12))):  # some characters get several messages: the newest counts
            message = parse_message(_random_state(rng, str(rng.choice(ids))))
            registry.submit(message)
            if message.aus is not None:  # a state message (extensions alone change no held state)
                newest[message.character or ids[0]] = message
        for character_id, message in newest.items():
            _per_au_reference(reference, registry.get(character_id).row, message)
        frames = registry.step(t_s)
        expected = reference.step(t_s)
        assert np.array_equal(frames, expected), (tick, np.abs(frames - expected).max())
        moved = max(moved, float(frames[:, : len(FACE_CHANNELS) - 5].max()))
    assert moved > 4.0  # the sequence drove the faces
    assert registry.counters.rejections == {}


def _no_laughter_extra(*args: object, **kwargs: object) -> NoReturn:
    raise MissingExtraError("scipy", "laughter")  # what the library raises on an install without the extra


def test_a_missing_extra_costs_one_message_not_the_tick(monkeypatch: pytest.MonkeyPatch) -> None:
    registry = _registry("a", "b")
    registry.step(0.0)
    monkeypatch.setattr(registry.batch, "laugh", _no_laughter_extra)
    registry.submit(parse_message(b'{"laugh": "laughter", "character": "a"}'))
    registry.submit(parse_message(b'{"emotion": "joy", "character": "a"}'))
    registry.submit(parse_message(openfacs_message({"AU12": 4}, 1, character="b")))
    frames = registry.step(0.5)
    assert registry.counters.rejections == {"missing_extra": 1}
    assert frames[1, AU12L] == 4.0  # the tick ran for every character
    frames = registry.step(1.0)
    assert frames[0, AU12L] > 0.5  # and the laugh's own character got its next event (joy, started at 0.5)
    assert "mien[laughter]" in registry.missing["laugh"]
    with pytest.raises(MessageRejected) as caught:  # the next laugh is refused on arrival, with the fix
        registry.submit(parse_message(b'{"laugh": "laughter", "intensity": 2, "character": "b"}'))
    assert caught.value.reason is Rejection.MISSING_EXTRA and "pip install 'mien[laughter]'" in caught.value.detail


def test_a_raw_import_error_is_reported_as_the_extra_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    def scipy_missing(*args: object, **kwargs: object) -> NoReturn:
        raise ModuleNotFoundError("No module named 'scipy'", name="scipy.ndimage")

    registry = _registry("a")
    monkeypatch.setattr(registry.batch, "laugh", scipy_missing)
    registry.submit(parse_message(b'{"laugh": "sly_smile"}'))
    registry.step(0.1)
    assert registry.counters.rejections == {"missing_extra": 1}
    assert registry.missing == {"laugh": "scipy is needed for this; install it with: pip install 'mien[laughter]'"}


def test_warm_up_generates_a_laugh_before_the_clock_or_records_the_missing_extra(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    calls: list[str] = []
    real_laugh = CharacterBatch.laugh

    def counted(self: CharacterBatch, rows: object, laugh_type: str, *args: object, **kwargs: object) -> object:
        calls.append(laugh_type)
        return real_laugh(self, rows, laugh_type, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(CharacterBatch, "laugh", counted)
    registry = _registry("a")
    registry.warm_up()
    assert calls == ["laughter"] and registry.missing == {}
    assert registry.batch.time_s == 0.0 and not registry.batch._laughs  # the characters were not touched
    monkeypatch.setattr(CharacterBatch, "laugh", _no_laughter_extra)
    bare = _registry("a")
    bare.warm_up()
    assert list(bare.missing) == ["laugh"]
    with pytest.raises(MessageRejected) as caught:
        bare.submit(parse_message(b'{"laugh": "laughter"}'))
    assert caught.value.reason is Rejection.MISSING_EXTRA
    bare.submit(parse_message(b'{"emotion": "joy"}'))  # everything else is still served
