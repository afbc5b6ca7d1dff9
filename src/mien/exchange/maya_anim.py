"""Maya ASCII ``.anim`` curves (the format Mascaró et al. 2021 hand to animators): writer and reader.

Format (Autodesk, "ANIM file format", Maya help, version 1.1): header lines ``animVersion 1.1;``,
``mayaVersion 2020;``, ``timeUnit film;`` (frames per second by name, or ``<n>fps``), ``linearUnit cm;``,
``angularUnit deg;``, ``startTime N;``, ``endTime N;``; then per curve
``anim <fullAttribute> <leafAttribute> <node> <row> <childCount> <attributeIndex>;`` and an ``animData { ... }``
block (``input time; output unitless; weighted 0; preInfinity constant; postInfinity constant;`` and
``keys { <frame> <value> <inTangent> <outTangent> <tanLocked> <weightLocked> <breakdown>; ... }``, where a
``fixed`` tangent is followed by its angle (angular unit) and weight). ``//`` and ``#`` start comments.

mien writes one ``unitless`` curve per channel (laughter controllers, ARKit weights, AU intensities) on one
node, with ``linear`` tangents: keys come from :func:`~mien.exchange.key_reduction.reduce_keys`, so sampling
the file back (:func:`to_clip`) reproduces every original sample within the stated tolerance (by default 0.5 %
of each curve's value range). Values are written with Python's shortest round-trip ``repr``, so keys are exact.

The reader evaluates other tangent types as well: ``step``/``stepnext`` hold, ``flat`` has zero slope,
``fixed`` uses its angle (slope ``tan(angle)`` in value per second), and the smooth types (``spline``,
``auto``, ``clamped``, ``plateau``, ``smooth``, ``global``, ``slow``, ``fast``) use Catmull-Rom slopes, flattened
at local extrema for ``auto``/``clamped``/``plateau``; cubic Hermite segments join them. For those types the
result approximates Maya's evaluation; linear keys are exact.
"""

from __future__ import annotations

import math
import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from mien.errors import InvalidValueError
from mien.exchange.key_reduction import default_tolerance, reduce_keys
from mien.exchange.timing import resample
from mien.facs.clip import Clip
from mien.fileio.limits import check_count, current
from mien.fileio.streams import Source, TargetT, read_bytes, refuse_rig, source_name, write_text

__all__ = [
    "MAYA_FPS_UNITS",
    "SUFFIXES",
    "TIME_UNITS",
    "AnimCurve",
    "AnimFile",
    "controller_script",
    "evaluate_curve",
    "fps_to_time_unit",
    "read",
    "read_curves",
    "to_clip",
    "write",
]

SUFFIXES: tuple[str, ...] = (".anim",)
"""File suffixes of this format."""

TIME_UNITS: dict[str, float] = {
    "game": 15.0,
    "film": 24.0,
    "pal": 25.0,
    "ntsc": 30.0,
    "show": 48.0,
    "palf": 50.0,
    "ntscf": 60.0,
    "hour": 1.0 / 3600.0,
    "min": 1.0 / 60.0,
    "sec": 1.0,
    "millisec": 1000.0,
}
"""Maya time-unit names -> frames per second (Maya help, "ANIM file format"; ``<n>fps`` names are parsed)."""

MAYA_FPS_UNITS: tuple[float, ...] = (
    2, 3, 4, 5, 6, 8, 10, 12, 16, 20, 23.976, 29.97, 40, 47.952, 59.94, 75, 80, 100, 120, 125, 150, 200, 240,
    250, 300, 375, 400, 500, 600, 750, 1200, 1500, 2000, 3000, 6000,
)  # fmt: skip
"""Rates Maya's ``<n>fps`` time units name (Maya 2018+ ``currentUnit -time``), besides the named units
(:data:`TIME_UNITS`). A clip at any other rate is resampled to the next higher rate Maya names."""

_WRITE_NAMES = {15.0: "game", 24.0: "film", 25.0: "pal", 30.0: "ntsc", 48.0: "show", 50.0: "palf", 60.0: "ntscf"}
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_TANGENTS: tuple[str, ...] = ("global", "fixed", "linear", "flat", "step", "stepnext", "slow", "fast", "smooth")
_TANGENTS += ("clamped", "plateau", "spline", "auto")

CurvesInput = Clip | Mapping[str, tuple[np.ndarray, np.ndarray]]
"""A :class:`~mien.facs.clip.Clip` or a dict ``name -> (times_s (n,), values (n,))``."""


@dataclass(frozen=True, eq=False)
class AnimCurve:
    """One ``anim`` curve as read from a file."""

    attribute: str
    """Leaf attribute name (e.g. ``smileFrown``)."""
    node: str
    """Node name the curve drives."""
    frames: np.ndarray
    """(k,) key times in frames of the file's time unit."""
    values: np.ndarray
    """(k,) key values."""
    in_tangents: tuple[str, ...]
    """In-tangent type of each key (``linear``, ``spline``, ``step``...)."""
    out_tangents: tuple[str, ...]
    """Out-tangent type of each key."""
    in_angles: np.ndarray
    """(k,) in-tangent angles for ``fixed`` keys (angular unit of the file), NaN elsewhere."""
    out_angles: np.ndarray
    """(k,) out-tangent angles for ``fixed`` keys, NaN elsewhere."""
    full_attribute: str = ""
    """Full attribute path (``translate.translateX``); the leaf name when equal."""
    settings: dict[str, str] = field(default_factory=dict)
    """The ``animData`` settings (``input``, ``output``, ``weighted``, ``preInfinity``, ``postInfinity``...)."""


@dataclass(frozen=True, eq=False)
class AnimFile:
    """A parsed ``.anim`` file."""

    header: dict[str, str]
    """Header fields as written (``animVersion``, ``mayaVersion``, ``timeUnit``, ``startTime``...)."""
    fps: float
    """Frames per second of ``timeUnit``."""
    curves: dict[str, AnimCurve]
    """Curves by channel name: the leaf attribute, or ``node.attribute`` when two nodes share it."""

    @property
    def start_frame(self) -> float:
        """``startTime`` if given, else the earliest key frame."""
        if "startTime" in self.header:
            return float(self.header["startTime"])
        return min((float(c.frames[0]) for c in self.curves.values()), default=0.0)

    @property
    def end_frame(self) -> float:
        """``endTime`` if given, else the latest key frame."""
        if "endTime" in self.header:
            return float(self.header["endTime"])
        return max((float(c.frames[-1]) for c in self.curves.values()), default=0.0)


# ---------------------------------------------------------------------------------------------------------------
# Writing


def fps_to_time_unit(fps: float) -> str:
    """Maya ``timeUnit`` name for a frame rate Maya names: ``game`` (15), ``film`` (24), ``pal`` (25), ``ntsc``
    (30), ``show`` (48), ``palf`` (50), ``ntscf`` (60), or ``<fps>fps`` for :data:`MAYA_FPS_UNITS`.

    Other rates raise; :func:`maya_rate` gives the rate a clip is resampled to.

    >>> fps_to_time_unit(24), fps_to_time_unit(120), fps_to_time_unit(29.97)
    ('film', '120fps', '29.97fps')
    """
    rate = float(fps)
    if not math.isfinite(rate) or rate <= 0:
        raise InvalidValueError("fps", fps, "a positive finite number")
    if rate in _WRITE_NAMES:
        return _WRITE_NAMES[rate]
    if rate in MAYA_FPS_UNITS:
        return f"{rate:g}fps"
    raise InvalidValueError("fps", fps, f"a rate Maya names ({maya_rate(rate):g} is the next one)")


def maya_rate(fps: float) -> float:
    """``fps`` when Maya has a time unit for it, else the smallest higher rate that Maya names.

    >>> maya_rate(30.0), maya_rate(33.0), maya_rate(7000.0)
    (30.0, 40.0, 6000.0)
    """
    rate = float(fps)
    named = sorted({*_WRITE_NAMES, *MAYA_FPS_UNITS})
    if rate in named:
        return rate
    return float(next((r for r in named if r > rate), named[-1]))


def _maya_names(table: dict[str, tuple[np.ndarray, np.ndarray]]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """``table`` with the dots of its names turned into ``_`` (Maya attribute names have none; see :func:`write`)."""
    renamed = {name: name.replace(".", "_") if _NAME.match(name.replace(".", "_")) else name for name in table}
    changed = [f"{old} -> {new}" for old, new in renamed.items() if old != new]
    if not changed:
        return table
    clash = next((old for old, new in renamed.items() if list(renamed.values()).count(new) > 1), None)
    if clash is not None:
        raise InvalidValueError("channel", clash, f"a name that stays unique as a Maya name ({renamed[clash]})")
    shown = ", ".join(changed[:3]) + (f" and {len(changed) - 3} more" if len(changed) > 3 else "")
    warnings.warn(f"Maya attribute names hold letters, digits and _ only: renamed {shown}", stacklevel=3)
    return {renamed[name]: curve for name, curve in table.items()}


def _number(value: float) -> str:
    """Shortest text that reads back as exactly ``value`` (``1`` rather than ``1.0``)."""
    value = float(value)
    if value == 0.0:
        return "0"
    text = repr(value)
    return text[:-2] if text.endswith(".0") else text


def _frame_text(frame: float) -> str:
    nearest = round(frame)
    return str(int(nearest)) if abs(frame - nearest) < 1e-9 else _number(frame)


def _curves(curves: CurvesInput, fps: float | None) -> tuple[dict[str, tuple[np.ndarray, np.ndarray]], float, str]:
    """(name -> (times_s, values), file rate, note): a clip is resampled to a rate Maya names when needed."""
    if isinstance(curves, Clip):
        wanted = curves.fps if fps is None else float(fps)
        rate = maya_rate(wanted)
        note = ""
        clip = curves
        if rate != curves.fps and curves.n_frames:
            clip = resample(curves, rate, cover_end=True)
            why = f"Maya has no {wanted:g} fps time unit" if rate != wanted else "as asked"
            note = f"// resampled from {curves.fps:g} fps to {rate:g} fps ({why})\n"
        times = clip.times_s
        return {name: (times, clip.values[:, j]) for j, name in enumerate(clip.channels)}, rate, note
    if not isinstance(curves, Mapping):
        raise InvalidValueError("curves", type(curves).__name__, "a Clip or a dict name -> (times_s, values)")
    if fps is None:
        raise InvalidValueError("fps", None, "a frame rate when curves is a dict")
    fps_to_time_unit(fps)  # a dict's key times stay as given: its rate must be one Maya names
    out = {}
    for name, pair in curves.items():
        try:
            times, values = pair
        except (TypeError, ValueError):
            raise InvalidValueError(f"curves[{name!r}]", type(pair).__name__, "a (times_s, values) pair") from None
        out[str(name)] = (np.asarray(times, dtype=np.float64), np.asarray(values, dtype=np.float64))
    return out, float(fps), ""


def _check_keys(name: str, times: np.ndarray, values: np.ndarray, frames: np.ndarray, rate: float) -> np.ndarray:
    """Integer frames of one curve's keys; NaN, unordered keys and keys between frames raise naming the key."""
    if times.ndim != 1 or times.shape != values.shape or times.size == 0:
        raise InvalidValueError(f"curves[{name!r}]", f"shapes {times.shape}, {values.shape}", "(n,) and (n,), n >= 1")
    bad = np.flatnonzero(~(np.isfinite(times) & np.isfinite(values)))
    if bad.size:
        i = int(bad[0])
        raise InvalidValueError(f"curves[{name!r}] key {i}", (float(times[i]), float(values[i])), "finite numbers")
    order = np.flatnonzero(np.diff(times) <= 0)
    if order.size:
        i = int(order[0]) + 1
        raise InvalidValueError(f"curves[{name!r}] key {i}", float(times[i]), "key times increasing, in order")
    whole = np.round(frames)
    off = np.flatnonzero(np.abs(frames - whole) > 1e-6)
    if off.size:
        i = int(off[0])
        raise InvalidValueError(f"curves[{name!r}] key {i}", float(times[i]), f"times on frames of {rate:g} fps")
    return whole


def write(
    curves: CurvesInput,
    target: TargetT,
    rig: object = None,
    *,
    fps: float | None = None,
    node: str = "mien",
    tolerance: float | None = None,
    reduce: bool = True,
    maya_version: str = "2020",
    start_frame: int = 0,
) -> TargetT:
    """Write curves as a Maya ``.anim`` file to ``target`` (a path, written atomically, or a binary stream).

    ``curves``: a Clip (one curve per channel, time ``i / fps``) or a dict ``name -> (times_s, values)``.
    ``fps``: frame rate of the file (default: the clip's). A clip whose rate Maya does not name (33 fps) is
    resampled (linearly) to the next rate Maya names (40 fps; :func:`maya_rate`), and the file says so in a
    comment; a dict's rate must be one Maya names. Time ``t`` seconds is frame ``start_frame + t * fps``; every
    key lies exactly on a frame (a dict key between frames raises). NaN values and keys out of time order raise
    naming the curve and key. ``node``: the Maya node the attributes belong to (``controller_script`` makes it).
    ``reduce``: keep only the keys needed so that linear interpolation reproduces every sample within
    ``tolerance`` (absolute; None: 0.5 % of each curve's value range); otherwise every sample is a key. Channel
    names must be Maya attribute names (letters, digits, ``_``); a ``.`` (a character file's
    ``h_expressions.Kiss_h``) turns into ``_`` with a warning, unless two names would then collide.
    """
    refuse_rig(rig, ".anim")
    table, rate, note = _curves(curves, fps)
    table = _maya_names(table)
    time_unit = fps_to_time_unit(rate)
    if not _NAME.match(node):
        raise InvalidValueError("node", node, "a Maya node name (letters, digits, _)")
    if tolerance is not None and (not math.isfinite(tolerance) or tolerance < 0):
        raise InvalidValueError("tolerance", tolerance, "None or a finite number >= 0")
    if not table:
        raise InvalidValueError("curves", "no curves", "at least one curve")
    blocks: list[str] = []
    first_frame, last_frame = float(start_frame), float(start_frame)
    for index, (name, (times, values)) in enumerate(table.items()):
        if not _NAME.match(name):
            raise InvalidValueError("channel", name, "a Maya attribute name (letters, digits, _)")
        frames_all = _check_keys(name, times, values, start_frame + times * rate, rate)
        keep = np.arange(times.size)
        if reduce:
            limit = default_tolerance(values) if tolerance is None else tolerance
            keep = reduce_keys(times, values, limit)
        frames = frames_all[keep]
        first_frame = min(first_frame, float(frames[0]))
        last_frame = max(last_frame, float(frames[-1]))
        keys = "\n".join(
            f"    {_frame_text(f)} {_number(v)} linear linear 1 1 0;" for f, v in zip(frames, values[keep], strict=True)
        )
        blocks.append(
            f"anim {name} {name} {node} 0 0 {index};\n"
            "animData {\n"
            "  input time;\n"
            "  output unitless;\n"
            "  weighted 0;\n"
            "  preInfinity constant;\n"
            "  postInfinity constant;\n"
            "  keys {\n"
            f"{keys}\n"
            "  }\n"
            "}\n"
        )
    if note:
        warnings.warn(f"{source_name(target)}: {note[3:].strip()}", stacklevel=2)
    header = (
        note + "animVersion 1.1;\n"
        f"mayaVersion {maya_version};\n"
        f"timeUnit {time_unit};\n"
        "linearUnit cm;\n"
        "angularUnit deg;\n"
        f"startTime {_frame_text(first_frame)};\n"
        f"endTime {_frame_text(last_frame)};\n"
    )
    write_text(header + "".join(blocks), target)
    return target


def controller_script(channels: tuple[str, ...] | list[str], node: str = "mien") -> str:
    """MEL that creates ``node`` (a transform) with a keyable double attribute per channel, for a ``.anim`` file.

    Run it in Maya's script editor, select ``node`` and import the ``.anim`` (File > Import, animImportExport
    plug-in): the curves then apply as they are. The general form, which reads the channel names out of any
    ``.anim`` file, is ``mien/exchange/data/mien_controller.mel`` (``mienCreateController "path.anim";``).
    """
    for name in (node, *channels):
        if not _NAME.match(name):
            raise InvalidValueError("channel", name, "a Maya name (letters, digits, _)")
    lines = [f'if (!`objExists "{node}"`) createNode transform -n "{node}";']
    for name in channels:
        lines.append(
            f'if (!`attributeQuery -node "{node}" -exists "{name}"`) addAttr -ln "{name}" -at double -k 1 "{node}";'
        )
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------------------------------
# Reading


def _time_unit_fps(unit: str, where: str, line: str) -> float:
    if unit in TIME_UNITS:
        return TIME_UNITS[unit]
    match = re.fullmatch(r"(\d+(?:\.\d+)?)(fps|df)", unit)
    if match:
        return float(match.group(1))
    raise InvalidValueError(where, line, f"a time unit ({', '.join(TIME_UNITS)} or <n>fps)")


def _float(token: str, where: str, line: str) -> float:
    try:
        value = float(token)
    except ValueError:
        raise InvalidValueError(where, line, f"a number where {token!r} is") from None
    if not math.isfinite(value):
        raise InvalidValueError(where, line, "finite numbers")
    return value


class _Builder:
    """Collects one curve's keys while parsing."""

    def __init__(self, full: str, leaf: str, node: str) -> None:
        self.full, self.leaf, self.node = full, leaf, node
        self.settings: dict[str, str] = {}
        self.keys: list[tuple[float, float, str, str, float, float]] = []

    def build(self, where: str, line: str) -> AnimCurve:
        if not self.keys:
            raise InvalidValueError(where, line, f"at least one key for {self.node}.{self.leaf}")
        frames = np.array([k[0] for k in self.keys])
        if np.any(np.diff(frames) <= 0):
            raise InvalidValueError(where, line, f"increasing key frames for {self.node}.{self.leaf}")
        return AnimCurve(
            attribute=self.leaf,
            node=self.node,
            frames=frames,
            values=np.array([k[1] for k in self.keys]),
            in_tangents=tuple(k[2] for k in self.keys),
            out_tangents=tuple(k[3] for k in self.keys),
            in_angles=np.array([k[4] for k in self.keys]),
            out_angles=np.array([k[5] for k in self.keys]),
            full_attribute=self.full,
            settings=dict(self.settings),
        )


def _parse_key(tokens: list[str], where: str, line: str) -> tuple[float, float, str, str, float, float]:
    if len(tokens) < 4:
        raise InvalidValueError(where, line, "a key: frame value inTangent outTangent tanLocked weightLocked ...")
    frame = _float(tokens[0], where, line)
    value = _float(tokens[1], where, line)
    in_type, out_type = tokens[2], tokens[3]
    for tangent in (in_type, out_type):
        if tangent not in _TANGENTS:
            raise InvalidValueError(where, line, f"a tangent type ({', '.join(_TANGENTS)}), not {tangent!r}")
    rest = tokens[4:]
    fixed = (in_type == "fixed") + (out_type == "fixed")
    # tanLocked weightLocked [breakdown] then (angle weight) per fixed tangent
    if len(rest) not in (2 + 2 * fixed, 3 + 2 * fixed):
        raise InvalidValueError(where, line, "tanLocked weightLocked [breakdown] and an angle/weight per fixed tangent")
    numbers = [_float(t, where, line) for t in rest]
    extra = numbers[len(rest) - 2 * fixed :]
    in_angle = out_angle = math.nan
    if in_type == "fixed":
        in_angle, extra = extra[0], extra[2:]
    if out_type == "fixed":
        out_angle = extra[0]
    return frame, value, in_type, out_type, in_angle, out_angle


def read(source: Source) -> Clip:
    """The curves of a ``.anim`` file sampled at its own frame rate (:func:`read_curves` then :func:`to_clip`)."""
    return to_clip(read_curves(source))


def read_curves(source: Source) -> AnimFile:
    """Parse a ``.anim`` file into its curves and keys; malformed content raises naming the file and line."""
    name = source_name(source)
    text = read_bytes(source).decode("utf-8", errors="replace")
    header: dict[str, str] = {}
    curves: list[AnimCurve] = []
    current: _Builder | None = None
    state = "top"  # top -> anim (after an anim line) -> data (in animData) -> keys (in keys)
    where = f"{name} line 0"
    line = ""
    for number, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        where = f"{name} line {number}"
        content = re.split(r"//|#", line, maxsplit=1)[0].strip()
        if not content:
            continue
        tokens = content.replace(";", " ; ").replace("{", " { ").replace("}", " } ").split()
        if state == "keys":
            if tokens == ["}"]:
                state = "data"
                continue
            if tokens[-1] != ";":
                raise InvalidValueError(where, line, "a key line ending in ';' or '}'")
            assert current is not None
            current.keys.append(_parse_key(tokens[:-1], where, line))
            continue
        if state == "data":
            if tokens[:2] == ["keys", "{"] and len(tokens) == 2:
                state = "keys"
            elif tokens == ["}"]:
                assert current is not None
                curves.append(current.build(where, line))
                current, state = None, "top"
            elif len(tokens) == 3 and tokens[2] == ";":
                assert current is not None
                current.settings[tokens[0]] = tokens[1]
            else:
                raise InvalidValueError(where, line, "an animData setting 'name value;', 'keys {' or '}'")
            continue
        if state == "anim" and tokens[:2] == ["animData", "{"] and len(tokens) == 2:
            state = "data"
            continue
        state = "top"
        current = None
        keyword = tokens[0]
        if keyword == "anim":
            if tokens[-1] != ";" or len(tokens) not in (6, 8) or not all(t.isdigit() for t in tokens[-4:-1]):
                raise InvalidValueError(where, line, "'anim <attr> <leaf> <node> <row> <child> <index>;'")
            if len(tokens) == 8:
                current = _Builder(tokens[1], tokens[2], tokens[3])
                state = "anim"
            continue  # a 4-field anim line names a node without a curve
        if len(tokens) != 3 or tokens[2] != ";":
            raise InvalidValueError(where, line, "a header line 'keyword value;' or an anim line")
        header[keyword] = tokens[1]
    if state != "top":
        raise InvalidValueError(where, line, "the file to close every animData and keys block")
    if "animVersion" not in header:
        raise InvalidValueError(f"{name} line 1", "no animVersion", "an 'animVersion 1.1;' header line")
    fps = _time_unit_fps(header.get("timeUnit", "film"), f"{name} timeUnit", header.get("timeUnit", ""))
    for name in ("startTime", "endTime"):
        if name in header:
            _float(header[name], f"{name} {name}", header[name])
    named: dict[str, AnimCurve] = {}
    leaves = [c.attribute for c in curves]
    for curve in curves:
        name = curve.attribute if leaves.count(curve.attribute) == 1 else f"{curve.node}.{curve.attribute}"
        named[name] = curve
    return AnimFile(header=header, fps=fps, curves=named)


# ---------------------------------------------------------------------------------------------------------------
# Evaluation


def _slopes(curve: AnimCurve, fps: float, side: str) -> np.ndarray:
    """(k,) tangent slopes in value per frame on one side (``in`` or ``out``) of every key."""
    t, v = curve.frames, curve.values
    k = t.size
    types = curve.in_tangents if side == "in" else curve.out_tangents
    angles = curve.in_angles if side == "in" else curve.out_angles
    secant = np.diff(v) / np.diff(t) if k > 1 else np.zeros(0)
    slopes = np.zeros(k)
    for i, kind in enumerate(types):
        before = secant[i - 1] if i > 0 else (secant[0] if k > 1 else 0.0)
        after = secant[i] if i < k - 1 else (secant[-1] if k > 1 else 0.0)
        if kind == "linear":
            slopes[i] = before if side == "in" else after
        elif kind in ("flat", "step", "stepnext"):
            slopes[i] = 0.0
        elif kind == "fixed":
            slopes[i] = math.tan(math.radians(angles[i])) / fps
        else:
            if 0 < i < k - 1:
                slope = (v[i + 1] - v[i - 1]) / (t[i + 1] - t[i - 1])
                extremum = (v[i] - v[i - 1]) * (v[i + 1] - v[i]) <= 0
                if kind in ("auto", "clamped", "plateau") and extremum:
                    slope = 0.0
            else:
                slope = before if i > 0 else after
            slopes[i] = slope
    return slopes


def evaluate_curve(curve: AnimCurve, frames: np.ndarray, fps: float) -> np.ndarray:
    """Values of ``curve`` at ``frames`` (any float frames); constant outside the keys (pre/post infinity)."""
    f = np.asarray(frames, dtype=np.float64)
    t, v = curve.frames, curve.values
    if t.size == 1:
        return np.full(f.shape, v[0])
    segment = np.clip(np.searchsorted(t, f, side="right") - 1, 0, t.size - 2)
    t0, t1, v0, v1 = t[segment], t[segment + 1], v[segment], v[segment + 1]
    width = t1 - t0
    u = (f - t0) / width
    linear = v0 + u * (v1 - v0)
    out_slope = _slopes(curve, fps, "out")[segment] * width
    in_slope = _slopes(curve, fps, "in")[segment + 1] * width
    h00 = 2 * u**3 - 3 * u**2 + 1
    h10 = u**3 - 2 * u**2 + u
    h01 = -2 * u**3 + 3 * u**2
    h11 = u**3 - u**2
    hermite = h00 * v0 + h10 * out_slope + h01 * v1 + h11 * in_slope
    out_types = np.array(curve.out_tangents)[segment]
    in_types = np.array(curve.in_tangents)[segment + 1]
    result = np.where((out_types == "linear") & (in_types == "linear"), linear, hermite)
    result = np.where(out_types == "step", v0, result)
    result = np.where((out_types == "stepnext") & (u > 0), v1, result)
    result = np.where(f <= t[0], v[0], result)
    return np.where(f >= t[-1], v[-1], result)


def to_clip(anim: AnimFile, fps: float | None = None) -> Clip:
    """Sample every curve at ``fps`` (default: the file's) from ``startTime`` to ``endTime``.

    Clip time 0 is ``startTime``; channels are the curve names in file order.
    """
    rate = anim.fps if fps is None else float(fps)
    if not math.isfinite(rate) or rate <= 0:
        raise InvalidValueError("fps", fps, "a positive finite number")
    if not anim.curves:
        raise InvalidValueError("anim", "no curves", "a file with at least one animated curve")
    duration_s = (anim.end_frame - anim.start_frame) / anim.fps
    n_frames = math.floor(duration_s * rate + 1e-9) + 1
    # a few bytes of header (endTime 1e9) must not make a clip of gigabytes: checked before allocating
    check_count("anim", "values (frames x curves)", n_frames * len(anim.curves), current().clip_values)
    frames = anim.start_frame + np.arange(n_frames) * (anim.fps / rate)
    values = np.stack([evaluate_curve(c, frames, anim.fps) for c in anim.curves.values()], axis=1)
    return Clip(values, rate, tuple(anim.curves))
