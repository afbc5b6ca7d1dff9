"""Benchmark: ``mien assets fetch ict-facekit`` against a plain urllib copy of the same files, both from one
local HTTP server on 127.0.0.1 that serves the shared ICT-FaceKit copy at the commit's paths.

Run: ``.venv/bin/python bench/assets_fetch.py [REPEATS]``. Needs the asset (``MIEN_ICT_FACEKIT``, the config
file, or ``../shared/assets/ict-facekit``). The baseline copies the 76 files with ``urlopen`` +
``shutil.copyfileobj`` and checks nothing; a second baseline adds one SHA-256 per file. mien's fetch adds the
staging folder, ``.part`` files and renames, the resume scan and the progress generator (bar off). Repeats are
interleaved; each row prints median (min..max) and throughput; the ratio is mien / plain copy. A last row times
a resume with every file already verified (the hash scan alone). On a real network the transfer dominates:
this measures only what mien adds.
"""

from __future__ import annotations

import functools
import hashlib
import http.server
import shutil
import statistics
import sys
import tempfile
import threading
import time
import urllib.request
from collections.abc import Callable
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "src"))

from _ict import ict_facekit_folder  # noqa: E402

from mien.assets.fetch import SOURCES, fetch_asset, files_to_fetch, staging_folder  # noqa: E402


class _Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: object) -> None:
        pass


def _plain_copy(base: str, files: tuple[str, ...], dest: Path, hashed: bool) -> None:
    for path in files:
        target = dest / path
        target.parent.mkdir(parents=True, exist_ok=True)
        with urllib.request.urlopen(f"{base}/{path}", timeout=30) as response, target.open("wb") as handle:
            if not hashed:
                shutil.copyfileobj(response, handle, 1 << 16)
                continue
            digest = hashlib.sha256()
            while block := response.read(1 << 16):
                handle.write(block)
                digest.update(block)
            digest.hexdigest()


def _timed(run: Callable[[Path], None], work: Path) -> float:
    dest = Path(tempfile.mkdtemp(dir=work)) / "ict"
    start = time.perf_counter()
    run(dest)
    elapsed = time.perf_counter() - start
    shutil.rmtree(dest.parent)
    return elapsed


def _row(label: str, times: list[float], n_bytes: int) -> str:
    median = statistics.median(times)
    return (
        f"  {label:34s} median {median:6.3f} s  (min {min(times):.3f}, max {max(times):.3f})  "
        f"{n_bytes / 1e6 / median:6.0f} MB/s"
    )


def main() -> None:
    folder = ict_facekit_folder()
    if folder is None:
        return
    repeats = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    source = SOURCES["ict-facekit"]
    files = files_to_fetch(source)
    n_bytes = sum((folder / path).stat().st_size for path in files)
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(_Quiet, directory=str(folder)))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    base = f"http://127.0.0.1:{server.server_address[1]}"
    runs: dict[str, Callable[[Path], None]] = {
        "plain urllib copy (baseline)": lambda dest: _plain_copy(base, files, dest, hashed=False),
        "plain urllib copy + SHA-256": lambda dest: _plain_copy(base, files, dest, hashed=True),
        "mien fetch_asset": lambda dest: fetch_asset(source.name, base, dest, show_progress=False),
    }
    times: dict[str, list[float]] = {label: [] for label in runs}
    resume: list[float] = []
    with tempfile.TemporaryDirectory(prefix="mien-bench-fetch-") as work_text:
        work = Path(work_text)
        for run in runs.values():  # warm-up: page cache, imports, the loader's file list
            _timed(run, work)
        for _ in range(repeats):
            for label, run in runs.items():
                times[label].append(_timed(run, work))
            done = work / "resume" / "ict"  # every file verified, the rename not yet made
            fetch_asset(source.name, base, done, show_progress=False)
            done.rename(staging_folder(done))
            start = time.perf_counter()
            fetch_asset(source.name, base, done, show_progress=False)
            resume.append(time.perf_counter() - start)
            shutil.rmtree(work / "resume")
    server.shutdown()
    server.server_close()
    print(f"ICT-FaceKit from {folder}: {len(files)} files, {n_bytes / 1e6:.1f} MB over 127.0.0.1, {repeats} repeats")
    for label, values in times.items():
        print(_row(label, values, n_bytes))
    print(_row("mien resume, all files verified", resume, n_bytes))
    plain = statistics.median(times["plain urllib copy (baseline)"])
    print(f"ratio mien fetch_asset / plain urllib copy: {statistics.median(times['mien fetch_asset']) / plain:.2f}")
    hashed = statistics.median(times["plain urllib copy + SHA-256"])
    print(f"ratio mien fetch_asset / plain copy + SHA-256: {statistics.median(times['mien fetch_asset']) / hashed:.2f}")


if __name__ == "__main__":
    main()
