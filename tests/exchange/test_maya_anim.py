"""Maya .anim writer/reader: golden file, round trip within the key-reduction tolerance, malformed input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError
from mien.exchange import reader_for, writer_for
from mien.exchange.key_reduction import default_tolerance, interpolate_keys, reduce_keys
from mien.exchange.maya_anim import evaluate_curve, fps_to_time_unit, read, read_curves, to_clip, write
from mien.facs.clip import Clip

DATA = Path(__file__).parent / "data"


def tiny_clip() -> Clip:
    values = np.array([[0.0, 0.0], [0.25, 0.1], [0.5, 0.2], [0.75, 0.2], [0.5, 0.2]])
    return Clip(values, 24.0, ("smileFrown", "jaw"))


def smooth_clip(seconds: float = 10.0, fps: float = 60.0) -> Clip:
    t = np.arange(int(seconds * fps)) / fps
    smile = 0.8 * np.exp(-(((t - 4.0) / 1.8) ** 2)) + 0.1 * np.sin(2 * np.pi * t / 10.0)
    jaw = 0.5 * (1 - np.cos(2 * np.pi * t / 10.0))
    return Clip(np.stack([smile, jaw], axis=1), fps, ("smileFrown", "jaw"))


def test_golden_file(tmp_path: Path) -> None:
    path = write(tiny_clip(), tmp_path / "tiny.anim", tolerance=0.0)
    assert path.read_text() == (DATA / "tiny_controllers.anim").read_text()


def test_registered_by_suffix(tmp_path: Path) -> None:
    assert writer_for("x.anim") is write and reader_for("x.ANIM") is read


def test_read_golden() -> None:
    anim = read_curves(DATA / "tiny_controllers.anim")
    assert anim.fps == 24.0 and anim.header["timeUnit"] == "film" and anim.header["animVersion"] == "1.1"
    assert list(anim.curves) == ["smileFrown", "jaw"]
    jaw = anim.curves["jaw"]
    assert jaw.frames.tolist() == [0.0, 2.0, 4.0] and jaw.values.tolist() == [0.0, 0.2, 0.2]
    assert jaw.in_tangents == ("linear",) * 3 and jaw.node == "mien" and jaw.settings["output"] == "unitless"
    clip = to_clip(anim)
    np.testing.assert_allclose(clip.values, tiny_clip().values, rtol=0, atol=1e-15)


def test_round_trip_within_tolerance_with_few_keys(tmp_path: Path) -> None:
    clip = smooth_clip()
    path = write(clip, tmp_path / "smooth.anim")
    anim = read_curves(path)
    back = to_clip(anim)
    assert back.channels == clip.channels and back.fps == 60.0 and back.n_frames == 600
    for j, name in enumerate(clip.channels):
        limit = default_tolerance(clip.values[:, j])
        assert np.abs(back.values[:, j] - clip.values[:, j]).max() <= limit + 1e-12
        assert len(anim.curves[name].frames) < 60
    full = read_curves(write(clip, tmp_path / "full.anim", reduce=False))
    assert len(full.curves["jaw"].frames) == 600
    np.testing.assert_array_equal(to_clip(full).values, clip.values)


def test_reduce_keys_bound_is_exact() -> None:
    rng = np.random.default_rng(0)
    times = np.arange(600) / 60.0
    values = np.cumsum(rng.normal(0, 0.01, 600))
    for tolerance in (0.0, 1e-3, 0.01, 0.1):
        kept = reduce_keys(times, values, tolerance)
        assert kept[0] == 0 and kept[-1] == 599 and np.all(np.diff(kept) > 0)
        error = np.abs(interpolate_keys(times[kept], values[kept], times) - values)
        assert error.max() <= tolerance
    assert len(reduce_keys(times, values, 0.1)) < len(reduce_keys(times, values, 0.01)) < 600
    assert reduce_keys(times, np.full(600, 0.3), 0.0).tolist() == [0, 599]
    with pytest.raises(InvalidValueError, match="tolerance"):
        reduce_keys(times, values, -1.0)
    with pytest.raises(InvalidValueError, match="times"):
        reduce_keys(np.array([0.0, 0.0]), np.array([1.0, 2.0]), 0.1)


def test_dict_input_and_time_units(tmp_path: Path) -> None:
    curves = {"eyeBlinkLeft": (np.array([0.0, 0.1, 0.2]), np.array([0.0, 1.0, 0.0]))}
    anim = read_curves(write(curves, tmp_path / "blink.anim", fps=120))
    assert anim.header["timeUnit"] == "120fps" and anim.fps == 120.0
    assert anim.curves["eyeBlinkLeft"].frames.tolist() == [0.0, 12.0, 24.0]
    assert [fps_to_time_unit(f) for f in (24, 25, 30, 48, 50, 60)] == ["film", "pal", "ntsc", "show", "palf", "ntscf"]
    with pytest.raises(InvalidValueError, match="fps"):
        write(curves, tmp_path / "x.anim")
    with pytest.raises(InvalidValueError, match="channel"):
        write({"bad name": curves["eyeBlinkLeft"]}, tmp_path / "x.anim", fps=30)


MAYA_STYLE = """// exported by hand in the style of Maya
animVersion 1.1;
mayaVersion 2020;
timeUnit ntsc;
linearUnit cm;
angularUnit deg;
startTime 1;
endTime 5;
anim translate.translateX translateX pCube1 0 1 0;
animData {
  input time;
  output linear;
  weighted 0;
  preInfinity constant;
  postInfinity constant;
  keys {
    1 0 spline spline 1 1 0;
    3 2 flat step 1 0 0;
    5 4 fixed linear 1 0 0 45 1;
  }
}
anim pCubeShape1 1 0 0;
"""


def test_read_maya_style_tangents(tmp_path: Path) -> None:
    path = tmp_path / "maya.anim"
    path.write_text(MAYA_STYLE)
    anim = read_curves(path)
    curve = anim.curves["translateX"]
    assert curve.full_attribute == "translate.translateX" and curve.out_tangents == ("spline", "step", "linear")
    assert np.isnan(curve.in_angles[0]) and curve.in_angles[2] == 45.0
    values = evaluate_curve(curve, np.array([0.0, 1.0, 2.0, 3.0, 4.0, 4.99, 5.0, 9.0]), anim.fps)
    assert values[[0, 1, 3, 6, 7]].tolist() == [0.0, 0.0, 2.0, 4.0, 4.0]
    assert values[4] == 2.0 and values[5] == 2.0  # stepped out of frame 3
    assert 0.0 < values[2] < 2.0  # Hermite between spline and flat keys
    clip = to_clip(anim)
    assert clip.n_frames == 5 and clip.channels == ("translateX",)


@pytest.mark.parametrize(
    ("text", "line"),
    [
        ("animVersion 1.1;\nmayaVersion 2020\n", 2),
        ("animVersion 1.1;\nanim a a n 0 0 0;\nanimData {\n  keys {\n    0 x linear linear 1 1 0;\n  }\n}\n", 5),
        ("animVersion 1.1;\nanim a a n 0 0 0;\nanimData {\n  keys {\n    0 1 wobbly linear 1 1 0;\n  }\n}\n", 5),
        ("animVersion 1.1;\nanim a a n 0 0 0;\nanimData {\n  keys {\n    0 1 linear linear 1 1 0;\n", 5),
        ("animVersion 1.1;\nanim a a n 0 0 0;\nanimData {\n  keys {\n  }\n}\n", 6),
        ("animVersion 1.1;\nanim a a n 0;\n", 2),
    ],
)
def test_malformed_files_name_the_line(tmp_path: Path, text: str, line: int) -> None:
    path = tmp_path / "bad.anim"
    path.write_text(text)
    with pytest.raises(InvalidValueError) as info:
        read_curves(path)
    assert info.value.field == f"bad.anim line {line}"


def test_rate_maya_does_not_name_is_resampled_and_said(tmp_path: Path) -> None:
    clip = smooth_clip(seconds=1.0, fps=33.0)
    with pytest.warns(UserWarning, match="resampled from 33 fps to 40 fps"):
        path = write(clip, tmp_path / "odd.anim", reduce=False)
    text = path.read_text()
    assert text.startswith("// resampled from 33 fps to 40 fps (Maya has no 33 fps time unit)\n")
    anim = read_curves(path)
    assert anim.header["timeUnit"] == "40fps"
    frames = anim.curves["jaw"].frames
    assert np.array_equal(frames, np.round(frames)) and frames.tolist() == list(range(40))
    back = read(path)
    np.testing.assert_allclose(back.sample(clip.times_s), clip.values, atol=2e-3)
    assert fps_to_time_unit(15) == "game" and fps_to_time_unit(29.97) == "29.97fps"
    with pytest.raises(InvalidValueError, match="40 is the next"):
        fps_to_time_unit(33)


def test_nan_and_unordered_keys_refused_at_write(tmp_path: Path) -> None:
    nan = {"jaw": (np.array([0.0, 1 / 30, 2 / 30]), np.array([0.0, np.nan, 1.0]))}
    with pytest.raises(InvalidValueError, match=r"curves\['jaw'\] key 1"):
        write(nan, tmp_path / "nan.anim", fps=30, reduce=False)
    unordered = {"jaw": (np.array([0.0, 2 / 30, 1 / 30]), np.array([0.0, 1.0, 0.5]))}
    with pytest.raises(InvalidValueError, match=r"key 2.*increasing"):
        write(unordered, tmp_path / "order.anim", fps=30)
    between = {"jaw": (np.array([0.0, 0.01]), np.array([0.0, 1.0]))}
    with pytest.raises(InvalidValueError, match="on frames of 30 fps"):
        write(between, tmp_path / "between.anim", fps=30)
    assert not list(tmp_path.iterdir())  # nothing half-written


def test_controller_script_creates_the_node_the_curves_target(tmp_path: Path) -> None:
    from importlib.resources import files

    from mien.exchange.maya_anim import controller_script

    mel = controller_script(("smileFrown", "jaw"))
    assert 'createNode transform -n "mien"' in mel and 'addAttr -ln "jaw" -at double -k 1 "mien"' in mel
    general = (files("mien.exchange") / "data" / "mien_controller.mel").read_text()
    assert "global proc string[] mienCreateController(string $animPath)" in general
    # The general script keys on the anim lines mien writes: 7 tokens, attribute at 2 and node at 3.
    line = next(x for x in (DATA / "tiny_controllers.anim").read_text().splitlines() if x.startswith("anim "))
    tokens = line.replace(";", " ").split()
    assert len(tokens) == 7 and tokens[2] == "smileFrown" and tokens[3] == "mien"
    assert general.count("{") == general.count("}")
