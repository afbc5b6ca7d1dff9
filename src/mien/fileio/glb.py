"""The GLB container (glTF 2.0 binary): a 12-byte header, a JSON chunk and an optional binary chunk.

One codec for every ``.glb`` mien reads or writes: the reader of users' character files
(:mod:`mien.rig.files.gltf`), mien's own head and clip files (:mod:`mien.exchange.glb`), a user's file animated
(:mod:`mien.exchange.glb_user`) and VRM (:mod:`mien.exchange.vrm`). Layout (glTF 2.0 specification, section
"Binary glTF Layout"): ``magic "glTF" | version 2 | total length`` (little-endian uint32), then chunks of
``length | type | data``; the first chunk is ``JSON`` (padded with spaces to 4 bytes), the next, when present,
``BIN\\0`` (padded with zeros); chunks of other types are skipped, as the specification asks.

Accessors are read here too (:func:`read_accessor`): strided views, sparse substitution, every component type,
a count checked against :mod:`mien.fileio.limits` before anything is allocated;
the caller hands over the bytes of a buffer view, so compressed views (``EXT_meshopt_compression``) are decoded
by whoever owns that decoder.

Every problem raises :class:`GlbError` (an :class:`~mien.errors.InvalidValueError`) whose field names the file
and the place, and whose :attr:`GlbError.problem` says what is wrong in a few words.

>>> data = pack_glb({"asset": {"version": "2.0"}}, b"\\x01\\x02")
>>> len(data) % 4, data[:4]
(0, b'glTF')
>>> unpack_glb(data, "example.glb")
({'asset': {'version': '2.0'}}, b'\\x01\\x02\\x00\\x00')
>>> try:
...     unpack_glb(data[:30], "example.glb")
... except GlbError as exc:
...     print(exc.field, "|", exc.problem)
example.glb length | truncated: the GLB header says 60 bytes, the file has 30
"""

from __future__ import annotations

import json
import struct
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from mien.errors import InvalidValueError
from mien.fileio.limits import current

__all__ = [
    "COMPONENT_DTYPES",
    "TYPE_WIDTHS",
    "BytesLike",
    "GlbError",
    "dequantize",
    "pack_glb",
    "parse_json",
    "read_accessor",
    "unpack_glb",
]

MAGIC = b"glTF"
"""The first four bytes of every GLB file."""
VERSION = 2
"""The container version this codec reads and writes."""
JSON_CHUNK = b"JSON"
BIN_CHUNK = b"BIN\x00"
_HEADER = struct.Struct("<4sII")
_CHUNK = struct.Struct("<I4s")

COMPONENT_DTYPES: dict[int, type[np.generic]] = {
    5120: np.int8,
    5121: np.uint8,
    5122: np.int16,
    5123: np.uint16,
    5125: np.uint32,
    5126: np.float32,
}
"""glTF ``componentType`` -> NumPy scalar type."""
TYPE_WIDTHS: dict[str, int] = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
"""glTF accessor ``type`` -> components per element."""
BytesLike = bytes | bytearray | memoryview
"""What a buffer view's data may be: a zero-copy slice of a file's buffer is a memoryview."""
_NORMALIZE: dict[int, float] = {5120: 127.0, 5121: 255.0, 5122: 32767.0, 5123: 65535.0}


class GlbError(InvalidValueError):
    """A GLB container, its JSON or an accessor is truncated, corrupt or inconsistent.

    ``field`` is ``"<file> <place>"`` (``"head.glb header"``); :attr:`problem` is a short sentence naming what is
    wrong (``"truncated: the GLB header says 900 bytes, the file has 450"``).
    """

    def __init__(self, name: str, place: str, value: Any, expected: str, problem: str) -> None:
        super().__init__(f"{name} {place}", value, expected)
        self.problem = problem
        """What is wrong, without the file name (callers with their own error type quote it)."""


# ---------------------------------------------------------------------------------------------------------------
# The container


def pack_glb(document: Mapping[str, Any] | bytes, binary: bytes | bytearray | memoryview = b"") -> bytes:
    """GLB bytes of a glTF JSON document (a mapping, or its UTF-8 bytes) and the data of buffer 0.

    The JSON is padded with spaces and the binary chunk with zeros to 4 bytes; an empty ``binary`` writes no
    binary chunk.
    """
    text = document if isinstance(document, bytes) else json.dumps(document, separators=(",", ":")).encode("utf-8")
    text += b" " * ((-len(text)) % 4)
    parts = [b"", _CHUNK.pack(len(text), JSON_CHUNK), text]
    if len(binary):
        padding = b"\0" * ((-len(binary)) % 4)
        parts += [_CHUNK.pack(len(binary) + len(padding), BIN_CHUNK), bytes(binary), padding]
    total = sum(len(part) for part in parts) + _HEADER.size
    parts[0] = _HEADER.pack(MAGIC, VERSION, total)
    return b"".join(parts)


def unpack_glb(data: bytes, name: str) -> tuple[dict[str, Any], bytes | None]:
    """The JSON document (a dict) and the binary chunk (None when the file has none) of GLB ``data``.

    ``name`` names the file in errors. Checks the magic, the version, the declared length against the data
    (truncated files), that the first chunk is JSON and that every chunk fits; raises :class:`GlbError`.
    """
    if len(data) < _HEADER.size + _CHUNK.size:
        raise GlbError(name, "length", f"{len(data)} bytes", "a GLB file (12-byte header and a JSON chunk)",
                       f"truncated: {len(data)} bytes, shorter than a GLB header and its first chunk")  # fmt: skip
    magic, version, total = _HEADER.unpack_from(data, 0)
    if magic != MAGIC:
        raise GlbError(name, "header", bytes(data[:4]), "a glTF 2.0 binary file (magic 'glTF')",
                       f"not a GLB file (it starts with {bytes(data[:4])!r}, not b'glTF')")  # fmt: skip
    if version != VERSION:
        raise GlbError(name, "header", f"version {version}", "a glTF 2.0 binary file (version 2)",
                       f"GLB container version {version}; mien reads version 2")  # fmt: skip
    if total > len(data):
        raise GlbError(name, "length", f"{len(data)} of {total} bytes", "a complete file (truncated?)",
                       f"truncated: the GLB header says {total} bytes, the file has {len(data)}")  # fmt: skip
    if total < _HEADER.size + _CHUNK.size:
        raise GlbError(name, "length", f"{total} bytes declared", "a GLB file (12-byte header and a JSON chunk)",
                       f"corrupt GLB: the header declares {total} bytes, too few for a JSON chunk")  # fmt: skip
    chunks: list[tuple[bytes, int, int]] = []  # (type, start, stop)
    at = _HEADER.size
    while at + _CHUNK.size <= total:
        length, kind = _CHUNK.unpack_from(data, at)
        start = at + _CHUNK.size
        if start + length > total:
            raise GlbError(name, f"chunk at byte {at}", f"{length} bytes of {kind!r}", "a chunk inside the file",
                           f"truncated: chunk {kind!r} at byte {at} runs past the end")  # fmt: skip
        chunks.append((kind, start, start + length))
        at = start + length
    if chunks[0][0] != JSON_CHUNK:
        raise GlbError(name, "byte 16", chunks[0][0], "a JSON chunk first", "corrupt GLB: the first chunk is not JSON")
    document = parse_json(data[chunks[0][1] : chunks[0][2]], name)
    binary = next((bytes(data[start:stop]) for kind, start, stop in chunks[1:] if kind == BIN_CHUNK), None)
    return document, binary


def parse_json(text: bytes, name: str) -> dict[str, Any]:
    """The glTF JSON object of ``text`` (a ``.gltf`` file or a GLB's JSON chunk); raises :class:`GlbError`."""
    try:
        document = json.loads(text.decode("utf-8"))
    except (UnicodeDecodeError, ValueError) as exc:
        raise GlbError(name, "JSON chunk", str(exc), "valid JSON",
                       f"not a readable glTF 2.0 file (its JSON does not parse: {exc})") from None  # fmt: skip
    if not isinstance(document, dict):
        raise GlbError(name, "JSON chunk", type(document).__name__, "a JSON object",
                       "not a readable glTF 2.0 file (its JSON is not an object)")  # fmt: skip
    return document


# ---------------------------------------------------------------------------------------------------------------
# Accessors


def _rows(data: BytesLike, offset: int, stride: int, dtype: np.dtype[Any], width: int, count: int) -> np.ndarray | None:
    """(count, width) copy of strided elements of ``data``, or None when they run past its end."""
    item = dtype.itemsize * width
    stride = stride or item
    if count and offset + stride * (count - 1) + item > len(data):
        return None
    if not count:
        return np.zeros((0, width), dtype)
    if stride == item:
        return np.frombuffer(data, dtype, count * width, offset).reshape(count, width).copy()
    raw = np.frombuffer(data, np.uint8)
    rows = np.lib.stride_tricks.as_strided(raw[offset:], shape=(count, item), strides=(stride, 1))
    return np.ascontiguousarray(rows).view(dtype).reshape(count, width)


def read_accessor(
    document: Mapping[str, Any], index: int, view_bytes: Callable[[int], BytesLike], name: str,
    stride_of: Callable[[int], int] | None = None,
) -> np.ndarray:  # fmt: skip
    """(count, width) array of accessor ``index`` in its stored type (integers stay integers), sparse applied.

    ``view_bytes(i)`` gives the (decoded) bytes of buffer view ``i``; ``stride_of(i)`` its element stride in
    bytes (default: the view's ``byteStride``, 0 for tightly packed). :func:`dequantize` turns the result into
    floats. Raises :class:`GlbError` naming ``name`` for a missing accessor, an unknown type or data that runs
    past its view.
    """
    accessors = document.get("accessors") or []
    views = document.get("bufferViews") or []
    if not isinstance(index, int) or not 0 <= index < len(accessors):
        raise GlbError(name, f"accessor {index}", index, f"an accessor index below {len(accessors)}",
                       f"accessor {index} does not exist")  # fmt: skip
    accessor = accessors[index]
    component, kind = accessor.get("componentType"), accessor.get("type")
    if component not in COMPONENT_DTYPES or kind not in TYPE_WIDTHS:
        raise GlbError(name, f"accessor {index}", f"{component} / {kind}", "a glTF componentType and type",
                       f"accessor {index} has componentType {component} / type {kind}")  # fmt: skip
    dtype, width, count = np.dtype(COMPONENT_DTYPES[component]), TYPE_WIDTHS[kind], int(accessor.get("count", 0))
    if count < 0:
        raise GlbError(name, f"accessor {index}", count, "a count >= 0", f"accessor {index} has count {count}")
    limit = current().accessor_components
    if count * width > limit:  # before allocating: an accessor without a bufferView is zeros of any count
        raise GlbError(name, f"accessor {index}", f"{count} x {kind}", f"at most {limit} numbers per accessor",
                       f"accessor {index} declares {count * width} numbers, over the decode limit {limit} "
                       "(mien.fileio.limits)")  # fmt: skip

    def block(view: Any, offset: int, item_dtype: np.dtype[Any], items: int, n: int) -> np.ndarray:
        if not isinstance(view, int) or not 0 <= view < len(views):
            raise GlbError(name, f"accessor {index}", view, f"a bufferView index below {len(views)}",
                           f"accessor {index}: bufferView {view} does not exist")  # fmt: skip
        stride = stride_of(view) if stride_of is not None else int(views[view].get("byteStride") or 0)
        data = view_bytes(view)
        found = _rows(data, offset, stride, item_dtype, items, n)
        if found is None:
            raise GlbError(name, f"accessor {index}", "past the end of its bufferView", "a complete file",
                           f"accessor {index}: its data runs past bufferView {view} ({len(data)} bytes)")  # fmt: skip
        return found

    if accessor.get("bufferView") is not None:
        values = block(accessor["bufferView"], int(accessor.get("byteOffset") or 0), dtype, width, count)
    else:
        values = np.zeros((count, width), dtype)
    sparse = accessor.get("sparse")
    if sparse:
        indices, patch = sparse.get("indices") or {}, sparse.get("values") or {}
        n = int(sparse.get("count", 0))
        if not 0 <= n <= count:
            raise GlbError(name, f"accessor {index}", n, f"a sparse count 0..{count}",
                           f"accessor {index}: sparse count {n} outside 0..{count}")  # fmt: skip
        index_type = indices.get("componentType")
        if index_type not in (5121, 5123, 5125):
            raise GlbError(name, f"accessor {index}", index_type, "unsigned sparse indices",
                           f"accessor {index}: sparse indices of componentType {index_type}")  # fmt: skip
        index_dtype = np.dtype(COMPONENT_DTYPES[index_type])
        ids = block(indices.get("bufferView"), int(indices.get("byteOffset") or 0), index_dtype, 1, n)[:, 0]
        ids = ids.astype(np.int64)
        if ids.size and (ids.min() < 0 or ids.max() >= count):
            raise GlbError(name, f"accessor {index}", int(ids.max()), f"sparse indices below {count}",
                           f"accessor {index}: sparse indices outside 0..{count - 1}")  # fmt: skip
        values[ids] = block(patch.get("bufferView"), int(patch.get("byteOffset") or 0), dtype, width, n)
    return values


def dequantize(values: np.ndarray, accessor: Mapping[str, Any]) -> np.ndarray:
    """float32 values of an accessor read by :func:`read_accessor` (``KHR_mesh_quantization``: normalized
    integers map to 0..1 or -1..1 by glTF 2.0's formulas, unnormalized ones keep their value)."""
    component = accessor.get("componentType")
    if accessor.get("normalized") and component in _NORMALIZE:
        return np.maximum(values.astype(np.float32) / np.float32(_NORMALIZE[component]), np.float32(-1.0))
    return values.astype(np.float32)
