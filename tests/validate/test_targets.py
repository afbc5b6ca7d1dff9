"""The per-head target scorecard on fixed numbers: bounds, heads kept apart, unmeasured targets left out."""

from __future__ import annotations

import json

import numpy as np

from mien.validate.detector import EMOTION_LABELS
from mien.validate.scores import RecognitionResult, Stimulus, StimulusScore
from mien.validate.statistics import wilson_interval
from mien.validate.targets import TARGETS, TargetCheck, check_targets, scorecard_lines


def _score(
    expression: str, label: str, head: str, view: str = "frontal-1m", facs_top: str | None = None
) -> StimulusScore:
    vector = np.full(len(EMOTION_LABELS), 0.05)
    vector[EMOTION_LABELS.index(label)] = 0.7
    stimulus = Stimulus(expression, head, "a", "facs", view, 1.2)
    return StimulusScore(stimulus, tuple(vector / vector.sum()), True, facs_top=facs_top)


def _result() -> RecognitionResult:
    scores = [
        # ict: joy read 10 of 10 frontally; builtin: 8 of 10 (below the 90% bound)
        *[_score("joy", "happy", "ict") for _ in range(10)],
        *[_score("joy", "happy" if k < 8 else "sad", "builtin") for k in range(10)],
        # 45 degrees: ict 3 of 4 (the 75% bound, met), builtin 2 of 4
        *[_score("fear", "fear" if k < 3 else "surprise", "ict", "oblique-1m") for k in range(4)],
        *[_score("fear", "fear" if k < 2 else "surprise", "builtin", "oblique-1m") for k in range(4)],
        # disgust read as anger by the FACS reading: ict 1 of 10 (the 10% bound, met), builtin 2 of 10
        *[_score("disgust", "angry", "ict", facs_top="anger" if k < 1 else "disgust") for k in range(10)],
        *[_score("disgust", "angry", "builtin", facs_top="anger" if k < 2 else "disgust") for k in range(10)],
    ]
    return RecognitionResult(tuple(scores), "fixed", {})


def test_targets_are_checked_per_head_and_over_all_heads() -> None:
    checks = {(c.head, c.target.name): c for c in check_targets(_result())}
    assert checks[("ict:a", "frontal joy")].value == 1.0 and checks[("ict:a", "frontal joy")].met
    assert checks[("builtin:a", "frontal joy")].value == 0.8 and checks[("builtin:a", "frontal joy")].met is False
    assert checks[("all", "frontal joy")].value == 0.9 and checks[("all", "frontal joy")].met
    assert checks[("ict:a", "45 degrees, the five")].met and checks[("builtin:a", "45 degrees, the five")].met is False
    anger = "disgust read as anger (FACS reading)"
    assert checks[("ict:a", anger)].met and checks[("builtin:a", anger)].met is False
    # nothing rendered for sadness or the blends: not measured, neither met nor missed
    assert checks[("ict:a", "frontal sadness")].met is None
    assert checks[("all", "blend evil (top two)")].met is None


def test_scorecard_names_what_each_head_misses() -> None:
    lines = scorecard_lines(check_targets(_result()))
    heads = [line.split()[0] for line in lines if not line.startswith("    ")]
    assert heads == ["builtin:a", "ict:a", "all"]
    text = "\n".join(lines)
    builtin, ict = text.split("ict:a")[0], text.split("ict:a")[1].split("all")[0]
    assert "meets 3 of 3" in ict and "misses" not in ict
    assert "meets 0 of 3; misses:" in builtin
    # 8 of 10 against 90%: the 95% interval (49-94%) reaches the bound, so the miss is within noise
    assert "frontal joy 80% (8 of 10; 95% interval 49-94%; >= 90%), within noise" in builtin
    assert "disgust read as anger (FACS reading) 20% (2 of 10; 95% interval 6-51%; <= 10%), within noise" in builtin


def test_a_miss_is_decided_once_enough_renders_agree() -> None:
    joy = TARGETS[0]
    assert TargetCheck("x", joy, 35, 80).decided and not TargetCheck("x", joy, 35, 80).met
    assert TargetCheck("x", joy, 80, 80).decided and TargetCheck("x", joy, 80, 80).met
    assert not TargetCheck("x", joy, 7, 8).decided
    low, high = wilson_interval(35, 80)
    assert 0.33 < low < 0.34 and 0.54 < high < 0.56
    assert wilson_interval(0, 0) != wilson_interval(0, 0)  # nan: nothing judged


def test_recognition_json_carries_the_targets() -> None:
    data = json.loads(json.dumps(_result().to_json(), default=float))
    rows = {(row["head"], row["target"]): row for row in data["targets"]}
    assert len(rows) == 3 * len(TARGETS)
    joy = rows[("builtin:a", "frontal joy")]
    assert joy["met"] is False and joy["rule"] == ">= 90%" and (joy["hits"], joy["n"]) == (8, 10)
    assert joy["decided"] is False and 0.49 < joy["interval95"][0] < 0.5
