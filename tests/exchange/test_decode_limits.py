"""Issue 29, case 3: every clip reader checks what a file declares against :mod:`mien.fileio.limits` before it
allocates (a small file must not make mien take gigabytes), and names the file and the count."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest

from mien.errors import InvalidValueError
from mien.exchange import clip_json, clip_npz, curves_csv, maya_anim, openface_csv, openfacs_jsonl
from mien.exchange import glb as glb_format
from mien.facs.clip import Clip
from mien.fileio.glb import GlbError, pack_glb, read_accessor
from mien.fileio.limits import DecodeLimits, current, decode_limits


def _stream(data: bytes, name: str) -> io.BytesIO:
    stream = io.BytesIO(data)
    stream.name = name
    return stream


def test_the_defaults_and_a_limit_inside_a_block() -> None:
    assert current() == DecodeLimits()
    with decode_limits(clip_values=10) as limits:
        assert current().clip_values == 10 == limits.clip_values
        assert current().zip_members == DecodeLimits().zip_members
    assert current().clip_values == 2**25
    with pytest.raises(InvalidValueError, match="clip_values"):
        with decode_limits(clip_values=-1):
            pass


def test_an_npz_of_zeros_is_refused_from_its_headers() -> None:
    """The issue's 1 MB ``.npz`` unpacked to 1 GiB; here 30 KB that would unpack to 32 MB, under a lower limit."""
    buffer = io.BytesIO()
    clip_npz.write(Clip(np.zeros((64_000, 62)), 60.0, tuple(f"c{i}" for i in range(62))), buffer)
    assert len(buffer.getvalue()) < 100_000
    with decode_limits(clip_values=1_000_000):
        with pytest.raises(InvalidValueError, match=r"bomb\.npz size.*3968000 values.*at most 1000000"):
            clip_npz.read(_stream(buffer.getvalue(), "bomb.npz"))
    with decode_limits(zip_bytes=1_000_000):
        with pytest.raises(InvalidValueError, match=r"bytes unpacked"):
            clip_npz.read(_stream(buffer.getvalue(), "bomb.npz"))
    assert clip_npz.read(_stream(buffer.getvalue(), "bomb.npz")).n_frames == 64_000  # under the default limits


def test_an_npz_with_many_members_is_refused(tmp_path) -> None:
    path = tmp_path / "many.npz"
    np.savez(path, values=np.zeros((2, 1)), fps=np.array(30.0), channels=np.array(["a"]),
             **{f"x{i}": np.zeros(1) for i in range(70)})  # fmt: skip
    with pytest.raises(InvalidValueError, match=r"many\.npz size.*73 zip members"):
        clip_npz.read(path)


def test_a_glb_accessor_count_is_checked_before_allocating() -> None:
    document = {
        "asset": {"version": "2.0"},
        "meshes": [{"primitives": [{"attributes": {}, "targets": [{}]}]}],
        "nodes": [{"mesh": 0}],
        "accessors": [{"componentType": 5126, "type": "SCALAR", "count": 100_000_000}] * 2,
        "animations": [{"channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
                        "samplers": [{"input": 0, "output": 1}]}],
    }  # fmt: skip
    data = pack_glb(document)
    assert len(data) < 500  # the 476 bytes took 1.46 GB
    with pytest.raises(GlbError, match=r"bomb\.glb accessor 0.*100000000 x SCALAR.*at most 33554432"):
        glb_format.read(_stream(data, "bomb.glb"))
    negative = {"accessors": [{"componentType": 5126, "type": "VEC3", "count": -5}]}
    with pytest.raises(GlbError, match=r"neg\.glb accessor 0=-5 .*a count >= 0"):
        read_accessor(negative, 0, lambda view: b"", "neg.glb")
    sparse = {"accessors": [{"componentType": 5126, "type": "SCALAR", "count": 4,
                             "sparse": {"count": 9, "indices": {"componentType": 5125}, "values": {}}}]}  # fmt: skip
    with pytest.raises(GlbError, match=r"sparse\.glb accessor 0=9 .*a sparse count 0\.\.4"):
        read_accessor(sparse, 0, lambda view: b"", "sparse.glb")


def test_text_readers_check_rows_times_columns() -> None:
    csv = b"time_s,a,b\n" + b"".join(b"%d,1,2\n" % i for i in range(100))
    with decode_limits(clip_values=299):
        with pytest.raises(InvalidValueError, match=r"take\.csv size.*300 values \(rows x columns\)"):
            curves_csv.read(_stream(csv, "take.csv"))
    with decode_limits(clip_values=300):
        assert curves_csv.read(_stream(csv, "take.csv")).values.shape == (100, 2)
    openface = b"frame, timestamp, AU12_r\n" + b"".join(b"%d, %f, 1.0\n" % (i + 1, i / 30) for i in range(100))
    with decode_limits(clip_values=1000):  # 300 cells in the file, but 100 x 62 channels in the clip
        with pytest.raises(InvalidValueError, match=r"of\.csv size.*6200 values \(frames x channels\)"):
            openface_csv.read(_stream(openface, "of.csv"))
    lines = b"".join(json.dumps({"time_s": i / 30, "AU12": 1}).encode() + b"\n" for i in range(100))
    with decode_limits(clip_values=1000):
        with pytest.raises(InvalidValueError, match=r"take\.jsonl size.*6200 values \(lines x channels\)"):
            openfacs_jsonl.read(_stream(lines, "take.jsonl"))
    clip = json.dumps({"fps": 30, "channels": ["a", "b"], "values": [[1, 2]] * 100}).encode()
    with decode_limits(clip_values=150):
        with pytest.raises(InvalidValueError, match=r"take\.json size.*commas"):
            clip_json.read(_stream(clip, "take.json"))
    assert openfacs_jsonl.read(_stream(lines, "take.jsonl")).n_frames == 100  # the default limits fit


def test_an_anim_header_cannot_ask_for_a_billion_frames() -> None:
    """``endTime 1000000000`` in a 330-byte ``.anim`` asked for 10^9 frames (8 GB) before the check."""
    text = (
        b"animVersion 1.1;\nmayaVersion 2020;\ntimeUnit film;\nlinearUnit cm;\nangularUnit deg;\nstartTime 0;\n"
        b"endTime 1000000000;\nanim w w mien 0 0 0;\nanimData {\n  input time;\n  output unitless;\n  weighted 0;\n"
        b"  preInfinity constant;\n  postInfinity constant;\n  keys {\n    0 0 linear linear 1 1 0;\n"
        b"    1000000000 1 linear linear 1 1 0;\n  }\n}\n"
    )
    with pytest.raises(InvalidValueError, match=r"anim size.*1000000001 values \(frames x curves\)"):
        maya_anim.read(_stream(text, "bomb.anim"))
    small = text.replace(b"1000000000", b"48")
    assert maya_anim.read(_stream(small, "ok.anim")).n_frames == 49
