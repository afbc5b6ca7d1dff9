import numpy as np
import pytest

from mien import InvalidValueError, UnknownNameError
from mien.character import Character, CharacterBatch
from mien.facs.catalogue import FACE_CHANNELS

AU = {name: i for i, name in enumerate(FACE_CHANNELS)}


def test_envelope_shape_on_the_face():
    c = Character(idle=False, mood_gain=0.0)  # no mood: the envelope alone
    c.emote("joy", 1.0)  # AU12 at 3.5 at intensity 1 (prototypes v2), 0.4/0.3/0.3 s
    assert c.step(0.2)[AU["AU12L"]] == pytest.approx(1.75, abs=1e-9)
    hold = [c.step(t)[AU["AU12L"]] for t in (0.4, 0.55, 0.7)]
    assert hold == pytest.approx([3.5, 3.5, 3.5])
    assert c.step(0.85)[AU["AU12L"]] == pytest.approx(1.75, abs=1e-9)
    assert c.step(1.0)[AU["AU12L"]] == 0.0
    assert c.step(1.5)[AU["AU12L"]] == 0.0


def test_strong_intensity_keeps_the_prototype_proportions():
    """Above the knee the whole prototype scales by one factor (sadness keeps AU4 below AU1; v1 clamped both at E)."""
    from mien.facs.prototypes import prototype_vector

    prototype = prototype_vector("sadness")
    for intensity in (1.2, 2.4, 5.0):
        c = Character(idle=False, mood_gain=0.0)
        c.emote("sadness", intensity)
        frame = c.step(0.55)[: len(prototype) - 5]
        assert frame.max() <= 5.0
        np.testing.assert_allclose(frame / frame.max(), prototype[:-5] / prototype.max(), atol=1e-9)
    strong, weak = Character(idle=False, mood_gain=0.0), Character(idle=False, mood_gain=0.0)
    strong.emote("sadness", 2.4)
    weak.emote("sadness", 1.2)
    assert strong.step(0.55).max() > weak.step(0.55).max()  # 2.4 is still the stronger face


def test_geometric_intensity_doubles_the_face():
    a, b = Character(idle=False), Character(idle=False)
    a.emote("sadness", 0.5)
    b.emote("sadness", 1.0)
    fa, fb = a.step(0.5).copy(), b.step(0.5).copy()
    np.testing.assert_allclose(2 * fa, fb, atol=0.02)


def test_blend_is_the_sum_of_its_components():
    blend, joy, anger = Character(idle=False), Character(idle=False), Character(idle=False)
    blend.emote("evil", 0.5)
    joy.emote("joy", 0.5)
    anger.emote("anger", 0.5)
    # mood contributions are tiny here; compare the expression at the hold
    total = joy.step(0.5).copy() + anger.step(0.5).copy()
    np.testing.assert_allclose(blend.step(0.5), np.clip(total, 0, 5), atol=0.02)


def test_face_returns_to_the_mood_with_closed_mouth():
    c = Character(idle=False, mood_time_constant_s=2.0)
    for k in range(6):  # repeated surprise builds a surprised mood
        c.emote("surprise", 1.0, start_s=k * 1.0)
        c.step(k * 1.0)
    during = c.step(5.5).copy()
    assert during[AU["AU26"]] > 1.0
    after = c.step(12.0).copy()
    assert after[AU["AU1L"]] > 0.05  # the mood still raises the brows
    assert after[AU["AU26"]] == 0.0  # ... with the jaw closed
    assert after[AU["AU25"]] == 0.0


def test_blink_during_a_smile_still_closes_the_eyes():
    c = Character(seed=2)
    c.set_au("AU6", 5.0, tau_s=0.0)
    c.set_au("AU12", 5.0, tau_s=0.0)
    peak = max(c.step(i / 100)[AU["AU45L"]] for i in range(2000))
    assert peak > 4.9


def test_idle_mouth_motion_yields_to_a_busy_mouth():
    quiet, busy = Character(seed=4), Character(seed=4)
    busy.set_au("AU26", 5.0, tau_s=0.0)
    busy.set_au("AU12", 0.0)
    q = np.array([quiet.step(i / 60)[AU["AU15L"]] for i in range(1, 1200)])
    b = np.array([busy.step(i / 60)[AU["AU15L"]] for i in range(1, 1200)])
    assert q.max() > 0.0
    assert b.max() == 0.0


def test_character_is_deterministic_for_a_seed():
    def run(seed):
        c = Character(seed=seed)
        c.emote("fear", 1.2, start_s=0.3)
        c.play_au("AU12C", start_s=1.0)
        return c.run(3.0, fps=30).values

    assert np.array_equal(run(7), run(7))
    assert not np.array_equal(run(7), run(8))


def test_feature_point_basis_drives_feature_weights():
    c = Character(idle=False, expression_basis="feature_points")
    c.emote("surprise", 1.0)
    frame = c.step(0.5)
    assert not frame[: AU["head_yaw_deg"]].any()
    from mien.affect.basis import feature_target_names

    jaw_y = feature_target_names().index("fp_Jaw_y")
    assert c.feature_weights[jaw_y] == pytest.approx(-0.01, abs=1e-4)


def test_batch_equals_single_characters():
    seeds = [3, 5, 8]
    batch = CharacterBatch(np.array(seeds))
    singles = [Character(seed=s) for s in seeds]
    batch.emote(0, "joy", 1.2, start_s=0.5)
    singles[0].emote("joy", 1.2, start_s=0.5)
    batch.emote([1, 2], "frustrated", 1.0, start_s=1.0)
    for s in singles[1:]:
        s.emote("frustrated", 1.0, start_s=1.0)
    batch.set_au(2, "AU4", 3.0)
    singles[2].set_au("AU4", 3.0)
    for i in range(240):
        t = i / 60
        frames = batch.step(t)
        for k, single in enumerate(singles):
            np.testing.assert_allclose(frames[k], single.step(t), atol=1e-6)


def test_bad_commands_raise_typed_errors():
    c = Character()
    with pytest.raises(UnknownNameError):
        c.emote("glee", 1.0)
    with pytest.raises(InvalidValueError, match="intensity"):
        c.emote("joy", 6.0)
    with pytest.raises(InvalidValueError):
        c.emote("joy", float("nan"))
    with pytest.raises(UnknownNameError):
        c.set_au("AU99", 1.0)
    with pytest.raises(InvalidValueError, match="expression_basis"):
        Character(expression_basis="mpeg")
    with pytest.raises(InvalidValueError, match="duration_s"):
        c.run(-1.0)
    c.step(1.0)
    with pytest.raises(InvalidValueError, match="t_s"):
        c.step(0.5)


def test_batch_set_au_back_to_zero_relaxes_the_face():
    batch = CharacterBatch(np.array([1, 2]), idle=False)
    batch.set_au(slice(None), "AU12", 4.0, tau_s=0.0)
    assert batch.step(0.1)[:, AU["AU12L"]].tolist() == [4.0, 4.0]
    batch.set_au(1, "AU12", 0.0)
    frames = batch.step(5.0)
    assert frames[0, AU["AU12L"]] == 4.0 and frames[1, AU["AU12L"]] == 0.0
