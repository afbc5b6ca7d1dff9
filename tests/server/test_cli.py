"""``mien send`` end to end against a live server, and ``mien serve`` refusing bad options (exit 2)."""

from __future__ import annotations

import subprocess
import sys

import pytest

from mien.cli import main


def test_send_over_udp_and_websocket(live, au_value, wait_until, capsys) -> None:
    assert main(["send", "--au", "AU12=3", "--au", "AU6L=1.5", "--speed", "1", "--udp-port", str(live.udp_port)]) == 0
    assert "sent" in capsys.readouterr().out
    wait_until(lambda: au_value(live, "a", "AU12L") == 3.0, what="AU12 from mien send")
    assert au_value(live, "a", "AU6L") == 1.5 and au_value(live, "a", "AU6R") == 0.0
    argv = ["send", "--emotion", "sadness", "--intensity", "1.2", "--character", "b", "--udp-port", str(live.udp_port)]
    assert main(argv) == 0
    wait_until(lambda: au_value(live, "b", "AU15L") > 0.5, what="sadness on b")
    argv = ["send", "--ws", "--http-port", str(live.http_port), "--character", "b", "--au", "AU26=2", "--speed", "1"]
    assert main(argv) == 0
    assert "frame tick" in capsys.readouterr().out
    wait_until(lambda: au_value(live, "b", "AU26") == 2.0, what="AU26 over the WebSocket")


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["send", "--au", "AU12"], "AU=INTENSITY"),
        (["send", "--au", "AU12=8"], "AU12=8 is outside 0..5"),
        (["send", "--au", "AU99=1"], "AU99"),
        (["send", "--emotion", "bliss"], "bliss"),
        (["send", "--laugh", "guffaw"], "guffaw"),
        (["send", "--pad", "2", "0", "0"], "pad[0]=2.0"),
        (["send"], "at least one of"),
        (["send", "--emotion", "joy", "--udp-port", "0"], "--udp-port=0"),
        (["send", "--emotion", "joy", "--ws", "--http-port", "70000"], "--http-port=70000"),
        (["send", "--emotion", "joy", "--ws", "--udp-port", "5000"], "the WebSocket is on --http-port"),
        (["send", "--emotion", "joy", "--http-port", "8000"], "--ws as well"),
        (["send", "--emotion", "joy", "--port", "5001", "--udp-port", "5002"], "give --udp-port only"),
        (["serve", "--head", "builtin:b", "--identity", "c"], "--identity 'c'"),
        (["serve", "--udp-port", "70000"], "--udp-port=70000"),
        (["serve", "--tick-hz", "0"], "--tick-hz=0.0"),
        (["serve", "--head", "marble"], "unknown head 'marble'"),
        (["serve", "--udp-port", "5999", "--http-port", "5999"], "--http-port"),
        (["serve", "--token", "short"], "token"),
    ],
)
def test_bad_options_exit_2_with_a_message(argv, words, capsys) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err


def test_serve_on_a_busy_port_exits_2(live, capsys) -> None:
    assert main(["serve", "--udp-port", str(live.udp_port), "--http-port", "0", "--head", "builtin"]) == 2
    assert "--udp-port" in capsys.readouterr().err


def test_serve_check_runs_and_stops() -> None:
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "mien.cli",
            "serve",
            "--udp-port",
            "0",
            "--http-port",
            "0",
            "--head",
            "builtin",
            "--check",
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    assert "OpenFACS UDP on 127.0.0.1:" in result.stdout and "ws://127.0.0.1:" in result.stdout
