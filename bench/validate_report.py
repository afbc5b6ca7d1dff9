"""Benchmark: `mien validate report` for one head with the averaged judge against the code before it.

The averaged judge (mien.validate.judge) reads every face twelve times (two render sizes, six crops); the report
must not take longer than before it. Baseline: the same command run from a checkout of the earlier code (``--baseline
SRC``, its ``src`` folder, e.g. a ``git worktree add /tmp/old <commit>``), in the same run, interleaved (baseline,
current, baseline, current...) so the machine's load falls on both alike. Prints the medians, the spread (min..max)
of the repeats and the ratio current / baseline (target <= 1.00), and each run's stage timings from its report.

Run: ``.venv/bin/python bench/validate_report.py --baseline /tmp/old/src [--head ict:a] [--repeats 3]``
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SHARED = Path(os.environ.get("MIEN_SHARED", Path(__file__).resolve().parents[2] / "shared"))
CURRENT = Path(__file__).resolve().parents[1] / "src"


def _environment(src: Path) -> dict[str, str]:
    env = dict(os.environ)
    defaults = {
        "MIEN_ICT_FACEKIT": SHARED / "assets" / "ict-facekit",
        "MIEN_FACE_LANDMARKER": SHARED / "models" / "face_landmarker.task",
        "MIEN_EMOTION_MODEL": SHARED / "models" / "emotion" / "fer_emotion_model_quantized.tflite",
    }
    for name, path in defaults.items():
        if name not in env and path.exists():
            env[name] = str(path)
    env["PYTHONPATH"] = str(src)
    return env


def _stages(report: Path) -> str:
    """``"rig fidelity 9.1, emotion recognition 30.2"`` from the report's timing table."""
    text = report.read_text(encoding="utf-8") if report.is_file() else ""
    table = text.split("<h2>Timings (seconds per stage)</h2>")[-1].split("</table>")[0]
    cells = re.findall(r"<td>([^<]*)</td>", table)
    return ", ".join(f"{cells[i]} {cells[i + 1]}" for i in range(0, len(cells) - 1, 2))


def run_once(src: Path, head: str) -> tuple[float, str]:
    """Seconds of one ``mien validate report --head HEAD`` with ``src`` first on the path, and its stage timings."""
    with tempfile.TemporaryDirectory() as folder:
        argv = [sys.executable, "-m", "mien.cli", "validate", "report", "--head", head, "--quiet", "-o", folder]
        started = time.perf_counter()
        subprocess.run(argv, check=True, capture_output=True, env=_environment(src))
        seconds = time.perf_counter() - started
        return seconds, _stages(Path(folder) / "report.html")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", type=Path, required=True, help="the earlier code's src folder")
    parser.add_argument("--head", default="ict:a")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    times: dict[str, list[float]] = {"baseline": [], "current": []}
    for repeat in range(args.repeats):
        for name, src in (("baseline", args.baseline), ("current", CURRENT)):
            seconds, stages = run_once(src, args.head)
            times[name].append(seconds)
            print(f"  round {repeat + 1} {name:8s} {seconds:6.1f} s  ({stages})", flush=True)
    base, now = statistics.median(times["baseline"]), statistics.median(times["current"])
    print(f"mien validate report --head {args.head}, {args.repeats} interleaved rounds")
    for name, values in times.items():
        print(f"  {name:8s} {statistics.median(values):6.1f} s  (min {min(values):.1f}, max {max(values):.1f})")
    print(f"  ratio current/baseline: {now / base:.2f}  (target <= 1.00)")


if __name__ == "__main__":
    main()
