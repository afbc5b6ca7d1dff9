"""The one vocabulary every ``mien`` subcommand speaks (README "CLI vocabulary"), and its deprecated spellings.

* **Output**: ``-o/--output PATH`` names a command's main output, file or folder (:func:`add_output`). Extra
  outputs keep their own names (``--plot PNG``, ``--report-dir DIR``).
* **Head**: ``--head HEAD[:IDENTITY]`` (:func:`add_head`, :func:`head_spec`); the identity part is optional.
* **Models**: ``--landmarker PATH`` (MediaPipe Face Landmarker) and ``--emotion-model PATH`` (the FER
  classifier) (:func:`add_landmarker`, :func:`add_emotion_model`).
* **Ports**: ``--udp-port`` (OpenFACS UDP) and ``--http-port`` (HTTP and WebSocket), in ``serve``, ``send`` and
  ``study serve`` alike.
* **Basis**: ``facs`` or ``feature_points``, spelled as in Python and TOML (:func:`basis_name`).
* **Frame rate**: :data:`ANIMATION_FPS` for animation data, :data:`VIDEO_FPS` for video.
* **Progress**: ``--quiet`` on every command that shows progress (:func:`add_quiet`).
* **Processes**: ``--workers N`` where work is split over processes (:func:`add_workers`; ``track``, ``capture``).
* **Access token**: ``--token``, ``--token-file FILE`` or ``$MIEN_TOKEN`` (:func:`add_token`).

An old spelling keeps working until :data:`REMOVED_IN` (:func:`add_deprecated_alias`,
:func:`add_deprecated_option`, ``add_output(positional=True)``): it is noted while parsing, and ``mien.cli``
prints one ``warning: OLD is deprecated, use NEW; it will be removed in 0.2`` line on stderr per old spelling
once every argument has parsed (a usage error prints only the error). Finishing steps that need every
argument (the deprecated positional output, ``--identity``) are registered on the parser as ``_finish_*``
defaults and run by :func:`finish`.
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

__all__ = [
    "ANIMATION_FPS",
    "BASES",
    "PENDING_DEPRECATIONS",
    "REMOVED_IN",
    "TOKEN_ENV",
    "VIDEO_FPS",
    "add_deprecated_alias",
    "add_deprecated_option",
    "add_emotion_model",
    "add_head",
    "add_landmarker",
    "add_output",
    "add_quiet",
    "add_token",
    "add_workers",
    "basis_list",
    "basis_name",
    "deprecated",
    "finish",
    "head_list",
    "head_spec",
    "worker_count",
]

REMOVED_IN = "0.2"
"""The release that drops the deprecated spellings."""

ANIMATION_FPS = 60.0
"""Default frame rate of animation data (AU curves, clips, laughs; the live server's clock), frames per second."""

VIDEO_FPS = 30.0
"""Default frame rate of video (``demo``, ``render``; a study design's stimuli), frames per second."""

BASES = ("facs", "feature_points")
"""Expression bases, spelled as ``Character(expression_basis=...)`` and a study design's ``bases``."""

_OLD_BASES = {"feature-points": "feature_points"}
"""Deprecated CLI spellings of :data:`BASES`."""

PENDING_DEPRECATIONS: list[str] = []
"""Deprecation notes of the arguments parsed so far (``mien.cli`` prints them once parsing succeeded)."""

_PRIVATE = ("_deprecated_", "_finish_")
"""Prefixes of the namespace entries this module adds; :func:`finish` removes them."""


def deprecated(old: str, new: str) -> None:
    """Note that the spelling ``old`` was used where ``new`` is the word now (printed after parsing)."""
    note = f"warning: {old} is deprecated, use {new}; it will be removed in {REMOVED_IN}"
    if note not in PENDING_DEPRECATIONS:
        PENDING_DEPRECATIONS.append(note)


def finish(args: argparse.Namespace) -> None:
    """Run the ``_finish_*`` steps registered on the parsed subcommand, then drop this module's private entries.

    A step calls its parser's ``error`` for a conflict (an old and a new spelling naming different values).
    """
    steps = [value for name, value in sorted(vars(args).items()) if name.startswith("_finish_")]
    for step in steps:
        step(args)
    for name in [name for name in vars(args) if name.startswith(_PRIVATE)]:
        delattr(args, name)


# ------------------------------------------------------------------------------------------------ aliases


class _DeprecatedAlias(argparse.Action):
    """An old spelling of ``canonical``: the same value in the same place, with a deprecation note."""

    def __init__(self, option_strings: Sequence[str], dest: str, canonical: argparse.Action, new: str) -> None:
        super().__init__(
            option_strings,
            dest=canonical.dest,
            nargs=canonical.nargs,
            type=canonical.type,  # type: ignore[arg-type]  # typeshed allows a str here
            choices=canonical.choices,
            default=argparse.SUPPRESS,
            help=argparse.SUPPRESS,
            metavar=canonical.metavar,
        )
        self.canonical = canonical
        self.new = new

    def __call__(
        self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: Any, option: str | None = None
    ) -> None:
        deprecated(option or self.option_strings[0], self.new)
        self.canonical(parser, namespace, values, self.canonical.option_strings[-1])


class _DeprecatedOption(argparse._StoreAction):
    """An old option whose meaning a ``_finish_*`` step translates: stored under ``_deprecated_*``, noted."""

    def __init__(self, option_strings: Sequence[str], dest: str, new: str, **kwargs: Any) -> None:
        super().__init__(option_strings, dest, **kwargs)
        self.new = new

    def __call__(
        self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: Any, option: str | None = None
    ) -> None:
        deprecated(option or self.option_strings[0], self.new)
        super().__call__(parser, namespace, values, option)


def add_deprecated_alias(parser: argparse.ArgumentParser, old: str, canonical: argparse.Action) -> None:
    """Let ``old`` (hidden from ``--help``) spell the option ``canonical`` until :data:`REMOVED_IN`."""
    parser.add_argument(old, action=_DeprecatedAlias, canonical=canonical, new="/".join(canonical.option_strings))


def add_deprecated_option(parser: argparse.ArgumentParser, old: str, new: str, **kwargs: Any) -> str:
    """Add the hidden option ``old``, stored under ``_deprecated_<name>`` (returned) for a ``_finish_*`` step to
    translate; ``new`` is what the deprecation note tells the user to write instead."""
    dest = "_deprecated_" + old.lstrip("-").replace("-", "_")
    parser.add_argument(old, action=_DeprecatedOption, dest=dest, new=new, default=None, help=argparse.SUPPRESS,
                        **kwargs)  # fmt: skip
    return dest


# ------------------------------------------------------------------------------------------------ output


def add_output(
    parser: argparse.ArgumentParser,
    *,
    type: Callable[[str], Any],
    help: str,
    default: Any = None,
    metavar: str | None = None,
    dest: str = "output",
    required: bool = False,
    old: Sequence[str] = (),
    positional: bool = False,
) -> argparse.Action:
    """Add ``-o/--output``: the command's main output, a file or a folder (``type`` checks which).

    ``old``: deprecated option spellings (``--out``, ``--dest``...). ``positional``: the output may also come,
    deprecated, as a last positional argument (``mien export IN OUT``); then ``required`` is checked after
    parsing, when both spellings are known.
    """
    action = parser.add_argument(
        "-o", "--output", type=type, default=default, metavar=metavar, dest=dest, help=help,
        required=required and not positional,
    )  # fmt: skip
    for spelling in old:
        add_deprecated_alias(parser, spelling, action)
    if positional:
        legacy = "_deprecated_positional_output"
        parser.add_argument(legacy, nargs="?", type=type, default=None, help=argparse.SUPPRESS)

        def take_positional(args: argparse.Namespace) -> None:
            value = getattr(args, legacy)
            if value is not None:
                if getattr(args, dest) is not None:
                    parser.error(f"the output is given twice ({value} and -o {getattr(args, dest)}): keep -o only")
                deprecated(f"the positional output ({value})", "-o/--output")
                setattr(args, dest, value)
            if required and getattr(args, dest) is None:
                parser.error("the following arguments are required: -o/--output")

        parser.set_defaults(_finish_output=take_positional)
    return action


# ------------------------------------------------------------------------------------------------ head


def head_spec(text: str) -> tuple[str, str | None]:
    """argparse type: ``HEAD[:IDENTITY]`` -> ``(head, identity or None)``, as :func:`mien.heads.load_head`
    takes them; an unknown head is refused. A head file (``face.glb``, ``file:PATH``) stays one spec.

    >>> head_spec("builtin:b")
    ('builtin', 'b')
    """
    from mien.errors import MienError
    from mien.rig.heads import parse_head_spec

    spec = text.strip()
    try:
        head, identity = parse_head_spec(spec)
    except MienError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    if head == "file":
        return spec, None  # a path is its own name; load_head reads it from the spec
    if spec.endswith(":") or (identity is not None and ":" in identity):
        raise argparse.ArgumentTypeError(f"head {text!r}: give HEAD or HEAD:IDENTITY, e.g. builtin or ict:b")
    return head, identity


def head_list(text: str) -> str:
    """argparse type: comma-separated ``HEAD[:IDENTITY]`` specs, each checked by :func:`head_spec`; returns the
    text as given (``mien validate --head ict:a,builtin``)."""
    for item in text.split(","):
        head_spec(item)
    return text


class _Head(argparse.Action):
    """``--head HEAD[:IDENTITY]``: stores ``head`` and ``identity`` (None when the spec names none). Parsed here,
    not by ``type=``, which argparse would also apply to the default and so leave a tuple in ``head``."""

    def __call__(
        self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: Any, option: str | None = None
    ) -> None:
        try:
            namespace.head, namespace.identity = head_spec(str(values))
        except argparse.ArgumentTypeError as exc:
            raise argparse.ArgumentError(self, str(exc)) from None


def add_head(parser: argparse.ArgumentParser, *, default: str | None = "default", help: str) -> None:
    """Add ``--head HEAD[:IDENTITY]`` (sets ``args.head`` and ``args.identity``, None when not given) and the
    deprecated ``--identity ID``."""
    parser.add_argument("--head", action=_Head, default=default, metavar="HEAD[:IDENTITY]", help=help)
    parser.set_defaults(identity=None)
    old = add_deprecated_option(parser, "--identity", "--head HEAD:IDENTITY", metavar="ID")

    def take_identity(args: argparse.Namespace) -> None:
        identity = getattr(args, old)
        if identity is None:
            return
        if args.identity is not None and args.identity != identity:
            parser.error(f"--head names identity {args.identity!r} and --identity {identity!r}: give --head HEAD:ID")
        args.identity = identity

    parser.set_defaults(_finish_identity=take_identity)


# ------------------------------------------------------------------------------------------------ models


def add_landmarker(parser: argparse.ArgumentParser, *, type: Callable[[str], Any], old: Sequence[str] = ()) -> None:
    """Add ``--landmarker PATH``: the MediaPipe Face Landmarker model (``old``: deprecated spellings)."""
    action = parser.add_argument(
        "--landmarker",
        type=type,
        metavar="PATH",
        help="MediaPipe face_landmarker.task (default: $MIEN_FACE_LANDMARKER or the config file)",
    )
    for spelling in old:
        add_deprecated_alias(parser, spelling, action)


def add_emotion_model(parser: argparse.ArgumentParser, *, type: Callable[[str], Any]) -> None:
    """Add ``--emotion-model PATH``: the FER emotion classifier."""
    parser.add_argument(
        "--emotion-model",
        type=type,
        metavar="PATH",
        help="emotion classifier .tflite (default: $MIEN_EMOTION_MODEL or the config file)",
    )


# ------------------------------------------------------------------------------------------------ basis


def basis_name(text: str) -> str:
    """argparse type: an expression basis of :data:`BASES` (``feature-points`` is the deprecated spelling).

    >>> basis_name("feature_points")
    'feature_points'
    """
    name = text.strip()
    if name in _OLD_BASES:
        deprecated(f"--basis {name}", f"--basis {_OLD_BASES[name]}")
        return _OLD_BASES[name]
    if name not in BASES:
        raise argparse.ArgumentTypeError(f"unknown basis {text!r}: give one of {', '.join(BASES)}")
    return name


def basis_list(text: str) -> str:
    """argparse type: comma-separated bases, each as :func:`basis_name` -> the canonical comma-separated text.

    >>> basis_list("facs,feature_points")
    'facs,feature_points'
    """
    names = [basis_name(item) for item in text.split(",") if item.strip()]
    if not names:
        raise argparse.ArgumentTypeError(f"{text!r} names no basis: give one or more of {', '.join(BASES)}")
    return ",".join(names)


# ------------------------------------------------------------------------------------------------ progress


def add_quiet(parser: argparse.ArgumentParser) -> None:
    """Add ``--quiet``: no progress bars (bars show only on a terminal anyway)."""
    parser.add_argument("--quiet", action="store_true", help="no progress bars")


def worker_count(text: str) -> int:
    """argparse type: a number of worker processes, a whole number >= 1.

    >>> worker_count("2")
    2
    """
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number: give a number of processes >= 1") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} must be >= 1 (processes), e.g. 2; leave it out for one per CPU")
    return value


def add_workers(parser: argparse.ArgumentParser, *, help: str) -> None:
    """Add ``--workers N``: processes sharing the work (default None: the command picks, one per CPU)."""
    parser.add_argument("--workers", type=worker_count, default=None, metavar="N", help=help)


# ------------------------------------------------------------------------------------------------ secrets

TOKEN_ENV = "MIEN_TOKEN"
"""Environment variable that holds the live server's access token (``serve``, ``send``) when no option gives it."""


def add_token(parser: argparse.ArgumentParser, *, help: str) -> None:
    """Add ``--token TOKEN`` and ``--token-file FILE``; after parsing ``args.token`` is the access token from
    ``--token`` (other users see it in ``ps``), else the file's content (surrounding whitespace removed), else
    ``$MIEN_TOKEN`` (:data:`TOKEN_ENV`), else None. Both options at once, or a missing, unreadable or empty
    file, is a usage error naming the file (never the token)."""
    parser.add_argument(
        "--token", help=f"{help}; visible to other users in `ps`: prefer --token-file FILE or ${TOKEN_ENV}"
    )
    parser.add_argument(
        "--token-file", metavar="FILE", help=f"read the access token from FILE (as --token; else ${TOKEN_ENV})"
    )

    def take_token(args: argparse.Namespace) -> None:
        if args.token_file is not None:
            if args.token is not None:
                parser.error("give the access token once: --token or --token-file, not both")
            try:
                token = Path(args.token_file).read_text(encoding="utf-8").strip()
            except (OSError, UnicodeDecodeError) as error:
                reason = getattr(error, "strerror", None) or type(error).__name__
                parser.error(
                    f"--token-file {args.token_file}: cannot be read ({reason}); give a file holding the token"
                )
            if not token:
                parser.error(f"--token-file {args.token_file} is empty: write the token into it")
            args.token = token
        elif args.token is None:
            args.token = os.environ.get(TOKEN_ENV) or None

    parser.set_defaults(_finish_token=take_token)
