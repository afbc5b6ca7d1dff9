"""mien export / mien import / mien render with any readable format and laugh types."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mien.cli import main
from mien.exchange import format_for, read_clip

OPENFACE = "formats/OpenFace_Test.csv"


def test_import_openface_then_export_everywhere(shared_data: Path, tmp_path: Path, capsys) -> None:
    clip_path = tmp_path / "of.npz"
    assert main(["import", str(shared_data / OPENFACE), "-o", str(clip_path)]) == 0
    assert "100 frames at 1000 fps (AU clip" in capsys.readouterr().out
    clip = read_clip(clip_path)
    glb_path = tmp_path / "of.glb"
    assert main(["export", str(clip_path), "-o", str(glb_path), "--head", "builtin", "--fps", "100"]) == 0
    assert read_clip(glb_path).n_frames == 10  # 0.099 s at 100 fps
    live = tmp_path / "live.csv"
    assert main(["export", str(glb_path), "-o", str(live), "--format", "arkit_csv"]) == 0
    assert format_for(live) == "arkit_csv"
    back = tmp_path / "back.json"
    assert main(["import", str(live), "-o", str(back), "--au"]) == 0
    assert read_clip(back).n_frames == 10
    states = tmp_path / "of.jsonl"
    assert main(["export", str(clip_path), "-o", str(states)]) == 0
    np.testing.assert_allclose(read_clip(states).values, clip.values, atol=1e-12)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["export", "{clip}", "-o", "{tmp}/x.anim", "--head", "ict"], "--head='ict' is invalid: expected no --head"),
        (["export", "{clip}", "-o", "{tmp}/x.xyz"], "unknown output file suffix '.xyz'"),
        (["export", "{clip}", "-o", "{tmp}/x.csv", "--format", "openface_csv"], "a format that can write"),
        (["import", "{clip}", "-o", "{tmp}/x.glb"], "a mien clip path ending in .npz or .json"),
        (["import", "{clip}", "-o", "{tmp}/x.npz", "--au"], "no --au"),
        (["export", "{tmp}/bad.csv", "-o", "{tmp}/x.json"], "bad.csv line 3 column 2 (AU12L)"),
        (["render", "{clip}", "--seed", "3", "-o", "{tmp}/x.png"], "no --seed"),
        (["render", "laughter", "--no-idle", "-o", "{tmp}/x.png"], "no --no-idle"),
    ],
)
def test_mistakes_exit_2_with_one_line(tmp_path: Path, capsys, argv: list[str], message: str) -> None:
    clip = tmp_path / "clip.csv"
    clip.write_text("time_s,AU12L\n0,1\n0.1,2\n")
    (tmp_path / "bad.csv").write_text("time_s,AU12L\n0,1\n0.1,NaN\n")
    filled = [a.format(clip=clip, tmp=tmp_path) for a in argv]
    assert main(filled) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_render_a_laugh_type_and_a_live_link_file(tmp_path: Path) -> None:
    pytest.importorskip("moderngl")
    from PIL import Image

    laugh = tmp_path / "laugh.png"
    assert main(["render", "laughter", "--head", "builtin", "--size", "96", "-o", str(laugh), "--seed", "2"]) == 0
    neutral_clip = tmp_path / "neutral.csv"
    neutral_clip.write_text("time_s,AU12L\n0,0\n0.1,0\n")
    neutral = tmp_path / "neutral.png"
    assert main(["render", str(neutral_clip), "--head", "builtin", "--size", "96", "-o", str(neutral)]) == 0
    difference = np.abs(np.asarray(Image.open(laugh), float) - np.asarray(Image.open(neutral), float))
    assert difference.max() > 30  # the laugh's strongest frame, not a neutral face
