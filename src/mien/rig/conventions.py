"""Morph-target naming conventions as data: each convention's names -> mien's ARKit vocabulary.

One CSV table per convention ships in ``data/conventions/`` (source cited in each file's comment header):
:data:`CONVENTION_NAMES`. A row ``source,arkit,weight,side`` says that the rig's shape ``source`` contributes
``weight`` times its deltas to the ARKit target ``arkit``; ``side`` ``L`` / ``R`` keeps only the character's
left (x > 0) / right half of the shape (to split a both-sided shape such as VRM's ``blink``), empty keeps all of it.
Several rows into one ARKit target combine shapes (ICT's ``browInnerUp_L`` + ``_R``; a head's and its teeth's jaw
shapes, so both meshes move together); several rows from one shape split it.

:func:`match_names` detects a rig's convention by name overlap and reports what matched, what did not, which ARKit
targets the rig lacks and which AUs that costs (through the shipped AU -> ARKit table). A user overrides any row
with a small TOML file (:func:`read_overrides`)::

    convention = "rocketbox"            # optional: skip detection
    [targets]
    "h_expressions.Lsad_h" = "browInnerUp"                       # one ARKit target, weight 1
    "MySmile" = [{arkit = "mouthSmileLeft", side = "L"}, {arkit = "mouthSmileRight", side = "R"}]
    "h_expressions.Kiss_h" = []                                  # leave this shape unmapped

>>> match = match_names(["eyeBlink_L", "eyeBlink_R", "jawOpen", "cheekRaiser_L"])
>>> match.convention
'ict'
>>> match.unmatched
('cheekRaiser_L',)
>>> "AU1" in match.au_cannot_show
True
"""

from __future__ import annotations

import csv
import math
import os
import tomllib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from mien.errors import InvalidValueError, UnknownNameError
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.catalogue import FACE_CHANNELS
from mien.rig.mapping import AUMapping
from mien.rig.vrm_presets import preset_arkit, vrm1_name

__all__ = [
    "CONVENTION_NAMES",
    "PROJECTED_PRESETS",
    "Convention",
    "ConventionRow",
    "NameMatch",
    "au_costs",
    "load_convention",
    "match_names",
    "preset_rows",
    "read_overrides",
]

CONVENTION_NAMES: tuple[str, ...] = ("arkit", "livelink", "metahuman", "ict", "cc4", "rocketbox", "vrm1", "vrm0")
"""Shipped conventions, in the order ties in detection are broken."""

PROJECTED_PRESETS: tuple[str, ...] = ("happy", "angry", "sad", "surprised")
"""The VRM 1.0 emotion presets a VRM rig is driven through by projection (relaxed is a soft happy in mien's
table, so it would share happy's weight: it stays the rig's own shape)."""
PROJECTION_TOLERANCE = 1e-3
"""Projection weights smaller than this are left out of the rows."""

_COLUMNS = ("source", "arkit", "weight", "side")
_SIDES = ("", "L", "R")


@dataclass(frozen=True)
class ConventionRow:
    """One shape's contribution to one ARKit target."""

    source: str
    """The rig's own shape name."""
    arkit: str
    """The ARKit target it feeds (one of :data:`mien.facs.arkit.ARKIT_NAMES`)."""
    weight: float = 1.0
    """Factor on the shape's deltas in that target."""
    side: str = ""
    """``"L"``: only the character's left half (x > 0) of the shape; ``"R"``: the right half; ``""``: all."""


@dataclass(frozen=True)
class Convention:
    """A naming convention: its rows and where they come from."""

    name: str
    """Short name (``"ict"``, ``"rocketbox"``...)."""
    title: str
    """What the convention is, in words."""
    rows: tuple[ConventionRow, ...]
    """Every row of its table, in file order."""
    source: str
    """The table it was read from (``mien:rig/data/conventions/ict.csv`` or a file path)."""

    @property
    def source_names(self) -> frozenset[str]:
        """The shape names this convention knows."""
        return frozenset(row.source for row in self.rows)


def _row(where: str, source: str, arkit: str, weight: Any, side: Any) -> ConventionRow:
    if not source:
        raise InvalidValueError(f"{where} source", source, "a shape name")
    if arkit not in ARKIT_NAMES:
        raise UnknownNameError(f"ARKit target ({where})", arkit, ARKIT_NAMES)
    try:
        value = float(weight)
    except (TypeError, ValueError):
        value = math.nan
    if not math.isfinite(value):
        raise InvalidValueError(f"{where} weight", weight, "a finite number")
    side = "" if side is None else str(side).strip().upper()
    if side not in _SIDES:
        raise InvalidValueError(f"{where} side", side, "L, R or empty")
    return ConventionRow(source, arkit, value, side)


def _parse(text: str, source: str) -> Convention:
    name = title = ""
    lines: list[tuple[int, list[str]]] = []
    for number, line in enumerate(text.splitlines(), 1):
        stripped = line.strip()
        if stripped.startswith("#"):
            key, _, value = stripped[1:].strip().partition(":")
            if key == "convention":
                name = value.strip()
            elif key == "title":
                title = value.strip()
            continue
        if stripped:
            lines.append((number, next(csv.reader([stripped]))))
    if not lines or tuple(cell.strip() for cell in lines[0][1]) != _COLUMNS:
        raise InvalidValueError(f"{source} header", lines[0][1] if lines else [], ",".join(_COLUMNS))
    rows = []
    for number, cells in lines[1:]:
        if len(cells) != 4:
            raise InvalidValueError(f"{source} line {number}", ",".join(cells), "4 columns: " + ",".join(_COLUMNS))
        rows.append(_row(f"{source} line {number}", *(cell.strip() for cell in cells)))
    return Convention(name or Path(source).stem, title, tuple(rows), source)


@cache
def load_convention(name: str) -> Convention:
    """The shipped convention ``name`` (one of :data:`CONVENTION_NAMES`)."""
    if name not in CONVENTION_NAMES:
        raise UnknownNameError("naming convention", name, CONVENTION_NAMES)
    text = resources.files("mien.rig").joinpath(f"data/conventions/{name}.csv").read_text(encoding="utf-8")
    return _parse(text, f"mien:rig/data/conventions/{name}.csv")


@dataclass(frozen=True)
class Overrides:
    """A user's TOML overrides: a forced convention and replacement rows per shape."""

    convention: str | None = None
    """Convention to use instead of detecting one (None = detect)."""
    rows: Mapping[str, tuple[ConventionRow, ...]] = field(default_factory=dict)
    """Shape name -> the rows that replace the convention's rows for it (empty: leave it unmapped)."""
    source: str = ""
    """The TOML file read."""


def read_overrides(path: str | os.PathLike[str]) -> Overrides:
    """Read a TOML override file (format in the module doc); errors name the file and the entry."""
    file = Path(path)
    try:
        data = tomllib.loads(file.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise InvalidValueError(f"naming overrides {file}", str(exc), "a readable TOML file") from None
    unknown = sorted(set(data) - {"convention", "targets"})
    if unknown:
        raise InvalidValueError(f"naming overrides {file}", unknown, "only the keys convention and [targets]")
    convention = data.get("convention")
    if convention is not None and convention not in CONVENTION_NAMES:
        raise UnknownNameError(f"naming convention ({file})", convention, CONVENTION_NAMES)
    targets = data.get("targets", {})
    if not isinstance(targets, dict):
        raise InvalidValueError(f"{file} [targets]", targets, "a table: shape name = ARKit name or list of rows")
    rows: dict[str, tuple[ConventionRow, ...]] = {}
    for shape, value in targets.items():
        where = f"{file} targets.{shape}"
        entries = [value] if isinstance(value, str | dict) else value
        if not isinstance(entries, list):
            raise InvalidValueError(where, value, "an ARKit name, a table {arkit, weight, side} or a list of them")
        parsed = []
        for entry in entries:
            if isinstance(entry, str):
                entry = {"arkit": entry}
            if not isinstance(entry, dict) or "arkit" not in entry or set(entry) - {"arkit", "weight", "side"}:
                raise InvalidValueError(where, entry, "{arkit = NAME, weight = 1.0, side = 'L'|'R'|''}")
            parsed.append(_row(where, shape, entry["arkit"], entry.get("weight", 1.0), entry.get("side", "")))
        rows[shape] = tuple(parsed)
    return Overrides(convention, rows, str(file))


@cache
def _au_targets() -> dict[str, frozenset[str]]:
    """AU name (``AU1``) -> the ARKit targets the shipped AU table drives for it."""

    mapping = AUMapping.default()

    out: dict[str, set[str]] = {}
    for i, channel in enumerate(FACE_CHANNELS):
        driven = {mapping.target_names[j] for j in range(mapping.n_targets) if mapping.matrix[i, j] > 0}
        if driven:
            au = channel.rstrip("LR") if channel[-1] in "LR" and channel[:-1].rstrip("0123456789") == "AU" else channel
            out.setdefault(au, set()).update(driven)
    return {au: frozenset(names) for au, names in out.items()}


def au_costs(missing: Iterable[str]) -> tuple[dict[str, tuple[str, ...]], dict[str, tuple[str, ...]]]:
    """What lacking the ARKit targets ``missing`` costs, through the shipped AU -> ARKit table.

    Returns ``(cannot_show, partly)``: AU -> the missing targets, for AUs all of whose targets are missing and
    for AUs that lose some of theirs.
    """
    lacking = frozenset(missing)
    cannot: dict[str, tuple[str, ...]] = {}
    partly: dict[str, tuple[str, ...]] = {}
    for au, targets in sorted(_au_targets().items(), key=lambda item: int(item[0][2:]) if item[0][2:].isdigit() else 0):
        lost = tuple(name for name in ARKIT_NAMES if name in targets & lacking)
        if not lost:
            continue
        (cannot if len(lost) == len(targets) else partly)[au] = lost
    return cannot, partly


@dataclass(frozen=True)
class NameMatch:
    """How a rig's shape names map onto mien's ARKit names, and what the rig cannot show."""

    convention: str
    """The convention used (detected, or forced by the overrides)."""
    rows: tuple[ConventionRow, ...]
    """The rows that apply to this rig (overrides included), in table order."""
    matched: tuple[str, ...]
    """The rig's shapes that feed at least one ARKit target."""
    unmatched: tuple[str, ...]
    """The rig's shapes no row maps (kept as the rig's own targets under their names)."""
    missing: tuple[str, ...]
    """ARKit targets no shape of the rig feeds, in ARKit order."""
    scores: dict[str, int]
    """Convention -> how many of the rig's names it knows (the detection evidence)."""
    au_cannot_show: dict[str, tuple[str, ...]]
    """AU -> its missing targets, for AUs that cannot show at all."""
    au_partly: dict[str, tuple[str, ...]]
    """AU -> its missing targets, for AUs that lose part of their motion."""
    overrides: str = ""
    """The override file applied (empty when none)."""
    presets: tuple[str, ...] = ()
    """The rig's VRM emotion presets driven by projection (:func:`preset_rows`); empty for other rigs."""

    @property
    def arkit_targets(self) -> tuple[str, ...]:
        """The ARKit targets the rig has, in ARKit order."""
        fed = {row.arkit for row in self.rows}
        return tuple(name for name in ARKIT_NAMES if name in fed)

    def report(self) -> str:
        """A few lines for people: the convention, counts, unmatched shapes and each missing target's cost."""
        ties = [name for name, score in self.scores.items() if score == self.scores.get(self.convention, 0)]
        lines = [
            f"naming convention: {self.convention}"
            + (f" (same score: {', '.join(t for t in ties if t != self.convention)})" if len(ties) > 1 else "")
            + (f"; overrides from {self.overrides}" if self.overrides else ""),
            f"matched {len(self.matched)} shape(s) onto {len(self.arkit_targets)} of {len(ARKIT_NAMES)} ARKit targets",
        ]
        if self.presets:
            lines.append(
                f"driven through its VRM emotion presets ({', '.join(self.presets)}): each ARKit pose is projected "
                "onto the faces mien gives these presets (least squares), so an emotion shows as its preset and an AU "
                "as far as the presets resemble it"
            )
        if self.unmatched:
            lines.append(
                f"not matched ({len(self.unmatched)}, kept under their own names): {', '.join(self.unmatched)}"
            )
        for name in self.missing:
            cannot = [au for au, lost in self.au_cannot_show.items() if name in lost]
            partly = [au for au, lost in self.au_partly.items() if name in lost]
            costs = ([f"{', '.join(cannot)} cannot show"] if cannot else []) + (
                [f"{', '.join(partly)} lose part of their motion"] if partly else []
            )
            lines.append(f"no {name}: " + ("; ".join(costs) if costs else "no AU uses it"))
        return "\n".join(lines)


def _lookup(names: Sequence[str], known: frozenset[str]) -> dict[str, str]:
    """Rig name -> table name: exact, else after dropping an exporter's ``Mesh.`` / ``blendShape1.`` prefix."""
    found = {}
    for name in names:
        if name in known:
            found[name] = name
            continue
        _head, dot, tail = name.rpartition(".")
        if dot and tail in known:
            found[name] = tail
    return found


def match_names(names: Sequence[str], convention: str | None = None, overrides: Overrides | None = None) -> NameMatch:
    """Map the rig's shape ``names`` onto ARKit names.

    ``convention``: force one of :data:`CONVENTION_NAMES` (None = the overrides' choice, else the one that knows
    the most of ``names``; ties go to the earlier in :data:`CONVENTION_NAMES`). ``overrides`` replace rows per shape.
    """
    names = list(dict.fromkeys(names))
    scores = {name: len(_lookup(names, load_convention(name).source_names)) for name in CONVENTION_NAMES}
    chosen = convention or (overrides.convention if overrides else None)
    if chosen is None:
        chosen = max(CONVENTION_NAMES, key=lambda n: (scores[n], -CONVENTION_NAMES.index(n)))
    table = load_convention(chosen)
    replaced = dict(overrides.rows) if overrides else {}
    by_source: dict[str, list[ConventionRow]] = {}
    for row in table.rows:
        by_source.setdefault(row.source, []).append(row)
    for shape, replacement in replaced.items():
        by_source[shape] = list(replacement)
    found = _lookup(names, frozenset(by_source))
    projected: dict[str, str] = {}
    if chosen in ("vrm0", "vrm1"):
        projected = {name: preset for name in names if name in found and found[name] not in replaced
                     and (preset := vrm1_name(found[name])) in PROJECTED_PRESETS}  # fmt: skip
    rows = [
        ConventionRow(name, row.arkit, row.weight, row.side) for name in names if name in found
        and name not in projected for row in by_source[found[name]]
    ]  # fmt: skip
    if len(projected) > 1:
        rows += preset_rows(projected, {row.arkit for row in rows})
    else:
        rows += [ConventionRow(name, row.arkit, row.weight, row.side) for name in projected
                 for row in by_source[found[name]]]  # fmt: skip
        projected = {}
    matched = tuple(dict.fromkeys(row.source for row in rows))
    fed = {row.arkit for row in rows}
    missing = tuple(name for name in ARKIT_NAMES if name not in fed)
    cannot, partly = au_costs(missing)
    return NameMatch(
        convention=chosen,
        rows=tuple(sorted(rows, key=lambda r: ARKIT_NAMES.index(r.arkit))),
        matched=matched,
        unmatched=tuple(name for name in names if name not in matched),
        missing=missing,
        scores=scores,
        au_cannot_show=cannot,
        au_partly=partly,
        overrides=overrides.source if overrides else "",
        presets=tuple(projected),
    )


def preset_rows(presets: Mapping[str, str], direct: Iterable[str] = ()) -> list[ConventionRow]:
    """Rows that drive a rig's VRM emotion presets by projection: ``presets`` maps the rig's shape -> its VRM 1.0
    preset (:data:`PROJECTED_PRESETS`), ``direct`` names ARKit targets other shapes already feed (left out).

    Each ARKit target k becomes ``sum_p P[k, p] * shape_p`` with ``P`` the pseudo-inverse of the presets' faces
    (:func:`mien.rig.vrm_presets.preset_arkit`, one row each, over the targets not in ``direct``). An ARKit pose
    ``a`` then weights the presets by ``a @ P``, its least-squares fit by the presets' faces: a frame of joy at the
    preset's intensity gives happy 1 and the others 0; an ARKit target no preset's face uses stays missing.
    """
    names = list(presets)
    faces = np.stack([preset_arkit(presets[name]) for name in names])
    faces[:, [ARKIT_NAMES.index(name) for name in set(direct)]] = 0.0
    inverse = np.linalg.pinv(faces)  # (52, n_presets)
    rows = []
    for k, arkit in enumerate(ARKIT_NAMES):
        for j, name in enumerate(names):
            weight = round(float(inverse[k, j]), 4)
            if abs(weight) >= PROJECTION_TOLERANCE:
                rows.append(ConventionRow(name, arkit, weight, ""))
    return rows
