"""TEMPORARY stand-in for the row API of :class:`mien.character.CharacterBatch` while it is being rewritten.

The server codes against ``CharacterBatch(0).add_character(...)`` and friends. Until ``character.py`` has
them, :func:`new_batch` returns this adapter, which implements the same calls with one
:class:`mien.character.Character` per row. Delete this module once ``CharacterBatch.add_character`` exists.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from mien.errors import InvalidValueError

__all__ = ["new_batch"]


def new_batch() -> Any:
    """An empty batch with the row API (the real :class:`CharacterBatch` when it has ``add_character``)."""
    from mien.character import CharacterBatch

    if hasattr(CharacterBatch, "add_character"):
        return CharacterBatch(0)
    return _CharacterRows()


class _CharacterRows:
    """One :class:`~mien.character.Character` per row; rows of removed characters stay free (zeros)."""

    def __init__(self) -> None:
        from mien.facs.catalogue import FACE_CHANNELS

        self._characters: list[Any] = []
        self._frames = np.zeros((0, len(FACE_CHANNELS)))
        self._t_s = 0.0

    def add_character(self, seed: int = 0, idle: bool = True, expression_basis: str = "facs") -> int:
        from mien.character import Character

        character = Character(seed=seed, idle=idle, expression_basis=expression_basis)
        if self._t_s > 0:
            character.step(self._t_s)
        for row, existing in enumerate(self._characters):
            if existing is None:
                self._characters[row] = character
                return row
        self._characters.append(character)
        self._frames = np.vstack([self._frames, np.zeros((1, self._frames.shape[1]))])
        return len(self._characters) - 1

    def remove_character(self, row: int) -> None:
        self._characters[row] = None
        self._frames[row] = 0.0

    def active_rows(self) -> np.ndarray:
        return np.array([i for i, c in enumerate(self._characters) if c is not None], dtype=np.int64)

    def _each(self, rows: Any) -> list[Any]:
        return [self._characters[int(r)] for r in np.atleast_1d(rows)]

    def set_aus(self, rows: Any, intensities: Mapping[str, float], replace: bool = False) -> None:
        for c in self._each(rows):
            c.set_aus(intensities, replace=replace)

    def set_au(self, rows: Any, au: str, intensity: float, tau_s: float | None = None) -> None:
        for c in self._each(rows):
            c.set_au(au, intensity, tau_s)

    def set_speed(self, rows: Any, speed: float, au: str | None = None) -> None:
        from mien.facs.dynamics import time_constant_from_speed

        for c in self._each(rows):
            if au is None:
                c.facs.set_speed(speed)
            else:
                c.facs.set(au, float(c.facs.target[_first_channel(au)]), time_constant_from_speed(speed))

    def play_au(self, rows: Any, au: str, intensity: float, **timing: float) -> None:
        for c in self._each(rows):
            c.play_au(au, intensity, **timing)

    def emote(self, rows: Any, emotion: str, intensity: float, t_s: float) -> None:
        for c in self._each(rows):
            c.emote(emotion, intensity, start_s=t_s)

    def set_pad(self, rows: Any, p: float, a: float, d: float, t_s: float) -> None:
        raise InvalidValueError("pad", (p, a, d), "a CharacterBatch with PAD support (engine being rewritten)")

    def laugh(
        self, rows: Any, laugh_type: str, intensity: float = 1.0, start_s: float | None = None, seed: int | None = None
    ) -> None:
        for c in self._each(rows):
            c.laugh(laugh_type, intensity, seed=seed, start_s=start_s)

    def play_clip(self, rows: Any, clip: Any, start_s: float | None = None) -> None:
        for c in self._each(rows):
            c.play_clip(clip, start_s)

    def step(self, t_s: float) -> np.ndarray:
        for row, c in enumerate(self._characters):
            if c is not None:
                self._frames[row] = c.step(t_s)
        self._t_s = t_s
        return self._frames

    def snapshot(self, row: int) -> dict[str, Any]:
        return dict(self._characters[row].snapshot())


def _first_channel(au: str) -> int:
    from mien.facs.catalogue import FACE_CHANNELS

    name = au if au in FACE_CHANNELS else f"{au}L"
    return FACE_CHANNELS.index(name)
