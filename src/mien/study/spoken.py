"""Spoken stimuli: a sentence (``[stimuli] say`` of the design) said while the stimulus shows its expression.

The sentence is spoken once by espeak-ng (:func:`speak_line`); each rendered stimulus says it from the
design's ``onset_s`` while its emotion rises at the same moment and holds to the sentence's end
(:func:`speaking_envelope`), so the emotion is the condition and the words are the same in every stimulus. The
MP4 carries the sound (:func:`sound_from_start`: the utterance after ``onset_s`` of silence, muxed as AAC), and the
manifest records what was said and where its timing came from (:func:`speech_record`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from mien.facs.envelope import Envelope

if TYPE_CHECKING:
    from mien.speech.track import Audio, Utterance
    from mien.study.design import Design, SpokenLine

__all__ = ["SPEECH_TAIL_S", "clip_duration_s", "sound_from_start", "speak_line", "speaking_envelope", "speech_record"]

SPEECH_TAIL_S = 0.4
"""Seconds a spoken stimulus runs on after its sentence (the mouth comes to rest, the emotion decays)."""


def speak_line(line: SpokenLine) -> Utterance:
    """The design's sentence spoken by espeak-ng (raises the typed errors of :func:`mien.speech.espeak.speak`:
    an unknown language names the voices there are; no libespeak-ng says what to install)."""
    from mien.speech.espeak import speak

    return speak(line.text, line.language, line.rate_wpm)


def clip_duration_s(design: Design, utterance: Utterance) -> float:
    """Length of a spoken stimulus, seconds: the design's ``duration_s``, longer if the sentence needs it."""
    return max(design.duration_s, design.onset_s + utterance.duration_s + SPEECH_TAIL_S)


def speaking_envelope(utterance: Utterance) -> Envelope:
    """The emotion's profile while speaking: the study onset (0.4 s), held to the sentence's end, the study
    decay (0.3 s)."""
    onset = Envelope().onset_s
    return Envelope(onset, max(Envelope().hold_s, utterance.duration_s - onset), Envelope().decay_s)


def sound_from_start(utterance: Utterance, onset_s: float) -> Audio:
    """The utterance's sound placed at ``onset_s`` in the video: that much silence first."""
    from mien.speech.track import Audio

    audio = utterance.audio
    assert audio is not None  # espeak-ng always returns the sound
    silence = np.zeros(round(onset_s * audio.sample_rate), np.float32)
    return Audio(np.concatenate([silence, audio.samples]), audio.sample_rate)


def speech_record(line: SpokenLine, utterance: Utterance, onset_s: float) -> dict[str, Any]:
    """What the manifest says about a spoken stimulus: the text, voice, rate, timing source and times (seconds)."""
    return {
        "text": line.text,
        "language": line.language,
        "rate_wpm": line.rate_wpm,
        "timing_source": utterance.source,
        "onset_s": onset_s,
        "duration_s": round(utterance.duration_s, 6),
        "phonemes": len(utterance.segments),
    }
