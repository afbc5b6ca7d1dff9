"""Storage on SQLite and on a real PostgreSQL server: idempotent answers, nrShows as a maximum, the long
answers table in the contract's column order, concurrent writers, CSV round trip, and a locked or
unreachable database -> StorageUnavailableError after retries (nothing half-stored)."""

from __future__ import annotations

import sqlite3
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from mien.ports import free_port
from mien.study.export import read_answers_csv, write_answers_csv
from mien.study.storage import StorageUnavailableError, Store, database_url

STIMULI = [
    {"id": "s001", "expression": "joy", "conditions": {"head": "builtin", "identity": "", "basis": "facs",
     "view": "frontal", "distance_m": 1.0, "intensity": 1.2}, "file": "s001.mp4", "sha256": "a"},
    {"id": "s002", "expression": "anger", "conditions": {"head": "builtin", "identity": "", "basis": "facs",
     "view": "lateral", "distance_m": 1.0, "intensity": 1.2}, "file": "s002.mp4", "sha256": "b"},
]  # fmt: skip

COLUMNS = ["study", "participant", "session_started_at", "position", "stimulus", "protocol", "expression", "head",
           "identity", "basis", "view", "distance_m", "intensity", "question", "label_position", "rating",
           "nr_shows", "answered_at"]  # fmt: skip


@pytest.fixture(params=["sqlite", pytest.param("postgresql", marks=pytest.mark.database)])
def store(request: pytest.FixtureRequest, tmp_path: Path) -> Store:
    if request.param == "sqlite":
        url = database_url(tmp_path / "study.sqlite", tmp_path / "unused.sqlite")
    else:
        url = request.getfixturevalue("postgres_url")
    s = Store(url)
    for table in reversed(s._meta.sorted_tables):  # a fresh study per test on the shared server
        with s.engine.begin() as connection:
            connection.execute(table.delete())
    s.register_stimuli("st", "broekens", STIMULI)
    yield s
    s.close()


def plan(_ordinal: int) -> tuple[list[str], list[str], list[int]]:
    return ["s002", "s001"], ["label:joy", "label:anger", "naturalness"], [1, 0]


def test_answers_idempotent_and_frame(store: Store, tmp_path: Path) -> None:
    assert list(store.answers_frame("st").columns) == COLUMNS  # the factor columns even with no answer yet
    record = store.ensure_participant("st", "p1", plan)
    assert record.sequence == ("s002", "s001") and record.ordinal == 0
    assert store.ensure_participant("st", "p1", plan) == record
    assert store.ensure_participant("st", "p2", plan).ordinal == 1
    assert store.record_show("st", "p1", "s002", 1) == 1
    assert store.record_show("st", "p1", "s002", 3) == 3
    assert store.record_show("st", "p1", "s002", 2) == 3  # a late duplicate never lowers the count
    ratings = {"label:joy": 1, "label:anger": 5, "naturalness": 4}
    positions = {"label:joy": 0, "label:anger": 1}
    assert store.record_answer("st", "p1", "s002", 0, ratings, positions, 3) == 3
    assert store.record_answer("st", "p1", "s002", 0, {**ratings, "label:joy": 2}, positions, 3) == 0
    assert store.progress("st", "p1") == ({"s002"}, {"s002": 3})
    frame = store.answers_frame("st")
    assert list(frame.columns) == COLUMNS
    assert list(frame["question"]) == ["label:joy", "label:anger", "naturalness"]
    assert list(frame["rating"]) == [1, 5, 4]  # the first submit wins
    assert list(frame["label_position"].astype(object).where(frame["label_position"].notna(), None)) == [0, 1, None]
    row = frame.iloc[0]
    assert (row["stimulus"], row["expression"], row["view"], row["position"], row["nr_shows"]) == (
        "s002", "anger", "lateral", 0, 3
    )  # fmt: skip
    assert row["session_started_at"] == record.started_at and row["answered_at"].endswith("+00:00")
    path, rows = write_answers_csv(store, tmp_path / "answers.csv", "st")
    assert rows == 3 and path.read_text().splitlines()[0] == ",".join(COLUMNS)
    back = read_answers_csv(path)
    assert list(back.columns) == COLUMNS and list(back["rating"]) == [1, 5, 4]
    assert back["label_position"].isna().tolist() == [False, False, True]


def test_concurrent_writers(store: Store) -> None:
    participants = [f"p{k}" for k in range(12)]

    def session(participant: str) -> int:
        store.ensure_participant("st", participant, plan)
        stored = 0
        for position, stimulus in enumerate(("s002", "s001")):
            for _ in range(2):  # every answer submitted twice
                stored += store.record_answer(
                    "st", participant, stimulus, position, {"label:joy": 3, "label:anger": 2, "naturalness": 5}, {}, 1
                )
        return stored

    with ThreadPoolExecutor(max_workers=6) as pool:
        stored = list(pool.map(session, participants))
    assert stored == [6] * len(participants)
    ordinals = sorted(store.participant("st", p).ordinal for p in participants)  # type: ignore[union-attr]
    assert ordinals == list(range(len(participants)))  # unique arrival order even when arriving together
    assert store.count_answers("st") == 6 * len(participants)


def test_locked_sqlite_retries_then_fails(tmp_path: Path) -> None:
    path = tmp_path / "locked.sqlite"
    store = Store(database_url(path, path), retry_s=0.01, busy_timeout_s=0.05)
    store.register_stimuli("st", "broekens", STIMULI)
    store.ensure_participant("st", "p1", plan)
    blocker = sqlite3.connect(path, timeout=0.1)
    blocker.execute("BEGIN EXCLUSIVE")
    try:
        with pytest.raises(StorageUnavailableError, match="locked or unreachable"):
            store.record_answer("st", "p1", "s001", 1, {"naturalness": 3}, {}, 1)
    finally:
        blocker.rollback()
        blocker.close()
    assert store.count_answers("st") == 0
    assert store.record_answer("st", "p1", "s001", 1, {"naturalness": 3}, {}, 1) == 1  # works once unlocked
    store.close()


def test_unreachable_postgresql() -> None:
    port = free_port()  # a port nobody listens on
    with pytest.raises(StorageUnavailableError, match=str(port)):
        Store(f"postgresql+psycopg://postgres@127.0.0.1:{port}/postgres", retry_s=0.01, busy_timeout_s=1)


def test_database_url(tmp_path: Path) -> None:
    assert database_url(None, tmp_path / "a.sqlite") == f"sqlite:///{tmp_path / 'a.sqlite'}"
    assert database_url("postgresql://u@h:5/d", tmp_path) == "postgresql+psycopg://u@h:5/d"
    with pytest.raises(ValueError, match="mysql"):
        database_url("mysql://x", tmp_path)
