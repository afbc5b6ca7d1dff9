"""Learning a laugh library from labelled real video: skips, checkpoints and resume, pool vs Dask."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError
from mien.laughter.generator import generate
from mien.laughter.library import load_library
from mien.laughter.names import CONTROLLER_NAMES
from mien.learning.learn import LearnResult, learn_library, read_labels, work_folder


@pytest.fixture(scope="module")
def corpus(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder with a broken video and labels naming the real shared videos by absolute path."""
    folder = tmp_path_factory.mktemp("corpus")
    (folder / "broken.mp4").write_bytes(b"\x00\x01 not a video " * 200)
    video = shared_data / "video"
    (folder / "labels.csv").write_text(
        "video,type,performer\n"
        f"{video / 'single_face.mp4'},laughter,ann\n"
        f"{video / 'single_face.mp4'},Laughter,bob\n"
        "broken.mp4,laughter,carl\n"
        "missing.mp4,sly_smile,dan\n"
        f"{video / 'single_face.mp4'},giggle,eve\n"
        f"{video / 'no_face.mp4'},sly smile,fay\n",
        encoding="utf-8",
    )
    return folder


@pytest.fixture(scope="module")
def first_run(corpus: Path, landmarker_path: Path, tmp_path_factory: pytest.TempPathFactory) -> LearnResult:
    out = tmp_path_factory.mktemp("serial") / "lib.npz"
    return learn_library(
        corpus,
        corpus / "labels.csv",
        out,
        workers=0,
        model=landmarker_path,
        report_dir=out.parent / "report",
        show_progress=False,
    )


def test_read_labels_reports_missing_files_and_unknown_types(tmp_path: Path) -> None:
    (tmp_path / "a.mp4").write_bytes(b"x")
    (tmp_path / "labels.csv").write_text(
        "# my corpus\nvideo,type,performer\na.mp4,Sly-smile,p1\nb.mp4,laughter,p2\na.mp4,chuckle,p3\n,laughter,p4\n"
    )
    rows, skips = read_labels(tmp_path / "labels.csv", tmp_path)
    assert [(r.video.name, r.type, r.performer) for r in rows] == [("a.mp4", "sly_smile", "p1")]
    reasons = [s.reason for s in skips]
    assert reasons[0].startswith("video file not found")
    assert reasons[1].startswith("unknown laugh type 'chuckle'")
    assert reasons[2] == "empty video or type field"
    (tmp_path / "bad.csv").write_text("file,kind\na.mp4,laughter\n")
    with pytest.raises(InvalidValueError) as info:
        read_labels(tmp_path / "bad.csv", tmp_path)
    assert info.value.field == "labels columns"


def test_learn_uses_good_takes_and_reports_the_rest(first_run: LearnResult) -> None:
    library = first_run.library
    assert library.types == ("laughter",)
    assert library.metadata.n_takes == {"laughter": 2}
    assert [t.label for t in first_run.takes] == ["ann", "bob"]
    curve = library.curve("laughter")
    assert curve.channels == CONTROLLER_NAMES and curve.duration_s > 2.0
    assert np.abs(curve.values).max() > 0.0
    reasons = {s.what.split()[0]: s.reason for s in first_run.skipped}
    assert "not found" in reasons["labels.csv:5"]
    assert "unknown laugh type" in reasons["labels.csv:6"]
    assert "broken.mp4" in reasons and "InvalidValueError" in reasons["broken.mp4"]
    assert reasons["no_face.mp4"] == "no face found in any frame"
    assert first_run.dtw["laughter"].shape == (16, 2, 2)
    assert np.all(first_run.dtw["laughter"] == 0.0)  # the same video twice
    assert load_library(first_run.path).equals(library, ignore=())


def test_report_folder(first_run: LearnResult) -> None:
    report = first_run.path.parent / "report"
    names = sorted(p.name for p in report.iterdir())
    assert names == [
        "dtw_laughter.png",
        "dtw_laughter.txt",
        "dtw_laughter_smileFrown.png",
        "prototype_laughter.png",
        "summary.txt",
    ]
    summary = (report / "summary.txt").read_text()
    assert "takes used: 2" in summary and "no face found" in summary and "broken.mp4" in summary
    table = (report / "dtw_laughter.txt").read_text()
    assert "laughter: smileFrown" in table and "ann" in table


def test_rerun_resumes_without_recomputing(
    first_run: LearnResult, corpus: Path, landmarker_path: Path, tmp_path: Path
) -> None:
    # Rerun on a copy of the first run's output and work folder: the module's first run stays as it was written.
    out = tmp_path / first_run.path.name
    shutil.copy2(first_run.path, out)
    shutil.copytree(work_folder(first_run.path), work_folder(out))
    checkpoints = sorted((work_folder(out) / "videos").iterdir())
    assert len(checkpoints) == 3  # single_face, broken (a rejected input is final), no_face
    stamps = [p.stat().st_mtime_ns for p in checkpoints]
    again = learn_library(corpus, corpus / "labels.csv", out, workers=0, model=landmarker_path, show_progress=False)
    assert again.computed == ()
    assert sorted(again.resumed) == ["broken.mp4", "no_face.mp4", "single_face.mp4"]
    assert [p.stat().st_mtime_ns for p in checkpoints] == stamps
    assert again.library.equals(first_run.library)


def test_process_pool_and_dask_give_identical_libraries(
    first_run: LearnResult, corpus: Path, landmarker_path: Path, tmp_path: Path
) -> None:
    distributed = pytest.importorskip("dask.distributed")
    pooled = learn_library(
        corpus, corpus / "labels.csv", tmp_path / "pool.npz", workers=2, model=landmarker_path, show_progress=False
    )
    assert pooled.computed  # really ran in the pool, not from checkpoints
    with distributed.LocalCluster(
        n_workers=1, processes=False, threads_per_worker=2, dashboard_address=None
    ) as cluster:
        with distributed.Client(cluster) as client:
            dasked = learn_library(
                corpus,
                corpus / "labels.csv",
                tmp_path / "dask.npz",
                scheduler=client,
                model=landmarker_path,
                show_progress=False,
            )
    assert dasked.computed
    assert pooled.library.equals(dasked.library)
    assert pooled.library.equals(first_run.library)
    assert [s.reason for s in pooled.skipped] == [s.reason for s in dasked.skipped]


def test_nothing_usable_is_a_clear_error(corpus: Path, landmarker_path: Path, tmp_path: Path) -> None:
    labels = tmp_path / "labels.csv"
    labels.write_text("video,type,performer\nmissing.mp4,laughter,a\nbroken.mp4,giggle,b\n")
    with pytest.raises(InvalidValueError) as info:
        learn_library(corpus, labels, tmp_path / "x.npz", workers=0, model=landmarker_path, show_progress=False)
    assert "video file not found" in str(info.value) and "giggle" in str(info.value)
    labels.write_text("video,type,performer\nbroken.mp4,laughter,b\n")
    with pytest.raises(InvalidValueError) as info:
        learn_library(corpus, labels, tmp_path / "y.npz", workers=0, model=landmarker_path, show_progress=False)
    assert "broken.mp4" in str(info.value)


def test_learned_library_drives_the_generator(first_run: LearnResult) -> None:
    learned = generate("laughter", library=first_run.library, seed=1)
    builtin = generate("laughter", seed=1)
    assert not np.array_equal(learned.controllers.values, builtin.controllers.values)
    assert learned.face_clip.channel("AU12R").max() > 1.0
    assert generate("sly_smile", library=first_run.library) == generate("sly_smile")


def test_cli_learn_and_laugh(
    first_run: LearnResult, corpus: Path, landmarker_path: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mien.cli import main

    out = tmp_path / "cli.npz"
    code = main(
        [
            "learn",
            str(corpus),
            "--labels",
            str(corpus / "labels.csv"),
            "-o",
            str(out),
            "--workers",
            "0",
            "--landmarker",
            str(landmarker_path),
            "--method",
            "dba",
            "--quiet",
        ]
    )
    assert code == 0 and out.is_file()
    assert "takes used: 2" in capsys.readouterr().out
    assert load_library(out).metadata.method == "dba"
    assert main(["laugh", "laughter", "--library", str(out), "-o", str(tmp_path / "l.json")]) == 0
    assert (tmp_path / "l.json").stat().st_size > 1000
    assert os.path.exists(tmp_path / "l.json")
