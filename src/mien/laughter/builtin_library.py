"""The built-in laugh library: representative controller curves made from the taxonomy, no video needed.

For each type, an AU clip is built from the taxonomy recipe (``data/taxonomy.csv``) and published dynamics:
a smile envelope with the type's onset/apex/offset timing (Schmidt et al. 2003/2006: smooth spontaneous
onsets, faster and flatter posed ones; Ekman & Friesen 1982: abrupt false smiles), the cheek raise trailing
the lip-corner pull slightly, and for laughter "ha" pulses on the jaw at the type's rate, in exhaled bouts
of about 1.5 s separated by an inhalation, each bout's pulses weakening as the lungs empty (Ruch & Ekman
2001; Bachorowski et al. 2001). The AU clip is then turned into the 16 rig controllers with the per-AU
facial-parameter gains of ``data/au_controllers.csv`` and the paper's Eq 1 in the units of
:mod:`mien.laughter.controllers` (``C = eps * CONTROLLER_GAIN * dFP``).

The result is a :class:`~mien.laughter.library.LaughLibrary` in exactly the format a learned one has.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from mien.facs.catalogue import FACE_CHANNELS, au_channels
from mien.facs.clip import Clip
from mien.facs.intensity import MAX_INTENSITY
from mien.fileio.tables import read_table
from mien.laughter.controllers import CONTROLLER_GAIN, DEFAULT_EPS
from mien.laughter.library import LaughLibrary, LibraryMetadata
from mien.laughter.names import CONTROLLER_NAMES, LAUGH_TYPES
from mien.laughter.taxonomy import LaughRecipe, recipe

__all__ = [
    "BUILTIN_EPS",
    "BUILTIN_FPS",
    "JAW_PULSE_DEPTH",
    "PulseTrain",
    "au_clip_to_controllers",
    "builtin_au_clip",
    "default_library",
    "laugh_pulses",
    "smile_envelope",
]

BUILTIN_FPS = 30.0
"""Frame rate of the built-in curves (a typical video rate, like learned curves)."""
BUILTIN_EPS = DEFAULT_EPS
"""Hardness factor of the built-in curves (the controllers' default, middle of the paper's 0.1-0.3)."""
LEAD_IN_S = 0.25
"""Neutral time before the onset and after the offset, seconds (learned takes start from neutral too)."""
EYE_LAG_S = 0.08
"""The cheek raise / lid tightening trails the lip-corner pull by this much, seconds."""
JAW_PULSE_DEPTH = 0.35
"""Laughter pulse amplitude on the mouth-opening AUs, as a fraction of their apex intensity."""
EYE_PULSE_DEPTH = 0.08
"""Laughter pulse amplitude on the cheek/lip-corner AUs, as a fraction of their apex intensity."""
BOUT_S = 1.5
"""Length of one exhaled laughter bout, seconds (Ruch & Ekman 2001: 1-2 s)."""
INHALE_S = 0.35
"""Inhalation pause between bouts, seconds."""
BOUT_DECAY = 0.45
"""Fraction of pulse amplitude lost from the start to the end of a bout (the lungs empty)."""

_MOUTH_OPENING_AUS = (25, 26, 27)
_EYE_AUS = (6, 7)


def _ease(x: np.ndarray, abrupt: bool) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    if abrupt:  # a posed smile switches on: nearly linear, fast
        return x
    return x * x * x * (x * (6.0 * x - 15.0) + 10.0)  # smootherstep: zero velocity at both ends


def smile_envelope(times_s: np.ndarray, r: LaughRecipe, start_s: float = LEAD_IN_S) -> np.ndarray:
    """(n,) 0..1 envelope of a smile or laugh over ``times_s`` (seconds): onset, apex, offset of ``r``.

    Spontaneous (non-voluntary) types drift down 8% over the apex; voluntary ones hold a flat apex and
    switch on and off linearly.
    """
    t = np.asarray(times_s, dtype=np.float64) - start_s
    onset = _ease(t / r.onset_s, r.voluntary)
    apex_end = r.onset_s + r.apex_s
    drift = 0.0 if r.voluntary else 0.08
    level = 1.0 - drift * np.clip((t - r.onset_s) / r.apex_s, 0.0, 1.0)
    offset = 1.0 - _ease((t - apex_end) / r.offset_s, r.voluntary)
    return np.where(t < r.onset_s, onset, level * np.where(t < apex_end, 1.0, offset))


@dataclass(frozen=True)
class PulseTrain:
    """Laughter "ha" pulses: a zero-mean oscillation in -1..1 and when each pulse peaks."""

    values: np.ndarray
    """(n,) pulse signal, -1..1, 0 outside pulses (between bouts, outside the laugh)."""
    peak_times_s: np.ndarray
    """(k,) time of each pulse's peak, seconds."""


def laugh_pulses(
    times_s: np.ndarray,
    rate_hz: float,
    envelope: np.ndarray,
    rng: np.random.Generator | None = None,
    bout_s: float = BOUT_S,
    inhale_s: float = INHALE_S,
    decay: float = BOUT_DECAY,
) -> PulseTrain:
    """Exhaled "ha" pulses at ``rate_hz`` while ``envelope`` (n,) 0..1 is up, in bouts with inhalations.

    Each pulse is one raised-cosine cycle (mean zero); within a bout the amplitude falls linearly by
    ``decay``; bouts last ``bout_s`` seconds with ``inhale_s`` pauses between them. With ``rng`` every pulse
    period is jittered by 7% and each bout's length by 15%, so two seeds give two natural-looking laughs.
    """
    t = np.asarray(times_s, dtype=np.float64)
    env = np.asarray(envelope, dtype=np.float64)
    out = np.zeros_like(t)
    peaks: list[float] = []
    active = np.flatnonzero(env > 0.3)
    if active.size == 0 or rate_hz <= 0:
        return PulseTrain(out, np.zeros(0))
    start, stop = float(t[active[0]]), float(t[active[-1]])
    gate = np.clip((env - 0.2) / 0.5, 0.0, 1.0)
    period = 1.0 / rate_hz
    bout_start, cursor = start, start
    bout_len = bout_s * (1.0 + (0.15 * rng.standard_normal() if rng is not None else 0.0))
    while cursor < stop:
        if cursor - bout_start >= bout_len:  # breathe in, start a new bout
            cursor += inhale_s * (1.0 + (0.15 * rng.standard_normal() if rng is not None else 0.0))
            bout_start = cursor
            bout_len = bout_s * (1.0 + (0.15 * rng.standard_normal() if rng is not None else 0.0))
            continue
        length = period * (1.0 + (0.07 * rng.standard_normal() if rng is not None else 0.0))
        length = max(length, 0.5 * period)
        amplitude = 1.0 - decay * min(1.0, (cursor - bout_start) / bout_len)
        inside = (t >= cursor) & (t < cursor + length)
        phase = (t[inside] - cursor) / length
        out[inside] = amplitude * -np.cos(2.0 * np.pi * phase)
        peaks.append(cursor + 0.5 * length)
        cursor += length
    return PulseTrain(out * gate, np.asarray(peaks))


def builtin_au_clip(type_name: str, fps: float = BUILTIN_FPS) -> Clip:
    """The built-in AU clip of ``type_name`` over :data:`~mien.facs.catalogue.FACE_CHANNELS` (0..5, degrees).

    Lead-in and lead-out of :data:`LEAD_IN_S` neutral seconds around the typical duration of the recipe.
    """
    r = recipe(type_name)
    n = round((r.duration_s + 2 * LEAD_IN_S) * fps) + 1
    times = np.arange(n) / fps
    env = smile_envelope(times, r)
    eye_env = smile_envelope(times, r, LEAD_IN_S + EYE_LAG_S)
    pulses = laugh_pulses(times, r.pulse_rate_hz, env).values if r.pulses else np.zeros(n)
    mouth = {i for code in _MOUTH_OPENING_AUS for i in au_channels(code)}
    eyes = {i for code in _EYE_AUS for i in au_channels(code)}
    values = np.zeros((n, len(FACE_CHANNELS)))
    for index, apex in r.au_frame().items():
        course = eye_env if index in eyes else env
        if index in mouth:
            course = env + JAW_PULSE_DEPTH * pulses
        elif r.pulses:
            course = course + EYE_PULSE_DEPTH * pulses
        values[:, index] = np.clip(apex * course, 0.0, MAX_INTENSITY)
    values[:, FACE_CHANNELS.index("head_pitch_deg")] = r.head_pitch_deg * env
    return Clip(values, fps, FACE_CHANNELS)


@functools.cache
def _gains() -> tuple[tuple[int, str, float], ...]:
    rows = read_table("mien.laughter", "data/au_controllers.csv")
    return tuple((int(row["au"]), row["controller"], float(row["gain"])) for row in rows)


def au_clip_to_controllers(au_clip: Clip, eps: float = BUILTIN_EPS) -> Clip:
    """Controller clip (n, 16) from an AU clip over FACE_CHANNELS: ``eps * CONTROLLER_GAIN * sum(gain * AU)``.

    ``right*`` controllers read an AU's R channel, ``left*`` its L channel, the others the mean of both.
    """
    values = np.zeros((au_clip.n_frames, len(CONTROLLER_NAMES)))
    for code, controller, gain in _gains():
        if controller.startswith("right"):
            side: str | None = "R"
        elif controller.startswith("left"):
            side = "L"
        else:
            side = None
        lateral = len(au_channels(code)) == 2
        columns = au_channels(code, side) if lateral and side else au_channels(code)
        au = au_clip.values[:, list(columns)].mean(axis=1)
        values[:, CONTROLLER_NAMES.index(controller)] += eps * CONTROLLER_GAIN * gain * au
    return Clip(values, au_clip.fps, CONTROLLER_NAMES)


@functools.cache
def default_library() -> LaughLibrary:
    """The built-in library: one representative controller curve for each of the 13 types (cached)."""
    curves = {name: au_clip_to_controllers(builtin_au_clip(name)) for name in LAUGH_TYPES}
    metadata = LibraryMetadata(
        source="builtin",
        eps=BUILTIN_EPS,
        fps=BUILTIN_FPS,
        n_takes=dict.fromkeys(LAUGH_TYPES, 0),
        created="2021-05-13T00:00:00+00:00",  # fixed: the built-in curves do not change between runs
        method="recipe",
        extra={"basis": "taxonomy.csv + au_controllers.csv (mien.laughter.builtin_library)"},
    )
    return LaughLibrary(curves, metadata)
