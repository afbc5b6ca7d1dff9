"""The procedural laugh/smile generator: every type distinct and true to its recipe, seeds, scaling."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from scipy.signal import find_peaks

from mien.errors import InvalidValueError, UnknownNameError
from mien.facs.catalogue import FACE_CHANNELS
from mien.laughter.generator import MOUTH_CHANNELS, LaughResult, face_frame_at, generate
from mien.laughter.names import CONTROLLER_NAMES, LAUGH_TYPES
from mien.laughter.taxonomy import TAXONOMY
from mien.learning.dtw import dtw_distance_matrix

LAUGHS = [t for t, r in TAXONOMY.items() if r.pulses]


@functools.cache
def made(name: str, seed: int = 0) -> LaughResult:
    return generate(name, seed=seed, fps=30.0)


def peak(result: LaughResult, channel: str) -> float:
    return float(result.face_clip.channel(channel).max())


def test_shapes_and_channels() -> None:
    result = generate("laughter", duration_s=2.0, fps=60.0)
    assert result.controllers.channels == CONTROLLER_NAMES
    assert result.face_clip.channels == FACE_CHANNELS
    assert result.controllers.values.shape == (120, 16)
    assert result.face_clip.values.shape == (120, 62)
    au = [i for i, c in enumerate(FACE_CHANNELS) if c.startswith("AU")]
    assert result.face_clip.values[:, au].min() >= 0.0 and result.face_clip.values[:, au].max() <= 5.0


def test_every_type_is_distinct_from_every_other() -> None:
    """Pairwise multivariate DTW between types exceeds 0.5 and each type's own seed-to-seed spread."""
    between = dtw_distance_matrix([made(t).controllers.values for t in LAUGH_TYPES])
    off_diagonal = between[np.triu_indices(len(LAUGH_TYPES), k=1)]
    assert off_diagonal.min() > 0.5  # controller units (eps 0.2); the closest pair is about 0.9
    for i, name in enumerate(LAUGH_TYPES):  # each type's own seeds are closer than any other type
        own = float(dtw_distance_matrix([made(name, s).controllers.values for s in range(3)]).max())
        assert np.delete(between[i], i).min() > 1.2 * own, name


def test_false_smile_and_false_laughter_have_no_cheek_raise() -> None:
    for name in ("false_smile", "false_laughter"):
        assert peak(made(name), "AU6L") == 0.0 and peak(made(name), "AU6R") == 0.0
    for name in ("smiling_closed_mouth", "laughter"):
        assert peak(made(name), "AU6R") > 1.5


def test_false_smile_is_asymmetric() -> None:
    assert peak(made("false_smile"), "AU12L") < 0.8 * peak(made("false_smile"), "AU12R")


def test_sly_smile_lowers_the_brows() -> None:
    assert peak(made("sly_smile"), "AU4L") > 1.5 and peak(made("sly_smile"), "AU4R") > 1.5
    brow = made("sly_smile").controllers.channel("rightBrowRaise")
    assert brow.min() < -0.05 and brow.max() <= 1e-9  # brow-to-nose distance shrinks


def test_melancholy_raises_the_inner_brows() -> None:
    assert peak(made("melancholy_smile"), "AU1R") > 2.5
    assert made("melancholy_smile").controllers.channel("upsetSad").max() > 0.05
    assert peak(made("smiling_closed_mouth"), "AU1R") == 0.0


def test_debauched_lowers_the_upper_lids_partly() -> None:
    result = made("debauched_smile")
    assert peak(result, "AU41R") > 2.0
    assert 0.5 < peak(result, "AU43R") < 3.0
    assert result.controllers.channel("rightBlink").max() > 0.05  # + = eye closing
    closed = made("closed_eye_smile")
    assert peak(closed, "AU43L") > 4.0
    assert closed.controllers.channel("rightBlink").max() > result.controllers.channel("rightBlink").max()


def test_closed_mouth_smiles_keep_the_jaw_still() -> None:
    for name in ("smiling_closed_mouth", "melancholy_smile", "closed_eye_smile", "false_smile"):
        result = made(name)
        assert peak(result, "AU26") == 0.0 and peak(result, "AU27") == 0.0
        assert np.abs(result.controllers.channel("jaw")).max() < 1e-3, name
    assert made("stifled_smile").controllers.channel("jaw").max() <= 1e-9  # pressed lips: the mouth never opens


@pytest.mark.parametrize("name", LAUGHS)
def test_laughs_pulse_the_jaw_at_a_few_hertz(name: str) -> None:
    result = generate(name, duration_s=3.0, fps=60.0, seed=3)
    jaw = result.controllers.channel("jaw")
    peaks, _ = find_peaks(jaw, prominence=0.1 * float(np.ptp(jaw)))
    active = result.face_clip.channel("AU26") > 0.3 * peak(result, "AU26")
    active_s = float(active.sum()) / result.face_clip.fps
    rate = len(peaks) / active_s
    assert 2.5 < rate < 6.5, (name, len(peaks), active_s)
    assert len(result.pulse_times_s) >= 6
    assert peak(result, "AU26") > 2.0


def test_uproarious_laughter_opens_widest_and_throws_the_head_back() -> None:
    up, plain = made("uproarious_laughter"), made("laughter")
    assert np.abs(up.controllers.channel("jaw")).max() > 1.5 * np.abs(plain.controllers.channel("jaw")).max()
    assert peak(up, "head_pitch_deg") > 8.0 > peak(plain, "head_pitch_deg")
    assert peak(up, "AU27") > 1.0


def test_smiles_have_no_pulses() -> None:
    for name in LAUGH_TYPES:
        assert (len(made(name).pulse_times_s) > 0) == TAXONOMY[name].pulses


def test_same_seed_identical_different_seeds_differ_but_stay_close() -> None:
    first, again, other = generate("laughter", seed=7), generate("laughter", seed=7), generate("laughter", seed=8)
    assert first == again
    assert first != other
    assert not np.array_equal(first.pulse_times_s, other.pulse_times_s)
    assert abs(first.duration_s - other.duration_s) < 0.5
    assert abs(peak(first, "AU12R") - peak(other, "AU12R")) < 0.6
    assert abs(len(first.pulse_times_s) - len(other.pulse_times_s)) <= 3


def test_intensity_scales_the_curves() -> None:
    one, two = generate("smiling_closed_mouth", 1.0, seed=2), generate("smiling_closed_mouth", 2.0, seed=2)
    np.testing.assert_allclose(two.controllers.values, 2.0 * one.controllers.values)
    assert peak(two, "AU12R") == pytest.approx(min(5.0, 2 * peak(one, "AU12R")), rel=1e-6)
    zero = generate("laughter", 0.0)
    assert np.abs(zero.controllers.values).max() == 0.0 and zero.face_clip.values.max() == 0.0


def test_duration_stretches_the_curve_but_not_the_pulse_rate() -> None:
    short, long = generate("laughter", duration_s=2.0, seed=1), generate("laughter", duration_s=5.0, seed=1)
    assert short.face_clip.n_frames == 120 and long.face_clip.n_frames == 300
    short_rate = len(short.pulse_times_s) / short.duration_s
    long_rate = len(long.pulse_times_s) / long.duration_s
    assert long_rate == pytest.approx(short_rate, rel=0.35)
    smile = generate("smiling_open_mouthed", duration_s=6.0)
    apex = np.argmax(smile.face_clip.channel("AU12R")) / smile.face_clip.fps
    assert 0.4 < apex < 5.0


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"intensity": 5.5}, "intensity"),
        ({"intensity": -0.1}, "intensity"),
        ({"intensity": float("nan")}, "intensity"),
        ({"duration_s": 0.0}, "duration_s"),
        ({"duration_s": -1.0}, "duration_s"),
        ({"fps": 0.0}, "fps"),
    ],
)
def test_bad_values_are_rejected(kwargs: dict[str, float], field: str) -> None:
    with pytest.raises(InvalidValueError) as info:
        generate("laughter", **kwargs)  # type: ignore[arg-type]
    assert info.value.field == field


def test_unknown_type_lists_the_13() -> None:
    with pytest.raises(UnknownNameError) as info:
        generate("chuckle")
    assert info.value.known == LAUGH_TYPES


def test_face_frame_at_interpolates_and_is_none_outside() -> None:
    result = generate("laughter", duration_s=1.0, fps=10.0)
    clip = result.face_clip
    assert face_frame_at(result, -0.01) is None
    assert face_frame_at(result, 1.01) is None
    np.testing.assert_array_equal(face_frame_at(result, 0.3), clip.values[3])
    np.testing.assert_allclose(face_frame_at(result, 0.35), 0.5 * (clip.values[3] + clip.values[4]))
    np.testing.assert_array_equal(face_frame_at(result, 1.0), clip.values[-1])
    assert face_frame_at(result, 0.5).shape == (62,)


def test_mouth_channels_cover_the_jaw_and_lip_corners() -> None:
    assert {"AU12L", "AU12R", "AU25", "AU26", "AU27", "AU24L"} <= set(MOUTH_CHANNELS)
    assert not {"AU6L", "AU1L", "AU43L", "head_pitch_deg"} & set(MOUTH_CHANNELS)


def test_generate_from_a_given_library() -> None:
    from mien.facs.clip import Clip
    from mien.laughter.builtin_library import default_library
    from mien.laughter.library import LaughLibrary

    curve = default_library().curve("laughter")
    doubled = LaughLibrary(
        {"laughter": Clip(curve.values * 2, curve.fps, CONTROLLER_NAMES)}, default_library().metadata
    )
    mine, builtin = generate("laughter", library=doubled), generate("laughter")
    np.testing.assert_allclose(mine.controllers.values, 2 * builtin.controllers.values, atol=1e-12)
    np.testing.assert_allclose(mine.face_clip.values, builtin.face_clip.values, atol=1e-9)  # AUs are normalised
    assert generate("sly_smile", library=doubled) == generate("sly_smile")  # missing type: built-in


def test_cli_laugh(tmp_path: object, capsys: pytest.CaptureFixture[str]) -> None:
    from pathlib import Path

    from mien.cli import main

    assert main(["laugh", "--list"]) == 0
    listing = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in listing] == list(LAUGH_TYPES)
    assert main(["laugh", "sly_smile", "--seed", "2"]) == 0
    assert "AU4R" in capsys.readouterr().out
    out = Path(str(tmp_path)) / "sly.json"
    assert main(["laugh", "sly_smile", "--duration", "2", "--fps", "30", "-o", str(out)]) == 0
    assert "60 frames at 30 fps" in capsys.readouterr().out
    assert main(["laugh", "giggle"]) == 2
    assert "unknown laugh type 'giggle'" in capsys.readouterr().err
    assert main(["laugh", "laughter", "--duration", "0"]) == 2
