"""The one GLB codec: container round trip and padding, every malformed container, accessors (strided, sparse,
quantized), and the readers and writers that share it."""

from __future__ import annotations

import json
import struct

import numpy as np
import pytest

from mien.errors import InvalidValueError
from mien.fileio.glb import GlbError, dequantize, pack_glb, parse_json, read_accessor, unpack_glb


def _glb(chunks: list[tuple[bytes, bytes]], version: int = 2, total: int | None = None) -> bytes:
    body = b"".join(struct.pack("<I4s", len(data), kind) + data for kind, data in chunks)
    return struct.pack("<4sII", b"glTF", version, 12 + len(body) if total is None else total) + body


def test_round_trip_pads_json_with_spaces_and_binary_with_zeros() -> None:
    document = {"asset": {"version": "2.0"}, "buffers": [{"byteLength": 5}]}
    data = pack_glb(document, b"\x01\x02\x03\x04\x05")
    magic, version, total = struct.unpack_from("<4sII", data)
    assert (magic, version, total) == (b"glTF", 2, len(data)) and len(data) % 4 == 0
    json_length, kind = struct.unpack_from("<I4s", data, 12)
    text = data[20 : 20 + json_length]
    assert kind == b"JSON" and json_length % 4 == 0 and json.loads(text) == document
    assert text.rstrip(b" ") == json.dumps(document, separators=(",", ":")).encode()
    bin_length, kind = struct.unpack_from("<I4s", data, 20 + json_length)
    assert (kind, bin_length) == (b"BIN\x00", 8)
    assert data[-8:] == b"\x01\x02\x03\x04\x05\x00\x00\x00"
    assert unpack_glb(data, "x.glb") == (document, b"\x01\x02\x03\x04\x05\x00\x00\x00")


def test_no_binary_chunk_and_unknown_chunks_skipped() -> None:
    data = pack_glb({"asset": {"version": "2.0"}})
    assert len(data) == 12 + 8 + 28 and unpack_glb(data, "x.glb") == ({"asset": {"version": "2.0"}}, None)
    text = b'{"asset":{"version":"2.0"}}   '
    with_extra = _glb([(b"JSON", text + b" "), (b"XTRA", b"abcd"), (b"BIN\x00", b"\x07\x00\x00\x00")])
    assert unpack_glb(with_extra, "x.glb")[1] == b"\x07\x00\x00\x00"


@pytest.mark.parametrize(
    ("data", "field", "problem"),
    [
        (b"glTF\x02\x00\x00\x00", "bad.glb length", "truncated: 8 bytes"),
        (b"PK\x03\x04" + bytes(40), "bad.glb header", "not a GLB file (it starts with b'PK\\x03\\x04'"),
        (_glb([(b"JSON", b"{}  ")], version=1), "bad.glb header", "GLB container version 1"),
        (_glb([(b"JSON", b"{}  ")], total=400), "bad.glb length", "truncated: the GLB header says 400 bytes"),
        (_glb([(b"BIN\x00", b"abcd"), (b"JSON", b"{}  ")]), "bad.glb byte 16", "corrupt GLB: the first chunk is"),
        (_glb([(b"JSON", b"{{{{")]), "bad.glb JSON chunk", "not a readable glTF 2.0 file (its JSON does not parse"),
        (_glb([(b"JSON", b"[1] ")]), "bad.glb JSON chunk", "not a readable glTF 2.0 file (its JSON is not an object)"),
    ],
)  # fmt: skip
def test_malformed_containers_raise_naming_the_file_and_the_place(data: bytes, field: str, problem: str) -> None:
    with pytest.raises(GlbError) as caught:
        unpack_glb(data, "bad.glb")
    assert isinstance(caught.value, InvalidValueError)
    assert caught.value.field == field and caught.value.problem.startswith(problem), caught.value.problem


def test_chunk_lengths_are_checked_against_the_declared_total() -> None:
    data = _glb([(b"JSON", b"{}  ")]) + struct.pack("<I4s", 64, b"BIN\x00") + bytes(8)
    data = data[:8] + struct.pack("<I", len(data)) + data[12:]
    with pytest.raises(GlbError, match="chunk at byte 24") as caught:
        unpack_glb(data, "bad.glb")
    assert caught.value.problem == "truncated: chunk b'BIN\\x00' at byte 24 runs past the end"


def test_parse_json_of_a_gltf_file() -> None:
    assert parse_json(b'{"asset": {"version": "2.0"}}', "a.gltf") == {"asset": {"version": "2.0"}}
    with pytest.raises(GlbError, match=r"a\.gltf JSON chunk"):
        parse_json(b"\xff\xfe", "a.gltf")


def _document(accessors: list[dict[str, object]], views: list[dict[str, object]]) -> dict[str, object]:
    return {"accessors": accessors, "bufferViews": views}


def test_accessors_tight_strided_sparse_and_quantized() -> None:
    tight = np.arange(6, dtype=np.float32).tobytes()
    strided = b"".join(struct.pack("<hhhxx", *row) for row in ([32767, 0, -32767], [16384, -32768, 1]))
    ids, patch = np.array([2], np.uint16).tobytes(), np.array([9.0, 8.0], np.float32).tobytes()
    views = {0: tight, 1: strided, 2: ids, 3: patch}
    document = _document(
        [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC2"},
            {"bufferView": 1, "componentType": 5122, "count": 2, "type": "VEC3", "normalized": True},
            {"bufferView": 0, "byteOffset": 8, "componentType": 5126, "count": 2, "type": "SCALAR"},
            {"componentType": 5126, "count": 3, "type": "VEC2", "sparse": {"count": 1,
             "indices": {"bufferView": 2, "componentType": 5123}, "values": {"bufferView": 3}}},
        ],
        [{"byteLength": 24}, {"byteLength": 16, "byteStride": 8}, {"byteLength": 2}, {"byteLength": 8}],
    )  # fmt: skip
    accessors = document["accessors"]
    assert isinstance(accessors, list)
    np.testing.assert_array_equal(read_accessor(document, 0, views.__getitem__, "a.glb"), [[0, 1], [2, 3], [4, 5]])
    raw = read_accessor(document, 1, views.__getitem__, "a.glb")
    assert raw.dtype == np.int16 and raw.tolist() == [[32767, 0, -32767], [16384, -32768, 1]]
    np.testing.assert_allclose(dequantize(raw, accessors[1]), [[1, 0, -1], [16384 / 32767, -1, 1 / 32767]], rtol=1e-6)
    np.testing.assert_array_equal(read_accessor(document, 2, views.__getitem__, "a.glb")[:, 0], [2.0, 3.0])
    np.testing.assert_array_equal(read_accessor(document, 3, views.__getitem__, "a.glb"), [[0, 0], [0, 0], [9, 8]])


def test_accessor_errors_name_the_file() -> None:
    document = _document([{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
                          {"bufferView": 0, "componentType": 1, "count": 1, "type": "VEC3"}],
                         [{"byteLength": 12}])  # fmt: skip
    with pytest.raises(GlbError, match=r"a\.glb accessor 0") as caught:
        read_accessor(document, 0, lambda _: bytes(12), "a.glb")
    assert caught.value.problem == "accessor 0: its data runs past bufferView 0 (12 bytes)"
    with pytest.raises(GlbError, match=r"a\.glb accessor 1='1 / VEC3'") as caught:
        read_accessor(document, 1, lambda _: bytes(12), "a.glb")
    assert caught.value.problem == "accessor 1 has componentType 1 / type VEC3"
    with pytest.raises(GlbError, match=r"a\.glb accessor 5") as caught:
        read_accessor(document, 5, lambda _: bytes(12), "a.glb")
    assert caught.value.problem == "accessor 5 does not exist"
