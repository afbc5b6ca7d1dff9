"""The ``mien`` command: one entry point, one subcommand per job (see :mod:`mien.commands`)."""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import warnings
from collections.abc import Callable, Sequence
from typing import NoReturn

from mien.commands import COMMAND_MODULES
from mien.commands._checks import PENDING_OUTPUTS, prepare_outputs
from mien.commands._vocabulary import PENDING_DEPRECATIONS, finish
from mien.errors import MienError
from mien.signals import termination_as_interrupt
from mien.version import __version__

__all__ = ["UsageError", "build_parser", "main"]


class UsageError(Exception):
    """An argparse usage error, raised instead of printing usage and exiting (see :class:`_Parser`)."""

    def __init__(self, prog: str, message: str) -> None:
        self.prog = prog
        super().__init__(message)


class _Parser(argparse.ArgumentParser):
    """argparse with the CLI contract's error form: one line ``PROG: error: MESSAGE (see PROG --help)``,
    exit 2, for usage errors as for every other user mistake. Subparsers inherit the class."""

    def error(self, message: str) -> NoReturn:
        raise UsageError(self.prog, message)


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser, with every subcommand registered."""
    parser = _Parser(
        prog="mien",
        description="Make virtual characters' faces express emotion (FACS, emotions, laughter).",
    )
    parser.add_argument("--version", action="version", version=f"mien {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(f"mien.commands.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"mien.commands.{name}":
                continue  # a subcommand not built yet
            raise
        module.register(subparsers)
    return parser


def _one_line(message: object) -> str:
    """The contract's one-line message (a multi-line error joined with '; ')."""
    return "; ".join(line.strip() for line in str(message).splitlines() if line.strip())


def _warning_line(command: str) -> Callable[..., str]:
    """A :func:`warnings.formatwarning` that writes ``mien COMMAND: warning: MESSAGE`` on one line: what a library
    warns of while a command runs (a head that lacks a shape, a texture it cannot decode) reads as the commands'
    own warnings do, with no source path or code line. Recorded warnings (``catch_warnings(record=True)``) are not
    formatted, so a caller that collects them still gets them whole."""

    def line(
        message: Warning | str, category: type[Warning], filename: str, lineno: int, text: str | None = None
    ) -> str:
        return f"mien {command}: warning: {_one_line(message)}\n"

    return line


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``mien`` with ``argv`` (default: ``sys.argv[1:]``) and return the exit code."""
    parser = build_parser()
    PENDING_OUTPUTS.clear()
    PENDING_DEPRECATIONS.clear()
    try:
        args = parser.parse_args(argv)
        finish(args)  # old spellings translated, conflicts between old and new spellings refused
    except UsageError as exc:
        PENDING_OUTPUTS.clear()
        PENDING_DEPRECATIONS.clear()  # the error is what matters: one line
        print(f"{exc.prog}: error: {_one_line(exc)} (see {exc.prog} --help)", file=sys.stderr)
        return 2
    for note in PENDING_DEPRECATIONS:
        print(f"mien {args.command}: {note}", file=sys.stderr)
    PENDING_DEPRECATIONS.clear()
    if getattr(args, "handler", None) is None:
        parser.print_help()
        return 0
    formatwarning = warnings.formatwarning
    warnings.formatwarning = _warning_line(args.command)
    try:
        prepare_outputs()  # the missing output folders, made once every argument is known to be good
        with termination_as_interrupt():  # SIGTERM / SIGHUP clean up as Ctrl-C does, in every command
            code = int(args.handler(args) or 0)
        sys.stdout.flush()  # a reader that went away is met here, not in the interpreter's last flush
        return code
    except MienError as exc:
        print(f"mien {args.command}: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # The reader went away (`mien ... | head -1`); files already written stay. Silence the final flush.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        print(f"mien {args.command}: error: output pipe closed; files already written are kept", file=sys.stderr)
        return 2
    except MemoryError:
        print(
            f"mien {args.command}: error: out of memory; ask for less (shorter, lower fps, smaller size)",
            file=sys.stderr,
        )
        return 2
    except OSError as exc:
        # A file system refusal met while writing (disk full, a path that vanished): name the path.
        where = f": {exc.filename}" if exc.filename else ""
        print(f"mien {args.command}: error: {exc.strerror or exc}{where}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    finally:
        warnings.formatwarning = formatwarning


if __name__ == "__main__":
    sys.exit(main())
