"""The FACS action-unit catalogue as data, and the dense channel layout of a face frame.

The catalogue is read from ``data/action_units.csv`` (sources cited there). A face frame is a dense float
vector over :data:`FACE_CHANNELS`: one intensity channel per action unit (two, ``AU12L`` and ``AU12R``, for
AUs FACS allows to be scored on one side), then head rotation and eye gaze in degrees.

Directions: ``head_yaw_deg`` > 0 turns the head to the character's left, ``head_pitch_deg`` > 0 raises the
chin, ``head_roll_deg`` > 0 tilts the head toward the character's left shoulder; ``gaze_yaw_deg`` > 0 looks
to the character's left, ``gaze_pitch_deg`` > 0 looks up.
"""

from __future__ import annotations

from dataclasses import dataclass

from mien.errors import UnknownNameError
from mien.fileio.tables import read_table

__all__ = [
    "ACTION_UNITS",
    "FACE_AU_CODES",
    "FACE_CHANNELS",
    "OPENFACS_AUS",
    "POSE_CHANNELS",
    "ActionUnit",
    "action_unit",
    "au_channels",
    "channel_index",
]


@dataclass(frozen=True)
class ActionUnit:
    """One FACS action (an AU, a head or an eye action code)."""

    code: int
    """FACS number, e.g. 12."""
    name: str
    """FACS name, e.g. ``"Lip Corner Puller"``."""
    muscles: str
    """Muscular basis as FACS gives it (empty for head and eye codes)."""
    lateral: bool
    """True when FACS scores it on one side (``L12``/``R12``); mien then keeps two channels."""
    openfacs: bool
    """True for the 18 AUs that OpenFACS animates."""
    kind: str
    """``"face"`` (intensity channel), ``"head"`` or ``"eye"`` (rotation channel)."""
    channel: str
    """For head/eye codes, the pose channel it turns; empty for face AUs."""
    degrees_per_unit: float
    """For head/eye codes, degrees of rotation per intensity unit (sign gives the direction)."""

    @property
    def label(self) -> str:
        """``"AU12"`` style label."""
        return f"AU{self.code}"


def _load() -> dict[int, ActionUnit]:
    rows = read_table("mien.facs", "data/action_units.csv")
    out: dict[int, ActionUnit] = {}
    for row in rows:
        code = int(row["code"])
        out[code] = ActionUnit(
            code=code,
            name=row["name"],
            muscles=row["muscles"],
            lateral=row["lateral"] == "1",
            openfacs=row["openfacs"] == "1",
            kind=row["kind"],
            channel=row["channel"],
            degrees_per_unit=float(row["degrees_per_unit"] or 0.0),
        )
    return out


ACTION_UNITS: dict[int, ActionUnit] = _load()
"""Every action mien knows, by FACS code."""

OPENFACS_AUS: tuple[int, ...] = tuple(code for code, au in ACTION_UNITS.items() if au.openfacs)
"""The 18 AUs of OpenFACS: 1, 2, 4, 5, 6, 7, 9, 10, 12, 14, 15, 17, 20, 23, 25, 26, 28, 45."""

FACE_AU_CODES: tuple[int, ...] = tuple(code for code, au in ACTION_UNITS.items() if au.kind == "face")
"""Codes of the AUs that have intensity channels."""

POSE_CHANNELS: tuple[str, ...] = (
    "head_yaw_deg",
    "head_pitch_deg",
    "head_roll_deg",
    "gaze_yaw_deg",
    "gaze_pitch_deg",
)
"""Head rotation and eye gaze channels, in degrees."""


def _face_channels() -> tuple[str, ...]:
    names: list[str] = []
    for code in FACE_AU_CODES:
        if ACTION_UNITS[code].lateral:
            names += [f"AU{code}L", f"AU{code}R"]
        else:
            names.append(f"AU{code}")
    return tuple(names) + POSE_CHANNELS


FACE_CHANNELS: tuple[str, ...] = _face_channels()
"""Channel names of a face frame, in order: AU intensities (0..5), then :data:`POSE_CHANNELS`."""

_CHANNEL_INDEX = {name: i for i, name in enumerate(FACE_CHANNELS)}


def channel_index(name: str) -> int:
    """Position of channel ``name`` in a face frame; raises :class:`UnknownNameError`."""
    try:
        return _CHANNEL_INDEX[name]
    except KeyError:
        raise UnknownNameError("channel", name, FACE_CHANNELS) from None


def action_unit(code: int) -> ActionUnit:
    """The catalogue entry for FACS ``code``; raises :class:`UnknownNameError`."""
    try:
        return ACTION_UNITS[code]
    except KeyError:
        known = tuple(f"AU{c}" for c in ACTION_UNITS)
        raise UnknownNameError("action unit", f"AU{code}", known) from None


def au_channels(code: int, side: str | None = None) -> tuple[int, ...]:
    """Face-frame positions an AU drives: both sides, or one (``side`` ``"L"``/``"R"``).

    >>> [FACE_CHANNELS[i] for i in au_channels(12)]
    ['AU12L', 'AU12R']
    >>> [FACE_CHANNELS[i] for i in au_channels(12, "L")]
    ['AU12L']
    """
    au = action_unit(code)
    if au.kind != "face":
        return (_CHANNEL_INDEX[au.channel],)
    if not au.lateral:
        if side is not None:
            raise UnknownNameError("action unit side", f"{side}{code}", (f"AU{code} has no left/right variant",))
        return (_CHANNEL_INDEX[f"AU{code}"],)
    if side is None:
        return (_CHANNEL_INDEX[f"AU{code}L"], _CHANNEL_INDEX[f"AU{code}R"])
    return (_CHANNEL_INDEX[f"AU{code}{side}"],)
