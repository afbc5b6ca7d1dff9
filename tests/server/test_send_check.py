"""Issue 29, case 7: ``mien send`` over UDP cannot know whether the server took the message; it says so, and
``--check`` asks the server over HTTP (exit 2 with the reason when the character does not exist or the server
refused the message)."""

from __future__ import annotations

import pytest

from mien.cli import main
from mien.client import HttpClient
from mien.errors import MienError
from mien.ports import free_port


def test_a_plain_udp_send_says_it_cannot_confirm(live, capsys) -> None:
    assert main(["send", "--au", "AU12=3", "--character", "nobody", "--udp-port", str(live.udp_port)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("sent") and "UDP has no reply" in out and "--check" in out


def test_check_refuses_a_character_the_server_lacks(live, capsys) -> None:
    ports = ["--udp-port", str(live.udp_port), "--http-port", str(live.http_port)]
    assert main(["send", "--au", "AU12=3", "--character", "nobody", "--check", *ports]) == 2
    err = capsys.readouterr().err
    assert "--character='nobody'" in err and "a, b" in err and "Traceback" not in err
    assert HttpClient(live.base_url).health()["datagrams_received"] == 0  # nothing was sent


def test_check_confirms_delivery(live, au_value, wait_until, capsys) -> None:
    ports = ["--udp-port", str(live.udp_port), "--http-port", str(live.http_port)]
    assert main(["send", "--au", "AU12=3", "--speed", "1", "--character", "b", "--check", *ports]) == 0
    assert "the server accepted it" in capsys.readouterr().out
    wait_until(lambda: au_value(live, "b", "AU12L") == 3.0, what="AU12 on b")


def test_check_says_when_nothing_arrived_or_no_server_answers(live, capsys) -> None:
    wrong_udp = ["--udp-port", str(free_port()), "--http-port", str(live.http_port)]
    assert main(["send", "--emotion", "joy", "--check", *wrong_udp]) == 2
    assert "received nothing" in capsys.readouterr().err
    assert main(["send", "--emotion", "joy", "--check", "--http-port", str(free_port())]) == 2
    assert "cannot reach" in capsys.readouterr().err


def test_http_client(live) -> None:
    client = HttpClient(live.base_url)
    assert client.characters() == ["a", "b"]
    assert client.character("a")["aus"]["AU12L"] == 0.0
    with pytest.raises(MienError, match="404"):
        client.character("nobody")
