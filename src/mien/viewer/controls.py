"""The viewer's control lists, built from the package's own catalogues (never hard-coded in the page).

:func:`viewer_controls` returns one JSON-ready dict that ``/viewer/controls.json`` serves and ``viewer.js``
turns into sliders and buttons: the face AUs of the FACS catalogue with the A..E letters, the six emotions
and the blends, the PAD factors, the 13 laugh/smile types, the idle parts grouped as the page's toggles, and
the Broekens camera presets.

>>> controls = viewer_controls()
>>> [au["label"] for au in controls["aus"]][:3]
['AU1', 'AU2', 'AU4']
>>> controls["intensity_letters"]
['A', 'B', 'C', 'D', 'E']
>>> len(controls["laughter"])
13
"""

from __future__ import annotations

import logging
from dataclasses import fields
from typing import Any

from mien.affect.emotions import BLENDS, EMOTIONS, MAX_INTENSITY
from mien.affect.pad import PAD_FACTORS
from mien.exchange import readable_suffixes
from mien.facs.catalogue import ACTION_UNITS
from mien.facs.idle import IdleSettings
from mien.laughter.taxonomy import TAXONOMY
from mien.render.camera import VIEWS
from mien.rig.heads import HEADS

__all__ = ["EMOTION_INTENSITY_MAX", "IDLE_TOGGLES", "INTENSITY_LETTERS", "viewer_controls"]

log = logging.getLogger(__name__)

INTENSITY_LETTERS: tuple[str, ...] = ("A", "B", "C", "D", "E")
"""FACS intensity letters; letter ``i`` (0-based) is intensity ``i + 1`` on mien's 0..5 AU scale."""

EMOTION_INTENSITY_MAX = 2.4
"""Largest emotion intensity the page offers: the strongest condition of the Broekens study (1 = prototype)."""

IDLE_TOGGLES: dict[str, tuple[str, ...]] = {
    "blink": ("blink",),
    "micro-motion": ("mouth", "eyelids", "neck", "wobble"),
    "gaze": ("gaze",),
}
"""The page's idle switches and the :class:`~mien.facs.idle.IdleSettings` flags each one sets."""


def _aus() -> list[dict[str, Any]]:

    return [
        {
            "code": au.code,
            "label": au.label,
            "name": au.name,
            "lateral": au.lateral,
            "openfacs": au.openfacs,
        }
        for au in ACTION_UNITS.values()
        if au.kind == "face"
    ]


def _laughter() -> list[dict[str, Any]]:

    return [
        {"type": r.type, "label": r.label, "family": r.family, "duration_s": r.duration_s, "notes": r.notes}
        for r in TAXONOMY.values()
    ]


def _cameras() -> list[dict[str, Any]]:

    out = []
    study_views = sorted((v for v in VIEWS.values() if v.in_study), key=lambda v: (v.distance_m, v.yaw_deg))
    for view in study_views:
        name, camera = view.name, view.camera
        out.append(
            {
                "name": name,
                "position_m": [round(float(c), 6) for c in camera.position],
                "target_m": list(camera.target),
                "fov_deg": camera.fov_deg,
                "distance_m": camera.distance_m,
            }
        )
    return out


def _idle() -> list[dict[str, Any]]:

    flags = {f.name for f in fields(IdleSettings) if f.type in (bool, "bool")}
    missing = sorted({flag for group in IDLE_TOGGLES.values() for flag in group} - flags)
    if missing:  # the toggles must name real IdleSettings switches
        raise RuntimeError(f"IDLE_TOGGLES names unknown IdleSettings flags: {missing}")
    return [{"name": name, "flags": list(group)} for name, group in IDLE_TOGGLES.items()]


def _clip_suffixes() -> list[str]:
    try:
        return sorted(readable_suffixes())
    except Exception as exc:  # a broken format module must not take the page down: offer every file instead
        # (only the file picker's filter depends on this; the server's clip endpoint names a bad suffix)
        log.warning("mien viewer: clip formats unavailable (%s); the clip picker accepts any file", exc)
        return []


def viewer_controls() -> dict[str, Any]:
    """Everything the page's controls list, as a JSON-ready dict.

    Keys: ``aus`` (face AUs in catalogue order: ``code``, ``label``, ``name``, ``lateral``, ``openfacs``),
    ``intensity_letters`` (A..E = 1..5), ``au_max`` (5.0), ``emotions`` (the six basic emotions),
    ``blends`` (the built-in blends), ``emotion_intensity_max`` (2.4), ``pad_factors``, ``laughter`` (the 13
    types: ``type``, ``label``, ``family``, ``duration_s``, ``notes``), ``idle`` (toggles: ``name`` and the
    IdleSettings ``flags`` it sets), ``cameras`` (``name``, ``position_m`` and ``target_m`` in the rig frame,
    metres; vertical ``fov_deg``; ``distance_m``), ``heads`` (head names a new character may use) and
    ``clip_suffixes`` (file suffixes the server reads as clips).
    """

    return {
        "aus": _aus(),
        "intensity_letters": list(INTENSITY_LETTERS),
        "au_max": MAX_INTENSITY,
        "emotions": list(EMOTIONS),
        "blends": list(BLENDS),
        "emotion_intensity_max": EMOTION_INTENSITY_MAX,
        "pad_factors": list(PAD_FACTORS),
        "laughter": _laughter(),
        "idle": _idle(),
        "cameras": _cameras(),
        "heads": list(HEADS),
        "clip_suffixes": _clip_suffixes(),
    }
