"""Naming conventions as data: tables load, detection by overlap, combined shapes, AU costs, TOML overrides."""

from __future__ import annotations

import json

import pytest
from tests.conftest import shared_root

from mien.errors import InvalidValueError, UnknownNameError
from mien.facs.arkit import ARKIT_NAMES
from mien.rig.conventions import CONVENTION_NAMES, load_convention, match_names, read_overrides


@pytest.mark.parametrize("name", CONVENTION_NAMES)
def test_every_table_loads_with_arkit_targets_and_a_cited_source(name: str) -> None:
    table = load_convention(name)
    assert table.name == name and table.title
    assert table.rows and all(row.arkit in ARKIT_NAMES for row in table.rows)
    assert all(row.side in ("", "L", "R") for row in table.rows)


def test_arkit_and_livelink_tables_cover_all_52_names() -> None:
    assert [row.arkit for row in load_convention("arkit").rows] == list(ARKIT_NAMES)
    livelink = {row.source: row.arkit for row in load_convention("livelink").rows}
    assert livelink["EyeBlinkLeft"] == "eyeBlinkLeft" and livelink["TongueOut"] == "tongueOut"
    assert len(livelink) == 52


@pytest.mark.parametrize(
    ("names", "expected"),
    [
        (["eyeBlink_L", "eyeBlink_R", "browInnerUp_L", "browInnerUp_R", "jawOpen"], "ict"),
        (["EyeBlinkLeft", "JawOpen", "MouthSmileLeft"], "livelink"),
        (["eyeBlinkLeft", "jawOpen", "mouthSmileLeft"], "arkit"),
        (["Eye_Blink_L", "Mouth_Smile_L", "Brow_Raise_Inner_L"], "cc4"),
        (["h_expressions.LeyeClose_h", "h_expressions.MouthOpen_h", "t_MouthOpen_h"], "rocketbox"),
        (["happy", "blink", "blinkLeft", "aa", "relaxed"], "vrm1"),
        (["joy", "blink_l", "blink_r", "a", "sorrow"], "vrm0"),
    ],
)
def test_the_convention_is_detected_by_name_overlap(names: list[str], expected: str) -> None:
    assert match_names(names).convention == expected


def test_combined_shapes_report_and_costs() -> None:
    match = match_names(["browInnerUp_L", "browInnerUp_R", "eyeBlink_L", "cheekRaiser_L"])
    inner = [row for row in match.rows if row.arkit == "browInnerUp"]
    assert sorted(row.source for row in inner) == ["browInnerUp_L", "browInnerUp_R"]
    assert match.matched == ("browInnerUp_L", "browInnerUp_R", "eyeBlink_L")
    assert match.unmatched == ("cheekRaiser_L",)
    assert "eyeBlinkRight" in match.missing and "browInnerUp" not in match.missing
    assert match.au_cannot_show["AU12"] == ("mouthSmileLeft", "mouthSmileRight", "cheekSquintLeft", "cheekSquintRight")
    assert "AU1" not in match.au_cannot_show
    lacking = match_names(["eyeBlink_L", "eyeBlink_R"])
    assert "no browInnerUp: AU1 cannot show" in lacking.report().splitlines()


def test_an_exporter_prefix_is_dropped_when_the_exact_name_is_unknown() -> None:
    match = match_names(["Face.eyeBlinkLeft", "Face.jawOpen"])
    assert match.convention == "arkit"
    assert {row.arkit for row in match.rows} == {"eyeBlinkLeft", "jawOpen"}


def test_vrm_blink_is_split_into_left_and_right_halves() -> None:
    rows = [row for row in match_names(["blink"], convention="vrm1").rows if row.source == "blink"]
    assert {(row.arkit, row.side) for row in rows} == {("eyeBlinkLeft", "L"), ("eyeBlinkRight", "R")}


def test_toml_overrides_replace_rows_force_a_convention_and_unmap(tmp_path) -> None:
    path = tmp_path / "names.toml"
    path.write_text(
        'convention = "rocketbox"\n'
        "[targets]\n"
        '"h_expressions.Lsad_h" = "browInnerUp"\n'
        '"MySmile" = [{arkit = "mouthSmileLeft", side = "L", weight = 0.8}, {arkit = "mouthSmileRight", side = "R"}]\n'
        '"h_expressions.Kiss_h" = []\n',
        encoding="utf-8",
    )
    overrides = read_overrides(path)
    match = match_names(["h_expressions.Lsad_h", "MySmile", "h_expressions.Kiss_h", "eyeBlink_L"], overrides=overrides)
    assert match.convention == "rocketbox" and match.overrides == str(path)
    assert {(r.source, r.arkit, r.weight, r.side) for r in match.rows} == {
        ("h_expressions.Lsad_h", "browInnerUp", 1.0, ""),
        ("MySmile", "mouthSmileLeft", 0.8, "L"),
        ("MySmile", "mouthSmileRight", 1.0, "R"),
    }
    assert "h_expressions.Kiss_h" in match.unmatched and "mouthPucker" in match.missing


def test_bad_overrides_name_the_file_and_entry(tmp_path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("[targets\n", encoding="utf-8")
    with pytest.raises(InvalidValueError, match=r"bad\.toml"):
        read_overrides(bad)
    unknown = tmp_path / "unknown.toml"
    unknown.write_text('[targets]\n"x" = "mouthSmile"\n', encoding="utf-8")
    with pytest.raises(UnknownNameError, match=r"unknown.toml targets.x"):
        read_overrides(unknown)
    side = tmp_path / "side.toml"
    side.write_text('[targets]\n"x" = {arkit = "jawOpen", side = "middle"}\n', encoding="utf-8")
    with pytest.raises(InvalidValueError, match=r"side"):
        read_overrides(side)


def test_the_rocketbox_table_names_exactly_shapes_of_the_valid_avatars() -> None:
    root = shared_root()
    folder = None if root is None else root / "avatars" / "valid"
    if folder is None or not folder.is_dir():
        pytest.skip("VALID avatars not available: set MIEN_SHARED to the shared folder (needs avatars/valid)")
    names: set[str] = set()
    for path in sorted(folder.glob("*.glb")):
        data = path.read_bytes()
        document = json.loads(data[20 : 20 + int.from_bytes(data[12:16], "little")])
        own = [n for mesh in document["meshes"] for n in (mesh.get("extras") or {}).get("targetNames", [])]
        assert len(own) == 96, path.name
        match = match_names(own)
        assert (match.convention, len(match.matched), len(match.arkit_targets)) == ("rocketbox", 44, 36), path.name
        names.update(own)
    assert load_convention("rocketbox").source_names <= names
