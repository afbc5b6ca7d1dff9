"""Issue 29 case 7 (the serve part): ``mien serve`` stops cleanly on SIGINT even when it was started with SIGINT
ignored (a background job of a script), and on SIGTERM, and gives its UDP port back (a real child process on
127.0.0.1, bounded waits)."""

from __future__ import annotations

import re
import signal
import socket
import subprocess
import sys
import time

import pytest

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")


def _start(ignore_sigint: bool) -> tuple[subprocess.Popen[str], int]:
    ignore = "signal.signal(signal.SIGINT, signal.SIG_IGN); " if ignore_sigint else ""  # as a script's `&` job
    code = (
        f"import runpy, signal, sys; {ignore}sys.argv = ['mien', 'serve', '--udp-port', '0', '--http-port', '0', "
        "'--head', 'builtin']; runpy.run_module('mien.cli', run_name='__main__')"
    )
    process = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert process.stdout is not None
    deadline = time.monotonic() + 60.0
    udp_port = 0
    while time.monotonic() < deadline:
        line = process.stdout.readline()
        if not line:
            break
        if match := re.search(r"UDP on 127\.0\.0\.1:(\d+)", line):
            udp_port = int(match.group(1))
        if "stops" in line:
            return process, udp_port
    process.kill()
    process.communicate(timeout=10.0)
    pytest.fail("mien serve did not start")


def _port_is_free(port: int) -> bool:
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        sock.bind(("127.0.0.1", port))
        return True
    except OSError:
        return False
    finally:
        sock.close()


@pytest.mark.parametrize(
    ("ignore_sigint", "signum", "code", "words"),
    [
        (True, signal.SIGINT, 130, "interrupted"),
        (False, signal.SIGINT, 130, "interrupted"),
        (False, signal.SIGTERM, 0, "stopped (SIGTERM)"),
        (True, signal.SIGTERM, 0, "stopped (SIGTERM)"),
    ],
)
def test_serve_stops_cleanly_on_a_signal_and_frees_its_port(ignore_sigint, signum, code, words) -> None:
    process, udp_port = _start(ignore_sigint)
    try:
        assert udp_port and not _port_is_free(udp_port)
        process.send_signal(signum)
        _, err = process.communicate(timeout=20.0)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate(timeout=10.0)
    assert process.returncode == code, err
    assert words in err and "Traceback" not in err
    assert _port_is_free(udp_port)
