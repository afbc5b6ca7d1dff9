"""The one message parser (with a hypothesis fuzz) and the binary frame format."""

from __future__ import annotations

import json

import numpy as np
import orjson
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mien.client import openfacs_message
from mien.server.protocol import (
    AU_KEYS,
    MAX_MESSAGE_BYTES,
    OPENFACS_KEYS,
    Message,
    MessageRejected,
    Rejection,
    decode_frame,
    encode_frame,
    frame_bytes,
    parse_message,
)


def test_openfacs_message_is_parsed_as_full_state() -> None:
    data = b'{"AU1": 0, "AU2": 0, "AU4": 5, "AU5": 3, "AU6": 0, "AU7": 0, "AU9": 0, "AU10": 0, "AU12": 0, '
    data += b'"AU14": 0, "AU15": 3, "AU17": 3, "AU20": 0, "AU23": 0, "AU25": 0, "AU26": 0, "AU28": 0, "AU45": 0, '
    data += b'"Speed": 0.05}'
    assert 200 <= len(data) <= 215  # about 205 bytes, as the issue says
    message = parse_message(data)
    assert message.aus is not None and dict(message.aus)["AU4"] == 5.0 and len(message.aus) == 18
    assert message.speed == 0.05 and not message.has_events and message.character is None


def test_client_builds_the_original_key_order() -> None:
    data = openfacs_message({"AU12": 3, "AU4": 1.5}, speed=0.1)
    assert tuple(json.loads(data)) == OPENFACS_KEYS
    assert json.loads(data)["AU12"] == 3 and b'"AU12": 3,' in data  # integers stay integers


def test_extensions() -> None:
    message = parse_message(
        b'{"AU12L": 2.5, "speeds": {"AU12L": 0.2}, "tau_s": {"AU4": 0.3}, "emotion": "happy", "intensity": 1.2,'
        b' "pad": [0.5, -0.2, 0.1], "laugh": "laughter", "character": "alice",'
        b' "play": {"au": "AU45", "intensity": 5, "onset_s": 0.1}}'
    )
    assert message.aus == (("AU12L", 2.5),) and message.speed is None
    assert message.speeds == (("AU12L", 0.2),) and message.tau_s == (("AU4", 0.3),)
    assert message.emotion == "happy" and message.intensity == 1.2 and message.laugh == "laughter"
    assert message.pad == (0.5, -0.2, 0.1) and message.character == "alice" and message.has_events
    assert message.play is not None and message.play.au == "AU45" and message.play.onset_s == 0.1
    assert parse_message(b'{"idle": {"blink": false, "gaze": true}}').idle == (("blink", False), ("gaze", True))
    assert dict(parse_message(b'{"idle": false}').idle or ()) == dict.fromkeys(
        ("blink", "mouth", "eyelids", "neck", "gaze", "wobble"), False
    )
    assert parse_message(b'{"emotion": "joy"}').aus is None  # events alone leave the held AUs alone
    assert parse_message(b"{}") == Message(aus=())  # an empty OpenFACS state: every AU to 0


@pytest.mark.parametrize(
    ("data", "reason"),
    [
        (b"{not json", Rejection.MALFORMED_JSON),
        (b"\xff\xfe\x00garbage", Rejection.MALFORMED_JSON),
        (b"[1, 2]", Rejection.NOT_OBJECT),
        (b'"AU12"', Rejection.NOT_OBJECT),
        (b'{"AU12": "3"}', Rejection.WRONG_TYPE),
        (b'{"AU12": true}', Rejection.WRONG_TYPE),
        (b'{"AU12": null}', Rejection.WRONG_TYPE),
        (b'{"AU99": 1}', Rejection.UNKNOWN_AU),
        (b'{"AU12X": 1}', Rejection.UNKNOWN_AU),
        (b'{"speeds": {"AU3": 0.1}}', Rejection.UNKNOWN_AU),
        (b'{"foo": 1}', Rejection.UNKNOWN_FIELD),
        (b'{"AU12": 5.5}', Rejection.OUT_OF_RANGE),
        (b'{"AU12": -1}', Rejection.OUT_OF_RANGE),
        (b'{"AU12": 1e400}', Rejection.MALFORMED_JSON),  # orjson refuses infinities
        (b'{"Speed": 2}', Rejection.OUT_OF_RANGE),
        (b'{"pad": [2, 0, 0]}', Rejection.OUT_OF_RANGE),
        (b'{"pad": [0, 0]}', Rejection.WRONG_TYPE),
        (b'{"character": "a b"}', Rejection.OUT_OF_RANGE),
        (b'{"emotion": "bliss"}', Rejection.UNKNOWN_NAME),
        (b'{"laugh": "guffaw"}', Rejection.UNKNOWN_NAME),
        (b'{"play": {"au": "AU12", "when": 1}}', Rejection.UNKNOWN_FIELD),
        (b'{"idle": {"sneeze": true}}', Rejection.UNKNOWN_FIELD),
        (b'{"idle": {"blink": 1}}', Rejection.WRONG_TYPE),
        (b'{"idle": "off"}', Rejection.WRONG_TYPE),
        (b" " * (MAX_MESSAGE_BYTES + 1), Rejection.OVERSIZED),
    ],
)
def test_rejections_name_their_reason(data: bytes, reason: Rejection) -> None:
    with pytest.raises(MessageRejected) as caught:
        parse_message(data)
    assert caught.value.reason is reason
    assert caught.value.detail


_json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-10, 10) | st.floats(allow_nan=False) | st.text(max_size=8),
    lambda children: st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=6), children, max_size=4),
    max_leaves=12,
)
_keys = st.sampled_from([*sorted(AU_KEYS), "Speed", "emotion", "pad", "laugh", "character", "speeds", "x"])


@settings(max_examples=300, deadline=None)
@given(
    st.one_of(
        st.binary(max_size=300),
        st.text(max_size=100),
        st.dictionaries(_keys, _json_values, max_size=6).map(orjson.dumps),
    )
)
def test_fuzz_parse_message_returns_a_message_or_a_typed_rejection(data: bytes | str) -> None:
    try:
        message = parse_message(data)
    except MessageRejected as exc:
        assert isinstance(exc.reason, Rejection)
        return
    assert isinstance(message, Message)
    for key, value in message.aus or ():
        assert key in AU_KEYS and 0.0 <= value <= 5.0
    assert message.speed is None or 0.0 <= message.speed <= 1.0


@settings(max_examples=100, deadline=None)
@given(st.dictionaries(st.sampled_from(sorted(AU_KEYS)), st.floats(0.0, 5.0), max_size=10), st.floats(0.0, 1.0))
def test_fuzz_valid_states_round_trip(aus: dict[str, float], speed: float) -> None:
    message = parse_message(openfacs_message(aus, speed))
    assert message.speed == speed
    parsed = dict(message.aus or ())
    assert all(parsed[key] == value for key, value in aus.items())


def test_frame_layout_is_fixed() -> None:
    weights = np.linspace(0.0, 1.0, 52)
    pose = np.array([10.0, -5.0, 2.5, 3.0, -1.0])
    data = encode_frame(1234, 7, 12.5, pose, weights)
    assert len(data) == frame_bytes(52) == 44 + 2 * 52
    assert data[:4] == b"MIEN" and data[4:6] == (1).to_bytes(2, "little") and data[6:8] == (52).to_bytes(2, "little")
    assert int.from_bytes(data[8:12], "little") == 1234 and int.from_bytes(data[12:16], "little") == 7
    assert np.frombuffer(data[16:24], "<f8")[0] == 12.5
    assert np.allclose(np.frombuffer(data[24:44], "<f4"), pose)
    frame = decode_frame(data)
    assert frame.tick == 1234 and frame.row == 7 and frame.time_s == 12.5 and frame.pose_deg[0] == 10.0
    assert np.abs(frame.weights - weights).max() < 1e-3  # float16
    with pytest.raises(Exception, match="frame"):
        decode_frame(data[:-1])


def test_openfacs_message_with_a_character_id_is_a_state_message() -> None:
    message = parse_message(openfacs_message({"AU12": 3, "AU6L": 1.5}, 0.05, character="c7"))
    assert message.character == "c7" and message.speed == 0.05 and not message.has_events
    assert message.aus is not None and len(message.aus) == 19 and dict(message.aus)["AU12"] == 3
    assert dict(message.aus)["AU6L"] == 1.5 and dict(message.aus)["AU4"] == 0
    assert parse_message(b'{"character": "c7"}').aus is None  # an id alone changes no state
    assert parse_message(b'{"Speed": 1, "character": "c7"}').aus == ()  # Speed alone is a full state
    for data, reason in (
        (b'{"AU12": 3, "character": "b c"}', Rejection.OUT_OF_RANGE),
        (b'{"AU12": 3, "character": 5}', Rejection.WRONG_TYPE),
        (b'{"AU12": 3, "character": true}', Rejection.WRONG_TYPE),
        (b'{"AU12": 9, "character": "b"}', Rejection.OUT_OF_RANGE),
        (b'{"AU12": 1, "Speed": 2, "character": "b"}', Rejection.OUT_OF_RANGE),
    ):
        with pytest.raises(MessageRejected) as caught:
            parse_message(data)
        assert caught.value.reason is reason, data
