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
