"""Installing assets from their public homes: ``mien assets fetch`` (download, verify, unpack atomically).

The sources (URL, expected SHA-256, licence) are data, in ``data/sources.toml``; :mod:`mien.paths` finds an
installed asset in :func:`mien.paths.installed_path`. Importing this package needs the standard library only.
"""

from mien.assets.fetch import SOURCES, AssetSource, fetch_asset, load_sources

__all__ = ["SOURCES", "AssetSource", "fetch_asset", "load_sources"]
