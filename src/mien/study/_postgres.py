"""A throw-away PostgreSQL server in a temporary folder (Debian's ``initdb`` / ``pg_ctl``), for the study
storage tests and the study server benchmark: :func:`temporary_postgres`.

Standard library only. PostgreSQL refuses to run as root, so as root the server runs as the ``postgres``
system user (the one Debian's ``postgresql`` package creates).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from mien.ports import free_port


def _postgres_bin(name: str) -> str | None:
    """``name`` on ``PATH``, else the newest ``/usr/lib/postgresql/*/bin/name``, else None."""
    found = shutil.which(name)
    if found:
        return found
    candidates = sorted(Path("/usr/lib/postgresql").glob(f"*/bin/{name}"))
    return str(candidates[-1]) if candidates else None


def postgres_available() -> bool:
    """Whether the PostgreSQL server binaries (``initdb`` and ``pg_ctl``) are installed."""
    return _postgres_bin("initdb") is not None and _postgres_bin("pg_ctl") is not None


@contextmanager
def temporary_postgres(prefix: str = "mien-pg-", max_connections: int | None = None) -> Iterator[str]:
    """Start a new PostgreSQL server in a temporary folder; yields its SQLAlchemy URL.

    The URL is ``postgresql+psycopg://postgres@127.0.0.1:PORT/postgres`` (user ``postgres``, trust
    authentication, a free port on loopback). ``prefix``: of the temporary folder's name.
    ``max_connections``: the server's limit (None: PostgreSQL's default, 100). The server is stopped and
    its folder removed on exit. Raises :class:`FileNotFoundError` when the binaries are missing (check
    :func:`postgres_available` first) and :class:`subprocess.CalledProcessError` when the server does not
    start.
    """
    initdb, pg_ctl = _postgres_bin("initdb"), _postgres_bin("pg_ctl")
    if initdb is None or pg_ctl is None:
        raise FileNotFoundError("PostgreSQL server binaries not found: apt install postgresql")
    folder = Path(tempfile.mkdtemp(prefix=prefix))  # its own folder, not inside a 0700 one: postgres reads it
    as_user: list[str] = []
    if os.geteuid() == 0:
        shutil.chown(folder, "postgres")
        as_user = ["runuser", "-u", "postgres", "--"]
    data, port = folder / "data", free_port()
    try:
        subprocess.run(
            [*as_user, initdb, "-D", str(data), "-U", "postgres", "-A", "trust"], check=True, capture_output=True
        )
        options = f"-p {port} -h 127.0.0.1 -k {folder}"
        if max_connections is not None:
            options += f" -c max_connections={max_connections}"
        subprocess.run(
            [*as_user, pg_ctl, "-D", str(data), "-o", options, "-l", str(folder / "log"), "-w", "start"],
            check=True,
            capture_output=True,
        )
        try:
            yield f"postgresql+psycopg://postgres@127.0.0.1:{port}/postgres"
        finally:
            subprocess.run([*as_user, pg_ctl, "-D", str(data), "-m", "fast", "-w", "stop"], capture_output=True)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
