"""Text to speech with espeak-ng through its C library, ``libespeak-ng``, with the timing of every phoneme.

The command line ``espeak-ng`` gives no timing, so mien loads the library with :mod:`ctypes` and initialises
it for phoneme events (``espeakINITIALIZE_PHONEME_EVENTS``): in retrieval mode the synthesis callback gets
the audio in blocks and, with them, an ``espeakEVENT_PHONEME`` per phoneme carrying its mnemonic and its
position in the audio (``sample``, at the library's sample rate). A phoneme lasts until the next event. The
library is process-global and not thread-safe: one lock serialises its use.

Install it with Debian/Ubuntu ``apt install libespeak-ng1`` (or ``espeak-ng``), macOS ``brew install
espeak-ng``. API reference: espeak-ng ``src/include/espeak-ng/speak_lib.h``.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import threading
from functools import cache
from typing import Any

import numpy as np

from mien.errors import InvalidValueError, MissingAssetError, UnknownNameError
from mien.speech.coarticulation import coarticulate
from mien.speech.phonemes import viseme_of
from mien.speech.track import Audio, Segment, Utterance

__all__ = ["DEFAULT_LANGUAGE", "MAX_TEXT_CHARS", "speak", "synthesize", "voices"]

DEFAULT_LANGUAGE = "en"
"""espeak-ng voice used when none is named."""

MAX_TEXT_CHARS = 10_000
"""Longest text one call speaks (about ten minutes of speech)."""

_AUDIO_OUTPUT_RETRIEVAL = 1
_INITIALIZE_PHONEME_EVENTS = 0x0001
_INITIALIZE_DONT_EXIT = 0x8000
_CHARS_UTF8 = 1
_POS_CHARACTER = 1
_EVENT_LIST_TERMINATED = 0
_EVENT_PHONEME = 7
_EE_OK = 0
_LIBRARY_NAMES = ("espeak-ng", "libespeak-ng.so.1", "libespeak-ng.dylib")

_LOCK = threading.Lock()


class _EventId(ctypes.Union):
    _fields_ = [("number", ctypes.c_int), ("name", ctypes.c_char_p), ("string", ctypes.c_char * 8)]


class _Event(ctypes.Structure):
    _fields_ = [
        ("type", ctypes.c_int),
        ("unique_identifier", ctypes.c_uint),
        ("text_position", ctypes.c_int),
        ("length", ctypes.c_int),
        ("audio_position", ctypes.c_int),
        ("sample", ctypes.c_int),
        ("user_data", ctypes.c_void_p),
        ("id", _EventId),
    ]


class _Voice(ctypes.Structure):
    _fields_ = [
        ("name", ctypes.c_char_p),
        ("languages", ctypes.c_char_p),
        ("identifier", ctypes.c_char_p),
        ("gender", ctypes.c_ubyte),
        ("age", ctypes.c_ubyte),
        ("variant", ctypes.c_ubyte),
        ("xx1", ctypes.c_ubyte),
        ("score", ctypes.c_int),
        ("spare", ctypes.c_void_p),
    ]


_CALLBACK = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.POINTER(ctypes.c_short), ctypes.c_int, ctypes.POINTER(_Event))


class _Engine:
    """The loaded library, initialised once, and the buffers its callback fills."""

    def __init__(self, library: ctypes.CDLL) -> None:
        self.library = library
        library.espeak_Initialize.restype = ctypes.c_int
        library.espeak_SetVoiceByName.argtypes = [ctypes.c_char_p]
        library.espeak_ListVoices.restype = ctypes.POINTER(ctypes.POINTER(_Voice))
        library.espeak_Synth.argtypes = [
            ctypes.c_void_p, ctypes.c_size_t, ctypes.c_uint, ctypes.c_int, ctypes.c_uint, ctypes.c_uint,
            ctypes.c_void_p, ctypes.c_void_p,
        ]  # fmt: skip
        self.sample_rate = int(
            library.espeak_Initialize(
                _AUDIO_OUTPUT_RETRIEVAL, 0, None, _INITIALIZE_PHONEME_EVENTS | _INITIALIZE_DONT_EXIT
            )
        )
        if self.sample_rate <= 0:
            raise MissingAssetError(
                "libespeak-ng could not start (its espeak-ng-data is missing?): reinstall espeak-ng"
            )
        self.blocks: list[np.ndarray] = []
        self.events: list[tuple[int, str]] = []
        self.callback = _CALLBACK(self._on_audio)  # kept referenced: the library calls it
        library.espeak_SetSynthCallback(self.callback)

    def _on_audio(self, wav: Any, n_samples: int, events: Any) -> int:
        if wav and n_samples > 0:
            self.blocks.append(np.ctypeslib.as_array(wav, shape=(n_samples,)).copy())
        i = 0
        while events[i].type != _EVENT_LIST_TERMINATED:
            event = events[i]
            if event.type == _EVENT_PHONEME:
                self.events.append(
                    (int(event.sample), bytes(event.id.string).split(b"\0")[0].decode("ascii", "replace"))
                )
            i += 1
        return 0


@cache
def _engine() -> _Engine:
    for name in _LIBRARY_NAMES:
        found = ctypes.util.find_library(name) or name
        try:
            return _Engine(ctypes.CDLL(found))
        except OSError:
            continue
    raise MissingAssetError(
        "libespeak-ng (espeak-ng's C library) is not installed: apt install libespeak-ng1 (Debian/Ubuntu) or "
        "brew install espeak-ng (macOS); or give a timing file or audio instead"
    )


def voices() -> list[str]:
    """The language codes of the installed espeak-ng voices (``"en"``, ``"en-us"``, ``"de"``...), sorted."""
    with _LOCK:
        listing = _engine().library.espeak_ListVoices(None)
        found = set()
        i = 0
        while listing[i]:
            languages = listing[i].contents.languages or b""
            # a list of (priority byte, language, NUL), ended by an empty entry
            for entry in languages.split(b"\0"):
                if len(entry) > 1:
                    found.add(entry[1:].decode("ascii", "replace"))
                break  # the first language is the voice's own; ctypes stops c_char_p at the first NUL anyway
            i += 1
    return sorted(found)


def synthesize(text: str, language: str = DEFAULT_LANGUAGE, rate_wpm: int = 175) -> tuple[list[Segment], Audio]:
    """Speak ``text`` with the espeak-ng voice ``language`` at ``rate_wpm`` words per minute.

    Returns the phoneme segments (espeak mnemonics in :attr:`Segment.phoneme`, their visemes, seconds from
    the first sample) and the sound (mono, the library's rate: 22,050 Hz). Raises
    :class:`InvalidValueError` for empty or too long text, :class:`UnknownNameError` for a language without a
    voice, :class:`MissingAssetError` when libespeak-ng is not installed.
    """
    if not isinstance(text, str) or not text.strip():
        raise InvalidValueError("text", text, "some text to speak (it is empty)")
    if len(text) > MAX_TEXT_CHARS:
        raise InvalidValueError("text", f"{len(text)} characters", f"at most {MAX_TEXT_CHARS} characters per call")
    if isinstance(rate_wpm, bool) or not isinstance(rate_wpm, int) or not 80 <= rate_wpm <= 450:
        raise InvalidValueError("rate_wpm", rate_wpm, "words per minute, an integer 80..450 (espeak-ng's range)")
    if not isinstance(language, str) or not language or "\0" in language:
        raise InvalidValueError("language", language, "an espeak-ng voice such as en, en-us, de, fr")
    data = text.encode("utf-8") + b"\0"
    with _LOCK:
        engine = _engine()
        library = engine.library
        has_voice = library.espeak_SetVoiceByName(language.encode("ascii", "replace")) == _EE_OK
        if has_voice:
            status = _synth(engine, data, rate_wpm)
            blocks, events, rate = engine.blocks, engine.events, engine.sample_rate
            engine.blocks, engine.events = [], []
    if not has_voice:
        raise UnknownNameError("espeak-ng language", language, tuple(voices()))
    if status != _EE_OK:
        raise InvalidValueError("text", text[:40], f"text espeak-ng can speak (espeak_Synth returned {status})")
    samples = (np.concatenate(blocks) if blocks else np.zeros(0, np.int16)).astype(np.float32) / 32768.0
    audio = Audio(samples, rate)
    segments = _segments(events, rate, len(samples))
    if not segments:
        raise InvalidValueError("text", text[:40], "text with something to pronounce (espeak-ng gave no phonemes)")
    return segments, audio


def _synth(engine: _Engine, data: bytes, rate_wpm: int) -> int:
    """One synthesis into ``engine``'s buffers (the caller holds the lock); espeak_Synth's status."""
    library = engine.library
    library.espeak_SetParameter(1, rate_wpm, 0)  # espeakRATE, absolute
    engine.blocks, engine.events = [], []
    status = int(library.espeak_Synth(data, len(data), 0, _POS_CHARACTER, 0, _CHARS_UTF8, None, None))
    library.espeak_Synchronize()
    return status


def _segments(events: list[tuple[int, str]], rate: int, n_samples: int) -> list[Segment]:
    """Phoneme events (sample, mnemonic) -> segments, each lasting until the next event."""
    segments = []
    for i, (sample, name) in enumerate(events):
        end = events[i + 1][0] if i + 1 < len(events) else max(n_samples, sample + 1)
        if end <= sample or not name:
            continue
        segments.append(Segment(sample / rate, end / rate, viseme_of(name, "espeak"), name))
    return segments


def speak(text: str, language: str = DEFAULT_LANGUAGE, rate_wpm: int = 175) -> Utterance:
    """``text`` spoken by espeak-ng as an :class:`Utterance` (coarticulated track, phoneme segments, sound).

    >>> utterance = speak("my mama made a map")              # doctest: +SKIP
    >>> [s.phoneme for s in utterance.segments][:13]          # doctest: +SKIP
    ['m', 'aI', 'm', 'a', 'm', 'a#', 'm', 'eI', 'd', 'a#', 'm', 'a', 'p']
    """
    segments, audio = synthesize(text, language, rate_wpm)
    track = coarticulate(segments, duration_s=max(audio.duration_s, segments[-1].end_s))
    return Utterance(track, tuple(segments), audio, text, "espeak-ng", {"language": language, "rate_wpm": rate_wpm})
