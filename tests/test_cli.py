import numpy as np
import pytest

from mien.cli import build_parser, main
from mien.exchange import reader_for


def test_help_lists_every_subcommand(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    out = capsys.readouterr().out
    for command in ("demo", "emote", "au", "render", "assets", "track", "learn", "laugh", "validate"):
        assert command in out
    assert build_parser().prog == "mien"


def test_emote_saves_curves_and_plot(tmp_path, capsys):
    csv, png = tmp_path / "joy.csv", tmp_path / "joy.png"
    assert main(["emote", "joy", "--intensity", "2.4", "--duration", "2", "-o", str(csv), "--plot", str(png)]) == 0
    clip = reader_for(csv)(csv)
    assert clip.n_frames == 120 and clip.fps == pytest.approx(60.0)
    assert clip.channel("AU12L").max() == pytest.approx(5.0, abs=0.01)  # 2.4 x 3.5 saturates softly toward E
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"


def test_au_prints_active_channels_as_csv(capsys):
    assert main(["au", "AU6C", "AU12C", "--duration", "1", "--no-idle", "--tau", "0.1"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0] == "time_s,AU6L,AU6R,AU12L,AU12R"
    last = [float(v) for v in lines[-1].split(",")]
    assert last[1:] == pytest.approx([3.0, 3.0, 3.0, 3.0], abs=0.01)


def test_au_speed_mode_and_json(tmp_path):
    out = tmp_path / "au.json"
    assert (
        main(["au", "AU4E", "--speed", "0.05", "--duration", "1.2", "--start", "0.2", "--no-idle", "-o", str(out)]) == 0
    )
    clip = reader_for(out)(out)
    expected = 5.0 * (1 - 0.95**60)  # OpenFACS: 60 ticks of 5% after one second
    assert clip.channel("AU4L")[-1] == pytest.approx(expected, abs=0.1)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["emote", "glee"], "unknown emotion 'glee'"),
        (["emote", "joy", "--intensity", "7"], "intensity=7.0"),
        (["emote", "joy", "--intensity", "nan"], "intensity=nan"),
        (["emote", "joy", "--hold", "-1"], "argument --hold: seconds '-1' must be >= 0"),
        (["au", "AU99"], "unknown action unit 'AU99'"),
        (["au", "AU12X"], "AU12X"),
        (["render", "joy", "--size", "0x10"], "size"),
        (["render", "joy", "--camera", "overhead"], "camera preset"),
    ],
)
def test_bad_input_gives_a_clear_error_and_exit_code_2(argv, message, capsys):
    assert main(argv) == 2
    assert message in capsys.readouterr().err


def test_render_still_png_on_the_builtin_head(tmp_path):
    pytest.importorskip("moderngl")
    out = tmp_path / "surprise.png"
    assert main(["render", "surprise", "--head", "builtin", "--size", "128x128", "-o", str(out)]) == 0
    from PIL import Image

    image = np.asarray(Image.open(out))
    assert image.shape == (128, 128, 3)
    assert image.std() > 10  # a lit face, not a blank frame


def test_demo_writes_video_contact_sheet_and_curves(tmp_path, capsys):
    pytest.importorskip("moderngl")
    from mien.render.video import read_video_info

    out = tmp_path / "demo"
    assert main(["demo", "--head", "builtin", "--size", "96x96", "--fps", "5", "-o", str(out)]) == 0
    info = read_video_info(out / "demo.mp4")
    assert info.n_frames == 100 and info.codec == "h264" and info.fps == pytest.approx(5.0)
    assert (out / "demo_contact_sheet.png").stat().st_size > 5_000
    assert reader_for(out / "demo_curves.csv")(out / "demo_curves.csv").n_frames == 100
    printed = capsys.readouterr().out
    assert "demo.mp4" in printed and "demo_contact_sheet.png" in printed


def test_render_a_clip_file_with_a_subset_of_channels(tmp_path):
    pytest.importorskip("moderngl")
    from PIL import Image

    clip_file = tmp_path / "smile.csv"
    clip_file.write_text("time_s,AU12L,AU12R\n0,0,0\n0.5,4,4\n1.0,0,0\n")
    smile, neutral = tmp_path / "smile.png", tmp_path / "neutral.png"
    assert main(["render", str(clip_file), "--head", "builtin", "--size", "128x128", "-o", str(smile)]) == 0
    still = tmp_path / "still.csv"
    still.write_text("time_s,AU12L,AU12R\n0,0,0\n0.5,0,0\n1.0,0,0\n")
    assert main(["render", str(still), "--head", "builtin", "--size", "128x128", "-o", str(neutral)]) == 0
    difference = np.abs(np.asarray(Image.open(smile), float) - np.asarray(Image.open(neutral), float))
    assert difference.max() > 30  # the peak frame (AU12 at D) was rendered, not the neutral first frame
    bad = tmp_path / "bad.csv"
    bad.write_text("time_s,AU99\n0,0\n")
    assert main(["render", str(bad), "-o", str(tmp_path / "bad.png")]) == 2


def test_the_demo_says_which_head_it_used_and_how_to_get_the_realistic_one(tmp_path, monkeypatch):
    from mien.commands.demo import head_line

    monkeypatch.setenv("MIEN_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.setenv("MIEN_CONFIG", str(tmp_path / "no-config.toml"))
    monkeypatch.delenv("MIEN_ICT_FACEKIT", raising=False)
    assert head_line("builtin", 14883, 52, "portrait") == (
        "head: builtin (the stylised built-in head: 14,883 vertices, 52 morph targets); camera: portrait; "
        "for the realistic head run `mien assets fetch ict-facekit` (190 MB), then this again"
    )
    (tmp_path / "data" / "ict-facekit").mkdir(parents=True)  # where the fetch installs
    assert head_line("builtin-b", 14883, 52, "portrait").endswith("; the realistic head is installed: add --head ict")
    assert head_line("ict-facekit", 26719, 60, "portrait") == (
        "head: ict-facekit (the realistic head: 26,719 vertices, 60 morph targets); camera: portrait"
    )
