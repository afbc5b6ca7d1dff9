"""A rig with only VRM presets (a VRoid-like file: opaque morph-target names, expressions bound to them) is driven
through its emotion presets by projection, and the name report says so."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from mien.exchange import vrm
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.clip import Clip
from mien.facs.prototypes import prototype_vector
from mien.fileio.glb import pack_glb, unpack_glb
from mien.heads.amplitude import calibrate_amplitudes
from mien.rig.animate import face_to_rig
from mien.rig.conventions import PROJECTED_PRESETS, match_names, preset_rows, read_overrides
from mien.rig.files import FileRig, load_head_file
from mien.rig.heads import open_head
from mien.rig.vrm_presets import PRESETS, preset_arkit, vrm1_name


@pytest.fixture(scope="module")
def preset_only(tmp_path_factory: pytest.TempPathFactory) -> FileRig:
    """mien's VRM 1.0 of the built-in head with its morph targets renamed Fcl_00... and no custom expressions:
    the only names a convention knows are the 18 presets."""
    folder = tmp_path_factory.mktemp("vrm_presets")
    source, target = folder / "builtin.vrm", folder / "presets.vrm"
    vrm.write(Clip(np.zeros((2, 1)), 30.0, ("jawOpen",)), source, rig=open_head("builtin"))
    document, binary = unpack_glb(source.read_bytes(), source.name)
    for mesh in document["meshes"]:
        names = (mesh.get("extras") or {}).get("targetNames")
        if names:
            mesh["extras"]["targetNames"] = [f"Fcl_{i:02d}" for i in range(len(names))]
    document["extensions"]["VRMC_vrm"]["expressions"]["custom"] = {}
    target.write_bytes(pack_glb(document, binary))
    return load_head_file(target)


def _preset_weights(rig: FileRig, emotion: str) -> dict[str, float]:
    """The file's shape weights a prototype frame of ``emotion`` gives (each side row carries half a both-sided
    shape here, as the viewer's least-squares weight of a shape whose halves are both at w is w)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the presets cannot show every ARKit target: said once
        weights, _ = face_to_rig(rig, prototype_vector(emotion)[None])
    out: dict[str, float] = {}
    for name, weight in zip(rig.target_names, weights[0], strict=True):
        for shape, row_weight, side in rig.info.source_names.get(name, ()):
            out[shape] = out.get(shape, 0.0) + float(weight) * row_weight * (0.5 if side else 1.0)
    return out


def test_the_table_names_both_versions_and_gives_each_emotion_preset_its_prototype() -> None:
    assert [vrm1_name(name) for name in ("joy", "sorrow", "fun", "blink_l", "a", "happy", "smirk")] == [
        "happy", "sad", "relaxed", "blinkLeft", "aa", "happy", None,
    ]  # fmt: skip
    assert tuple(vrm.EXPRESSION_PRESETS) == tuple(PRESETS) and len(PRESETS) == 18
    happy, sad = preset_arkit("happy"), preset_arkit("sad")
    names = list(ARKIT_NAMES)
    assert happy[names.index("mouthSmileLeft")] > 0.5 and happy[names.index("browInnerUp")] == 0.0
    assert sad[names.index("browInnerUp")] > 0.5 and sad[names.index("mouthFrownLeft")] > 0.5
    np.testing.assert_allclose(preset_arkit("relaxed"), np.clip(0.4 * happy, 0, 1), atol=0.02)


def test_a_preset_only_rig_is_detected_and_reported_as_driven_through_its_presets(preset_only: FileRig) -> None:
    names = preset_only.info.names
    assert names.convention == "vrm1"
    assert names.presets == ("happy", "angry", "sad", "surprised") == PROJECTED_PRESETS
    report = names.report()
    assert "driven through its VRM emotion presets (happy, angry, sad, surprised)" in report
    assert "no mouthStretchLeft: AU20 cannot show" in report  # no preset's face stretches the lips
    assert "relaxed" in names.unmatched and "Fcl_00" in names.unmatched
    # the blinks, looks and the two visemes with a table row still drive their ARKit targets directly
    direct = {row.source: row.arkit for row in names.rows if row.source not in names.presets}
    assert direct["blinkLeft"] == "eyeBlinkLeft" and direct["aa"] == "jawOpen"


@pytest.mark.parametrize(("emotion", "preset"), [("joy", "happy"), ("anger", "angry"), ("sadness", "sad"),
                                                 ("surprise", "surprised")])  # fmt: skip
def test_each_emotion_shows_as_its_own_preset_alone(preset_only: FileRig, emotion: str, preset: str) -> None:
    weights = _preset_weights(preset_only, emotion)
    assert weights[preset] == pytest.approx(1.0, abs=0.01)
    others = {name: weights.get(name, 0.0) for name in PROJECTED_PRESETS if name != preset}
    assert max(abs(w) for w in others.values()) < 0.01, others


def test_an_emotion_without_a_preset_is_its_least_squares_blend(preset_only: FileRig) -> None:
    # fear has no VRM preset: it shows as mostly surprised with some angry and sad (raised, drawn-together brows)
    weights = _preset_weights(preset_only, "fear")
    assert weights["surprised"] > 0.5 and weights["angry"] > 0.2 and weights["sad"] > 0.1


def test_projection_rows_are_the_pseudo_inverse_of_the_preset_faces() -> None:
    rows = preset_rows({"Joy": "happy", "Sorrow": "sad"})
    inverse = np.zeros((52, 2))
    for row in rows:
        inverse[list(ARKIT_NAMES).index(row.arkit), ("Joy", "Sorrow").index(row.source)] = row.weight
    faces = np.stack([preset_arkit("happy"), preset_arkit("sad")])
    np.testing.assert_allclose(faces @ inverse, np.eye(2), atol=1e-3)


def test_a_vrm0_rig_projects_its_three_emotion_presets_and_overrides_win(tmp_path: Path) -> None:
    names = ["joy", "angry", "sorrow", "fun", "blink_l", "blink_r", "a"]
    match = match_names(names)
    assert match.convention == "vrm0" and match.presets == ("joy", "angry", "sorrow")
    one = match_names(["joy", "blink_l", "blink_r", "a"])  # one emotion preset: its table stand-in row
    assert one.presets == () and {row.arkit for row in one.rows if row.source == "joy"} == {
        "mouthSmileLeft", "mouthSmileRight",
    }  # fmt: skip
    (tmp_path / "o.toml").write_text('[targets]\n"joy" = [{arkit = "mouthSmileLeft", side = "L"}]\n')
    overridden = match_names(names, overrides=read_overrides(tmp_path / "o.toml"))
    assert overridden.presets == ("angry", "sorrow")
    assert [(row.arkit, row.weight, row.side) for row in overridden.rows if row.source == "joy"] == [
        ("mouthSmileLeft", 1.0, "L")
    ]


def test_a_preset_rig_keeps_its_author_strength(preset_only: FileRig) -> None:
    rig, gains = calibrate_amplitudes(preset_only)
    assert gains == {} and rig is preset_only
