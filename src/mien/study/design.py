"""A study's design file (TOML) -> :class:`Design`, frozen and checked.

Every unknown key, expression, laughter type, head, view or factor raises a typed error naming the file
and the key, so ``mien study ...`` answers exit 2 with a message instead of a traceback. Example::

    [study]
    name = "broekens-replication"
    protocol = "broekens"        # or "mascaro"
    completion_code = ""         # shown at the end (optional)
    redirect_url = ""            # e.g. a Prolific URL; {participant} is replaced (optional)
    [stimuli]
    source = "render"            # or "files" with [[stimuli.file]] entries
    expressions = ["joy", "sadness", "anger", "fear", "surprise", "disgust",
                   "evil", "furious", "enthusiastic", "frustrated"]
    heads = ["default"]          # "default", "builtin", "ict", with an identity: "ict:a", "builtin:b", or your
                                 #   character file, relative to this file: "avatars/me.glb"
    bases = ["facs", "feature_points"]
    views = ["frontal", "lateral"]
    distances_m = [1.0, 3.0]
    intensities = [1.2, 2.4]
    duration_s = 3.0
    fps = 30
    size = 256
    # say = "I have something to tell you"   # optional: every stimulus speaks it (espeak-ng), its
    #   expression the condition; or say = {text = "...", language = "en", rate_wpm = 175}
    [design]
    within = ["basis", "view", "distance_m", "intensity"]
    order = "counterbalanced"

Mascaró designs give ``laughter_types = [...]`` (ids of :data:`mien.laughter.taxonomy.LAUGH_TYPES`) and an
optional ``[stimuli.descriptions]`` table (type -> the text participants judge the motion against).
"""

from __future__ import annotations

import hashlib
import itertools
import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

from mien.affect.emotions import MAX_INTENSITY, STUDY_EXPRESSIONS, known_names, resolve_emotion
from mien.errors import InvalidValueError, MienError, MissingAssetError, UnknownNameError
from mien.laughter.taxonomy import LAUGH_TYPES, TAXONOMY
from mien.render.camera import STUDY_ANGLES
from mien.rig.files.head import FILE_SUFFIXES, is_head_file
from mien.rig.heads import HEADS

__all__ = [
    "BROEKENS_EXPRESSIONS",
    "BROEKENS_FACTORS",
    "MASCARO_FACTORS",
    "ORDERS",
    "PROTOCOLS",
    "VIEWS",
    "Design",
    "SpokenLine",
    "StimulusSpec",
    "check_redirect_url",
    "check_study_name",
    "load_design",
    "parse_design",
]

PROTOCOLS: tuple[str, ...] = ("broekens", "mascaro")
"""Study protocols: Broekens et al. (ten labels + naturalness, 1..5) and Mascaró et al. (two questions, 0..5)."""

BROEKENS_FACTORS: tuple[str, ...] = ("head", "identity", "basis", "view", "distance_m", "intensity")
"""Condition keys of a Broekens stimulus, in manifest and CSV column order."""

MASCARO_FACTORS: tuple[str, ...] = ("laughter_type", "description")
"""Condition keys of a Mascaró stimulus, in manifest and CSV column order."""

BROEKENS_EXPRESSIONS: tuple[str, ...] = STUDY_EXPRESSIONS
"""The ten expressions of the Broekens study (six basic emotions, four blends):
:data:`mien.affect.emotions.STUDY_EXPRESSIONS`."""

VIEWS: tuple[str, ...] = STUDY_ANGLES
"""Camera views of the Broekens study (:data:`mien.render.camera.STUDY_ANGLES`: ``frontal`` and ``lateral``)."""

ORDERS: tuple[str, ...] = ("counterbalanced", "random", "fixed")
"""Orders of the within-subject blocks: balanced Latin square over participants, random per participant, or
the design order."""

BROEKENS_ONLY_KEYS: tuple[str, ...] = ("expressions", "heads", "bases", "views", "distances_m", "intensities", "say")
"""``[stimuli]`` keys of Broekens designs only."""

BASES: tuple[str, ...] = ("facs", "feature_points")
"""Expression bases (:class:`mien.character.Character` ``expression_basis``)."""

STUDY_NAME_PATTERN = re.compile(r"\w[\w .+-]{0,99}")
"""Accepted study names: a letter, digit or ``_`` first, then letters, digits, spaces or ``_ . + -``, up to
100 characters. The name becomes the default database's file name (``NAME.sqlite`` next to the design), so
no path separator, ``..`` or control character gets in."""

_KEYS: dict[str, tuple[str, ...]] = {
    "": ("study", "stimuli", "design"),
    "study": ("name", "protocol", "completion_code", "redirect_url", "consent_text", "instructions_text"),
    "stimuli": (
        "source",
        "expressions",
        "laughter_types",
        "descriptions",
        "heads",
        "bases",
        "views",
        "distances_m",
        "intensities",
        "duration_s",
        "onset_s",
        "fps",
        "size",
        "seed",
        "say",
        "file",
    ),
    "design": ("within", "order"),
    "file": ("path", "expression", "conditions"),
    "say": ("text", "language", "rate_wpm"),
}

MAX_SPOKEN_CHARS = 1000
"""Longest sentence a stimulus speaks, characters (about a minute of speech)."""


@dataclass(frozen=True)
class SpokenLine:
    """What every rendered stimulus says (``[stimuli] say``), spoken by espeak-ng from the expression's onset."""

    text: str
    """The sentence."""
    language: str = "en"
    """espeak-ng voice (``en``, ``de``, ``fr``...)."""
    rate_wpm: int = 175
    """Speaking rate, words per minute (80..450)."""


@dataclass(frozen=True)
class StimulusSpec:
    """One stimulus of the design, before it exists as a file."""

    id: str
    """Manifest id, ``"s001"``, ``"s002"``... in design order."""
    expression: str
    """Emotion or blend name (Broekens) or laughter type id (Mascaró)."""
    conditions: dict[str, Any] = field(hash=False)
    """Factor -> level: :data:`BROEKENS_FACTORS` or :data:`MASCARO_FACTORS` keys (``distance_m`` metres,
    ``intensity`` 0..5)."""
    file: str | None = None
    """Supplied video path (``source = "files"``), else None (rendered)."""


@dataclass(frozen=True)
class Design:
    """A checked study design (see the module docstring for the file format)."""

    path: Path
    """The design file."""
    sha256: str
    """Hex SHA-256 of the design file's bytes."""
    name: str
    """Study name (one database can hold several studies)."""
    protocol: str
    """One of :data:`PROTOCOLS`."""
    source: str
    """``"render"`` or ``"files"``."""
    stimuli: tuple[StimulusSpec, ...]
    """Every stimulus, in design order."""
    within: tuple[str, ...]
    """Factors every participant sees at every level (blocks); other multi-level factors are between-subject."""
    order: str
    """Block order, one of :data:`ORDERS`."""
    completion_code: str = ""
    """Shown on the completion page ('' = none)."""
    redirect_url: str = ""
    """Where the completion page sends the participant ('' = stay); ``{participant}`` is replaced."""
    consent_text: str = ""
    """Consent page text ('' = the built-in one)."""
    instructions_text: str = ""
    """Instructions page text ('' = the protocol's built-in one)."""
    duration_s: float = 3.0
    """Rendered clip length, seconds."""
    onset_s: float = 0.5
    """When the expression starts in a rendered clip, seconds."""
    fps: float = 30.0
    """Rendered frames per second."""
    size: int = 256
    """Rendered frame width and height, pixels (even)."""
    seed: int = 0
    """Seed of the idle behaviour (blinks, head motion) of rendered clips."""
    say: SpokenLine | None = None
    """A sentence every rendered stimulus speaks while it shows its expression (None: silent stimuli)."""

    @property
    def factors(self) -> tuple[str, ...]:
        """Condition keys of this protocol's stimuli, in column order."""
        return BROEKENS_FACTORS if self.protocol == "broekens" else MASCARO_FACTORS

    def levels(self, factor: str) -> tuple[Any, ...]:
        """Distinct levels of ``factor`` over the stimuli, in first-seen order."""
        seen: dict[Any, None] = {}
        for spec in self.stimuli:
            seen.setdefault(spec.conditions.get(factor), None)
        return tuple(seen)


def _fail(path: Path, key: str, value: Any, expected: str) -> InvalidValueError:
    return InvalidValueError(f"{path}: {key}", value, expected)


def check_study_name(name: str, where: str = "study.name") -> str:
    """``name`` when it fits :data:`STUDY_NAME_PATTERN` (no path characters: it names the database file),
    else :class:`~mien.errors.InvalidValueError` naming ``where`` and the value.

    >>> check_study_name("broekens-replication")
    'broekens-replication'
    """
    if not isinstance(name, str) or not STUDY_NAME_PATTERN.fullmatch(name) or ".." in name:
        raise InvalidValueError(
            where, name, "a study name of letters, digits, spaces and _ . + - (no / \\ or ..; up to 100 characters)"
        )
    return name


def check_redirect_url(url: str, where: str = "study.redirect_url") -> str:
    """``url`` when it is empty or an ``http://`` / ``https://`` URL with a host, else
    :class:`~mien.errors.InvalidValueError` naming ``where`` (a ``javascript:`` or ``data:`` URL would run in
    the participant's page).

    >>> check_redirect_url("https://app.prolific.com/submissions/complete?cc=XYZ")
    'https://app.prolific.com/submissions/complete?cc=XYZ'
    """
    if url == "":
        return url
    try:
        parts = urlsplit(url.replace("{participant}", "p"))
    except ValueError:
        parts = None
    if (
        parts is None
        or parts.scheme.lower() not in ("http", "https")
        or not parts.netloc
        or any(ord(c) < 0x20 or c == "\x7f" or c.isspace() for c in url)
    ):
        raise InvalidValueError(where, url, "an http:// or https:// URL with a host, or '' for none")
    return url


def _check_keys(path: Path, table: Any, section: str, prefix: str) -> dict[str, Any]:
    if not isinstance(table, dict):
        raise _fail(path, prefix or "file", table, "a TOML table")
    for key in table:
        if key not in _KEYS[section]:
            raise UnknownNameError(f"key in {path} [{prefix}]" if prefix else f"table in {path}", key, _KEYS[section])
    return table


def _string_list(path: Path, key: str, value: Any, default: tuple[str, ...]) -> tuple[str, ...]:
    if value is None:
        return default
    if not isinstance(value, list) or not value or not all(isinstance(v, str) and v for v in value):
        raise _fail(path, key, value, "a non-empty list of names")
    if len(set(value)) != len(value):
        raise _fail(path, key, value, "names without repeats")
    return tuple(value)


def _number_list(path: Path, key: str, value: Any, default: tuple[float, ...], low: float, high: float) -> tuple:
    if value is None:
        return default
    if not isinstance(value, list) or not value:
        raise _fail(path, key, value, f"a non-empty list of numbers in [{low}, {high}]")
    for v in value:
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v) or not low <= v <= high:
            raise _fail(path, key, v, f"a number in [{low}, {high}]")
    if len(set(value)) != len(value):
        raise _fail(path, key, value, "numbers without repeats")
    return tuple(float(v) for v in value)


def _number(path: Path, key: str, value: Any, default: float, low: float, high: float) -> float:
    if value is None:
        return default
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise _fail(path, key, value, f"a number in [{low}, {high}]")
    if not low <= value <= high:
        raise _fail(path, key, value, f"a number in [{low}, {high}]")
    return float(value)


def _text(path: Path, key: str, value: Any) -> str:
    if value is None:
        return ""
    if not isinstance(value, str):
        raise _fail(path, key, value, "a string")
    return value


def _expression(path: Path, key: str, name: str) -> str:

    try:
        canonical = resolve_emotion(name)
    except MienError:
        raise UnknownNameError(f"expression in {path} {key}", name, known_names()) from None
    return canonical


def _laughter_type(path: Path, key: str, name: str) -> str:

    if name not in LAUGH_TYPES:
        raise UnknownNameError(f"laughter type in {path} {key}", name, LAUGH_TYPES)
    return name


def _say(path: Path, value: Any) -> SpokenLine | None:
    """``[stimuli] say``: a sentence, or a table ``{text, language, rate_wpm}`` (None when absent)."""
    if value is None:
        return None
    table = {"text": value} if isinstance(value, str) else _check_keys(path, value, "say", "stimuli.say")
    text = table.get("text")
    if not isinstance(text, str) or not text.strip() or len(text) > MAX_SPOKEN_CHARS:
        raise _fail(path, "stimuli.say.text", text, f"a sentence to speak (1..{MAX_SPOKEN_CHARS} characters)")
    language = table.get("language", "en")
    if not isinstance(language, str) or not re.fullmatch(r"[A-Za-z]{2,3}(-[A-Za-z0-9]{1,8}){0,3}", language):
        raise _fail(path, "stimuli.say.language", language, "an espeak-ng voice such as en, en-us, de, fr")
    rate = table.get("rate_wpm", 175)
    if isinstance(rate, bool) or not isinstance(rate, int) or not 80 <= rate <= 450:
        raise _fail(path, "stimuli.say.rate_wpm", rate, "words per minute, an integer 80..450")
    return SpokenLine(text.strip(), language, rate)


def _head(path: Path, spec: str) -> tuple[str, str]:
    """``"ict:a"`` -> ("ict", "a"); ``"default"`` -> ("default", ""); a character file (``"me.glb"`` or
    ``"file:me.glb"``, relative to the design file, as supplied videos are) -> ("file", its absolute path). Checks
    the head name and that a file exists (identities are checked when a head is loaded, which needs its assets)."""

    name, _, identity = spec.partition(":")
    if name in HEADS:
        return name, identity
    file = spec[len("file:") :] if name == "file" else spec
    full = (path.parent / file).resolve()
    if is_head_file(full):
        return "file", str(full)
    if name == "file" or Path(file).suffix.lower() in FILE_SUFFIXES or "/" in file:
        raise _fail(
            path,
            "stimuli.heads",
            spec,
            f"a character file that exists: {full} is not a {', '.join(FILE_SUFFIXES)} file or a folder of OBJ shapes "
            "(paths are relative to the design file)",
        )
    raise UnknownNameError(f"head in {path} stimuli.heads", spec, HEADS)


def _conditions(path: Path, key: str, value: Any, protocol: str) -> dict[str, Any]:
    factors = BROEKENS_FACTORS if protocol == "broekens" else MASCARO_FACTORS
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise _fail(path, key, value, "a table of condition = level")
    for name, level in value.items():
        if name not in factors:
            raise UnknownNameError(f"condition in {path} {key}", name, factors)
        if not isinstance(level, str | int | float) or isinstance(level, bool):
            raise _fail(path, f"{key}.{name}", level, "a string or number level")
    return {name: value[name] for name in factors if name in value}


def _rendered_broekens(path: Path, s: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
    expressions = _string_list(path, "stimuli.expressions", s.get("expressions"), BROEKENS_EXPRESSIONS)
    expressions = tuple(_expression(path, "stimuli.expressions", e) for e in expressions)
    heads = [_head(path, h) for h in _string_list(path, "stimuli.heads", s.get("heads"), ("default",))]
    bases = _string_list(path, "stimuli.bases", s.get("bases"), ("facs",))
    for basis in bases:
        if basis not in BASES:
            raise UnknownNameError(f"basis in {path} stimuli.bases", basis, BASES)
    views = _string_list(path, "stimuli.views", s.get("views"), ("frontal",))
    for view in views:
        if view not in VIEWS:
            raise UnknownNameError(f"view in {path} stimuli.views", view, VIEWS)
    distances = _number_list(path, "stimuli.distances_m", s.get("distances_m"), (1.0,), 0.1, 100.0)
    intensities = _number_list(path, "stimuli.intensities", s.get("intensities"), (1.2,), 0.0, MAX_INTENSITY)
    rows = []
    for (head, identity), basis, view, distance, intensity, expression in itertools.product(
        heads, bases, views, distances, intensities, expressions
    ):
        conditions = {
            "head": head,
            "identity": identity,
            "basis": basis,
            "view": view,
            "distance_m": distance,
            "intensity": intensity,
        }
        rows.append((expression, conditions))
    return rows


def _rendered_mascaro(path: Path, s: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:

    types = _string_list(path, "stimuli.laughter_types", s.get("laughter_types"), LAUGH_TYPES)
    types = tuple(_laughter_type(path, "stimuli.laughter_types", t) for t in types)
    descriptions = s.get("descriptions") or {}
    if not isinstance(descriptions, dict):
        raise _fail(path, "stimuli.descriptions", descriptions, "a table of laughter type = text")
    for name, text in descriptions.items():
        if name not in types:
            raise UnknownNameError(f"laughter type in {path} stimuli.descriptions", name, types)
        if not isinstance(text, str):
            raise _fail(path, f"stimuli.descriptions.{name}", text, "a string")
    return [(t, {"laughter_type": t, "description": descriptions.get(t, TAXONOMY[t].label)}) for t in types]


def _supplied(path: Path, s: dict[str, Any], protocol: str) -> list[tuple[str, dict[str, Any], str]]:
    entries = s.get("file")
    if not isinstance(entries, list) or not entries:
        raise _fail(path, "stimuli.file", entries, 'one or more [[stimuli.file]] entries when source = "files"')
    rows = []
    for k, entry in enumerate(entries):
        key = f"stimuli.file[{k}]"
        _check_keys(path, entry, "file", key)
        file = entry.get("path")
        if not isinstance(file, str) or not file:
            raise _fail(path, f"{key}.path", file, "a video file path (relative to the design file)")
        name = entry.get("expression")
        if not isinstance(name, str):
            raise _fail(path, f"{key}.expression", name, "an expression name")
        check = _expression if protocol == "broekens" else _laughter_type
        expression = check(path, f"{key}.expression", name)
        conditions = _conditions(path, f"{key}.conditions", entry.get("conditions"), protocol)
        if protocol == "mascaro":
            conditions.setdefault("laughter_type", expression)
        full = (path.parent / file).resolve()
        rows.append((expression, conditions, str(full)))
    return rows


def parse_design(data: dict[str, Any], path: Path, sha256: str = "") -> Design:
    """A :class:`Design` from a parsed TOML table (``path`` names the file in errors)."""
    _check_keys(path, data, "", "")
    study = _check_keys(path, data.get("study", {}), "study", "study")
    s = _check_keys(path, data.get("stimuli", {}), "stimuli", "stimuli")
    d = _check_keys(path, data.get("design", {}), "design", "design")
    name = study.get("name")
    if not isinstance(name, str) or not name.strip():
        raise _fail(path, "study.name", name, "a non-empty study name")
    check_study_name(name.strip(), f"{path}: study.name")
    protocol = study.get("protocol", "broekens")
    if protocol not in PROTOCOLS:
        raise UnknownNameError(f"protocol in {path} study.protocol", protocol, PROTOCOLS)
    unused = ("laughter_types", "descriptions") if protocol == "broekens" else BROEKENS_ONLY_KEYS
    for key in unused:
        if key in s:
            raise _fail(
                path,
                f"stimuli.{key}",
                s[key],
                f"no such key in a {protocol} design (Mascaró stimuli use the default head)",
            )
    source = s.get("source", "render")
    if source not in ("render", "files"):
        raise UnknownNameError(f"stimulus source in {path} stimuli.source", source, ("render", "files"))
    if source == "files" and "say" in s:
        raise _fail(path, "stimuli.say", s["say"], 'no say with source = "files" (supplied videos bring their sound)')
    files: list[str | None]
    if source == "files":
        supplied = _supplied(path, s, protocol)
        rows = [(e, c) for e, c, _ in supplied]
        files = [f for _, _, f in supplied]
    else:
        rows = _rendered_broekens(path, s) if protocol == "broekens" else _rendered_mascaro(path, s)
        files = [None] * len(rows)
    stimuli = tuple(
        StimulusSpec(f"s{k + 1:03d}", expression, conditions, file)
        for k, ((expression, conditions), file) in enumerate(zip(rows, files, strict=True))
    )
    factors = BROEKENS_FACTORS if protocol == "broekens" else MASCARO_FACTORS
    within = _string_list(path, "design.within", d.get("within"), ()) if d.get("within") != [] else ()
    for factor in within:
        if factor not in factors:
            raise UnknownNameError(f"within-subject factor in {path} design.within", factor, factors)
    order = d.get("order", "counterbalanced")
    if order not in ORDERS:
        raise UnknownNameError(f"block order in {path} design.order", order, ORDERS)
    size = _number(path, "stimuli.size", s.get("size"), 256, 16, 4096)
    if int(size) != size or int(size) % 2:
        raise _fail(path, "stimuli.size", s.get("size"), "an even number of pixels (H.264 needs even sizes)")
    seed = s.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int):
        raise _fail(path, "stimuli.seed", seed, "an integer")
    duration_s = _number(path, "stimuli.duration_s", s.get("duration_s"), 3.0, 0.1, 60.0)
    onset_s = _number(path, "stimuli.onset_s", s.get("onset_s"), min(0.5, duration_s / 4), 0.0, duration_s)
    return Design(
        path=path,
        sha256=sha256,
        name=name.strip(),
        protocol=protocol,
        source=source,
        stimuli=stimuli,
        within=within,
        order=order,
        completion_code=_text(path, "study.completion_code", study.get("completion_code")),
        redirect_url=check_redirect_url(
            _text(path, "study.redirect_url", study.get("redirect_url")).strip(), f"{path}: study.redirect_url"
        ),
        consent_text=_text(path, "study.consent_text", study.get("consent_text")),
        instructions_text=_text(path, "study.instructions_text", study.get("instructions_text")),
        duration_s=duration_s,
        onset_s=onset_s,
        fps=_number(path, "stimuli.fps", s.get("fps"), 30.0, 1.0, 240.0),
        size=int(size),
        seed=seed,
        say=_say(path, s.get("say")),
    )


def load_design(path: str | Path) -> Design:
    """Read and check the design TOML at ``path``.

    Raises :class:`~mien.errors.MissingAssetError` when the file is missing, and
    :class:`~mien.errors.InvalidValueError` / :class:`~mien.errors.UnknownNameError` naming the file and key
    for anything malformed or unknown.
    """

    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise MissingAssetError(f"design file {path} not found: give the path of a study TOML file") from None
    except OSError as error:
        raise MissingAssetError(f"design file {path} cannot be read: {error.strerror}") from None
    try:
        data = tomllib.loads(raw.decode("utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as error:
        raise InvalidValueError(str(path), "TOML", f"a valid UTF-8 TOML design file ({error})") from None
    return parse_design(data, path, hashlib.sha256(raw).hexdigest())
