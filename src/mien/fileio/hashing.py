"""Content hashes: a file's SHA-256 and a short stable digest of a cache key.

>>> key_sha256({"b": 1, "a": [2, 3]}, length=12)
'e91782078782'
"""

from __future__ import annotations

import hashlib
import json
import os

__all__ = ["CHUNK_BYTES", "file_sha256", "key_sha256"]

CHUNK_BYTES = 1 << 20
"""Bytes read at a time while hashing a file (1 MiB: large files never sit in memory whole)."""


def file_sha256(path: str | os.PathLike[str]) -> str:
    """Hex SHA-256 (64 digits) of the bytes of the file at ``path``."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(CHUNK_BYTES), b""):
            digest.update(block)
    return digest.hexdigest()


def key_sha256(key: object, length: int = 64) -> str:
    """The first ``length`` hex digits of the SHA-256 of ``key`` as canonical JSON (sorted keys): a cache
    file's name that changes whenever any part of the key does."""
    return hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()[:length]
