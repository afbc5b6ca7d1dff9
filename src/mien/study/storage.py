"""Where answers live: SQLite by default, PostgreSQL by URL (SQLAlchemy Core, the same schema on both).

Every answer is committed in its own transaction the moment it is given, keyed by (study, participant,
stimulus, question) with ``INSERT ... ON CONFLICT DO NOTHING``: a double submit or a replayed page stores
nothing twice, and a killed server or a closed browser loses nothing already answered. SQLite runs in WAL
mode. Every operation waits at most ``busy_timeout_s`` (:data:`BUSY_TIMEOUT_S`) in all, retries and lock
waits together; a database that stays locked or unreachable that long raises
:class:`StorageUnavailableError` (the runner answers HTTP 503 with ``Retry-After``), never a silent loss.
While the database is unavailable, a second writer does not queue behind the one already waiting: it is
refused at once, so one held lock costs each request at most the bound (:meth:`Store.health` says so).

Tables: ``stimuli`` (the manifest: id, expression, conditions as JSON, file, hash), ``participants``
(their stored plan: sequence, label order, block order, arrival ordinal), ``shows`` (replays per stimulus,
nrShows) and ``answers`` (one row per rated question).
"""

from __future__ import annotations

import contextlib
import json
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from mien.errors import InvalidValueError, MienError
from mien.extras import require
from mien.study.design import BROEKENS_FACTORS, MASCARO_FACTORS

if TYPE_CHECKING:
    import pandas as pd
    import sqlalchemy as sa

__all__ = [
    "ANSWER_COLUMNS",
    "ParticipantRecord",
    "StorageUnavailableError",
    "Store",
    "database_url",
    "now_iso",
]

T = TypeVar("T")

ANSWER_COLUMNS: tuple[str, ...] = (
    "study",
    "participant",
    "session_started_at",
    "position",
    "stimulus",
    "protocol",
    "expression",
)
"""First columns of the long answers table; the design factors, then :data:`TAIL_COLUMNS` follow."""

TAIL_COLUMNS: tuple[str, ...] = ("question", "label_position", "rating", "nr_shows", "answered_at")
"""Last columns of the long answers table."""

RETRIES = 5
"""Most attempts of one database operation before :class:`StorageUnavailableError` (all within the bound)."""

BUSY_TIMEOUT_S = 3.0
"""Default bound, seconds, on the time one database operation may wait for a lock or a connection, retries
included (``mien study serve --busy-timeout``)."""


OUTAGE_PROBE_S = 0.5
"""While SQLite is known to be locked, the one writer let through waits at most this long (seconds) to see
whether the lock is gone; the others are refused at once (the page retries after ``Retry-After``)."""


class StorageUnavailableError(MienError):
    """The database stayed locked or unreachable for the whole bound; nothing was stored."""


class _WriterQueueTimeout(Exception):
    """The in-process writer lock was not free within ``wait_s`` seconds (0: the database is unavailable and
    another writer is already waiting for it)."""

    def __init__(self, wait_s: float) -> None:
        super().__init__(wait_s)
        self.wait_s = wait_s


def now_iso() -> str:
    """The current UTC time, ISO 8601 with microseconds and ``+00:00``."""
    return datetime.now(UTC).isoformat()


def database_url(url_or_path: str | Path | None, default_path: Path) -> str:
    """A SQLAlchemy URL from ``--db``: a URL (``postgresql://...``, ``sqlite:///...``) is kept (plain
    ``postgresql://`` gets the psycopg 3 driver), a file path becomes SQLite, None is ``default_path``."""
    if url_or_path is None:
        return f"sqlite:///{Path(default_path).resolve()}"
    text = str(url_or_path)
    if "://" not in text:
        return f"sqlite:///{Path(text).resolve()}"
    if text.startswith(("postgresql://", "postgres://")):
        return "postgresql+psycopg://" + text.split("://", 1)[1]
    if not text.startswith(("sqlite", "postgresql")):
        raise InvalidValueError("db", text, "a SQLite file path, sqlite:///PATH or postgresql://USER@HOST:PORT/DB")
    return text


@dataclass(frozen=True)
class ParticipantRecord:
    """A participant as stored."""

    participant: str
    """Participant id (from the link ``?participant=ID``)."""
    ordinal: int
    """0-based arrival order in the study (picks the Latin-square row)."""
    started_at: str
    """First visit, ISO 8601 UTC."""
    sequence: tuple[str, ...]
    """Stimulus ids in presentation order."""
    label_order: tuple[str, ...]
    """Question keys in on-screen order."""
    block_order: tuple[int, ...]
    """Within-subject block indices in the order shown."""
    consent_at: str | None
    """When consent was given (None = not yet)."""
    completed_at: str | None
    """When the last stimulus was answered (None = not yet)."""


def _schema() -> tuple[sa.MetaData, dict[str, sa.Table]]:
    import sqlalchemy as sa

    meta = sa.MetaData()
    text = sa.Text
    tables = {
        "stimuli": sa.Table(
            "mien_study_stimuli",
            meta,
            sa.Column("study", text, primary_key=True),
            sa.Column("stimulus", text, primary_key=True),
            sa.Column("design_index", sa.Integer, nullable=False),
            sa.Column("protocol", text, nullable=False),
            sa.Column("expression", text, nullable=False),
            sa.Column("conditions", text, nullable=False),
            sa.Column("file", text, nullable=False),
            sa.Column("sha256", text, nullable=False),
        ),
        "participants": sa.Table(
            "mien_study_participants",
            meta,
            sa.Column("study", text, primary_key=True),
            sa.Column("participant", text, primary_key=True),
            sa.Column("ordinal", sa.Integer, nullable=False),
            sa.Column("started_at", text, nullable=False),
            sa.Column("sequence", text, nullable=False),
            sa.Column("label_order", text, nullable=False),
            sa.Column("block_order", text, nullable=False),
            sa.Column("consent_at", text),
            sa.Column("completed_at", text),
            sa.UniqueConstraint("study", "ordinal", name="mien_study_participant_ordinal"),
        ),
        "shows": sa.Table(
            "mien_study_shows",
            meta,
            sa.Column("study", text, primary_key=True),
            sa.Column("participant", text, primary_key=True),
            sa.Column("stimulus", text, primary_key=True),
            sa.Column("nr_shows", sa.Integer, nullable=False),
        ),
        "answers": sa.Table(
            "mien_study_answers",
            meta,
            sa.Column("study", text, primary_key=True),
            sa.Column("participant", text, primary_key=True),
            sa.Column("stimulus", text, primary_key=True),
            sa.Column("question", text, primary_key=True),
            sa.Column("position", sa.Integer, nullable=False),
            sa.Column("label_position", sa.Integer),
            sa.Column("rating", sa.Integer, nullable=False),
            sa.Column("nr_shows", sa.Integer, nullable=False),
            sa.Column("answered_at", text, nullable=False),
        ),
    }
    return meta, tables


class Store:
    """The study database at ``url`` (a SQLAlchemy URL; see :func:`database_url`). Creates its tables.

    Thread-safe (a connection pool); every method is one transaction, retried on a locked or lost
    database. ``retry_s`` is the first back-off, doubled per attempt; ``busy_timeout_s`` (seconds, > 0) bounds
    the whole operation: SQLite's lock waits, the in-process writer queue and the retries together
    (PostgreSQL: also the connect timeout).
    """

    def __init__(self, url: str, retry_s: float = 0.05, busy_timeout_s: float = BUSY_TIMEOUT_S) -> None:
        sa = require("sqlalchemy", "study")
        if not (isinstance(busy_timeout_s, int | float) and 0 < busy_timeout_s <= 3600):
            raise InvalidValueError("busy_timeout_s", busy_timeout_s, "a number of seconds in (0, 3600]")
        self.url = url
        self.retry_s = retry_s
        self.busy_timeout_s = float(busy_timeout_s)
        self._local = threading.local()  # the running operation's deadline (time.monotonic seconds)
        self._health_lock = threading.Lock()
        self._unavailable_since: str | None = None  # ISO time of the first failure of the current outage
        self._unavailable_error = ""
        self._unavailable_count = 0  # operations refused since the store opened
        self._sa = sa
        self.is_sqlite = url.startswith("sqlite")
        insert: Any
        if self.is_sqlite:
            from sqlalchemy.dialects.sqlite import insert

            engine = sa.create_engine(
                url, connect_args={"timeout": busy_timeout_s, "check_same_thread": False}, pool_size=20
            )

            @sa.event.listens_for(engine, "connect")
            def _pragmas(connection: Any, _record: Any) -> None:
                cursor = connection.cursor()
                cursor.execute("PRAGMA journal_mode=WAL")
                cursor.execute("PRAGMA synchronous=NORMAL")  # WAL + NORMAL: a commit survives a killed process
                cursor.execute(f"PRAGMA busy_timeout={int(busy_timeout_s * 1000)}")
                cursor.close()

        else:
            insert = require("sqlalchemy.dialects.postgresql", "study").insert
            engine = sa.create_engine(
                url,
                pool_size=10,
                max_overflow=10,  # no pre-ping round trip per checkout: a dropped connection is retried
                # a row or table lock held elsewhere is waited for no longer than the bound either
                connect_args={
                    "connect_timeout": max(1, round(busy_timeout_s)),
                    "options": f"-c lock_timeout={int(busy_timeout_s * 1000)}",
                },
            )
        self._insert = insert
        self._write_lock = threading.Lock() if self.is_sqlite else None
        self.engine = engine
        self._meta, self.tables = _schema()
        self._retry(lambda: self._meta.create_all(self.engine))

    def _remaining_s(self) -> float:
        """Seconds left of the running operation's bound (the whole bound outside :meth:`_retry`)."""
        deadline = getattr(self._local, "deadline", None)
        return self.busy_timeout_s if deadline is None else max(0.0, deadline - time.monotonic())

    @contextlib.contextmanager
    def _writing(self) -> Iterator[Any]:
        """A write transaction. SQLite: one writer at a time in this process (a lock, so threads queue in
        order instead of sleeping in SQLite's busy handler, which costs tens of ms per clash), waited for no
        longer than the operation's bound, and not at all while the database is known to be unavailable (the
        writer already waiting is enough); SQLite's own busy timeout is set to what is left of the bound (in an
        outage: :data:`OUTAGE_PROBE_S` at most)."""
        if self._write_lock is None:
            with self.engine.begin() as connection:
                yield connection
            return
        outage = self._unavailable_since is not None
        wait_s = 0.0 if outage else self._remaining_s()
        if not self._write_lock.acquire(timeout=wait_s):
            raise _WriterQueueTimeout(wait_s)
        try:
            with self.engine.connect() as connection:
                raw = connection.connection.dbapi_connection
                assert raw is not None
                busy_s = min(self._remaining_s(), OUTAGE_PROBE_S) if outage else self._remaining_s()
                raw.execute(f"PRAGMA busy_timeout={max(1, int(busy_s * 1000))}")
                try:
                    with connection.begin():
                        yield connection
                    self._local.wrote = True  # committed: the database takes writes again
                finally:
                    raw.execute(f"PRAGMA busy_timeout={int(self.busy_timeout_s * 1000)}")
        finally:
            self._write_lock.release()

    def close(self) -> None:
        """Close every pooled connection."""
        self.engine.dispose()

    def __enter__(self) -> Store:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def health(self) -> dict[str, Any]:
        """The database's state as the last operations found it: ``{"database": "ok" | "unavailable",
        "unavailable_since": ISO time or None, "error": the last failure ('' when ok), "refused": operations
        refused with :class:`StorageUnavailableError` since the store opened, "busy_timeout_s": the bound}``."""
        with self._health_lock:
            return {
                "database": "ok" if self._unavailable_since is None else "unavailable",
                "unavailable_since": self._unavailable_since,
                "error": self._unavailable_error,
                "refused": self._unavailable_count,
                "busy_timeout_s": self.busy_timeout_s,
            }

    def _failed(self, reason: str, attempts: int, started: float) -> StorageUnavailableError:
        waited_s = time.monotonic() - started
        message = (
            f"the study database {self.engine.url.render_as_string(hide_password=True)} is locked or unreachable "
            f"({reason}; {attempts} attempt{'s' if attempts != 1 else ''} in {waited_s:.1f} s, bound "
            f"{self.busy_timeout_s:g} s); nothing was stored, try again"
        )
        with self._health_lock:
            if self._unavailable_since is None:
                self._unavailable_since = now_iso()
            self._unavailable_error = reason
            self._unavailable_count += 1
        return StorageUnavailableError(message)

    def _retry(self, operation: Callable[[], T]) -> T:
        """Run ``operation`` until it succeeds, retrying a locked or lost database with back-off, for at most
        :data:`RETRIES` attempts and ``busy_timeout_s`` seconds in all."""
        from sqlalchemy.exc import DBAPIError, OperationalError

        started = time.monotonic()
        outer = getattr(self._local, "deadline", None)
        self._local.deadline = started + self.busy_timeout_s if outer is None else outer
        delay = self.retry_s
        self._local.wrote = False
        try:
            for attempt in range(1, RETRIES + 1):
                try:
                    result = operation()
                except _WriterQueueTimeout as error:
                    reason = (
                        "another request is already waiting for it"
                        if error.wait_s == 0
                        else f"the writers before this one held it {error.wait_s:.1f} s"
                    )
                    raise self._failed(reason, attempt, started) from None
                except (OperationalError, DBAPIError) as error:
                    transient = isinstance(error, OperationalError) or bool(
                        getattr(error, "connection_invalidated", False)
                    )
                    if not transient:
                        raise
                    probe = self.is_sqlite and self._unavailable_since is not None  # one look during an outage
                    if probe or attempt == RETRIES or self._remaining_s() < delay:
                        reason = str(getattr(error, "orig", error)).strip().splitlines()[0]
                        raise self._failed(reason, attempt, started) from None
                    time.sleep(delay)
                    delay *= 2
                else:
                    # SQLite in WAL mode reads while another program holds the write lock: only a write ends
                    # the outage there; on PostgreSQL any answer means the server is back
                    recovered = not self.is_sqlite or getattr(self._local, "wrote", False)
                    if self._unavailable_since is not None and recovered:
                        with self._health_lock:
                            self._unavailable_since, self._unavailable_error = None, ""
                    return result
            raise AssertionError("unreachable")
        finally:
            self._local.deadline = outer

    # ---------------------------------------------------------------- writes

    def register_stimuli(self, study: str, protocol: str, stimuli: Iterable[Mapping[str, Any]]) -> None:
        """Store the manifest's stimuli (dicts with id, expression, conditions, file, sha256); existing rows
        of the same id are replaced, so a re-rendered stimulus set updates its hashes."""
        rows = [
            {
                "study": study,
                "stimulus": s["id"],
                "design_index": k,
                "protocol": protocol,
                "expression": s["expression"],
                "conditions": json.dumps(s.get("conditions", {}), sort_keys=False),
                "file": s.get("file", ""),
                "sha256": s.get("sha256", ""),
            }
            for k, s in enumerate(stimuli)
        ]
        table = self.tables["stimuli"]

        def write() -> None:
            with self._writing() as connection:
                for row in rows:
                    statement = self._insert(table).values(**row)
                    update = {k: statement.excluded[k] for k in row if k not in ("study", "stimulus")}
                    connection.execute(
                        statement.on_conflict_do_update(index_elements=["study", "stimulus"], set_=update)
                    )

        self._retry(write)

    def ensure_participant(
        self, study: str, participant: str, plan: Callable[[int], tuple[Any, Any, Any]]
    ) -> ParticipantRecord:
        """The stored participant, created on first arrival with ``plan(ordinal) -> (sequence, label_order,
        block_order)``; ordinal = 0, 1, 2... in order of arrival, unique per study even when participants
        arrive at the same moment (a clash on the unique (study, ordinal) is retried with the next one).
        Idempotent."""
        sa = self._sa
        table = self.tables["participants"]
        for _ in range(100):
            existing = self.participant(study, participant)
            if existing is not None:
                return existing

            def create() -> None:
                with self._writing() as connection:
                    last = connection.execute(
                        sa.select(sa.func.max(table.c.ordinal)).where(table.c.study == study)
                    ).scalar_one()
                    ordinal = 0 if last is None else int(last) + 1
                    sequence, label_order, block_order = plan(ordinal)
                    connection.execute(
                        self._insert(table)
                        .values(
                            study=study,
                            participant=participant,
                            ordinal=ordinal,
                            started_at=now_iso(),
                            sequence=json.dumps(list(sequence)),
                            label_order=json.dumps(list(label_order)),
                            block_order=json.dumps([int(b) for b in block_order]),
                        )
                        .on_conflict_do_nothing()  # this participant, or this ordinal, taken meanwhile
                    )

            self._retry(create)
        raise StorageUnavailableError(f"participant {participant!r} could not be stored (100 clashing arrivals)")

    def _set_time(self, study: str, participant: str, column: str) -> None:
        sa = self._sa
        table = self.tables["participants"]

        def write() -> None:
            with self._writing() as connection:
                connection.execute(
                    sa.update(table)
                    .where(table.c.study == study, table.c.participant == participant, table.c[column].is_(None))
                    .values({column: now_iso()})
                )

        self._retry(write)

    def record_consent(self, study: str, participant: str) -> None:
        """Mark consent given (the first time only)."""
        self._set_time(study, participant, "consent_at")

    def record_completed(self, study: str, participant: str) -> None:
        """Mark the session complete (the first time only)."""
        self._set_time(study, participant, "completed_at")

    def record_show(self, study: str, participant: str, stimulus: str, nr_shows: int) -> int:
        """Store that ``stimulus`` has been played ``nr_shows`` times (the client's count, so a repeated
        request is idempotent); returns the stored count (the larger of the stored and given)."""
        sa = self._sa
        table = self.tables["shows"]

        def write() -> int:
            with self._writing() as connection:
                statement = self._insert(table).values(
                    study=study, participant=participant, stimulus=stimulus, nr_shows=int(nr_shows)
                )
                connection.execute(
                    statement.on_conflict_do_update(
                        index_elements=["study", "participant", "stimulus"],
                        set_={"nr_shows": sa.func.max(table.c.nr_shows, statement.excluded.nr_shows)}
                        if self.is_sqlite
                        else {"nr_shows": sa.func.greatest(table.c.nr_shows, statement.excluded.nr_shows)},
                    )
                )
                return int(
                    connection.execute(
                        sa.select(table.c.nr_shows).where(
                            table.c.study == study, table.c.participant == participant, table.c.stimulus == stimulus
                        )
                    ).scalar_one()
                )

        return self._retry(write)

    def record_answer(
        self,
        study: str,
        participant: str,
        stimulus: str,
        position: int,
        ratings: Mapping[str, int],
        label_positions: Mapping[str, int],
        nr_shows: int,
    ) -> int:
        """Store one stimulus's ratings (question -> int) in one transaction; returns how many rows were new
        (0 for a repeated submit: ``ON CONFLICT DO NOTHING`` on (study, participant, stimulus, question))."""
        table = self.tables["answers"]
        answered_at = now_iso()
        rows = [
            {
                "study": study,
                "participant": participant,
                "stimulus": stimulus,
                "question": question,
                "position": int(position),
                "label_position": label_positions.get(question),
                "rating": int(rating),
                "nr_shows": int(nr_shows),
                "answered_at": answered_at,
            }
            for question, rating in ratings.items()
        ]

        if not rows:
            return 0

        def write() -> int:
            with self._writing() as connection:
                # one multi-row INSERT; RETURNING counts the rows that were new on both dialects
                statement = self._insert(table).values(rows).on_conflict_do_nothing().returning(table.c.question)
                return len(connection.execute(statement).fetchall())

        return self._retry(write)

    # ---------------------------------------------------------------- reads

    def participant(self, study: str, participant: str) -> ParticipantRecord | None:
        """The stored participant, or None."""
        sa = self._sa
        table = self.tables["participants"]

        def read() -> Any:
            with self.engine.connect() as connection:
                return connection.execute(
                    sa.select(table).where(table.c.study == study, table.c.participant == participant)
                ).first()

        row = self._retry(read)
        if row is None:
            return None
        return ParticipantRecord(
            participant=row.participant,
            ordinal=int(row.ordinal),
            started_at=row.started_at,
            sequence=tuple(json.loads(row.sequence)),
            label_order=tuple(json.loads(row.label_order)),
            block_order=tuple(json.loads(row.block_order)),
            consent_at=row.consent_at,
            completed_at=row.completed_at,
        )

    def progress(self, study: str, participant: str) -> tuple[set[str], dict[str, int]]:
        """(stimulus ids with at least one stored answer, stimulus -> stored nrShows) of a participant."""
        sa = self._sa
        answers, shows = self.tables["answers"], self.tables["shows"]

        def read() -> tuple[set[str], dict[str, int]]:
            with self.engine.connect() as connection:
                done = connection.execute(
                    sa.select(answers.c.stimulus)
                    .where(answers.c.study == study, answers.c.participant == participant)
                    .distinct()
                ).scalars()
                counts = connection.execute(
                    sa.select(shows.c.stimulus, shows.c.nr_shows).where(
                        shows.c.study == study, shows.c.participant == participant
                    )
                )
                return set(done), {s: int(n) for s, n in counts}

        return self._retry(read)

    def count_answers(self, study: str | None = None) -> int:
        """Number of stored answer rows (of ``study``, or all)."""
        sa = self._sa
        table = self.tables["answers"]
        query = sa.select(sa.func.count()).select_from(table)
        if study is not None:
            query = query.where(table.c.study == study)

        def read() -> int:
            with self.engine.connect() as connection:
                return int(connection.execute(query).scalar_one())

        return self._retry(read)

    def studies(self) -> tuple[str, ...]:
        """Names of the studies with registered stimuli."""
        sa = self._sa
        table = self.tables["stimuli"]

        def read() -> tuple[str, ...]:
            with self.engine.connect() as connection:
                return tuple(connection.execute(sa.select(table.c.study).distinct().order_by(table.c.study)).scalars())

        return self._retry(read)

    def answers_frame(self, study: str | None = None) -> pd.DataFrame:
        """The long answers table (one row per answered question), columns in the contract order:
        :data:`ANSWER_COLUMNS`, the design factors present in the stimuli's conditions (``head, identity,
        basis, view, distance_m, intensity`` or ``laughter_type, description``; '' when not applicable),
        then :data:`TAIL_COLUMNS`. ``rating``, ``nr_shows`` and ``position`` are ints, ``label_position`` a
        nullable Int64. Rows sorted by study, participant, position and on-screen question order."""
        import pandas as pd

        sa = self._sa
        answers, stimuli, participants = self.tables["answers"], self.tables["stimuli"], self.tables["participants"]
        query = (
            sa.select(
                answers.c.study,
                answers.c.participant,
                participants.c.started_at.label("session_started_at"),
                answers.c.position,
                answers.c.stimulus,
                stimuli.c.protocol,
                stimuli.c.expression,
                stimuli.c.conditions,
                answers.c.question,
                answers.c.label_position,
                answers.c.rating,
                answers.c.nr_shows,
                answers.c.answered_at,
            )
            .select_from(answers)
            .join(stimuli, sa.and_(stimuli.c.study == answers.c.study, stimuli.c.stimulus == answers.c.stimulus))
            .join(
                participants,
                sa.and_(participants.c.study == answers.c.study, participants.c.participant == answers.c.participant),
            )
        )
        if study is not None:
            query = query.where(answers.c.study == study)

        def read() -> list[Any]:
            with self.engine.connect() as connection:
                return list(connection.execute(query))

        factor_query = sa.select(stimuli.c.conditions)
        if study is not None:
            factor_query = factor_query.where(stimuli.c.study == study)

        def read_factors() -> list[str]:
            with self.engine.connect() as connection:
                return list(connection.execute(factor_query).scalars())

        rows = self._retry(read)
        conditions = [json.loads(r.conditions) for r in rows]
        # factors from every registered stimulus, so the columns are there even before any answer
        present = {key for text in self._retry(read_factors) for key in json.loads(text)}
        factors = [f for f in (*BROEKENS_FACTORS, *MASCARO_FACTORS) if f in present]
        factors += sorted(present - set(factors))
        records = []
        for r, c in zip(rows, conditions, strict=True):
            record = {name: getattr(r, name) for name in ANSWER_COLUMNS}
            record.update({f: c.get(f, "") for f in factors})
            record.update({name: getattr(r, name) for name in TAIL_COLUMNS})
            records.append(record)
        columns = [*ANSWER_COLUMNS, *factors, *TAIL_COLUMNS]
        frame = pd.DataFrame.from_records(records, columns=columns)
        for name in ("position", "rating", "nr_shows"):
            frame[name] = frame[name].astype("int64")
        frame["label_position"] = frame["label_position"].astype("Int64")
        label_rank = frame["label_position"].fillna(10_000)
        frame = (
            frame.assign(_rank=label_rank)
            .sort_values(["study", "participant", "position", "_rank", "question"], kind="stable")
            .drop(columns="_rank")
            .reset_index(drop=True)
        )
        return frame
