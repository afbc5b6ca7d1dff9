"""``mien head inspect``: the report a user reads before trusting their character, and the landmark picture."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from tests.conftest import shared_root

from mien.cli import main

pytest.importorskip("moderngl", reason="moderngl not installed (render extra)")
pytest.importorskip("PIL", reason="Pillow not installed (render extra)")


def test_inspect_a_named_head_draws_its_landmarks(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    picture = tmp_path / "builtin.png"
    assert main(["head", "inspect", "builtin", "-o", str(picture)]) == 0
    out = capsys.readouterr().out
    assert "landmarks: 68 iBUG points built into the head" in out
    assert "outer eye corners 90.8 mm apart" in out
    from PIL import Image

    image = np.asarray(Image.open(picture).convert("RGB"))
    assert image.shape == (768, 768, 3)
    marked = (image[..., 0] > 200) & (image[..., 1] < 110) & (image[..., 2] < 80)  # the landmark colour
    assert marked.sum() > 68 * 6


def test_inspect_a_valid_avatar(tmp_path: Path, landmarker_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("mediapipe", reason="mediapipe not installed (track extra)")
    root = shared_root()
    avatar = None if root is None else root / "avatars" / "valid" / "Black_M_1_Casual.glb"
    if avatar is None or not avatar.is_file():
        pytest.skip("VALID avatars not available: set MIEN_SHARED to the shared folder (needs avatars/valid)")
    picture = tmp_path / "black_m.png"
    assert main(["head", "inspect", str(avatar), "-o", str(picture)]) == 0
    out = capsys.readouterr().out
    assert "naming convention: rocketbox" in out
    assert "no mouthClose: AU8 cannot show" in out  # a correction of another shape: not synthesized
    assert "synthesized (7, the reference head's moves through the feature-point fields):" in out
    assert "mouthStretchLeft" in out and "no mouthStretchLeft" not in out
    assert "landmarks: 68 iBUG points found on the head's render (seen from +z/+y" in out
    assert "mouth: modelled closed; 3 of 3 inner-lip pairs put one point on each lip" in out
    assert "file frame: unit m, up +y, forward +z" in out
    assert "driven harder, as far as the reference head" in out
    assert picture.stat().st_size > 10_000
