"""Procedural laughs and smiles: type + intensity + duration + seed -> controller curves and a face clip.

Built from a library's representative curve of the type (:func:`~mien.laughter.builtin_library.default_library`
unless another library is given) and the taxonomy recipe:

* duration stretching: the representative curve is time-warped to the requested duration; a smooth random
  monotone warp (seeded) jitters the onset, apex and offset timing a little;
* laughter pulses: for laughing types the curve is split into its envelope (a 0.1 s Gaussian low-pass) and
  its pulses; the envelope is warped, and the pulses are made anew at the type's rate (jittered per seed and
  per pulse), in exhaled bouts with inhalations and decaying amplitude, with each controller's pulse depth
  and sign measured on the representative, so stretching a laugh never slows its "ha" rate;
* intensity: a gain on every curve (1 = the library's typical apex; 0..5); per-controller amplitude jitter
  of about 5% per seed;
* the face clip (AU intensities 0..5 and head pitch) follows from :func:`mien.laughter.to_face.controllers_to_face`.

The same seed always gives the identical result.

Character integration: while a laugh is active it *drives the mouth*: a character adding a laughter layer
should let the laugh's values replace its idle mouth motion on :data:`MOUTH_CHANNELS`, and sample the layer
with :func:`face_frame_at`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mien.errors import InvalidValueError
from mien.facs.catalogue import FACE_CHANNELS
from mien.facs.clip import Clip, interpolate_frames
from mien.facs.intensity import MAX_INTENSITY
from mien.laughter.builtin_library import default_library, laugh_pulses
from mien.laughter.library import LaughLibrary
from mien.laughter.names import CONTROLLER_NAMES
from mien.laughter.taxonomy import recipe
from mien.laughter.to_face import controllers_to_face, expression_envelope, smooth
from mien.plot import pyplot

__all__ = ["MOUTH_CHANNELS", "LaughResult", "face_frame_at", "generate", "plot_result"]

MOUTH_AUS: tuple[int, ...] = (10, 11, 12, 13, 14, 15, 16, 17, 18, 20, 22, 23, 24, 25, 26, 27, 28)
"""Mouth and jaw action units (FACS lower face)."""
MOUTH_CHANNELS: tuple[str, ...] = tuple(
    c for c in FACE_CHANNELS if c.startswith("AU") and int(c[2:].rstrip("LR")) in MOUTH_AUS
)
"""Face channels a laugh drives while it is active (a character's idle mouth motion yields on these)."""

DURATION_JITTER = 0.06
"""Log-normal sigma of the default duration between seeds."""
WARP_JITTER = 0.08
"""Sigma of each of the 3 sine coefficients of the random time warp (timing jitter)."""
AMPLITUDE_JITTER = 0.05
"""Sigma of the per-controller amplitude factor between seeds."""
RATE_JITTER = 0.08
"""Sigma of the relative pulse-rate change between seeds."""


@dataclass(frozen=True, eq=False)
class LaughResult:
    """A generated laugh or smile."""

    type: str
    """Laugh type id."""
    intensity: float
    """Gain that was applied (1 = typical)."""
    seed: int
    """Seed that made it."""
    controllers: Clip
    """(n_frames, 16) controller curves over :data:`~mien.laughter.names.CONTROLLER_NAMES`."""
    face_clip: Clip
    """(n_frames, 62) face clip over :data:`~mien.facs.catalogue.FACE_CHANNELS` (AUs 0..5, degrees)."""
    pulse_times_s: np.ndarray
    """(k,) times of the laughter pulse peaks in seconds (empty for smiles)."""

    @property
    def duration_s(self) -> float:
        """Length in seconds."""
        return self.face_clip.duration_s

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, LaughResult):
            return NotImplemented
        return (
            (self.type, self.intensity, self.seed) == (other.type, other.intensity, other.seed)
            and self.controllers == other.controllers
            and self.face_clip == other.face_clip
            and bool(np.array_equal(self.pulse_times_s, other.pulse_times_s))
        )

    __hash__ = None  # type: ignore[assignment]


def _check(intensity: float, duration_s: float | None, fps: float) -> tuple[float, float | None, float]:
    try:
        gain = float(intensity)
    except (TypeError, ValueError):
        raise InvalidValueError("intensity", intensity, f"a number in 0..{MAX_INTENSITY:g}") from None
    if not math.isfinite(gain) or not 0.0 <= gain <= MAX_INTENSITY:
        raise InvalidValueError("intensity", intensity, f"a finite number in 0..{MAX_INTENSITY:g} (1 = typical)")
    if duration_s is not None:
        try:
            duration = float(duration_s)
        except (TypeError, ValueError):
            raise InvalidValueError("duration_s", duration_s, "a positive number of seconds") from None
        if not math.isfinite(duration) or duration <= 0:
            raise InvalidValueError("duration_s", duration_s, "a positive finite number of seconds")
        duration_s = duration
    try:
        rate = float(fps)
    except (TypeError, ValueError):
        raise InvalidValueError("fps", fps, "a positive number") from None
    if not math.isfinite(rate) or rate <= 0:
        raise InvalidValueError("fps", fps, "a positive finite number")
    return gain, duration_s, rate


def _warp(u: np.ndarray, coefficients: np.ndarray) -> np.ndarray:
    """Monotone map of [0, 1] onto itself: ``u + sum a_k sin(k pi u) / (k pi)`` (slope >= 1 - sum|a_k| > 0)."""
    out = u.copy()
    for k, a in enumerate(coefficients, start=1):
        out += a * np.sin(k * np.pi * u) / (k * np.pi)
    return np.clip(out, 0.0, 1.0)


def _pulse_depths(reference: Clip) -> np.ndarray:
    """(16,) signed pulse depth of each controller in the representative: 95th percentile of |fast part|."""
    slow = smooth(reference.values, reference.fps)
    fast = reference.values - slow
    jaw = CONTROLLER_NAMES.index("jaw")
    jaw_sign = math.copysign(1.0, float(slow[np.argmax(np.abs(slow[:, jaw])), jaw]))
    depths = np.percentile(np.abs(fast), 95, axis=0)
    reference_fast = fast[:, jaw]
    signs = np.ones(len(CONTROLLER_NAMES))
    for j in range(len(CONTROLLER_NAMES)):
        product = float(np.dot(fast[:, j], reference_fast))
        signs[j] = jaw_sign * (1.0 if product >= 0 else -1.0)
    return np.asarray(depths * signs)


def generate(
    type_name: str,
    intensity: float = 1.0,
    duration_s: float | None = None,
    seed: int = 0,
    fps: float = 60.0,
    library: LaughLibrary | None = None,
) -> LaughResult:
    """Generate a laugh or smile of ``type_name`` (one of the 13 ids).

    ``intensity`` 0..5 is a gain (1 = the typical apex); ``duration_s`` the length in seconds (default: the
    representative's, jittered per seed); ``fps`` the output frame rate. ``library`` defaults to the
    built-in one; a type missing from a given library falls back to the built-in curve.

    >>> result = generate("laughter", seed=1)
    >>> result.controllers.channels[:2], result.face_clip.values.shape[1]
    (('rightTwich', 'leftTwich'), 62)
    """
    r = recipe(type_name)
    gain, duration_s, fps = _check(intensity, duration_s, fps)
    if library is not None and type_name in library.types:
        reference = library.curve(type_name)
    else:
        reference = default_library().curve(type_name)
    rng = np.random.default_rng(seed)
    duration_jitter = math.exp(DURATION_JITTER * rng.standard_normal())
    coefficients = np.clip(WARP_JITTER * rng.standard_normal(3), -0.2, 0.2)
    amplitude = 1.0 + AMPLITUDE_JITTER * rng.standard_normal(len(CONTROLLER_NAMES))
    rate = r.pulse_rate_hz * (1.0 + RATE_JITTER * rng.standard_normal())

    source_span = (reference.n_frames - 1) / reference.fps
    duration = duration_s if duration_s is not None else (source_span + 1.0 / fps) * duration_jitter
    n = max(2, round(duration * fps))
    times = np.arange(n) / fps
    source_times = _warp(np.linspace(0.0, 1.0, n), coefficients) * source_span

    if r.pulses:
        slow = interpolate_frames(smooth(reference.values, reference.fps), reference.fps, source_times)
        gate = expression_envelope(Clip(slow, fps, CONTROLLER_NAMES), reference)
        gate = gate / max(float(gate.max()), 1e-12)
        train = laugh_pulses(times, rate, gate, rng)
        values = slow + np.outer(train.values, _pulse_depths(reference))
        pulse_times = train.peak_times_s
    else:
        slow = interpolate_frames(reference.values, reference.fps, source_times)
        values = slow
        pulse_times = np.zeros(0)
    scale = gain * amplitude
    controllers = Clip(values * scale, fps, CONTROLLER_NAMES)
    envelope = expression_envelope(Clip(slow * scale, fps, CONTROLLER_NAMES), reference)
    face = controllers_to_face(controllers, r, reference, envelope)
    return LaughResult(r.type, gain, int(seed), controllers, face, pulse_times)


def face_frame_at(result: LaughResult, t_s: float) -> np.ndarray | None:
    """(62,) face frame of ``result`` at ``t_s`` seconds from its start (linear interpolation between frames).

    ``None`` before 0 or after :attr:`LaughResult.duration_s`: the laugh is not active then. While it is
    active the laugh drives the mouth (:data:`MOUTH_CHANNELS`).
    """
    t = float(t_s)
    if not math.isfinite(t) or t < 0.0 or t > result.duration_s:
        return None
    return result.face_clip.sample(t)


def plot_result(result: LaughResult, path: str | Path) -> Path:
    """Plot a result's moving controller curves and AU channels (two panels) to a PNG at ``path``."""

    plt = pyplot()
    path = Path(path)
    figure, (top, bottom) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    for clip, axes, unit in ((result.controllers, top, "controller value"), (result.face_clip, bottom, "AU 0..5")):
        for name in clip.active_channels(1e-4):
            if name.endswith("_deg"):
                continue
            axes.plot(clip.times_s, clip.channel(name), label=name, linewidth=1)
        axes.set_ylabel(unit)
        axes.legend(fontsize=6, ncol=4, loc="upper right")
    for t in result.pulse_times_s:
        bottom.axvline(t, color="0.85", linewidth=0.5, zorder=0)
    bottom.set_xlabel("time (s)")
    top.set_title(f"{result.type} (intensity {result.intensity:g}, seed {result.seed})")
    figure.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=100)
    plt.close(figure)
    return path
