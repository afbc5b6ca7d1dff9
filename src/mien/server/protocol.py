"""The live wire protocol: the one message parser and the binary frame format.

Messages (UDP datagrams and WebSocket text commands) are JSON objects. An OpenFACS message is the full
face state: ``{"AU1": 0, ..., "AU45": 0, "Speed": 0.05}``; a missing AU is 0. mien also accepts fractional
intensities and optional extensions that old clients never send:

=================  =====================================================================================
key                meaning
=================  =====================================================================================
``AU12``           intensity 0..5 of an AU (any face AU mien knows, not only the 18 of OpenFACS)
``AU12L``          one side of a lateral AU (``L``/``R``)
``Speed``          OpenFACS per-tick speed 0..1 at 60 Hz (mien turns it into a time constant)
``speeds``         ``{"AU12": 0.2}``: per-AU speed 0..1
``tau_s``          ``{"AU12": 0.3}``: per-AU time constant in seconds
``play``           ``{"au": "AU12", "intensity": 3, "onset_s": 0.4, "apex_s": 0.3, "offset_s": 0.3}``
``emotion``        an emotion or blend name (``"joy"``, ``"furious"``), with ``intensity`` 0..5 (default 1)
``pad``            ``[pleasure, arousal, dominance]``, each in -1..1
``laugh``          a laugh type (``"laughter"``), with ``intensity`` 0..5 (default 1)
``idle``           ``true``/``false`` (all idle behaviour on/off) or ``{"blink": false, "gaze": true, ...}``
``capture``        ``true``/``false``: follow the server's capture source (``mien serve --capture``) or stop
``say``            text to speak (espeak-ng), or ``{"text": "...", "language": "en", "rate_wpm": 175}``; at most
                   :data:`MAX_SAY_CHARS` characters (a UDP datagram: :data:`MAX_MESSAGE_BYTES` bytes)
``character``      the character id (default: the first character)
``watch``          WebSocket only: switch the stream to this character id
=================  =====================================================================================

A message with any AU key or ``Speed`` is a *state* message (full state: AUs not named go to 0). A message
with only extension keys leaves the held AUs alone. Any bad part rejects the whole message (the server keeps
the last good state) with a :class:`Rejection` reason.

Frames (server -> WebSocket viewers), little-endian, ``44 + 2 * n_weights`` bytes:

====== ======== ========================================================================
bytes  type     field
====== ======== ========================================================================
0-3    4 bytes  ``b"MIEN"``
4-5    uint16   version (1)
6-7    uint16   n_weights
8-11   uint32   tick
12-15  uint32   character row
16-23  float64  time_s (server clock, seconds)
24-43  5 float32 head yaw, pitch, roll, gaze yaw, pitch (degrees)
44..   float16  n_weights morph weights 0..1 in the order of the head's glTF ``targetNames`` (a user's head file:
                 up to 2.5 where mien drives a timid shape harder, see mien.heads.amplitude)
====== ======== ========================================================================
"""

from __future__ import annotations

import enum
import math
import re
import struct
from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from mien.affect.emotions import resolve_emotion
from mien.errors import MienError
from mien.extras import require
from mien.facs.catalogue import ACTION_UNITS, FACE_AU_CODES, FACE_CHANNELS, OPENFACS_AUS, POSE_CHANNELS, au_channels
from mien.facs.idle import IdleSettings
from mien.laughter.names import LAUGH_TYPES

__all__ = [
    "AU_CHANNELS",
    "AU_KEYS",
    "FRAME_HEADER_BYTES",
    "FRAME_MAGIC",
    "FRAME_VERSION",
    "MAX_MESSAGE_BYTES",
    "MAX_SAY_CHARS",
    "N_AU_CHANNELS",
    "OPENFACS_KEYS",
    "Frame",
    "Message",
    "MessageRejected",
    "PlayRequest",
    "Rejection",
    "SayRequest",
    "decode_frame",
    "encode_frame",
    "frame_bytes",
    "idle_parts",
    "parse_message",
]

MAX_MESSAGE_BYTES = 1024
"""Largest accepted message in bytes (the original OpenFACS server reads at most 1024 bytes a datagram)."""

MAX_SAY_CHARS = 400
"""Longest text of a ``say`` command, characters (about 25 s of speech at 175 words per minute): speech is
synthesised off the clock, but a long text holds the one TTS worker and its sound is kept in memory."""

OPENFACS_KEYS: tuple[str, ...] = (*(f"AU{code}" for code in OPENFACS_AUS), "Speed")
"""The keys of an OpenFACS message, in the order its client sends them."""


def _au_keys() -> frozenset[str]:
    keys: set[str] = set()
    for code in FACE_AU_CODES:
        keys.add(f"AU{code}")
        if ACTION_UNITS[code].lateral:
            keys.update((f"AU{code}L", f"AU{code}R"))
    return frozenset(keys)


AU_KEYS: frozenset[str] = _au_keys()
"""Every AU key a message may hold: ``AU<code>`` for each face AU, plus ``AU<code>L``/``R`` for lateral ones."""

N_AU_CHANNELS = len(FACE_CHANNELS) - len(POSE_CHANNELS)
"""AU channels at the start of a face frame (a state message sets all of them)."""

AU_CHANNELS: dict[str, tuple[int, ...]] = {
    key: au_channels(int(key[2:].rstrip("LR")), key[-1] if key[-1] in "LR" else None) for key in sorted(AU_KEYS)
}
"""AU key -> the face-frame channels it sets, resolved once (``"AU12"``: both sides; ``"AU12L"``: the left).

>>> [FACE_CHANNELS[i] for i in AU_CHANNELS["AU12"]], [FACE_CHANNELS[i] for i in AU_CHANNELS["AU12L"]]
(['AU12L', 'AU12R'], ['AU12L'])
"""

_EXTENSION_KEYS = frozenset(
    {"Speed", "speeds", "tau_s", "play", "emotion", "intensity", "pad", "laugh", "idle", "capture", "say"}
    | {"character", "watch"}
)
_OPENFACS_FAST_KEYS = AU_KEYS | {"Speed", "character"}
_NUMBER_TYPES = (int, float)  # JSON numbers; bool is excluded by the exact type test
_CHARACTER_ID = re.compile(r"^[A-Za-z0-9_.\-]{1,64}$")


class Rejection(enum.StrEnum):
    """Why a message was dropped (the keys of the health endpoint's ``rejections``)."""

    OVERSIZED = "oversized"
    MALFORMED_JSON = "malformed_json"
    NOT_OBJECT = "not_object"
    WRONG_TYPE = "wrong_type"
    UNKNOWN_AU = "unknown_au"
    UNKNOWN_FIELD = "unknown_field"
    OUT_OF_RANGE = "out_of_range"
    UNKNOWN_NAME = "unknown_name"
    UNKNOWN_CHARACTER = "unknown_character"
    MISSING_EXTRA = "missing_extra"
    NO_CAPTURE = "no_capture"
    TOO_LONG = "too_long"
    UNKNOWN_LANGUAGE = "unknown_language"
    NO_TTS = "no_tts"
    SPEECH_BUSY = "speech_busy"
    ENGINE_ERROR = "engine_error"
    INTERNAL_ERROR = "internal_error"


class MessageRejected(MienError):
    """A message was dropped: ``reason`` (a :class:`Rejection`) and a human ``detail`` naming the value."""

    def __init__(self, reason: Rejection, detail: str) -> None:
        self.reason = reason
        self.detail = detail
        super().__init__(f"{reason.value}: {detail}")


@dataclass(frozen=True)
class PlayRequest:
    """An AU played once with an onset/apex/offset envelope (seconds)."""

    au: str
    """AU key, e.g. ``"AU12"`` or ``"AU12L"``."""
    intensity: float
    """Apex intensity 0..5."""
    onset_s: float = 0.4
    """Onset duration, seconds."""
    apex_s: float = 0.3
    """Apex (hold) duration, seconds."""
    offset_s: float = 0.3
    """Offset duration, seconds."""


@dataclass(frozen=True)
class SayRequest:
    """Text for the character to speak (espeak-ng, off the clock; :mod:`mien.server.speech`)."""

    text: str
    """What to say, 1..:data:`MAX_SAY_CHARS` characters."""
    language: str = "en"
    """espeak-ng voice (``en``, ``en-us``, ``de``...)."""
    rate_wpm: int = 175
    """Speaking rate, words per minute (80..450)."""


@dataclass(frozen=True)
class Message:
    """One parsed message. ``None`` fields were not in the message."""

    aus: tuple[tuple[str, float], ...] | None = None
    """Full-state AU targets ``((key, intensity 0..5), ...)`` when this is a state message, else None (JSON
    integers stay ``int``)."""
    speed: float | None = None
    """OpenFACS Speed 0..1 per tick at 60 Hz."""
    speeds: tuple[tuple[str, float], ...] = ()
    """Per-AU speeds 0..1."""
    tau_s: tuple[tuple[str, float], ...] = ()
    """Per-AU time constants, seconds (>= 0)."""
    play: PlayRequest | None = None
    """An AU to play once."""
    emotion: str | None = None
    """Emotion or blend name (as given; the engine resolves aliases)."""
    laugh: str | None = None
    """Laugh or smile type (one of :data:`mien.laughter.names.LAUGH_TYPES`)."""
    intensity: float = 1.0
    """Intensity 0..5 of ``emotion`` and ``laugh``."""
    pad: tuple[float, float, float] | None = None
    """(pleasure, arousal, dominance), each in -1..1."""
    idle: tuple[tuple[str, bool], ...] | None = None
    """Idle switches to change, ``((part, on), ...)`` over :func:`idle_parts` (``true``/``false``: all parts)."""
    capture: bool | None = None
    """Follow the server's capture source (True) or stop (False)."""
    say: SayRequest | None = None
    """Text to speak."""
    character: str | None = None
    """Target character id; None = the default (first) character, or the one a WebSocket watches."""
    watch: str | None = None
    """WebSocket: switch the stream to this character id."""

    @classmethod
    def state(cls, aus: tuple[tuple[str, float], ...], speed: float | None, character: str | None = None) -> Message:
        """A plain state message, built without the dataclass ``__init__`` (the UDP hot path: the other fields
        keep their class-level defaults)."""
        message = object.__new__(cls)
        object.__setattr__(message, "aus", aus)
        object.__setattr__(message, "speed", speed)
        if character is not None:
            object.__setattr__(message, "character", character)
        return message

    @property
    def has_events(self) -> bool:
        """True when the message carries a one-off event (emotion, laugh, PAD, play) that must not be merged."""
        return (
            self.emotion is not None
            or self.laugh is not None
            or self.pad is not None
            or self.play is not None
            or self.idle is not None
            or self.capture is not None
            or self.say is not None
        )


def _number(key: str, value: Any, low: float, high: float) -> float:
    # bool is an int subclass; true/false are not intensities
    if type(value) is int or type(value) is float:
        number = float(value)
    else:
        shown = "null" if value is None else repr(value)  # a null is refused by name, never read as "not given"
        raise MessageRejected(Rejection.WRONG_TYPE, f"{key}={shown} is not a number"[:200])
    if not (low <= number <= high):  # also false for NaN
        raise MessageRejected(Rejection.OUT_OF_RANGE, f"{key}={value!r} is outside {low:g}..{high:g}")
    return number


def _au_map(key: str, value: Any, low: float, high: float) -> tuple[tuple[str, float], ...]:
    if not isinstance(value, dict):
        raise MessageRejected(Rejection.WRONG_TYPE, f"{key} must be an object of AU -> number, got {value!r}"[:200])
    items = []
    for au, number in value.items():
        if au not in AU_KEYS:
            raise MessageRejected(Rejection.UNKNOWN_AU, f"{key}[{au!r}] is not an AU mien knows")
        items.append((au, _number(f"{key}[{au}]", number, low, high)))
    return tuple(items)


def _name(key: str, value: Any) -> str:
    if not isinstance(value, str):
        shown = "null" if value is None else repr(value)
        raise MessageRejected(Rejection.WRONG_TYPE, f"{key}={shown} is not a string"[:200])
    return value


def _check_names(emotion: str | None, laugh: str | None) -> None:
    if emotion is not None:
        try:
            resolve_emotion(emotion)
        except MienError:
            raise MessageRejected(
                Rejection.UNKNOWN_NAME, f"emotion={emotion!r} is not a known emotion or blend"
            ) from None
    if laugh is not None:
        if laugh not in LAUGH_TYPES:
            raise MessageRejected(Rejection.UNKNOWN_NAME, f"laugh={laugh!r}: expected one of {', '.join(LAUGH_TYPES)}")


def _play(value: Any) -> PlayRequest:
    if not isinstance(value, dict):
        raise MessageRejected(Rejection.WRONG_TYPE, f"play must be an object, got {value!r}"[:200])
    unknown = set(value) - {"au", "intensity", "onset_s", "apex_s", "offset_s"}
    if unknown:
        raise MessageRejected(Rejection.UNKNOWN_FIELD, f"play has unknown keys {sorted(unknown)}")
    au = _name("play.au", value.get("au"))
    if au not in AU_KEYS:
        raise MessageRejected(Rejection.UNKNOWN_AU, f"play.au={au!r} is not an AU mien knows")
    return PlayRequest(
        au=au,
        intensity=_number("play.intensity", value.get("intensity", 3.0), 0.0, 5.0),
        onset_s=_number("play.onset_s", value.get("onset_s", 0.4), 0.0, 60.0),
        apex_s=_number("play.apex_s", value.get("apex_s", 0.3), 0.0, 60.0),
        offset_s=_number("play.offset_s", value.get("offset_s", 0.3), 0.0, 60.0),
    )


_IDLE_PARTS = tuple(f.name for f in fields(IdleSettings) if f.type in (bool, "bool"))


def idle_parts() -> tuple[str, ...]:
    """The on/off switches of :class:`mien.facs.idle.IdleSettings` (``blink``, ``mouth``, ...)."""
    return _IDLE_PARTS


def _idle(value: Any) -> tuple[tuple[str, bool], ...]:
    parts = idle_parts()
    if isinstance(value, bool):
        return tuple((part, value) for part in parts)
    if not isinstance(value, dict):
        raise MessageRejected(Rejection.WRONG_TYPE, f"idle={value!r} must be true, false or an object"[:200])
    switches = []
    for part, on in value.items():
        if part not in parts:
            raise MessageRejected(Rejection.UNKNOWN_FIELD, f"idle[{part[:40]!r}]: expected one of {', '.join(parts)}")
        if not isinstance(on, bool):
            raise MessageRejected(Rejection.WRONG_TYPE, f"idle[{part}]={on!r} must be true or false"[:200])
        switches.append((part, on))
    return tuple(switches)


_LANGUAGE = re.compile(r"^[A-Za-z]{2,3}(-[A-Za-z0-9]{1,8}){0,3}$")


def _say(value: Any) -> SayRequest:
    """``"text"`` or ``{"text", "language", "rate_wpm"}`` -> a :class:`SayRequest` (the language's voice is
    checked where the TTS runs: :meth:`mien.server.speech.SpeechService.check`)."""
    parts = {"text": value} if isinstance(value, str) else value
    if not isinstance(parts, dict):
        raise MessageRejected(Rejection.WRONG_TYPE, f"say={value!r} must be text or an object with text"[:200])
    unknown = set(parts) - {"text", "language", "rate_wpm"}
    if unknown:
        raise MessageRejected(Rejection.UNKNOWN_FIELD, f"say has unknown keys {sorted(unknown)}"[:200])
    text = _name("say.text", parts.get("text"))
    if len(text) > MAX_SAY_CHARS:
        raise MessageRejected(Rejection.TOO_LONG, f"say.text has {len(text)} characters > {MAX_SAY_CHARS}")
    if not text.strip():
        raise MessageRejected(Rejection.OUT_OF_RANGE, "say.text is empty: give some text to speak")
    language = _name("say.language", parts.get("language", "en"))
    if not _LANGUAGE.match(language):
        raise MessageRejected(Rejection.UNKNOWN_LANGUAGE, f"say.language={language[:40]!r} is no voice name (en, de)")
    rate = parts.get("rate_wpm", 175)
    if type(rate) is not int or not 80 <= rate <= 450:
        raise MessageRejected(Rejection.OUT_OF_RANGE, f"say.rate_wpm={rate!r}: words per minute, an integer 80..450")
    return SayRequest(text, language, rate)


def _character(key: str, value: Any) -> str:
    name = _name(key, value)
    if not _CHARACTER_ID.match(name):
        raise MessageRejected(Rejection.OUT_OF_RANGE, f"{key}={name[:80]!r}: ids are 1-64 of A-Z a-z 0-9 _ . -")
    return name


_JSON: tuple[Callable[[bytes], Any], type[Exception]] | None = None


def _json() -> tuple[Callable[[bytes], Any], type[Exception]]:
    global _JSON
    orjson = require("orjson", "serve")  # imported on first use, so the client needs no extra

    _JSON = (orjson.loads, orjson.JSONDecodeError)
    return _JSON


def parse_message(data: bytes | str, max_bytes: int = MAX_MESSAGE_BYTES) -> Message:
    """Parse one message (a datagram's bytes or a WebSocket text) into a :class:`Message`.

    Raises :class:`MessageRejected` with a :class:`Rejection` reason on any bad part.

    >>> m = parse_message(b'{"AU4": 5, "AU15": 3, "Speed": 0.05}')
    >>> m.aus, m.speed
    ((('AU4', 5), ('AU15', 3)), 0.05)
    >>> parse_message(b'{"AU4": "x"}')
    Traceback (most recent call last):
    ...
    mien.server.protocol.MessageRejected: wrong_type: AU4='x' is not a number
    """
    if isinstance(data, str):  # a WebSocket text message; the fast path below looks at the raw bytes
        data = data.encode("utf-8", "surrogatepass")  # a lone surrogate becomes malformed JSON, not a crash
    if len(data) > max_bytes:
        raise MessageRejected(Rejection.OVERSIZED, f"{len(data)} bytes > {max_bytes}")
    loads, decode_error = _JSON or _json()
    try:
        obj = loads(data)
    except decode_error as exc:
        raise MessageRejected(Rejection.MALFORMED_JSON, str(exc)[:200]) from None
    if not isinstance(obj, dict):
        raise MessageRejected(Rejection.NOT_OBJECT, f"expected a JSON object, got {type(obj).__name__}")
    if obj.keys() <= _OPENFACS_FAST_KEYS and b"true" not in data and b"false" not in data and b"null" not in data:
        # the common OpenFACS message (with a character id when many faces are driven), checked in bulk: min/max
        # raise TypeError on strings, lists and objects; booleans and null were ruled out on the raw bytes (AU
        # keys never contain those words; an id that does takes the full path, which refuses "Speed": null)
        speed = obj.pop("Speed", None)
        character = obj.pop("character", None)
        values = obj.values()
        try:
            ok = not obj or (min(values) >= 0.0 and max(values) <= 5.0)
        except TypeError:
            ok = False
        if (
            ok
            and (speed is None or (type(speed) in _NUMBER_TYPES and 0.0 <= speed <= 1.0))
            and (
                character is None  # an id alone is no state message: the full path
                or ((obj or speed is not None) and type(character) is str and _CHARACTER_ID.match(character))
            )
        ):
            return Message.state(tuple(obj.items()), speed, character)
        if speed is not None:
            obj["Speed"] = speed  # let the full check below name the bad value
        if character is not None:
            obj["character"] = character
    aus: list[tuple[str, float]] = []
    state = False
    extensions = []
    for key, value in obj.items():
        if key in AU_KEYS:
            state = True
            aus.append((key, _number(key, value, 0.0, 5.0)))
        elif key in _EXTENSION_KEYS:
            extensions.append(key)
        elif key.startswith("AU"):
            raise MessageRejected(Rejection.UNKNOWN_AU, f"{key[:40]!r} is not an AU mien knows")
        else:
            raise MessageRejected(Rejection.UNKNOWN_FIELD, f"unknown key {key[:40]!r}")
    if not extensions:  # the OpenFACS fast path
        return Message(aus=tuple(aus))
    fields: dict[str, Any] = {}
    for key in extensions:
        value = obj[key]
        if key == "Speed":
            state = True
            fields["speed"] = _number(key, value, 0.0, 1.0)
        elif key == "speeds":
            fields["speeds"] = _au_map(key, value, 0.0, 1.0)
        elif key == "tau_s":
            fields["tau_s"] = _au_map(key, value, 0.0, 3600.0)
        elif key == "play":
            fields["play"] = _play(value)
        elif key == "idle":
            fields["idle"] = _idle(value)
        elif key == "capture":
            if not isinstance(value, bool):
                raise MessageRejected(Rejection.WRONG_TYPE, f"capture={value!r} must be true or false"[:200])
            fields["capture"] = value
        elif key == "say":
            fields["say"] = _say(value)
        elif key in ("emotion", "laugh"):
            fields[key] = _name(key, value)
        elif key == "intensity":
            fields["intensity"] = _number(key, value, 0.0, 5.0)
        elif key == "pad":
            if not isinstance(value, list) or len(value) != 3:
                raise MessageRejected(
                    Rejection.WRONG_TYPE, f"pad={value!r} must be [pleasure, arousal, dominance]"[:200]
                )
            p, a, d = (_number(f"pad[{i}]", v, -1.0, 1.0) for i, v in enumerate(value))
            fields["pad"] = (p, a, d)
        else:  # character, watch
            fields[key] = _character(key, value)
    _check_names(fields.get("emotion"), fields.get("laugh"))
    return Message(aus=tuple(aus) if state else None, **fields)


FRAME_MAGIC = b"MIEN"
"""First four bytes of every frame."""
FRAME_VERSION = 1
"""Frame format version."""
_HEADER = struct.Struct("<4sHHIId5f")
FRAME_HEADER_BYTES = _HEADER.size
"""Bytes before the weights (44)."""


def frame_bytes(n_weights: int) -> int:
    """Size of one frame in bytes: 44 + 2 * n_weights (52 targets of the built-in head: 148 bytes).

    >>> frame_bytes(52)
    148
    """
    return FRAME_HEADER_BYTES + 2 * n_weights


@dataclass(frozen=True)
class Frame:
    """One decoded frame."""

    tick: int
    """Server tick number."""
    row: int
    """The character's row in the server's batch."""
    time_s: float
    """Server clock, seconds."""
    pose_deg: tuple[float, float, float, float, float]
    """Head yaw, pitch, roll, gaze yaw, pitch, degrees."""
    weights: np.ndarray
    """(n_weights,) float32 morph weights 0..1 in the head's target order."""


def encode_frame(tick: int, row: int, time_s: float, pose_deg: np.ndarray, weights: np.ndarray) -> bytes:
    """One frame: ``pose_deg`` (5,) degrees, ``weights`` (n_weights,) 0..1 -> ``44 + 2 n_weights`` bytes.

    >>> data = encode_frame(7, 0, 0.5, np.zeros(5), np.array([0.0, 0.5, 1.0]))
    >>> len(data), decode_frame(data).weights.tolist()
    (50, [0.0, 0.5, 1.0])
    """
    yaw, pitch, roll, gaze_yaw, gaze_pitch = (float(v) for v in pose_deg)
    header = _HEADER.pack(
        FRAME_MAGIC, FRAME_VERSION, len(weights), tick & 0xFFFFFFFF, row, time_s, yaw, pitch, roll, gaze_yaw, gaze_pitch
    )
    return header + np.asarray(weights, dtype="<f2").tobytes()


def decode_frame(data: bytes) -> Frame:
    """Decode a frame made by :func:`encode_frame` (raises :class:`~mien.errors.MienError` if it is not one)."""
    if len(data) < FRAME_HEADER_BYTES:
        raise MienError(f"a frame has at least {FRAME_HEADER_BYTES} bytes, got {len(data)}")
    magic, version, n, tick, row, time_s, *pose = _HEADER.unpack_from(data)
    if magic != FRAME_MAGIC or version != FRAME_VERSION:
        raise MienError(f"not a mien frame (magic {magic!r}, version {version})")
    if len(data) != frame_bytes(n):
        raise MienError(f"frame of {n} weights must have {frame_bytes(n)} bytes, got {len(data)}")
    weights = np.frombuffer(data, dtype="<f2", offset=FRAME_HEADER_BYTES, count=n).astype(np.float32)
    if not all(math.isfinite(v) for v in pose):
        raise MienError("frame pose is not finite")
    return Frame(tick, row, time_s, (pose[0], pose[1], pose[2], pose[3], pose[4]), weights)
