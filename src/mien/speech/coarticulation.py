"""Coarticulation: timed segments -> a smooth viseme track, by Cohen & Massaro's dominance model.

Cohen, M. M. & Massaro, D. W. (1993). Modeling coarticulation in synthetic visual speech. In N. M. Thalmann &
D. Thalmann (eds.), *Models and Techniques in Computer Animation*, Springer, pp. 139-156.

Each segment s (viseme v) spreads a dominance over time, highest inside the segment and falling off
exponentially outside it::

    D_s(t) = alpha_v * exp(-theta_v * d(t, s))      d(t, s): seconds from t to [start_s, end_s] (0 inside)

and the mouth at t is the dominance-weighted mean of the segments' targets: the weight of viseme v is
``sum of D_s over its segments / sum of all D_s``. Cohen & Massaro use ``exp(-theta * |tau|^c)`` from the
segment centre with c = 1 as the common case; measuring from the segment's edges keeps a long segment (a held
vowel, a pause) at full strength inside, which mien prefers for TTS timings. alpha and theta per viseme are data
(``data/visemes.csv``): labial closures dominate with a steep fall-off, so /p b m/ close the lips while the
vowels around them stay open; a closure shorter than its viseme's ``min_s`` (a 25 ms /p/ from a TTS) spreads its
dominance over ``min_s`` about its centre, so it shows on a video frame. Before the first and after the last
segment the mouth rests (an implicit ``sil`` on each side).

>>> track = coarticulate([Segment(0.0, 0.1, "aa"), Segment(0.1, 0.18, "PP"), Segment(0.18, 0.3, "aa")])
>>> track.dominant()[5], track.dominant()[14], track.dominant()[24]
('aa', 'PP', 'aa')
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from mien.errors import InvalidValueError
from mien.speech.track import TRACK_FPS, Segment, VisemeTrack
from mien.speech.visemes import VISEMES, check_viseme, viseme_dominance

__all__ = ["NEGLIGIBLE", "TAIL_S", "coarticulate"]

TAIL_S = 0.2
"""Seconds of rest after the last segment, so the mouth closes before the track ends."""

NEGLIGIBLE = 1e-6
"""A dominance under this fraction of the weakest alpha is left out (see :func:`coarticulate`)."""


def coarticulate(segments: Sequence[Segment], fps: float = TRACK_FPS, duration_s: float | None = None) -> VisemeTrack:
    """The viseme track of ``segments`` (in time order, non-overlapping) at ``fps``.

    It covers ``0 .. duration_s`` (default: the last segment's end + :data:`TAIL_S`). Cost is
    O(frames x segments), a few ms for a 10 s sentence.
    """
    if not segments:
        raise InvalidValueError("segments", [], "at least one timed speech segment")
    if not (math.isfinite(fps) and fps > 0):
        raise InvalidValueError("fps", fps, "a positive frame rate")
    starts = np.array([s.start_s for s in segments])
    ends = np.array([s.end_s for s in segments])
    ids = np.array([check_viseme(s.viseme) for s in segments])
    end_s = segments[-1].end_s + TAIL_S if duration_s is None else float(duration_s)
    n = max(1, math.ceil(end_s * fps - 1e-9) + 1)
    times = np.arange(n) / fps
    alpha, theta, min_s = viseme_dominance()
    widen = np.maximum(0.0, min_s[ids] - (ends - starts)) / 2.0  # short closures held min_s about their centre
    # a segment's reach: beyond it its dominance is under NEGLIGIBLE of the weakest alpha, so each frame sums
    # only the k segments within reach (banded, O(frames x k) instead of O(frames x segments))
    reach = math.log(float(alpha.max()) / (NEGLIGIBLE * float(alpha.min()))) / float(theta.min()) + float(widen.max())
    first = np.searchsorted(np.maximum.accumulate(ends), times - reach)
    stop = np.searchsorted(starts, times + reach, side="right")
    k = max(1, int((stop - first).max()))
    band = np.minimum(first[:, None] + np.arange(k), len(segments) - 1)
    inside = first[:, None] + np.arange(k) < stop[:, None]
    band_ids = ids[band]
    distance = np.maximum(
        0.0, np.maximum(starts[band] - widen[band] - times[:, None], times[:, None] - ends[band] - widen[band])
    )
    dominance = np.where(inside, alpha[band_ids] * np.exp(-theta[band_ids] * distance), 0.0)
    weights = np.zeros((n, len(VISEMES)))
    frame = np.arange(n)
    for column in range(k):
        weights[frame, band_ids[:, column]] += dominance[:, column]  # one segment per frame in a column
    # the rest before the first and after the last segment (an implicit sil reaching to +-infinity)
    silence = VISEMES.index("sil")
    before = np.maximum(0.0, times - starts[0])
    after = np.maximum(0.0, ends[-1] - times)
    weights[:, silence] += alpha[silence] * (np.exp(-theta[silence] * before) + np.exp(-theta[silence] * after))
    weights /= weights.sum(axis=1, keepdims=True)
    return VisemeTrack(weights, fps)
