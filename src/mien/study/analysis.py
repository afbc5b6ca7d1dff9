"""Analysis of a perception study's answers, as the papers did it: :func:`analyze` -> :class:`StudyAnalysis`.

Input is the long answers table of the study contract (one row per answered item, columns
:data:`ANSWER_COLUMNS` with the design factors between ``expression`` and ``question``), from
:meth:`mien.study.storage.Store.answers_frame` or the CSV of ``mien study export`` (:func:`analyze_csv`).

Broekens protocol (ten emotion labels and naturalness, 1..5):

* quality per expression, overall and per level of each condition (:mod:`mien.study.quality`, Table 4);
* the rating profile: mean rating 1..5 of each label per expression (the paper's Figure 7);
* naturalness per expression: mean rating 1..5 and a t-based 95% interval over participants;
* repeated-measures ANOVA per dependent measure (the paper's 14 outcome variables: the ten label
  intensities, naturalness, nrShows, mean and target intensity) over the within-subject factors, and one over
  the expressions (the paper's Table 3).

Mascaró protocol (two questions, 0..5): per laughter type and question, the mean over participants with a
t-based 95% interval, and the rm-ANOVA of each question over the laughter types (and any varied factor).

The ANOVAs are :func:`mien.study.anova.rm_anova` (one value per participant and cell; participants missing a
cell dropped and named; pingouin for one or two factors, the balanced computation for more).
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from mien.errors import InvalidValueError, UnknownNameError
from mien.extras import require
from mien.fileio.hashing import file_sha256
from mien.study.anova import AnovaTable, rm_anova
from mien.study.export import answers_sha256
from mien.study.protocol import BROEKENS_LABELS
from mien.study.quality import LABEL_PREFIX, label_intensity, label_question, quality_table

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "ANSWER_COLUMNS",
    "FACTOR_COLUMNS",
    "QUESTIONS",
    "RATING_RANGE",
    "AnovaTable",
    "StudyAnalysis",
    "analyze",
    "analyze_csv",
    "check_answers",
    "mean_ci",
    "rm_anova",
    "trials_frame",
]

ANSWER_COLUMNS: tuple[str, ...] = (
    "study", "participant", "session_started_at", "position", "stimulus", "protocol", "expression",
    "question", "label_position", "rating", "nr_shows", "answered_at",
)  # fmt: skip
"""The fixed columns of the answers table (the design factors sit between ``expression`` and ``question``)."""

FACTOR_COLUMNS: tuple[str, ...] = (
    "head", "identity", "basis", "view", "distance_m", "intensity", "laughter_type", "description",
)  # fmt: skip
"""Design factors a manifest may carry, in the contract's order."""

RATING_RANGE: dict[str, tuple[int, int]] = {"broekens": (1, 5), "mascaro": (0, 5)}
"""Protocol -> (lowest, highest) rating."""

QUESTIONS: dict[str, tuple[str, ...]] = {
    "broekens": ("naturalness",),
    "mascaro": ("feels_right", "represents_description"),
}
"""Protocol -> its questions other than the ``label:NAME`` emotion labels (Broekens only)."""

_NOT_WITHIN = ("laughter_type", "description")  # one per laughter type: the expression itself


@dataclass(frozen=True, eq=False)
class StudyAnalysis:
    """Everything :func:`analyze` computes from one study's answers (tables are pandas DataFrames)."""

    study: str
    """Study name (the ``study`` column)."""
    protocol: str
    """``"broekens"`` or ``"mascaro"``."""
    n_participants: int
    """Participants with at least one answer."""
    n_answers: int
    """Rows of the answers table."""
    factors: tuple[str, ...]
    """Within-subject factors the ANOVAs used."""
    factor_levels: dict[str, tuple[str, ...]]
    """Design factor column -> its levels in the data (as text; numbers formatted with ``:g``)."""
    labels: tuple[str, ...] = ()
    """Broekens: the rated label questions (``"label:joy"``...) in profile order; empty for Mascaró."""
    quality: pd.DataFrame | None = None
    """Broekens: ``factor, level, expression, n_trials, target_intensity, mean_intensity, quality`` (intensities
    0..1); ``factor == "all"`` rows are over every condition, the others per level of one factor."""
    profile: pd.DataFrame | None = None
    """Broekens: mean rating 1..5, expression (rows) x label question (columns)."""
    naturalness: pd.DataFrame | None = None
    """Broekens: ``expression, n, mean, sd, ci_low, ci_high`` of naturalness 1..5 (over participants' means)."""
    anova: dict[str, AnovaTable] = field(default_factory=dict)
    """Dependent measure -> rm-ANOVA over :attr:`factors`."""
    expression_anova: dict[str, AnovaTable] = field(default_factory=dict)
    """Broekens: dependent measure -> rm-ANOVA over the expressions (the paper's Table 3)."""
    mascaro: pd.DataFrame | None = None
    """Mascaró: ``expression, question, n, mean, sd, ci_low, ci_high`` (0..5, over participants' means)."""
    trials: pd.DataFrame | None = None
    """One row per trial (participant x stimulus): the factors, ``nr_shows``, each question's rating, and for
    Broekens ``target_intensity`` / ``mean_intensity`` (0..1)."""
    incomplete_trials: int = 0
    """Trials missing some question's answer (a session stopped mid-stimulus), left out of the Broekens tables."""
    source: str = ""
    """Where the answers came from (a CSV path, or ``"answers frame"``)."""
    source_sha256: str = ""
    """SHA-256 of the CSV file analysed, or of an in-memory frame's canonical CSV bytes
    (:func:`mien.study.export.answers_sha256`: what ``mien study export`` would write from it)."""
    notes: tuple[str, ...] = ()
    """Things a reader of the results must know (dropped participants, left-out trials...)."""


def _need_pandas() -> Any:
    return require("pandas", "study")


def _level_text(value: object) -> str:
    """A factor level as text: numbers as ``:g`` (``1.0`` -> ``"1"``), missing as ``""``."""
    if value is None:
        return ""
    if isinstance(value, float) and math.isnan(value):
        return ""
    text = str(value).strip()
    if text.lower() in ("nan", "none"):
        return ""
    try:
        number = float(text)
    except ValueError:
        return text
    return f"{number:g}" if math.isfinite(number) else text


def _text(value: object) -> str:
    """A cell as stripped text (missing -> ``""``)."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    return str(value).strip()


def _where(source: str, index: int, from_csv: bool) -> str:
    return f"{source} line {index + 2}" if from_csv else f"{source} row {index}"


def check_answers(answers: pd.DataFrame, source: str = "answers frame", from_csv: bool = False) -> pd.DataFrame:
    """Validate the long answers table and return a clean copy (``rating``/``nr_shows``/``position`` as int,
    factor levels as text).

    Raises :class:`~mien.errors.InvalidValueError` naming ``source`` and the line (CSV: the file's line number,
    header = 1) or row, and the column, for: a missing column, more than one study or protocol, an unknown
    protocol or question, a rating or nrShows that is empty, not an integer or out of range, and an item
    answered twice by the same participant.
    """
    pd = _need_pandas()
    missing = [c for c in ANSWER_COLUMNS if c not in answers.columns]
    if missing:
        raise InvalidValueError(
            f"columns of {source}",
            ", ".join(missing),
            f"every column of the answers table: {', '.join(ANSWER_COLUMNS)}",
        )
    if len(answers) == 0:
        raise InvalidValueError(f"rows of {source}", 0, "at least one answer")
    frame = answers.reset_index(drop=True).copy()
    for name in ("study", "participant", "stimulus", "protocol", "expression", "question"):
        frame[name] = [_text(v) for v in frame[name]]
    protocols = sorted(set(frame["protocol"]))
    if len(protocols) != 1 or protocols[0] not in RATING_RANGE:
        raise InvalidValueError(f"protocol in {source}", ", ".join(protocols), "one of 'broekens' or 'mascaro'")
    protocol = protocols[0]
    studies = sorted(set(frame["study"]))
    if len(studies) != 1:
        raise InvalidValueError(f"study in {source}", ", ".join(studies), "the answers of one study")
    known = QUESTIONS[protocol]
    for index, question in enumerate(frame["question"]):
        is_label = protocol == "broekens" and question.startswith(LABEL_PREFIX) and len(question) > len(LABEL_PREFIX)
        if not is_label and question not in known:
            allowed = ("label:NAME", *known) if protocol == "broekens" else known
            raise InvalidValueError(
                f"{_where(source, index, from_csv)} column 'question'", question, f"one of {', '.join(allowed)}"
            )
    low, high = RATING_RANGE[protocol]
    for column, lowest, highest in (("rating", low, high), ("nr_shows", 0, None), ("position", 0, None)):
        numbers = pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=np.float64)
        bad = ~np.isfinite(numbers) | (numbers != np.round(numbers)) | (numbers < lowest)
        if highest is not None:
            bad |= numbers > highest
        if bad.any():
            index = int(np.flatnonzero(bad)[0])
            wanted = (
                f"an integer {lowest}..{highest} ({protocol})" if highest is not None else f"an integer >= {lowest}"
            )
            raise InvalidValueError(
                f"{_where(source, index, from_csv)} column '{column}'", frame[column][index], wanted
            )
        frame[column] = numbers.astype(np.int64)
    for column in _factor_columns(frame):
        frame[column] = [_level_text(v) for v in frame[column]]
    doubled = frame.duplicated(["participant", "stimulus", "question"], keep="first").to_numpy()
    if doubled.any():
        index = int(np.flatnonzero(doubled)[0])
        row = frame.iloc[index]
        raise InvalidValueError(
            f"{_where(source, index, from_csv)}",
            f"{row['participant']}/{row['stimulus']}/{row['question']}",
            "each item answered once per participant (this one is a duplicate: fix the export or the store)",
        )
    return frame


def _factor_columns(frame: pd.DataFrame) -> list[str]:
    """The design-factor columns: every column that is not one of :data:`ANSWER_COLUMNS`, in table order."""
    return [c for c in frame.columns if c not in ANSWER_COLUMNS]


def trials_frame(answers: pd.DataFrame) -> pd.DataFrame:
    """One row per trial (participant x stimulus) from a checked answers table (:func:`check_answers`).

    Columns: ``participant, stimulus, position, expression``, the factor columns, ``nr_shows`` (the largest
    recorded), then one column per question holding its rating (NaN when not answered), and for Broekens
    ``target_intensity`` (0..1, NaN when the expression's label was not rated) and ``mean_intensity`` (0..1).
    """
    pd = _need_pandas()
    factors = _factor_columns(answers)
    keys = ["participant", "stimulus"]
    first = answers.groupby(keys, sort=False).agg(
        position=("position", "min"),
        expression=("expression", "first"),
        nr_shows=("nr_shows", "max"),
        **{f: (f, "first") for f in factors},
    )
    ratings = answers.pivot_table(index=keys, columns="question", values="rating", aggfunc="first")
    ratings.columns.name = None
    trials = first.join(ratings).reset_index()
    labels = [c for c in ratings.columns if str(c).startswith(LABEL_PREFIX)]
    if labels:
        intensity = label_intensity(trials[labels].to_numpy())
        trials["mean_intensity"] = intensity.mean(axis=1)
        target = np.full(len(trials), np.nan)
        for row, expression in enumerate(trials["expression"]):
            column = label_question(expression)
            if column in labels:
                target[row] = intensity[row, labels.index(column)]
        trials["target_intensity"] = target
    order = ["participant", "stimulus", "position", "expression", *factors, "nr_shows"]
    return pd.DataFrame(trials[[*order, *[c for c in trials.columns if c not in order]]])


def mean_ci(values: Sequence[float] | np.ndarray, confidence: float = 0.95) -> tuple[int, float, float, float, float]:
    """``(n, mean, sd, low, high)``: mean with its t-based ``confidence`` interval (sd with n - 1).

    NaN values are ignored; with fewer than two values the sd and interval are NaN.

    >>> n, mean, sd, low, high = mean_ci([1.0, 2.0, 3.0])
    >>> n, mean, sd, round(low, 4), round(high, 4)
    (3, 2.0, 1.0, -0.4841, 4.4841)
    """
    from scipy import stats

    data = np.asarray(values, dtype=np.float64)
    data = data[np.isfinite(data)]
    n = int(data.size)
    if n == 0:
        return 0, float("nan"), float("nan"), float("nan"), float("nan")
    mean = float(data.mean())
    if n < 2:
        return n, mean, float("nan"), float("nan"), float("nan")
    sd = float(data.std(ddof=1))
    half = float(stats.t.ppf(0.5 + confidence / 2, n - 1)) * sd / math.sqrt(n)
    return n, mean, sd, mean - half, mean + half


def _summary(trials: pd.DataFrame, measure: str, by: Sequence[str]) -> pd.DataFrame:
    """Mean and 95% interval of ``measure`` over participants' means, per ``by`` group."""
    pd = _need_pandas()
    per_participant = trials.groupby([*by, "participant"], sort=True, observed=True)[measure].mean().reset_index()
    rows = []
    for key, group in per_participant.groupby(list(by), sort=True, observed=True):
        key_values = key if isinstance(key, tuple) else (key,)
        rows.append([*key_values, *mean_ci(group[measure].to_numpy())])
    return pd.DataFrame(rows, columns=[*by, "n", "mean", "sd", "ci_low", "ci_high"])


def _default_factors(frame: pd.DataFrame, protocol: str) -> tuple[list[str], list[str]]:
    """``(within, between)``: varied factor columns that some participant saw at two or more levels, and those
    every participant saw at one level only (between-subject: not a factor of the repeated-measures ANOVA)."""
    varied = [c for c in _factor_columns(frame) if c not in _NOT_WITHIN and frame[c].nunique() > 1]
    within = [c for c in varied if int(frame.groupby("participant")[c].nunique().max()) > 1]
    between = [c for c in varied if c not in within]
    return (["expression", *within] if protocol == "mascaro" else within), between


def _label_order(questions: Sequence[str]) -> list[str]:
    """Label questions in the rating form's order (:data:`mien.study.protocol.BROEKENS_LABELS`), others after."""

    preferred = [LABEL_PREFIX + name for name, _ in BROEKENS_LABELS]
    present = set(questions)
    return [q for q in preferred if q in present] + sorted(q for q in present if q not in preferred)


def _expression_order(expressions: Sequence[str], labels: Sequence[str]) -> list[str]:
    rank = {label: i for i, label in enumerate(labels)}
    return sorted(set(expressions), key=lambda e: (rank.get(label_question(e), len(rank)), e))


def analyze(
    answers: pd.DataFrame,
    design_factors: Sequence[str] | None = None,
    *,
    source: str = "answers frame",
    source_sha256: str = "",
    _from_csv: bool = False,
) -> StudyAnalysis:
    """Analyse one study's long answers table (see the module docstring for what is computed).

    ``design_factors``: the within-subject factors of the ANOVAs (columns of the table; ``"expression"``
    allowed). Default: every design-factor column that some participant answered at two or more levels
    (Mascaró: the laughter type, as ``expression``, first); factors each participant saw at one level only are
    between-subject and named in :attr:`StudyAnalysis.notes`. An unknown name raises
    :class:`~mien.errors.UnknownNameError`; a bad table :class:`~mien.errors.InvalidValueError` (see
    :func:`check_answers`). ``source_sha256``: the hash of the file the table was read from; default the
    hash of the table itself as exported (:func:`mien.study.export.answers_sha256`), so the provenance
    always names what was analysed.
    """
    checked = check_answers(answers, source, from_csv=_from_csv)
    if not source_sha256:
        source_sha256 = answers_sha256(answers)
    protocol = str(checked["protocol"].iloc[0])
    factor_columns = _factor_columns(checked)
    notes: list[str] = []
    if design_factors is None:
        factors, between = _default_factors(checked, protocol)
        if between:
            notes.append(
                f"between-subject factors (each participant saw one level), not in the rm-ANOVA: {', '.join(between)}"
            )
    else:
        factors = list(design_factors)
        for name in factors:
            if name != "expression" and name not in factor_columns:
                raise UnknownNameError(f"design factor (columns of {source})", name, ("expression", *factor_columns))
    levels = {c: tuple(sorted(set(checked[c]), key=_level_key)) for c in factor_columns}
    common = StudyAnalysis(
        study=str(checked["study"].iloc[0]),
        protocol=protocol,
        n_participants=int(checked["participant"].nunique()),
        n_answers=len(checked),
        factors=tuple(factors),
        factor_levels=levels,
        source=source,
        source_sha256=source_sha256,
        notes=tuple(notes),
    )
    trials = trials_frame(checked)
    if protocol == "broekens":
        return _analyze_broekens(common, checked, trials)
    return _analyze_mascaro(common, trials)


def _level_key(text: str) -> tuple[int, float, str]:
    try:
        return 0, float(text), text
    except ValueError:
        return 1, 0.0, text


def _analyze_broekens(common: StudyAnalysis, checked: pd.DataFrame, trials: pd.DataFrame) -> StudyAnalysis:
    """``common`` (the fields every protocol fills) completed with the Broekens tables of ``checked``."""
    pd = _need_pandas()
    factors, levels, notes = common.factors, common.factor_levels, list(common.notes)
    labels = _label_order([q for q in set(checked["question"]) if q.startswith(LABEL_PREFIX)])
    asked = [*labels, "naturalness"]
    present = [q for q in asked if q in trials.columns]
    complete_mask = trials[present].notna().all(axis=1) & (len(present) == len(asked))
    incomplete = int((~complete_mask).sum())
    if incomplete:
        notes.append(f"{incomplete} trial(s) missing some answer (a session stopped mid-stimulus) left out")
    complete = trials[complete_mask].copy()
    if complete.empty:
        raise InvalidValueError(
            f"answers in {common.source}", "no complete trial", "at least one stimulus with every label rated"
        )
    expressions = _expression_order(complete["expression"].tolist(), labels)
    complete["expression"] = pd.Categorical(complete["expression"], categories=expressions, ordered=True)
    quality_parts = [quality_table(complete, labels).assign(factor="all", level="")]
    for column in [c for c in levels if c not in _NOT_WITHIN and len(levels[c]) > 1]:
        part = quality_table(complete, labels, by=[column]).rename(columns={column: "level"})
        quality_parts.append(part.assign(factor=column))
    quality = pd.concat(quality_parts, ignore_index=True)
    quality["expression"] = quality["expression"].astype(str)
    quality = quality[["factor", "level", "expression", "n_trials", "target_intensity", "mean_intensity", "quality"]]
    profile = complete.groupby("expression", observed=True)[labels].mean()
    profile.index = profile.index.astype(str)
    naturalness = _summary(complete, "naturalness", ["expression"])
    naturalness["expression"] = naturalness["expression"].astype(str)
    complete["expression"] = complete["expression"].astype(str)
    measures = ["target_intensity", "mean_intensity", "naturalness", "nr_shows", *labels]
    anova = {m: rm_anova(complete, m, factors) for m in measures} if factors else {}
    expression_anova = {m: rm_anova(complete, m, ["expression"]) for m in measures}
    for table in (*anova.values(), *expression_anova.values()):
        if table.dropped:
            notes.append(f"ANOVA of {table.measure} over {' x '.join(table.factors)}: {table.note}")
            break
    if not factors:
        notes.append("no within-subject factor with two levels: no condition ANOVA")
    return replace(
        common, labels=tuple(labels), quality=quality, profile=profile, naturalness=naturalness, anova=anova,
        expression_anova=expression_anova, trials=complete, incomplete_trials=incomplete, notes=tuple(notes),
    )  # fmt: skip


def _analyze_mascaro(common: StudyAnalysis, trials: pd.DataFrame) -> StudyAnalysis:
    """``common`` (the fields every protocol fills) completed with the Mascaró tables of ``trials``."""
    pd = _need_pandas()
    factors, notes = common.factors, list(common.notes)
    questions = [q for q in QUESTIONS["mascaro"] if q in trials.columns]
    parts = []
    for question in questions:
        part = _summary(trials.dropna(subset=[question]), question, ["expression"])
        parts.append(part.assign(question=question))
    mascaro = pd.concat(parts, ignore_index=True)[["expression", "question", "n", "mean", "sd", "ci_low", "ci_high"]]
    anova = {q: rm_anova(trials, q, factors) for q in questions} if factors else {}
    for table in anova.values():
        if table.dropped:
            notes.append(f"ANOVA of {table.measure}: {table.note}")
    return replace(common, anova=anova, mascaro=mascaro, trials=trials, notes=tuple(notes))


def analyze_csv(path: str | os.PathLike[str], design_factors: Sequence[str] | None = None) -> StudyAnalysis:
    """:func:`analyze` the CSV written by ``mien study export`` (errors name the file, line and column).

    Every cell is read as text (an empty factor cell means "not applicable"), then checked and converted.
    """
    pd = _need_pandas()
    file = Path(path)
    if not file.is_file():
        raise InvalidValueError("answers CSV", str(file), "an existing file written by 'mien study export'")
    try:
        frame = pd.read_csv(file, dtype=str, keep_default_na=False, encoding="utf-8")
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as error:
        reason = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise InvalidValueError(
            "answers CSV", str(file), f"a CSV file written by 'mien study export' ({reason})"
        ) from None

    return analyze(frame, design_factors, source=str(file), source_sha256=file_sha256(file), _from_csv=True)
