"""The ``mien`` subcommands, one module each.

Each module defines ``register(subparsers)``, which adds its parser and sets ``handler`` (a function taking the
parsed ``argparse.Namespace`` and returning an exit code). Modules import only argparse at load time; heavy
imports happen inside the handlers. Argument checks come from :mod:`mien.commands._checks` (the CLI contract) and
the shared words (``-o/--output``, ``--head HEAD[:IDENTITY]``, ``--landmarker``, ports, ``--basis``, fps,
``--quiet``) and their deprecated spellings from :mod:`mien.commands._vocabulary` (README "CLI vocabulary").
"""

COMMAND_MODULES: tuple[str, ...] = (
    "demo",
    "emote",
    "au",
    "render",
    "head",
    "assets",
    "track",
    "capture",
    "learn",
    "laugh",
    "say",
    "validate",
    "export",
    "import_",
    "serve",
    "send",
    "study",
)
"""Subcommand modules under :mod:`mien.commands`, in ``mien --help`` order."""
