"""Issue 29, cases 4 and 5: what a web page, a hostile client or a clumsy one may send the live server.

Case 4: a page from another site (``Origin: http://evil.example``), a DNS-rebound name (``Host: evil.example``)
or a cross-site ``text/plain`` POST must not reach a handler. Case 5: every JSON endpoint has a small body limit
enforced while the body streams, a time limit, no unknown fields, no NaN; ``"Speed": null`` over UDP is refused.
"""

from __future__ import annotations

import asyncio
import json
import socket
import time

import httpx
import pytest
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from mien.server.guard import MAX_JSON_BYTES, BodyTooLarge, BodyTooSlow, access_policy, origin_of, read_body


def _raw(port: int, request: bytes, wait_s: float = 10.0) -> bytes:
    """Send ``request`` on a fresh connection; the answer, read until the server closes (at most 64 KiB)."""
    answer = b""
    with socket.create_connection(("127.0.0.1", port), timeout=wait_s) as sock:
        sock.sendall(request)
        while len(answer) < 65536 and (part := sock.recv(4096)):
            answer += part
    return answer


# ---------------------------------------------------------------------------------------------------------------
# Case 4: Origin, Host, content types


def test_a_websocket_from_another_site_is_refused_and_its_commands_never_applied(live, au_value) -> None:
    url = f"ws://127.0.0.1:{live.http_port}/ws"
    with pytest.raises(InvalidStatus) as refused:
        with connect(url, origin="http://evil.example", open_timeout=5) as ws:  # type: ignore[arg-type]
            ws.send(json.dumps({"AU12": 5, "Speed": 1}))
    assert refused.value.response.status_code == 403
    assert au_value(live, "a", "AU12L") == 0.0
    with connect(url, origin=f"http://127.0.0.1:{live.http_port}", open_timeout=5) as ws:  # type: ignore[arg-type]
        assert isinstance(ws.recv(timeout=5), bytes)  # the viewer's own page is served


def test_a_host_that_is_not_the_server_is_refused(live) -> None:
    answer = _raw(
        live.http_port, b"GET /api/characters HTTP/1.1\r\nHost: evil.example:8000\r\nConnection: close\r\n\r\n"
    )
    assert answer.startswith(b"HTTP/1.1 403") and b"evil.example" in answer
    for host in (f"localhost:{live.http_port}", f"127.0.0.1:{live.http_port}", "127.0.0.1"):
        request = f"GET /api/characters HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n".encode()
        assert _raw(live.http_port, request).startswith(b"HTTP/1.1 200"), host
    with pytest.raises(InvalidStatus):
        with connect(f"ws://127.0.0.1:{live.http_port}/ws", additional_headers={"Host": "evil.example"}):
            pass


def test_cross_site_posts_never_reach_a_handler(live) -> None:
    base = live.base_url
    clip = json.dumps({"fps": 30.0, "channels": ["AU12L"], "values": [[4.0]] * 30}).encode()
    text_plain = httpx.post(
        f"{base}/api/characters/a/clip",
        params={"suffix": ".json"},
        content=clip,
        headers={"content-type": "text/plain"},
    )
    assert text_plain.status_code == 415 and "application/octet-stream" in text_plain.text
    form = httpx.post(f"{base}/api/characters/a/emotion", data={"emotion": "anger"})  # a form a page may send
    assert form.status_code == 415 and "application/json" in form.text
    missing = httpx.post(f"{base}/api/characters/a/emotion", content=b'{"emotion": "anger"}')
    assert missing.status_code == 415
    evil = httpx.post(
        f"{base}/api/characters/a/emotion", json={"emotion": "anger"}, headers={"origin": "http://evil.example"}
    )
    assert evil.status_code == 403 and "--allow-origin" in evil.text
    assert httpx.get(f"{base}/api/health").json()["http_commands"] == 0
    own = httpx.post(f"{base}/api/characters/a/emotion", json={"emotion": "joy"}, headers={"origin": base})
    assert own.status_code == 202


def test_an_allowed_origin_may_use_the_server(server_factory) -> None:
    with server_factory(allow_origins=("http://lab.example:3000",)) as live:
        url = f"ws://127.0.0.1:{live.http_port}/ws"
        with connect(url, origin="http://lab.example:3000", open_timeout=5) as ws:  # type: ignore[arg-type]
            assert isinstance(ws.recv(timeout=5), bytes)
        preflight = httpx.options(
            f"{live.base_url}/api/characters/a/emotion",
            headers={"origin": "http://lab.example:3000", "access-control-request-method": "POST",
                     "access-control-request-headers": "content-type"},
        )  # fmt: skip
        assert preflight.headers["access-control-allow-origin"] == "http://lab.example:3000"
        request = b"GET /api/health HTTP/1.1\r\nHost: lab.example:8000\r\nConnection: close\r\n\r\n"
        assert _raw(live.http_port, request).startswith(b"HTTP/1.1 200")  # its host name too
        with pytest.raises(InvalidStatus):
            with connect(url, origin="http://lab.example:4000", open_timeout=5):  # type: ignore[arg-type]
                pass


def test_access_policy_and_origins() -> None:
    loopback = access_policy("127.0.0.1")
    assert loopback.refusal({"host": "127.0.0.1:8000"}) is None
    assert loopback.refusal({"host": "[::1]:8000", "origin": "http://[::1]:8000"}) is None
    assert "Host 'rebind.example:8000'" in (loopback.refusal({"host": "rebind.example:8000"}) or "")
    assert "Origin 'null'" in (loopback.refusal({"host": "127.0.0.1:8000", "origin": "null"}) or "")
    wide = access_policy("0.0.0.0")  # beyond loopback the token guards it; any name may reach it
    assert wide.refusal({"host": "lab-pc.local:8000", "origin": "http://lab-pc.local:8000"}) is None
    assert wide.refusal({"host": "lab-pc.local:8000", "origin": "http://evil.example"}) is not None
    assert origin_of("HTTPS://Lab.Example:443/x") == "https://lab.example:443"
    from mien.errors import InvalidValueError
    from mien.server.app import ServeConfig

    with pytest.raises(InvalidValueError, match="ftp://x"):
        ServeConfig(allow_origins=("ftp://x",))


# ---------------------------------------------------------------------------------------------------------------
# Case 5: body limits and time, unknown fields, NaN


def test_a_claimed_huge_body_is_answered_at_once(live) -> None:
    request = (
        b"POST /api/characters/a/emotion HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
        b"Content-Length: 1000000000000\r\n\r\n{"
    )
    answer = _raw(live.http_port, request)  # before: no answer, ever
    assert answer.startswith(b"HTTP/1.1 413") and b"1000000000000" in answer and str(MAX_JSON_BYTES).encode() in answer


def test_a_chunked_json_body_is_cut_off_at_its_limit(live) -> None:
    """A chunked body gets 413 once it passes the limit, long before the client has sent it all."""
    head = (
        b"POST /api/characters/a/emotion HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
        b"Transfer-Encoding: chunked\r\n\r\n"
    )
    chunk = b"x" * 65536
    sent = 0
    answer = b""
    with socket.create_connection(("127.0.0.1", live.http_port), timeout=10) as sock:
        sock.sendall(head)
        sock.setblocking(False)
        for _ in range(3200):  # up to 200 MiB, as in the issue
            try:
                answer = sock.recv(4096)
                if answer:
                    break
            except BlockingIOError:
                pass
            try:
                sock.sendall(b"%x\r\n%s\r\n" % (len(chunk), chunk))
                sent += len(chunk)
            except BlockingIOError:
                time.sleep(0.01)
            except OSError:  # the server closed after answering
                break
        sock.setblocking(True)
        sock.settimeout(10)
        answer = answer or sock.recv(4096)
    assert answer.startswith(b"HTTP/1.1 413")
    assert sent < 64 * 2**20  # the server stopped reading; before, all 200 MiB were read, then 202


def test_unknown_fields_and_nan_are_refused_by_name(live) -> None:
    base = live.base_url
    junk = httpx.post(f"{base}/api/characters/a/emotion", json={"emotion": "joy", "junk": "x" * 1000})
    assert junk.status_code == 422 and "junk" in junk.text and "Extra inputs are not permitted" in junk.text
    big = httpx.post(f"{base}/api/characters/a/emotion", json={"emotion": "joy", "junk": "x" * (1 << 20)})
    assert big.status_code == 413
    headers = {"content-type": "application/json"}
    nan = httpx.post(
        f"{base}/api/characters/a/emotion", content=b'{"emotion": "joy", "intensity": NaN}', headers=headers
    )
    assert nan.status_code == 422 and "intensity" in nan.text and "finite number" in nan.text
    inf = httpx.post(f"{base}/api/characters/a/aus", content=b'{"aus": {"AU12": Infinity}}', headers=headers)
    assert inf.status_code == 422 and "AU12" in inf.text and "finite number" in inf.text
    extra = httpx.post(f"{base}/api/characters", json={"id": "c", "head": "builtin", "colour": "blue"})
    assert extra.status_code == 422 and "colour" in extra.text
    assert httpx.get(f"{base}/api/health").json()["http_commands"] == 0
    assert [c["id"] for c in httpx.get(f"{base}/api/characters").json()] == ["a", "b"]


def test_read_body_stops_at_the_limit_and_the_deadline() -> None:
    async def never() -> dict[str, object]:
        await asyncio.sleep(3600)
        return {}

    async def endless() -> dict[str, object]:
        return {"type": "http.request", "body": b"x" * 1000, "more_body": True}

    with pytest.raises(BodyTooSlow, match=r"0\.05 s"):
        asyncio.run(read_body(never, 100, 0.05))
    with pytest.raises(BodyTooLarge, match="more than 5000"):
        asyncio.run(read_body(endless, 5000, 5.0))
    with pytest.raises(BodyTooLarge, match="10 bytes"):
        asyncio.run(read_body(never, 5, 5.0, declared=10))


def test_speed_null_over_udp_is_refused_and_counted(live, au_value, wait_until) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.sendto(b'{"AU12": 4, "Speed": 1}', ("127.0.0.1", live.udp_port))
        wait_until(lambda: au_value(live, "a", "AU12L") == 4.0, what="AU12 at 4")
        sock.sendto(b'{"AU12": 1, "Speed": null}', ("127.0.0.1", live.udp_port))  # before: AU12 went to 1
        sock.sendto(b'{"AU12": 1, "character": null}', ("127.0.0.1", live.udp_port))
        health = wait_until(lambda: (h := httpx.get(f"{live.base_url}/api/health").json())["rejections"] and h)
    wait_until(lambda: httpx.get(f"{live.base_url}/api/health").json()["rejections"].get("wrong_type") == 2)
    assert au_value(live, "a", "AU12L") == 4.0  # the face kept its last good state
    assert set(health["rejections"]) == {"wrong_type"}
