"""The reverse AU solve recovers known AU mixes from synthetic blendshape vectors."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("scipy")

from mien.facs.catalogue import FACE_CHANNELS, au_channels
from mien.rig.au_solve import SOLVED_AUS, AUSolver
from mien.rig.mapping import AUMapping


def _frame(mix: dict[int, float]) -> np.ndarray:
    frame = np.zeros(len(FACE_CHANNELS))
    for code, value in mix.items():
        frame[list(au_channels(code))] = value
    return frame


@pytest.mark.parametrize(
    "mix",
    [
        {12: 3.0, 6: 2.0},  # joy
        {1: 3.5, 4: 2.0, 15: 3.5, 17: 2.0},  # sadness
        {1: 2.5, 2: 4.0, 5: 3.0, 26: 3.5},  # surprise
        {4: 4.0, 7: 2.0, 10: 2.5, 23: 1.0},  # anger without the open mouth
        {45: 5.0},
        {},
    ],
)
def test_recovers_known_mixes(mix: dict[int, float]) -> None:
    mapping = AUMapping.default()
    solver = AUSolver(mapping)
    aus = solver.solve(mapping.to_weights(_frame(mix)))
    expected = np.array([mix.get(code, 0.0) for code in solver.aus])
    np.testing.assert_allclose(aus, expected, atol=0.05)


def test_random_mixes_round_trip_and_batches() -> None:
    rng = np.random.default_rng(7)
    mapping = AUMapping.default()
    solver = AUSolver(mapping)
    # sparse mixes of 3 AUs that do not share a blendshape column, low enough that no weight clips at 1
    distinct = [1, 2, 6, 12, 15, 17, 20, 26, 28, 45]
    truth = np.zeros((20, len(solver.aus)))
    frames = np.zeros((20, len(FACE_CHANNELS)))
    for row in range(20):
        for code in rng.choice(distinct, 3, replace=False):
            value = rng.uniform(0.5, 3.0)
            truth[row, solver.aus.index(int(code))] = value
            frames[row, list(au_channels(int(code)))] = value
    estimate = solver.solve(mapping.to_weights(frames))
    assert estimate.shape == (20, len(SOLVED_AUS))
    np.testing.assert_allclose(estimate, truth, atol=0.1)


def test_bad_blendshapes_are_refused() -> None:
    from mien.errors import InvalidValueError

    solver = AUSolver()
    with pytest.raises(InvalidValueError, match="blendshapes"):
        solver.solve(np.zeros(51))
    with pytest.raises(InvalidValueError, match="blendshapes"):
        solver.solve(np.full(52, np.nan))
