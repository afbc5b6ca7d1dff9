"""The answers as one long CSV (one row per answered question), the table the analysis reads.

Columns, in order: ``study, participant, session_started_at, position, stimulus, protocol, expression``, the
design factors present (``head, identity, basis, view, distance_m, intensity`` or ``laughter_type,
description``; empty when not applicable), then ``question, label_position, rating, nr_shows,
answered_at`` (see :meth:`mien.study.storage.Store.answers_frame`).

The CSV's bytes are the answers' canonical form: :func:`answers_sha256` of a frame read from the database is
the SHA-256 of the file :func:`write_answers_csv` writes from it, so a report made from the database and one
made from the exported file name the same answers with the same hash.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path
from typing import TYPE_CHECKING

from mien.fileio.streams import atomic_path

if TYPE_CHECKING:
    import pandas as pd

    from mien.study.storage import Store

__all__ = ["answers_csv_bytes", "answers_sha256", "read_answers_csv", "write_answers_csv"]


def answers_csv_bytes(frame: pd.DataFrame) -> bytes:
    """The answers ``frame`` as the UTF-8 CSV bytes :func:`write_answers_csv` writes (no index, ``\\n``)."""
    return frame.to_csv(index=False, lineterminator="\n").encode("utf-8")


def answers_sha256(frame: pd.DataFrame) -> str:
    """Hex SHA-256 of :func:`answers_csv_bytes` of ``frame``: the hash of the CSV it would be exported as."""
    return hashlib.sha256(answers_csv_bytes(frame)).hexdigest()


def write_answers_csv(
    source: Store | pd.DataFrame, out: str | os.PathLike[str], study: str | None = None
) -> tuple[Path, int]:
    """Write the answers of ``source`` (a :class:`~mien.study.storage.Store`, filtered to ``study`` when
    given, or a frame from :meth:`~mien.study.storage.Store.answers_frame`) to ``out`` (UTF-8 CSV, written
    to a temporary file and renamed). Returns (path, number of rows)."""
    import pandas as pd

    frame = source if isinstance(source, pd.DataFrame) else source.answers_frame(study)
    path = Path(out)
    if path.parent and not path.parent.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as temporary:
        Path(temporary).write_bytes(answers_csv_bytes(frame))
    return path, len(frame)


def read_answers_csv(path: str | os.PathLike[str]) -> pd.DataFrame:
    """Read a CSV written by :func:`write_answers_csv` back with the same column types (ints, nullable
    ``label_position``, text factors kept as text)."""
    import pandas as pd

    frame = pd.read_csv(path, keep_default_na=False, na_values={"label_position": [""]})
    for name in ("position", "rating", "nr_shows"):
        frame[name] = frame[name].astype("int64")
    frame["label_position"] = frame["label_position"].astype("Int64")
    return frame
