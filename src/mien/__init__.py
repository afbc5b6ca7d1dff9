"""mien: make virtual characters' faces express emotion.

The core (this namespace) needs numpy only: face states, the FACS engine, the emotion engine, idle
behaviour and characters. Rigs, rendering, tracking and laughter learning live in subpackages whose heavy
dependencies are imported only when used (``pip install 'mien[all]'``).

>>> from mien import Character
>>> face = Character(seed=0)
>>> face.emote("joy", 1.2)
>>> frame = face.step(0.5)        # (62,) AU intensities + head/gaze degrees at t = 0.5 s
"""

from mien.affect.emotions import BLENDS, EMOTIONS, Blend, define_blend
from mien.affect.engine import EmotionEngine
from mien.character import Character, CharacterBatch
from mien.errors import InvalidValueError, MienError, MissingAssetError, MissingExtraError, UnknownNameError
from mien.facs.catalogue import ACTION_UNITS, FACE_CHANNELS, OPENFACS_AUS, ActionUnit
from mien.facs.clip import Clip
from mien.facs.dynamics import FacsEngine, time_constant_from_speed
from mien.facs.envelope import Envelope
from mien.facs.idle import Idle, IdleSettings
from mien.facs.intensity import AUSpec, parse_au
from mien.facs.prototypes import EMFACS_PROTOTYPES
from mien.version import __version__

__all__ = [
    "ACTION_UNITS",
    "BLENDS",
    "EMFACS_PROTOTYPES",
    "EMOTIONS",
    "FACE_CHANNELS",
    "OPENFACS_AUS",
    "AUSpec",
    "ActionUnit",
    "Blend",
    "Character",
    "CharacterBatch",
    "Clip",
    "EmotionEngine",
    "Envelope",
    "FacsEngine",
    "Idle",
    "IdleSettings",
    "InvalidValueError",
    "MienError",
    "MissingAssetError",
    "MissingExtraError",
    "UnknownNameError",
    "__version__",
    "define_blend",
    "parse_au",
    "time_constant_from_speed",
]
