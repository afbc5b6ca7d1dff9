"""Contact sheets tile images with labels underneath."""

from __future__ import annotations

import numpy as np
import pytest

from mien.errors import InvalidValueError
from mien.render.contact_sheet import contact_sheet
from mien.render.video import write_png


def test_tiles_are_placed_row_by_row_with_labels_below(tmp_path) -> None:  # type: ignore[no-untyped-def]
    tiles = [np.full((40, 60, 3), value, np.uint8) for value in (0, 80, 160)]
    sheet = contact_sheet(tiles, ["neutral", "happy", "sad"], columns=2, padding=4, font_size=12)
    label_h = 18
    assert sheet.shape == (2 * (40 + label_h + 4) + 4, 2 * 60 + 3 * 4, 3)
    assert (sheet[4:44, 4:64] == 0).all()  # first tile, top left
    assert (sheet[4:44, 68:128] == 80).all()  # second tile, top right
    assert (sheet[4 + 62 : 44 + 62, 4:64] == 160).all()  # third tile starts the second row
    under_first = sheet[44 : 44 + label_h, 4:64]
    assert (under_first < 128).any()  # the label's dark text
    assert (sheet[44 + 62 : 44 + 62 + label_h, 68:128] == 255).all()  # no tile, no label
    assert write_png(sheet, tmp_path / "sheet.png").stat().st_size > 0


def test_bad_input_is_rejected() -> None:
    tile = np.zeros((8, 8, 3), np.uint8)
    with pytest.raises(InvalidValueError, match="labels"):
        contact_sheet([tile, tile], ["one"])
    with pytest.raises(InvalidValueError, match="images"):
        contact_sheet([])
    with pytest.raises(InvalidValueError, match=r"images\[0\]"):
        contact_sheet([np.zeros((8, 8), np.float32)], ["x"])
    with pytest.raises(InvalidValueError, match="columns"):
        contact_sheet([tile], ["x"], columns=0)
