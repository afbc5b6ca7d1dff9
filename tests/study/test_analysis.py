"""Study analysis: hand-computed quality, rm-ANOVA against a second implementation, t intervals, bad CSVs."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from mien.errors import InvalidValueError, UnknownNameError
from mien.study.analysis import ANSWER_COLUMNS, analyze, analyze_csv, mean_ci, trials_frame
from mien.study.export import answers_sha256
from mien.study.quality import paper_table4

DATA = Path(__file__).parent / "data"


def test_quality_matches_hand_computation() -> None:
    """broekens_small.csv: ratings other than 1 are listed in data/make_fixtures.py; intensity = (r - 1) / 4."""
    result = analyze_csv(DATA / "broekens_small.csv")
    q = result.quality.set_index(["factor", "level", "expression"])
    # joy trials (target joy; other labels above 1 add to the sum over labels):
    #   p1 frontal joy 5 surprise 3 -> target 1.00, sum 1.50   p1 lateral joy 4          -> 0.75, 0.75
    #   p2 frontal joy 5            -> 1.00, 1.00              p2 lateral joy 3 surpr. 2 -> 0.50, 0.75
    #   p3 frontal joy 4 enthus. 3  -> 0.75, 1.25              p3 lateral joy 4 enthus. 3 -> 0.75, 1.25
    # quality = mean target / (mean over 10 labels x 10) = sum of targets / sum of sums
    assert q.loc[("all", "", "joy"), "quality"] == pytest.approx((1 + 0.75 + 1 + 0.5 + 0.75 + 0.75) / 6.5)
    assert q.loc[("all", "", "joy"), "target_intensity"] == pytest.approx(4.75 / 6)
    assert q.loc[("all", "", "joy"), "mean_intensity"] == pytest.approx(6.5 / 60)
    assert q.loc[("view", "frontal", "joy"), "quality"] == pytest.approx(2.75 / 3.75)
    assert q.loc[("view", "lateral", "joy"), "quality"] == pytest.approx(2.0 / 2.75)
    # sadness: p1 f sad 5 frustr 3 (1.0/1.5), p1 l sad 3 fear 2 (0.5/0.75), p2 f sad 4 (0.75/0.75),
    #          p2 l sad 4 frustr 2 (0.75/1.0), p3 f sad 2 anger 2 (0.25/0.5), p3 l sad 5 (1.0/1.0)
    assert q.loc[("all", "", "sadness"), "quality"] == pytest.approx(4.25 / 5.5)
    assert q.loc[("view", "lateral", "sadness"), "quality"] == pytest.approx(2.25 / 2.75)
    assert q.loc[("all", "", "joy"), "n_trials"] == 6
    # rating profile (1..5): joy's joy label 5, 4, 5, 3, 4, 4 -> 25 / 6
    assert result.profile.loc["joy", "label:joy"] == pytest.approx(25 / 6)
    assert result.profile.loc["sadness", "label:frustrated"] == pytest.approx(9 / 6)
    assert list(result.profile.columns[:3]) == ["label:joy", "label:sadness", "label:anger"]
    assert result.n_participants == 3 and result.n_answers == 132 and result.factors == ("view",)
    assert len(result.source_sha256) == 64


def test_paper_table4_is_self_consistent() -> None:
    """The cited figures obey the paper's own formula (to the table's rounding)."""
    table = paper_table4()
    assert len(table) == 10
    np.testing.assert_allclose(table["target"] / (table["average"] * 10), table["quality"], atol=0.005)


def test_naturalness_and_mascaro_intervals_match_scipy() -> None:
    result = analyze_csv(DATA / "broekens_small.csv")
    natural = result.naturalness.set_index("expression")
    # participants' mean naturalness for joy: p1 (4+3)/2, p2 (5+3)/2, p3 (4+2)/2
    values = np.array([3.5, 4.0, 3.0])
    low, high = stats.t.interval(0.95, 2, loc=values.mean(), scale=stats.sem(values))
    assert natural.loc["joy", "mean"] == pytest.approx(3.5)
    assert natural.loc["joy", "ci_low"] == pytest.approx(low) and natural.loc["joy", "ci_high"] == pytest.approx(high)

    laughs = analyze_csv(DATA / "mascaro_small.csv")
    raw = pd.read_csv(DATA / "mascaro_small.csv")
    for (kind, question), group in raw.groupby(["expression", "question"]):
        row = laughs.mascaro.set_index(["expression", "question"]).loc[(kind, question)]
        ratings = group["rating"].to_numpy(float)
        low, high = stats.t.interval(0.95, len(ratings) - 1, loc=ratings.mean(), scale=stats.sem(ratings))
        assert row["n"] == 5
        assert row["mean"] == pytest.approx(ratings.mean())
        assert row["ci_low"] == pytest.approx(low) and row["ci_high"] == pytest.approx(high)
    assert laughs.protocol == "mascaro" and laughs.factors == ("expression",)
    assert mean_ci([2.0])[2:] != mean_ci([2.0])[2:]  # NaN sd and interval for one value


def _statsmodels_anova(trials: pd.DataFrame, measure: str, factors: list[str]) -> pd.DataFrame:
    from statsmodels.stats.anova import AnovaRM

    cells = trials.groupby(["participant", *factors])[measure].mean().reset_index()
    return AnovaRM(cells, measure, "participant", within=factors).fit().anova_table


@pytest.mark.parametrize("factors", [["view"], ["view", "intensity"], ["basis", "expression"]])
def test_rm_anova_pingouin_agrees_with_statsmodels(factors: list[str]) -> None:
    result = analyze_csv(DATA / "broekens_anova.csv", design_factors=factors)
    for measure in ("target_intensity", "naturalness", "label:joy"):
        ours = result.anova[measure]
        assert ours.engine == "pingouin.rm_anova" and ours.n_participants == 8 and not ours.dropped
        reference = _statsmodels_anova(result.trials, measure, factors)
        assert len(ours.table) == len(reference)
        for (_, row), (_, ref) in zip(ours.table.iterrows(), reference.iterrows(), strict=True):
            assert row["F"] == pytest.approx(ref["F Value"], abs=1e-6, rel=1e-6)
            assert row["df1"] == pytest.approx(ref["Num DF"], abs=1e-6)
            assert row["df2"] == pytest.approx(ref["Den DF"], abs=1e-6)
            assert row["p"] == pytest.approx(ref["Pr > F"], abs=1e-6)
    # the view effect built into the fixture (frontal rated higher) is found
    if "view" in factors:
        view = result.anova["target_intensity"].table.set_index("effect").loc["view"]
        assert view["p"] < 0.01


@pytest.mark.parametrize("factors", [["basis", "view", "intensity"], ["expression", "basis", "view", "intensity"]])
def test_rm_anova_three_or_more_factors_agrees_with_statsmodels(factors: list[str]) -> None:
    result = analyze_csv(DATA / "broekens_anova.csv", design_factors=factors)
    for measure in ("target_intensity", "naturalness", "label:anger"):
        table = result.anova[measure]
        assert table.engine == "mien.study.anova.balanced_rm_anova" and table.n_participants == 8
        reference = _statsmodels_anova(result.trials, measure, factors)
        reference.index = [" x ".join(str(i).split(":")) for i in reference.index]
        assert sorted(table.table["effect"]) == sorted(reference.index) and len(reference) == 2 ** len(factors) - 1
        ours = table.table.set_index("effect").loc[reference.index]
        np.testing.assert_allclose(ours["F"], reference["F Value"], rtol=1e-6, atol=1e-9)
        np.testing.assert_allclose(ours["df1"], reference["Num DF"], atol=1e-9)
        np.testing.assert_allclose(ours["df2"], reference["Den DF"], atol=1e-9)
        np.testing.assert_allclose(ours["p"], reference["Pr > F"], rtol=1e-6, atol=1e-9)


def test_balanced_rm_anova_agrees_with_pingouin_epsilon_and_eta() -> None:
    """Three-level factors (sphericity matters): eps, GG p and ng2 as pingouin computes them."""
    from mien.study.anova import _pingouin, balanced_rm_anova

    rng = np.random.default_rng(3)
    values = rng.normal(size=(9, 3, 4)) + np.array([0.0, 0.4, 1.0])[None, :, None]
    values[:, :, 2] += rng.normal(scale=2.0, size=(9, 3))  # unequal variances: eps < 1
    rows = [(f"s{s}", f"a{a}", f"b{b}", values[s, a, b]) for s in range(9) for a in range(3) for b in range(4)]
    frame = pd.DataFrame(rows, columns=["participant", "A", "B", "y"])
    ours = balanced_rm_anova(values, ["A", "B"]).set_index("effect")
    theirs = _pingouin(frame, "participant", ["A", "B"], "y").set_index("effect")
    for effect in ("A", "B", "A x B"):
        for column in ("F", "df1", "df2", "p", "p_gg", "eps", "ng2"):
            assert ours.loc[effect, column] == pytest.approx(theirs.loc[effect, column], rel=1e-6, abs=1e-9), (
                effect,
                column,
            )
    assert ours.loc["B", "eps"] < 0.9
    one = balanced_rm_anova(values.mean(axis=2), ["A"]).iloc[0]
    ref = _pingouin(frame.groupby(["participant", "A"])["y"].mean().reset_index(), "participant", ["A"], "y").iloc[0]
    assert one["eps"] == pytest.approx(ref["eps"]) and one["p_gg"] == pytest.approx(ref["p_gg"])
    # a 3-level factor: the GG-corrected p uses eps x df, as SPSS (the paper's Table 3) does
    assert one["p_gg"] == pytest.approx(stats.f.sf(one["F"], 2 * one["eps"], one["df2"] * one["eps"]))


def test_unbalanced_cells_drop_participants_and_say_so() -> None:
    answers = pd.read_csv(DATA / "broekens_anova.csv", dtype=str, keep_default_na=False)
    gone = (answers["participant"] == "P03") & (answers["view"] == "lateral")
    result = analyze(answers[~gone], design_factors=["view", "intensity"])
    table = result.anova["target_intensity"]
    assert table.dropped == ("P03",) and table.n_participants == 7
    assert "1 participant(s)" in table.note and "P03" in table.note
    assert any("P03" in note for note in result.notes)
    lonely = analyze(answers[answers["participant"] == "P00"], design_factors=["view"])
    assert lonely.anova["naturalness"].table.empty and "at least 2" in lonely.anova["naturalness"].note


def test_incomplete_trial_left_out_and_counted() -> None:
    answers = pd.read_csv(DATA / "broekens_small.csv", dtype=str, keep_default_na=False)
    stopped = answers.drop(index=answers.index[-3:])  # p3's last stimulus: two labels and naturalness missing
    result = analyze(stopped)
    assert result.incomplete_trials == 1
    assert result.quality.set_index(["factor", "level", "expression"]).loc[("all", "", "joy"), "n_trials"] in (5, 6)
    assert int(result.quality.query("factor == 'all'")["n_trials"].sum()) == 11
    assert trials_frame(stopped.assign(rating=stopped["rating"].astype(int), nr_shows=1, position=0)).shape[0] == 12


def _write(tmp_path: Path, frame: pd.DataFrame) -> Path:
    path = tmp_path / "answers.csv"
    frame.to_csv(path, index=False)
    return path


def test_bad_csvs_are_rejected_with_file_line_and_column(tmp_path: Path) -> None:
    answers = pd.read_csv(DATA / "broekens_small.csv", dtype=str, keep_default_na=False)
    with pytest.raises(InvalidValueError, match=r"answers\.csv.*rating"):
        analyze_csv(_write(tmp_path, answers.drop(columns=["rating"])))
    bad = answers.copy()
    bad.loc[4, "rating"] = ""
    with pytest.raises(InvalidValueError, match=r"answers\.csv line 6 column 'rating'.*1\.\.5"):
        analyze_csv(_write(tmp_path, bad))
    bad = answers.copy()
    bad.loc[9, "rating"] = "7"
    with pytest.raises(InvalidValueError, match=r"line 11 column 'rating'='7'"):
        analyze_csv(_write(tmp_path, bad))
    bad = answers.copy()
    bad.loc[2, "rating"] = "2.5"
    with pytest.raises(InvalidValueError, match=r"line 4 column 'rating'"):
        analyze_csv(_write(tmp_path, bad))
    bad = answers.copy()
    bad.loc[3, "nr_shows"] = "-1"
    with pytest.raises(InvalidValueError, match=r"line 5 column 'nr_shows'"):
        analyze_csv(_write(tmp_path, bad))
    bad = answers.copy()
    bad.loc[0, "question"] = "label"
    with pytest.raises(InvalidValueError, match=r"line 2 column 'question'"):
        analyze_csv(_write(tmp_path, bad))
    with pytest.raises(InvalidValueError, match=r"duplicate"):
        analyze_csv(_write(tmp_path, pd.concat([answers, answers.iloc[[7]]], ignore_index=True)))
    bad = answers.copy()
    bad.loc[0, "protocol"] = "mascaro"
    with pytest.raises(InvalidValueError, match=r"protocol"):
        analyze_csv(_write(tmp_path, bad))
    with pytest.raises(UnknownNameError, match=r"design factor.*'colour'"):
        analyze_csv(DATA / "broekens_small.csv", design_factors=["colour"])
    with pytest.raises(InvalidValueError, match=r"existing file"):
        analyze_csv(tmp_path / "nope.csv")
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    with pytest.raises(InvalidValueError, match=r"empty\.csv"):
        analyze_csv(empty)
    header_only = tmp_path / "header.csv"
    header_only.write_text(",".join(ANSWER_COLUMNS) + "\n")
    with pytest.raises(InvalidValueError, match=r"at least one answer"):
        analyze_csv(header_only)


def test_frame_from_store_with_numbers_and_nones() -> None:
    """The store's frame carries ints, floats and None for empty factors: same results as the CSV."""
    answers = pd.read_csv(DATA / "broekens_small.csv")
    answers["label_position"] = answers["label_position"].astype(object).where(answers["label_position"].notna(), None)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no pandas/pingouin warning leaks to the user
        from_frame = analyze(answers)
    from_csv = analyze_csv(DATA / "broekens_small.csv")
    pd.testing.assert_frame_equal(from_frame.quality, from_csv.quality)
    assert from_frame.factor_levels["distance_m"] == ("1",)
    assert from_frame.source_sha256 == answers_sha256(answers)  # what was read, hashed (was empty)
