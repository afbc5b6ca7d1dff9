"""FACS intensities (0..5, letters A..E) and parsing of action-unit strings.

Accepted spellings (case-insensitive): ``AU12``, ``12``, ``12C``, ``AU12C``, ``AU12L``, ``AU12LC``,
``AU12CL``, ``L12``, ``L12C``, ``R12B``. Letters map A=1 .. E=5 (FACS's ordinal scale as OpenFACS's
integers); fractional intensities are allowed everywhere else.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from mien.errors import InvalidValueError, UnknownNameError
from mien.facs.catalogue import action_unit

__all__ = [
    "INTENSITY_LETTERS",
    "MAX_INTENSITY",
    "AUSpec",
    "check_intensity",
    "intensity_letter",
    "parse_au",
]

MAX_INTENSITY = 5.0
"""Top of the FACS scale (E): the largest AU intensity and the largest emotion intensity mien accepts (1 = the
prototype / Table 1 magnitude; the study used 1.2 and 2.4). The one home of this limit."""

INTENSITY_LETTERS = {"A": 1.0, "B": 2.0, "C": 3.0, "D": 4.0, "E": 5.0}
"""FACS intensity letters and the value each stands for."""

_PATTERN = re.compile(r"^(?P<pre>[LR])?(?:AU)?(?P<code>\d+)(?P<s1>[LR])?(?P<letter>[A-E])?(?P<s2>[LR])?$")


def check_intensity(value: float, field: str = "intensity") -> float:
    """Return ``value`` as float if it is a finite number in 0..5, else raise :class:`InvalidValueError`."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InvalidValueError(field, value, f"a number in [0, {MAX_INTENSITY:g}]") from None
    if not math.isfinite(number) or not 0.0 <= number <= MAX_INTENSITY:
        raise InvalidValueError(field, value, f"a finite number in [0, {MAX_INTENSITY:g}]")
    return number


def intensity_letter(value: float) -> str:
    """FACS letter of an intensity (rounded): ``""`` for below 0.5 (absent), else ``"A"``..``"E"``.

    >>> intensity_letter(2.6)
    'C'
    """
    value = check_intensity(value)
    if value < 0.5:
        return ""
    return "ABCDE"[min(4, round(value) - 1)]


@dataclass(frozen=True)
class AUSpec:
    """A parsed action-unit string: which AU, which side, at what intensity."""

    code: int
    """FACS code."""
    side: str | None
    """``"L"``, ``"R"`` or ``None`` for both sides / a midline AU."""
    intensity: float | None
    """0..5 from the letter, or ``None`` when the string gave no letter."""

    @property
    def label(self) -> str:
        """Canonical spelling, e.g. ``"AU12LC"``."""
        letter = intensity_letter(self.intensity) if self.intensity is not None else ""
        return f"AU{self.code}{self.side or ''}{letter}"


def parse_au(text: str) -> AUSpec:
    """Parse ``"AU12"``, ``"12C"``, ``"AU12L"``, ``"L12C"``... into an :class:`AUSpec`.

    >>> parse_au("L12C")
    AUSpec(code=12, side='L', intensity=3.0)
    >>> parse_au("au6e")
    AUSpec(code=6, side=None, intensity=5.0)
    """
    if not isinstance(text, str):
        raise UnknownNameError("action unit", text)
    match = _PATTERN.match(text.strip().upper())
    if match is None:
        raise UnknownNameError("action unit", text, ("AU12", "12C", "AU12C", "AU12L", "L12C"))
    sides = [s for s in (match["pre"], match["s1"], match["s2"]) if s]
    if len(sides) > 1:
        raise UnknownNameError("action unit", text, ("give the side once, e.g. L12C or AU12LC",))
    code = int(match["code"])
    au = action_unit(code)
    side = sides[0] if sides else None
    if side is not None and not au.lateral:
        raise UnknownNameError("action unit side", text, (f"AU{code} has no left/right variant",))
    letter = match["letter"]
    return AUSpec(code=code, side=side, intensity=INTENSITY_LETTERS[letter] if letter else None)
