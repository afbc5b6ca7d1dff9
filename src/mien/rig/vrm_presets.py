"""VRM expression presets and the face mien gives each: one table (``data/vrm_expressions.csv``) for both versions.

A preset's face is an EMFACS prototype (mien.facs.prototypes) at an intensity, sent through the shipped AU -> ARKit
mapping, plus ARKit poses of its own (visemes, blinks, looks). mien's VRM writer builds its expressions from it
(:mod:`mien.exchange.vrm`); a user's rig that has only VRM presets is driven through them by projecting each
ARKit pose onto the presets' faces (:func:`mien.rig.conventions.match_names`).

>>> PRESETS["sad"].vrm0, PRESETS["sad"].emotion
('sorrow', 'sadness')
>>> float(preset_arkit("aa")[ARKIT_INDEX["jawOpen"]])
0.7
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from mien.facs.arkit import ARKIT_INDEX, ARKIT_NAMES
from mien.facs.prototypes import prototype_vector
from mien.fileio.tables import read_table
from mien.rig.mapping import AUMapping

__all__ = ["EMOTION_PRESETS", "PRESETS", "VrmPreset", "preset_arkit", "vrm1_name"]


@dataclass(frozen=True)
class VrmPreset:
    """One VRM expression preset (a row of ``data/vrm_expressions.csv``)."""

    name: str
    """The VRM 1.0 preset name (``happy``, ``aa``, ``blinkLeft``...)."""
    vrm0: str
    """The VRM 0.x ``blendShapeMaster`` preset name (``joy``, ``a``, ``blink_l``...); empty where 0.x has none."""
    emotion: str
    """The EMFACS prototype the preset shows (empty for visemes, blinks and looks)."""
    intensity: float
    """The prototype's intensity (0 without one)."""
    arkit: tuple[tuple[str, float], ...]
    """ARKit (name, weight 0..1) pairs added to the prototype's."""


@cache
def _presets() -> dict[str, VrmPreset]:
    out = {}
    for row in read_table("mien.rig", "data/vrm_expressions.csv"):
        pairs = []
        for token in (row["arkit"] or "").split():
            name, _, weight = token.partition(":")
            pairs.append((name, float(weight)))
        out[row["expression"]] = VrmPreset(
            row["expression"], row["vrm0"] or "", row["emotion"] or "", float(row["intensity"] or 0.0), tuple(pairs)
        )
    return out


PRESETS: dict[str, VrmPreset] = _presets()
"""VRM 1.0 preset name -> :class:`VrmPreset`, in the table's order."""

EMOTION_PRESETS: tuple[str, ...] = tuple(name for name, preset in PRESETS.items() if preset.emotion)
"""The presets that show an emotion (happy, angry, sad, relaxed, surprised)."""

_VRM1_OF_VRM0 = {preset.vrm0: name for name, preset in PRESETS.items() if preset.vrm0}


def vrm1_name(name: str) -> str | None:
    """The VRM 1.0 preset of a preset name of either version (``sorrow`` -> ``sad``); None if neither knows it."""
    return name if name in PRESETS else _VRM1_OF_VRM0.get(name)


@cache
def _arkit(name: str) -> np.ndarray:
    preset = PRESETS[name]
    weights = np.zeros(len(ARKIT_NAMES), np.float64)
    if preset.emotion:
        weights += AUMapping.default().to_weights(prototype_vector(preset.emotion) * preset.intensity)
    for target, weight in preset.arkit:
        weights[ARKIT_INDEX[target]] += weight
    weights = np.clip(weights, 0.0, 1.0)
    weights.flags.writeable = False
    return weights


def preset_arkit(name: str) -> np.ndarray:
    """(52,) ARKit weights 0..1 of the face mien gives the VRM 1.0 preset ``name`` (read-only)."""
    return _arkit(name)
