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


def test_store_frame_analyses_like_the_csv(tmp_path: Path) -> None:
    """The contract both ways: answers stored through a real SQLite Store come back from answers_frame() and
    give the same analysis as the CSV they came from."""
    from mien.study.storage import Store

    answers = pd.read_csv(DATA / "broekens_small.csv", dtype=str, keep_default_na=False)
    factors = ["head", "identity", "basis", "view", "distance_m", "intensity"]
    stimuli = answers.drop_duplicates("stimulus").sort_values("stimulus")
    store = Store(f"sqlite:///{tmp_path / 'study.sqlite'}")
    try:
        store.register_stimuli(
            "tiny",
            "broekens",
            [
                {
                    "id": row["stimulus"],
                    "file": f"{row['stimulus']}.mp4",
                    "sha256": "0" * 64,
                    "expression": row["expression"],
                    "conditions": {f: (float(row[f]) if f in ("distance_m", "intensity") else row[f]) for f in factors},
                    "duration_s": 1.0,
                    "fps": 10,
                }
                for _, row in stimuli.iterrows()
            ],
        )
        for participant, rows in answers.groupby("participant", sort=True):
            sequence = tuple(rows.drop_duplicates("stimulus").sort_values("position")["stimulus"])
            store.ensure_participant("tiny", participant, lambda _ordinal, s=sequence: (s, (), ()))
            for (stimulus, position), trial in rows.groupby(["stimulus", "position"]):
                ratings = {q: int(r) for q, r in zip(trial["question"], trial["rating"], strict=True)}
                label_positions = {
                    q: int(p) for q, p in zip(trial["question"], trial["label_position"], strict=True) if p != ""
                }
                shows = int(trial["nr_shows"].iloc[0])
                assert store.record_answer(
                    "tiny", participant, stimulus, int(position), ratings, label_positions, shows
                )
        frame = store.answers_frame("tiny")
    finally:
        store.close()
    assert len(frame) == len(answers)
    from_store = analyze(frame)
    expected = analyze(answers)
    pd.testing.assert_frame_equal(from_store.quality, expected.quality)
    pd.testing.assert_frame_equal(from_store.profile, expected.profile)
    assert from_store.anova["naturalness"].table["F"].tolist() == expected.anova["naturalness"].table["F"].tolist()
