"""OpenFACS's synthetic-expert validation: a human video against the character, as AU activation maps.

A "synthetic expert" (MediaPipe Face Landmarker's 52 blendshape scores, turned into FACS AU intensities by
:class:`~mien.rig.au_solve.AUSolver`) watches the human video and the character's renderings; each
becomes an activation map (AU x time, :mod:`mien.validate.activation`) and the maps are compared by their
2D correlation coefficient (Cuculo & D'Amelio 2019, section 5 and Fig. 5).

Two comparisons:

* **expression** (Fig. 5): the character performs the named expression (an emotion such as ``"joy"``
  through its onset/hold/decay envelope stretched to the video's duration, or AUs such as ``"AU6+AU12D"``
  played with the same envelope) and is detected like the human;
* **closed loop**: the human's own per-frame AU estimates are replayed on the character at the video's
  frame times, rendered and detected again; the maps' correlation (per AU row and overall) measures how
  much of a performance survives the trip through the rig.

Both sides go through the capture path of ``mien capture`` (:mod:`mien.capture`): the human video is
tracked with :func:`mien.tracking.track_video` (MediaPipe in video mode, cached) and captured by
:func:`mien.capture.capture_track` (jitter filter, the performer's neutral from the first face seconds
subtracted, the reverse AU mapping); the replay plays those captured face frames. Rendered frames go through
a :class:`~mien.validate.detector.Detector` (MediaPipe in image mode by default) and their scores through the
same :class:`~mien.capture.stream.CaptureStream`, with the character's own rendered neutral subtracted. Frames
without a face are left out of a map; its samples bridge them linearly. The report's ``per_au_r`` is each AU's
correlation over time between the person and the character's re-detected face.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mien.affect.emotions import known_names, resolve_emotion
from mien.capture import CaptureSettings, capture_frames, capture_track
from mien.capture.stream import N_INPUT
from mien.character import Character
from mien.errors import InvalidValueError, MienError, UnknownNameError
from mien.facs.catalogue import FACE_CHANNELS, au_channels
from mien.facs.clip import Clip
from mien.facs.envelope import Envelope
from mien.facs.intensity import parse_au
from mien.heads import load_head
from mien.paths import require_asset
from mien.progress import progress as progress_bar
from mien.render.camera import camera_from_options
from mien.rig.au_solve import SOLVED_AUS, AUSolver
from mien.tracking import track_video
from mien.validate.activation import (
    DEFAULT_LENGTH,
    MIN_SAMPLES,
    activation_map,
    correlation_note,
    map_correlation,
    row_correlations,
)
from mien.validate.face_detector import MediaPipeDetector
from mien.validate.figures import plot_comparison
from mien.validate.json_values import rounded
from mien.validate.stimuli import StimulusRenderer

__all__ = [
    "MIN_FACE_SHARE",
    "MIN_FRAMES",
    "CompareResult",
    "MapComparison",
    "run_compare",
]

MIN_FACE_SHARE = 0.8
"""Smallest share of a video's frames on which the face must be found (tracked or gap-filled)."""

MIN_FRAMES = 10
"""Fewest frames with a face a clip needs before it is resampled into a map (a third of a second at 30 fps)."""

_STUDY_ENVELOPE_S = (0.4, 0.3, 0.3)
"""Broekens' onset / hold / decay (seconds); stretched in proportion to the human clip's duration."""


@dataclass(frozen=True, eq=False)
class MapComparison:
    """Two activation maps of one expression (human and character) and their correlations."""

    name: str
    """What was compared: the expression (``"joy"``, ``"AU6+AU12"``) or ``"closed-loop"``."""
    aus: tuple[int, ...]
    """AU numbers, one per map row."""
    human: np.ndarray
    """(n_aus, length) the human's detected AU intensities 0..5 over normalised time."""
    character: np.ndarray
    """(n_aus, length) the character's detected AU intensities 0..5 over the same time samples."""
    character_face_share: float
    """Share (0..1) of rendered frames on which the detector found the character's face."""

    @property
    def r(self) -> float:
        """2D correlation coefficient of the two maps (MATLAB ``corr2``); NaN when either map is constant."""
        return map_correlation(self.human, self.character)

    @property
    def row_r(self) -> np.ndarray:
        """(n_aus,) correlation of each AU's row over time; NaN where either row is constant."""
        return row_correlations(self.human, self.character)

    @property
    def note(self) -> str:
        """Why :attr:`r` is undefined, or ``""``."""
        return correlation_note(self.human, self.character, "activation map")

    def to_dict(self) -> dict[str, Any]:
        """Plain-dict form (NaN as None; maps rounded to 1e-4)."""
        row_r = self.row_r
        return {
            "name": self.name,
            "r": rounded(self.r),
            "r_note": self.note,
            "per_au_r": {f"AU{code}": rounded(value) for code, value in zip(self.aus, row_r, strict=True)},
            "constant_rows": [f"AU{code}" for code, value in zip(self.aus, row_r, strict=True) if math.isnan(value)],
            "character_face_share": round(self.character_face_share, 4),
            "human_map": np.round(self.human, 4).tolist(),
            "character_map": np.round(self.character, 4).tolist(),
        }


@dataclass(frozen=True, eq=False)
class CompareResult:
    """The outcome of :func:`run_compare`."""

    video: str
    """Absolute path of the human video."""
    duration_s: float
    """Duration of the video, seconds (frame count / fps)."""
    fps: float
    """Frame rate of the video, frames per second."""
    n_frames: int
    """Decoded frames of the video."""
    face_share: float
    """Share (0..1) of the video's frames with the human's face (found or gap-filled)."""
    head: str
    """Name of the rig rendered (``"builtin"``, ``"ict-facekit"``...)."""
    identity: str | None
    """Head identity preset, or None for the head's default."""
    camera: str
    """Camera preset name."""
    size: tuple[int, int]
    """Render size (width, height), pixels."""
    length: int
    """Time samples per activation map."""
    detector: str
    """Name of the detector run over the rendered frames."""
    closed_loop: MapComparison
    """Human map vs the map of the human's AU estimates replayed on the character."""
    expression: MapComparison | None = None
    """Human map vs the character's own rendering of the named expression (Fig. 5), or None."""
    timings_s: dict[str, float] = field(default_factory=dict)
    """Wall-clock seconds per stage (tracking, closed loop, expression, total)."""

    @property
    def comparisons(self) -> tuple[MapComparison, ...]:
        """The expression comparison (when there is one) and the closed loop."""
        return (self.expression, self.closed_loop) if self.expression is not None else (self.closed_loop,)

    def to_dict(self) -> dict[str, Any]:
        """Plain-dict form of everything (the content of ``compare.json``)."""
        return {
            "video": self.video,
            "duration_s": round(self.duration_s, 4),
            "fps": self.fps,
            "n_frames": self.n_frames,
            "face_share": round(self.face_share, 4),
            "head": self.head,
            "identity": self.identity,
            "camera": self.camera,
            "size": list(self.size),
            "length": self.length,
            "detector": self.detector,
            "aus": [f"AU{code}" for code in self.closed_loop.aus],
            "expression": None if self.expression is None else self.expression.to_dict(),
            "closed_loop": self.closed_loop.to_dict(),
            "timings_s": {key: round(value, 3) for key, value in self.timings_s.items()},
        }

    def to_json(self) -> str:
        """JSON text of :meth:`to_dict` (NaN written as null)."""
        return json.dumps(self.to_dict(), indent=1)

    def per_au_csv(self) -> str:
        """CSV text, one row per AU: its row correlation in each comparison (empty when undefined), then the
        peak intensity of the human's row and of each character row (a row that barely moves has a noisy r)."""
        out = io.StringIO()
        writer = csv.writer(out, lineterminator="\n")
        peaks = ["human_peak", *(f"{c.name}_peak" for c in self.comparisons)]
        writer.writerow(["au", *(f"{c.name}_r" for c in self.comparisons), *peaks])
        columns = [c.row_r for c in self.comparisons]
        maxima = [m.max(axis=1) for m in (self.closed_loop.human, *(c.character for c in self.comparisons))]
        for i, code in enumerate(self.closed_loop.aus):
            r_cells = ("" if math.isnan(col[i]) else f"{col[i]:.4f}" for col in columns)
            writer.writerow([f"AU{code}", *r_cells, *(f"{m[i]:.3f}" for m in maxima)])
        return out.getvalue()

    def write(self, out_dir: str | os.PathLike[str]) -> dict[str, Path]:
        """Write ``compare.json``, ``per_au.csv`` and one PNG per comparison into ``out_dir``; returns the paths.

        Every file is written under a temporary name first and renamed when all are done (``compare.json``
        last), so a failure never leaves a complete-looking result.
        """
        folder = Path(out_dir)
        folder.mkdir(parents=True, exist_ok=True)
        figures = {f"{_slug(c.name)}.png": c for c in self.comparisons}
        final = {name: folder / name for name in (*figures, "per_au.csv", "compare.json")}
        partial = {name: folder / f".{name}.partial-{os.getpid()}" for name in final}
        try:
            for name, comparison in figures.items():
                plot_comparison(comparison, partial[name])
            partial["per_au.csv"].write_text(self.per_au_csv(), encoding="utf-8")
            partial["compare.json"].write_text(self.to_json() + "\n", encoding="utf-8")
            final["compare.json"].unlink(missing_ok=True)  # an old result must not outlive new figures
            for name in final:  # compare.json is last
                partial[name].replace(final[name])
        finally:
            for path in partial.values():
                path.unlink(missing_ok=True)
        return {Path(name).stem: path for name, path in final.items()}


def _slug(name: str) -> str:
    if name == "closed-loop":
        return "closed_loop"
    return "expression_" + "".join(ch if ch.isalnum() else "_" for ch in name.lower()).strip("_")


# ---------------------------------------------------------------------------------------------- running


def _expression_player(expression: str, intensity: float) -> Callable[[Any, Any], None]:
    """A function ``(character, envelope) -> None`` starting ``expression`` at t = 0."""
    names = known_names()
    try:
        emotion = resolve_emotion(expression)
    except UnknownNameError:
        pass
    else:

        def emote(character: Any, envelope: Any) -> None:
            character.emote(emotion, intensity, start_s=0.0, envelope=envelope)

        return emote
    parts = [p for p in expression.replace(",", "+").replace(" ", "+").split("+") if p]
    try:
        specs = [parse_au(part) for part in parts]
    except UnknownNameError:
        raise UnknownNameError("expression", expression, (*names, "AU lists such as AU6+AU12D")) from None
    if not specs:
        raise UnknownNameError("expression", expression, (*names, "AU lists such as AU6+AU12D"))

    def play(character: Any, envelope: Any) -> None:
        for spec in specs:  # an AU without a letter plays at C (3) scaled by the intensity
            value = min(5.0, (spec.intensity or 3.0) * intensity)
            character.play_au(
                spec, value, onset_s=envelope.onset_s, apex_s=envelope.hold_s, offset_s=envelope.decay_s, start_s=0.0
            )

    return play


def _check_video(track: Any, path: Path) -> None:
    n = track.n_frames
    found = int(track.face_found.sum())
    if found == 0:
        raise InvalidValueError("video", str(path), f"a video showing a face (none was found on any of its {n} frames)")
    share = float(track.tracked.mean())
    if share < MIN_FACE_SHARE:
        raise InvalidValueError(
            "video",
            str(path),
            f"a face on at least {MIN_FACE_SHARE:.0%} of frames (found on {share:.0%}: "
            f"{int(track.tracked.sum())} of {n} frames, gaps filled)",
        )
    if int(track.tracked.sum()) < MIN_FRAMES:
        raise InvalidValueError(
            "video",
            str(path),
            f"at least {MIN_FRAMES} frames with a face to resample into an activation map "
            f"(it has {int(track.tracked.sum())}, {n / track.fps:.2f} s)",
        )


def _au_rows(frames: np.ndarray, aus: Sequence[int]) -> np.ndarray:
    """(n, len(aus)) AU intensities of (n, 62) face frames (the mean of a lateral AU's two sides)."""
    return np.stack([frames[:, list(au_channels(code))].mean(axis=1) for code in aus], axis=1)


def _character_neutral(renderer: Any, detector: Any) -> np.ndarray:
    """(55,) the character's rendered neutral as the detector reads it (subtracted like the performer's)."""
    rgb, hint = renderer.render(np.zeros(len(FACE_CHANNELS)))
    detection = detector.detect(rgb, hint)
    if not detection.found or detection.blendshapes is None:  # no neutral to subtract
        return np.zeros(N_INPUT)
    return np.r_[np.asarray(detection.blendshapes, np.float64), np.zeros(3)]


def _detected_aus(
    renderer: Any,
    detector: Any,
    solver: Any,
    frames: np.ndarray,
    times_s: np.ndarray,
    desc: str,
    show_progress: bool,
    settings: CaptureSettings | None = None,
    neutral: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Render (n, 62) face frames, detect each; ``(aus (k, n_aus), times (k,))`` of the frames with a face.

    With ``settings`` the detected scores go through the capture path (filter, ``neutral`` subtracted, the
    reverse AU mapping) as the performer's did; without, straight through ``solver``.
    """
    scores: list[np.ndarray] = []
    kept: list[float] = []
    for frame, time_s in progress_bar(zip(frames, times_s, strict=True), len(frames), desc, show_progress):
        rgb, hint = renderer.render(frame)
        detection = detector.detect(rgb, hint)
        if detection.found and detection.blendshapes is not None and not detection.landmarks_from_hint:
            scores.append(detection.blendshapes)
            kept.append(float(time_s))
    if len(kept) < max(MIN_FRAMES, MIN_SAMPLES):
        raise MienError(
            f"{desc}: the detector found the character's face on only {len(kept)} of {len(frames)} rendered "
            f"frames (needs {MIN_FRAMES}); try another camera or a larger size"
        )
    times = np.asarray(kept)
    if settings is None:
        return solver.solve(np.stack(scores)), times
    n = len(kept)
    fps = (n - 1) / max(float(times[-1] - times[0]), 1e-9)
    captured = capture_frames(
        desc, fps, times, np.stack(scores), np.zeros((n, 3)), np.ones(n, bool), settings, neutral=neutral
    )
    return _au_rows(captured.frames, solver.aus), times


def run_compare(
    video_path: str | os.PathLike[str],
    expression: str | None,
    head: str = "default",
    identity: str | None = None,
    camera: str = "frontal-1m",
    size: tuple[int, int] = (512, 512),
    length: int = DEFAULT_LENGTH,
    progress: bool = True,
    *,
    intensity: float = 1.0,
    envelope: Any | None = None,
    aus: Sequence[int] | None = None,
    detector: Any | None = None,
    landmarker: str | os.PathLike[str] | None = None,
) -> CompareResult:
    """Compare the human in ``video_path`` with the character: the closed loop, and ``expression`` if given.

    expression: an emotion or blend (``"joy"``), or AUs (``"AU6+AU12D"``); None runs only the closed loop.
    head / identity: see :func:`mien.heads.load_head`. camera: a preset of
    :data:`mien.render.camera.CAMERA_PRESETS`. size: render (width, height) pixels. length: time samples
    per map. intensity: the expression's intensity (1 = the prototype). envelope: the expression's
    :class:`~mien.facs.envelope.Envelope` (default Broekens' 0.4/0.3/0.3 s stretched to the video's
    duration; a longer one than the video is an error). aus: AU numbers (map rows; default the 18 OpenFACS
    AUs). detector: run over the renders (default MediaPipe in image mode). landmarker: the
    ``face_landmarker.task`` path (default the configured asset).

    Raises :class:`InvalidValueError` (field ``video``) for a video that is missing, has no face, has a face
    on too few frames or is too short, :class:`MissingAssetError` for a missing model or head asset, and
    :class:`UnknownNameError` for an unknown head, identity, camera or expression.
    """
    started = time.perf_counter()
    timings: dict[str, float] = {}
    if int(length) != length or length < MIN_SAMPLES:
        raise InvalidValueError("length", length, f"an integer >= {MIN_SAMPLES}")
    if len(size) != 2 or min(int(s) for s in size) < 64:
        raise InvalidValueError("size", size, "(width, height) of at least 64 pixels each")
    # cheap checks first: a bad name or a missing asset fails before any video is decoded
    model = require_asset("face_landmarker", landmarker)
    view = camera_from_options(camera)
    play = _expression_player(expression, intensity) if expression is not None else None
    rig = load_head(head, identity)
    solver = AUSolver(aus=tuple(aus) if aus is not None else SOLVED_AUS)
    path = Path(video_path).expanduser().resolve()

    mark = time.perf_counter()
    track = track_video(path, model, show_progress=progress)
    _check_video(track, path)
    duration_s = track.n_frames / track.fps
    if envelope is not None and envelope.total_s > duration_s + 1e-9:
        raise InvalidValueError(
            "video",
            str(path),
            f"a clip at least as long as the expression ({envelope.total_s:.2f} s); it lasts {duration_s:.2f} s",
        )
    settings = CaptureSettings()
    capture = capture_track(track, settings)  # the one capture path (`mien capture`)
    tracked = capture.face_found
    human_times = track.timestamps_s[tracked]
    span = (float(track.timestamps_s[0]), float(track.timestamps_s[-1]))
    human_frames = capture.frames[tracked]
    human_map = activation_map(_au_rows(human_frames, solver.aus), human_times, length, span)
    timings["tracking"] = time.perf_counter() - mark

    own_detector = detector is None
    if detector is None:
        detector = MediaPipeDetector(model)
    expression_result: MapComparison | None = None
    try:
        with StimulusRenderer(rig, view, (int(size[0]), int(size[1]))) as renderer:
            mark = time.perf_counter()
            neutral = _character_neutral(renderer, detector)
            replay_aus, replay_times = _detected_aus(
                renderer, detector, solver, human_frames, human_times, "closed loop", progress, settings, neutral
            )
            closed = MapComparison(
                "closed-loop",
                solver.aus,
                human_map,
                activation_map(replay_aus, replay_times, length, span),
                len(replay_times) / len(human_times),
            )
            timings["closed_loop"] = time.perf_counter() - mark

            if play is not None and expression is not None:
                mark = time.perf_counter()
                if envelope is None:
                    envelope = Envelope(*(duration_s * part for part in _STUDY_ENVELOPE_S))
                character = Character(idle=False)
                play(character, envelope)
                clip: Clip = character.run(duration_s, fps=track.fps)
                times = track.timestamps_s
                character_aus, character_times = _detected_aus(
                    renderer, detector, solver, clip.sample(times - times[0]), times, expression, progress, settings,
                    neutral,
                )  # fmt: skip
                expression_result = MapComparison(
                    expression,
                    solver.aus,
                    human_map,
                    activation_map(character_aus, character_times, length, span),
                    len(character_times) / len(times),
                )
                timings["expression"] = time.perf_counter() - mark
    finally:
        if own_detector:
            detector.close()
    timings["total"] = time.perf_counter() - started
    return CompareResult(
        video=str(path),
        duration_s=duration_s,
        fps=track.fps,
        n_frames=track.n_frames,
        face_share=float(tracked.mean()),
        head=rig.name,
        identity=identity,
        camera=camera,
        size=(int(size[0]), int(size[1])),
        length=int(length),
        detector=str(getattr(detector, "name", type(detector).__name__)),
        closed_loop=closed,
        expression=expression_result,
        timings_s=timings,
    )
