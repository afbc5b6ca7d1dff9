import numpy as np

from mien.character import Character
from mien.facs.catalogue import FACE_CHANNELS

AU = {name: i for i, name in enumerate(FACE_CHANNELS)}


def test_laugh_plays_on_the_character_and_idle_mouth_yields():
    c = Character(seed=3)
    c.emote("joy", 0.5)
    clip = c.laugh("laughter", intensity=1.0, duration_s=2.0, seed=1)
    frames = np.array([c.step(i / 60).copy() for i in range(1, 120)])
    assert frames[:, AU["AU26"]].max() > 0.5  # the laugh opens the jaw
    assert frames[:, AU["AU6L"]].max() > 0.5  # genuine laughter keeps the Duchenne marker
    assert clip.channels == FACE_CHANNELS
    # while the laugh plays, idle mouth-corner walks add nothing: same face as without idle mouth
    quiet = Character(seed=3, idle=False)
    quiet.emote("joy", 0.5)
    quiet.laugh("laughter", intensity=1.0, duration_s=2.0, seed=1)
    quiet_frames = np.array([quiet.step(i / 60).copy() for i in range(1, 120)])
    mouth = [AU["AU12L"], AU["AU12R"], AU["AU15L"], AU["AU15R"]]
    np.testing.assert_allclose(frames[30:90, mouth], quiet_frames[30:90, mouth], atol=1e-9)


def test_false_smile_has_no_cheek_raise_on_the_character():
    c = Character(seed=0, idle=False)
    c.laugh("false_smile", duration_s=1.5)
    frames = np.array([c.step(i / 60).copy() for i in range(1, 90)])
    assert frames[:, AU["AU12L"]].max() > 1.0
    assert frames[:, AU["AU6L"]].max() == 0.0
