"""Data tables: comments skipped, columns by header, each caller gets its own copy."""

from __future__ import annotations

from mien.fileio.tables import read_table, table_comments


def test_read_table_skips_comments_and_keys_rows_by_header() -> None:
    rows = read_table("mien.affect", "data/pad_prototypes.csv")
    assert [row["emotion"] for row in rows] == ["joy", "sadness", "anger", "surprise", "disgust", "fear"]
    assert not any(value.startswith("#") for row in rows for value in row.values())


def test_read_table_returns_a_fresh_copy_each_call() -> None:
    first = read_table("mien.laughter", "data/taxonomy.csv")
    first[0]["type"] = "changed"
    first.clear()
    again = read_table("mien.laughter", "data/taxonomy.csv")
    assert len(again) == 13
    assert again[0]["type"] == "uproarious_laughter"


def test_table_comments_hold_the_source_lines() -> None:
    comments = table_comments("mien.laughter", "data/taxonomy.csv")
    assert comments[0].startswith("The 13 laugh and smile types of Mascaro et al.")
    assert "Sources:" in comments
