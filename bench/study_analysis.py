"""Benchmark: analysing the full Broekens design, against reading the same CSV with pandas.

The data set: the paper's 19 participants x the full design of docs/STUDIES.md (10 expressions x 2 bases x
2 views x 2 distances x 2 intensities = 160 stimuli), each rated on 10 labels + naturalness: 33,440 answers,
seeded random ratings. Stages timed, interleaved over repeats:

* baseline ``pandas.read_csv`` of the export CSV (what any analysis must do);
* ``analyze_csv`` (checks, quality, profiles, 14 rm-ANOVAs over 4 within factors with statsmodels, 14 over the
  expressions with pingouin);
* ``write_report`` (figures and the HTML page; no machine judgement).

Prints the median seconds and the spread (min..max) of each, and the ratios to the baseline.
Run: ``python bench/study_analysis.py [--repeats 3] [--participants 19]``.
"""

from __future__ import annotations

import argparse
import csv
import itertools
import statistics
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

LABELS = ("joy", "sadness", "anger", "surprise", "disgust", "fear", "enthusiastic", "furious", "frustrated", "evil")


def make_answers(path: Path, participants: int, seed: int = 0) -> int:
    """Write a synthetic export CSV of the full design; returns the number of answers."""
    rng = np.random.default_rng(seed)
    cells = list(itertools.product(("facs", "feature_points"), ("frontal", "lateral"), ("1", "3"), ("1.2", "2.4")))
    stimuli = [(e, *c) for c in cells for e in LABELS]
    header = [
        "study", "participant", "session_started_at", "position", "stimulus", "protocol", "expression", "head",
        "identity", "basis", "view", "distance_m", "intensity", "question", "label_position", "rating", "nr_shows",
        "answered_at",
    ]  # fmt: skip
    rows = 0
    with open(path, "w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle, lineterminator="\n")
        writer.writerow(header)
        for p in range(participants):
            order = rng.permutation(len(stimuli))
            labels = [LABELS[i] for i in rng.permutation(len(LABELS))]
            for position, index in enumerate(order):
                expression, basis, view, distance, intensity = stimuli[index]
                base = ["bench", f"p{p:03d}", "2026-01-01T00:00:00Z", position, f"s{index + 1:03d}", "broekens",
                        expression, "default", "", basis, view, distance, intensity]  # fmt: skip
                shows = int(rng.integers(1, 4))
                for label_position, label in enumerate(labels):
                    centre = 3.6 - 0.6 * (view == "lateral") if label == expression else 1.4
                    rating = int(np.clip(np.rint(rng.normal(centre, 1.0)), 1, 5))
                    writer.writerow([*base, f"label:{label}", label_position, rating, shows, "2026-01-01T00:01:00Z"])
                    rows += 1
                natural = int(np.clip(np.rint(rng.normal(3.2, 1.0)), 1, 5))
                writer.writerow([*base, "naturalness", "", natural, shows, "2026-01-01T00:01:00Z"])
                rows += 1
    return rows


def main() -> None:
    import pandas as pd

    from mien.study.analysis import analyze_csv
    from mien.study.report import write_report

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--participants", type=int, default=19)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "answers.csv"
        answers = make_answers(path, args.participants)
        times: dict[str, list[float]] = {"read_csv (baseline)": [], "analyze_csv": [], "write_report": []}
        for repeat in range(args.repeats):
            started = time.perf_counter()
            pd.read_csv(path, dtype=str, keep_default_na=False)
            times["read_csv (baseline)"].append(time.perf_counter() - started)
            started = time.perf_counter()
            result = analyze_csv(path)
            times["analyze_csv"].append(time.perf_counter() - started)
            started = time.perf_counter()
            write_report(result, Path(folder) / f"report{repeat}")
            times["write_report"].append(time.perf_counter() - started)
    anovas = len(result.anova) + len(result.expression_anova)
    print(f"{args.participants} participants, {answers} answers, factors {', '.join(result.factors)}; "
          f"{anovas} rm-ANOVAs; {args.repeats} interleaved repeats")  # fmt: skip
    baseline = statistics.median(times["read_csv (baseline)"])
    for name, values in times.items():
        median = statistics.median(values)
        print(f"{name:22s} median {median:7.3f} s  (min {min(values):.3f} .. max {max(values):.3f})  "
              f"x{median / baseline:6.1f} of read_csv")  # fmt: skip


if __name__ == "__main__":
    main()
