"""Controller curves (Eq. 1, Table 2) and their ARKit weights, on synthetic faces and the real smile video."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError, UnknownNameError
from mien.facs.arkit import ARKIT_INDEX, ARKIT_NAMES
from mien.facs.clip import Clip
from mien.laughter.controllers import (
    CONTROLLER_GAIN,
    DEFAULT_EPS,
    arkit_mapping,
    controller_matrix,
    controllers,
    controllers_from_points,
    controllers_to_arkit,
)
from mien.laughter.names import CONTROLLER_NAMES
from mien.learning.takes import controllers_from_track


def _neutral_face() -> np.ndarray:
    """(68, 2) a rough frontal face in pixels (y down), 100 px between the outer eye corners."""
    face = np.zeros((68, 2))
    face[0:17, 0] = np.linspace(120.0, 280.0, 17)
    face[0:17, 1] = 200.0 + 90.0 * np.sin(np.linspace(0.0, np.pi, 17))
    face[17:22] = np.column_stack([np.linspace(140.0, 190.0, 5), np.full(5, 170.0)])
    face[22:27] = np.column_stack([np.linspace(210.0, 260.0, 5), np.full(5, 170.0)])
    face[27:31] = np.column_stack([np.full(4, 200.0), np.linspace(195.0, 240.0, 4)])
    face[31:36] = np.column_stack([np.linspace(185.0, 215.0, 5), np.full(5, 250.0)])
    face[36:42] = [(150, 200), (160, 195), (175, 195), (185, 200), (175, 205), (160, 205)]
    face[42:48] = [(215, 200), (225, 195), (240, 195), (250, 200), (240, 205), (225, 205)]
    face[48:60] = [(175, 275), (185, 270), (193, 267), (200, 268), (207, 267), (215, 270),
                   (225, 275), (215, 282), (207, 285), (200, 286), (193, 285), (185, 282)]  # fmt: skip
    face[60:68] = [(180, 275), (193, 273), (200, 273), (207, 273), (220, 275), (207, 278), (200, 279), (193, 278)]
    return face


def _sequence(change: dict[int, tuple[float, float]], n_frames: int = 10) -> np.ndarray:
    """Neutral for 5 frames, then the points in ``change`` moved by (dx, dy) pixels."""
    frames = np.repeat(_neutral_face()[None], n_frames, axis=0)
    for point, delta in change.items():
        frames[5:, point] += delta
    return frames


def test_matrix_encodes_table_2() -> None:
    weights = controller_matrix()
    assert weights.shape == (15, 16)
    jaw = CONTROLLER_NAMES.index("jaw")
    assert weights[9, jaw] == 0.5 and weights[13, jaw] == 0.5 and np.count_nonzero(weights[:, jaw]) == 2
    for name in ("upsetSad", "shocked"):
        column = weights[:, CONTROLLER_NAMES.index(name)]
        assert column[1] == column[3] == 0.5 and np.count_nonzero(column) == 2
    assert weights[0, CONTROLLER_NAMES.index("leftTwich")] == 1.0  # FP1 = 46-47, the performer's left eye
    assert weights[4, CONTROLLER_NAMES.index("leftBlink")] == -1.0  # closing shortens the distance


def test_neutral_face_gives_zero_and_eps_scales() -> None:
    clip = controllers_from_points(_sequence({}), fps=30.0)
    assert clip.channels == CONTROLLER_NAMES and clip.fps == 30.0
    assert np.allclose(clip.values, 0.0)
    smile = _sequence({48: (-10.0, -3.0), 54: (10.0, -3.0)})
    soft = controllers_from_points(smile, 30.0, eps=0.1)
    hard = controllers_from_points(smile, 30.0, eps=0.3)
    assert np.allclose(hard.values, 3.0 * soft.values)
    with pytest.raises(InvalidValueError, match="eps"):
        controllers_from_points(smile, 30.0, eps=0.0)


def test_signs_mean_what_the_names_say() -> None:
    def last(change: dict[int, tuple[float, float]]) -> dict[str, float]:
        clip = controllers_from_points(_sequence(change), 30.0)
        return dict(zip(clip.channels, clip.values[-1], strict=True))

    smile = last({48: (-10.0, -3.0), 54: (10.0, -3.0)})  # corners out and up
    # Mouth 50 px -> 70 px wide: +0.2 inter-ocular distances -> 0.2 * eps * gain.
    assert smile["smileFrown"] == pytest.approx(0.2 * DEFAULT_EPS * CONTROLLER_GAIN)
    assert smile["leftSmileFrown"] > 0 and smile["rightSmileFrown"] > 0
    frown = last({48: (5.0, 4.0), 54: (-5.0, 4.0)})
    assert frown["smileFrown"] < 0
    left_only = last({54: (10.0, -3.0)})  # iBUG 54: the performer's left corner
    assert left_only["leftSmileFrown"] > 0.1 and left_only["rightSmileFrown"] == 0.0
    opened = last({57: (0.0, 15.0), 8: (0.0, 15.0), 56: (0, 15), 58: (0, 15)})
    assert opened["jaw"] > 0.3
    brows_up = last({21: (0.0, -8.0), 22: (0.0, -8.0)})
    assert brows_up["upsetSad"] > 0 and brows_up["shocked"] > 0
    assert brows_up["leftBrowRaise"] > 0 and brows_up["rightBrowRaise"] > 0
    left_brow_down = last({22: (0.0, 6.0)})  # brow toward the eye: the performer's left eye narrows
    assert left_brow_down["leftBlink"] > 0 and left_brow_down["rightBlink"] == 0.0
    sneer = last({51: (0.0, -6.0), 48: (0.0, -6.0), 54: (0.0, -6.0)})
    assert sneer["sneer"] > 0 and sneer["leftSneer"] > 0 and sneer["rightSneer"] > 0


def test_arkit_mapping_splits_signed_controllers() -> None:
    version, rows = arkit_mapping()
    assert version == 1 and rows
    assert {r.controller for r in rows} == set(CONTROLLER_NAMES) - {"neck"}
    values = np.zeros((3, 16))
    values[1, CONTROLLER_NAMES.index("smileFrown")] = 1.0
    values[2, CONTROLLER_NAMES.index("smileFrown")] = -1.0
    values[:, CONTROLLER_NAMES.index("jaw")] = 5.0
    weights = controllers_to_arkit(Clip(values, 30.0, CONTROLLER_NAMES))
    assert weights.channels == ARKIT_NAMES and weights.values.min() >= 0.0 and weights.values.max() <= 1.0
    assert weights.values[0, ARKIT_INDEX["mouthSmileLeft"]] == 0.0
    assert (
        weights.values[1, ARKIT_INDEX["mouthSmileLeft"]] > 0.4 and weights.values[1, ARKIT_INDEX["mouthFrownLeft"]] == 0
    )
    assert (
        weights.values[2, ARKIT_INDEX["mouthFrownRight"]] > 0.4
        and weights.values[2, ARKIT_INDEX["mouthSmileRight"]] == 0
    )
    assert np.all(weights.channel("jawOpen") == 1.0)  # clipped
    with pytest.raises(UnknownNameError, match="smileFrown"):
        controllers_to_arkit(Clip(np.zeros((2, 1)), 30.0, ("jaw",)))


def test_controllers_from_parameters_directly() -> None:
    clip = controllers(np.ones((4, 15)), fps=25.0, neutral=np.ones(15))
    assert clip.n_frames == 4 and np.allclose(clip.values, 0.0)


@pytest.fixture(scope="module")
def smile_clip(shared_data: Path, landmarker_path: Path) -> Clip:
    from mien.tracking.track import track_video

    track = track_video(
        shared_data / "video" / "single_face.mp4", landmarker_path, use_cache=False, show_progress=False
    )
    clips = controllers_from_track(track)
    assert len(clips) == 1 and clips[0].n_frames == 72 and clips[0].fps == 30.0
    return clips[0]


def test_real_smile_rises_and_stays(smile_clip: Clip) -> None:
    early, late = slice(0, 15), slice(36, 66)  # the smile relaxes in the clip's last 0.15 s
    for name in ("smileFrown", "leftSmileFrown", "rightSmileFrown"):
        curve = smile_clip.channel(name)
        assert curve[late].mean() > curve[early].mean() + 0.15, name
        assert curve[late].min() > 0.1, name  # stays up
    smile = smile_clip.channel("smileFrown")
    assert 0.7 < smile[late].mean() < 1.4  # a full smile is about 1 at the default eps
    assert abs(smile[early].mean()) < 0.1


def test_real_jaw_and_blink_are_plausible(smile_clip: Clip) -> None:
    assert np.all(np.abs(smile_clip.channel("jaw")) < 1.0) and smile_clip.channel("jaw")[36:].mean() > 0.1
    for name in ("leftBlink", "rightBlink"):
        blink = smile_clip.channel(name)
        assert np.all(np.abs(blink) < 0.5), name  # never stuck closed
    assert np.all(np.abs(smile_clip.values) < 2.0)


def test_real_smile_on_arkit(smile_clip: Clip) -> None:
    weights = controllers_to_arkit(smile_clip)
    for name in ("mouthSmileLeft", "mouthSmileRight"):
        assert weights.channel(name)[:15].mean() < 0.1 and weights.channel(name)[36:].mean() > 0.7
    assert weights.channel("eyeBlinkLeft").max() < 0.5


def test_track_without_takes_gives_no_clips() -> None:
    class NoTakes:
        fps = 30.0
        takes: tuple[tuple[int, int], ...] = ()
        landmarks_px = np.full((4, 478, 3), np.nan)

    assert controllers_from_track(NoTakes()) == []
