"""Speech: talking characters (issue 32; SPEC section 9).

Timed speech units (phonemes or visemes) from a source of timing become a coarticulated track of the 15
visemes (:data:`VISEMES`), which the character engine (:meth:`mien.character.CharacterBatch.say`) blends
with emotion, laughter and idle motion by one rule (:func:`~mien.speech.arbitration.arbitrate`).

Sources of timing, each returning an :class:`Utterance`:

* :func:`~mien.speech.espeak.speak`: text spoken by espeak-ng through ``libespeak-ng`` (phoneme events with
  their audio positions; the sound is kept);
* :func:`~mien.speech.timing_file.read_timing`: a small JSON or CSV phoneme/viseme timing file from any TTS;
* :func:`~mien.speech.openfacefx.read_openfacefx`: OpenFaceFX's ``openfacefx.track`` viseme output, read as a
  track;
* :func:`~mien.speech.audio.utterance_from_audio`: audio alone, the jaw following the sound's energy.

Importing this package needs only numpy; libespeak-ng is loaded (ctypes) on first use and ffmpeg is called
only to decode compressed audio.
"""

from mien.speech.arbitration import SPEECH_CHANNELS, arbitrate
from mien.speech.audio import mux_audio, read_audio, utterance_from_audio
from mien.speech.coarticulation import coarticulate
from mien.speech.espeak import speak, voices
from mien.speech.openfacefx import read_openfacefx
from mien.speech.timing_file import read_timing
from mien.speech.track import TRACK_FPS, Audio, Segment, Utterance, VisemeTrack
from mien.speech.visemes import VISEMES, rig_viseme_targets, viseme_arkit, viseme_aus

__all__ = [
    "SPEECH_CHANNELS",
    "TRACK_FPS",
    "VISEMES",
    "Audio",
    "Segment",
    "Utterance",
    "VisemeTrack",
    "arbitrate",
    "coarticulate",
    "mux_audio",
    "read_audio",
    "read_openfacefx",
    "read_timing",
    "rig_viseme_targets",
    "speak",
    "utterance_from_audio",
    "viseme_arkit",
    "viseme_aus",
    "voices",
]
