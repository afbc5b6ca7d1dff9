"""Speech cost: a 100-character server tick with every character talking, and a 10 s sentence to its clip.

Part 1 (issue 32: speech adds at most 10 % to the tick). Two identical server workloads of 100 characters
(``CharacterBatch``, idle on 80, emotions held on all, OpenFACS full-state AU messages to 10 characters a tick,
a laugh now and then, then ``RigDriver.weights``/``pose`` for the whole batch, as bench/engine_tick.py does),
stepped tick by tick, interleaved (which goes first alternates). Named baseline: the same tick with no
speech. The talking batch has every character saying an utterance (espeak-ng sentences of 3-6 s, each row
starting at its own time and saying the next one when it ends, so ``say`` calls land during the run too).
Reported, in wall-clock time and in the thread's CPU time (the code's own cost, preemption by the other
processes of a busy machine excluded): median and p99 per tick (ms), the spread (min..max of the three thirds'
medians), and the ratio talking / silent of the medians.

Part 2 (a 10 s sentence becomes its clip in under 50 ms, TTS excluded): espeak-ng speaks a ~10 s text once;
then the timed segments -> coarticulated viseme track -> engine frames (``speech_frames``) -> the (n, 62) face
clip at 30 fps is timed over interleaved repeats. Named baseline in the same run: only reading the segments
back from the timing-file format (JSON) into an utterance, to show what the coarticulation itself costs.

Run ``python bench/speech_tick.py`` (``--ticks`` shortens part 1).
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

FPS = 60.0
N_CHARACTERS = 100
SENTENCES = (
    "Pete and Bob may keep a bump on the map, but the tub is empty.",
    "The quick brown fox jumps over the lazy dog.",
    "My mama made a map of the moon for me.",
    "Would you like a cup of tea before we begin the meeting?",
)
LONG_TEXT = (
    "Most characters that express emotion also talk: conversational agents, game characters, robots, and the "
    "stimuli of many studies. Emotion while speaking, without the mouth shapes fighting, is a common request."
)


def _workload(talking: bool, utterances: list) -> tuple:  # type: ignore[type-arg]
    from mien.character import CharacterBatch
    from mien.facs.idle import IdleSettings
    from mien.rig.driver import RigDriver

    batch = CharacterBatch(0)
    for k in range(N_CHARACTERS):
        batch.add_character(seed=k, idle=IdleSettings() if k < 80 else False)
        batch.emote(k, ("joy", "sadness", "anger", "surprise")[k % 4], 1.0)
    if talking:
        for k in range(N_CHARACTERS):
            batch.say(k, utterances[k % len(utterances)], start_s=0.01 * k)
    driver = RigDriver()
    weights = np.empty((N_CHARACTERS, driver.n_targets), np.float32)
    pose = np.empty((N_CHARACTERS, 5))
    return batch, driver, weights, pose


def server_ticks(n_ticks: int) -> dict[str, list[float]]:
    from mien.laughter.generator import generate
    from mien.speech.espeak import speak

    utterances = [speak(text) for text in SENTENCES]
    laugh = generate("laughter", duration_s=1.5, seed=3).face_clip
    runs = {"silent": _workload(False, utterances), "talking": _workload(True, utterances)}
    rng = np.random.default_rng(4)
    aus = ("AU1", "AU2", "AU4", "AU6", "AU12", "AU15", "AU25", "AU26")
    times: dict[str, list[float]] = {"silent": [], "talking": [], "silent cpu": [], "talking cpu": []}
    for i in range(n_ticks):
        t = i / FPS
        rows = np.arange(i % 10, N_CHARACTERS, 10)
        message = {au: float(v) for au, v in zip(aus, rng.uniform(0.0, 3.0, len(aus)), strict=True)}
        laugh_row = int(rng.integers(N_CHARACTERS)) if i % 120 == 0 else None
        order = ("silent", "talking") if i % 2 == 0 else ("talking", "silent")
        for name in order:
            batch, driver, weights, pose = runs[name]
            start, start_cpu = time.perf_counter(), time.thread_time()
            batch.set_aus(rows, message, speed=0.3, replace=True)
            if laugh_row is not None:
                batch.play_clip(laugh_row, laugh)
            if name == "talking":
                for row in range(i % 20, N_CHARACTERS, 20):  # a finished row says its next sentence
                    if batch.speech.utterance(row) is None:
                        batch.say(row, utterances[(row + i) % len(utterances)])
            frames = batch.step(t)
            driver.weights(frames, out=weights)
            driver.pose(frames, out=pose)
            times[name].append(time.perf_counter() - start)
            times[f"{name} cpu"].append(time.thread_time() - start_cpu)
    talking_batch = runs["talking"][0]
    talking_batch.step(n_ticks / FPS)
    print(f"  rows speaking at the end: {int((talking_batch.speech.presence > 0).sum())} of {N_CHARACTERS}")
    return times


def _thirds(values: list[float]) -> tuple[float, float]:
    parts = [values[k * len(values) // 3 : (k + 1) * len(values) // 3] for k in range(3)]
    medians = [statistics.median(p) * 1e3 for p in parts]
    return min(medians), max(medians)


def sentence_to_clip(repeats: int) -> dict[str, list[float]]:
    from mien.speech.batch import speech_frames
    from mien.speech.coarticulation import coarticulate
    from mien.speech.espeak import synthesize
    from mien.speech.timing_file import read_timing_segments
    from mien.speech.track import Utterance

    segments, audio = synthesize(LONG_TEXT)
    print(f"  text spoken by espeak-ng: {audio.duration_s:.2f} s of sound, {len(segments)} phoneme segments")
    folder = Path(tempfile.mkdtemp(prefix="mien-speech-bench-"))
    timing = folder / "t.json"
    timing.write_text(json.dumps({"alphabet": "viseme", "segments": [
        {"start_s": s.start_s, "end_s": s.end_s, "unit": s.viseme} for s in segments]}))  # fmt: skip
    times: dict[str, list[float]] = {"clip": [], "read segments only": []}
    for i in range(repeats):
        for name in ("clip", "read segments only") if i % 2 == 0 else ("read segments only", "clip"):
            start = time.perf_counter()
            if name == "clip":
                track = coarticulate(segments, duration_s=audio.duration_s)
                utterance = Utterance(track, tuple(segments), audio, LONG_TEXT, "espeak-ng")
                speech_frames(utterance)
                utterance.face_clip(30.0)
            else:
                read_timing_segments(timing)
            times[name].append(time.perf_counter() - start)
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=3600, help="server ticks (default %(default)s = 60 s)")
    parser.add_argument("--repeats", type=int, default=30, help="sentence-to-clip repeats (default %(default)s)")
    args = parser.parse_args()
    print(f"part 1: {N_CHARACTERS}-character server tick at {FPS:g} Hz, {args.ticks} ticks, interleaved")
    ticks = server_ticks(args.ticks)
    for clock, suffix in (("wall clock", ""), ("thread CPU time (preemption excluded)", " cpu")):
        print(f"  {clock}:")
        for name in ("silent", "talking"):
            ms = np.asarray(ticks[name + suffix]) * 1e3
            low, high = _thirds(ticks[name + suffix])
            print(f"    {name:8s} median {np.median(ms):.3f} ms (thirds {low:.3f}..{high:.3f}), "
                  f"p99 {np.percentile(ms, 99):.3f} ms")  # fmt: skip
        ratio = statistics.median(ticks["talking" + suffix]) / statistics.median(ticks["silent" + suffix])
        print(f"    talking / silent (baseline: the same tick without speech), medians: {ratio:.3f} "
              f"(+{100 * (ratio - 1):.1f} %; goal <= +10 %)")  # fmt: skip
    print(f"part 2: a ~10 s sentence to its clip (TTS excluded), {args.repeats} interleaved repeats")
    clip = sentence_to_clip(args.repeats)
    for name, values in clip.items():
        ms = np.asarray(values) * 1e3
        print(f"  {name:18s} median {np.median(ms):.2f} ms (min {ms.min():.2f}, max {ms.max():.2f})")
    ratio = statistics.median(clip["clip"]) / statistics.median(clip["read segments only"])
    print(f"  clip / reading the segments (baseline): {ratio:.1f}x; goal: clip under 50 ms")


if __name__ == "__main__":
    main()
