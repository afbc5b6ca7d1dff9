"""One self-contained HTML page for a study's analysis (``mien study analyze``): :func:`write_report`.

The page holds the tables (quality next to Broekens' Table 4, rating profiles, naturalness, the rm-ANOVA
tables, or Mascaró's means and intervals), the figures of :mod:`mien.study.plots` embedded as base64 PNG,
the machine's judgement of the same stimuli beside the people's (:mod:`mien.study.machine`) or why it was not
run, and what produced the numbers: the answers file and its SHA-256, participants in and dropped, the
versions of mien and the libraries, the detector models. The PNGs also stay in ``figures/`` beside the page.
The page is written under a temporary name and renamed when complete.
"""

from __future__ import annotations

import html
import json
import os
import platform
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from mien.errors import MienError
from mien.fileio.hashing import file_sha256
from mien.fileio.streams import write_text
from mien.htmlpage import STYLE, img, library_versions, num, pct, table
from mien.study import plots
from mien.study.machine import judge_stimuli, machine_unavailable
from mien.study.quality import paper_table4
from mien.study.stimuli import MANIFEST_NAME
from mien.version import __version__

if TYPE_CHECKING:
    import pandas as pd

    from mien.study.analysis import AnovaTable, StudyAnalysis
    from mien.study.machine import MachineJudgement

__all__ = ["render_report", "write_report"]

_LIBRARIES = ("numpy", "scipy", "pandas", "pingouin", "statsmodels", "matplotlib", "mediapipe", "ai-edge-litert")

_INTERACTION_MEASURES = ("target_intensity", "mean_intensity", "naturalness")


def _p(value: float) -> str:
    if value is None or not np.isfinite(value):
        return "–"
    return "&lt;0.0001" if value < 1e-4 else f"{value:.4f}"


def _text(value: object) -> str:
    return html.escape(str(value))


def _anova_rows(tables: list[AnovaTable]) -> list[list[str]]:
    rows = []
    for result in tables:
        if result.table.empty:
            rows.append(
                [
                    _text(result.measure),
                    "–",
                    "–",
                    "–",
                    "–",
                    "–",
                    "–",
                    "–",
                    str(result.n_participants),
                    _text(result.note or "not run"),
                ]
            )
            continue
        for _, row in result.table.iterrows():
            mark = ' class="low"' if np.isfinite(row["p"]) and row["p"] < 0.05 else ""
            rows.append(
                [
                    _text(result.measure),
                    _text(row["effect"]),
                    f"{num(row['df1'], 3)}, {num(row['df2'], 3)}",
                    num(row["F"], 3),
                    f"<span{mark}>{_p(row['p'])}</span>",
                    _p(row["p_gg"]),
                    num(row["eps"], 3),
                    num(row["ng2"], 3),
                    str(result.n_participants),
                    _text(f"{result.engine}; {result.note}" if result.note else result.engine),
                ]
            )
    return rows


_ANOVA_HEADER = ["measure", "effect", "df", "F", "p", "p (GG)", "eps (GG)", "ng2", "n", "engine / note"]


def _quality_section(analysis: StudyAnalysis, figures: dict[str, Path]) -> str:

    assert analysis.quality is not None and analysis.profile is not None and analysis.naturalness is not None
    quality = analysis.quality
    paper = paper_table4().set_index("expression")
    overall = quality[quality["factor"] == "all"]
    rows = []
    for _, row in overall.iterrows():
        name = str(row["expression"])
        cited = paper.loc[name] if name in paper.index else None
        rows.append(
            [
                f"<b>{_text(name)}</b>",
                str(int(row["n_trials"])),
                num(row["target_intensity"], 3),
                num(row["mean_intensity"], 3),
                f"<b>{num(row['quality'], 3)}</b>",
                num(None if cited is None else float(cited["target"]), 3),
                num(None if cited is None else float(cited["average"]), 3),
                num(None if cited is None else float(cited["quality"]), 3),
            ]
        )
    lines = [
        "<h2>Recognition quality (Broekens et al., Table 4)</h2>",
        "<p>quality = target intensity / (mean intensity over the labels x number of labels): the share of the "
        "perceived intensity that went to the intended label (0.1 = no preference among ten labels). Intensities "
        "0..1 = (rating - 1) / 4, means over every complete trial. The paper's values (19 participants, averaged "
        "over the male-close, female-close and male-far conditions) beside.</p>",
        table(
            ["expression", "trials", "target", "mean", "quality", "paper target", "paper mean", "paper quality"], rows
        ),
    ]
    by_condition = quality[quality["factor"] != "all"]
    if not by_condition.empty:
        pivot = by_condition.pivot_table(index="expression", columns=["factor", "level"], values="quality", sort=False)
        header = ["expression", *[f"{f} = {lvl}" for f, lvl in pivot.columns]]
        lines.append("<h3>Quality per condition</h3>")
        lines.append(
            table(header, [[_text(e), *[num(v, 3) for v in pivot.loc[e]]] for e in pivot.index]),
        )
    if "quality" in figures:
        lines.append(img(figures["quality"], "quality", "70%"))
    profile = analysis.profile
    lines.append("<h2>Rating profiles (mean rating 1..5 per label)</h2>")
    lines.append(
        table(
            ["expression", *[c.removeprefix("label:") for c in profile.columns]],
            [[f"<b>{_text(e)}</b>", *[num(v) for v in profile.loc[e]]] for e in profile.index],
        )
    )
    if "profile" in figures:
        lines.append(img(figures["profile"], "rating profiles", "80%"))
    lines.append("<h2>Naturalness (1..5, mean and 95% CI over participants' means)</h2>")
    lines.append(_summary_table(analysis.naturalness, ["expression"]))
    if "naturalness" in figures:
        lines.append(img(figures["naturalness"], "naturalness", "60%"))
    return "\n".join(lines)


def _summary_table(frame: pd.DataFrame, keys: list[str]) -> str:
    rows = [
        [
            *[_text(row[k]) for k in keys],
            str(int(row["n"])),
            num(row["mean"]),
            num(row["sd"]),
            f"[{num(row['ci_low'])}, {num(row['ci_high'])}]",
        ]
        for _, row in frame.iterrows()
    ]
    return table([*keys, "n", "mean", "sd", "95% CI"], rows)


def _anova_section(analysis: StudyAnalysis, figures: dict[str, Path]) -> str:
    lines = ["<h2>Repeated-measures ANOVA over the within-subject conditions</h2>"]
    if analysis.anova:
        lines.append(
            f"<p>Within-subject factors: <b>{_text(', '.join(analysis.factors))}</b>. One value per participant and "
            "cell (the mean of their trials in it); participants without a value in every cell are dropped (column "
            "n, and the note). p: uncorrected; GG: Greenhouse-Geisser corrected p and its epsilon; ng2: generalised "
            "eta squared; p &lt; 0.05 in red."
            + (" Label measures and target/mean intensity are intensities 0..1." if analysis.labels else "")
            + "</p>"
        )
        lines.append(table(_ANOVA_HEADER, _anova_rows(list(analysis.anova.values()))))
    else:
        lines.append("<p>No within-subject factor varies in these answers: no condition ANOVA.</p>")
    for key in sorted(k for k in figures if k.startswith("interaction_")):
        lines.append(img(figures[key], key, "90%"))
    if analysis.expression_anova:
        lines.append("<h2>Effect of the expression on each measure (the paper's Table 3)</h2>")
        lines.append(table(_ANOVA_HEADER, _anova_rows(list(analysis.expression_anova.values()))))
    return "\n".join(lines)


def _mascaro_section(analysis: StudyAnalysis, figures: dict[str, Path]) -> str:
    assert analysis.mascaro is not None
    lines = [
        "<h2>Mascaró questions (0..5)</h2>",
        "<p>feels_right: \u201cDoes the motion feel right?\u201d; represents_description: \u201cDoes the motion "
        "represent the description?\u201d. Mean over participants' means per laughter type, t-based 95% interval.</p>",
        _summary_table(analysis.mascaro, ["expression", "question"]),
    ]
    if "mascaro" in figures:
        lines.append(img(figures["mascaro"], "mascaro", "70%"))
    return "\n".join(lines)


def _machine_section(analysis: StudyAnalysis, machine: MachineJudgement | str | None) -> str:
    lines = ["<h2>Machine judgement of the same stimuli</h2>"]
    if machine is None:
        lines.append("<p>Not run: no stimuli folder was given.</p>")
        return "\n".join(lines)
    if isinstance(machine, str):
        lines.append(f"<p>Not run: {_text(machine)}</p>")
        return "\n".join(lines)

    paper = paper_table4().set_index("expression")["quality"]
    human: dict[str, float] = {}
    if analysis.quality is not None:
        overall = analysis.quality[analysis.quality["factor"] == "all"]
        human = dict(zip(overall["expression"], overall["quality"], strict=True))
    rows = []
    for _, row in machine.table().iterrows():
        name = str(row["expression"])
        rows.append(
            [
                f"<b>{_text(name)}</b>",
                str(int(row["n_stimuli"])),
                str(int(row["faces_found"])),
                f"{_text(row['top_label'])} ({pct(row['top_share'])})" if row["top_label"] else "–",
                pct(row["recognised"]),
                num(row["quality"], 3),
                num(human.get(name), 3),
                num(float(paper[name]) if name in paper.index else None, 3),
            ]
        )
    lines.append(
        f"<p>{len(machine.stimulus_ids)} videos of <code>{_text(machine.manifest)}</code> judged by "
        f"<code>{_text(machine.result.detector)}</code> on each video's peak frame (the sampled frame whose "
        "blendshapes moved most from the first one). Recognised: the classifier's top label is the expression's "
        "(blends: its two top labels are the components'). Machine quality: mean probability of the target label "
        "(basic emotions; the classifier has no blend labels). Faces found: MediaPipe found the face itself.</p>"
    )
    lines.append(
        table(
            [
                "expression",
                "stimuli",
                "faces found",
                "top label",
                "recognised",
                "machine quality",
                "human quality (this study)",
                "human quality (paper)",
            ],
            rows,
        )
    )
    return "\n".join(lines)


def _provenance(analysis: StudyAnalysis, machine: MachineJudgement | str | None) -> dict[str, Any]:

    info: dict[str, Any] = {
        "mien": __version__,
        "python": platform.python_version(),
        "platform": platform.platform(),
        "libraries": library_versions(_LIBRARIES),
        "answers": analysis.source,
        "answers_sha256": analysis.source_sha256 or "(in-memory frame)",
        "date": time.strftime("%Y-%m-%d %H:%M:%S %Z"),
    }
    if machine is not None and not isinstance(machine, str):
        info["detector"] = machine.result.detector
        info["models"] = {
            name: {"path": path, "sha256": file_sha256(path) if path and Path(path).is_file() else ""}
            for name, path in machine.models.items()
        }
        info["machine_timings_s"] = machine.timings_s
    return info


def render_report(
    analysis: StudyAnalysis, figures: dict[str, Path], machine: MachineJudgement | str | None = None
) -> str:
    """The report page as a string (``figures``: name -> PNG path, embedded)."""
    dropped = sorted({p for t in (*analysis.anova.values(), *analysis.expression_anova.values()) for p in t.dropped})
    facts = [
        f"<li>protocol <b>{_text(analysis.protocol)}</b>; <b>{analysis.n_participants}</b> participants, "
        f"{analysis.n_answers} answers</li>",
        f"<li>answers: <code>{_text(analysis.source)}</code>"
        + (f", SHA-256 <code>{analysis.source_sha256}</code>" if analysis.source_sha256 else "")
        + "</li>",
        "<li>conditions: "
        + "; ".join(f"{_text(k)} = {_text(', '.join(v))}" for k, v in analysis.factor_levels.items() if v != ("",))
        + "</li>",
        f"<li>dropped from an ANOVA (a cell without answers): <b>{len(dropped)}</b>"
        + (f" ({_text(', '.join(dropped))})" if dropped else "")
        + "</li>",
    ]
    if analysis.incomplete_trials:
        facts.append(f"<li>incomplete trials left out: <b>{analysis.incomplete_trials}</b></li>")
    facts.extend(f"<li>{_text(note)}</li>" for note in analysis.notes)
    sections = []
    if analysis.protocol == "broekens":
        sections.append(_quality_section(analysis, figures))
    else:
        sections.append(_mascaro_section(analysis, figures))
    sections.append(_anova_section(analysis, figures))
    sections.append(_machine_section(analysis, machine))
    return (
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
        f"<title>mien study report: {_text(analysis.study)}</title><style>{STYLE}</style></head><body>"
        f"<h1>Study {_text(analysis.study)}</h1><ul>{''.join(facts)}</ul>"
        + "\n".join(sections)
        + "<h2>What produced these numbers</h2><pre>"
        + html.escape(json.dumps(_provenance(analysis, machine), indent=1))
        + "</pre></body></html>"
    )


def _figures(analysis: StudyAnalysis, folder: Path) -> dict[str, Path]:

    folder.mkdir(parents=True, exist_ok=True)
    out: dict[str, Path] = {}
    if analysis.protocol == "broekens":
        out["quality"] = plots.plot_quality(analysis, folder / "quality.png")
        out["profile"] = plots.plot_profile(analysis, folder / "profile.png")
        out["naturalness"] = plots.plot_naturalness(analysis, folder / "naturalness.png")
        measures = [m for m in _INTERACTION_MEASURES if m in analysis.anova]
    else:
        out["mascaro"] = plots.plot_mascaro(analysis, folder / "mascaro.png")
        measures = list(analysis.anova)
    if analysis.factors:
        for measure in measures:
            name = f"interaction_{measure.replace(':', '_')}"
            out[name] = plots.plot_interactions(analysis, measure, folder / f"{name}.png")
    return out


def write_report(
    analysis: StudyAnalysis,
    out: str | os.PathLike[str],
    machine: MachineJudgement | str | None = None,
    stimuli: str | os.PathLike[str] | None = None,
    landmarker: str | os.PathLike[str] | None = None,
    emotion_model: str | os.PathLike[str] | None = None,
    progress: bool = False,
) -> Path:
    """Write the report and return the page's path.

    ``out``: a folder (the page is ``out/report.html``, figures in ``out/figures/``) or a ``.html`` path
    (figures in ``NAME_figures/`` beside it). ``machine``: a :class:`~mien.study.machine.MachineJudgement`, or
    a reason it was not run; when None and ``stimuli`` (a folder with ``manifest.json``) is given, the
    stimuli are judged here (``landmarker`` / ``emotion_model``: model paths, default the configured ones), or
    the page says why they could not be (models absent, manifest missing, a video changed).
    """
    target = Path(out)
    if target.suffix.lower() in (".html", ".htm"):
        page, folder = target, target.with_name(target.stem + "_figures")
    else:
        page, folder = target / "report.html", target / "figures"
    page.parent.mkdir(parents=True, exist_ok=True)
    if machine is None and stimuli is not None:
        machine = _judge(Path(stimuli), landmarker, emotion_model, progress)
    figures = _figures(analysis, folder)
    write_text(render_report(analysis, figures, machine), page)
    return page


def _judge(
    stimuli: Path,
    landmarker: str | os.PathLike[str] | None,
    emotion_model: str | os.PathLike[str] | None,
    progress: bool,
) -> MachineJudgement | str:

    if not (stimuli / MANIFEST_NAME).is_file():
        return f"no {MANIFEST_NAME} in {stimuli} (run `mien study stimuli DESIGN.toml`, or pass --stimuli)"
    reason = machine_unavailable(landmarker, emotion_model)
    if reason:
        return reason
    try:
        return judge_stimuli(stimuli, landmarker=landmarker, emotion_model=emotion_model, progress=progress)
    except MienError as error:
        return str(error)
