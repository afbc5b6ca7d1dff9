"""Phonemes to visemes: espeak-ng mnemonics and ARPABET, through ``data/phonemes.csv`` (sources cited there).

>>> [viseme_of(p) for p in "m aI m a m a# m eI d a# m a p".split()]
['PP', 'aa', 'PP', 'aa', 'PP', 'aa', 'PP', 'E', 'DD', 'aa', 'PP', 'aa', 'PP']
>>> viseme_of("UW1", "arpabet")
'U'
"""

from __future__ import annotations

from functools import cache

from mien.errors import UnknownNameError
from mien.fileio.tables import read_table

__all__ = ["ALPHABETS", "phoneme_table", "viseme_of"]

ALPHABETS = ("espeak", "arpabet")
"""Phoneme alphabets the table knows: espeak-ng's mnemonics and the CMU dictionary's ARPABET."""

_MARKS = "'\",%=!-/+"
"""espeak-ng's stress, tone and variant marks, stripped before a second lookup."""


@cache
def phoneme_table(alphabet: str) -> dict[str, str]:
    """``{phoneme: viseme}`` of ``alphabet`` (one of :data:`ALPHABETS`)."""
    if alphabet not in ALPHABETS:
        raise UnknownNameError("phoneme alphabet", alphabet, ALPHABETS)
    return {row["phoneme"]: row["viseme"] for row in read_table("mien.speech", "data/phonemes.csv")
            if row["alphabet"] == alphabet}  # fmt: skip


def viseme_of(phoneme: str, alphabet: str = "espeak", *, strict: bool = False) -> str:
    """The viseme that shows ``phoneme`` of ``alphabet``.

    Lookup order: the name as given; without stress and variant marks (espeak ``'a``, ``a:`` ..., ARPABET stress
    digits ``AA1``); with ``strict=False`` (what a TTS's own output gets, so a phoneme of another language
    still moves the mouth), the row of its first letter, else ``"DD"`` (a half-open neutral consonant) for a
    letter the table lacks. With ``strict=True`` (timing files) an unknown phoneme raises
    :class:`UnknownNameError`.
    """
    table = phoneme_table(alphabet)
    if phoneme in table:
        return table[phoneme]
    bare = phoneme.strip(_MARKS).rstrip("0123456789") if alphabet == "arpabet" else phoneme.strip(_MARKS)
    if bare in table:
        return table[bare]
    shorter = bare.rstrip(":#")
    if shorter in table:
        return table[shorter]
    if strict:
        raise UnknownNameError(f"{alphabet} phoneme", phoneme, tuple(table))
    if shorter[:1] in table:
        return table[shorter[:1]]
    return "sil" if not shorter or shorter.startswith("_") else "DD"
