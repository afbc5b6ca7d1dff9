"""How the fixed answer tables beside this file were made (run once: ``python tests/study/data/make_fixtures.py``).

* ``broekens_small.csv``: 3 participants x 2 expressions (joy, sadness) x 2 views, ratings chosen by hand so
  the quality values can be computed on paper (tests/study/test_analysis.py does it step by step).
* ``broekens_anova.csv``: 8 participants x 2 expressions x 2 views x 2 intensities x 2 bases, seeded random
  ratings with a view effect, for the pingouin / statsmodels cross-check.
* ``mascaro_small.csv``: 5 participants x 3 laughter types x 2 questions, seeded random 0..5.

The tables follow the export contract (docs/STUDIES.md): one row per answered item.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

LABELS = ("joy", "sadness", "anger", "surprise", "disgust", "fear", "enthusiastic", "furious", "frustrated", "evil")
HEADER = [
    "study", "participant", "session_started_at", "position", "stimulus", "protocol", "expression",
    "head", "identity", "basis", "view", "distance_m", "intensity",
    "question", "label_position", "rating", "nr_shows", "answered_at",
]  # fmt: skip

# participant -> (expression, view) -> ({label: rating other than 1}, naturalness, nr_shows)
SMALL = {
    "p1": {
        ("joy", "frontal"): ({"joy": 5, "surprise": 3}, 4, 1),
        ("joy", "lateral"): ({"joy": 4}, 3, 2),
        ("sadness", "frontal"): ({"sadness": 5, "frustrated": 3}, 4, 1),
        ("sadness", "lateral"): ({"sadness": 3, "fear": 2}, 2, 3),
    },
    "p2": {
        ("joy", "frontal"): ({"joy": 5}, 5, 1),
        ("joy", "lateral"): ({"joy": 3, "surprise": 2}, 3, 1),
        ("sadness", "frontal"): ({"sadness": 4}, 4, 2),
        ("sadness", "lateral"): ({"sadness": 4, "frustrated": 2}, 3, 1),
    },
    "p3": {
        ("joy", "frontal"): ({"joy": 4, "enthusiastic": 3}, 4, 2),
        ("joy", "lateral"): ({"joy": 4, "enthusiastic": 3}, 2, 1),
        ("sadness", "frontal"): ({"sadness": 2, "anger": 2}, 3, 1),
        ("sadness", "lateral"): ({"sadness": 5}, 4, 1),
    },
}


def _stamp(minute: int, second: int) -> str:
    return f"2026-01-05T10:{minute:02d}:{second:02d}Z"


def small(path: Path) -> None:
    rows = []
    stimuli = {key: f"s{i + 1:03d}" for i, key in enumerate(SMALL["p1"])}
    for p_index, (participant, trials) in enumerate(SMALL.items()):
        order = np.random.default_rng(p_index).permutation(len(LABELS))
        shown = [LABELS[i] for i in order]
        keys = list(trials)[p_index:] + list(trials)[:p_index]  # a different stimulus order per participant
        for position, key in enumerate(keys):
            ratings, natural, shows = trials[key]
            expression, view = key
            base = [
                "tiny", participant, _stamp(p_index, 0), position, stimuli[key], "broekens", expression,
                "default", "default", "facs", view, "1.0", "1.2",
            ]  # fmt: skip
            for label_pos, label in enumerate(shown):
                answered = _stamp(p_index * 10 + position, label_pos)
                rows.append([*base, f"label:{label}", label_pos, ratings.get(label, 1), shows, answered])
            rows.append([*base, "naturalness", "", natural, shows, _stamp(p_index * 10 + position, 30)])
    _write(path, HEADER, rows)


def anova(path: Path) -> None:
    rng = np.random.default_rng(7)
    rows = []
    conditions = [
        (e, v, i, b) for e in ("joy", "anger") for v in ("frontal", "lateral") for i in ("1.2", "2.4")
        for b in ("facs", "feature_points")
    ]  # fmt: skip
    for p_index in range(8):
        participant = f"P{p_index:02d}"
        skill = rng.normal(0, 0.6)
        for position, (expression, view, intensity, basis) in enumerate(conditions):
            stimulus = f"s{conditions.index((expression, view, intensity, basis)) + 1:03d}"
            base = [
                "anova", participant, "2026-01-06T09:00:00Z", position, stimulus, "broekens", expression,
                "default", "default", basis, view, "1.0", intensity,
            ]  # fmt: skip
            boost = (1.2 if view == "frontal" else 0.0) + (0.6 if intensity == "2.4" else 0.0) + skill
            for label_pos, label in enumerate(LABELS):
                centre = 2.0 + boost if label == expression else 1.3
                rating = int(np.clip(np.rint(rng.normal(centre, 0.9)), 1, 5))
                rows.append(
                    [*base, f"label:{label}", label_pos, rating, int(rng.integers(1, 4)), "2026-01-06T09:01:00Z"]
                )
            natural = int(np.clip(np.rint(rng.normal(3 + 0.5 * (basis == "facs"), 1.0)), 1, 5))
            rows.append([*base, "naturalness", "", natural, 1, "2026-01-06T09:01:00Z"])
    _write(path, HEADER, rows)


def mascaro(path: Path) -> None:
    rng = np.random.default_rng(11)
    header = [
        "study", "participant", "session_started_at", "position", "stimulus", "protocol", "expression",
        "laughter_type", "description", "question", "label_position", "rating", "nr_shows", "answered_at",
    ]  # fmt: skip
    types = {"sly_smile": 4.0, "false_smile": 2.5, "laughter": 3.5}
    rows = []
    for p_index in range(5):
        for position, (kind, centre) in enumerate(types.items()):
            base = [
                "laughs", f"m{p_index}", "2026-01-07T12:00:00Z", position, f"s{position + 1:03d}", "mascaro", kind,
                kind, f"a {kind.replace('_', ' ')}",
            ]  # fmt: skip
            for question in ("feels_right", "represents_description"):
                rating = int(np.clip(np.rint(rng.normal(centre, 1.0)), 0, 5))
                rows.append([*base, question, "", rating, 1, "2026-01-07T12:01:00Z"])
    _write(path, header, rows)


def _write(path: Path, header: list[str], rows: list[list[object]]) -> None:
    with open(path, "w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle, lineterminator="\n")
        writer.writerow(header)
        writer.writerows(rows)


if __name__ == "__main__":
    here = Path(__file__).parent
    small(here / "broekens_small.csv")
    anova(here / "broekens_anova.csv")
    mascaro(here / "mascaro_small.csv")
