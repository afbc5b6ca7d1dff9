"""Learning a laugh library from labelled videos (Mascaró et al. 2021, "Laugh and smile learning").

Pipeline: a folder of videos + a labels CSV (columns ``video,type,performer``) ->

1. labels: rows naming a missing file or an unknown type are skipped with a reason;
2. per video (in parallel): track the face (:func:`mien.tracking.track.track_video`, cached) and turn each
   take into controller curves (:func:`mien.learning.takes.controllers_from_track`); each video's
   result is checkpointed in the output's work folder (``<library>.work/videos/``), so a re-run resumes and
   never recomputes a finished video; a failing video is reported and skipped;
3. per type (in parallel): DTW distance matrices between all takes, one per controller (the paper's Table 3
   form) and one multivariate (all 16 controllers together);
4. per type: k-medoids on the multivariate DTW matrix and the representative curve of the main cluster
   (``method="medoid"``: a real performance; ``"dba"``: its DTW barycenter average). Clustering whole takes
   rather than each controller apart keeps one performance's controllers in step (per-controller prototypes
   taken from different performers would desynchronise the face);
5. a :class:`~mien.laughter.library.LaughLibrary` file, and optionally a report folder (summary text, DTW
   tables, heat maps, prototype plots).

Parallel work runs on a ``concurrent.futures.ProcessPoolExecutor`` (``workers`` processes) by default, in
this process when ``workers=0``, or on a Dask cluster when ``scheduler`` is given (an address or a
``dask.distributed.Client``); results are identical either way. Types with no usable take are absent from
the library (the generator then falls back to the built-in curve).
"""

from __future__ import annotations

import csv
import os
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from mien.errors import InvalidValueError, MienError
from mien.extras import require
from mien.facs.clip import Clip, interpolate_frames
from mien.fileio.container import load_container, save_container
from mien.fileio.hashing import key_sha256
from mien.laughter.library import LaughLibrary, LibraryMetadata, utc_now
from mien.laughter.names import CONTROLLER_NAMES, LAUGH_TYPES
from mien.learning.clustering import KMedoidsDTW, representative_curve
from mien.learning.dtw import dtw_distance_matrices_per_channel, dtw_distance_matrix
from mien.learning.dtw_report import format_dtw_table, plot_dtw_heatmap
from mien.learning.takes import controllers_from_track
from mien.paths import require_asset
from mien.plot import pyplot
from mien.progress import progress
from mien.tracking.track import track_video

__all__ = [
    "CHECKPOINT_VERSION",
    "MIN_TAKE_S",
    "LabelRow",
    "LearnResult",
    "Skip",
    "Take",
    "learn_library",
    "read_labels",
    "work_folder",
]

CHECKPOINT_VERSION = 1
"""Bumped when per-video results change meaning, so old checkpoints are not reused."""
CHECKPOINT_FORMAT = "mien-learn-checkpoint"
"""Container kind of a per-video checkpoint (:mod:`mien.fileio.container`)."""
MIN_TAKE_S = 0.5
"""Takes shorter than this (seconds) are rejected: too short to hold an onset, apex and offset."""
LABEL_COLUMNS = ("video", "type", "performer")
"""Required columns of the labels CSV."""


@dataclass(frozen=True)
class LabelRow:
    """One usable row of the labels file."""

    video: Path
    """Absolute path of the video."""
    type: str
    """Laugh type id."""
    performer: str
    """Performer name (labels the DTW tables)."""
    line: int
    """Line number in the labels file (1 = header)."""


@dataclass(frozen=True)
class Skip:
    """Something left out, and why."""

    what: str
    """The label line, video or take."""
    reason: str
    """Why it was left out."""


@dataclass(frozen=True)
class Take:
    """One performance used for learning."""

    label: str
    """``performer`` (``performer#k`` when a video has several takes)."""
    type: str
    """Laugh type id."""
    video: str
    """Video file name."""
    curves: Clip
    """Controller curves at the library frame rate."""


@dataclass(frozen=True)
class LearnResult:
    """What :func:`learn_library` did."""

    library: LaughLibrary
    """The learned library (also saved to ``path``)."""
    path: Path
    """Where the library was written."""
    takes: tuple[Take, ...]
    """Takes used, in label order."""
    skipped: tuple[Skip, ...]
    """Label rows, videos and takes left out, with reasons."""
    computed: tuple[str, ...]
    """Videos processed in this run (the others came from checkpoints)."""
    resumed: tuple[str, ...]
    """Videos whose results were read back from checkpoints."""
    dtw: dict[str, np.ndarray] = field(default_factory=dict)
    """Per type, (16, n, n) per-controller DTW matrices between its takes."""
    summary: str = ""
    """Human-readable summary (also ``summary.txt`` in the report folder)."""


# ----------------------------------------------------------------------------------------------- labels


def _type_id(text: str) -> str:
    return text.strip().lower().replace("-", "_").replace(" ", "_")


def read_labels(labels: str | os.PathLike[str], video_dir: str | os.PathLike[str]) -> tuple[list[LabelRow], list[Skip]]:
    """Parse a labels CSV (``video,type,performer``; ``#`` comment lines allowed) against ``video_dir``.

    Returns the usable rows and the skipped ones (missing video file, unknown type, empty fields). Type
    names are matched case-insensitively with spaces or hyphens for underscores (``"Sly smile"``).
    """
    path = Path(labels)
    if not path.is_file():
        raise InvalidValueError("labels", str(path), "an existing CSV file with columns video,type,performer")
    folder = Path(video_dir)
    if not folder.is_dir():
        raise InvalidValueError("video_dir", str(folder), "an existing folder of videos")
    lines = path.read_text(encoding="utf-8-sig").splitlines()
    body = [(number, line) for number, line in enumerate(lines, 1) if line.strip() and not line.startswith("#")]
    reader = csv.reader([line for _, line in body])
    header = [h.strip().lower() for h in next(reader, [])]
    missing = [c for c in LABEL_COLUMNS if c not in header]
    if missing:
        raise InvalidValueError("labels columns", header, f"a header with columns {', '.join(LABEL_COLUMNS)}")
    rows: list[LabelRow] = []
    skips: list[Skip] = []
    for (number, _), cells in zip(body[1:], reader, strict=True):
        values = dict(zip(header, (c.strip() for c in cells), strict=False))
        what = f"{path.name}:{number}"
        video, kind, performer = (values.get(c, "") for c in LABEL_COLUMNS)
        if not video or not kind:
            skips.append(Skip(what, "empty video or type field"))
            continue
        type_name = _type_id(kind)
        if type_name not in LAUGH_TYPES:
            skips.append(Skip(f"{what} {video}", f"unknown laugh type {kind!r} (known: {', '.join(LAUGH_TYPES)})"))
            continue
        file = (folder / video).resolve()
        if not file.is_file():
            skips.append(Skip(f"{what} {video}", f"video file not found: {file}"))
            continue
        rows.append(LabelRow(file, type_name, performer or file.stem, number))
    return rows, skips


# ------------------------------------------------------------------------------------------ per video


@dataclass(frozen=True)
class _VideoJob:
    video: str
    eps: float
    model: str | None


@dataclass(frozen=True)
class _VideoOutcome:
    video: str
    takes: tuple[np.ndarray, ...]
    fps: float
    error: str
    final: bool  # a deterministic outcome worth checkpointing (success or a rejected input)


def _process_video(job: _VideoJob) -> _VideoOutcome:
    """Track one video and compute controller curves per take (runs in a worker; never raises)."""
    try:
        track = track_video(job.video, job.model, show_progress=False)
        clips = controllers_from_track(track, eps=job.eps)
        if not clips:
            return _VideoOutcome(job.video, (), float(track.fps), "no face found in any frame", True)
        return _VideoOutcome(job.video, tuple(c.values for c in clips), float(clips[0].fps), "", True)
    except MienError as exc:
        return _VideoOutcome(job.video, (), 0.0, f"{type(exc).__name__}: {exc}", True)
    except Exception as exc:  # a broken video must never kill the run; not checkpointed, retried next time
        return _VideoOutcome(job.video, (), 0.0, f"{type(exc).__name__}: {exc}", False)


def work_folder(output: str | os.PathLike[str]) -> Path:
    """The work folder of a library being learned into ``output``: ``<output without .npz>.work``."""
    out = Path(output)
    stem = out.name[: -len(".npz")] if out.name.endswith(".npz") else out.name
    return out.with_name(stem + ".work")


def _checkpoint_path(work: Path, job: _VideoJob) -> Path:
    stat = Path(job.video).stat()
    key = {
        "video": job.video,
        "size": stat.st_size,
        "mtime_ns": stat.st_mtime_ns,
        "eps": job.eps,
        "model": job.model,
        "version": CHECKPOINT_VERSION,
    }
    digest = key_sha256(key, 24)
    return work / "videos" / f"{Path(job.video).stem}-{digest}.npz"


def _save_checkpoint(path: Path, outcome: _VideoOutcome) -> None:

    meta = {"video": outcome.video, "fps": outcome.fps, "error": outcome.error, "n_takes": len(outcome.takes)}
    arrays = {f"take_{i}": values for i, values in enumerate(outcome.takes)}
    save_container(path, CHECKPOINT_FORMAT, CHECKPOINT_VERSION, meta, arrays, compress=False)  # atomic


def _load_checkpoint(path: Path) -> _VideoOutcome | None:

    try:
        box = load_container(path, CHECKPOINT_FORMAT, CHECKPOINT_VERSION)
        meta = box.meta
        takes = tuple(box.arrays[f"take_{i}"] for i in range(int(meta["n_takes"])))
    except (InvalidValueError, KeyError, ValueError, TypeError):
        return None  # damaged: compute again
    return _VideoOutcome(str(meta["video"]), takes, float(meta["fps"]), str(meta["error"]), True)


# ----------------------------------------------------------------------------------------- executors


def _type_dtw(series: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(16, n, n) per-controller and (n, n) multivariate DTW matrices of one type's takes."""

    return dtw_distance_matrices_per_channel(series, n_jobs=1), dtw_distance_matrix(series, n_jobs=1)


class _Backend:
    """Where parallel work runs: this process (``workers=0``), a lazily started process pool, or Dask."""

    def __init__(self, workers: int | None, client: Any, size_hint: int) -> None:
        self.workers = workers
        self.client = client
        self.size_hint = max(1, size_hint)
        self.pool: Any = None

    def close(self) -> None:
        """Shut the process pool down (a Dask client belongs to the caller)."""
        if self.pool is not None:
            self.pool.shutdown()
            self.pool = None

    def run(
        self, function: Callable[[Any], Any], items: Sequence[Any], desc: str, show_progress: bool
    ) -> Iterator[tuple[int, Any]]:
        """Yield ``(index, result or exception)`` as each item finishes."""
        if not items:
            return
        if self.client is not None:
            from dask.distributed import as_completed as dask_completed

            futures = [self.client.submit(function, item, pure=False) for item in items]
            index = {f.key: i for i, f in enumerate(futures)}
            for future in progress(dask_completed(futures), len(futures), desc, show_progress):
                try:
                    yield index[future.key], future.result()
                except Exception as exc:
                    yield index[future.key], exc
            return
        if self.workers == 0:
            for i, item in progress(enumerate(items), len(items), desc, show_progress):
                try:
                    yield i, function(item)
                except Exception as exc:
                    yield i, exc
            return
        if self.pool is None:
            import multiprocessing
            from concurrent.futures import ProcessPoolExecutor

            count = min(self.workers or os.cpu_count() or 1, self.size_hint)
            # spawn, not fork: the parent may hold numba/mediapipe threads, which fork would copy half-alive
            self.pool = ProcessPoolExecutor(count, mp_context=multiprocessing.get_context("spawn"))
        from concurrent.futures import as_completed

        pending: dict[Future[Any], int] = {self.pool.submit(function, item): i for i, item in enumerate(items)}
        for future in progress(as_completed(pending), len(pending), desc, show_progress):
            try:
                yield pending[future], future.result()
            except Exception as exc:  # a crashed worker process
                yield pending[future], exc


def _connect(scheduler: Any) -> tuple[Any, bool]:
    """``(client, owned)`` for a scheduler address or an existing Dask client (None: no client)."""
    if scheduler is None:
        return None, False
    if not isinstance(scheduler, str):
        return scheduler, False
    return require("dask.distributed", "distributed").Client(scheduler), True


# ------------------------------------------------------------------------------------------- learning


def _resample(values: np.ndarray, fps: float, target_fps: float) -> np.ndarray:
    if fps == target_fps:
        return values
    times = np.arange(int(np.floor((values.shape[0] - 1) / fps * target_fps)) + 1) / target_fps
    return interpolate_frames(values, fps, times)


def learn_library(
    video_dir: str | os.PathLike[str],
    labels: str | os.PathLike[str],
    output: str | os.PathLike[str],
    *,
    eps: float = 0.2,
    workers: int | None = None,
    scheduler: Any = None,
    method: str = "medoid",
    report_dir: str | os.PathLike[str] | None = None,
    seed: int = 0,
    model: str | os.PathLike[str] | None = None,
    show_progress: bool = True,
) -> LearnResult:
    """Learn a laugh library from the videos in ``video_dir`` labelled by ``labels``; save it to ``output``.

    eps: controller hardness (paper's Eq 1). workers: processes (None: one per CPU; 0: in this process).
    scheduler: a Dask scheduler address or ``dask.distributed.Client`` (replaces the process pool).
    method: ``"medoid"`` or ``"dba"``. report_dir: where to write the summary, DTW tables and plots (None:
    no report files). seed: clustering seed. model: the face landmarker (default: the configured asset).
    Raises :class:`InvalidValueError` when no usable take remains (the message lists the reasons).
    """
    if method not in ("medoid", "dba"):
        raise InvalidValueError("method", method, "'medoid' or 'dba'")
    if not np.isfinite(eps) or eps <= 0:
        raise InvalidValueError("eps", eps, "a positive hardness factor (the paper uses 0.1-0.3)")
    if workers is not None and workers < 0:
        raise InvalidValueError("workers", workers, "0 (in this process) or a positive number of processes")
    rows, skipped = read_labels(labels, video_dir)
    if not rows:
        raise InvalidValueError("labels", str(labels), _nothing_usable(skipped))
    model_path = str(Path(model).resolve()) if model is not None else None
    if model_path is None:
        model_path = str(require_asset("face_landmarker"))
    output = Path(output)
    work = work_folder(output)
    videos = list(dict.fromkeys(str(row.video) for row in rows))
    jobs = [_VideoJob(v, float(eps), model_path) for v in videos]
    outcomes: dict[str, _VideoOutcome] = {}
    todo: list[_VideoJob] = []
    for job in jobs:
        saved = _load_checkpoint(_checkpoint_path(work, job)) if _checkpoint_path(work, job).is_file() else None
        if saved is not None:
            outcomes[job.video] = saved
        else:
            todo.append(job)
    resumed = tuple(Path(v).name for v in outcomes)
    client, owned = _connect(scheduler)
    backend = _Backend(workers, client, len(videos))
    try:
        for index, outcome in backend.run(_process_video, todo, "videos", show_progress):
            job = todo[index]
            if isinstance(outcome, BaseException):
                outcome = _VideoOutcome(job.video, (), 0.0, f"worker failed: {outcome!r}", False)
            if outcome.final:
                _save_checkpoint(_checkpoint_path(work, job), outcome)
            outcomes[job.video] = outcome
        takes, more = _collect_takes(rows, outcomes)
        skipped += more
        if not takes:
            raise InvalidValueError("labels", str(labels), _nothing_usable(skipped))
        by_type = {t: [take for take in takes if take.type == t] for t in LAUGH_TYPES}
        by_type = {t: group for t, group in by_type.items() if group}
        series = [[take.curves.values for take in group] for group in by_type.values()]
        matrices: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        names = list(by_type)
        for index, result in backend.run(_type_dtw, series, "DTW", show_progress):
            if isinstance(result, BaseException):
                raise result
            matrices[names[index]] = result
    finally:
        backend.close()
        if owned:
            client.close()
    library_fps = takes[0].curves.fps
    curves, extra = _representatives(by_type, matrices, method, seed)
    metadata = LibraryMetadata(
        source=f"learned:{Path(video_dir).resolve()}",
        eps=float(eps),
        fps=library_fps,
        n_takes={t: len(group) for t, group in by_type.items()},
        created=utc_now(),
        method=method,
        extra=extra,
    )
    library = LaughLibrary({t: Clip(v, library_fps, CONTROLLER_NAMES) for t, v in curves.items()}, metadata)
    path = library.save(output)
    computed = tuple(Path(job.video).name for job in todo)
    result = LearnResult(
        library,
        path,
        tuple(takes),
        tuple(skipped),
        computed,
        resumed,
        {t: m[0] for t, m in matrices.items()},
    )
    text = _summary(result, {t: m[1] for t, m in matrices.items()})
    result = replace(result, summary=text)
    if report_dir is not None:
        write_report(result, report_dir, {t: m[1] for t, m in matrices.items()})
    return result


def _nothing_usable(skipped: Sequence[Skip]) -> str:
    reasons = "; ".join(f"{s.what}: {s.reason}" for s in skipped[:10]) or "the labels file has no rows"
    return f"at least one usable labelled video; nothing usable remained ({reasons})"


def _collect_takes(rows: list[LabelRow], outcomes: dict[str, _VideoOutcome]) -> tuple[list[Take], list[Skip]]:
    takes: list[Take] = []
    skipped: list[Skip] = []
    target_fps = next((o.fps for o in (outcomes[str(r.video)] for r in rows) if o.takes), 30.0)
    for row in rows:
        outcome = outcomes[str(row.video)]
        name = row.video.name
        if outcome.error:
            skipped.append(Skip(f"{name} ({row.performer}, {row.type})", outcome.error))
            continue
        for k, values in enumerate(outcome.takes):
            label = row.performer if len(outcome.takes) == 1 else f"{row.performer}#{k}"
            duration = values.shape[0] / outcome.fps
            if duration < MIN_TAKE_S:
                skipped.append(
                    Skip(f"{name} take {k} ({row.performer})", f"too short ({duration:.2f} s < {MIN_TAKE_S} s)")
                )
                continue
            curves = Clip(_resample(values, outcome.fps, target_fps), target_fps, CONTROLLER_NAMES)
            takes.append(Take(label, row.type, name, curves))
    return takes, skipped


def _representatives(
    by_type: dict[str, list[Take]], matrices: dict[str, tuple[np.ndarray, np.ndarray]], method: str, seed: int
) -> tuple[dict[str, np.ndarray], dict[str, Any]]:

    curves: dict[str, np.ndarray] = {}
    extra: dict[str, Any] = {}
    for type_name, group in by_type.items():
        series = [take.curves.values for take in group]
        multivariate = matrices[type_name][1]
        model = KMedoidsDTW(random_state=seed).fit(precomputed=multivariate)
        curves[type_name] = representative_curve(
            series,
            "dba" if method == "dba" else "medoid",
            random_state=seed,
            precomputed=multivariate,
        )
        extra[type_name] = {
            "takes": [f"{t.label}:{t.video}" for t in group],
            "n_clusters": int(model.n_clusters_),
            "cluster_sizes": np.bincount(model.labels_).tolist(),
            "medoid": group[int(model.medoid_indices_[0])].label,
        }
    return curves, extra


# ------------------------------------------------------------------------------------------- reporting


def _summary(result: LearnResult, multivariate: dict[str, np.ndarray]) -> str:
    lines = [f"laugh library: {result.path}", f"takes used: {len(result.takes)}"]
    for take in result.takes:
        lines.append(f"  {take.type:22s} {take.label:16s} {take.video} ({take.curves.duration_s:.2f} s)")
    lines.append(f"left out: {len(result.skipped)}")
    lines += [f"  {s.what}: {s.reason}" for s in result.skipped]
    lines.append(f"videos computed this run: {len(result.computed)}, resumed from checkpoints: {len(result.resumed)}")
    for type_name, info in result.library.metadata.extra.items():
        matrix = multivariate[type_name]
        mean = float(matrix[np.triu_indices(matrix.shape[0], 1)].mean()) if matrix.shape[0] > 1 else 0.0
        lines.append(
            f"{type_name}: {len(info['takes'])} take(s), {info['n_clusters']} cluster(s) of sizes "
            f"{info['cluster_sizes']}, representative from {info['medoid']}, mean DTW {mean:.3f}"
        )
    return "\n".join(lines)


def write_report(result: LearnResult, report_dir: str | os.PathLike[str], multivariate: dict[str, np.ndarray]) -> Path:
    """Write ``summary.txt``, ``dtw_<type>.txt`` tables, heat maps and prototype plots into ``report_dir``."""

    folder = Path(report_dir)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "summary.txt").write_text(result.summary + "\n", encoding="utf-8")
    for type_name, per_channel in result.dtw.items():
        labels = [t.label for t in result.takes if t.type == type_name]
        tables = [format_dtw_table(multivariate[type_name], labels, f"{type_name}: all controllers")]
        for k, controller in enumerate(CONTROLLER_NAMES):
            tables.append(format_dtw_table(per_channel[k], labels, f"{type_name}: {controller}"))
        (folder / f"dtw_{type_name}.txt").write_text("\n\n".join(tables) + "\n", encoding="utf-8")
        plot_dtw_heatmap(multivariate[type_name], labels, folder / f"dtw_{type_name}.png", f"{type_name}: DTW")
        smile = CONTROLLER_NAMES.index("smileFrown")
        plot_dtw_heatmap(
            per_channel[smile], labels, folder / f"dtw_{type_name}_smileFrown.png", f"{type_name}: smileFrown"
        )
        _plot_prototype(result, type_name, folder / f"prototype_{type_name}.png")
    return folder


def _plot_prototype(result: LearnResult, type_name: str, path: Path) -> None:

    plt = pyplot()
    prototype = result.library.curve(type_name)
    takes = [t for t in result.takes if t.type == type_name]
    order = np.argsort(-np.abs(prototype.values).max(axis=0))[:4]
    figure, axes = plt.subplots(len(order), 1, figsize=(8, 1.8 * len(order)), sharex=True, squeeze=False)
    for row, column in zip(axes[:, 0], order, strict=True):
        for take in takes:
            row.plot(take.curves.times_s, take.curves.values[:, column], color="0.7", linewidth=0.8)
        row.plot(prototype.times_s, prototype.values[:, column], color="C0", linewidth=1.8)
        row.set_ylabel(CONTROLLER_NAMES[column], fontsize=8)
    axes[-1, 0].set_xlabel("time (s)")
    axes[0, 0].set_title(f"{type_name}: representative (blue) and takes (grey)")
    figure.tight_layout()
    figure.savefig(path, dpi=90)
    plt.close(figure)
