"""The 13 laugh and smile types as data: action units, mouth, laughter pulses and dynamics.

Read from ``data/taxonomy.csv`` (sources cited there: Faigin 1990, FACS, Ekman, Davidson & Friesen 1990,
Schmidt et al. 2003/2006, Ruch & Ekman 2001, Bachorowski et al. 2001). Genuine smiles and laughs carry the
Duchenne marker AU6 (cheek raise); the false smile and false laughter do not.

>>> recipe("false_smile").au_intensity(6)
0.0
>>> recipe("sly_smile").au_intensity(4)
3.0
"""

from __future__ import annotations

from dataclasses import dataclass

from mien.errors import InvalidValueError, UnknownNameError
from mien.facs.catalogue import au_channels
from mien.facs.intensity import check_intensity, parse_au
from mien.fileio.tables import read_table
from mien.laughter.names import LAUGH_TYPES

__all__ = ["TAXONOMY", "LaughRecipe", "recipe"]


@dataclass(frozen=True)
class LaughRecipe:
    """One laugh/smile type: which AUs at what apex intensity, and how it moves in time."""

    type: str
    """Identifier, one of :data:`~mien.laughter.names.LAUGH_TYPES`."""
    label: str
    """Human-readable name (``"Sly smile"``)."""
    family: str
    """``"smile"`` or ``"laugh"``."""
    aus: tuple[tuple[int, str | None, float], ...]
    """``(code, side or None, apex intensity 0..5)`` for each action unit."""
    duchenne: bool
    """True when the cheek raise AU6 (the Duchenne marker of felt joy) is present."""
    mouth: str
    """``"closed"``, ``"parted"`` (lips apart, jaw closed) or ``"open"`` (jaw dropped)."""
    pulses: bool
    """True for laughter: repeated exhaled "ha" pulses on the jaw."""
    pulse_rate_hz: float
    """Typical "ha" pulse rate in Hz (0 when ``pulses`` is False)."""
    onset_s: float
    """Typical onset (neutral to apex) duration in seconds."""
    apex_s: float
    """Typical apex (held) duration in seconds."""
    offset_s: float
    """Typical offset (apex to neutral) duration in seconds."""
    asymmetry: float
    """0 = symmetric; 0.3 = the character's left side 30% weaker."""
    head_pitch_deg: float
    """Head pitch at the apex in degrees (> 0 chin up, the head thrown back)."""
    voluntary: bool
    """True for posed or controlled expressions."""
    sources: tuple[str, ...]
    """Keys of the sources cited in the data file (``F``, ``EDF``, ``RE01``...)."""
    notes: str
    """One-line description."""

    @property
    def duration_s(self) -> float:
        """Typical total duration in seconds (onset + apex + offset)."""
        return self.onset_s + self.apex_s + self.offset_s

    def au_intensity(self, code: int, side: str | None = None) -> float:
        """Apex intensity (0..5) of AU ``code`` (on ``side`` ``"L"``/``"R"``, or its strongest side); 0 if absent."""
        best = 0.0
        for au_code, au_side, value in self.aus:
            if au_code == code and (side is None or au_side is None or au_side == side):
                best = max(best, value)
        return best

    def au_frame(self) -> dict[int, float]:
        """Apex intensities by face-frame channel index (asymmetry applied to the left side)."""
        frame: dict[int, float] = {}
        for code, side, value in self.aus:
            for index in au_channels(code, side):
                frame[index] = value
            if side is None and len(au_channels(code)) == 2:
                left = au_channels(code, "L")[0]
                frame[left] = value * (1.0 - self.asymmetry)
        return frame


def _parse_aus(text: str, type_name: str) -> tuple[tuple[int, str | None, float], ...]:
    out: list[tuple[int, str | None, float]] = []
    for item in text.split():
        name, _, value = item.partition("=")
        spec = parse_au(name)
        out.append((spec.code, spec.side, check_intensity(float(value), f"{type_name}.{name}")))
    return tuple(out)


def _load() -> dict[str, LaughRecipe]:
    rows = read_table("mien.laughter", "data/taxonomy.csv")
    out: dict[str, LaughRecipe] = {}
    for row in rows:
        name = row["type"]
        if name not in LAUGH_TYPES:
            raise UnknownNameError("laugh type in taxonomy.csv", name, LAUGH_TYPES)
        out[name] = LaughRecipe(
            type=name,
            label=row["label"],
            family=row["family"],
            aus=_parse_aus(row["aus"], name),
            duchenne=row["duchenne"] == "1",
            mouth=row["mouth"],
            pulses=row["pulses"] == "1",
            pulse_rate_hz=float(row["pulse_rate_hz"]),
            onset_s=float(row["onset_s"]),
            apex_s=float(row["apex_s"]),
            offset_s=float(row["offset_s"]),
            asymmetry=float(row["asymmetry"]),
            head_pitch_deg=float(row["head_pitch_deg"]),
            voluntary=row["voluntary"] == "1",
            sources=tuple(row["sources"].split(";")),
            notes=row["notes"],
        )
    missing = [t for t in LAUGH_TYPES if t not in out]
    if missing:
        raise InvalidValueError("taxonomy.csv", missing, "a row for each of the 13 laugh types")
    return {t: out[t] for t in LAUGH_TYPES}


TAXONOMY: dict[str, LaughRecipe] = _load()
"""Every laugh/smile type's recipe, in :data:`~mien.laughter.names.LAUGH_TYPES` order."""


def recipe(type_name: str) -> LaughRecipe:
    """The recipe of ``type_name``; raises :class:`UnknownNameError` listing the 13 types."""
    try:
        return TAXONOMY[type_name]
    except (KeyError, TypeError):
        raise UnknownNameError("laugh type", type_name, LAUGH_TYPES) from None
