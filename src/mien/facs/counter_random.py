"""Counter-based random numbers: ``uniform(seed, stream, counter)`` is a pure function.

Idle behaviour draws from these instead of a stateful generator so that a character's face at time t depends
only on its seed and t, and so that a batch of characters (vectorised over seeds) reproduces single
characters exactly. The mixer is SplitMix64 (Steele, Lea & Flood 2014), applied to a key built from the
three inputs; outputs are uniform doubles in [0, 1) with 53 random bits.
"""

from __future__ import annotations

import numpy as np

__all__ = ["normal", "uniform"]

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_SEED_MUL = np.uint64(0xD1B54A32D192ED03)
_STREAM_MUL = np.uint64(0xAEF17502108EF2D9)


def _mix(z: np.ndarray) -> np.ndarray:
    z = (z ^ (z >> np.uint64(30))) * _M1
    z = (z ^ (z >> np.uint64(27))) * _M2
    return z ^ (z >> np.uint64(31))


def uniform(seed: np.ndarray | int, stream: np.ndarray | int, counter: np.ndarray | int) -> np.ndarray:
    """Uniform [0, 1) doubles for broadcast arrays of (seed, stream, counter) non-negative integers.

    >>> float(uniform(1, 2, 3)) == float(uniform(1, 2, 3))
    True
    """
    with np.errstate(over="ignore"):
        key = (
            np.asarray(seed, dtype=np.uint64) * _SEED_MUL
            + np.asarray(stream, dtype=np.uint64) * _STREAM_MUL
            + (np.asarray(counter, dtype=np.uint64) + np.uint64(1)) * _GOLDEN
        )
        bits = _mix(_mix(key))
    return (bits >> np.uint64(11)).astype(np.float64) * (1.0 / 9007199254740992.0)


def normal(seed: np.ndarray | int, stream: np.ndarray | int, counter: np.ndarray | int) -> np.ndarray:
    """Standard normal doubles (Box-Muller on two counter-based uniforms)."""
    counter = np.asarray(counter, dtype=np.uint64)
    u1 = uniform(seed, stream, counter * np.uint64(2))
    u2 = uniform(seed, stream, counter * np.uint64(2) + np.uint64(1))
    return np.sqrt(-2.0 * np.log1p(-u1)) * np.cos(2.0 * np.pi * u2)
