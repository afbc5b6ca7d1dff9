"""Download an asset archive, check its SHA-256 and unpack it atomically where :mod:`mien.paths` looks.

Nothing half-written is ever left: the archive is streamed into a temporary folder beside the destination,
hashed while it streams, refused on a hash mismatch, unpacked and checked there, and only then renamed into
place (one ``rename`` on the same file system). Any failure removes the temporary folder.
"""

from __future__ import annotations

import math
import os
import re
import tempfile
import tomllib
import zipfile
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from importlib import resources
from pathlib import Path, PurePosixPath
from typing import Any

from mien.errors import InvalidValueError, UnknownNameError
from mien.fileio.hashing import file_sha256
from mien.paths import installed_path
from mien.progress import progress

__all__ = ["CHUNK_BYTES", "SOURCES", "AssetSource", "fetch_asset", "load_sources"]

CHUNK_BYTES = 1 << 20
"""Download block size, bytes (one progress step)."""


@dataclass(frozen=True)
class AssetSource:
    """Where one fetchable asset comes from (a table of ``data/sources.toml``)."""

    name: str
    """Name on the command line (``ict-facekit``)."""
    asset: str
    """Its name in :data:`mien.paths.ASSETS` (``ict_facekit``)."""
    url: str
    """Default download URL of the zip archive."""
    sha256: str
    """Expected SHA-256 of the archive, lower-case hex; empty when no maintainer has recorded it yet."""
    licence: str
    """Licence of the asset."""
    marker: str
    """Relative path (POSIX) that marks the asset's root folder inside the archive."""


def load_sources() -> dict[str, AssetSource]:
    """Read ``data/sources.toml``: command-line name -> :class:`AssetSource`."""
    text = resources.files("mien.assets").joinpath("data/sources.toml").read_text(encoding="utf-8")
    return {name: AssetSource(name=name, **table) for name, table in tomllib.loads(text).items()}


SOURCES: dict[str, AssetSource] = load_sources()
"""The fetchable assets, from ``data/sources.toml``."""


def _check_sha256(text: str | None) -> str:
    value = (text or "").strip().lower()
    if value and not re.fullmatch(r"[0-9a-f]{64}", value):
        raise InvalidValueError("sha256", text, "64 hexadecimal digits")
    return value


def _chunks(response: Any) -> Iterator[bytes]:
    while block := response.read(CHUNK_BYTES):
        yield block


def _download(url: str, target: Path, show_progress: bool, timeout_s: float, label: str) -> str:
    """Stream ``url`` into ``target``; returns the SHA-256 hex digest of what was written."""
    import urllib.error
    import urllib.request

    if not re.match(r"(?i)^(https?|file)://", url):
        raise InvalidValueError("url", url, "an http://, https:// or file:// URL")
    request = urllib.request.Request(url, headers={"User-Agent": "mien-assets-fetch"})
    try:
        with urllib.request.urlopen(request, timeout=timeout_s) as response, target.open("wb") as handle:
            length = int(response.headers.get("Content-Length") or 0) if hasattr(response, "headers") else 0
            total = math.ceil(length / CHUNK_BYTES) if length else None
            size = f" ({length / 1024**2:.0f} MiB)" if length else ""
            for block in progress(_chunks(response), total=total, desc=f"downloading {label}{size}",
                                  enabled=show_progress):  # fmt: skip
                handle.write(block)
    except urllib.error.HTTPError as exc:
        raise InvalidValueError("url", url, f"a downloadable archive (the server answered HTTP {exc.code} "
                                f"{exc.reason}); check the address or pass another with --url") from None  # fmt: skip
    except urllib.error.URLError as exc:
        reason = getattr(exc.reason, "strerror", None) or str(exc.reason)
        raise InvalidValueError(
            "url", url, f"a reachable server ({reason}); check the network or pass another address with --url"
        ) from None
    except (TimeoutError, ConnectionError) as exc:
        raise InvalidValueError("url", url, f"a server that answers ({exc}); try again or pass --url") from None
    return file_sha256(target)


def _unpack(archive: Path, folder: Path, marker: str, url: str) -> Path:
    """Extract ``archive`` into ``folder`` (refusing unsafe names); returns the folder that holds ``marker``."""
    try:
        with zipfile.ZipFile(archive) as package:
            for member in package.namelist():
                parts = PurePosixPath(member).parts
                if member.startswith(("/", "\\")) or ".." in parts or (parts and ":" in parts[0]):
                    raise InvalidValueError("archive member", member, "a relative path inside the archive")
            package.extractall(folder)
    except zipfile.BadZipFile as exc:
        raise InvalidValueError("archive", url, f"a zip archive ({exc})") from None
    candidates = [folder, *sorted(p for p in folder.iterdir() if p.is_dir())]
    for root in candidates:
        if (root / marker).is_file():
            return root
    raise InvalidValueError("archive", url, f"an archive holding {marker} (at its top or in one top folder)")


def fetch_asset(
    name: str,
    url: str | None = None,
    sha256: str | None = None,
    dest: str | os.PathLike[str] | None = None,
    *,
    force: bool = False,
    show_progress: bool = True,
    timeout_s: float = 30.0,
    verify: Callable[[Path], list[str]] | None = None,
) -> Path:
    """Download asset ``name`` (see :data:`SOURCES`), check its SHA-256, install it; returns the folder.

    url / sha256: override the recorded source (``sha256`` is 64 hex digits). dest: the folder to create
    (default :func:`mien.paths.installed_path`). force: replace an existing folder at ``dest``. verify: a
    function listing what an unpacked folder lacks (empty list: complete), run before it is published.
    Raises :class:`InvalidValueError` on a bad URL, an HTTP error, an unreachable server, a hash mismatch
    (or no known hash), an archive that is not a zip or lacks the asset, or an existing ``dest``;
    nothing is left behind then.
    """

    if name not in SOURCES:
        raise UnknownNameError("fetchable asset", name, tuple(SOURCES))
    source = SOURCES[name]
    url = url or source.url
    expected = _check_sha256(sha256) or _check_sha256(source.sha256)
    target = Path(dest).expanduser() if dest is not None else installed_path(source.asset)
    if target.exists() and not force:
        raise InvalidValueError("dest", str(target), "a folder that does not exist yet (or pass --force to replace it)")
    created = []  # parent folders made here, removed again on failure
    for parent in reversed(target.parents):
        if not parent.exists():
            created.append(parent)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InvalidValueError("dest", str(target), f"a place that can be written ({exc.strerror})") from None
    try:
        with tempfile.TemporaryDirectory(dir=target.parent, prefix=f".{target.name}.partial-") as work:
            archive = Path(work) / f"{name}.zip"
            digest = _download(url, archive, show_progress, timeout_s, name)
            if not expected:
                raise InvalidValueError(
                    "sha256", None, f"the archive's SHA-256, but none is recorded for {url}; the download measured "
                    f"{digest}: check it against the source, then run again with --sha256 {digest}"
                )  # fmt: skip
            if digest != expected:
                raise InvalidValueError(
                    "sha256", digest, f"{expected} for {url}: the download does not match, nothing was installed"
                )
            root = _unpack(archive, Path(work) / "unpacked", source.marker, url)
            missing = verify(root) if verify is not None else []
            if missing:
                shown = ", ".join(missing[:8]) + (" ..." if len(missing) > 8 else "")
                raise InvalidValueError("archive", url, f"a complete {name} ({len(missing)} files missing: {shown})")
            if target.exists():  # --force: move the old install aside first, dropped with the temporary folder
                target.rename(Path(work) / "previous")
            root.rename(target)
    except BaseException:
        for folder in reversed(created):
            if folder.exists() and not any(folder.iterdir()):
                folder.rmdir()
        raise
    return target
