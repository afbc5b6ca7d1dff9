import sys

import numpy as np
import pytest

from mien.character import Character
from mien.facs.catalogue import FACE_CHANNELS
from mien.laughter.to_face import smooth

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


def test_a_laugh_needs_no_extra(monkeypatch):
    """Laughter generation is numpy only: the same clip with scipy unimportable (``import scipy`` fails)."""
    with_scipy = Character(seed=2).laugh("laughter", duration_s=1.5)
    for name in [m for m in sys.modules if m == "scipy" or m.startswith("scipy.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "scipy", None)
    monkeypatch.setitem(sys.modules, "scipy.ndimage", None)
    without = Character(seed=2).laugh("laughter", duration_s=1.5)
    np.testing.assert_array_equal(without.values, with_scipy.values)
    assert without.values.max() > 1.0


def test_smooth_gives_scipys_gaussian_filter():
    ndimage = pytest.importorskip("scipy.ndimage")  # the reference, where it is installed
    values = np.random.default_rng(4).normal(size=(150, 16))
    for fps, sigma_s in ((60.0, 0.1), (30.0, 0.25), (59.94, 0.1), (60.0, 0.01)):
        expected = ndimage.gaussian_filter1d(values, sigma_s * fps, axis=0, mode="nearest")
        np.testing.assert_allclose(smooth(values, fps, sigma_s), expected, rtol=0.0, atol=1e-15)
    short = values[:3, 0]  # shorter than the kernel: the held edges fill it
    np.testing.assert_allclose(smooth(short, 60.0), ndimage.gaussian_filter1d(short, 6.0, mode="nearest"))
