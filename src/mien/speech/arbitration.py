"""Who owns which face channel while a character speaks: the rule as data plus one function.

``data/arbitration.csv`` lists, per AU, ``speech`` (speech owns it while speaking: the lips' opening and
rounding and the jaw) or ``add`` (the other layers keep it and speech adds to it: the spread of E, I, SS over
the emotion's lip corners); every channel it does not list (brows, lids, cheeks, nose, lip corners, the upper
lip, blinks, head and gaze) stays the other layers' own. :func:`arbitrate` applies it.

Around it, in :class:`~mien.speech.batch.SpeechBatch` and :meth:`mien.character.CharacterBatch.step`:
laughter interrupts speech (the speech fades out over :data:`LAUGH_FADE_S` as a laugh starts and back in as
it ends; the speech keeps its clock, so the mouth comes back in sync with the sound), idle mouth motion
yields in proportion to the speaking presence, and blinks are applied after everything and always show.

>>> [FACE_CHANNELS[i] for i in SPEECH_CHANNELS[:4]]
['AU16L', 'AU16R', 'AU17', 'AU18']
>>> face = np.zeros((1, len(SPEECH_CHANNELS))); face[0, list(SPEECH_CHANNELS).index(FACE_CHANNELS.index("AU25"))] = 1.5
>>> out = arbitrate(face, np.zeros_like(face), np.array([1.0]))   # a bilabial closure over joy's parted lips
>>> float(out.max())
0.0
"""

from __future__ import annotations

import numpy as np

from mien.errors import InvalidValueError
from mien.facs.catalogue import FACE_CHANNELS, au_channels
from mien.fileio.tables import read_table, table_version

__all__ = [
    "ARBITRATION_VERSION",
    "LAUGH_FADE_S",
    "REPLACES",
    "RULES",
    "SPAN",
    "SPEECH_CHANNELS",
    "arbitrate",
    "keep_fraction",
]

_TABLE = ("mien.speech", "data/arbitration.csv")

LAUGH_FADE_S = 0.12
"""Seconds over which speech fades out as a laugh starts (and back in as it ends)."""


def _load() -> tuple[dict[str, str], np.ndarray, np.ndarray]:
    rules: dict[str, str] = {}
    channels: list[int] = []
    replaces: list[float] = []
    for row in read_table(*_TABLE):
        if row["rule"] not in ("speech", "add"):
            raise InvalidValueError("arbitration rule", row["rule"], "speech or add")
        for channel in au_channels(int(row["au"])):
            rules[FACE_CHANNELS[channel]] = row["rule"]
            channels.append(channel)
            replaces.append(1.0 if row["rule"] == "speech" else 0.0)
    order = np.argsort(channels)
    return rules, np.array(channels)[order], np.array(replaces)[order]


_LOADED = _load()
RULES: dict[str, str] = _LOADED[0]
"""Face channel -> ``"speech"`` or ``"add"``; channels not listed are the other layers' own."""
SPEECH_CHANNELS: np.ndarray = _LOADED[1]
"""(k,) int positions in :data:`~mien.facs.catalogue.FACE_CHANNELS` that speech writes, ascending."""
REPLACES: np.ndarray = _LOADED[2]
"""(k,) 1.0 where speech owns the channel (``speech``), 0.0 where it adds (``add``)."""

SPAN = slice(int(SPEECH_CHANNELS.min()), int(SPEECH_CHANNELS.max()) + 1)
"""The face-frame columns from the first to the last speech channel (contiguous: AU16L..AU28), where the
engine applies the rule in place; the columns in it that speech does not write keep exactly their value."""

_REPLACES_IN_SPAN = np.zeros(SPAN.stop - SPAN.start)
_REPLACES_IN_SPAN[SPEECH_CHANNELS - SPAN.start] = REPLACES

ARBITRATION_VERSION: str = table_version(*_TABLE)
"""The ``# version:`` of the shipped arbitration table."""


def arbitrate(face: np.ndarray, speech: np.ndarray, presence: np.ndarray) -> np.ndarray:
    """Blend speech into the face on :data:`SPEECH_CHANNELS`: the one arbitration rule.

    ``face`` (n, k): the other layers' values (FACS, emotion, mood) on those channels, AU intensity 0..5;
    ``speech`` (n, k): the speech layer's values there, already weighted by how much speech holds the mouth
    (``viseme weights @ viseme shapes``, 0 at rest); ``presence`` (n,): that hold, 0..1 (1 - weight of
    ``sil``, times any laughter fade). Returns (n, k)::

        owned ("speech"):  face * (1 - presence) + speech
        shared ("add"):    face + speech

    so a speaking mouth closes on /p b m/ whatever the emotion opened, and a silent one is the emotion's.
    The engine applies the same rule over :data:`SPAN` as ``face * keep_fraction(presence) + speech``.
    """
    return face * keep_fraction(presence, span=False) + speech


def keep_fraction(presence: np.ndarray, span: bool = True) -> np.ndarray:
    """(n, k) how much of the other layers' value each channel keeps: ``1 - presence * REPLACES``.

    Over :data:`SPEECH_CHANNELS`, or (``span=True``) over every column of :data:`SPAN` (1 where speech does not
    write). Linear in ``presence``, so interpolating it between two frames is interpolating the presence.
    """
    replaces = _REPLACES_IN_SPAN if span else REPLACES
    return 1.0 - np.asarray(presence, dtype=np.float64)[:, None] * replaces
