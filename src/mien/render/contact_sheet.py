"""Contact sheets: a grid of labelled images in one picture (save it with :func:`mien.render.write_png`)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from mien.errors import InvalidValueError
from mien.extras import require

__all__ = ["contact_sheet"]


def contact_sheet(
    images: Sequence[np.ndarray],
    labels: Sequence[str] | None = None,
    columns: int | None = None,
    padding: int = 8,
    font_size: int = 14,
    background: tuple[int, int, int] = (255, 255, 255),
    text_color: tuple[int, int, int] = (20, 20, 20),
) -> np.ndarray:
    """One (H, W, 3) uint8 image tiling ``images`` ((h, w, 3) uint8 each) row by row, ``labels`` under each.

    ``columns`` defaults to a near-square grid (ceil(sqrt(n))). A label may have several lines
    (``"\n"``). Tiles of different sizes are centred in
    cells as large as the largest image. ``padding`` pixels separate the cells; ``font_size`` is the label
    height in pixels (Pillow's default font).

    >>> sheet = contact_sheet([np.zeros((32, 32, 3), np.uint8)] * 3, ["a", "b", "c"], columns=2)
    >>> sheet.shape[1] == 2 * 32 + 3 * 8, sheet.dtype
    (True, dtype('uint8'))
    """
    if len(images) == 0:
        raise InvalidValueError("images", 0, "at least one image")
    checked = []
    for index, image in enumerate(images):
        image = np.asarray(image)
        if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8 or 0 in image.shape:
            raise InvalidValueError(f"images[{index}]", (image.shape, str(image.dtype)), "(h, w, 3) uint8")
        checked.append(image)
    if labels is None:
        labels = [""] * len(checked)
    if len(labels) != len(checked):
        raise InvalidValueError("labels", len(labels), f"one label per image ({len(checked)})")
    if columns is None:
        columns = math.ceil(math.sqrt(len(checked)))
    if isinstance(columns, bool) or not isinstance(columns, int) or columns < 1:
        raise InvalidValueError("columns", columns, "an integer >= 1")
    if padding < 0 or font_size < 1:
        raise InvalidValueError("padding/font_size", (padding, font_size), "padding >= 0 and font_size >= 1")
    require("PIL", "render")
    from PIL import Image, ImageDraw, ImageFont

    rows = math.ceil(len(checked) / columns)
    tile_h = max(image.shape[0] for image in checked)
    tile_w = max(image.shape[1] for image in checked)
    lines = max(label.count("\n") + 1 for label in labels)
    label_h = int(font_size * 1.5 * lines) if any(labels) else 0
    cell_h = tile_h + label_h
    sheet = Image.new("RGB", (columns * tile_w + (columns + 1) * padding, rows * (cell_h + padding) + padding))
    sheet.paste(tuple(background), (0, 0, *sheet.size))
    draw = ImageDraw.Draw(sheet)
    font = ImageFont.load_default(size=font_size)
    for index, (image, label) in enumerate(zip(checked, labels, strict=True)):
        row, column = divmod(index, columns)
        left = padding + column * (tile_w + padding)
        top = padding + row * (cell_h + padding)
        h, w = image.shape[:2]
        sheet.paste(Image.fromarray(image), (left + (tile_w - w) // 2, top + (tile_h - h) // 2))
        for line_number, line in enumerate(str(label).split("\n") if label else []):
            text = line
            # Shorten a line that does not fit under its tile.
            while len(text) > 1 and draw.textlength(text, font=font) > tile_w:
                text = text[:-2] + "…"
            width = draw.textlength(text, font=font)
            y = top + tile_h + font_size * (0.2 + 1.5 * line_number)
            draw.text((left + (tile_w - width) / 2, y), text, fill=text_color, font=font)
    return np.asarray(sheet)
