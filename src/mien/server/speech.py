"""Speech on the live server: a ``say`` command spoken off the clock, started on it, its sound served.

A ``say`` (UDP, WebSocket or HTTP; :func:`mien.server.protocol.parse_message`) is checked on arrival
(:meth:`SpeechService.check`: a TTS is installed, the language has a voice) and handed to one worker thread
(:meth:`SpeechService.request`), which runs espeak-ng (:func:`mien.speech.espeak.speak`, 10-100 ms a sentence)
and encodes the sound as WAV: the 60 Hz tick never waits on it. The first tick after it is done puts the
utterance on the character's row (:meth:`SpeechService.deliver`, called by
:meth:`mien.server.registry.Registry.apply_pending`) to start :data:`ANNOUNCE_LEAD_S` later on the server clock,
and announces it at once, so viewers have that long to fetch the sound and start it with the face's first
viseme. The face and the sound share the server clock: the character keeps its clock whatever the TTS costs.

Each started utterance is a :class:`Spoken`: its sound is served as ``GET /api/speech/{id}.wav`` and
announced to the character's WebSocket viewers as a text message (:meth:`Spoken.announcement`)::

    {"speech": {"id": 3, "character": "default", "url": "/api/speech/3.wav", "start_s": 12.35,
                "duration_s": 1.9, "text": "hello"}}

``start_s`` is on the clock the binary frames carry (``time_s``), so a viewer plays the sound from
``start_s`` against the frames it shows (``mien/viewer/static/viewer.js``).

Limits: at most :data:`MAX_PENDING_SAYS` says wait for the worker (more are refused as ``speech_busy``); a
text is at most :data:`~mien.server.protocol.MAX_SAY_CHARS` characters (``too_long``); the newest
:data:`KEPT_UTTERANCES` sounds are kept for viewers to fetch.
"""

from __future__ import annotations

import io
import itertools
import logging
import queue
import threading
import wave
from collections import OrderedDict, deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from mien.errors import MienError, MissingAssetError, UnknownNameError
from mien.server.protocol import MessageRejected, Rejection, SayRequest

__all__ = ["ANNOUNCE_LEAD_S", "KEPT_UTTERANCES", "MAX_PENDING_SAYS", "SpeechService", "Spoken", "wav_bytes"]

log = logging.getLogger("mien.server")

MAX_PENDING_SAYS = 8
"""``say`` commands waiting for the TTS worker at once, all characters together; more are refused
(``speech_busy``) rather than queued without end."""

ANNOUNCE_LEAD_S = 0.2
"""Seconds between an utterance's announcement and its start on the server clock: time for a viewer to fetch
and decode the sound (a few tens of ms on a LAN) so that it starts with the face, not skipped into."""

KEPT_UTTERANCES = 32
"""Newest utterances whose sound the server keeps for ``GET /api/speech/{id}.wav`` (about 1 MB each at most)."""


def wav_bytes(samples: np.ndarray, sample_rate: int) -> bytes:
    """``samples`` (n,) float -1..1 as a 16-bit PCM mono WAV file's bytes."""
    pcm = np.round(np.clip(samples, -1.0, 1.0) * 32767.0).astype("<i2")
    buffer = io.BytesIO()
    with wave.open(buffer, "wb") as out:
        out.setnchannels(1)
        out.setsampwidth(2)
        out.setframerate(int(sample_rate))
        out.writeframes(pcm.tobytes())
    return buffer.getvalue()


@dataclass(frozen=True)
class Spoken:
    """An utterance a character started on the server clock."""

    id: int
    """Number of the utterance (1, 2...), unique in this server."""
    character: str
    """The character that says it."""
    start_s: float
    """Server time of its first sound sample, seconds (the clock of the frames' ``time_s``)."""
    duration_s: float
    """Seconds of speech."""
    text: str
    """What it says."""
    wav: bytes
    """Its sound, a 16-bit PCM mono WAV file."""

    @property
    def url(self) -> str:
        """Where its sound is served (relative to the server)."""
        return f"/api/speech/{self.id}.wav"

    def announcement(self) -> dict[str, Any]:
        """What the character's WebSocket viewers are told (see the module docstring)."""
        return {
            "speech": {
                "id": self.id,
                "character": self.character,
                "url": self.url,
                "start_s": self.start_s,
                "duration_s": self.duration_s,
                "text": self.text,
            }
        }


@dataclass(frozen=True)
class _Done:
    """A finished synthesis waiting for the next tick."""

    id: int
    character: str
    say: SayRequest
    utterance: Any  # mien.speech.track.Utterance, or None when it failed
    wav: bytes
    error: MessageRejected | None


def _compile(utterance: Any) -> None:
    """Compile ``utterance`` for the engine here, off the clock: the speech layer caches each utterance's
    compiled frames (a 20 s sentence: about 15 ms), so the tick that starts it only stores them (about 5 ms)."""
    from mien.speech.batch import SpeechBatch

    SpeechBatch(1).say(np.zeros(1, np.intp), utterance, 0.0)


Speak = Callable[[str, str, int], Any]
"""``speak(text, language, rate_wpm) -> Utterance``: :func:`mien.speech.espeak.speak` by default."""


class SpeechService:
    """The TTS worker, the sounds kept for viewers, and the announcements (see the module docstring).

    ``speak`` replaces espeak-ng (another TTS returning a :class:`mien.speech.track.Utterance`).
    """

    def __init__(self, speak: Speak | None = None) -> None:
        self.listeners: list[Callable[[Spoken], None]] = []
        """Called on the clock's thread with each utterance as it starts (the WebSocket hub announces it)."""
        self.unavailable: str | None = None
        """Why ``say`` cannot be served here (no libespeak-ng), or None."""
        self.spoken = 0
        """Utterances started."""
        self._speak = speak
        self._voices: frozenset[str] | None = None
        self._requests: queue.Queue[tuple[int, str, SayRequest] | None] = queue.Queue(MAX_PENDING_SAYS)
        self._done: deque[_Done] = deque()
        self._kept: OrderedDict[int, Spoken] = OrderedDict()
        self._ids = itertools.count(1)
        self._thread: threading.Thread | None = None
        self._start = threading.Lock()

    # ------------------------------------------------------------------ arrival (any thread)

    def warm_up(self) -> None:
        """Load the TTS and its voice list and speak one word in a background thread (about 1 s cold), so the
        server starts without waiting and the first ``say`` finds it ready; without libespeak-ng, ``say`` is
        refused (``no_tts``) from then on."""
        threading.Thread(target=self._warm, name="mien-tts-warm-up", daemon=True).start()

    def _warm(self) -> None:
        try:
            self._voice_list()
            self._synthesize(SayRequest("a"))
        except MissingAssetError as exc:
            self.unavailable = str(exc)
            log.warning("say commands will be rejected: %s", exc)
        except Exception:  # a broken TTS is reported when a say uses it, not here
            log.debug("warming up the TTS failed", exc_info=True)

    def _voice_list(self) -> frozenset[str]:
        if self._voices is None:
            if self._speak is not None:
                self._voices = frozenset()  # another TTS: it judges its own languages
            else:
                from mien.speech.espeak import voices

                self._voices = frozenset(voices())
        return self._voices

    def check(self, say: SayRequest) -> None:
        """Refuse (:class:`MessageRejected`) a ``say`` this server cannot speak: ``no_tts`` when libespeak-ng is
        missing, ``unknown_language`` when no installed voice speaks its language (``en`` stands for its
        variants ``en-gb``, ``en-us``...)."""
        if self.unavailable is not None:
            raise MessageRejected(Rejection.NO_TTS, f"say: {self.unavailable}")
        try:
            known = self._voice_list()
        except MissingAssetError as exc:
            self.unavailable = str(exc)
            raise MessageRejected(Rejection.NO_TTS, f"say: {exc}") from None
        language = say.language.lower()
        if known and language not in known and not any(v.startswith(language + "-") for v in known):
            shown = ", ".join(sorted(v for v in known if "-" not in v)[:12])
            raise MessageRejected(
                Rejection.UNKNOWN_LANGUAGE, f"say.language={say.language!r}: espeak-ng has no such voice ({shown}...)"
            )

    def request(self, character_id: str, say: SayRequest) -> int:
        """Queue ``say`` for ``character_id``'s TTS (never waits); its utterance number. Raises
        :class:`MessageRejected` (``speech_busy``) when :data:`MAX_PENDING_SAYS` already wait."""
        utterance_id = next(self._ids)
        try:
            self._requests.put_nowait((utterance_id, character_id, say))
        except queue.Full:
            raise MessageRejected(
                Rejection.SPEECH_BUSY, f"say: {MAX_PENDING_SAYS} texts already wait for the TTS; send it again later"
            ) from None
        if self._thread is None:
            with self._start:
                if self._thread is None:
                    self._thread = threading.Thread(target=self._work, name="mien-tts", daemon=True)
                    self._thread.start()
        return utterance_id

    # ------------------------------------------------------------------ the worker

    def _synthesize(self, say: SayRequest) -> Any:
        if self._speak is not None:
            return self._speak(say.text, say.language, say.rate_wpm)
        from mien.speech.espeak import speak

        return speak(say.text, say.language, say.rate_wpm)

    def close(self) -> None:
        """Stop the worker after the synthesis it is running (the server stops); later says are refused."""
        self.unavailable = "the server is stopping"
        thread, self._thread = self._thread, None
        if thread is not None:
            self._requests.put(None)  # blocks at most until the worker takes the next request
            thread.join(5.0)

    def _work(self) -> None:
        while True:
            request = self._requests.get()
            if request is None:
                return
            utterance_id, character_id, say = request
            utterance, wav, error = None, b"", None
            try:
                utterance = self._synthesize(say)
                _compile(utterance)
                if utterance.audio is not None:
                    wav = wav_bytes(utterance.audio.samples, utterance.audio.sample_rate)
            except UnknownNameError as exc:
                error = MessageRejected(Rejection.UNKNOWN_LANGUAGE, f"say: {exc}")
            except MissingAssetError as exc:
                error = MessageRejected(Rejection.NO_TTS, f"say: {exc}")
            except MienError as exc:
                error = MessageRejected(Rejection.ENGINE_ERROR, f"say: {exc}")
            except Exception as exc:  # a TTS bug costs this say, never the worker
                error = MessageRejected(Rejection.INTERNAL_ERROR, f"say: {type(exc).__name__}: {exc}"[:300])
            self._done.append(_Done(utterance_id, character_id, say, utterance, wav, error))

    # ------------------------------------------------------------------ the clock

    def deliver(
        self, start: Callable[[str, Any, float], bool], reject: Callable[[MessageRejected], None], t_s: float
    ) -> None:
        """Hand on the utterances the worker finished at server time ``t_s`` (the clock's thread, between ticks):
        ``start(character_id, utterance, start_s)`` puts each on the character's row from ``start_s = t_s +``
        :data:`ANNOUNCE_LEAD_S` (False: the character is gone), then the listeners announce it; a failed
        synthesis is ``reject``-ed (counted)."""
        while self._done:
            done = self._done.popleft()
            if done.error is not None:
                reject(done.error)
                continue
            start_s = t_s + ANNOUNCE_LEAD_S
            if not start(done.character, done.utterance, start_s):
                continue
            duration = float(done.utterance.duration_s)
            spoken = Spoken(done.id, done.character, start_s, duration, done.say.text, done.wav)
            self._kept[spoken.id] = spoken
            while len(self._kept) > KEPT_UTTERANCES:
                self._kept.popitem(last=False)
            self.spoken += 1
            for listener in self.listeners:
                listener(spoken)

    # ------------------------------------------------------------------ readers

    def get(self, utterance_id: int) -> Spoken | None:
        """A kept utterance by number, or None."""
        return self._kept.get(utterance_id)

    def playing(self, character_id: str, t_s: float) -> Spoken | None:
        """The utterance ``character_id`` is saying, or about to say, at server time ``t_s``, or None."""
        for spoken in reversed(self._kept.values()):
            if spoken.character == character_id:
                return spoken if t_s < spoken.start_s + spoken.duration_s else None
        return None

    def pending(self) -> int:
        """``say`` commands waiting for or being spoken by the worker, or finished and waiting for a tick."""
        return self._requests.qsize() + len(self._done)
