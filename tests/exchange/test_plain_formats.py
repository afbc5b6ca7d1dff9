import numpy as np
import pytest

from mien import Clip, InvalidValueError, UnknownNameError
from mien.character import Character
from mien.exchange import reader_for, writer_for


@pytest.mark.parametrize("suffix", [".csv", ".json", ".npz"])
def test_character_clip_round_trips_through_each_plain_format(tmp_path, suffix):
    character = Character(seed=3)
    character.emote("evil", 1.2, start_s=0.1)
    clip = character.run(1.5, fps=30)
    path = tmp_path / f"curves{suffix}"
    writer_for(path)(clip, path)
    back = reader_for(path)(path)
    assert back.channels == clip.channels
    assert back.fps == pytest.approx(clip.fps)
    np.testing.assert_array_equal(back.values, clip.values)


def test_csv_is_readable_by_column_name(tmp_path):
    clip = Clip(np.array([[0.0, 1.0], [0.5, 2.0]]), 10.0, ("AU12L", "AU6L"))
    path = writer_for("x.csv")(clip, tmp_path / "c.csv")
    header = path.read_text().splitlines()[0]
    assert header == "time_s,AU12L,AU6L"


def test_unknown_suffix_and_malformed_files(tmp_path):
    with pytest.raises(UnknownNameError, match=r"\.xyz"):
        writer_for("curves.xyz")
    bad = tmp_path / "bad.csv"
    bad.write_text("time_s,AU12L\n0.0,abc\n")
    with pytest.raises(InvalidValueError, match=r"bad\.csv"):
        reader_for(bad)(bad)
    nohead = tmp_path / "nohead.csv"
    nohead.write_text("a,b\n1,2\n")
    with pytest.raises(InvalidValueError, match="time_s"):
        reader_for(nohead)(nohead)
