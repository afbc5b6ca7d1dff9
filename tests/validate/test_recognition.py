"""Emotion recognition of rendered faces: the metrics on fixed numbers, and a quick real validation that fails CI
when a change breaks the faces (one head, the five clearest emotions, frontal, the study's intensities)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError, UnknownNameError
from mien.validate.detector import EMOTION_LABELS
from mien.validate.emotion_classifier import FRAMINGS, face_box
from mien.validate.judge import JUDGE_CROPS, crop_names, framing_of
from mien.validate.recognition import judge_crops_for, peak_face, run_recognition, study_stimuli
from mien.validate.scores import RecognitionResult, Stimulus, StimulusScore
from mien.validate.targets import check_targets

FIVE = ("joy", "sadness", "anger", "surprise", "fear")


def _score(expression: str, probs: dict[str, float], view: str = "frontal-1m") -> StimulusScore:
    vector = np.array([probs.get(label, 0.0) for label in EMOTION_LABELS])
    vector = vector / vector.sum()
    return StimulusScore(Stimulus(expression, "builtin", "default", "facs", view, 1.2), tuple(vector), True)


def test_rate_quality_and_confusion_on_fixed_numbers() -> None:
    scores = (
        _score("joy", {"happy": 0.8, "neutral": 0.2}),
        _score("joy", {"happy": 0.4, "surprise": 0.6}),
        _score("anger", {"angry": 0.5, "disgust": 0.3, "neutral": 0.2}),
        _score("evil", {"happy": 0.5, "angry": 0.3, "sad": 0.2}),  # blend: top two = joy's and anger's labels
        _score("furious", {"angry": 0.5, "fear": 0.3, "surprise": 0.2}),  # top label a component, top two not
        _score("frustrated", {"fear": 0.5, "angry": 0.3, "sad": 0.2}),  # top label fear: a miss
    )
    result = RecognitionResult(scores, "fixed", {})
    assert result.rate(expression="joy") == 0.5
    assert result.rate(expression="evil") == 1.0 and result.rate(expression="furious") == 1.0
    assert result.rate(expression="frustrated") == 0.0
    assert result.both_rate(expression="evil") == 1.0 and result.both_rate(expression="furious") == 0.0
    assert np.isnan(result.both_rate(expression="joy"))  # not a blend
    # Broekens' quality target / (mean over labels x labels) = the target's share of the probability mass
    assert result.quality("joy") == pytest.approx((0.8 + 0.4) / 2)
    assert result.quality("anger") == pytest.approx(0.5)
    assert np.isnan(result.quality("evil"))
    rows, matrix = result.confusion()
    assert rows == ["joy", "anger", "furious", "frustrated", "evil"]
    assert matrix[0, EMOTION_LABELS.index("happy")] == 1 and matrix[0, EMOTION_LABELS.index("surprise")] == 1
    assert result.to_json()["recognition"]["joy"] == 0.5


def _judged(
    expression: str, landmarks: dict[str, float], fer: dict[str, float], view: str = "frontal-1m"
) -> StimulusScore:
    """A score whose readings (as :mod:`mien.validate.judge` names them) say ``landmarks`` under the landmark crops
    and ``fer`` under fer's, at both render sizes; the verdict is their mean, as run_recognition makes it."""
    readings = {}
    for name in crop_names(512):
        probs = landmarks if framing_of(name) == "landmarks" else fer
        vector = np.array([probs.get(label, 0.0) for label in EMOTION_LABELS])
        readings[name] = tuple(vector / vector.sum())
    mean = tuple(np.mean(list(readings.values()), axis=0))
    return StimulusScore(Stimulus(expression, "ict", "a", "facs", view, 1.2), mean, True, crops=readings)


def test_a_face_that_reads_under_one_framing_only_does_not_pass(tmp_path: Path) -> None:
    """The averaging at work: joy that the landmark crops read as happy and fer's crops as neutral is a miss, though
    the landmark crops alone would pass it; the spread across crops shows how far one crop would have moved it."""
    one_framing = [_judged("joy", {"happy": 0.55, "neutral": 0.45}, {"neutral": 0.8, "happy": 0.2}) for _ in range(8)]
    both = [_judged("sadness", {"sad": 0.6, "neutral": 0.4}, {"sad": 0.55, "fear": 0.45}) for _ in range(8)]
    result = RecognitionResult((*one_framing, *both), "fixed", {}, framing="averaged")
    assert result.framed_rate("landmarks", expression="joy") == 1.0 and result.framed_rate("fer", expression="joy") == 0
    assert result.rate(expression="joy") == 0.0 and result.rate(expression="sadness") == 1.0
    assert result.spread(expression="joy") == (0.0, 1.0) and result.spread(expression="sadness") == (1.0, 1.0)
    checks = {c.target.name: c for c in check_targets(result) if c.head == "ict:a"}
    assert checks["frontal joy"].met is False and checks["frontal joy"].spread == (0.0, 1.0)
    assert checks["frontal sadness"].met is True
    assert len(result.readings) == 12 and result.framings == ("averaged", "fer", "landmarks")
    data = result.to_json()
    assert data["framing"] == "averaged" and data["recognition_by_framing"]["landmarks"]["joy"] == 1.0
    assert data["recognition_spread"]["joy"] == [0.0, 1.0]
    assert len(data["stimuli"][0]["crops"]) == 12
    # the report shows the spread beside each figure: joy 0% by the verdict, 0-100% as one crop alone would judge
    from mien.validate.report import _emotions_section

    page = _emotions_section(result, tmp_path)
    assert "<td><b>joy</b></td><td>0% <small>(0%-100%)</small></td>" in page and "judged <b>averaged</b>" in page


def test_judge_crops_cover_both_framings_jittered() -> None:
    assert {crop.framing for crop in JUDGE_CROPS} == set(FRAMINGS) and len(JUDGE_CROPS) == 6
    landmarks = np.array([[200.0 + 10 * (i % 10), 180.0 + 12 * (i // 10)] for i in range(68)])
    boxes = {crop.name: face_box(landmarks, crop.framing, crop.jitter) for crop in JUDGE_CROPS}
    plain, wide = boxes["landmarks"], boxes["landmarks up-left wide"]
    assert wide[2] > plain[2] and wide[0] < plain[0] and wide[1] < plain[1]
    assert boxes["fer"][1] < plain[1]  # fer's framing starts higher, in the forehead
    with pytest.raises(UnknownNameError, match="judge"):
        judge_crops_for("haar")
    assert {crop.framing for crop in judge_crops_for("fer")} == {"fer"}


def test_stimuli_cover_the_study_conditions_and_refuse_unknowns() -> None:
    stimuli = study_stimuli([("builtin", "default")], ("facs",), ("frontal-1m", "lateral-3m"), (1.2, 2.4))
    assert len(stimuli) == 2 * (1 + 10 * 2)
    with pytest.raises(UnknownNameError, match="view"):
        study_stimuli([("builtin", "default")], views=("sideways",))
    with pytest.raises(UnknownNameError, match="expression"):
        study_stimuli([("builtin", "default")], expressions=("bored",))
    with pytest.raises(InvalidValueError, match="intensity"):
        study_stimuli([("builtin", "default")], intensities=(0.0,))


def test_peak_face_keeps_prototype_proportions_at_the_strong_condition() -> None:
    weak, _ = peak_face("sadness", 1.2, "facs")
    strong, _ = peak_face("sadness", 2.4, "facs")
    assert strong.max() <= 5.0 and strong.max() > weak.max()
    active = weak > 0
    np.testing.assert_allclose(strong[active] / strong.max(), weak[active] / weak.max(), atol=1e-9)
    _, features = peak_face("joy", 2.4, "feature_points")
    assert features is not None and np.abs(features).max() > 0


def _quick(
    heads: list[tuple[str, str]], bases: tuple[str, ...], views: tuple[str, ...], expressions: tuple[str, ...]
) -> RecognitionResult:
    """The stimuli at intensities 1.2 and 2.4, rendered at 384 px and judged (skips without the render extras)."""
    for module in ("moderngl", "ai_edge_litert", "mediapipe"):
        pytest.importorskip(module)
    stimuli = study_stimuli(heads, bases, views, (1.2, 2.4), expressions)
    return run_recognition(stimuli, size=(384, 384), progress=False)


@pytest.fixture(scope="module")
def ict_frontal(ict_dir, landmarker_path, emotion_model_path) -> RecognitionResult:
    return _quick([("ict", "a")], ("facs",), ("frontal-1m", "frontal-3m"), (*FIVE, "disgust"))


def test_quick_validation_five_emotions_frontal(ict_frontal: RecognitionResult) -> None:
    # the averaged judge (docs/VALIDATION.md, "What a verdict is"); targets: 90% of renders for each of the five and
    # neutral; measured 100% on ICT a's FACS basis (its joy at 1.2 read neutral, 50%, before the mapping's v3)
    assert ict_frontal.framing == "averaged"
    assert ict_frontal.rate(expression=FIVE) >= 0.85
    for name in FIVE:
        assert ict_frontal.rate(expression=name) >= 0.75, name
    assert ict_frontal.rate(expression="neutral") == 1.0
    assert all(score.face_found for score in ict_frontal.scores)
    # every verdict is the mean of the averaged judge's twelve readings (two sizes x six crops, both framings)
    for score in ict_frontal.scores:
        assert len(score.crops) == 12
        np.testing.assert_allclose(score.emotions, np.mean(list(score.crops.values()), axis=0), atol=1e-6)
    assert ict_frontal.framed_rate("fer", expression="neutral") == 1.0


@pytest.fixture(scope="module")
def builtin_feature_points(landmarker_path, emotion_model_path) -> RecognitionResult:
    return _quick([("builtin", "default")], ("feature_points",), ("frontal-1m",), FIVE)


def test_quick_validation_feature_point_basis(builtin_feature_points: RecognitionResult) -> None:
    # Table 1 on the built-in head, frontal at 1 m, 384 px: measured 9/10 (docs/VALIDATION.md, fourth pass; 6/10 before
    # the jaw carried the lower teeth and the lower lip curved into a smile); the built-in head's bar is 80%
    assert builtin_feature_points.rate(expression=FIVE) >= 0.7
    assert builtin_feature_points.rate(expression="joy") >= 0.5


@pytest.fixture(scope="module")
def ict_feature_points(ict_dir, landmarker_path, emotion_model_path) -> RecognitionResult:
    return _quick([("ict", "b")], ("feature_points",), ("frontal-1m",), FIVE)


def test_quick_validation_feature_point_basis_on_ict(ict_feature_points: RecognitionResult) -> None:
    # Table 1 on ICT identity b, frontal at 1 m: 7/10 before the skin-detail correctives (the smile and anger at 1.2
    # read neutral: smooth skin, no fold), 10/10 with them (docs/VALIDATION.md, seventh pass); 9/10 under the
    # averaged judge at 512 px (anger at 2.4 reads surprise); the target is 90%
    assert ict_feature_points.rate(expression=FIVE) >= 0.8
    assert ict_feature_points.rate(expression="joy") == 1.0


@pytest.fixture(scope="module")
def ict_oblique(ict_dir, landmarker_path, emotion_model_path) -> RecognitionResult:
    return _quick([("ict", "b")], ("facs",), ("oblique-1m",), FIVE)


def test_quick_validation_at_45_degrees_on_ict(ict_oblique: RecognitionResult) -> None:
    # ICT identity b at 45 degrees: 5/10 while ICT's brow lowerer moved the brow 3.4 mm (anger and fear read happy;
    # 5/10 at 384 px too),
    # 10/10 at 512 px and 9/10 at 384 px with it doubled (ICT_TARGET_GAINS; docs/VALIDATION.md, eighth pass); the
    # averaged judge at 512 px: 9/10 (anger at 1.2 reads surprise under fer's crops); the target is 75%
    assert ict_oblique.rate(expression=FIVE) >= 0.7
    assert ict_oblique.rate(expression="anger") >= 0.5


@pytest.fixture(scope="module")
def builtin_surprise(landmarker_path, emotion_model_path) -> RecognitionResult:
    heads = [("builtin", "default"), ("builtin", "b")]
    return _quick(heads, ("facs",), ("frontal-1m", "frontal-3m"), ("surprise",))


def test_quick_validation_builtin_surprise(builtin_surprise: RecognitionResult) -> None:
    # the built-in head's surprise: 3/8 at 512 px and 0/8 at 384 px while its jaw opened the lips as a wide slot
    # (read as fear), 7/8 at both with the bowl-shaped opening (mien.rig.head_targets; docs/VALIDATION.md, eighth pass)
    assert builtin_surprise.rate(expression="surprise") >= 0.75


def test_disgust_shows_its_facs_signs(ict_frontal: RecognitionResult) -> None:
    neutral = ict_frontal.subset(expression="neutral")
    disgust = ict_frontal.subset(expression="disgust")
    lip_neutral = np.mean([s.nose_lip_mm for s in neutral])
    for score in disgust:
        # upper-lip raiser seen by the detector, and the nose-to-lip distance shortened on the mesh
        assert score.aus["AU10"] > max(s.aus["AU10"] for s in neutral) + 0.5
        assert score.nose_lip_mm < lip_neutral - 1.0
        # the landmark estimates agree: the upper-lip raise, and the prototype's trace of AU9 (1 x 1.2), which the
        # nose's ridge tells from AU10's cross-talk on ICT (it read 0 from the nostrils and the lip alone)
        assert score.landmark_aus["AU10"] > 2.0
        assert score.landmark_aus["AU9"] > 0.5
    assert all(s.landmark_aus == {"AU9": 0.0, "AU10": 0.0} for s in neutral)
    for score in ict_frontal.subset(expression="anger"):
        assert score.landmark_aus["AU9"] < 0.6
    # what the CLI and the report print: disgust's signs on the mesh next to anger's
    signs = ict_frontal.disgust_signs()
    assert set(signs) == {"facs"}
    assert signs["facs"]["disgust"]["AU9"] > signs["facs"]["anger"]["AU9"] + 0.5
    assert signs["facs"]["disgust"]["AU10"] > signs["facs"]["anger"]["AU10"]


def test_facs_reading_matches_prototypes() -> None:
    from mien.facs.catalogue import OPENFACS_AUS
    from mien.facs.prototypes import EMFACS_PROTOTYPES
    from mien.validate.facs_reading import facs_reading

    aus = tuple(OPENFACS_AUS)
    neutral = np.full(len(aus), 0.3)
    for name, prototype in EMFACS_PROTOTYPES.items():
        face = neutral + np.array([prototype.get(f"AU{code}", 0.0) for code in aus]) * 0.8
        assert facs_reading(face, neutral, aus) == name
    assert facs_reading(neutral, neutral, aus) is None  # nothing moved: no reading
    anger = np.array([EMFACS_PROTOTYPES["anger"].get(f"AU{code}", 0.0) for code in aus])
    assert facs_reading(anger + 0.4 * np.random.default_rng(0).random(len(aus)), np.zeros(len(aus)), aus) == "anger"


def test_facs_reading_takes_the_nose_wrinkle_led_disgust_for_disgust() -> None:
    from mien.facs.catalogue import OPENFACS_AUS
    from mien.validate.facs_reading import facs_reading

    # what the detector and the mesh's landmarks saw of Table 1's disgust at 1.2 (feature-point basis, mean of
    # the sixteen frontal renders): the lids and brows of anger, the lips parted, and the nose wrinkled hard
    aus = tuple(OPENFACS_AUS)
    seen = {"AU4": 0.7, "AU7": 0.8, "AU9": 4.0, "AU10": 0.7, "AU25": 1.6, "AU26": 1.6}
    face = np.array([seen.get(f"AU{code}", 0.0) for code in aus])
    assert facs_reading(face, np.zeros(len(aus)), aus) == "disgust"
    no_wrinkle = np.array([0.0 if code == 9 else seen.get(f"AU{code}", 0.0) for code in aus])
    assert facs_reading(no_wrinkle, np.zeros(len(aus)), aus) == "anger"  # the same face without AU9 is anger


def test_disgust_is_not_read_as_anger_by_its_facs_signs(ict_frontal: RecognitionResult) -> None:
    # the classifier answers "disgust" for almost nothing; the FACS reading tells disgust from anger
    assert ict_frontal.facs_rate(expression="disgust") >= 0.75
    assert ict_frontal.facs_rate("anger", expression="disgust") == 0.0
    assert ict_frontal.facs_rate(expression="anger") >= 0.75


def test_a_user_blend_is_judged_by_its_own_components() -> None:
    from mien.affect.emotions import define_blend, remove_blend

    define_blend("wistful", {"joy": 1.0, "sadness": 1.0})
    try:
        hit = _score("wistful", {"happy": 0.5, "sad": 0.4, "neutral": 0.1})
        half = _score("wistful", {"happy": 0.5, "angry": 0.4, "neutral": 0.1})
        miss = _score("wistful", {"angry": 0.5, "happy": 0.4, "neutral": 0.1})
        assert (hit.correct(), half.correct(), miss.correct()) == (True, True, False)
        assert (hit.both_components(), half.both_components()) == (True, False)
        assert RecognitionResult((hit, half, miss), "fixed", {}).rate(expression="wistful") == pytest.approx(2 / 3)
    finally:
        remove_blend("wistful")
    assert hit.correct() is None  # no longer a name the classifier can be asked about
