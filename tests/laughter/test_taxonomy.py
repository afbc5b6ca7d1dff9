"""The laugh/smile taxonomy as data: 13 types, Duchenne marker, brows and lids after Faigin."""

from __future__ import annotations

import pytest

from mien.errors import UnknownNameError
from mien.laughter.names import LAUGH_TYPES
from mien.laughter.taxonomy import TAXONOMY, recipe

GENUINE = [t for t in LAUGH_TYPES if not t.startswith("false_")]


def test_all_13_types_in_order() -> None:
    assert tuple(TAXONOMY) == LAUGH_TYPES
    assert len(TAXONOMY) == 13


@pytest.mark.parametrize("name", GENUINE)
def test_genuine_types_have_the_duchenne_marker(name: str) -> None:
    r = recipe(name)
    assert r.duchenne
    assert r.au_intensity(6) > 0
    assert r.au_intensity(12) > 0


@pytest.mark.parametrize("name", ["false_smile", "false_laughter"])
def test_false_types_lack_au6_and_are_abrupt_and_asymmetric(name: str) -> None:
    r = recipe(name)
    assert not r.duchenne
    assert r.au_intensity(6) == 0.0
    assert r.au_intensity(12) > 0
    assert r.voluntary
    assert r.asymmetry > 0
    assert r.onset_s <= 0.25 and r.offset_s <= 0.3  # abrupt (Ekman & Friesen 1982)


def test_brows_and_lids_of_the_combined_smiles() -> None:
    melancholy, eager, ingratiating = recipe("melancholy_smile"), recipe("eager_laugh"), recipe("ingratiating_smile")
    assert melancholy.au_intensity(1) > 0 and melancholy.au_intensity(4) > 0  # sadness brows
    assert eager.au_intensity(1) > 0 and eager.au_intensity(2) > 0 and eager.au_intensity(5) > 0  # surprise
    assert all(ingratiating.au_intensity(code) > 0 for code in (1, 2, 4))  # fear brows
    assert recipe("sly_smile").au_intensity(4) >= 2.0  # anger brows lowered
    debauched = recipe("debauched_smile")
    assert debauched.au_intensity(41) > 0 and 0 < debauched.au_intensity(43) < 3  # lids partly cover the pupils
    assert recipe("closed_eye_smile").au_intensity(43) >= 4.0
    stifled = recipe("stifled_smile")
    assert stifled.au_intensity(24) > 0 and stifled.au_intensity(17) > 0 and stifled.au_intensity(23) > 0


def test_mouth_pulses_and_head() -> None:
    laughs = {t for t, r in TAXONOMY.items() if r.pulses}
    assert laughs == {"uproarious_laughter", "laughter", "eager_laugh", "false_laughter"}
    assert all(3.0 <= TAXONOMY[t].pulse_rate_hz <= 6.0 for t in laughs)  # Ruch & Ekman: ~4-5 Hz
    assert recipe("smiling_closed_mouth").mouth == "closed"
    assert recipe("smiling_closed_mouth").au_intensity(26) == 0.0
    uproarious = recipe("uproarious_laughter")
    assert uproarious.mouth == "open"
    assert uproarious.au_intensity(26) >= max(recipe(t).au_intensity(26) for t in LAUGH_TYPES)
    assert uproarious.au_intensity(27) > 0
    assert uproarious.head_pitch_deg >= 10  # head thrown back


def test_au_frame_applies_asymmetry_to_the_left_side() -> None:
    from mien.facs.catalogue import channel_index

    frame = recipe("false_smile").au_frame()
    assert frame[channel_index("AU12R")] == 3.0
    assert frame[channel_index("AU12L")] == pytest.approx(3.0 * (1 - 0.35))


def test_every_type_cites_sources_and_has_positive_timing() -> None:
    for r in TAXONOMY.values():
        assert r.sources and all(r.sources)
        assert r.onset_s > 0 and r.apex_s > 0 and r.offset_s > 0
        assert r.duration_s == pytest.approx(r.onset_s + r.apex_s + r.offset_s)


def test_unknown_type_lists_the_13() -> None:
    with pytest.raises(UnknownNameError) as info:
        recipe("giggle")
    assert "giggle" in str(info.value)
    assert info.value.known == LAUGH_TYPES
