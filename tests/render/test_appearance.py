"""How heads look: face paint (brows, lash lines, lips) on ICT-FaceKit, the renderer's paint texture."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError
from mien.render.camera import CAMERA_PRESETS
from mien.render.face_paint import BROW_ALBEDO, LIP_ALBEDO, _paint, face_paint
from mien.render.offscreen import OffscreenRenderer
from mien.rig.builtin_head import builtin_head
from mien.rig.model import Rig

SIZE = 384
MakeRenderer = Callable[..., OffscreenRenderer]


def luminance(pixels: np.ndarray) -> np.ndarray:
    return np.asarray(pixels[..., :3].astype(float) @ [0.299, 0.587, 0.114])


# ---- the renderer's paint texture, on the generated head ----------------------------------------------------


def test_paint_with_zero_strength_changes_nothing(make_renderer: MakeRenderer, rig: Rig) -> None:
    camera = CAMERA_PRESETS["frontal-1m"]
    plain = make_renderer(rig.faces, 96, 96, camera).render(rig.neutral)
    black = np.zeros((4, 4, 4), np.float32)
    black[..., 3] = 1.0
    texcoords = np.zeros((rig.n_vertices, 3), np.float32)
    texcoords[:, :2] = 0.5
    unpainted = make_renderer(rig.faces, 96, 96, camera, texture=black, texcoords=texcoords).render(rig.neutral)
    assert np.array_equal(plain, unpainted)


def test_paint_covers_the_vertex_colour_where_strong(make_renderer: MakeRenderer, rig: Rig) -> None:
    camera = CAMERA_PRESETS["frontal-1m"]
    green = np.zeros((4, 4, 4), np.float32)
    green[..., 1] = green[..., 3] = 1.0  # premultiplied opaque green
    texcoords = np.full((rig.n_vertices, 3), 0.5, np.float32)
    texcoords[:, 2] = (rig.neutral[:, 0] > 0).astype(np.float32)  # paint only the +x half (image right)
    image = make_renderer(rig.faces, 96, 96, camera, texture=green, texcoords=texcoords).render(rig.neutral)
    face = np.abs(image.astype(int) - image[0, 0]).max(axis=2) > 3
    right, left = face.copy(), face.copy()
    right[:, :56], left[:, 40:] = False, False
    assert (image[right][:, 1] > 2 * image[right][:, 0]).mean() > 0.9
    assert (image[left][:, 0] > image[left][:, 1]).mean() > 0.9  # skin stays skin


def test_bad_paint_is_rejected(rig: Rig) -> None:
    camera = CAMERA_PRESETS["frontal-1m"]
    texcoords = np.zeros((rig.n_vertices, 3), np.float32)
    with pytest.raises(InvalidValueError, match="texture"):
        OffscreenRenderer(rig.faces, 8, 8, camera, texture=np.zeros((4, 4, 3)), texcoords=texcoords)
    with pytest.raises(InvalidValueError, match="texcoords"):
        OffscreenRenderer(rig.faces, 8, 8, camera, texture=np.zeros((4, 4, 4)), texcoords=texcoords[:, :2])
    with pytest.raises(InvalidValueError, match="texture"):
        OffscreenRenderer(rig.faces, 8, 8, camera, texcoords=texcoords)


# ---- which heads get paint -----------------------------------------------------------------------------------


def test_heads_that_paint_themselves_or_lack_landmarks_get_no_paint(rig: Rig) -> None:
    assert face_paint(builtin_head()) is None  # its own vertex_colors carry its brows
    assert face_paint(rig) is None  # all 68 landmarks on one vertex


# ---- ICT-FaceKit ---------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def ict_rig(ict_dir: Path) -> Rig:
    from mien.rig.ict_facekit import ict_identity_presets, load_ict_facekit

    return load_ict_facekit(ict_dir, identity=ict_identity_presets()["a"])


@pytest.fixture(scope="module")
def ict_frames(ict_rig: Rig) -> dict[str, np.ndarray]:
    """Frontal-1m renders of the neutral face and of both brows lowered (browDown), SIZE x SIZE."""
    from mien.render.clip_render import render_still
    from mien.render.offscreen import EGLUnavailableError

    weights = np.zeros(len(ict_rig.targets), np.float32)
    lowered = weights.copy()
    lowered[[ict_rig.target_index("browDownLeft"), ict_rig.target_index("browDownRight")]] = 1.0
    camera = CAMERA_PRESETS["frontal-1m"]
    try:
        return {
            "neutral": render_still(ict_rig, weights, camera, (SIZE, SIZE)),
            "browDown": render_still(ict_rig, lowered, camera, (SIZE, SIZE)),
        }
    except EGLUnavailableError as error:
        pytest.skip(f"no headless OpenGL here: {error}")


def pixel(rig: Rig, point: np.ndarray) -> tuple[int, int]:
    """(row, column) of a rig-frame point in a frontal-1m SIZE x SIZE image."""
    x, y = CAMERA_PRESETS["frontal-1m"].project(point, SIZE, SIZE)[0]
    return round(float(y)), round(float(x))


def test_ict_paint_is_deterministic_and_stays_on_the_front(ict_rig: Rig) -> None:
    paint, fresh = face_paint(ict_rig), _paint(ict_rig, 0)
    assert paint is not None and fresh is not None
    assert face_paint(ict_rig) is paint  # cached
    assert np.array_equal(paint.texture, fresh.texture)
    assert paint.texcoords.shape == (ict_rig.n_vertices, 3)
    strength = paint.texcoords[:, 2]
    assert np.all(strength[ict_rig.landmarks[17:68]] == 1.0)
    back = ict_rig.neutral[:, 2] < -0.06
    assert np.all(strength[back] == 0.0)
    assert np.all(strength[ict_rig.regions["teeth"]] == 0.0)


def test_ict_brows_are_dark_and_thickest_at_the_inner_end(ict_rig: Rig, ict_frames: dict[str, np.ndarray]) -> None:
    image = luminance(ict_frames["neutral"])
    lm = ict_rig.neutral[ict_rig.landmarks]
    for mid, inner, outer in ((19, 21, 17), (24, 22, 26)):
        brow = image[pixel(ict_rig, lm[mid] - [0, 0.003, 0])]
        forehead = image[pixel(ict_rig, lm[mid] + [0, 0.02, 0])]
        assert brow < 0.6 * forehead

        def dark_rows(landmark: int, toward_middle: float, mid: int = mid) -> int:
            point = lm[landmark] + toward_middle * (lm[mid] - lm[landmark])
            row, col = pixel(ict_rig, point)
            skin = image[pixel(ict_rig, point + np.array([0, 0.015, 0]))]
            column = image[row - 10 : row + 15, col]
            return int((column < 0.6 * skin).sum())

        assert dark_rows(inner, 0.4) > dark_rows(outer, 0.3) >= 1


def test_ict_brows_move_down_with_brow_down(ict_rig: Rig, ict_frames: dict[str, np.ndarray]) -> None:
    lm = ict_rig.neutral[ict_rig.landmarks]
    for landmark in (20, 23):  # the inner half, where browDown pulls
        row, col = pixel(ict_rig, lm[landmark])  # about 1 px per mm; the landmark marks the brow's top edge
        top_edges = []
        for name in ("neutral", "browDown"):
            image = luminance(ict_frames[name])
            skin = image[pixel(ict_rig, lm[landmark] + [0, 0.02, 0])]
            column = image[row - 8 : row + 30, col]
            top_edges.append(row - 8 + int(np.argmax(column < 0.6 * skin)))
        assert abs(top_edges[0] - row) <= 3  # a painted brow, not the shadow over the eye further down
        assert top_edges[1] >= top_edges[0] + 2  # rows grow downward


def test_ict_upper_lids_have_a_dark_lash_line(ict_rig: Rig, ict_frames: dict[str, np.ndarray]) -> None:
    image = luminance(ict_frames["neutral"])
    lm = ict_rig.neutral[ict_rig.landmarks]
    ratios = []
    for landmark in (37, 38, 43, 44):  # on the upper lid margin; about 1 px per mm
        row, col = pixel(ict_rig, lm[landmark])
        lid_skin = image[pixel(ict_rig, lm[landmark] + [0, 0.007, 0])]
        ratios.append(image[row - 3 : row, col].min() / lid_skin)  # just above the margin, on the lid
    assert np.mean(ratios) < 0.45  # unpainted, only the lid's shadow: about 0.7


def test_ict_lips_are_redder_than_skin(ict_rig: Rig, ict_frames: dict[str, np.ndarray]) -> None:
    image = ict_frames["neutral"].astype(float)
    lm = ict_rig.neutral[ict_rig.landmarks]

    def redness(point: np.ndarray) -> float:
        r, g, _ = image[pixel(ict_rig, point)]
        return float(r / max(g, 1.0))

    cheek = redness(lm[48] + [-0.012, 0.012, 0])
    for landmark in (51, 57):  # upper and lower lip, mid-line
        middle = lm[landmark] + 0.3 * (lm[62 if landmark == 51 else 66] - lm[landmark])
        assert redness(middle) > cheek + 0.25
    # A soft edge: just outside the outer contour the colour is between lip and skin, not lip.
    assert redness(lm[57] + [0, -0.004, 0]) < redness(lm[57] + [0, 0.002, 0])


def test_paint_colours_are_linear_albedo() -> None:
    for albedo in (BROW_ALBEDO, LIP_ALBEDO):
        assert all(0.0 <= c <= 1.0 for c in albedo)
    assert sum(BROW_ALBEDO) < 0.15
    assert LIP_ALBEDO[0] > 2 * LIP_ALBEDO[1]
