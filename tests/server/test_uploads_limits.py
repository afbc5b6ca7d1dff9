"""Issue 29, case 3: clip uploads are read off the event loop (a worker process with a time limit), their body is
cut off while it streams, and what a file may decode to is checked before anything is allocated."""

from __future__ import annotations

import asyncio
import io
import socket

import httpx
import numpy as np
import pytest

from mien.errors import InvalidValueError, MienError
from mien.exchange.clip_npz import write as write_npz
from mien.facs.catalogue import FACE_CHANNELS
from mien.facs.clip import Clip
from mien.fileio.glb import pack_glb
from mien.server.uploads import MAX_CLIP_BYTES, UPLOAD_LIMITS, Uploads, parse_in_worker

BINARY = {"content-type": "application/octet-stream"}


def _csv(rows: int) -> bytes:
    """A curves CSV of ``rows`` frames of the 62 face channels."""
    values = np.random.default_rng(0).uniform(0, 5, (rows, len(FACE_CHANNELS))).round(3)
    text = io.StringIO()
    text.write(",".join(("time_s", *FACE_CHANNELS)) + "\n")
    times = np.arange(rows) / 60.0
    np.savetxt(text, np.column_stack([times, values]), fmt=["%.6f"] + ["%.3g"] * len(FACE_CHANNELS), delimiter=",")
    return text.getvalue().encode()


def _npz_bomb() -> bytes:
    """An ``.npz`` of zeros, a few dozen KB, whose values unpack past the upload limit (1 GiB in the issue)."""
    frames = UPLOAD_LIMITS["clip_values"] // len(FACE_CHANNELS) + 1000
    buffer = io.BytesIO()
    write_npz(Clip(np.zeros((frames, len(FACE_CHANNELS))), 60.0, FACE_CHANNELS), buffer)
    return buffer.getvalue()


def _glb_bomb() -> bytes:
    """A few hundred bytes of ``.glb`` whose animation accessors claim 10^8 keys and have no buffer at all."""
    document = {
        "asset": {"version": "2.0"},
        "meshes": [{"primitives": [{"attributes": {}, "targets": [{}]}]}],
        "nodes": [{"mesh": 0}],
        "accessors": [{"componentType": 5126, "type": "SCALAR", "count": 100_000_000}] * 2,
        "animations": [{"channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
                        "samplers": [{"input": 0, "output": 1}]}],
    }  # fmt: skip
    return pack_glb(document)


def test_decode_bombs_are_refused_before_they_unpack(live) -> None:
    url = f"{live.base_url}/api/characters/a/clip"
    bomb = _npz_bomb()
    assert len(bomb) < 200_000
    npz = httpx.post(url, params={"suffix": ".npz"}, content=bomb, headers=BINARY, timeout=60)
    assert npz.status_code == 400 and "decode limit" in npz.text and str(UPLOAD_LIMITS["clip_values"]) in npz.text
    glb = _glb_bomb()
    assert len(glb) < 500
    answer = httpx.post(url, params={"suffix": ".glb"}, content=glb, headers=BINARY, timeout=60)
    assert answer.status_code == 400 and "accessor 0" in answer.text and "100000000" in answer.text
    registry = live.server.registry
    assert live.call(lambda: len(registry.get("a").clips)) == 0  # nothing queued
    assert httpx.get(f"{live.base_url}/api/health").json()["http_commands"] == 0


def test_a_clip_that_fits_plays_and_a_chunked_body_is_cut_off_at_the_limit(live, wait_until) -> None:
    url = f"{live.base_url}/api/characters/b/clip"
    good = httpx.post(url, params={"suffix": ".csv"}, content=_csv(120), headers=BINARY, timeout=60)
    assert good.status_code == 202
    head = (
        b"POST /api/characters/b/clip?suffix=.csv HTTP/1.1\r\nHost: 127.0.0.1\r\n"
        b"Content-Type: application/octet-stream\r\nTransfer-Encoding: chunked\r\n\r\n"
    )
    chunk = b"0" * 2**20
    sent = 0
    answer = b""
    with socket.create_connection(("127.0.0.1", live.http_port), timeout=10) as sock:
        sock.sendall(head)
        sock.settimeout(0.05)
        for _ in range(300):  # up to 300 MiB, as in the issue
            try:
                answer = sock.recv(4096)
                break
            except TimeoutError:
                pass
            try:
                sock.sendall(b"%x\r\n%s\r\n" % (len(chunk), chunk))
                sent += len(chunk)
            except TimeoutError:
                pass
            except OSError:  # closed after the answer
                break
        sock.settimeout(10)
        answer = answer or sock.recv(4096)
    assert answer.startswith(b"HTTP/1.1 413")  # the body may be lost to the reset of a connection closed unread
    assert sent < MAX_CLIP_BYTES + 32 * 2**20  # before: all 300 MiB were read into memory, then 413


def test_the_clock_runs_while_a_big_clip_is_read() -> None:
    """The worker reads a 5 MB CSV while a coroutine on the same loop keeps ticking (before: the loop stopped)."""
    data = _csv(12_000)

    async def run() -> tuple[int, Clip]:
        ticks = 0
        done = False

        async def ticker() -> None:
            nonlocal ticks
            while not done:
                await asyncio.sleep(0.01)
                ticks += 1

        task = asyncio.create_task(ticker())
        await asyncio.sleep(0)
        clip = await Uploads().read(data, ".csv")
        done = True
        await task
        return ticks, clip

    ticks, clip = asyncio.run(run())
    assert clip.values.shape == (12_000, len(FACE_CHANNELS)) and clip.channels == FACE_CHANNELS
    assert ticks > 10  # the read takes a worker's start-up and seconds of parsing; the loop ticked all along


def test_the_worker_has_a_time_limit_and_a_memory_limit() -> None:
    with pytest.raises(InvalidValueError, match=r"reads in 0\.05 s"):
        asyncio.run(parse_in_worker(_csv(100), ".csv", timeout_s=0.05))  # killed before it has even started
    limits = dict(UPLOAD_LIMITS, clip_values=2**40, zip_bytes=2**40)  # no decode limit: only memory stops it
    with pytest.raises(MienError, match="MiB"):
        asyncio.run(parse_in_worker(_npz_bomb(), ".npz", limits=limits, memory_bytes=16 * 2**20))


def test_too_many_uploads_at_once_get_503() -> None:
    uploads = Uploads(parallel=1)
    with uploads.slot():
        with pytest.raises(MienError, match="retry"):
            with uploads.slot():
                pass
    with uploads.slot():
        assert uploads.active == 1
    assert uploads.active == 0
