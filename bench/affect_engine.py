"""Per-frame cost of the emotion engine (mien.affect) against a plain-numpy step doing the same work.

Run: .venv/bin/python bench/affect_engine.py
Prints the median of several repeats (microseconds per frame) and the ratio against the baseline, a
straightforward numpy implementation of one frame (vectorised envelopes over event arrays, np.add.at,
numpy moving average), measured in the same run.
"""

from __future__ import annotations

import math
import statistics
import time
from collections.abc import Callable

import numpy as np

from mien.affect.basis import expression, feature_point_basis
from mien.affect.engine import EmotionEngine
from mien.facs.envelope import envelope_value, envelope_values

FRAMES = 20_000
REPEATS = 7
DT = 1.0 / 60.0


def median_us(step: Callable[[float], object], frames: int = FRAMES) -> float:
    """Median over REPEATS of the mean time per call of ``step(t)``, microseconds."""
    runs = []
    for r in range(REPEATS):
        t0 = time.perf_counter()
        for i in range(frames):
            step(1e-9 * (r * frames + i))  # times stay inside the events' hold
        runs.append((time.perf_counter() - t0) / frames * 1e6)
    return statistics.median(runs)


def numpy_baseline(n_events: int) -> Callable[[float], object]:
    """The same frame done with numpy arrays throughout."""
    starts = np.zeros(n_events)
    index = np.arange(n_events) % 6
    amounts = np.full(n_events, 1.2)
    mood = np.zeros(6)
    state = {"t": 0.0}
    k_tau = 10.0

    def step(t: float) -> object:
        values = envelope_values(t + 0.5 - starts, 0.4, 0.3, 0.3) * amounts
        emotion = np.zeros(6)
        np.add.at(emotion, index, values)
        np.minimum(emotion, 5.0, out=emotion)
        k = -math.expm1(-(t - state["t"]) / k_tau)
        state["t"] = t
        mood[:] += k * (emotion - mood)
        shown = (1.0 - min(1.0, float(emotion.sum()))) * mood
        return emotion, shown

    return step


def engine_step(n_events: int) -> Callable[[float], object]:
    engine = EmotionEngine()
    names = ("joy", "sadness", "anger", "surprise", "disgust", "fear")
    for i in range(n_events):
        engine.trigger(names[i % 6], 1.2, -0.5)
    engine.intensities(0.0)
    emotion_out, mood_out = np.empty(6), np.empty(6)

    def step(t: float) -> object:
        return engine.expressed(t, emotion_out, mood_out)

    return step


def main() -> None:
    print(f"emotion engine, one frame (median of {REPEATS} x {FRAMES} frames), microseconds")
    for n in (0, 1, 3, 10):
        base = median_us(numpy_baseline(n)) if n else float("nan")
        ours = median_us(engine_step(n))
        ratio = f"{base / ours:5.1f}x faster than the numpy baseline" if n else "(no baseline: nothing to add)"
        print(
            f"  {n:2d} active events: EmotionEngine.expressed {ours:6.2f} us   numpy baseline {base:6.2f} us   {ratio}"
        )
    basis = feature_point_basis()
    out = np.empty(basis.shape[1])
    weights = np.linspace(0.1, 0.6, 6)
    ours = median_us(lambda t: expression(weights, basis, out=out))
    base = median_us(lambda t: weights @ basis)
    print(
        f"  expression (6,)@(6,54) into out: {ours:5.2f} us   baseline `weights @ basis`: {base:5.2f} us   "
        f"ratio {base / ours:4.2f}"
    )
    elapsed = np.random.default_rng(0).uniform(-0.5, 1.5, (1000, 4))
    flat = elapsed.ravel().tolist()
    ours = median_us(lambda t: envelope_values(elapsed, 0.4, 0.3, 0.3), frames=200)
    base = median_us(lambda t: [envelope_value(x, 0.4, 0.3, 0.3) for x in flat], frames=20)
    print(
        f"  envelope_values, 1000 characters x 4 events: {ours:6.1f} us   baseline scalar envelope_value loop: "
        f"{base:7.1f} us   {base / ours:5.1f}x faster"
    )


if __name__ == "__main__":
    main()
