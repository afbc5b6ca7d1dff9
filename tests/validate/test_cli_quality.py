"""``mien validate emotions`` prints a quality for neutral and each basic emotion and says why a blend has none
(issue 29 case 16: a blend printed ``quality nan``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mien.commands.validate as validate_command
from mien.cli import main
from mien.validate.detector import EMOTION_LABELS
from mien.validate.scores import RecognitionResult, Stimulus, StimulusScore


def _score(expression: str, probs: dict[str, float]) -> StimulusScore:
    vector = np.array([probs.get(label, 0.0) for label in EMOTION_LABELS])
    intensity = 0.0 if expression == "neutral" else 1.2
    stimulus = Stimulus(expression, "builtin", "default", "facs", "frontal-1m", intensity)
    return StimulusScore(stimulus, tuple(vector / vector.sum()), True)


def test_blends_print_quality_n_a_with_the_reason(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    scores = (
        _score("neutral", {"neutral": 0.9, "sad": 0.1}),
        _score("joy", {"happy": 0.8, "neutral": 0.2}),
        _score("evil", {"happy": 0.5, "angry": 0.3, "sad": 0.2}),
    )
    fixed = RecognitionResult(scores, "fixed", {})
    monkeypatch.setattr(validate_command, "emotions_result", lambda args, heads: fixed)
    monkeypatch.setattr("mien.validate.recognition.write_recognition", lambda result, out: [])
    assert main(["validate", "emotions", "--head", "builtin", "-o", str(tmp_path / "out")]) == 0
    printed = capsys.readouterr().out
    assert "nan" not in printed
    lines = {line.split()[0]: line for line in printed.splitlines() if line.startswith("  ")}
    assert "quality 0.80" in lines["joy"]
    assert "quality 0.90" in lines["neutral"]
    assert "quality  n/a   FACS reading" in lines["evil"]
    assert "quality n/a: none of the classifier's 7 labels is a blend" in printed
