"""Fixtures of the speech tests: espeak-ng's library (skips with a reason when it is not installed)."""

from __future__ import annotations

import pytest

from mien.errors import MissingAssetError
from mien.speech.track import Utterance

SENTENCE = "Pete and Bob may keep a bump on the map, but the tub is empty."
"""A sentence dense in /p b m/ between open vowels."""


@pytest.fixture(scope="session")
def spoken() -> Utterance:
    """:data:`SENTENCE` spoken by espeak-ng (libespeak-ng), with its phoneme events and sound."""
    from mien.speech.espeak import speak

    try:
        return speak(SENTENCE)
    except MissingAssetError as error:
        pytest.skip(f"libespeak-ng not installed ({error})")
