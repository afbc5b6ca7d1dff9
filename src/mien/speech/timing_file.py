"""Phoneme or viseme timing files from any TTS: a small JSON or CSV format.

JSON (``.json``)::

    {"format": "mien.speech.timing", "version": 1,
     "alphabet": "espeak",                      # "viseme", "espeak" or "arpabet"
     "audio": "hello.wav",                      # optional: the sound, relative to this file
     "segments": [{"start_s": 0.0, "end_s": 0.08, "unit": "h"},
                  {"start_s": 0.08, "end_s": 0.17, "unit": "@"}]}

CSV (``.csv``; ``#`` lines are comments): a header naming the time unit and the alphabet, one segment a row::

    start_s,end_s,arpabet
    0.00,0.08,HH
    0.08,0.17,AH0

Times are seconds (``start_s``/``end_s``) or milliseconds (``start_ms``/``end_ms``); no other unit is read.
Segments are in time order and tile the speech: each starts where the previous ends (within
:data:`TOLERANCE_S`); a pause is a segment of its own (``sil``, espeak ``_``, ARPABET ``SIL``/``SP``). The
first may start after 0 (silence before it). Overlaps, gaps, unknown time units and unknown phonemes or
visemes are refused with :class:`~mien.errors.InvalidValueError` naming the row.
"""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path
from typing import Any

from mien.errors import InvalidValueError, UnknownNameError
from mien.speech.audio import read_audio
from mien.speech.coarticulation import TAIL_S, coarticulate
from mien.speech.phonemes import ALPHABETS, viseme_of
from mien.speech.track import Audio, Segment, Utterance
from mien.speech.visemes import VISEMES

__all__ = ["FORMAT", "MAX_SEGMENTS", "TOLERANCE_S", "read_timing", "read_timing_segments"]

FORMAT = "mien.speech.timing"
"""The ``format`` value of a JSON timing file."""

TOLERANCE_S = 0.001
"""How far a segment's start may sit from the previous end before it is an overlap or a gap, seconds."""

MAX_SEGMENTS = 200_000
"""Most segments one file may hold."""

_UNITS = {"s": 1.0, "ms": 0.001}


def _scale(keys: list[str], where: str) -> tuple[str, str, float]:
    for unit, scale in _UNITS.items():
        if f"start_{unit}" in keys and f"end_{unit}" in keys:
            return f"start_{unit}", f"end_{unit}", scale
    raise InvalidValueError(
        f"{where} time columns", ",".join(keys), "start_s,end_s (seconds) or start_ms,end_ms (milliseconds)"
    )


def _visemes(units: list[str], alphabet: str, where: str) -> list[str]:
    if alphabet == "viseme":
        unknown = [u for u in units if u not in VISEMES]
        if unknown:
            raise UnknownNameError(f"viseme in {where}", unknown[0], VISEMES)
        return units
    if alphabet not in ALPHABETS:
        raise UnknownNameError(f"alphabet in {where}", alphabet, ("viseme", *ALPHABETS))
    return [viseme_of(u, alphabet, strict=True) for u in units]


def read_timing_segments(path: str | Path) -> tuple[list[Segment], Path | None]:
    """The checked segments of timing file ``path`` and its audio path (JSON ``"audio"``), if any."""
    source = Path(path)
    try:
        text = source.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise InvalidValueError("timing file", str(path), f"a readable UTF-8 JSON or CSV file ({error})") from None
    where = source.name
    audio: Path | None = None
    if source.suffix.lower() == ".json":
        try:
            data = json.loads(text)
        except json.JSONDecodeError as error:
            raise InvalidValueError("timing file", str(path), f"JSON ({error})") from None
        if not isinstance(data, dict) or not isinstance(data.get("segments"), list):
            raise InvalidValueError("timing file", str(path), f'a JSON object with "segments" (format {FORMAT})')
        rows: list[Any] = data["segments"]
        alphabet = str(data.get("alphabet", "viseme"))
        if data.get("audio"):
            audio = (source.parent / str(data["audio"])).resolve()
        if any(not isinstance(row, dict) for row in rows):
            raise InvalidValueError(f"{where} segments", "a non-object", '{"start_s": ..., "end_s": ..., "unit": ...}')
        keys = sorted({key for row in rows for key in row} - {"unit"}) if rows else ["start_s", "end_s"]
        start_key, end_key, scale = _scale(keys, where)
        units = [str(row.get("unit", "")) for row in rows]
        times = [(row.get(start_key), row.get(end_key)) for row in rows]
    elif source.suffix.lower() == ".csv":
        lines = "\n".join(line for line in text.splitlines() if line.strip() and not line.startswith("#"))
        reader = csv.reader(io.StringIO(lines))
        header = [name.strip() for name in next(reader, [])]
        if len(header) != 3:
            raise InvalidValueError(
                f"{where} header", ",".join(header), "three columns: start_s,end_s,<viseme|espeak|arpabet>"
            )
        start_key, end_key, scale = _scale(header[:2], where)
        alphabet = header[2]
        table = list(reader)
        if any(len(row) != 3 for row in table):
            raise InvalidValueError(f"{where} row", next(r for r in table if len(r) != 3), "three values a row")
        units = [row[2].strip() for row in table]
        times = [(row[0], row[1]) for row in table]
    else:
        raise InvalidValueError("timing file", str(path), "a .json or .csv timing file (see mien.speech.timing_file)")
    if not units:
        raise InvalidValueError("timing file", str(path), "at least one segment")
    if len(units) > MAX_SEGMENTS:
        raise InvalidValueError("timing file", f"{len(units)} segments", f"at most {MAX_SEGMENTS}")
    visemes = _visemes(units, alphabet, where)
    segments: list[Segment] = []
    for i, ((start_text, end_text), viseme, unit) in enumerate(zip(times, visemes, units, strict=True)):
        try:
            start, end = float(start_text) * scale, float(end_text) * scale
        except (TypeError, ValueError):
            raise InvalidValueError(f"{where} segment {i + 1} times", (start_text, end_text), "numbers") from None
        if not (math.isfinite(start) and math.isfinite(end) and 0.0 <= start < end):
            raise InvalidValueError(f"{where} segment {i + 1}", (start_text, end_text), "0 <= start < end")
        if segments:
            previous = segments[-1].end_s
            if start < previous - TOLERANCE_S:
                raise InvalidValueError(
                    f"{where} segment {i + 1}",
                    f"starts at {start:g} s",
                    f"no overlap: the previous ends at {previous:g} s",
                )
            if start > previous + TOLERANCE_S:
                raise InvalidValueError(
                    f"{where} segment {i + 1}",
                    f"starts at {start:g} s",
                    f"no gap: the previous ends at {previous:g} s (write pauses as sil / _ / SIL segments)",
                )
            start = previous
        segments.append(Segment(start, end, viseme, "" if alphabet == "viseme" else unit))
    return segments, audio


def read_timing(path: str | Path, audio: Audio | str | Path | None = None) -> Utterance:
    """An :class:`Utterance` from timing file ``path``, with ``audio`` (or the file's own ``"audio"``) as its sound."""
    segments, own_audio = read_timing_segments(path)
    given = audio if audio is not None else own_audio
    sound = read_audio(given) if isinstance(given, str | Path) else given
    duration = max(segments[-1].end_s, sound.duration_s if sound is not None else 0.0)
    track = coarticulate(segments, duration_s=duration + (TAIL_S if sound is None else 0.0))
    return Utterance(track, tuple(segments), sound, "", "timing file", {"timing": str(path)})
