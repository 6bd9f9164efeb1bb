"""Stretches between pauses, a check of the aligner's timing of each, and a fallback that cannot drift.

A stretch is a run of aligned syllables with no pause between them (a gap of at least
MIN_GAP between one syllable's end and the next one's start ends it), inside one sentence.
Its speaking rate is its own: its mean syllable duration. The aligner's
timing of a stretch is taken as unfit when the mean of its syllables' posteriors (the aligner's
own, SyllableTiming.posterior, not the miss model's confidence) is below SURE_UNFIT, or below
UNFIT_CONFIDENCE while its syllable durations are implausible for the stretch's rate (the
longest over LONGEST_SHARE times the stretch's mean syllable duration). An unfit stretch is timed again by
`spread_over_peaks`: one syllable nucleus per loudness peak of the 100-1000 Hz band,
the peaks chosen by dynamic programming to match the count and stay near an even spread
between the stretch's edges; each onset is the loudness minimum between two nuclei. Such
a timing cannot drift past the stretch's edges.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from cartoonface.speech.align import MIN_PAUSE
from cartoonface.speech.features import HOP, bands, smooth

if TYPE_CHECKING:
    from cartoonface.speech.audio import Audio

MIN_GAP = MIN_PAUSE * HOP  # s: a shorter gap between syllables is no pause (the aligner's)
# Tuned on the tuning half only (bench/align.py, `analyse` sets with punctuation kept / paragraphs;
# docs/BENCHMARKS.md), for the aligner's posterior confidence: within 50 ms 96.6 / 97.2 / 97.2 / 94.9 %
# and 95.2 / 95.2 / 95.2 / 92.7 % for a sure-unfit mean of 0.4 / 0.45 / 0.5 / 0.6 (gate 0.6; a gate
# of 0.7 or 0.8 changed nothing). 0.45 (one tuning stretch better) also fired on the clean espeak-ng
# sample samples/speech/story.wav, on a stretch the aligner had right (mean 0.43), so 0.4 is kept.
UNFIT_CONFIDENCE = 0.6     # mean posterior below which a stretch's durations are checked
SURE_UNFIT = 0.4           # mean posterior below which a stretch is unfit whatever its durations
LONGEST_SHARE = 3.0        # a syllable this many times the stretch's mean duration is implausible
MIN_SYLLABLES = 3          # shorter stretches are left as aligned
SPREAD_WEIGHT = 0.3        # score lost per squared (shift from the even spread / mean duration)
DIP_WEIGHT = 1.0           # score per dB of dip between two chosen peaks
SMOOTH_FRAMES = 5          # frames (50 ms) of smoothing before peaks are picked
FALLBACK_CONFIDENCE = 0.1  # confidence given to syllables timed by the fallback
FALLBACK_NOTE = "timing uncertain, syllables spread over loudness peaks"  # ends the note of each such stretch


def stretches(starts: np.ndarray, ends: np.ndarray, firsts: set[int]) -> list[tuple[int, int]]:
    """(N,) syllable starts and ends in seconds, indices that begin a sentence -> (first, past-last)
    index pairs of the runs of syllables with no pause (gap >= MIN_GAP) and no sentence start inside."""
    cuts = [0] + [k for k in range(1, len(starts)) if starts[k] - ends[k - 1] >= MIN_GAP or k in firsts]
    return list(zip(cuts, cuts[1:] + [len(starts)]))


def unfit(starts: np.ndarray, ends: np.ndarray, posterior: np.ndarray) -> bool:
    """(n,) starts, ends (s) and aligner posteriors of one stretch's syllables -> whether the aligner's
    timing is unfit: mean posterior below SURE_UNFIT, or below UNFIT_CONFIDENCE with a syllable implausibly
    long for the stretch's own rate (over LONGEST_SHARE times its mean syllable duration)."""
    if len(starts) < MIN_SYLLABLES or float(np.mean(posterior)) >= UNFIT_CONFIDENCE:
        return False
    durations = ends - starts
    return bool(durations.max() > LONGEST_SHARE * durations.mean()) or float(np.mean(posterior)) < SURE_UNFIT


def _low_band(audio: Audio, start: float, end: float) -> np.ndarray:
    """(T,) smoothed dB of the 100-1000 Hz band over start..end s of `audio`, one value per 10 ms frame."""
    clip = np.asarray(audio.samples[max(int(start * audio.rate), 0):max(int(end * audio.rate), 0)], dtype=np.float64)
    if clip.size == 0:
        return np.zeros(0)
    return smooth(bands(clip, audio.rate)[0], SMOOTH_FRAMES)


def _choose(candidates: np.ndarray, low: np.ndarray, targets: np.ndarray, scale: float) -> np.ndarray | None:
    """(C,) candidate frames (loudness peaks) in order, (T,) the band's dB, (n,) target frames, frames per
    syllable -> (n,) indices into candidates, increasing, maximising DIP_WEIGHT times the depth of the dip
    between each two chosen peaks (dB below the lower of the two) minus SPREAD_WEIGHT * ((frame - target)
    / scale)^2 per peak; None when there are fewer candidates than targets."""
    count, n = len(candidates), len(targets)
    if count < n:
        return None
    peaks = low[candidates]
    dips = np.zeros((count, count))
    for i in range(count):
        lowest = np.minimum.accumulate(low[candidates[i]:])[candidates[i:] - candidates[i]]
        dips[i, i:] = np.minimum(peaks[i], peaks[i:]) - lowest
    gain = -SPREAD_WEIGHT * ((candidates[None, :] - targets[:, None]) / scale) ** 2
    later = np.triu(np.ones((count, count), dtype=bool), 1)
    score = np.full((n, count), -np.inf)
    back = np.zeros((n, count), dtype=int)
    score[0] = gain[0]
    for k in range(1, n):
        options = np.where(later, score[k - 1][:, None] + DIP_WEIGHT * dips, -np.inf)
        back[k] = np.argmax(options, axis=0)
        score[k] = options[back[k], np.arange(count)] + gain[k]
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
    chosen = _choose(peaks, low, targets, scale) if total > 2 else None
    if chosen is None:
        bounds = [start + (end - start) * k / count for k in range(count + 1)]
    else:
        nuclei = peaks[chosen]
        onsets = [int(a + np.argmin(low[a:b + 1])) for a, b in zip(nuclei, nuclei[1:])]
        bounds = [start] + [min(start + frame * HOP, end) for frame in onsets] + [end]
    return list(zip(bounds, bounds[1:]))
