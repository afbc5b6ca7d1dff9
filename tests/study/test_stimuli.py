"""Stimuli: tiny rendered designs become decodable MP4s with hashes in an atomic manifest; a re-run resumes;
a late failure keeps the finished videos; supplied files are checked (missing, corrupt -> exit 2)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mien.cli import main
from mien.errors import InvalidValueError, MissingAssetError
from mien.render.video import read_video_info
from mien.study import stimuli as stimuli_module
from mien.study.design import load_design
from mien.study.stimuli import file_sha256, load_manifest, make_stimuli

TINY = """
[study]
name = "tiny"
protocol = "broekens"
[stimuli]
expressions = ["joy", "anger"]
heads = ["builtin"]
views = ["frontal", "lateral"]
duration_s = 0.8
fps = 10
size = 64
[design]
within = ["view"]
"""


def test_render_manifest_and_resume(tmp_path: Path) -> None:
    design_path = tmp_path / "design.toml"
    design_path.write_text(TINY)
    design = load_design(design_path)
    result = make_stimuli(design, progress=False)
    folder = tmp_path / "stimuli"
    assert result.manifest_path == folder / "manifest.json" and (result.rendered, result.skipped) == (4, 0)
    manifest = json.loads(result.manifest_path.read_text())
    assert manifest["study"] == "tiny" and manifest["protocol"] == "broekens"
    assert manifest["design_sha256"] == design.sha256
    assert [e["id"] for e in manifest["stimuli"]] == ["s001", "s002", "s003", "s004"]
    entry = manifest["stimuli"][2]
    assert entry["expression"] == "joy" and entry["conditions"]["view"] == "lateral"
    assert set(entry["conditions"]) == {"head", "identity", "basis", "view", "distance_m", "intensity"}
    for e in manifest["stimuli"]:
        video = folder / e["file"]
        assert file_sha256(video) == e["sha256"]
        info = read_video_info(video)
        assert (info.width, info.height, info.codec, info.n_frames) == (64, 64, "h264", 8)
        assert e["duration_s"] == pytest.approx(0.8) and e["fps"] == 10
    assert load_manifest(folder)["stimuli"] == manifest["stimuli"]
    # a re-run skips everything; a damaged video is rendered again
    (folder / "s002.mp4").write_bytes(b"garbage")
    with pytest.raises(InvalidValueError, match=r"s002\.mp4"):
        load_manifest(folder)
    again = make_stimuli(design, progress=False)
    assert (again.rendered, again.skipped) == (1, 3)
    assert again.manifest == manifest


def test_late_failure_keeps_finished_videos(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    design_path = tmp_path / "design.toml"
    design_path.write_text(TINY)
    design = load_design(design_path)
    real = stimuli_module._render
    calls = []

    def failing(design, spec, scenes, video, *head):  # type: ignore[no-untyped-def]
        calls.append(spec.id)
        if spec.id == "s003":
            raise RuntimeError("disk full")
        return real(design, spec, scenes, video, *head)

    monkeypatch.setattr(stimuli_module, "_render", failing)
    with pytest.raises(RuntimeError, match="disk full"):
        make_stimuli(design, progress=False)
    folder = tmp_path / "stimuli"
    assert not (folder / "manifest.json").exists()
    assert (folder / "s001.mp4").is_file() and (folder / "s002.mp4").is_file()
    monkeypatch.setattr(stimuli_module, "_render", real)
    result = make_stimuli(design, progress=False)
    assert (result.rendered, result.skipped) == (2, 2)


def test_mascaro_render(tmp_path: Path) -> None:
    path = tmp_path / "laughs.toml"
    path.write_text(
        '[study]\nname = "laughs"\nprotocol = "mascaro"\n'
        '[stimuli]\nlaughter_types = ["sly_smile"]\nduration_s = 0.5\nfps = 8\nsize = 48\n'
    )
    result = make_stimuli(load_design(path), tmp_path / "out", progress=False)
    entry = result.manifest["stimuli"][0]
    assert entry["conditions"] == {"laughter_type": "sly_smile", "description": "Sly smile"}
    assert entry["duration_s"] > 0.5  # the whole laugh, not cut at duration_s
    assert read_video_info(tmp_path / "out" / entry["file"]).n_frames == round(entry["duration_s"] * 8)


def files_design(tmp_path: Path, entries: list[tuple[str, str]]) -> Path:
    lines = ['[study]\nname = "supplied"\nprotocol = "broekens"\n[stimuli]\nsource = "files"\n']
    for file, expression in entries:
        lines.append(f'[[stimuli.file]]\npath = "{file}"\nexpression = "{expression}"\n')
        lines.append('conditions = { view = "frontal", intensity = 2.4 }\n')
    path = tmp_path / "design.toml"
    path.write_text("".join(lines))
    return path


def test_supplied_files(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    made = make_stimuli(load_design(_tiny(tmp_path / "src")), progress=False)
    good = made.manifest_path.parent / "s001.mp4"
    path = files_design(tmp_path, [(str(good), "joy")])
    assert main(["study", "stimuli", str(path)]) == 0
    manifest = load_manifest(tmp_path / "stimuli")
    assert manifest["stimuli"][0]["sha256"] == file_sha256(good)
    assert manifest["stimuli"][0]["conditions"] == {"view": "frontal", "intensity": 2.4}
    # missing file
    path = files_design(tmp_path, [(str(good), "joy"), ("nowhere.mp4", "anger")])
    assert main(["study", "stimuli", str(path)]) == 2
    assert "nowhere.mp4 not found" in capsys.readouterr().err
    # corrupt file
    corrupt = tmp_path / "corrupt.mp4"
    corrupt.write_bytes(good.read_bytes()[:200] + bytes(range(256)) * 8)
    path = files_design(tmp_path, [(str(corrupt), "anger")])
    assert main(["study", "stimuli", str(path)]) == 2
    err = capsys.readouterr().err
    assert "corrupt.mp4" in err and "mien study: error:" in err
    # unknown condition in a file entry
    path.write_text(path.read_text().replace("view =", "lighting ="))
    assert main(["study", "stimuli", str(path)]) == 2
    assert "'lighting'" in capsys.readouterr().err


def test_missing_manifest(tmp_path: Path) -> None:
    with pytest.raises(MissingAssetError, match="mien study stimuli"):
        load_manifest(tmp_path)


def _tiny(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "design.toml"
    path.write_text(TINY.replace('views = ["frontal", "lateral"]', 'views = ["frontal"]'))
    return path


@pytest.mark.filterwarnings("ignore:AU mapping.*lacks targets mouthClose")  # the VALID avatars have no mouthClose
def test_stimuli_render_on_a_users_character(tmp_path: Path) -> None:
    """A perception study on the user's own character: the design names the file, the stimuli are drawn with its
    textures, and the manifest records the file and its hash (a changed file renders them again)."""
    from tests.conftest import valid_avatar

    avatar = valid_avatar("Black_M_1_Casual.glb")
    (tmp_path / "me.glb").symlink_to(avatar)
    design_path = tmp_path / "design.toml"
    design_path.write_text(TINY.replace('heads = ["builtin"]', 'heads = ["me.glb"]').replace(', "lateral"', ""))
    result = make_stimuli(load_design(design_path), progress=False)
    assert (result.rendered, result.skipped) == (2, 0)
    for entry in result.manifest["stimuli"]:
        assert entry["conditions"]["head"] == "file"
        assert entry["rendered_head"] == {
            "head": "file", "identity": str(avatar.resolve()), "asset_sha256": file_sha256(avatar)
        }  # fmt: skip
        info = read_video_info(tmp_path / "stimuli" / entry["file"])
        assert (info.width, info.height, info.n_frames) == (64, 64, 8)
