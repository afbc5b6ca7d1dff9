"""``mien study analyze`` on an exported CSV: a report, or exit 2 naming the file, line and column; between-subject
factors stay out of the repeated-measures ANOVA."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from mien.cli import main
from mien.study.analysis import analyze

DATA = Path(__file__).parent / "data"

DESIGN = """
[study]
name = "tiny"
protocol = "broekens"
[stimuli]
expressions = ["joy", "sadness"]
heads = ["builtin"]
views = ["frontal", "lateral"]
[design]
within = ["view"]
"""


def test_analyze_command_writes_the_report(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    design = tmp_path / "design.toml"
    design.write_text(DESIGN)
    out = tmp_path / "report"
    code = main(["study", "analyze", str(design), "--answers", str(DATA / "broekens_small.csv"), "-o", str(out)])
    assert code == 0, capsys.readouterr().err
    page = (out / "report.html").read_text(encoding="utf-8")
    assert "<b>0.731</b>" in page and "Not run: no manifest.json" in page
    assert str(out / "report.html") in capsys.readouterr().out


def test_analyze_command_bad_csv_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    design = tmp_path / "design.toml"
    design.write_text(DESIGN)
    answers = pd.read_csv(DATA / "broekens_small.csv", dtype=str, keep_default_na=False)
    answers.loc[11, "rating"] = "nan"
    bad = tmp_path / "bad.csv"
    answers.to_csv(bad, index=False)
    assert main(["study", "analyze", str(design), "--answers", str(bad), "-o", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert "mien study: error:" in err and "bad.csv line 13 column 'rating'='nan'" in err and "Traceback" not in err
    assert not (tmp_path / "r" / "report.html").exists()
    answers.drop(columns=["nr_shows"]).to_csv(bad, index=False)
    assert main(["study", "analyze", str(design), "--answers", str(bad), "-o", str(tmp_path / "r")]) == 2
    assert "columns of" in (err := capsys.readouterr().err) and "nr_shows" in err


def test_between_subject_factor_is_not_a_repeated_measure() -> None:
    """Participants each see one head (between) and both views (within): the ANOVA is over view only."""
    answers = pd.read_csv(DATA / "broekens_anova.csv", dtype=str, keep_default_na=False)
    answers["head"] = ["ict" if p in ("P00", "P01", "P02", "P03") else "default" for p in answers["participant"]]
    result = analyze(answers)
    assert result.factors == ("basis", "view", "intensity")
    assert result.anova["naturalness"].n_participants == 8
    assert any("between-subject factors" in note and "head" in note for note in result.notes)
    assert set(result.quality["factor"]) == {"all", "head", "basis", "view", "intensity"}
