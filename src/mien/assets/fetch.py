"""Install an asset from its public home, file by file at a pinned commit (``mien assets fetch``).

Each source (``data/sources.toml``) names a repository, one commit, the base URL that serves that commit's
files and the SHA-256 of every file at that commit (a ``sha256sum`` list shipped beside it). Only the files
mien reads are fetched: what the asset's loader finds missing in an empty folder (the loader stays the one
home of that list) plus the source's extra files (its licence).

Nothing is ever half-installed. Files stream into a staging folder beside the destination
(``.NAME.partial``), each as ``FILE.part``, renamed to ``FILE`` once its SHA-256 matches the list; the staging
folder becomes the destination (one ``rename`` on the same file system) only when every file is there. An
interruption (a cut connection, a timeout, an HTTP 5xx, Ctrl-C) keeps the verified files and the partial one:
the same command resumes, asking for the rest of the partial file with an HTTP ``Range`` request. A failure
that retrying cannot mend (bytes that differ from the recorded hash, an HTTP 4xx, a write error such as a full
disk) removes the staging folder: nothing is left behind.
"""

from __future__ import annotations

import hashlib
import http.client
import math
import os
import re
import shutil
import tempfile
import tomllib
import urllib.error
import urllib.request
from collections.abc import Generator, Iterator
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from mien.errors import InvalidValueError, MienError, UnknownNameError
from mien.fileio.hashing import file_sha256
from mien.paths import installed_path
from mien.progress import progress

__all__ = [
    "CHUNK_BYTES",
    "SOURCES",
    "TICK_BYTES",
    "AssetSource",
    "FetchError",
    "fetch_asset",
    "file_hashes",
    "files_to_fetch",
    "load_sources",
    "staging_folder",
]

CHUNK_BYTES = 1 << 16
"""Bytes read from the network at a time."""

TICK_BYTES = 1 << 20
"""Bytes per step of the progress bar (1 MiB)."""

_MIB = 1024**2


class FetchError(MienError):
    """A download failed; the message names the file, what happened and what to do."""


@dataclass(frozen=True)
class AssetSource:
    """Where one fetchable asset comes from (a table of ``data/sources.toml``)."""

    name: str
    """Name on the command line (``ict-facekit``)."""
    asset: str
    """Its name in :data:`mien.paths.ASSETS` (``ict_facekit``)."""
    licence: str
    """Licence of the asset."""
    repository: str
    """The repository's home page."""
    commit: str
    """The pinned commit (40 hex digits)."""
    base_url: str
    """URL that serves the commit's files: ``FILE`` comes from ``base_url/FILE`` (no trailing slash)."""
    hashes: str
    """File name, in ``mien/assets/data``, of the ``sha256sum`` list of the files at ``commit``."""
    extra_files: tuple[str, ...]
    """Files fetched besides the ones the loader reads (the licence), relative POSIX paths."""
    download_bytes: int
    """Total size of the fetched files at ``commit``, bytes."""


def load_sources() -> dict[str, AssetSource]:
    """Read ``data/sources.toml``: command-line name -> :class:`AssetSource`."""
    text = resources.files("mien.assets").joinpath("data/sources.toml").read_text(encoding="utf-8")
    sources = {}
    for name, table in tomllib.loads(text).items():
        fields = {**table, "extra_files": tuple(table.get("extra_files", ()))}
        fields["base_url"] = fields["base_url"].format(commit=fields["commit"]).rstrip("/")
        sources[name] = AssetSource(name=name, **fields)
    return sources


SOURCES: dict[str, AssetSource] = load_sources()
"""The fetchable assets, from ``data/sources.toml``."""


def file_hashes(source: AssetSource) -> dict[str, str]:
    """Relative POSIX path -> lower-case hex SHA-256 of every file of ``source`` at its commit, read from the
    shipped ``sha256sum`` list (``#`` lines are comments)."""
    text = resources.files("mien.assets").joinpath("data", source.hashes).read_text(encoding="utf-8")
    table = {}
    for number, line in enumerate(text.splitlines(), 1):
        if not line.strip() or line.startswith("#"):
            continue
        match = re.fullmatch(r"([0-9a-fA-F]{64}) [ *](\S.*)", line.strip())
        if match is None:
            raise InvalidValueError(f"{source.hashes} line {number}", line, "'<64 hex digits>  <path>'")
        table[match[2]] = match[1].lower()
    return table


def files_to_fetch(source: AssetSource) -> tuple[str, ...]:
    """The files of ``source`` mien reads, relative POSIX paths in download order: the extra files (licence),
    then what the asset's loader finds missing in an empty folder."""
    loader: list[str] = []
    if source.asset == "ict_facekit":
        from mien.rig.ict_facekit import ict_missing_files

        with tempfile.TemporaryDirectory(prefix="mien-empty-") as empty:
            (Path(empty) / "FaceXModel").mkdir()
            loader = ict_missing_files(empty)
    return (*source.extra_files, *(name for name in loader if name not in source.extra_files))


def staging_folder(target: Path) -> Path:
    """The folder beside ``target`` where a fetch downloads before it renames (kept to resume after a cut)."""
    return target.parent / f".{target.name}.partial"


class _Cut(Exception):
    """The transfer stopped early; retrying can finish it (the staging folder is kept)."""


class _Fatal(Exception):
    """Retrying cannot mend it (the staging folder is removed)."""


def _check_base_url(url: str) -> str:
    if not re.match(r"(?i)^(https?|file)://\S+$", url):
        raise InvalidValueError("url", url, "an http://, https:// or file:// URL of the folder that serves the files")
    return url.rstrip("/")


def _stream(url: str, part: Path, timeout_s: float) -> Generator[int, None, str]:
    """Download ``url`` into ``part``, continuing after its present bytes with a Range request; yields the
    bytes written per block and returns the SHA-256 (hex) of the whole file, hashed as it streams.
    Raises :class:`_Cut` on a body shorter than announced."""
    offset = part.stat().st_size if part.exists() else 0
    headers = {"User-Agent": "mien-assets-fetch"}
    if offset:
        headers["Range"] = f"bytes={offset}-"
    try:
        response = urllib.request.urlopen(urllib.request.Request(url, headers=headers), timeout=timeout_s)
    except urllib.error.HTTPError as exc:
        if exc.code == 416 and offset:  # the partial file is already whole: its hash decides
            return file_sha256(part)
        raise
    with response:
        status = getattr(response, "status", None) or 200
        if status == 206 and not str(response.headers.get("Content-Range", "")).startswith(f"bytes {offset}-"):
            part.unlink()  # the next try starts this file afresh
            raise _Cut(f"the server answered another byte range than {offset}-")
        if status != 206:
            offset = 0  # the server sent the whole file (it ignores Range): start again
        digest = hashlib.sha256()
        if offset:
            with part.open("rb") as kept:
                for block in iter(lambda: kept.read(CHUNK_BYTES), b""):
                    digest.update(block)
        length = response.headers.get("Content-Length")
        expected = offset + int(length) if length and length.isdigit() else None
        written = offset
        try:  # unbuffered: a write error (a full disk) surfaces at its write, never later at close
            handle = part.open("ab" if offset else "wb", buffering=0)
        except OSError as exc:
            raise _Fatal(f"could not write {part} ({exc.strerror or exc})") from None
        with handle:
            while block := response.read(CHUNK_BYTES):
                view = memoryview(block)
                try:
                    while view:
                        view = view[handle.write(view) :]
                except OSError as exc:
                    raise _Fatal(f"could not write {part} ({exc.strerror or exc})") from None
                digest.update(block)
                written += len(block)
                yield len(block)
        if expected is not None and written < expected:
            raise _Cut(f"the connection closed after {written:,} of {expected:,} bytes")
    return digest.hexdigest()


def _fetch_one(url: str, staging: Path, path: str, sha256: str, commit: str, timeout_s: float) -> Iterator[int]:
    """Download one file into ``staging/path`` (via ``.part``), check its hash, rename it; yields bytes."""
    final = staging / path
    part = final.with_name(final.name + ".part")
    try:
        final.parent.mkdir(parents=True, exist_ok=True)
        measured = yield from _stream(url, part, timeout_s)
    except urllib.error.HTTPError as exc:
        what = f"{path}: the server answered HTTP {exc.code} {exc.reason} for {url}"
        if exc.code >= 500 or exc.code in (408, 429):
            raise _Cut(what) from None
        raise _Fatal(
            f"{what}; check --url (a mirror must serve commit {commit[:7]}'s files at the same paths)"
        ) from None
    except urllib.error.URLError as exc:
        reason = getattr(exc.reason, "strerror", None) or str(exc.reason)
        raise _Cut(f"could not reach {url} ({reason}); check the network or the address (--url)") from None
    except TimeoutError:
        raise _Cut(f"{path}: {url} sent nothing for {timeout_s:g} s (on a slow network raise --timeout)") from None
    except (ConnectionError, http.client.HTTPException) as exc:
        raise _Cut(f"{path}: the transfer from {url} failed ({exc or type(exc).__name__})") from None
    except _Cut as exc:
        raise _Cut(f"{path}: {exc} ({url})") from None
    except OSError as exc:  # the staging folder itself (mkdir)
        raise _Fatal(f"could not write {final.parent} ({exc.strerror or exc})") from None
    if measured != sha256:
        raise _Fatal(
            f"{path} from {url} has SHA-256 {measured}, not the {sha256} recorded for commit {commit[:7]}: "
            "the server does not serve that commit's file (check --url)"
        )
    try:
        part.rename(final)
    except OSError as exc:
        raise _Fatal(f"could not write {final} ({exc.strerror or exc})") from None


def _ticks(blocks: Iterator[int]) -> Iterator[None]:
    """One item per :data:`TICK_BYTES` of ``blocks`` (byte counts): the progress bar's steps."""
    pending = 0
    for size in blocks:
        pending += size
        while pending >= TICK_BYTES:
            pending -= TICK_BYTES
            yield None
    if pending:  # the last, partial MiB: the bar ends full
        yield None


def _folder_bytes(folder: Path) -> int:
    return sum(p.stat().st_size for p in folder.rglob("*") if p.is_file()) if folder.is_dir() else 0


def _remove_created(created: list[Path]) -> None:
    for folder in reversed(created):
        if folder.is_dir() and not any(folder.iterdir()):
            folder.rmdir()


def fetch_asset(
    name: str,
    url: str | None = None,
    dest: str | os.PathLike[str] | None = None,
    *,
    force: bool = False,
    show_progress: bool = True,
    timeout_s: float = 30.0,
) -> Path:
    """Download the files of asset ``name`` (see :data:`SOURCES`) that mien reads, check each against the
    SHA-256 list of the pinned commit, and install them; returns the installed folder.

    url: the base URL serving the commit's files instead of the recorded one (a mirror, a local server).
    dest: the folder to create (default :func:`mien.paths.installed_path`). force: replace an existing folder
    at ``dest``. A second call after an interruption resumes (see the module docstring).
    Raises :class:`InvalidValueError` on a bad URL or an existing ``dest``, :class:`FetchError` when a
    download fails (the message says whether the finished files were kept for a resume).
    """
    if name not in SOURCES:
        raise UnknownNameError("fetchable asset", name, tuple(SOURCES))
    source = SOURCES[name]
    base = _check_base_url(url or source.base_url)
    target = Path(dest).expanduser() if dest is not None else installed_path(source.asset)
    if target.exists() and not force:
        raise InvalidValueError("dest", str(target), "a folder that does not exist yet (or pass --force to replace it)")
    hashes = file_hashes(source)
    files = files_to_fetch(source)
    unlisted = [path for path in files if path not in hashes]
    if unlisted:  # the loader reads a file the pinned commit's list lacks: the package is inconsistent
        raise FetchError(f"{source.hashes} lists no SHA-256 for {unlisted[0]}; reinstall mien")
    created = [parent for parent in reversed(target.parents) if not parent.exists()]
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InvalidValueError("dest", str(target), f"a place that can be written ({exc.strerror})") from None
    staging = staging_folder(target)
    try:
        staging.mkdir(exist_ok=True)
        todo = []
        for path in files:  # resume: keep what an earlier run finished, if it still matches
            done = staging / path
            if done.is_file() and file_sha256(done) == hashes[path]:
                continue
            done.unlink(missing_ok=True)
            todo.append(path)
        left = max(0, source.download_bytes - _folder_bytes(staging))
        blocks = (
            size
            for path in todo
            for size in _fetch_one(f"{base}/{path}", staging, path, hashes[path], source.commit, timeout_s)
        )
        desc = f"downloading {name} ({len(todo)} files, {left / _MIB:.0f} MiB)"
        for _ in progress(_ticks(blocks), total=math.ceil(left / TICK_BYTES), desc=desc, enabled=show_progress):
            pass
        if target.exists():  # --force: the old install goes only once the new one is complete
            previous = target.parent / f".{target.name}.previous"
            shutil.rmtree(previous, ignore_errors=True)
            target.rename(previous)
            try:
                staging.rename(target)
            except OSError:
                previous.rename(target)
                raise
            shutil.rmtree(previous, ignore_errors=True)
        else:
            staging.rename(target)
    except _Fatal as exc:
        shutil.rmtree(staging, ignore_errors=True)
        _remove_created(created)
        raise FetchError(f"{exc}; nothing was installed") from None
    except _Cut as exc:
        verified = sum((staging / path).is_file() for path in files)
        if _folder_bytes(staging) == 0:
            shutil.rmtree(staging, ignore_errors=True)
            _remove_created(created)
            raise FetchError(f"{exc}; nothing was installed") from None
        raise FetchError(
            f"{exc}; {verified} of {len(files)} files ({_folder_bytes(staging) / _MIB:.0f} MiB) are kept in "
            f"{staging}: run the same command again to resume"
        ) from None
    except BaseException:  # Ctrl-C or an unexpected error: what is verified stays for a resume
        if _folder_bytes(staging) == 0:
            shutil.rmtree(staging, ignore_errors=True)
            _remove_created(created)
        raise
    return target
