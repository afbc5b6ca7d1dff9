"""The characters of a server: id -> batch row, head, identity, rig driver; queued commands per character.

Transports call :meth:`Registry.submit` (cheap: store the newest state message, queue events); the clock
calls :meth:`Registry.step`, which applies what is queued and steps ONE batch for every character. The state
messages of a tick are written in one go (names resolved once in :data:`~mien.server.protocol.AU_CHANNELS`,
one vectorised write of every row's targets); a bad or unservable message costs that message (a counted
rejection), never the tick. :meth:`Registry.warm_up` does before the clock starts what is slow the first time.

Changes may come from any thread: :meth:`~Registry.add`, :meth:`~Registry.remove`, :meth:`~Registry.submit` and
each tick hold :attr:`Registry.lock`, so a change lands between two ticks, never inside one (a head load, the
slow part of :meth:`~Registry.add`, runs before the lock is taken). A character whose step fails is quarantined
(:meth:`Registry.quarantine`: its row freed, counted, its id kept until deleted) and the others keep moving.
"""

from __future__ import annotations

import copy
import logging
import math
import re
import threading
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import partial
from typing import Any

import numpy as np

from mien.character import EXPRESSION_BASES, CharacterBatch, check_seed
from mien.errors import InvalidValueError, MienError, MissingExtraError, UnknownNameError
from mien.extras import EXTRA_OF
from mien.facs.catalogue import FACE_CHANNELS
from mien.facs.clip import Clip
from mien.facs.dynamics import time_constant_from_speed
from mien.facs.idle import IdleSettings
from mien.heads import load_head
from mien.laughter.names import LAUGH_TYPES
from mien.rig.driver import RigDriver
from mien.server.head_view import HeadView, frame_weights, head_view
from mien.server.protocol import AU_CHANNELS, N_AU_CHANNELS, Message, MessageRejected, Rejection, idle_parts
from mien.server.speech import SpeechService
from mien.server.stats import Counters, RateLimitedLog

__all__ = ["MAX_EVENTS_PER_CHARACTER", "MAX_QUARANTINE_TRIALS", "CharacterSpec", "Entry", "Registry"]

log = logging.getLogger("mien.server")

MAX_EVENTS_PER_CHARACTER = 256
"""Queued events (emotion, laugh, PAD, play) per character between two ticks; older ones are dropped."""

MAX_QUARANTINE_TRIALS = 32
"""Characters (newest first) tried one by one as the cause of a failed step before the batch is rebuilt."""

_ID = re.compile(r"^[A-Za-z0-9_.\-]{1,64}$")


@dataclass(frozen=True)
class CharacterSpec:
    """What a character is made of."""

    id: str
    """Character id (1-64 of ``A-Z a-z 0-9 _ . -``)."""
    head: str = "default"
    """Head name (:data:`mien.rig.heads.HEADS`), or ``"file"`` with the head file's path as :attr:`identity` (a
    path or ``file:PATH`` here means the same)."""
    identity: str | None = None
    """Identity preset of the head (None = the head's default); the file's path of a ``"file"`` head."""
    seed: int = 0
    """Seed of the idle behaviour and laughter (0..2**64-1)."""
    idle: bool = True
    """Idle behaviour (blinks, micro-motion, gaze) on or off."""
    expression_basis: str = "facs"
    """How emotions reach the face: ``"facs"`` (EMFACS prototypes) or ``"feature_points"``."""

    def __post_init__(self) -> None:
        if not isinstance(self.id, str) or not _ID.match(self.id):
            raise InvalidValueError("id", self.id, "1-64 characters of A-Z a-z 0-9 _ . -")
        check_seed(self.seed)
        if not isinstance(self.idle, bool):
            raise InvalidValueError("idle", self.idle, "true or false")
        if self.expression_basis not in EXPRESSION_BASES:
            raise UnknownNameError("expression basis", self.expression_basis, EXPRESSION_BASES)


@dataclass
class Entry:
    """One character of the registry."""

    spec: CharacterSpec
    """What it was created with."""
    row: int
    """Its row in the batch."""
    rig: Any
    """Its :class:`mien.rig.model.Rig`."""
    driver: Any
    """Its :class:`mien.rig.driver.RigDriver` (face frames -> morph weights and pose)."""
    state: Message | None = None
    """Newest state message not yet applied."""
    events: deque[Message] = field(default_factory=lambda: deque(maxlen=MAX_EVENTS_PER_CHARACTER))
    """Events not yet applied, oldest first."""
    idle: Any = None
    """Current :class:`mien.facs.idle.IdleSettings` (None: idle off)."""
    clips: list[Clip] = field(default_factory=list)
    """:class:`~mien.facs.clip.Clip` objects to start playing at the next tick."""
    view: HeadView | None = None
    """How viewers show its head, and the weights its frames carry (:mod:`mien.server.head_view`)."""
    performance: Any = None
    """The live :class:`~mien.server.capture_source.CaptureSource` whose face it follows, or None."""
    performance_seq: int = 0
    """Number of the newest performance frame given to its row."""


class Registry:
    """Characters stepped together; see the module docstring."""

    def __init__(self, counters: Counters | None = None) -> None:
        self.batch = CharacterBatch(0)
        """The one :class:`~mien.character.CharacterBatch` of every character."""
        self.counters = counters or Counters()
        """Counters shared with the transports."""
        self.entries: dict[str, Entry] = {}
        """Characters by id, in creation order."""
        self.frames = np.zeros((0, 62))
        """(n_rows, 62) face frames of the last step."""
        self.time_s = 0.0
        """Time of the last step, seconds."""
        self.missing: dict[str, str] = {}
        """Message fields this install cannot serve (``"laugh"``) -> why (the missing extra): such messages are
        rejected as ``missing_extra`` on arrival."""
        self.quarantined: dict[str, str] = {}
        """Characters taken out of the batch because stepping them failed: id -> why (until DELETEd)."""
        self.capture: Any = None
        """The server's :class:`~mien.server.capture_source.CaptureSource` (``mien serve --capture``), or None: what a
        ``{"capture": true}`` message makes a character follow."""
        self.speech = SpeechService()
        """The TTS worker of ``say`` commands and the utterances' sounds (:mod:`mien.server.speech`)."""
        self.lock = threading.RLock()
        """Held by each tick and each change (add, remove, submit), so changes from any thread land between ticks."""
        self._rigs: dict[tuple[str, str | None, bool], tuple[Any, Any]] = {}
        self._views: dict[tuple[str, str | None, bool], HeadView] = {}
        self._loading = threading.Lock()  # head loads, one at a time; never held by a tick
        self._log = RateLimitedLog()
        self._faults = RateLimitedLog(prefix="character fault")

    # ------------------------------------------------------------------ characters

    @property
    def default_id(self) -> str | None:
        """The first character's id (the target of messages without ``character``)."""
        return next(iter(self.entries), None)

    def prepare(self, spec: CharacterSpec) -> tuple[Any, Any]:
        """Load (once) and return the ``(rig, driver)`` of ``spec``'s head, and how viewers show it (a head file:
        its own glTF, with the rig -> file weight matrix): the slow part of :meth:`add`, which touches no
        character, so it can run off the event loop (raises UnknownNameError for a bad head, identity or
        expression basis, :class:`~mien.errors.MienError` for a head file that cannot be read)."""
        if spec.expression_basis not in EXPRESSION_BASES:
            raise UnknownNameError("expression basis", spec.expression_basis, EXPRESSION_BASES)
        key = _head_key(spec)
        if key in self._rigs:  # no lock once loaded: the event loop calls this too
            return self._rigs[key]
        with self._loading:
            if key not in self._rigs:
                rig = load_head(spec.head, spec.identity, feature_points=key[2])
                driver = RigDriver(rig)
                view = head_view(rig)
                if view.note:
                    log.info("%s", view.note)
                self._views[key] = view  # before _rigs: whoever finds the rig finds its view
                self._rigs[key] = (rig, driver)
        return self._rigs[key]

    def add(self, spec: CharacterSpec) -> Entry:
        """Create a character (raises :class:`InvalidValueError` if the id is taken or a value is refused,
        UnknownNameError for a bad head or identity). Atomic: a refused character changes nothing."""
        if not isinstance(spec, CharacterSpec):
            raise InvalidValueError("spec", spec, "a CharacterSpec")
        rig, driver = self.prepare(spec)  # slow the first time: before the lock, so no tick waits on it
        with self.lock:
            if spec.id in self.entries or spec.id in self.quarantined:
                raise InvalidValueError("id", spec.id, "an id not in use (DELETE it first)")
            row = int(  # "pad" mode: a live character takes PAD moves, and emotion events still add on top
                self.batch.add_character(
                    seed=spec.seed, idle=spec.idle, expression_basis=spec.expression_basis, emotion_mode="pad"
                )
            )
            entry = Entry(spec, row, rig, driver, view=self._views[_head_key(spec)])
            if spec.idle:
                entry.idle = IdleSettings()
            self.entries[spec.id] = entry
        return entry

    def remove(self, character_id: str) -> None:
        """Remove a character (its row is freed), or forget a quarantined one."""
        with self.lock:
            if character_id in self.quarantined and character_id not in self.entries:
                del self.quarantined[character_id]
                return
            entry = self.get(character_id)
            self.batch.remove_character(entry.row)
            del self.entries[character_id]

    def quarantine(self, character_id: str, why: str, *, free_row: bool = True) -> None:
        """Take a failing character out of the batch (its row freed unless ``free_row`` is False; its messages
        are refused as ``unknown_character``) and count it; its id stays taken until :meth:`remove`."""
        with self.lock:
            entry = self.entries.pop(character_id, None)
            if entry is None:
                return
            try:
                if free_row:
                    self.batch.remove_character(entry.row)
            except Exception:  # a batch broken beyond freeing a row is rebuilt by step()
                log.debug("freeing the row of quarantined %s failed", character_id, exc_info=True)
            self.quarantined[character_id] = why[:300]
            self.counters.quarantined += 1
            self._faults.warn("quarantined", f"{character_id} quarantined (DELETE it to free the id): {why}")

    def get(self, character_id: str) -> Entry:
        """The character ``character_id`` (raises :class:`UnknownNameError`)."""
        try:
            return self.entries[character_id]
        except KeyError:
            raise UnknownNameError("character", character_id, tuple(self.entries)) from None

    # ------------------------------------------------------------------ commands

    def warm_up(self) -> None:
        """Do what is slow the first time before the clock starts, so no tick stalls on it: generate and play
        one laugh on a scratch batch (imports the laughter extra and fills its caches: about 0.3-0.5 s cold,
        1-5 ms after). Without the laughter extra, laugh messages are rejected on arrival from now on
        (:attr:`missing`). The characters' heads are loaded by :meth:`add`."""
        self.speech.warm_up()  # libespeak-ng and its voices load in a background thread
        scratch = CharacterBatch(1, idle=False)
        try:
            scratch.laugh(0, LAUGH_TYPES[1])
            scratch.step(0.5)
        except ImportError as exc:  # MissingExtraError, or a raw ImportError of a module not yet behind require
            self.missing["laugh"] = _missing_extra(exc, "laughter")
            log.warning("laugh messages will be rejected: %s", self.missing["laugh"])

    def submit(self, message: Message, default: str | None = None) -> Entry:
        """Queue ``message`` for its character (``message.character``, else ``default``, else the first).

        Raises :class:`MessageRejected`: ``unknown_character`` when there is no such character,
        ``missing_extra`` for a laugh when this install lacks the laughter extra (see :attr:`missing`).
        """
        character_id = message.character or default or self.default_id
        entry = self.entries.get(character_id) if character_id is not None else None
        if entry is None:
            why = self.quarantined.get(character_id or "")
            detail = f"is quarantined ({why})" if why is not None else "does not exist"
            raise MessageRejected(Rejection.UNKNOWN_CHARACTER, f"character={character_id!r} {detail}")
        if message.laugh is not None and "laugh" in self.missing:
            raise MessageRejected(Rejection.MISSING_EXTRA, f"laugh={message.laugh!r}: {self.missing['laugh']}")
        if message.capture and self.capture is None:
            raise MessageRejected(Rejection.NO_CAPTURE, "capture=true: this server has no capture source (--capture)")
        if message.say is not None:  # spoken off the clock; started by the first tick after (apply_pending)
            self.speech.check(message.say)
            self.speech.request(entry.spec.id, message.say)
        with self.lock:
            if message.aus is not None:
                if entry.state is not None:
                    self.counters.coalesced += 1
                entry.state = message
            if message.has_events:
                entry.events.append(message)
        return entry

    def reject(self, error: MessageRejected, cause: BaseException | None = None) -> None:
        """Count and (rate-limited) log a dropped message (with ``cause``'s traceback: a bug's)."""
        self.counters.rejections[error.reason.value] += 1
        self._log.warn(error.reason.value, error.detail, cause)

    def _apply_states(self, states: list[tuple[Entry, Message]]) -> None:
        """Write the full AU states of a tick in one go: each message's targets (AUs not named: 0) and Speed
        (as a time constant), then the rare per-AU ``speeds``/``tau_s`` extensions."""
        tick_hz = self.batch.facs.tick_hz
        written: list[tuple[Entry, Message]] = []
        targets: list[list[float]] = []
        taus: list[float] = []
        for entry, message in states:
            values = [0.0] * N_AU_CHANNELS
            try:
                for key, value in message.aus or ():
                    for channel in AU_CHANNELS[key]:
                        values[channel] = value
                tau = math.nan if message.speed is None else time_constant_from_speed(message.speed, tick_hz)
            except KeyError as exc:  # parse_message lets no unknown key through; a hand-made Message might
                self.reject(MessageRejected(Rejection.UNKNOWN_AU, f"{entry.spec.id}: {exc.args[0]!r}"[:200]))
                continue
            except MienError as exc:
                self.reject(MessageRejected(Rejection.ENGINE_ERROR, f"{entry.spec.id}: {exc}"))
                continue
            written.append((entry, message))
            targets.append(values)
            taus.append(tau)
        facs = self.batch.facs
        rows = np.array([entry.row for entry, _ in written], dtype=np.intp)
        try:
            facs.set_targets(rows, np.array(targets, dtype=np.float64), np.array(taus))
        except (MienError, TypeError, ValueError):  # a bad value in a hand-made Message: keep the good ones
            for i, (entry, _) in enumerate(written):
                try:
                    one = slice(i, i + 1)
                    facs.set_targets(rows[one], np.array(targets[one], np.float64), np.array(taus[one]))
                except (MienError, TypeError, ValueError) as exc:
                    self.reject(MessageRejected(Rejection.ENGINE_ERROR, f"{entry.spec.id}: {exc}"))
        for entry, message in written:
            if message.speeds or message.tau_s:
                try:
                    aus = dict(message.aus or ())
                    for au, speed in message.speeds:
                        self.batch.set_speed(entry.row, speed, au=au)
                    for au, tau_s in message.tau_s:
                        self.batch.set_au(entry.row, au, aus.get(au, 0.0), tau_s=tau_s)
                except MienError as exc:
                    self.reject(MessageRejected(Rejection.ENGINE_ERROR, f"{entry.spec.id}: {exc}"))

    def _apply_idle(self, entry: Entry, switches: tuple[tuple[str, bool], ...], t_s: float) -> None:
        off: dict[str, Any] = dict.fromkeys(idle_parts(), False)
        current = entry.idle or replace(IdleSettings(), **off)
        changes: dict[str, Any] = dict(switches)
        settings = replace(current, **changes)
        entry.idle = settings if any(getattr(settings, part) for part in idle_parts()) else None
        rows = np.array([entry.row])
        self.batch.idle.reset_rows(rows, np.array([entry.spec.seed]), entry.idle, t_s)

    def _apply_event(self, entry: Entry, message: Message, t_s: float) -> None:
        row, seed = entry.row, entry.spec.seed
        if message.idle is not None:
            self._apply_idle(entry, message.idle, t_s)
        if message.play is not None:
            p = message.play
            self.batch.play_au(
                row, p.au, p.intensity, onset_s=p.onset_s, apex_s=p.apex_s, offset_s=p.offset_s, start_s=t_s
            )
        if message.emotion is not None:
            self.batch.emote(row, message.emotion, message.intensity, start_s=t_s)
        if message.pad is not None:
            self.batch.set_pad(row, *message.pad, start_s=t_s)
        if message.laugh is not None:
            self.batch.laugh(row, message.laugh, message.intensity, start_s=t_s, seed=seed)
        if message.capture is not None:
            self.follow(entry, message.capture)

    def follow(self, entry: Entry, on: bool) -> None:
        """Make ``entry`` follow the server's capture source (``on``), or drop its performance layer."""
        if on and self.capture is None:
            raise MessageRejected(Rejection.NO_CAPTURE, "capture=true: this server has no capture source (--capture)")
        with self.lock:
            entry.performance, entry.performance_seq = (self.capture if on else None), 0
            if not on and entry.spec.id in self.entries:
                self.batch.set_performance(entry.row, None)

    def apply_pending(self, t_s: float) -> None:
        """Apply every queued command at ``t_s``. Never raises: a message that fails costs that message only,
        counted as ``missing_extra`` (an optional dependency is not installed), ``engine_error`` (the engine
        refused a value) or ``internal_error`` (a bug, logged)."""
        states: list[tuple[Entry, Message]] = []
        busy: list[Entry] = []
        for entry in self.entries.values():
            if entry.state is not None:
                states.append((entry, entry.state))
                entry.state = None
            if entry.performance is not None:
                self._apply_performance(entry)
            if entry.events or entry.clips:
                busy.append(entry)
        if states:
            self._apply_states(states)  # events touch no held target, so the states can all go first
        self.speech.deliver(self._start_speech, self.reject, t_s)
        for entry in busy:
            while entry.events:
                message = entry.events.popleft()
                self._guarded(entry, message.laugh is not None, partial(self._apply_event, entry, message, t_s))
            while entry.clips:
                clip = entry.clips.pop(0)
                self._guarded(entry, False, partial(self.batch.play_clip, entry.row, clip, start_s=t_s))

    def _start_speech(self, character_id: str, utterance: Any, start_s: float) -> bool:
        """Put ``utterance`` on ``character_id``'s row from ``start_s`` (False: no such character, or refused)."""
        entry = self.entries.get(character_id)
        if entry is None:
            return False
        try:
            self.batch.say(entry.row, utterance, start_s=start_s)
        except MienError as exc:
            self.reject(MessageRejected(Rejection.ENGINE_ERROR, f"{character_id}: say: {exc}"))
            return False
        return True

    def _apply_performance(self, entry: Entry) -> None:
        """Give ``entry``'s row the newest frame of the performance it follows (a new one only: the batch holds it)."""
        seq, frame = entry.performance.latest()
        if seq == entry.performance_seq:
            return
        entry.performance_seq = seq
        self._guarded(entry, False, partial(self.batch.set_performance, entry.row, frame))

    def _guarded(self, entry: Entry, laugh: bool, apply: Callable[[], object]) -> None:
        """``apply()``, turning any failure into a counted rejection of this one message."""
        try:
            apply()
        except ImportError as exc:  # MissingExtraError, or a raw one from a module not yet behind require
            detail = _missing_extra(exc, "laughter" if laugh else None)
            if laugh:
                self.missing["laugh"] = detail  # reject the next ones on arrival
            self.reject(MessageRejected(Rejection.MISSING_EXTRA, f"{entry.spec.id}: {detail}"))
        except MienError as exc:
            self.reject(MessageRejected(Rejection.ENGINE_ERROR, f"{entry.spec.id}: {exc}"))
        except Exception as exc:  # a bug must cost one message, not the tick of every character
            detail = f"{entry.spec.id}: {type(exc).__name__}: {exc}"
            self.reject(MessageRejected(Rejection.INTERNAL_ERROR, detail), exc)  # one traceback per 5 s, not a flood

    def step(self, t_s: float) -> np.ndarray:
        """Apply queued commands and step every character to ``t_s``; returns the (n_rows, 62) frames.

        Never raises for a failing character: the one whose removal lets the step through is quarantined
        (:meth:`quarantine`); failing that, the batch is rebuilt from the characters' specs."""
        with self.lock:
            self.apply_pending(t_s)
            try:
                self.frames = self.batch.step(t_s)
            except Exception as exc:
                self.frames = self._recover(t_s, exc)
            self.time_s = t_s
            return self.frames

    def _recover(self, t_s: float, error: Exception) -> np.ndarray:
        """Frames at ``t_s`` after ``self.batch.step`` raised ``error``: step a copy without each character in
        turn (newest first, up to :data:`MAX_QUARANTINE_TRIALS`); the first copy that steps becomes the batch
        and that character is quarantined. If none does, :meth:`_rebuild`."""
        self.counters.step_failures += 1
        why = f"{type(error).__name__}: {error}"[:200]
        self._faults.warn("step", f"stepping the characters at t={t_s:.3f} s failed: {why}", error)
        for entry in list(reversed(self.entries.values()))[:MAX_QUARANTINE_TRIALS]:
            trial = copy.deepcopy(self.batch)
            try:
                trial.remove_character(entry.row)
                frames = trial.step(t_s)
            except Exception:
                continue
            self.batch = trial
            self.quarantine(entry.spec.id, f"stepping it failed: {why}", free_row=False)  # freed in the copy
            return frames
        return self._rebuild(t_s, why)

    def _rebuild(self, t_s: float, why: str) -> np.ndarray:
        """A new batch holding every character afresh (held AUs, emotions and clips are lost; rows may change),
        quarantining any the new batch refuses; stepped to ``t_s``."""
        log.warning("rebuilding the batch of %d characters after a failed step (%s)", len(self.entries), why)
        batch = CharacterBatch(0, tick_hz=self.batch.tick_hz)
        batch.step(max(t_s, 0.0))  # idle starts at t_s, not at 0
        refused: list[tuple[str, str]] = []
        for entry in list(self.entries.values()):
            try:
                entry.row = batch.add_character(
                    seed=entry.spec.seed,
                    idle=entry.idle if entry.idle is not None else False,
                    expression_basis=entry.spec.expression_basis,
                    emotion_mode="pad",
                )
            except Exception as exc:
                refused.append((entry.spec.id, f"re-adding it failed: {type(exc).__name__}: {exc}"))
            entry.state, entry.clips, entry.performance_seq = None, [], 0
            entry.events.clear()
        self.batch = batch
        for character_id, reason in refused:
            self.quarantine(character_id, reason, free_row=False)  # it has no row in the new batch
        self.counters.rebuilds += 1
        try:
            return self.batch.step(t_s)
        except Exception as exc:  # nothing left to try this tick: neutral faces, and the next tick tries again
            self._faults.warn("rebuild", f"the rebuilt batch failed too: {type(exc).__name__}: {exc}", exc)
            return np.zeros((self.batch.n_characters, len(FACE_CHANNELS)))

    def rig_output(self, entry: Entry) -> tuple[np.ndarray, np.ndarray]:
        """``(weights (n_targets,) float32, pose (5,) degrees)`` of ``entry`` at the last step."""
        frames = self.frames[entry.row : entry.row + 1]
        features = None
        if entry.spec.expression_basis == "feature_points":
            features = self.batch.feature_weights[entry.row : entry.row + 1]
        visemes = None  # a head with its own viseme shapes speaks through them
        if entry.driver.viseme_targets and self.batch.speech.utterance(entry.row) is not None:
            visemes = self.batch.speech.viseme_weights[entry.row : entry.row + 1]
        weights = entry.driver.weights(frames, feature_weights=features, visemes=visemes)[0]
        return weights, entry.driver.pose(frames)[0]

    def frame_output(self, entry: Entry) -> tuple[np.ndarray, np.ndarray]:
        """``(weights (n_frame_names,) float32, pose (5,) degrees)`` of ``entry`` at the last step as its frames
        carry them: the rig's weights, or a head file's own shape weights (:mod:`mien.server.head_view`)."""
        weights, pose = self.rig_output(entry)
        return (weights if entry.view is None else frame_weights(entry.view, weights)), pose

    def state(self, entry: Entry) -> dict[str, Any]:
        """The character's face frame at the last step as ``{channel: value}`` (AUs 0..5, pose degrees)."""
        if entry.row >= self.frames.shape[0]:
            return dict.fromkeys(FACE_CHANNELS, 0.0)
        return dict(zip(FACE_CHANNELS, self.frames[entry.row].tolist(), strict=True))


def _head_key(spec: CharacterSpec) -> tuple[str, str | None, bool]:
    """What makes two characters' heads the same: head, identity, feature-point targets."""
    return spec.head, spec.identity, spec.expression_basis == "feature_points"


def _missing_extra(error: ImportError, extra: str | None = None) -> str:
    """The message of the :class:`MissingExtraError` behind ``error`` (a raw ImportError gets one made, naming
    ``extra``, the extra of the feature that failed, else the smallest extra holding the module)."""
    if isinstance(error, MissingExtraError):
        return str(error)
    module = (error.name or "an optional module").split(".", 1)[0]
    return str(MissingExtraError(module, extra or EXTRA_OF.get(module, "all")))
