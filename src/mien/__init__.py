"""mien: make virtual characters' faces express emotion."""

from mien.errors import InvalidValueError, MienError, MissingAssetError, MissingExtraError, UnknownNameError
from mien.facs.catalogue import ACTION_UNITS, FACE_CHANNELS, OPENFACS_AUS, ActionUnit
from mien.facs.clip import Clip
from mien.facs.intensity import AUSpec, parse_au

__version__ = "0.1.0"

__all__ = [
    "ACTION_UNITS",
    "FACE_CHANNELS",
    "OPENFACS_AUS",
    "AUSpec",
    "ActionUnit",
    "Clip",
    "InvalidValueError",
    "MienError",
    "MissingAssetError",
    "MissingExtraError",
    "UnknownNameError",
    "__version__",
    "parse_au",
]
