import numpy as np
import pytest

from mien import Clip, InvalidValueError, UnknownNameError, parse_au
from mien.facs.catalogue import ACTION_UNITS, FACE_CHANNELS, OPENFACS_AUS, action_unit, au_channels
from mien.facs.intensity import check_intensity, intensity_letter


def test_openfacs_aus_are_the_papers_eighteen():
    assert OPENFACS_AUS == (1, 2, 4, 5, 6, 7, 9, 10, 12, 14, 15, 17, 20, 23, 25, 26, 28, 45)


def test_catalogue_names_and_muscles():
    assert action_unit(12).name == "Lip Corner Puller"
    assert "Zygomaticus major" in action_unit(12).muscles
    assert action_unit(1).name == "Inner Brow Raiser"
    assert action_unit(43).name == "Eyes Closed"
    assert action_unit(6).lateral and not action_unit(26).lateral
    assert action_unit(51).kind == "head" and action_unit(61).kind == "eye"
    assert all(au.muscles for au in ACTION_UNITS.values() if au.kind == "face" and au.code not in (19,))


def test_face_channels_layout():
    assert FACE_CHANNELS[-5:] == ("head_yaw_deg", "head_pitch_deg", "head_roll_deg", "gaze_yaw_deg", "gaze_pitch_deg")
    assert "AU12L" in FACE_CHANNELS and "AU12R" in FACE_CHANNELS and "AU12" not in FACE_CHANNELS
    assert "AU26" in FACE_CHANNELS
    assert [FACE_CHANNELS[i] for i in au_channels(12, "R")] == ["AU12R"]
    assert [FACE_CHANNELS[i] for i in au_channels(51)] == ["head_yaw_deg"]


@pytest.mark.parametrize(
    ("text", "code", "side", "intensity"),
    [
        ("AU12", 12, None, None),
        ("12C", 12, None, 3.0),
        ("AU12C", 12, None, 3.0),
        ("AU12L", 12, "L", None),
        ("L12", 12, "L", None),
        ("R12B", 12, "R", 2.0),
        ("au6e", 6, None, 5.0),
        ("AU12LC", 12, "L", 3.0),
        ("AU12CR", 12, "R", 3.0),
    ],
)
def test_parse_au_spellings(text, code, side, intensity):
    spec = parse_au(text)
    assert (spec.code, spec.side, spec.intensity) == (code, side, intensity)


@pytest.mark.parametrize("text", ["AU99", "AU12F", "smile", "", "L12R", "AU26L"])
def test_parse_au_rejects_unknown(text):
    with pytest.raises(UnknownNameError) as info:
        parse_au(text)
    assert text in str(info.value) or "AU99" in str(info.value)


@pytest.mark.parametrize("value", [-0.1, 5.01, float("nan"), float("inf"), "high", None])
def test_intensity_out_of_range_names_field_and_value(value):
    with pytest.raises(InvalidValueError) as info:
        check_intensity(value, "AU12")
    assert info.value.field == "AU12"
    assert "AU12" in str(info.value)


def test_intensity_letters():
    assert [intensity_letter(v) for v in (0.2, 1.0, 2.4, 3.0, 4.6, 5.0)] == ["", "A", "B", "C", "E", "E"]


def test_clip_round_trip_dict_and_json():
    values = np.random.default_rng(0).random((5, 3))
    clip = Clip(values, 30.0, ("a", "b", "c"))
    assert Clip.from_dict(clip.to_dict()) == clip
    assert Clip.from_json(clip.to_json()) == clip
    assert clip.duration_s == pytest.approx(5 / 30)
    assert clip.channel("b").tolist() == values[:, 1].tolist()
    assert clip.select(["c", "a"]).channels == ("c", "a")


def test_clip_rejects_bad_values():
    with pytest.raises(InvalidValueError, match="values\\[1, b\\]"):
        Clip(np.array([[0.0, 0.0], [0.0, np.nan]]), 30.0, ("a", "b"))
    with pytest.raises(InvalidValueError, match="fps"):
        Clip(np.zeros((2, 1)), -1.0, ("a",))
    with pytest.raises(InvalidValueError):
        Clip(np.zeros((2, 2)), 30.0, ("a",))
    with pytest.raises(InvalidValueError, match="clip JSON"):
        Clip.from_json("{not json")
    with pytest.raises(UnknownNameError):
        Clip(np.zeros((2, 1)), 30.0, ("a",)).channel("zz")
