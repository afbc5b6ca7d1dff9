"""Study report: one self-contained page with the tables, embedded figures, provenance; the machine judgement
of real rendered stimuli beside the people's, or the reason it was not run."""

from __future__ import annotations

import base64
import io
import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from mien.errors import InvalidValueError
from mien.study.analysis import analyze_csv
from mien.study.report import write_report

DATA = Path(__file__).parent / "data"

DESIGN = """
[study]
name = "machine"
protocol = "broekens"
[stimuli]
expressions = ["joy", "surprise"]
heads = ["builtin"]
views = ["frontal"]
intensities = [2.4]
duration_s = 1.4
fps = 10
size = 192
[design]
within = ["view"]
"""


def _images(page: str) -> list[Image.Image]:
    return [
        Image.open(io.BytesIO(base64.b64decode(data)))
        for data in re.findall(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', page)
    ]


def test_broekens_report_holds_tables_figures_and_provenance(tmp_path: Path) -> None:
    analysis = analyze_csv(DATA / "broekens_small.csv")
    path = write_report(analysis, tmp_path / "report")
    assert path == tmp_path / "report" / "report.html"
    page = path.read_text(encoding="utf-8")
    assert page.startswith("<!DOCTYPE html>") and page.endswith("</html>")
    assert "http://" not in page and "https://" not in page  # self-contained: nothing fetched
    # the quality table: hand-computed values (test_analysis) and the paper's beside
    assert "<b>0.731</b>" in page and "<b>0.773</b>" in page and "0.806" in page and "0.848" in page
    assert "view = frontal" in page and "0.733" in page  # per condition
    assert "Rating profiles" in page and "label:frustrated" in page
    assert "<b>3</b> participants, 132 answers" in page
    assert analysis.source_sha256 in page and "pingouin" in page and "statsmodels" in page
    assert "dropped from an ANOVA (a cell without answers): <b>0</b>" in page
    assert "Not run: no stimuli folder was given." in page
    assert "naturalness" in page and "target_intensity" in page and "pingouin.rm_anova" in page
    images = _images(page)
    assert len(images) == 6  # quality, profile, naturalness, three interaction plots
    assert all(image.format == "PNG" and image.width > 300 and image.height > 150 for image in images)
    # figures stay beside the page; no partial file left
    assert sorted(p.name for p in (tmp_path / "report" / "figures").iterdir()) == [
        "interaction_mean_intensity.png", "interaction_naturalness.png", "interaction_target_intensity.png",
        "naturalness.png", "profile.png", "quality.png",
    ]  # fmt: skip
    assert not list((tmp_path / "report").glob(".*partial*"))


def test_report_names_dropped_participants(tmp_path: Path) -> None:
    import pandas as pd

    from mien.study.analysis import analyze

    answers = pd.read_csv(DATA / "broekens_anova.csv", dtype=str, keep_default_na=False)
    gone = (answers["participant"] == "P05") & (answers["view"] == "lateral")
    page = write_report(analyze(answers[~gone]), tmp_path / "r.html").read_text(encoding="utf-8")
    assert "dropped from an ANOVA (a cell without answers): <b>1</b> (P05)" in page
    assert "balanced_rm_anova" in page and "without an answer in every cell dropped: P05" in page


def test_mascaro_report(tmp_path: Path) -> None:
    analysis = analyze_csv(DATA / "mascaro_small.csv")
    path = write_report(analysis, tmp_path / "laughs.html")
    page = path.read_text(encoding="utf-8")
    assert "Mascaró questions" in page and "sly_smile" in page and "represents_description" in page
    row = analysis.mascaro.set_index(["expression", "question"]).loc[("sly_smile", "feels_right")]
    assert f"[{row['ci_low']:.2f}, {row['ci_high']:.2f}]" in page
    assert len(_images(page)) == 3  # bars + an interaction plot per question
    assert (tmp_path / "laughs_figures" / "mascaro.png").is_file()


def test_machine_judgement_of_rendered_stimuli(tmp_path: Path, landmarker_path: Path, emotion_model_path: Path) -> None:
    from mien.study.design import load_design
    from mien.study.machine import judge_stimuli
    from mien.study.stimuli import make_stimuli
    from mien.validate.detector import EMOTION_LABELS

    (tmp_path / "design.toml").write_text(DESIGN)
    make_stimuli(load_design(tmp_path / "design.toml"), progress=False)
    folder = tmp_path / "stimuli"
    judged = judge_stimuli(folder, landmarker=landmarker_path, emotion_model=emotion_model_path)
    assert judged.stimulus_ids == ("s001", "s002")
    assert judged.models["face_landmarker"] == str(landmarker_path)
    table = judged.table().set_index("expression")
    assert list(table.index) == ["joy", "surprise"]
    assert (table["faces_found"] == 1).all()
    for score, peak_s in zip(judged.result.scores, judged.peak_s, strict=True):
        assert np.isclose(sum(score.emotions), 1, atol=1e-3)
        assert 0.2 < peak_s < 1.4  # the expression's peak, not the neutral start
    joy = judged.result.scores[0]
    assert table.loc["joy", "top_label"] == joy.top and table.loc["joy", "recognised"] == float(joy.correct())
    assert table.loc["joy", "quality"] == pytest.approx(joy.emotions[EMOTION_LABELS.index("happy")])
    assert joy.top == "happy"  # a smiling face at intensity 2.4 reads happy to the classifier
    # the page puts it beside the people's table
    analysis = analyze_csv(DATA / "broekens_small.csv")
    page = write_report(analysis, tmp_path / "out", machine=judged).read_text(encoding="utf-8")
    assert "2 videos of" in page and "mediapipe-face-landmarker+fer-emotion-tflite" in page
    assert "human quality (this study)" in page and str(landmarker_path) in page
    # a changed video: a clear error naming it, and the report says why the machine did not run
    (folder / "s002.mp4").write_bytes(b"not a video")
    with pytest.raises(InvalidValueError, match=r"s002\.mp4"):
        judge_stimuli(folder, landmarker=landmarker_path, emotion_model=emotion_model_path)
    page = write_report(analysis, tmp_path / "out2", stimuli=folder, landmarker=landmarker_path).read_text()
    assert "Not run: stimulus file" in page and "s002.mp4" in page


def test_machine_skipped_with_a_reason(tmp_path: Path) -> None:
    analysis = analyze_csv(DATA / "broekens_small.csv")
    page = write_report(analysis, tmp_path / "a", stimuli=tmp_path / "nowhere").read_text()
    assert "Not run: no manifest.json in" in page and "mien study stimuli" in page
    (tmp_path / "stimuli").mkdir()
    (tmp_path / "stimuli" / "manifest.json").write_text('{"study": "x", "protocol": "broekens", "stimuli": []}')
    missing = tmp_path / "no_model.task"
    page = write_report(analysis, tmp_path / "b", stimuli=tmp_path / "stimuli", landmarker=missing).read_text()
    assert "Not run: face_landmarker not found at" in page and "no_model.task" in page
