"""Options shared by the subcommands that render a head (render, demo): head, camera, size, basis."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from mien.commands._vocabulary import add_head, basis_name
from mien.errors import InvalidValueError
from mien.render.camera import CAMERA_PRESETS

if TYPE_CHECKING:
    from mien.render.camera import Camera
    from mien.rig.model import Rig

__all__ = ["add_scene_options", "parse_size", "scene_from_args"]


def parse_size(text: str) -> tuple[int, int]:
    """``"512"`` or ``"640x480"`` -> (width, height) pixels."""
    parts = text.lower().split("x")
    try:
        width, height = (int(parts[0]), int(parts[0])) if len(parts) == 1 else (int(parts[0]), int(parts[1]))
    except ValueError:
        raise InvalidValueError("size", text, "WIDTHxHEIGHT pixels, e.g. 512x512") from None
    if len(parts) > 2 or width <= 0 or height <= 0 or width > 8192 or height > 8192:
        raise InvalidValueError("size", text, "WIDTHxHEIGHT pixels between 1 and 8192")
    return width, height


def add_scene_options(parser: argparse.ArgumentParser, camera: str = "portrait") -> None:
    """Add head, camera, size and basis options."""
    add_head(
        parser,
        help="head: default (ICT-FaceKit if installed, else builtin), builtin or ict, with an optional identity "
        "(face morphology: builtin:b, ict:a, ict:mean...), or a head file (.glb, .gltf, .vrm, a folder of .obj)",
    )
    parser.add_argument(
        "--camera",
        default=camera,
        help=f"preset: {', '.join(CAMERA_PRESETS)} (default %(default)s)",
    )
    parser.add_argument("--yaw", type=float, help="camera yaw in degrees (90 = the character's left side)")
    parser.add_argument("--pitch", type=float, help="camera pitch in degrees")
    parser.add_argument("--distance", type=float, help="camera distance in metres")
    parser.add_argument("--fov", type=float, help="vertical field of view in degrees")
    parser.add_argument("--size", default="512x512", help="image size WIDTHxHEIGHT (default %(default)s)")
    parser.add_argument(
        "--basis",
        type=basis_name,
        default="facs",
        help="emotion expression basis: facs (EMFACS AU prototypes) or feature_points (Broekens' Table 1)",
    )


def scene_from_args(args: argparse.Namespace) -> tuple[Rig, Camera, tuple[int, int]]:
    """(rig, camera, size) from the parsed options."""
    from mien.heads import load_head
    from mien.render.camera import camera_from_options

    size = parse_size(args.size)
    camera = camera_from_options(args.camera, args.yaw, args.pitch, args.distance, args.fov)
    rig = load_head(args.head, args.identity, feature_points=args.basis == "feature_points")
    return rig, camera, size
