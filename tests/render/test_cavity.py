"""Baked mouth-interior occlusion: dark deep inside, unchanged outside and on the front teeth."""

from __future__ import annotations

import numpy as np

from mien.render.cavity import DEPTH_M, FLOOR, INTERIOR_REGIONS, cavity_shade
from mien.rig.builtin_head import builtin_head
from mien.rig.model import Rig


def test_shade_falls_with_depth_behind_the_front_teeth() -> None:
    rig = builtin_head()
    shade = cavity_shade(rig)
    inside = np.zeros(rig.n_vertices, bool)
    for name in INTERIOR_REGIONS:
        if name in rig.regions:
            inside[np.asarray(rig.regions[name], np.int64)] = True
    assert inside.any() and np.all(shade[~inside] == 1.0)
    ids = np.flatnonzero(inside)
    z = rig.neutral[ids, 2]
    assert shade[ids[np.argmax(z)]] > 0.99  # the most forward tooth keeps its colour
    deep = ids[z < z.max() - 3 * DEPTH_M]
    if deep.size:
        assert shade[deep].max() < FLOOR + (1 - FLOOR) * np.exp(-3) + 1e-6
    order = np.argsort(-z)
    assert np.all(np.diff(shade[ids][order]) <= 1e-6)  # deeper is never brighter


def test_rig_without_a_mouth_interior_is_unchanged() -> None:
    head = builtin_head()
    bare = Rig("bare", head.neutral, head.faces, (), head.landmarks)
    np.testing.assert_array_equal(cavity_shade(bare), np.ones(head.n_vertices, np.float32))


def test_every_output_gets_the_shade_through_the_rigs_colours() -> None:
    """Renders, glTF exports and the viewer all take a rig's colours from ``rig_vertex_colors``: one appearance."""
    from mien.exchange.glb import _appearance
    from mien.render.appearance import rig_vertex_colors

    rig = builtin_head()
    shade = cavity_shade(rig)
    colors = rig_vertex_colors(rig)
    dark = np.flatnonzero(shade < 0.5)
    assert dark.size > 100
    unshaded = np.asarray(rig.vertex_colors, np.float32)
    np.testing.assert_allclose(colors, unshaded * shade[:, None], rtol=1e-6)
    exported, _, _ = _appearance(rig)
    np.testing.assert_allclose(exported[dark], colors[dark], rtol=1e-6)  # the glTF's back teeth are dark too
