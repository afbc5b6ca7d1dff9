"""The answers as one long CSV (one row per answered question), the table the analysis reads.

Columns, in order: ``study, participant, session_started_at, position, stimulus, protocol, expression``, the
design factors present (``head, identity, basis, view, distance_m, intensity`` or ``laughter_type,
description``; empty when not applicable), then ``question, label_position, rating, nr_shows,
answered_at`` (see :meth:`mien.study.storage.Store.answers_frame`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

from mien.fileio.streams import atomic_path

if TYPE_CHECKING:
    import pandas as pd

    from mien.study.storage import Store

__all__ = ["read_answers_csv", "write_answers_csv"]


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
        frame.to_csv(temporary, index=False, lineterminator="\n")
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
