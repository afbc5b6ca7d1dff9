"""The characters of a server: id -> batch row, head, identity, rig driver; queued commands per character.

Transports call :meth:`Registry.submit` (cheap: store the newest state message, queue events); the clock
calls :meth:`Registry.step`, which applies what is queued and steps ONE batch for every character.
"""

from __future__ import annotations

import re
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mien.errors import InvalidValueError, MienError, UnknownNameError
from mien.server.protocol import Message, MessageRejected, Rejection
from mien.server.stats import Counters, RateLimitedLog

__all__ = ["MAX_EVENTS_PER_CHARACTER", "CharacterSpec", "Entry", "Registry"]

MAX_EVENTS_PER_CHARACTER = 256
"""Queued events (emotion, laugh, PAD, play) per character between two ticks; older ones are dropped."""

_ID = re.compile(r"^[A-Za-z0-9_.\-]{1,64}$")


@dataclass(frozen=True)
class CharacterSpec:
    """What a character is made of."""

    id: str
    """Character id (1-64 of ``A-Z a-z 0-9 _ . -``)."""
    head: str = "default"
    """Head name (:data:`mien.rig.heads.HEADS`)."""
    identity: str | None = None
    """Identity preset of the head (None = the head's default)."""
    seed: int = 0
    """Seed of the idle behaviour and laughter."""
    idle: bool = True
    """Idle behaviour (blinks, micro-motion, gaze) on or off."""
    expression_basis: str = "facs"
    """How emotions reach the face: ``"facs"`` (EMFACS prototypes) or ``"feature_points"``."""

    def __post_init__(self) -> None:
        if not isinstance(self.id, str) or not _ID.match(self.id):
            raise InvalidValueError("id", self.id, "1-64 characters of A-Z a-z 0-9 _ . -")


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
    clips: list[Any] = field(default_factory=list)
    """:class:`~mien.facs.clip.Clip` objects to start playing at the next tick."""


class Registry:
    """Characters stepped together; see the module docstring."""

    def __init__(self, counters: Counters | None = None) -> None:
        from mien.character import CharacterBatch

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
        self._rigs: dict[tuple[str, str | None, bool], tuple[Any, Any]] = {}
        self._log = RateLimitedLog()

    # ------------------------------------------------------------------ characters

    @property
    def default_id(self) -> str | None:
        """The first character's id (the target of messages without ``character``)."""
        return next(iter(self.entries), None)

    def add(self, spec: CharacterSpec) -> Entry:
        """Create a character (raises :class:`InvalidValueError` if the id is taken, UnknownNameError for a
        bad head or identity)."""
        from mien.character import EXPRESSION_BASES

        if spec.id in self.entries:
            raise InvalidValueError("id", spec.id, "an id not in use (DELETE it first)")
        if spec.expression_basis not in EXPRESSION_BASES:
            raise UnknownNameError("expression basis", spec.expression_basis, EXPRESSION_BASES)
        key = (spec.head, spec.identity, spec.expression_basis == "feature_points")
        if key not in self._rigs:
            from mien.rig.driver import RigDriver
            from mien.rig.heads import load_head

            rig = load_head(spec.head, spec.identity, feature_points=key[2])
            self._rigs[key] = (rig, RigDriver(rig))
        rig, driver = self._rigs[key]
        row = int(self.batch.add_character(seed=spec.seed, idle=spec.idle, expression_basis=spec.expression_basis))
        entry = Entry(spec, row, rig, driver)
        if spec.idle:
            from mien.facs.idle import IdleSettings

            entry.idle = IdleSettings()
        self.entries[spec.id] = entry
        return entry

    def remove(self, character_id: str) -> None:
        """Remove a character (its row is freed)."""
        entry = self.get(character_id)
        self.batch.remove_character(entry.row)
        del self.entries[character_id]

    def get(self, character_id: str) -> Entry:
        """The character ``character_id`` (raises :class:`UnknownNameError`)."""
        try:
            return self.entries[character_id]
        except KeyError:
            raise UnknownNameError("character", character_id, tuple(self.entries)) from None

    # ------------------------------------------------------------------ commands

    def submit(self, message: Message, default: str | None = None) -> Entry:
        """Queue ``message`` for its character (``message.character``, else ``default``, else the first).

        Raises :class:`MessageRejected` (``unknown_character``) when there is no such character.
        """
        character_id = message.character or default or self.default_id
        entry = self.entries.get(character_id) if character_id is not None else None
        if entry is None:
            raise MessageRejected(Rejection.UNKNOWN_CHARACTER, f"character={character_id!r} does not exist")
        if message.aus is not None:
            if entry.state is not None:
                self.counters.coalesced += 1
            entry.state = message
        if message.has_events:
            entry.events.append(message)
        return entry

    def reject(self, error: MessageRejected) -> None:
        """Count and (rate-limited) log a dropped message."""
        self.counters.rejections[error.reason.value] += 1
        self._log.warn(error.reason.value, error.detail)

    def _apply_state(self, row: int, message: Message) -> None:
        aus = dict(message.aus or ())
        self.batch.set_aus(row, aus, replace=True)
        if message.speed is not None:
            self.batch.set_speed(row, message.speed)
        for au, speed in message.speeds:
            self.batch.set_speed(row, speed, au=au)
        for au, tau_s in message.tau_s:
            self.batch.set_au(row, au, aus.get(au, 0.0), tau_s=tau_s)

    def _apply_idle(self, entry: Entry, switches: tuple[tuple[str, bool], ...], t_s: float) -> None:
        from dataclasses import replace

        from mien.facs.idle import IdleSettings
        from mien.server.protocol import idle_parts

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
            self.batch.emote(row, message.emotion, message.intensity, t_s)
        if message.pad is not None:
            self.batch.set_pad(row, *message.pad, t_s)
        if message.laugh is not None:
            self.batch.laugh(row, message.laugh, message.intensity, start_s=t_s, seed=seed)

    def apply_pending(self, t_s: float) -> None:
        """Apply every queued command at ``t_s`` (engine errors are counted as ``engine_error``, never raised)."""
        for entry in self.entries.values():
            if entry.state is None and not entry.events and not entry.clips:
                continue
            try:
                if entry.state is not None:
                    message, entry.state = entry.state, None
                    self._apply_state(entry.row, message)
                while entry.events:
                    self._apply_event(entry, entry.events.popleft(), t_s)
                while entry.clips:
                    self.batch.play_clip(entry.row, entry.clips.pop(0), start_s=t_s)
            except MienError as exc:
                self.reject(MessageRejected(Rejection.ENGINE_ERROR, f"{entry.spec.id}: {exc}"))

    def step(self, t_s: float) -> np.ndarray:
        """Apply queued commands and step every character to ``t_s``; returns the (n_rows, 62) frames."""
        self.apply_pending(t_s)
        self.frames = self.batch.step(t_s)
        self.time_s = t_s
        return self.frames

    def rig_output(self, entry: Entry) -> tuple[np.ndarray, np.ndarray]:
        """``(weights (n_targets,) float32, pose (5,) degrees)`` of ``entry`` at the last step."""
        frames = self.frames[entry.row : entry.row + 1]
        features = None
        if entry.spec.expression_basis == "feature_points":
            features = self.batch.feature_weights[entry.row : entry.row + 1]
        return entry.driver.weights(frames, feature_weights=features)[0], entry.driver.pose(frames)[0]

    def state(self, entry: Entry) -> dict[str, Any]:
        """The character's face frame at the last step as ``{channel: value}`` (AUs 0..5, pose degrees)."""
        from mien.facs.catalogue import FACE_CHANNELS

        if entry.row >= self.frames.shape[0]:
            return dict.fromkeys(FACE_CHANNELS, 0.0)
        return dict(zip(FACE_CHANNELS, self.frames[entry.row].tolist(), strict=True))
