"""Landmark AU estimates (AU9, AU10 from the deformed mesh): calibrated on the rig's own AU at E, linear below it,
and they show disgust's nose wrinkle on both expression bases where the detector cannot see it."""

from __future__ import annotations

import numpy as np
import pytest

from mien.facs.catalogue import FACE_CHANNELS
from mien.heads import load_head
from mien.rig.animate import face_to_rig
from mien.rig.deform import Deformer
from mien.rig.mapping import AUMapping
from mien.validate.landmark_aus import FROM_LANDMARKS, LandmarkAUs, merged_aus
from mien.validate.recognition import peak_face


@pytest.fixture(scope="module", params=["default", "b"])
def builtin(request: pytest.FixtureRequest) -> tuple[object, LandmarkAUs, Deformer]:
    rig = load_head("builtin", request.param, feature_points=True)
    return rig, LandmarkAUs(rig, AUMapping.default().weights_for(rig).to_weights), Deformer(rig)


def _estimate(
    head: tuple[object, LandmarkAUs, Deformer], expression: str, basis: str, intensity: float = 1.2
) -> dict[str, float]:
    rig, estimator, deformer = head
    frame, features = peak_face(expression, intensity, basis)
    weights = face_to_rig(rig, frame[None], None if features is None else features[None])[0][0]
    return estimator.estimate(deformer.deform(np.asarray(weights, np.float32)))


def test_the_rigs_own_au_reads_its_intensity(builtin: tuple[object, LandmarkAUs, Deformer]) -> None:
    rig, estimator, deformer = builtin
    mapping = AUMapping.default().weights_for(rig)  # type: ignore[arg-type]
    assert estimator.rise_at_e_mm[0, 0] > 2.0  # the nostril wings by AU9
    assert estimator.rise_at_e_mm[1, 1] > 2.0  # the upper lip by AU10
    for intensity in (1.0, 2.5, 5.0):
        frame = np.zeros(len(FACE_CHANNELS))
        frame[[FACE_CHANNELS.index("AU9L"), FACE_CHANNELS.index("AU9R")]] = intensity
        found = estimator.estimate(deformer.deform(mapping.to_weights(frame)))
        assert found["AU9"] == pytest.approx(intensity, abs=0.05)  # blendshapes are linear below E


def test_disgust_shows_its_nose_wrinkle_on_both_bases_and_anger_does_not(
    builtin: tuple[object, LandmarkAUs, Deformer],
) -> None:
    # Broekens' Table 1 disgust lifts the nostrils 8 mm (past the built-in rig's own AU9 at E, 3.5 mm); the EMFACS
    # prototype's trace of AU9 (1 x 1.2) reads about 1.2 beside its strong AU10. Anger's upper-lip raise (AU10 2.5 x
    # 1.2) lifts the nostril wings a little too, and the solve gives that to AU10, not AU9, on either basis.
    assert _estimate(builtin, "disgust", "feature_points")["AU9"] >= 4.0
    emfacs = _estimate(builtin, "disgust", "facs")
    assert emfacs["AU9"] == pytest.approx(1.2, abs=0.3) and emfacs["AU10"] >= 3.5
    for basis in ("facs", "feature_points"):
        assert _estimate(builtin, "anger", basis)["AU9"] < 0.6
        assert _estimate(builtin, "sadness", basis) == pytest.approx({"AU9": 0.0, "AU10": 0.0}, abs=0.15)


@pytest.fixture(scope="module")
def ict(ict_dir: object) -> tuple[object, LandmarkAUs, Deformer]:
    rig = load_head("ict", "a", feature_points=True)
    return rig, LandmarkAUs(rig, AUMapping.default().weights_for(rig).to_weights), Deformer(rig)


def test_on_ict_the_nose_ridge_tells_a_nose_wrinkle_from_a_lip_raise_and_a_raised_brow(
    ict: tuple[object, LandmarkAUs, Deformer],
) -> None:
    # ICT's AU9 and AU10 lift the nostril wings and the upper lip almost alike (9.2 / 10.5 mm against 5.9 / 8.2 mm
    # at E); only AU9 lifts the nose's ridge (3.1 mm against 0.15 mm), and so does AU1 (1.2 mm, a brow dragging
    # the skin up). With the ridge and AU1 in the solve, Table 1's disgust at 2.4 keeps its nose wrinkle (it read
    # 2.7 from the nostrils and the lip alone), the prototype's trace of AU9 shows (it read 0), and a sad brow is
    # no nose wrinkle.
    rig, estimator, deformer = ict
    mapping = AUMapping.default().weights_for(rig)  # type: ignore[arg-type]
    for intensity in (2.5, 5.0):
        for au in ("AU9", "AU10"):
            frame = np.zeros(len(FACE_CHANNELS))
            frame[[FACE_CHANNELS.index(au + "L"), FACE_CHANNELS.index(au + "R")]] = intensity
            found = estimator.estimate(deformer.deform(mapping.to_weights(frame)))
            assert found[au] == pytest.approx(intensity, abs=0.1)
    table1 = _estimate(ict, "disgust", "feature_points", 2.4)
    assert table1["AU9"] >= 3.5
    assert _estimate(ict, "disgust", "facs")["AU9"] >= 0.5
    for expression in ("sadness", "surprise", "fear", "anger"):
        for basis in ("facs", "feature_points"):
            # the most is Table 1's surprise at 1.2, 0.32 (0.29 before the lips' meeting lines were held; 0 at 2.4):
            # a raised brow's drag on the ridge that the solve does not wholly give to AU1
            assert _estimate(ict, expression, basis)["AU9"] < 0.35, (expression, basis)


def test_only_the_detectors_blind_aus_are_replaced() -> None:
    from mien.facs.catalogue import OPENFACS_AUS
    from mien.validate.facs_reading import facs_reading

    # what the detector sees of a disgust (lids lifted, a weak lip raise, lips parted: anger's signs, as on Table 1's
    # disgust); the nose wrinkle measured on the mesh, which the detector cannot see, makes it disgust
    aus = tuple(OPENFACS_AUS)
    detected_face = {f"AU{code}": 0.0 for code in aus} | {"AU7": 1.3, "AU10": 1.0, "AU26": 1.0}
    landmarks = {"AU9": 5.0, "AU10": 0.0}

    def reading(face: dict[str, float]) -> str | None:
        return facs_reading(np.array([face[f"AU{code}"] for code in aus]), np.zeros(len(aus)), aus)

    assert reading(detected_face) == "anger"
    assert reading(merged_aus(detected_face, landmarks)) == "disgust"
    assert "AU10" not in FROM_LANDMARKS  # the detector's AU10 stands: the landmark 0.0 above did not replace it
    detected = {"AU4": 1.5, "AU9": 0.0, "AU10": 0.4}
    assert merged_aus(detected, {"AU9": 4.0, "AU10": 5.0}) == {"AU4": 1.5, "AU9": 4.0, "AU10": 0.4}
    assert merged_aus(detected, {}) == detected  # no landmark estimate (a rig that cannot raise them): unchanged
