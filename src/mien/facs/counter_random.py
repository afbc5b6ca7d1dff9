"""Counter-based random numbers: ``uniform(seed, stream, counter)`` is a pure function.

Idle behaviour draws from these instead of a stateful generator so that a character's face at time t depends
only on its seed and t, and so that a batch of characters (vectorised over seeds) reproduces single
characters exactly. The mixer is SplitMix64 (Steele, Lea & Flood 2014), applied to a key built from the
three inputs; outputs are uniform doubles in [0, 1) with 53 random bits.

A caller that draws the same (seed, stream) pairs again and again (idle walks, once per tick) builds their
part of the key once with :func:`stream_keys` and draws with :func:`uniform_from_keys`: the same numbers as
:func:`uniform`, with four fewer array operations a draw and the mixing done in place.
"""

from __future__ import annotations

import numpy as np

__all__ = ["normal", "stream_keys", "uniform", "uniform_from_keys"]

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_SEED_MUL = np.uint64(0xD1B54A32D192ED03)
_STREAM_MUL = np.uint64(0xAEF17502108EF2D9)
_S30, _S27, _S31, _S11 = (np.uint64(s) for s in (30, 27, 31, 11))
_ONE = np.uint64(1)
_TO_UNIT = 1.0 / 9007199254740992.0


def _mix_in_place(z: np.ndarray, scratch: np.ndarray) -> None:
    """SplitMix64's finaliser on a uint64 array, in place (``scratch``: a buffer of the same shape)."""
    np.right_shift(z, _S30, out=scratch)
    z ^= scratch
    z *= _M1
    np.right_shift(z, _S27, out=scratch)
    z ^= scratch
    z *= _M2
    np.right_shift(z, _S31, out=scratch)
    z ^= scratch


def stream_keys(seed: np.ndarray | int, stream: np.ndarray | int) -> np.ndarray:
    """The (seed, stream) part of the key, broadcast: reuse it with :func:`uniform_from_keys`."""
    with np.errstate(over="ignore"):
        return np.asarray(
            np.asarray(seed, dtype=np.uint64) * _SEED_MUL + np.asarray(stream, dtype=np.uint64) * _STREAM_MUL,
            dtype=np.uint64,
        )


def uniform_from_keys(keys: np.ndarray, counter: np.ndarray | int) -> np.ndarray:
    """``uniform(seed, stream, counter)`` for ``keys = stream_keys(seed, stream)``; a new float array."""
    with np.errstate(over="ignore"):
        z = np.add(keys, (np.asarray(counter, dtype=np.uint64) + _ONE) * _GOLDEN, dtype=np.uint64)
        z = np.atleast_1d(z)
        scratch = np.empty_like(z)
        _mix_in_place(z, scratch)
        _mix_in_place(z, scratch)
        z >>= _S11
    out = z.astype(np.float64)
    out *= _TO_UNIT
    return out.reshape(np.broadcast_shapes(np.shape(keys), np.shape(counter)))


def uniform(seed: np.ndarray | int, stream: np.ndarray | int, counter: np.ndarray | int) -> np.ndarray:
    """Uniform [0, 1) doubles for broadcast arrays of (seed, stream, counter) non-negative integers.

    >>> float(uniform(1, 2, 3)) == float(uniform(1, 2, 3))
    True
    """
    return uniform_from_keys(stream_keys(seed, stream), counter)


def normal(seed: np.ndarray | int, stream: np.ndarray | int, counter: np.ndarray | int) -> np.ndarray:
    """Standard normal doubles (Box-Muller on two counter-based uniforms)."""
    counter = np.asarray(counter, dtype=np.uint64)
    u1 = uniform(seed, stream, counter * np.uint64(2))
    u2 = uniform(seed, stream, counter * np.uint64(2) + np.uint64(1))
    return np.sqrt(-2.0 * np.log1p(-u1)) * np.cos(2.0 * np.pi * u2)
