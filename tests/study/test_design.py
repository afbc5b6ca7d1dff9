"""Design files: the full Broekens and Mascaró designs parse; every unknown name or bad value is a typed
error naming the file and key, and ``mien study`` answers it with exit 2; participant plans."""

from __future__ import annotations

import itertools
from collections import Counter
from importlib import resources
from pathlib import Path

import pytest

from mien.cli import main
from mien.errors import InvalidValueError, MissingAssetError, UnknownNameError
from mien.study.design import BROEKENS_EXPRESSIONS, load_design
from mien.study.protocol import balanced_latin_square, participant_plan, questions

FULL = resources.files("mien.study").joinpath("data/broekens_full.toml").read_text(encoding="utf-8")
"""The shipped example: the paper's full design."""


def write(tmp_path: Path, text: str, name: str = "design.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_full_broekens_design(tmp_path: Path) -> None:
    design = load_design(write(tmp_path, FULL))
    assert design.name == "broekens-replication" and design.protocol == "broekens"
    assert len(design.stimuli) == 10 * 2 * 2 * 2 * 2
    assert [s.id for s in design.stimuli[:3]] == ["s001", "s002", "s003"]
    assert {s.expression for s in design.stimuli} == set(BROEKENS_EXPRESSIONS)
    first = design.stimuli[0]
    assert first.conditions == {
        "head": "default", "identity": "", "basis": "facs", "view": "frontal", "distance_m": 1.0, "intensity": 1.2
    }  # fmt: skip
    assert design.levels("view") == ("frontal", "lateral")
    assert design.within == ("basis", "view", "distance_m", "intensity")
    assert len(design.sha256) == 64


def test_mascaro_design_with_descriptions(tmp_path: Path) -> None:
    text = """
[study]
name = "laughs"
protocol = "mascaro"
[stimuli]
laughter_types = ["sly_smile", "false_laughter"]
[stimuli.descriptions]
sly_smile = "A sly, knowing smile"
"""
    design = load_design(write(tmp_path, text))
    assert [s.conditions for s in design.stimuli] == [
        {"laughter_type": "sly_smile", "description": "A sly, knowing smile"},
        {"laughter_type": "false_laughter", "description": "False laughter"},
    ]
    assert [q.key for q in questions("mascaro")] == ["feels_right", "represents_description"]
    with pytest.raises(InvalidValueError, match=r"stimuli\.heads"):
        load_design(write(tmp_path, text.replace("[stimuli]", '[stimuli]\nheads = ["ict:a"]')))


@pytest.mark.parametrize(
    ("old", "new", "error", "named"),
    [
        ('"evil", "furious"', '"evil", "smug"', UnknownNameError, "smug"),
        ('within = ["basis"', 'within = ["lighting"', UnknownNameError, "lighting"),
        ('views = ["frontal"', 'views = ["overhead"', UnknownNameError, "overhead"),
        ('bases = ["facs"', 'bases = ["blendshapes"', UnknownNameError, "blendshapes"),
        ('heads = ["default"]', 'heads = ["robot"]', UnknownNameError, "robot"),
        ('order = "counterbalanced"', 'order = "alphabetical"', UnknownNameError, "alphabetical"),
        ('protocol = "broekens"', 'protocol = "ekman"', UnknownNameError, "ekman"),
        ("size = 256", "size = 255", InvalidValueError, "255"),
        ("intensities = [1.2, 2.4]", "intensities = [1.2, 9.0]", InvalidValueError, "9.0"),
        ("fps = 30", "fps = 30\ncolour = 1", UnknownNameError, "colour"),
    ],
)
def test_bad_design_names_file_and_key(tmp_path: Path, old: str, new: str, error: type, named: str) -> None:
    assert old in FULL
    path = write(tmp_path, FULL.replace(old, new))
    with pytest.raises(error) as caught:
        load_design(path)
    assert str(path) in str(caught.value) and named in str(caught.value)


def test_cli_bad_design_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, FULL.replace('"evil", "furious"', '"evil", "smug"'))
    assert main(["study", "stimuli", str(path)]) == 2
    message = capsys.readouterr().err
    assert "mien study: error:" in message and "'smug'" in message and str(path) in message
    assert main(["study", "stimuli", str(tmp_path / "missing.toml")]) == 2
    missing = capsys.readouterr().err
    assert "no such file" in missing and "missing.toml" in missing and "did you mean" in missing
    broken = write(tmp_path, "[study\nname=", "broken.toml")
    assert main(["study", "serve", str(broken)]) == 2
    assert "valid UTF-8 TOML" in capsys.readouterr().err


def test_missing_design_file(tmp_path: Path) -> None:
    with pytest.raises(MissingAssetError, match=r"nope\.toml"):
        load_design(tmp_path / "nope.toml")


@pytest.mark.parametrize("n", [2, 3, 4, 5, 16])
def test_balanced_latin_square_is_balanced(n: int) -> None:
    rows = [balanced_latin_square(n, r) for r in range(n if n % 2 == 0 else 2 * n)]
    for row in rows:
        assert sorted(row) == list(range(n))
    for position in range(n):  # each condition equally often at each position
        assert len(set(Counter(row[position] for row in rows).values())) == 1
    pairs = Counter((a, b) for row in rows for a, b in itertools.pairwise(row))
    assert len(pairs) == n * (n - 1) and len(set(pairs.values())) == 1  # each ordered pair equally often


def test_participant_plan(tmp_path: Path) -> None:
    design = load_design(write(tmp_path, FULL))
    plan = participant_plan(design, "p-1", 0)
    assert sorted(plan.sequence) == sorted(s.id for s in design.stimuli)
    assert plan == participant_plan(design, "p-1", 0)  # seeded: the same participant gets the same plan
    assert plan.label_order[-1] == "naturalness"
    assert sorted(plan.label_order[:-1]) == sorted(f"label:{e}" for e in BROEKENS_EXPRESSIONS)
    orders = {participant_plan(design, f"p{k}", 0).label_order for k in range(8)}
    assert len(orders) > 4  # label order differs between participants
    by_id = {s.id: s for s in design.stimuli}
    within = ("basis", "view", "distance_m", "intensity")
    blocks = [tuple(by_id[s].conditions[f] for f in within) for s in plan.sequence]
    assert len(set(blocks)) == 16
    for k in range(16):  # each block's ten expressions are contiguous
        assert len(set(blocks[k * 10 : (k + 1) * 10])) == 1
    first_blocks = {participant_plan(design, f"p{k}", k).block_order[0] for k in range(16)}
    assert first_blocks == set(range(16))  # the Latin square over participants


def test_between_subject_factor(tmp_path: Path) -> None:
    text = FULL.replace('heads = ["default"]', 'heads = ["builtin", "builtin:b"]')
    design = load_design(write(tmp_path, text))
    seen = []
    for ordinal in range(4):
        plan = participant_plan(design, f"p{ordinal}", ordinal)
        identities = {s.conditions["identity"] for s in design.stimuli if s.id in plan.sequence}
        assert len(identities) == 1 and len(plan.sequence) == 160
        seen.append(identities.pop())
    assert seen == ["", "b", "", "b"]


def test_a_users_character_file_is_a_head(tmp_path: Path) -> None:
    """A design names a character file as it names supplied videos: relative to the design file, or with file:."""
    (tmp_path / "avatars").mkdir()
    (tmp_path / "avatars" / "me.glb").write_bytes(b"glTF")  # read when the stimuli are rendered, not here
    text = FULL.replace('heads = ["default"]', 'heads = ["avatars/me.glb", "file:avatars/me.glb", "builtin:b"]')
    design = load_design(write(tmp_path, text))
    heads = {(s.conditions["head"], s.conditions["identity"]) for s in design.stimuli}
    assert heads == {("file", str((tmp_path / "avatars" / "me.glb").resolve())), ("builtin", "b")}
    for missing in ("avatars/you.glb", "file:avatars/you.glb", "avatars/"):
        path = write(tmp_path, FULL.replace('heads = ["default"]', f'heads = ["{missing}"]'))
        with pytest.raises(InvalidValueError) as caught:
            load_design(path)
        message = str(caught.value)
        assert "stimuli.heads" in message and missing in message and "relative to the design file" in message
