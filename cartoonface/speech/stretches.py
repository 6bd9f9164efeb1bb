"""Stretches between pauses, a check of the aligner's timing of each, and a fallback that cannot drift.

A stretch is a run of aligned syllables with no pause between them (a gap of at least
MIN_GAP between one syllable's end and the next one's start ends it), inside one sentence.
Its speaking rate is its own: syllables per voiced second of the stretch. The aligner's
timing of a stretch is taken as unfit when its mean confidence is below UNFIT_CONFIDENCE
and its syllable durations are implausible for that rate (the longest over LONGEST_SHARE
times the stretch's mean syllable duration). An unfit stretch is timed again by
`spread_over_peaks`: one syllable nucleus per loudness peak of the 100-1000 Hz band,
the peaks chosen by dynamic programming to match the count and stay near an even spread
between the stretch's edges; each onset is the loudness minimum between two nuclei. Such
a timing cannot drift past the stretch's edges.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from cartoonface.speech.features import HOP, frames

if TYPE_CHECKING:
    from cartoonface.speech.audio import Audio

MIN_GAP = 0.1              # s: a shorter gap between syllables is no pause (align.MIN_PAUSE frames)
UNFIT_CONFIDENCE = 0.2     # mean confidence below which a stretch's timing is checked further
LONGEST_SHARE = 3.0        # a syllable this many times the stretch's mean duration is implausible
MIN_SYLLABLES = 3          # shorter stretches are left as aligned
SPREAD_WEIGHT = 4.0        # score lost per squared (shift from the even spread / mean duration)
PEAK_WEIGHT = 0.1          # score per dB of a peak above the stretch's floor
SMOOTH_FRAMES = 5          # frames (50 ms) of smoothing before peaks are picked
FLOOR_PERCENTILE = 10.0    # the stretch's floor level
FALLBACK_CONFIDENCE = 0.1  # confidence given to syllables timed by the fallback


def stretches(starts: np.ndarray, ends: np.ndarray, firsts: set[int]) -> list[tuple[int, int]]:
    """(N,) syllable starts and ends in seconds, indices that begin a sentence -> (first, past-last)
    index pairs of the runs of syllables with no pause (gap >= MIN_GAP) and no sentence start inside."""
    cuts = [0] + [k for k in range(1, len(starts)) if starts[k] - ends[k - 1] >= MIN_GAP or k in firsts]
    return list(zip(cuts, cuts[1:] + [len(starts)]))


def voiced_rate(audio: Audio, start: float, end: float, count: int) -> float:
    """Syllables per voiced second of `count` syllables over start..end s of `audio`: voiced frames are
    those of the 100-1000 Hz band above the midpoint of its 10th and 90th percentile there."""
    low = _low_band(audio, start, end)
    if low.size == 0:
        return 0.0
    floor, loud = np.percentile(low, [FLOOR_PERCENTILE, 100 - FLOOR_PERCENTILE])
    voiced = max(float(np.sum(low > (floor + loud) / 2)) * HOP, HOP)
    return count / voiced


def unfit(starts: np.ndarray, ends: np.ndarray, confidence: np.ndarray) -> bool:
    """(n,) starts, ends (s) and confidences of one stretch's syllables -> whether the aligner's timing
    is unfit: low mean confidence and a syllable implausibly long for the stretch's own rate."""
    if len(starts) < MIN_SYLLABLES or float(np.mean(confidence)) >= UNFIT_CONFIDENCE:
        return False
    durations = ends - starts
    return bool(durations.max() > LONGEST_SHARE * durations.mean())


def _low_band(audio: Audio, start: float, end: float) -> np.ndarray:
    """(T,) smoothed dB of the 100-1000 Hz band over start..end s of `audio`, one value per 10 ms frame."""
    clip = np.asarray(audio.samples[max(int(start * audio.rate), 0):max(int(end * audio.rate), 0)], dtype=np.float64)
    if clip.size == 0:
        return np.zeros(0)
    low = frames(clip, audio.rate).low
    kernel = np.ones(SMOOTH_FRAMES) / SMOOTH_FRAMES
    return np.convolve(np.pad(low, SMOOTH_FRAMES // 2, mode="edge"), kernel, mode="valid")[:low.size]


def _choose(candidates: np.ndarray, heights: np.ndarray, targets: np.ndarray, scale: float) -> np.ndarray | None:
    """(C,) candidate frames in order, (C,) their heights (dB above floor), (n,) target frames, frames per
    syllable -> (n,) indices into candidates, increasing, maximising the sum of PEAK_WEIGHT * height minus
    SPREAD_WEIGHT * ((frame - target) / scale)^2; None when there are fewer candidates than targets."""
    count, n = len(candidates), len(targets)
    if count < n:
        return None
    gain = PEAK_WEIGHT * heights[None, :] - SPREAD_WEIGHT * ((candidates[None, :] - targets[:, None]) / scale) ** 2
    score = np.full((n, count), -np.inf)
    back = np.zeros((n, count), dtype=int)
    score[0] = gain[0]
    for k in range(1, n):
        best = np.maximum.accumulate(score[k - 1])
        where = np.zeros(count, dtype=int)
        for c in range(1, count):
            where[c] = where[c - 1] if score[k - 1][where[c - 1]] >= score[k - 1][c] else c
        score[k, 1:] = best[:-1] + gain[k, 1:]
        back[k, 1:] = where[:-1]
    chosen = [int(np.argmax(score[-1]))]
    for k in range(n - 1, 0, -1):
        chosen.append(int(back[k, chosen[-1]]))
    return np.array(chosen[::-1])


def spread_over_peaks(audio: Audio, start: float, end: float, count: int) -> list[tuple[float, float]]:
    """`count` syllables spoken over start..end s of `audio` -> (start, end) seconds of each, in order,
    inside start..end: nuclei at loudness peaks chosen near an even spread, onsets at the minimum
    between nuclei (an even split when the stretch has fewer peaks than syllables)."""
    low = _low_band(audio, start, end)
    total = low.size
    scale = max(total / max(count, 1), 1.0)
    targets = (np.arange(count) + 0.5) * scale
    inner = np.arange(1, total - 1)
    peaks = inner[(low[inner] >= low[inner - 1]) & (low[inner] > low[inner + 1])] if total > 2 else inner
    chosen = _choose(peaks.astype(float), low[peaks] - np.percentile(low, FLOOR_PERCENTILE), targets, scale) \
        if total > 2 else None
    if chosen is None:
        bounds = [start + (end - start) * k / count for k in range(count + 1)]
    else:
        nuclei = peaks[chosen]
        onsets = [int(a + np.argmin(low[a:b + 1])) for a, b in zip(nuclei, nuclei[1:])]
        bounds = [start] + [min(start + frame * HOP, end) for frame in onsets] + [end]
    return list(zip(bounds, bounds[1:]))
