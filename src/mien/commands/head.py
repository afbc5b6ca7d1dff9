"""``mien head inspect HEAD``: what mien makes of a head (names, missing AUs, landmarks, scale) and a picture."""

from __future__ import annotations

import argparse

from mien.commands._checks import input_file, output_file
from mien.commands._vocabulary import add_landmarker, add_output, head_spec

__all__ = ["register", "run_inspect"]


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``head`` subcommand (``head inspect``)."""
    parser = subparsers.add_parser(
        "head",
        help="inspect a head: your character's file, or one of mien's",
        description="Heads: what mien reads in a character file and finds on its face.",
    )
    actions = parser.add_subparsers(dest="head_action", metavar="ACTION", required=True)
    inspect = actions.add_parser(
        "inspect",
        help="print a head's names, missing AUs, landmarks and scale; draw its landmarks",
        description=(
            "Load HEAD as every mien job does: a character file (.glb, .gltf, .vrm, or a folder of OBJ shapes) "
            "or a named head (builtin, ict, default, with :IDENTITY). Prints the naming convention found, the "
            "targets matched and not, the ARKit targets it lacks and which AUs that costs, the landmarks and "
            "the face's scale. A file is instrumented on first use (its landmarks found on its own render, "
            "about 5 s, then cached per file hash)."
        ),
    )
    inspect.add_argument("head", type=head_spec, metavar="HEAD", help="a character file or a head name")
    add_output(inspect, type=output_file, metavar="PNG", help="write a picture of the landmarks on the face")
    add_landmarker(inspect, type=input_file)
    inspect.set_defaults(handler=run_inspect)


def run_inspect(args: argparse.Namespace) -> int:
    """Inspect ``args.head``, print the report and write the picture when ``--output`` is given."""
    from mien.errors import InvalidValueError
    from mien.heads.inspect import inspect_head

    head, identity = args.head
    if args.output and not str(args.output).lower().endswith(".png"):
        raise InvalidValueError("output", str(args.output), "a path ending in .png")
    spec = f"file:{identity}" if head == "file" else head
    inspection = inspect_head(spec, None if head == "file" else identity, args.landmarker)
    print(inspection.report())
    if args.output:
        print(f"wrote {inspection.save_picture(args.output)}")
    return 0
