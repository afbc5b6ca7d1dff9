"""CharacterBatch: one implementation for one character and for many; rows; OpenFACS Speed semantics."""

import inspect
import math

import numpy as np
import pytest

from mien import InvalidValueError, UnknownNameError
from mien.affect.basis import feature_target_names
from mien.character import Character, CharacterBatch
from mien.facs.catalogue import FACE_CHANNELS
from mien.facs.dynamics import FacsBatch, FacsEngine
from mien.facs.idle import IdleSettings

AU = {name: i for i, name in enumerate(FACE_CHANNELS)}
FPS = 60.0


def _script(batch: CharacterBatch, row: int, character: Character) -> list:
    """The same commands on a batch row and on a single character, keyed by the tick they happen on."""

    def both(batch_call, single_call):
        return lambda: (batch_call(), single_call())

    return [
        (0, both(lambda: batch.set_speed(row, 0.05), lambda: character.set_speed(0.05))),
        (
            0,
            both(
                lambda: batch.set_aus(row, {"AU4": 2.0, "R14B": 1.0}, replace=True),
                lambda: character.set_aus({"AU4": 2.0, "R14B": 1.0}, replace=True),
            ),
        ),
        (0, both(lambda: batch.set_mood(row, {"sadness": 0.4}), lambda: character.set_mood({"sadness": 0.4}))),
        (
            10,
            both(
                lambda: batch.play_au(row, "AU1D", onset_s=0.2, apex_s=0.3, offset_s=0.4),
                lambda: character.play_au("AU1D", onset_s=0.2, apex_s=0.3, offset_s=0.4),
            ),
        ),
        (20, both(lambda: batch.emote(row, "joy", 1.2), lambda: character.emote("joy", 1.2))),
        (30, both(lambda: batch.set_au(row, "AU51", 2.0, tau_s=0.3), lambda: character.set_au("AU51", 2.0, tau_s=0.3))),
        (
            40,
            both(lambda: batch.emote(row, "evil", 0.8, start_s=0.9), lambda: character.emote("evil", 0.8, start_s=0.9)),
        ),
        (60, both(lambda: batch.set_speed(row, 0.2, au="AU12"), lambda: character.set_speed(0.2, au="AU12"))),
        (
            70,
            both(
                lambda: batch.laugh(row, "laughter", 0.8, seed=4, duration_s=1.5),
                lambda: character.laugh("laughter", 0.8, duration_s=1.5, seed=4),
            ),
        ),
        (
            90,
            both(
                lambda: batch.set_aus(row, {"AU26": 1.0}, replace=True),
                lambda: character.set_aus({"AU26": 1.0}, replace=True),
            ),
        ),
        (150, both(lambda: batch.emote(row, "surprise", 2.4), lambda: character.emote("surprise", 2.4))),
    ]


@pytest.mark.parametrize("basis", ["facs", "feature_points"])
def test_character_equals_a_row_of_a_larger_batch_for_every_layer(basis):
    batch = CharacterBatch(0)
    others = [batch.add_character(seed=s, expression_basis="facs") for s in (11, 12)]
    row = batch.add_character(seed=7, idle=True, expression_basis=basis)
    batch.add_character(seed=13, idle=IdleSettings(blink=False), expression_basis="feature_points")
    single = Character(seed=7, expression_basis=basis)
    batch.emote(others, "anger", 1.0)  # the neighbours are busy too
    batch.set_aus(others[0], {"AU12": 3.0})
    script = _script(batch, row, single)
    feature_peak = 0.0
    for i in range(300):
        for tick, call in script:
            if tick == i:
                call()
        t = i / FPS
        frames = batch.step(t)
        frame = single.step(t)
        np.testing.assert_allclose(frames[row], frame, atol=1e-9, err_msg=f"tick {i}")
        np.testing.assert_allclose(batch.feature_weights[row], single.feature_weights, atol=1e-12)
        feature_peak = max(feature_peak, float(np.abs(single.feature_weights).max()))
    assert batch.snapshot(row) == pytest.approx(single.snapshot(), abs=1e-9)
    assert frame[AU["AU26"]] > 0.5  # the last surprise opens the jaw in both, whichever basis
    if basis == "feature_points":
        assert feature_peak > 0.005  # the emotions moved the feature points (metres) ...
        assert frame[AU["AU2L"]] == 0.0  # ... and not the AU channels
        assert batch.feature_weights[others[0]].tolist() == [0.0] * len(feature_target_names())


def test_pad_and_timed_layers_equal_on_a_row():
    batch = CharacterBatch(np.array([3, 4, 5]), idle=False, emotion_mode="pad")
    single = Character(seed=4, idle=False, emotion_mode="pad")
    batch.set_pad(0, -0.5, 0.6, 0.2)  # row 0 moves differently
    batch.set_pad(1, 0.8, 0.5, 0.4, start_s=0.0)
    single.set_pad(0.8, 0.5, 0.4)
    for i in range(120):
        t = i / 30.0
        if i == 40:
            batch.set_pad(1, 0.0, 0.0, 0.0)  # now: the time of the last step
            single.set_pad(0.0, 0.0, 0.0)
            batch.play_au([1, 2], "AU6", 4.0, onset_s=0.1, apex_s=0.1, offset_s=0.1)
            single.play_au("AU6", 4.0, onset_s=0.1, apex_s=0.1, offset_s=0.1)
        np.testing.assert_allclose(batch.step(t)[1], single.step(t), atol=1e-9)
    smile = single.step(4.0)[AU["AU12L"]]
    assert not single.batch.emotions.advance(4.0).any() and 0.0 < smile < 1.0  # PAD neutral: a mood smile is left
    with pytest.raises(InvalidValueError, match="emotion_mode"):
        Character(idle=False).set_pad(0.1, 0.1, 0.1)
    mixed = CharacterBatch(0, idle=False)  # the mode is checked in the batch, per row
    pad_row = mixed.add_character(emotion_mode="pad")
    categorical_row = mixed.add_character()
    mixed.set_pad(pad_row, 0.5, 0.5, 0.5)
    with pytest.raises(InvalidValueError, match="emotion_mode"):
        mixed.set_pad([pad_row, categorical_row], 0.1, 0.1, 0.1)
    assert [mixed.emotion_mode(r) for r in (pad_row, categorical_row)] == ["pad", "categorical"]
    pads = mixed.emotions.pad_at(1.0)  # after the 0.4 s ramp: the refused call changed no row
    assert pads[pad_row].tolist() == [0.5, 0.5, 0.5] and pads[categorical_row].tolist() == [0.0, 0.0, 0.0]


def test_idle_seeds_are_reproducible_and_rows_independent():
    a, b = CharacterBatch(np.array([1, 2, 3])), CharacterBatch(np.array([9, 2]))
    for i in range(600):
        t = i / FPS
        np.testing.assert_array_equal(a.step(t)[1], b.step(t)[1])
    assert not np.array_equal(a.step(10.0)[0], a.step(10.0)[1])


def test_add_and_remove_rows():
    batch = CharacterBatch(0)
    assert batch.step(0.0).shape == (0, len(FACE_CHANNELS))
    rows = [batch.add_character(seed=s, idle=False) for s in range(3)]
    assert rows == [0, 1, 2] and batch.active_rows().tolist() == [0, 1, 2]
    batch.set_aus(slice(None), {"AU12": 4.0})
    batch.set_speed(slice(None), 1.0)
    batch.emote(1, "fear", 1.0)
    batch.laugh(1, "laughter", duration_s=2.0)
    batch.play_au(1, "AU45", 5.0, onset_s=1.0, apex_s=1.0, offset_s=1.0)
    assert batch.step(0.5)[1].max() > 0.0
    batch.remove_character(1)
    assert batch.active_rows().tolist() == [0, 2]
    frames = batch.step(0.6)
    assert not frames[1].any() and frames[0, AU["AU12L"]] == 4.0
    for bad in (1, [0, 1], 7, -1, "0", 1.5):
        with pytest.raises(InvalidValueError, match="row"):
            batch.set_au(bad, "AU12", 1.0)
    with pytest.raises(InvalidValueError):
        batch.snapshot(1)
    batch.set_aus(slice(None), {"AU2": 1.0})  # a slice selects the active rows only
    assert batch.step(0.7)[1].tolist() == [0.0] * len(FACE_CHANNELS)
    again = batch.add_character(seed=5, idle=False)
    assert again == 1  # the freed row is reused, neutral: no held AUs, events, actions or laughs left
    frames = batch.step(1.2)
    assert not frames[1].any()
    assert batch.add_character(seed=6) == 3 and batch.step(1.3).shape[0] == 4


def test_a_row_added_later_starts_its_idle_then():
    def run():
        batch = CharacterBatch(np.array([1]))
        out = [batch.step(i / FPS)[0].copy() for i in range(60)]
        batch.add_character(seed=8)
        out += [batch.step(1.0 + i / FPS)[1].copy() for i in range(600)]
        return np.array(out)

    first, second = run(), run()
    np.testing.assert_array_equal(first, second)
    assert first[60:, AU["AU45L"]].max() > 4.5  # it blinks (60 Hz samples miss the exact peak)


def test_openfacs_speed_lerp_semantics_and_rate_independence():
    def value_at(hz: float, t_s: float, speed: float = 0.05) -> float:
        batch = CharacterBatch(0, tick_hz=60.0)
        row = batch.add_character(idle=False)
        batch.set_speed(row, speed)
        batch.set_aus(row, {"AU12": 5.0})
        n = round(t_s * hz)
        frame = batch.step(0.0)
        for i in range(1, n + 1):
            frame = batch.step(i / hz)
        return float(frame[row, AU["AU12L"]])

    # OpenFACS: every rendered frame moves Lerp(current, target, Speed)
    lerp = 0.0
    for _ in range(30):
        lerp += 0.05 * (5.0 - lerp)
    assert value_at(60.0, 0.5) == pytest.approx(lerp, abs=1e-9)
    tau = -1.0 / (60.0 * math.log(0.95))
    assert 3.0 * tau == pytest.approx(0.97, abs=0.01)  # 95% of the way in ~0.97 s
    assert value_at(60.0, 59 / 60) / 5.0 >= 0.95 > value_at(60.0, 58 / 60) / 5.0
    for t in (0.5, 1.0):
        assert value_at(30.0, t) == pytest.approx(value_at(60.0, t), abs=1e-9)
        assert value_at(120.0, t) == pytest.approx(value_at(60.0, t), abs=1e-9)
    assert value_at(30.0, 1 / 30, speed=1.0) == 5.0  # Speed 1 jumps


def test_full_state_messages_replace_missing_aus():
    batch = CharacterBatch(np.array([0]), idle=False)
    batch.set_speed(0, 1.0)
    batch.set_aus(0, {"AU12": 3.0, "AU6": 2.0})
    batch.step(0.1)
    batch.set_aus(0, {"AU6": 1.0}, replace=True)
    frame = batch.step(0.2)[0]
    assert frame[AU["AU12L"]] == 0.0 and frame[AU["AU6L"]] == 1.0
    batch.set_aus(0, {"AU1": 1.0}, replace=False)
    frame = batch.step(0.3)[0]
    assert frame[AU["AU6L"]] == 1.0 and frame[AU["AU1L"]] == 1.0


def test_batch_bad_input_is_rejected_without_changing_state():
    batch = CharacterBatch(np.array([0, 1]), idle=False, emotion_mode="pad")
    with pytest.raises(UnknownNameError):
        batch.set_aus(0, {"AU12": 1.0, "AU99": 1.0})
    with pytest.raises(InvalidValueError, match="AU12"):
        batch.set_aus(0, {"AU12": 7.0})
    assert not batch.facs.target.any()
    with pytest.raises(InvalidValueError, match="Speed"):
        batch.set_speed(0, 1.5)
    with pytest.raises(UnknownNameError):
        batch.emote(0, "glee", 1.0)
    with pytest.raises(InvalidValueError, match="pleasure"):
        batch.set_pad(0, 2.0, 0.0, 0.0)
    with pytest.raises(InvalidValueError, match="mood"):
        batch.set_mood(0, [1.0, 2.0])
    with pytest.raises(InvalidValueError, match="seed"):
        batch.add_character(seed=-1)
    with pytest.raises(InvalidValueError, match="expression_basis"):
        batch.add_character(expression_basis="mpeg")
    with pytest.raises(InvalidValueError, match="idle"):
        batch.add_character(idle="yes")  # type: ignore[arg-type]
    with pytest.raises(InvalidValueError, match="clip"):
        batch.play_clip(0, "laugh.json")  # type: ignore[arg-type]
    assert batch.active_rows().tolist() == [0, 1]
    batch.step(1.0)
    for bad in (0.5, float("nan"), "later"):
        with pytest.raises(InvalidValueError, match="t_s"):
            batch.step(bad)  # type: ignore[arg-type]


def _public_methods(cls: type) -> set[str]:
    return {name for name, value in vars(cls).items() if callable(value) and not name.startswith("_")}


def _without_rows(cls: type, name: str) -> inspect.Signature:
    """The signature of ``cls.name`` without its first parameter after ``self`` when that is ``rows``/``row``."""
    signature = inspect.signature(getattr(cls, name))
    self_param, *rest = signature.parameters.values()
    if rest and rest[0].name in ("rows", "row"):
        rest = rest[1:]
    return signature.replace(parameters=[self_param, *rest])


TRAPS = {"start_s", "onset_s", "apex_s", "offset_s", "duration_s", "tau_s", "replace", "seed", "envelope"}
"""Arguments whose position would be a trap (times and switches): keyword-only wherever they appear."""


@pytest.mark.parametrize(
    ("single", "batch", "single_only"),
    [(Character, CharacterBatch, {"run"}), (FacsEngine, FacsBatch, set())],
)
def test_single_methods_are_the_batch_methods_without_rows(single, batch, single_only):
    methods = _public_methods(single)
    assert methods - single_only <= _public_methods(batch), methods - _public_methods(batch)
    for name in sorted(methods - single_only):
        assert _without_rows(single, name) == _without_rows(batch, name), name
    for cls in (single, batch):
        for name in sorted(methods - single_only):
            others = list(_without_rows(cls, name).parameters.values())[2:]  # the first may stay positional
            for parameter in others:
                if parameter.name in TRAPS:
                    assert parameter.kind is inspect.Parameter.KEYWORD_ONLY, f"{cls.__name__}.{name}({parameter.name})"


def test_the_signature_check_sees_a_drift():
    class Drifted(Character):
        def laugh(self, laugh_type, intensity=1.0, *, start_s=None, seed=None, duration_s=None):  # type: ignore[override]
            return super().laugh(laugh_type, intensity, duration_s=duration_s, seed=seed, start_s=start_s)

    assert _without_rows(Drifted, "laugh") != _without_rows(CharacterBatch, "laugh")
    assert _without_rows(Character, "laugh") == _without_rows(CharacterBatch, "laugh")
    assert list(_without_rows(CharacterBatch, "play_au").parameters)[1:] == [
        "au", "intensity", "onset_s", "apex_s", "offset_s", "start_s"
    ]  # fmt: skip


def test_readme_calls_work_on_one_character():
    face = Character(seed=1)
    face.set_au("AU6C")
    face.emote("joy", 1.2)
    face.emote("surprise", 0.8, start_s=1.0)
    face.set_aus({"AU4": 5, "AU15": 3}, speed=0.05)
    face.play_au("AU12E", onset_s=0.3, apex_s=1.0, offset_s=0.5)
    face.laugh("sly_smile", intensity=1.0, duration_s=2.5)
    clip = face.run(duration_s=3.0, fps=60)
    assert clip.values.shape == (180, len(FACE_CHANNELS))
    assert clip.channel("AU4L").max() > 4.0 and clip.channel("AU12L").max() > 1.0
    pad = Character(emotion_mode="pad", idle=False)
    pad.set_pad(0.6, 0.4, 0.2)
    assert pad.step(1.0)[: AU["head_yaw_deg"]].any()
    with pytest.raises(TypeError):
        face.play_au("AU12E", None, 0.3, 1.0, 0.5)  # type: ignore[misc]  # timings are keyword-only
