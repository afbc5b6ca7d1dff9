"""The live server's access token without ``ps`` seeing it (issue 29, case 9): ``--token-file FILE`` and
``$MIEN_TOKEN`` beside ``--token`` on ``serve`` and ``send``; a bad file is a usage error naming the file."""

from __future__ import annotations

from pathlib import Path

import pytest

from mien.cli import build_parser, main
from mien.commands._vocabulary import TOKEN_ENV, finish


def token_of(argv: list[str]) -> str | None:
    args = build_parser().parse_args(argv)
    finish(args)
    return args.token


@pytest.mark.parametrize("command", [["serve"], ["send", "--emotion", "joy", "--ws"]])
def test_token_from_option_file_or_environment(
    command: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv(TOKEN_ENV, raising=False)
    secret = tmp_path / "token.txt"
    secret.write_text("from-the-file-123\n")
    assert token_of(command) is None
    assert token_of([*command, "--token-file", str(secret)]) == "from-the-file-123"
    monkeypatch.setenv(TOKEN_ENV, "from-the-environment")
    assert token_of(command) == "from-the-environment"
    assert token_of([*command, "--token-file", str(secret)]) == "from-the-file-123"  # an option wins
    assert token_of([*command, "--token", "on-the-command-line"]) == "on-the-command-line"


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        (["--token-file", "{d}/missing.txt"], "missing.txt: cannot be read"),
        (["--token-file", "{d}/empty.txt"], "empty.txt is empty"),
        (["--token-file", "{d}/empty.txt", "--token", "abcdefgh12"], "not both"),
    ],
)
def test_bad_token_sources_exit_2_naming_the_file(
    extra: list[str], words: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "empty.txt").write_text(" \n")
    argv = ["serve", "--check", *(part.replace("{d}", str(tmp_path)) for part in extra)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert words in err and "abcdefgh12" not in err and "Traceback" not in err


def test_serve_uses_the_token_from_the_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    secret = tmp_path / "token.txt"
    secret.write_text("a-token-from-a-file\n")
    argv = ["serve", "--check", "--head", "builtin", "--udp-port", "0", "--http-port", "0", "--token-file", str(secret)]
    assert main(argv) == 0
    assert "/ws?token=a-token-from-a-file" in capsys.readouterr().out
