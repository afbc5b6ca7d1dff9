"""Installing assets from their public homes: ``mien assets fetch`` (the files mien reads, one by one at a pinned
commit, each checked against a shipped SHA-256 list, resumable, installed atomically).

The sources (repository, commit, base URL, hash list, licence) are data, in ``data/sources.toml``;
:mod:`mien.paths` finds an installed asset in :func:`mien.paths.installed_path`. Importing this package needs
the standard library only.
"""

from mien.assets.fetch import (
    SOURCES,
    AssetSource,
    FetchError,
    fetch_asset,
    file_hashes,
    files_to_fetch,
    load_sources,
    staging_folder,
)

__all__ = [
    "SOURCES",
    "AssetSource",
    "FetchError",
    "fetch_asset",
    "file_hashes",
    "files_to_fetch",
    "load_sources",
    "staging_folder",
]
