"""The speech vocabulary as data: visemes, their shapes, phoneme tables, rig viseme names, coarticulation."""

from __future__ import annotations

import numpy as np
import pytest
from tests.conftest import valid_avatar

from mien.errors import UnknownNameError
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.catalogue import FACE_CHANNELS
from mien.speech.arbitration import RULES, SPEECH_CHANNELS
from mien.speech.coarticulation import coarticulate
from mien.speech.phonemes import phoneme_table, viseme_of
from mien.speech.track import Segment
from mien.speech.visemes import VISEMES, VISEMES_VERSION, rig_viseme_targets, viseme_arkit, viseme_aus

AU = FACE_CHANNELS.index


def test_the_fifteen_visemes_in_the_shared_order() -> None:
    assert VISEMES == ("sil", "PP", "FF", "TH", "DD", "kk", "CH", "SS", "nn", "RR", "aa", "E", "I", "O", "U")
    assert VISEMES_VERSION == "1"


def test_shapes_in_au_terms_open_close_and_round() -> None:
    aus = viseme_aus()
    v = VISEMES.index
    assert not aus[v("sil")].any()
    assert aus[v("PP"), AU("AU25")] == aus[v("PP"), AU("AU26")] == 0.0 and aus[v("PP"), AU("AU24L")] > 0
    jaw = aus[:, AU("AU26")]
    assert jaw[v("aa")] == jaw.max() and jaw[v("aa")] > jaw[v("E")] > jaw[v("I")] > jaw[v("U")]
    assert aus[v("U"), AU("AU18")] == aus[:, AU("AU18")].max()  # the tightest rounding
    assert aus[v("O"), AU("AU22")] > 0 and aus[v("aa"), AU("AU22")] == 0
    # speech writes only channels the arbitration table gives it: brows, lids, cheeks, lip corners stay emotion's
    written = {FACE_CHANNELS[j] for j in np.flatnonzero(aus.any(axis=0))}
    assert written <= set(RULES), written - set(RULES)
    assert not written & {"AU12L", "AU12R", "AU15L", "AU6L", "AU1L", "AU10L", "AU45L"}


def test_shapes_in_arkit_terms_agree_with_the_au_shapes() -> None:
    arkit = viseme_arkit()
    jaw_arkit = arkit[:, ARKIT_NAMES.index("jawOpen")]
    jaw_au = viseme_aus()[:, AU("AU26")]
    assert np.corrcoef(jaw_arkit, jaw_au)[0, 1] > 0.9
    assert arkit[VISEMES.index("PP"), ARKIT_NAMES.index("mouthClose")] > 0
    pucker = arkit[:, ARKIT_NAMES.index("mouthPucker")]
    assert pucker[VISEMES.index("U")] == pucker.max()


def test_phoneme_tables() -> None:
    espeak = "m aI m a m a# m eI d a# m a p".split()  # "my mama made a map", issue 32
    expected = ["PP", "aa", "PP", "aa", "PP", "aa", "PP", "E", "DD", "aa", "PP", "aa", "PP"]
    assert [viseme_of(p) for p in espeak] == expected
    assert viseme_of("'aI") == "aa" and viseme_of("_:") == "sil" and viseme_of("tS") == "CH"
    assert [viseme_of(p, "arpabet") for p in ("HH", "AH0", "L", "OW1")] == ["kk", "aa", "DD", "O"]
    assert set(phoneme_table("espeak").values()) == set(VISEMES)
    with pytest.raises(UnknownNameError, match="Q!x"):
        viseme_of("Q!x", strict=True)
    assert viseme_of("y", "espeak") == "DD"  # an unlisted letter: the documented neutral consonant


def test_rig_viseme_names_of_rocketbox_and_oculus() -> None:
    names = ("AE_AA_h", "AO_a_h", "Ax_E_h", "TD_I_h", "UH_OO_h", "H_EST_h", "FV_h", "S_h", "SH_CH_h", "KG_h")
    rocketbox = [f"h_expressions.{n}" for n in names] + ["h_teeth.t_MPB_h", "jawOpen"]
    found = rig_viseme_targets(rocketbox)
    assert found["aa"] == "h_expressions.AE_AA_h" and found["FF"] == "h_expressions.FV_h"
    assert "PP" not in found  # the VALID avatars have MPB only on the teeth mesh (t_MPB_h), not MPB_h
    oculus = rig_viseme_targets([f"viseme_{v}" for v in VISEMES])
    assert list(oculus) == list(VISEMES)
    assert rig_viseme_targets(["jawOpen", "mouthClose"]) == {}


def test_the_valid_avatars_viseme_shapes_are_found() -> None:
    """The morph target names of a VALID avatar's meshes (glTF ``extras.targetNames``), read from the file."""
    from mien.fileio.glb import unpack_glb

    path = valid_avatar()
    document, _ = unpack_glb(path.read_bytes(), path.name)
    names = [n for mesh in document["meshes"] for n in (mesh.get("extras") or {}).get("targetNames", [])]
    found = rig_viseme_targets(names)
    assert {"aa", "E", "I", "O", "FF", "SS", "CH", "kk", "DD", "nn", "RR"} <= set(found), found
    assert found["aa"].endswith("AE_AA_h")


def test_coarticulation_neighbours_shape_each_other() -> None:
    """Cohen & Massaro: the same /s/ is rounder between two /u/ than between two /a/."""

    def pucker_at_s(vowel: str) -> float:
        track = coarticulate([Segment(0.0, 0.15, vowel), Segment(0.15, 0.2, "SS"), Segment(0.2, 0.35, vowel)])
        frame = track.face_clip().values[round(0.175 * track.fps)]
        return float(frame[AU("AU18")])

    assert pucker_at_s("U") > 0.5 > pucker_at_s("aa") == 0.0


def test_a_short_closure_still_closes_and_weights_sum_to_one() -> None:
    segments = [Segment(0.0, 0.1, "aa"), Segment(0.1, 0.125, "PP"), Segment(0.125, 0.25, "aa")]
    track = coarticulate(segments)
    assert np.allclose(track.weights.sum(axis=1), 1.0)
    closure = track.weights[round(0.1125 * track.fps), VISEMES.index("PP")]
    assert closure > 0.85
    assert track.weights[round(0.05 * track.fps), VISEMES.index("aa")] > 0.8
    assert track.presence[-1] < 0.05  # the tail rests


def test_speech_channels_are_the_mouth() -> None:
    names = {FACE_CHANNELS[i] for i in SPEECH_CHANNELS}
    assert {"AU25", "AU26", "AU27", "AU18", "AU22", "AU24L", "AU24R", "AU20L"} <= names
    assert not names & {"AU1L", "AU4L", "AU5L", "AU6L", "AU7L", "AU9L", "AU10L", "AU12L", "AU15L", "AU45L"}


def test_banded_coarticulation_equals_the_dominance_formula() -> None:
    """The banded sum is Cohen & Massaro's weighted mean over every segment (with the implicit rests), computed
    directly here on random timings."""
    from mien.speech.visemes import viseme_dominance

    rng = np.random.default_rng(2)
    durations = rng.uniform(0.02, 0.2, 60)
    edges = np.concatenate([[0.1], 0.1 + np.cumsum(durations)])
    segments = [
        Segment(a, b, VISEMES[v]) for a, b, v in zip(edges[:-1], edges[1:], rng.integers(0, 15, 60), strict=True)
    ]
    track = coarticulate(segments)
    alpha, theta, min_s = viseme_dominance()
    times = np.arange(track.n_frames) / track.fps
    expected = np.zeros_like(track.weights)
    rests = [(-1e9, edges[0], 0), (edges[-1], 1e9, 0)]
    for s in [(x.start_s, x.end_s, VISEMES.index(x.viseme)) for x in segments] + rests:
        widen = max(0.0, min_s[s[2]] - (s[1] - s[0])) / 2
        distance = np.maximum(0.0, np.maximum(s[0] - widen - times, times - s[1] - widen))
        expected[:, s[2]] += alpha[s[2]] * np.exp(-theta[s[2]] * distance)
    expected /= expected.sum(axis=1, keepdims=True)
    assert np.abs(track.weights - expected).max() < 1e-5
