"""Fidelity of a rig as a detector sees it: command each AU alone, render, detect, and compare (SPEC section 6).

For every head, every AU of a chosen set (default the 18 OpenFACS AUs, both sides) is commanded alone on a
neutral face at FACS intensities A..E (1..5), rendered frontally, passed to a detector (MediaPipe Face
Landmarker: 52 ARKit blendshape scores) and turned back into AU intensities 0..5 by
:class:`~mien.rig.au_solve.AUSolver`. The neutral face is rendered once as the baseline (commanded 0).
The solver always estimates the 18 OpenFACS AUs plus any other commanded AU, so a leak into an AU that was not
commanded shows up.

Per commanded AU (``x`` = commanded intensity 0, 1..5; ``y`` = detected intensity of the same AU):

* ``r``: Pearson correlation of ``x`` and ``y`` (NaN with fewer than 3 points, or when ``y`` spans less
  than :data:`MIN_RESPONSE`, 0.1: a correlation of detector noise means nothing);
* ``slope``: least-squares slope of ``y`` on ``x`` with an intercept (1 = the detector reads the AU back at
  the commanded scale);
* ``strongest``: at the top commanded intensity, the AU comes back as the strongest of all detected AUs
  (strictly above 0, ties count as strongest); the SPEC's "share of AUs that come back as the strongest
  response" is the mean of this flag;
* the cross-talk row: the least-squares slope of every detected AU against the commanded intensity
  (detected units per commanded unit). The diagonal is ``slope``; an off-diagonal 0.4 means commanding E
  (5) raises that other AU by about 2 (B).

Nothing is subtracted by default (``subtract_neutral=False``); the neutral's detected AUs are reported as
``neutral``, and slopes and correlations do not depend on a constant baseline anyway. With
``subtract_neutral`` the "strongest" test uses detected minus neutral.

**Can this detector see an AU at all?** Checked on real human faces, not assumed. An AU's *primary
blendshapes* are the ARKit targets its channels drive with at least half of its largest weight in the
mapping (AU12: mouthSmileLeft/Right; AU25: mouthLowerDown and mouthUpperUp). The AU *moves* on a set of faces
when the largest range (max - min) of a primary blendshape score over those faces is at least
:data:`MOVE_THRESHOLD` (0.1 on MediaPipe's 0..1 scale). It is measured on

* the human media (``human_data``: ``video/single_face.mp4``, every frame with a face; ``images/*.jpg``,
  each face found; ``multi_face.jpg`` in overlapping tiles, as the landmarker finds one face per call); and
* the rendered rig (the neutral and the AU's own renders).

The human data available is small: one clip of one person going from neutral into a broad smile with a blink,
and two photographs of smiles. Which AUs it performs was coded by eye from the frames
(:data:`~mien.validate.human_evidence.HUMAN_DATA_AUS`: AU6, AU12, AU25 throughout, AU45 in the clip). Per AU,
``seen_on_human`` is

* ``"yes"``: the human data performs the AU and its primary blendshapes move there;
* ``"no"``: the human data performs the AU and they do not move (the detector misses it on real faces);
* ``"untested"``: the human data never performs the AU. Movement there is no evidence that the detector sees
  the AU (it may be cross-talk from the smile), and stillness no evidence that it cannot.

``not_seen`` is the SPEC's "AUs this detector cannot see": primary blendshapes that move neither on the human
faces nor on the rendered rig. For an AU whose human verdict is ``"untested"`` that reads "not seen by this
detector (on the human data available)": the rig may simply not deform enough.
"""

from __future__ import annotations

import json
import math
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mien.errors import InvalidValueError, MissingAssetError, UnknownNameError
from mien.extras import require
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.catalogue import ACTION_UNITS, FACE_CHANNELS, OPENFACS_AUS, au_channels
from mien.heads import load_head
from mien.paths import require_asset
from mien.progress import progress as progress_bar
from mien.render.camera import camera_from_options
from mien.render.contact_sheet import contact_sheet
from mien.render.video import write_png
from mien.rig.au_solve import AUSolver
from mien.rig.heads import head_label, ict_installed, resolve_head_name
from mien.validate.face_detector import MediaPipeDetector
from mien.validate.figures import plot_crosstalk, plot_scatter
from mien.validate.human_evidence import HumanEvidence, default_human_folder, human_evidence
from mien.validate.json_values import array_of, rounded, rounded_array, unrounded
from mien.validate.statistics import least_squares_slope, pearson_r
from mien.validate.stimuli import StimulusRenderer

__all__ = [
    "MIN_RESPONSE",
    "MOVE_THRESHOLD",
    "HeadFidelity",
    "RigFidelity",
    "fidelity_stats",
    "primary_blendshapes",
    "run_rig_fidelity",
]

MOVE_THRESHOLD = 0.1
"""Smallest range (max - min) of a blendshape score (0..1) that counts as the detector moving it."""

MIN_RESPONSE = 0.1
"""Smallest range (max - min, intensity 0..5) of an AU's detected series for which its Pearson r is reported;
below it the series is detector noise and r is NaN."""

PRIMARY_SHARE = 0.5
"""A target is one of an AU's primary blendshapes when its mapping weight is at least this share of the AU's
largest weight."""


def fidelity_stats(
    intensities: Sequence[float],
    neutral: np.ndarray,
    detected: np.ndarray,
    own: Sequence[int],
    subtract_neutral: bool = False,
) -> dict[str, np.ndarray]:
    """Commanded-vs-detected statistics of one head.

    intensities: (k,) commanded intensities 1..5. neutral: (n_det,) detected AU intensities of the neutral face
    (commanded 0). detected: (n_cmd, k, n_det) detected AU intensities per commanded AU and intensity (NaN
    where no face was found). own: (n_cmd,) column of each commanded AU among the detected AUs.

    Returns ``r`` (n_cmd,), ``slope`` (n_cmd,), ``crosstalk`` (n_cmd, n_det) slopes of every detected AU on the
    commanded intensity (its diagonal entries ``crosstalk[i, own[i]]`` are ``slope``), and ``strongest``
    (n_cmd,) bool (the commanded AU is the largest detected AU at the top intensity, and above 0). ``r`` is
    NaN where the AU's own series spans less than :data:`MIN_RESPONSE`.

    >>> s = fidelity_stats([5.0], np.zeros(2), np.array([[[4.0, 1.0]], [[3.0, 2.0]]]), [0, 1])
    >>> s["slope"].tolist(), s["strongest"].tolist(), s["crosstalk"].tolist()
    ([0.8, 0.4], [True, False], [[0.8, 0.2], [0.6, 0.4]])
    """
    levels = np.asarray([0.0, *intensities], dtype=np.float64)
    neutral = np.asarray(neutral, dtype=np.float64)
    detected = np.asarray(detected, dtype=np.float64)
    n_cmd, k, n_det = detected.shape
    if k != len(levels) - 1 or neutral.shape != (n_det,) or len(own) != n_cmd:
        raise InvalidValueError("detected", detected.shape, f"(n_cmd, {len(levels) - 1}, {neutral.shape[0]})")
    series = np.concatenate([np.broadcast_to(neutral, (n_cmd, 1, n_det)), detected], axis=1)  # (n_cmd, k+1, n_det)
    crosstalk = np.array([[least_squares_slope(levels, series[i, :, j]) for j in range(n_det)] for i in range(n_cmd)])
    crosstalk = crosstalk.reshape(n_cmd, n_det)
    own_idx = np.asarray(own, dtype=np.intp)
    r = np.full(n_cmd, np.nan)
    for i in range(n_cmd):
        own_series = series[i, :, own_idx[i]]
        finite = own_series[np.isfinite(own_series)]
        if len(finite) and finite.max() - finite.min() >= MIN_RESPONSE:
            r[i] = pearson_r(levels, own_series)
    top = detected[:, -1, :] - (neutral if subtract_neutral else 0.0)
    strongest = np.zeros(n_cmd, dtype=bool)
    for i in range(n_cmd):
        row = top[i]
        if np.all(np.isfinite(row)):
            strongest[i] = bool(row[own_idx[i]] > 0.0 and row[own_idx[i]] >= row.max())
    return {
        "r": r,
        "slope": crosstalk[np.arange(n_cmd), own_idx] if n_cmd else np.zeros(0),
        "crosstalk": crosstalk,
        "strongest": strongest,
    }


def primary_blendshapes(matrix: np.ndarray, channels: Sequence[int]) -> np.ndarray:
    """Column ids of an AU's primary targets: weight >= :data:`PRIMARY_SHARE` x its largest weight.

    matrix: (n_channels, n_targets) AU -> target weights per unit intensity; channels: the AU's channel rows.
    """
    weights = np.asarray(matrix, dtype=np.float64)[list(channels)].max(axis=0)
    if weights.max() <= 0.0:
        return np.zeros(0, dtype=np.intp)
    return np.flatnonzero(weights >= PRIMARY_SHARE * weights.max())


def _range(values: np.ndarray, columns: np.ndarray) -> float:
    """Largest max - min over ``columns`` of (n, 52) scores (NaN rows ignored); NaN without finite rows."""
    values = np.asarray(values, dtype=np.float64)
    values = values[np.all(np.isfinite(values), axis=-1)]
    if len(values) == 0 or len(columns) == 0:
        return math.nan
    picked = values[:, columns]
    return float((picked.max(axis=0) - picked.min(axis=0)).max())


# ---------------------------------------------------------------------------------------------- results


@dataclass(frozen=True, eq=False)
class HeadFidelity:
    """Commanded vs detected AUs of one head / identity."""

    head: str
    """Head name as asked (``"builtin"``, ``"ict"``)."""
    identity: str | None
    """Identity preset, or None for the head's default."""
    rig: str
    """Name of the loaded rig."""
    aus: tuple[int, ...]
    """Commanded AU numbers (rows)."""
    detected_aus: tuple[int, ...]
    """AU numbers the solver estimates (columns): the 18 OpenFACS AUs, then any other commanded AU."""
    intensities: tuple[float, ...]
    """Commanded intensities 1..5 (A..E), each AU alone, both sides of lateral AUs."""
    neutral: np.ndarray
    """(n_det,) detected AU intensities 0..5 of the neutral face (commanded 0); NaN when no face was found."""
    detected: np.ndarray
    """(n_cmd, n_int, n_det) detected AU intensities 0..5; NaN where no face was found."""
    neutral_blendshapes: np.ndarray
    """(52,) the detector's ARKit scores 0..1 on the neutral face."""
    blendshapes: np.ndarray
    """(n_cmd, n_int, 52) the detector's ARKit scores 0..1 per commanded AU and intensity."""
    rig_range: np.ndarray
    """(n_cmd,) largest range of a primary blendshape over the neutral and the AU's renders."""
    human_range: np.ndarray
    """(n_cmd,) largest range of a primary blendshape over the human faces; NaN without human data."""
    seen_on_human: tuple[str, ...]
    """Per commanded AU ``"yes"``, ``"no"`` or ``"untested"`` (module docstring)."""
    primary: tuple[tuple[str, ...], ...]
    """Per commanded AU, its primary ARKit blendshapes."""
    subtract_neutral: bool = False
    """Whether :attr:`strongest` compares detected minus neutral."""
    timings_s: dict[str, float] = field(default_factory=dict)
    """Wall-clock seconds: ``load``, ``render``, ``detect``, ``solve``, ``total``; ``renders`` is a count."""
    sheet_images: tuple[np.ndarray, ...] = ()
    """(h, w, 3) uint8 crops of the neutral face and of each AU at the top intensity (not serialised)."""

    def _stats(self) -> dict[str, np.ndarray]:
        own = [self.detected_aus.index(code) for code in self.aus]
        return fidelity_stats(self.intensities, self.neutral, self.detected, own, self.subtract_neutral)

    @property
    def r(self) -> np.ndarray:
        """(n_cmd,) Pearson r of commanded vs detected intensity of each AU (NaN when undefined)."""
        return self._stats()["r"]

    @property
    def slope(self) -> np.ndarray:
        """(n_cmd,) least-squares slope of detected on commanded intensity of each AU (1 = read back to scale)."""
        return self._stats()["slope"]

    @property
    def crosstalk(self) -> np.ndarray:
        """(n_cmd, n_det) slope of every detected AU on the commanded AU's intensity (detected per commanded)."""
        return self._stats()["crosstalk"]

    @property
    def strongest(self) -> np.ndarray:
        """(n_cmd,) bool: the commanded AU is the strongest detected AU at the top intensity."""
        return self._stats()["strongest"]

    @property
    def strongest_share(self) -> float:
        """Share (0..1) of commanded AUs that come back as the strongest response."""
        return float(self.strongest.mean()) if self.aus else math.nan

    @property
    def seen_on_rig(self) -> np.ndarray:
        """(n_cmd,) bool: a primary blendshape moved by at least :data:`MOVE_THRESHOLD` on the renders."""
        return np.nan_to_num(self.rig_range, nan=0.0) >= MOVE_THRESHOLD

    @property
    def not_seen(self) -> np.ndarray:
        """(n_cmd,) bool: the primary blendshapes move neither on human faces nor on the rendered rig."""
        human = np.nan_to_num(self.human_range, nan=0.0) >= MOVE_THRESHOLD
        return ~human & ~self.seen_on_rig

    @property
    def label(self) -> str:
        """``head`` or ``head:identity``; a head file's name (:func:`mien.rig.heads.head_label`)."""
        return head_label(self.head, self.identity)

    def leaks(self, threshold: float = 0.2) -> list[list[tuple[int, float]]]:
        """Per commanded AU, the other detected AUs with a cross-talk slope >= ``threshold``, largest first."""
        out = []
        for i, row in enumerate(self.crosstalk):
            pairs = [
                (code, float(v))
                for code, v in zip(self.detected_aus, row, strict=True)
                if code != self.aus[i] and np.isfinite(v) and v >= threshold
            ]
            out.append(sorted(pairs, key=lambda p: -p[1]))
        return out

    def to_dict(self) -> dict[str, Any]:
        """Plain-dict form (NaN as None; values rounded to 1e-4)."""
        stats = self._stats()
        per_au = {}
        for i, code in enumerate(self.aus):
            per_au[f"AU{code}"] = {
                "r": rounded(stats["r"][i]),
                "slope": rounded(stats["slope"][i]),
                "strongest": bool(stats["strongest"][i]),
                "detected_at_top": rounded(self.detected[i, -1, self.detected_aus.index(code)]),
                "leaks": {f"AU{c}": round(v, 4) for c, v in self.leaks()[i]},
                "primary_blendshapes": list(self.primary[i]),
                "rig_range": rounded(self.rig_range[i]),
                "human_range": rounded(self.human_range[i]),
                "seen_on_rig": bool(self.seen_on_rig[i]),
                "seen_on_human": self.seen_on_human[i],
                "not_seen": bool(self.not_seen[i]),
            }
        return {
            "head": self.head,
            "identity": self.identity,
            "rig": self.rig,
            "aus": [f"AU{code}" for code in self.aus],
            "detected_aus": [f"AU{code}" for code in self.detected_aus],
            "intensities": list(self.intensities),
            "subtract_neutral": self.subtract_neutral,
            "crosstalk_kind": "least-squares slope of each detected AU (column) on the commanded AU's intensity (row)",
            "strongest_share": rounded(self.strongest_share),
            "per_au": per_au,
            "neutral": rounded_array(self.neutral),
            "detected": rounded_array(self.detected),
            "crosstalk": rounded_array(stats["crosstalk"]),
            "blendshape_names": list(ARKIT_NAMES),
            "neutral_blendshapes": rounded_array(self.neutral_blendshapes),
            "blendshapes": rounded_array(self.blendshapes),
            "timings_s": {key: round(value, 4) for key, value in self.timings_s.items()},
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> HeadFidelity:
        """Inverse of :meth:`to_dict` (without the contact-sheet images)."""
        aus = tuple(_au_code(name) for name in data["aus"])
        per_au = data["per_au"]
        return cls(
            head=data["head"],
            identity=data["identity"],
            rig=data["rig"],
            aus=aus,
            detected_aus=tuple(_au_code(name) for name in data["detected_aus"]),
            intensities=tuple(float(v) for v in data["intensities"]),
            neutral=array_of(data["neutral"]),
            detected=array_of(data["detected"]).reshape(len(aus), len(data["intensities"]), -1),
            neutral_blendshapes=array_of(data["neutral_blendshapes"]),
            blendshapes=array_of(data["blendshapes"]).reshape(len(aus), len(data["intensities"]), -1),
            rig_range=np.array([unrounded(per_au[f"AU{c}"]["rig_range"]) for c in aus]),
            human_range=np.array([unrounded(per_au[f"AU{c}"]["human_range"]) for c in aus]),
            seen_on_human=tuple(per_au[f"AU{c}"]["seen_on_human"] for c in aus),
            primary=tuple(tuple(per_au[f"AU{c}"]["primary_blendshapes"]) for c in aus),
            subtract_neutral=bool(data["subtract_neutral"]),
            timings_s={str(k): float(v) for k, v in data["timings_s"].items()},
        )


@dataclass(frozen=True, eq=False)
class RigFidelity:
    """The outcome of :func:`run_rig_fidelity`: one :class:`HeadFidelity` per head, and the human evidence."""

    heads: tuple[HeadFidelity, ...]
    """One result per (head, identity) asked for, in order."""
    human: HumanEvidence
    """What the detector does on real human faces."""
    detector: str
    """Name of the detector run over the renders."""
    model_path: str | None
    """The detector's model file, or None when it does not say."""
    camera: str
    """Camera preset name."""
    size: tuple[int, int]
    """Render size (width, height), pixels."""
    timings_s: dict[str, float] = field(default_factory=dict)
    """Wall-clock seconds: ``human`` (measuring the human media) and ``total``."""

    def to_dict(self) -> dict[str, Any]:
        """Plain-dict form of everything (the content of ``rig_fidelity.json``)."""
        return {
            "detector": self.detector,
            "model_path": self.model_path,
            "camera": self.camera,
            "size": list(self.size),
            "move_threshold": MOVE_THRESHOLD,
            "human": self.human.to_dict(),
            "heads": [head.to_dict() for head in self.heads],
            "timings_s": {key: round(value, 4) for key, value in self.timings_s.items()},
        }

    def to_json(self) -> str:
        """JSON text of :meth:`to_dict` (NaN written as null)."""
        return json.dumps(self.to_dict(), indent=1)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> RigFidelity:
        """Inverse of :meth:`to_dict` (without images or per-face human scores)."""
        return cls(
            heads=tuple(HeadFidelity.from_dict(head) for head in data["heads"]),
            human=HumanEvidence.from_dict(data["human"]),
            detector=data["detector"],
            model_path=data["model_path"],
            camera=data["camera"],
            size=(int(data["size"][0]), int(data["size"][1])),
            timings_s={str(k): float(v) for k, v in data["timings_s"].items()},
        )

    @classmethod
    def read(cls, path: str | os.PathLike[str]) -> RigFidelity:
        """Read a ``rig_fidelity.json`` written by :meth:`write`."""
        return cls.from_dict(json.loads(Path(path).read_text(encoding="utf-8")))

    def summary(self) -> str:
        """A plain-text table per head: AU, r, slope, strongest, detected at top, seen on rig / human, leaks."""
        lines = [f"detector: {self.detector}; human data: {self.human.n_faces} faces ({self.human.folder})"]
        for head in self.heads:
            lines.append(f"\n{head.label} ({head.rig}): strongest share {head.strongest_share:.2f}")
            lines.append(f"{'AU':<6}{'r':>7}{'slope':>7}{'strong':>8}{'at top':>8}{'rig':>5}{'human':>10}  leaks")
            stats = head._stats()
            leaks = head.leaks()
            for i, code in enumerate(head.aus):
                top = head.detected[i, -1, head.detected_aus.index(code)]
                leak = ", ".join(f"AU{c} {v:.2f}" for c, v in leaks[i][:3])
                lines.append(
                    f"AU{code:<4}{_fmt(stats['r'][i]):>7}{_fmt(stats['slope'][i]):>7}"
                    f"{'yes' if stats['strongest'][i] else 'no':>8}{_fmt(top):>8}"
                    f"{'yes' if head.seen_on_rig[i] else 'no':>5}{head.seen_on_human[i]:>10}  {leak}"
                )
        return "\n".join(lines)

    def write(self, out_dir: str | os.PathLike[str]) -> dict[str, Path]:
        """Write ``rig_fidelity.json`` and, per head, ``<head>_scatter.png``, ``<head>_crosstalk.png`` and
        ``<head>_contact_sheet.png`` (when the renders are at hand) into ``out_dir``; returns the paths by stem.

        Files are written under temporary names and renamed at the end (the JSON last), so a failure never
        leaves a complete-looking result.
        """
        folder = Path(out_dir)
        folder.mkdir(parents=True, exist_ok=True)
        final: dict[str, Path] = {}
        partial: dict[str, Path] = {}

        def reserve(name: str) -> Path:
            final[name] = folder / name
            partial[name] = folder / f".{name}.partial-{os.getpid()}"
            return partial[name]

        try:
            for head in self.heads:
                slug = _slug(head.label)
                plot_scatter(head, reserve(f"{slug}_scatter.png"))
                plot_crosstalk(head, reserve(f"{slug}_crosstalk.png"))
                if head.sheet_images:
                    write_png(_sheet(head), reserve(f"{slug}_contact_sheet.png"))
            reserve("rig_fidelity.json").write_text(self.to_json() + "\n", encoding="utf-8")
            final["rig_fidelity.json"].unlink(missing_ok=True)
            for name in final:  # the JSON was reserved last
                partial[name].replace(final[name])
        finally:
            for path in partial.values():
                path.unlink(missing_ok=True)
        return {Path(name).stem: path for name, path in final.items()}


def _fmt(value: float) -> str:
    return "-" if math.isnan(float(value)) else f"{float(value):.2f}"


def _au_code(name: str) -> int:
    return int(str(name).removeprefix("AU"))


def _slug(label: str) -> str:
    return "".join(ch if ch.isalnum() else "_" for ch in label.lower())


def _sheet(head: HeadFidelity) -> np.ndarray:
    top = head.intensities[-1]
    letter = "ABCDE"[round(top) - 1] if float(top).is_integer() and 1 <= top <= 5 else f"{top:g}"
    labels = ["neutral", *(f"AU{code}{letter}" for code in head.aus)]
    return contact_sheet(list(head.sheet_images), labels, columns=min(7, len(labels)))


# ---------------------------------------------------------------------------------------------- running


def _check_aus(aus: Sequence[int | str]) -> tuple[int, ...]:
    codes = []
    for au in aus:
        text = str(au).upper().removeprefix("AU")
        if not text.isdigit() or int(text) not in ACTION_UNITS or ACTION_UNITS[int(text)].kind != "face":
            known = tuple(f"AU{c}" for c, unit in ACTION_UNITS.items() if unit.kind == "face")
            raise UnknownNameError("face action unit", au, known)
        if int(text) not in codes:
            codes.append(int(text))
    if not codes:
        raise InvalidValueError("aus", tuple(aus), "at least one AU")
    return tuple(codes)


def _crop(rgb: np.ndarray, hint: np.ndarray, size: int = 256) -> np.ndarray:
    """A square crop around the projected landmarks (with margin), resized to ``size`` pixels."""
    image = require("PIL.Image", "render")
    low, high = hint.min(axis=0), hint.max(axis=0)
    centre = (low + high) / 2.0
    half = 0.75 * float((high - low).max())
    left, top = (int(v) for v in np.round(centre - half))
    right, bottom = (int(v) for v in np.round(centre + half))
    return np.asarray(image.fromarray(rgb).crop((left, top, right, bottom)).resize((size, size)))


def run_rig_fidelity(
    heads: Sequence[tuple[str, str | None]],
    aus: Sequence[int | str] | None = None,
    intensities: Sequence[float] = (1, 2, 3, 4, 5),
    camera: str = "frontal-1m",
    size: tuple[int, int] = (512, 512),
    detector: Any | None = None,
    progress: bool = True,
    *,
    human_data: str | os.PathLike[str] | None = None,
    subtract_neutral: bool = False,
    landmarker: str | os.PathLike[str] | None = None,
) -> RigFidelity:
    """Command each AU alone on each head, render, detect, and compare (module docstring).

    heads: ``(head, identity)`` pairs (:func:`mien.heads.load_head`; identity None = the head's default;
    ``("file", path)``: a user's head file).
    aus: AU numbers or names (default the 18 OpenFACS AUs). intensities: commanded levels in (0, 5].
    camera: a :data:`~mien.render.camera.CAMERA_PRESETS` name. size: render (width, height) pixels.
    detector: a :class:`~mien.validate.detector.Detector` giving blendshapes (default MediaPipe in image mode;
    one passed in is not closed). human_data: the shared data folder (``video/``, ``images/``; default
    ``$MIEN_SHARED/data`` when set, else no human evidence and every AU ``"untested"``). landmarker: the
    ``face_landmarker.task`` path (default the configured asset).

    Raises :class:`UnknownNameError` for an unknown head, identity, camera or AU, :class:`InvalidValueError`
    for bad intensities or size, and :class:`MissingAssetError` for an ICT head that is not installed
    (``MIEN_ICT_FACEKIT``) or a missing landmarker model.
    """
    started = time.perf_counter()
    commanded = _check_aus(OPENFACS_AUS if aus is None else aus)
    levels = tuple(float(v) for v in intensities)
    if not levels or not all(math.isfinite(v) and 0.0 < v <= 5.0 for v in levels) or len(set(levels)) != len(levels):
        raise InvalidValueError("intensities", tuple(intensities), "distinct intensities in (0, 5] (A..E = 1..5)")
    if len(size) != 2 or min(int(s) for s in size) < 64:
        raise InvalidValueError("size", size, "(width, height) of at least 64 pixels each")
    if not heads:
        raise InvalidValueError("heads", heads, "at least one (head, identity) pair")
    for name, _ in heads:
        resolve_head_name(name)  # the named heads and "file" (a user's head file, its path the identity)
        if name == "ict" and not ict_installed():
            raise MissingAssetError(
                "ICT-FaceKit is not installed: set MIEN_ICT_FACEKIT to the ICT-FaceKit folder (holds FaceXModel/)"
            )
    view = camera_from_options(camera)
    given_model = landmarker if detector is None else getattr(detector, "model_path", landmarker)
    model = require_asset("face_landmarker", given_model)
    detected_codes = (*OPENFACS_AUS, *(c for c in commanded if c not in OPENFACS_AUS))
    solver = AUSolver(aus=detected_codes)
    own_detector = detector is None
    if detector is None:
        detector = MediaPipeDetector(model)

    try:
        mark = time.perf_counter()
        human = human_evidence(human_data if human_data is not None else default_human_folder(), model, False)
        human_s = time.perf_counter() - mark
        results = []
        for name, identity in heads:
            results.append(
                _run_head(
                    name, identity, commanded, levels, view, size, detector, solver, human, subtract_neutral, progress
                )
            )
    finally:
        if own_detector:
            detector.close()
    model_path = getattr(detector, "model_path", None)
    return RigFidelity(
        heads=tuple(results),
        human=human,
        detector=str(getattr(detector, "name", type(detector).__name__)),
        model_path=None if model_path is None else str(model_path),
        camera=camera,
        size=(int(size[0]), int(size[1])),
        timings_s={"human": human_s, "total": time.perf_counter() - started},
    )


def _run_head(
    name: str,
    identity: str | None,
    commanded: tuple[int, ...],
    levels: tuple[float, ...],
    view: Any,
    size: tuple[int, int],
    detector: Any,
    solver: Any,
    human: HumanEvidence,
    subtract_neutral: bool,
    show_progress: bool,
) -> HeadFidelity:
    timings = {"load": 0.0, "render": 0.0, "detect": 0.0, "solve": 0.0}
    head_started = mark = time.perf_counter()
    rig = load_head(name, identity)
    timings["load"] = time.perf_counter() - mark
    n_blend = len(ARKIT_NAMES)
    jobs = [(-1, 0.0)] + [(i, level) for i in range(len(commanded)) for level in levels]
    scores = np.full((len(jobs), n_blend), np.nan)
    crops: dict[int, np.ndarray] = {}
    with StimulusRenderer(rig, view, (int(size[0]), int(size[1]))) as renderer:
        label = f"rig fidelity {head_label(name, identity)}"
        for k, (i, level) in enumerate(progress_bar(jobs, len(jobs), label, show_progress)):
            frame = np.zeros(len(FACE_CHANNELS))
            if i >= 0:
                frame[list(au_channels(commanded[i]))] = level
            mark = time.perf_counter()
            rgb, hint = renderer.render(frame)
            timings["render"] += time.perf_counter() - mark
            mark = time.perf_counter()
            detection = detector.detect(rgb, hint)
            timings["detect"] += time.perf_counter() - mark
            if detection.found and detection.blendshapes is not None and not detection.landmarks_from_hint:
                scores[k] = detection.blendshapes
            if level == levels[-1] or i < 0:
                crops[i] = _crop(rgb, hint)
    scores = np.round(scores, 4)  # the JSON's precision, so a report read back gives the same statistics
    mark = time.perf_counter()
    solved = np.full((len(jobs), len(solver.aus)), np.nan)
    found = np.all(np.isfinite(scores), axis=1)
    if found.any():
        solved[found] = np.round(solver.solve(scores[found]), 4)
    timings["solve"] = time.perf_counter() - mark
    n_int = len(levels)
    neutral, detected = solved[0], solved[1:].reshape(len(commanded), n_int, -1)
    neutral_scores, blend = scores[0], scores[1:].reshape(len(commanded), n_int, n_blend)

    matrix = solver.mapping.matrix
    primary = [primary_blendshapes(matrix, au_channels(code)) for code in commanded]
    rig_range = np.array([_range(np.vstack([neutral_scores[None], blend[i]]), p) for i, p in enumerate(primary)])
    human_range = np.array([_range(human.blendshapes, p) for p in primary])
    seen = []
    for code, value in zip(commanded, human_range, strict=True):
        if code not in human.performed or not np.isfinite(value):
            seen.append("untested")
        else:
            seen.append("yes" if value >= MOVE_THRESHOLD else "no")
    timings["total"] = time.perf_counter() - head_started
    timings["renders"] = float(len(jobs))
    return HeadFidelity(
        head=name,
        identity=identity,
        rig=rig.name,
        aus=commanded,
        detected_aus=tuple(solver.aus),
        intensities=levels,
        neutral=neutral,
        detected=detected,
        neutral_blendshapes=neutral_scores,
        blendshapes=blend,
        rig_range=rig_range,
        human_range=human_range,
        seen_on_human=tuple(seen),
        primary=tuple(tuple(ARKIT_NAMES[j] for j in p) for p in primary),
        subtract_neutral=subtract_neutral,
        timings_s=timings,
        sheet_images=(crops[-1], *(crops[i] for i in range(len(commanded)))),
    )
