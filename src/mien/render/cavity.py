"""Baked ambient occlusion of the mouth's interior: the deeper inside the mouth, the less light reaches it.

The renderer has no shadows, so without this the back teeth, tongue and palate of an open mouth are lit as
brightly as the cheek: an open mouth reads as a lit, toothy grin instead of a dark opening. Real light enters
the oral cavity only through the lips, and falls off with depth behind them. This is the usual real-time
answer (a baked cavity / ambient-occlusion term in the vertex colours): each vertex of the interior regions
(:data:`INTERIOR_REGIONS`) has its albedo multiplied by

``FLOOR + (1 - FLOOR) * exp(-depth / DEPTH_M)``

where ``depth`` is how far (metres, along the face's forward axis, in the neutral) it sits behind the front
of the teeth (the teeth's most forward vertex). The front incisors keep their colour; the molars and the back
of the tongue fall to a little above :data:`FLOOR`. The factor is a property of the rest shape, so it moves
with the jaw and costs nothing per frame.

>>> from mien.rig.builtin_head import builtin_head
>>> rig = builtin_head()
>>> shade = cavity_shade(rig)
>>> float(shade.max()), bool(shade.min() >= FLOOR)
(1.0, True)
"""

from __future__ import annotations

import numpy as np

from mien.rig.model import Rig

__all__ = ["DEPTH_M", "FLOOR", "INTERIOR_REGIONS", "cavity_shade"]

INTERIOR_REGIONS = (
    "teeth",
    "teeth_upper",
    "teeth_lower",
    "gums_tongue",
    "tongue",
    "mouth_socket",
    "mouth_cavity",
)
"""Regions inside the mouth (ICT-FaceKit's and the built-in head's names); a rig has some of them or none."""

DEPTH_M = 0.015
"""Depth behind the front teeth at which the light reaching the interior falls to 1/e (15 mm: about the
depth of the incisors and canines, so the premolars and molars behind them are mostly in shadow)."""

FLOOR = 0.15
"""Share of the light that still reaches the deepest interior (bounced light through the open lips)."""


def cavity_shade(rig: Rig) -> np.ndarray:
    """(n_vertices,) float32 albedo factor in [FLOOR, 1]: 1 outside the mouth and on the front teeth.

    A rig without interior regions, or without a ``teeth`` region to measure depth from (the interior's most
    forward vertex is used then), gets what it has; a rig with none gets all ones.
    """
    shade = np.ones(rig.n_vertices, np.float32)
    parts = [np.asarray(rig.regions[name], np.int64) for name in INTERIOR_REGIONS if name in rig.regions]
    if not parts:
        return shade
    ids = np.unique(np.concatenate(parts))
    teeth = [np.asarray(rig.regions[n], np.int64) for n in ("teeth", "teeth_upper", "teeth_lower") if n in rig.regions]
    reference = np.unique(np.concatenate(teeth)) if teeth else ids
    front = float(np.max(rig.neutral[reference, 2]))
    depth = np.clip(front - np.asarray(rig.neutral[ids, 2], np.float64), 0.0, None)
    shade[ids] = FLOOR + (1.0 - FLOOR) * np.exp(-depth / DEPTH_M)
    return shade
