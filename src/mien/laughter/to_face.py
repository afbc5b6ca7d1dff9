"""Laughter controller curves -> a face clip over FACE_CHANNELS (AU intensities 0..5 and head pitch).

The 16 controllers cannot say which AU moved (the brow controllers move for AU1 and AU4 alike), so the
taxonomy recipe says which AUs a type has and their apex intensities, and each AU takes its time course
from the controller that follows it (``data/face_drivers.csv``): ``AU(t) = apex * |C(t)| / max|C_ref|``,
``C_ref`` being the library's unscaled representative curve. Generated curves scaled by an intensity
above 1 thus raise the AUs above their typical apex (clipped to 5). A driver that barely moves in the
reference (under :data:`WEAK_FRACTION` of the strongest controller) is replaced by the whole expression's
envelope, as are the AUs no single controller follows (lip press, chin raise) and head pitch.
"""

from __future__ import annotations

import functools

import numpy as np

from mien.facs.catalogue import FACE_CHANNELS
from mien.facs.clip import Clip
from mien.facs.intensity import MAX_INTENSITY
from mien.fileio.tables import read_table
from mien.laughter.names import CONTROLLER_NAMES
from mien.laughter.taxonomy import LaughRecipe

__all__ = ["ENVELOPE_SMOOTHING_S", "WEAK_FRACTION", "controllers_to_face", "expression_envelope", "smooth"]

WEAK_FRACTION = 0.1
"""A driver whose reference peak is below this fraction of the strongest controller's counts as not moving."""
ENVELOPE_SMOOTHING_S = 0.1
"""Gaussian sigma (seconds) that removes laughter pulses (4-5 Hz) from a curve but keeps its envelope."""


def smooth(values: np.ndarray, fps: float, sigma_s: float = ENVELOPE_SMOOTHING_S) -> np.ndarray:
    """Gaussian low-pass of ``values`` (n,) or (n, c) along time; edges held (``nearest``).

    numpy only (laughter needs no extra): the kernel, truncation (4 sigma) and summation order of
    ``scipy.ndimage.gaussian_filter1d(..., mode="nearest")``, whose numbers it gives.
    """
    x = np.asarray(values, dtype=np.float64)
    sigma = sigma_s * fps
    if not sigma > 0.0 or x.shape[0] == 0:
        return x.copy()
    radius = int(4.0 * sigma + 0.5)
    offsets = np.arange(-radius, radius + 1)
    weights = np.exp(-0.5 / (sigma * sigma) * offsets**2)
    weights = weights / weights.sum()
    n = x.shape[0]
    padded = x[np.clip(np.arange(-radius, n + radius), 0, n - 1)]  # edges held
    out = padded[radius : radius + n] * weights[radius]
    for j in range(radius, 0, -1):  # symmetric pairs, outermost first
        out = out + (padded[radius - j : radius - j + n] + padded[radius + j : radius + j + n]) * weights[radius + j]
    return out


def expression_envelope(controllers: Clip, reference: Clip) -> np.ndarray:
    """(n,) envelope of a controller clip: the norm of its smoothed curves over the reference's peak norm."""
    norm = np.linalg.norm(smooth(controllers.values, controllers.fps), axis=1)
    ref = float(np.linalg.norm(smooth(reference.values, reference.fps), axis=1).max())
    return norm / ref if ref > 0 else np.zeros(controllers.n_frames)


@functools.cache
def _drivers() -> dict[str, tuple[str, str]]:
    rows = read_table("mien.laughter", "data/face_drivers.csv")
    return {row["au"]: (row["right"], row["left"]) for row in rows}


def _code_and_side(channel: str) -> tuple[str, str | None]:
    body = channel[2:]
    if body[-1] in "LR":
        return body[:-1], body[-1]
    return body, None


def controllers_to_face(controllers: Clip, r: LaughRecipe, reference: Clip, envelope: np.ndarray | None = None) -> Clip:
    """Face clip (n, 62) for ``controllers`` (n, 16) of type ``r``, timed like the controllers.

    ``reference`` is the library's representative curve of the type (it fixes what "apex" means);
    ``envelope`` (n,) the expression envelope (default: :func:`expression_envelope`).
    """
    columns = {name: controllers.values[:, i] for i, name in enumerate(CONTROLLER_NAMES)}
    peaks = {name: float(np.abs(reference.values[:, i]).max()) for i, name in enumerate(CONTROLLER_NAMES)}
    strongest = max(peaks.values())
    env = expression_envelope(controllers, reference) if envelope is None else np.asarray(envelope)
    drivers = _drivers()
    values = np.zeros((controllers.n_frames, len(FACE_CHANNELS)))
    for index, apex in r.au_frame().items():
        code, side = _code_and_side(FACE_CHANNELS[index])
        right, left = drivers.get(code, ("envelope", "envelope"))
        driver = left if side == "L" else right
        peak = peaks.get(driver, 0.0)
        if driver == "envelope" or peak <= WEAK_FRACTION * strongest or peak == 0.0:
            course = env
        else:  # each side on its own peak: the recipe's apex already holds the asymmetry
            course = np.abs(columns[driver]) / peak
        values[:, index] = np.clip(apex * course, 0.0, MAX_INTENSITY)
    values[:, FACE_CHANNELS.index("head_pitch_deg")] = r.head_pitch_deg * env
    return Clip(values, controllers.fps, FACE_CHANNELS)
