"""Lip sync from the recording alone, when there is no transcript (issue 14, docs/alignment.md).

`analyse_audio` makes the same Alignment records as `analyse.analyse`, without text:

- speech and pauses: the speaking parts of `sentences.find_speech_parts` (one untitled
  sentence each, text UNTRANSCRIBED, which the pages do not show);
- syllable nuclei: peaks of the 100-1000 Hz band's loudness (features.Frames.low) at least
  NUCLEUS_PROMINENCE_DB prominent and MIN_SYLLABLE apart; a syllable runs from the loudness
  minimum before its nucleus to the one after it (the part's edges: where the band rises
  within EDGE_DB of the nucleus);
- closures: a dip of the whole band's energy at least CLOSURE_DB below the quieter of the
  two nuclei around it (a stop or nasal closure, not a fricative, which keeps its energy)
  is left out of both syllables, a gap of CLOSURE_GAP around the dip, so the timeline closes
  the mouth there (animate/timeline.py: a gap of SHORT_PAUSE_MS = align.MIN_PAUSE or more closes it; the
  thesis's closed-shape onset would hold a leading m over 81 % of a two-shape syllable);
- vowel class: the first two formants at the nucleus (Burg, parselmouth), normalised per
  recording (z-scores over all nuclei, Lobanov), give open (high F1), rounded (low F2),
  spread (high F2) or mid. VOWEL_SHAPES maps each class onto the 12 mouth shapes.

Each syllable's `pinyin` field holds its vowel class (the TextGrid's syllables tier shows it).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from cartoonface.speech.audio import Audio
from cartoonface.speech.dsp import find_peaks
from cartoonface.speech.align import MIN_PAUSE
from cartoonface.speech.features import HOP, frames, smooth
from cartoonface.speech.records import Alignment, Sentence, Syllable
from cartoonface.speech.sentences import Span, find_speech_parts

UNTRANSCRIBED = "…"  # the text of a sentence found without a transcript; pages hide it
AUDIO_ONLY_NOTE = "no transcript: the lip sync comes from the audio alone (loudness and formants)"
SMOOTH_FRAMES = 3            # frames (30 ms) of smoothing of the band loudness before peaks are picked
NUCLEUS_PROMINENCE_DB = 3.0  # a loudness peak this prominent (dB) is a syllable nucleus
MIN_SYLLABLE = 0.1           # s between two nuclei at least (Mandarin: 3-7 syllables per second)
NUCLEUS_RANGE_DB = 30.0      # peaks this far below the part's loudest frame are noise, not nuclei
EDGE_DB = 20.0               # a part's first/last syllable starts/ends where the band is this far below its nucleus
CLOSURE_DB = 20.0            # energy dip (dB below the quieter neighbouring nucleus) taken as a lip closure
CLOSURE_GAP = MIN_PAUSE * HOP  # s left out around a closure (the aligner's shortest pause: a gap that closes the mouth)
FORMANT_STEP = HOP           # s between formant measurements
MAX_FORMANT_HZ = 5500.0      # Burg's ceiling (Praat's default for a female voice; fine for male voices too)
FORMANT_FRAMES = 2           # nucleus +- this many formant frames are averaged (median)
# Lobanov z-scores of F1 / F2 that decide the vowel class, and CLOSURE_DB: tuned on Biaobei 000001-000035
# (bench/no_transcript.py sweep, docs/BENCHMARKS.md: 55.8 % of frames in the same class; without closures
# 56.3 %, with 15 dB 55.5 %: closures are kept for the visible bilabial closures, at the deepest setting)
OPEN_Z = 0.5                 # F1 above this: open
ROUNDED_Z = -0.3             # F2 below this: rounded
SPREAD_Z = 0.5               # F2 above this: spread
# Vowel class -> the shape of thesis 002 5.2.2 shown (the closer variant when F1 is below the mean).
VOWEL_SHAPES: dict[str, tuple[str, str]] = {
    "open": ("a", "a"),      # (shape for F1 above the mean, shape for F1 below)
    "rounded": ("o", "u"),
    "spread": ("e", "i"),
    "mid": ("h", "h"),       # the mid central vowel (Mandarin e, er)
}
# The four mouth classes the lip sync without a transcript is measured in (bench/no_transcript.py):
# each of the 12 shapes of thesis 002 5.2.2 by its lips (m, f: closed or lower lip at the teeth;
# u, o, r: rounded or protruded; i, e, z: spread corners; a, h, h', n: open).
MOUTH_CLASSES: dict[str, str] = {
    "m": "closed", "f": "closed", "u": "rounded", "o": "rounded", "r": "rounded",
    "i": "spread", "e": "spread", "z": "spread", "a": "open", "h": "open", "h'": "open", "n": "open",
}
# No transcript confirms the timing: every syllable gets this confidence (above analyse.LOW_CONFIDENCE,
# so that the whole recording is not flagged syllable by syllable; the note says why instead).
AUDIO_ONLY_CONFIDENCE = 0.9


def transcribed(alignment: Alignment) -> bool:
    """Whether `alignment` holds text (False when it was made from the audio alone)."""
    return any(sentence.text != UNTRANSCRIBED for sentence in alignment.sentences)


def analyse_audio(
    audio: Audio,
    pause: tuple[float, float] | None = None,
    progress: Callable[[str, float], None] | None = None,
) -> Alignment:
    """Sentences (one per speaking part, text UNTRANSCRIBED) and syllables (shapes from loudness and
    formants) of `audio`, without a transcript. `pause` and `progress` as for analyse.analyse.
    A recording without speech gives no sentences and a note saying so."""
    report = progress or (lambda stage, fraction: None)
    report("segment", 0.0)
    parts = find_speech_parts(audio, pause)
    report("segment", 1.0)
    notes = [AUDIO_ONLY_NOTE]
    if not parts:
        return Alignment((), audio.duration, (*notes, "no speech told apart from noise: the mouth stays closed"))
    features = frames(audio.samples, audio.rate)
    low = smooth(features.low, SMOOTH_FRAMES)
    energy = smooth(features.energy, SMOOTH_FRAMES)
    timed = []
    for index, part in enumerate(parts):
        report("align", index / len(parts))
        timed.append(_syllables(low, energy, part))
    report("align", 1.0)
    nuclei = [nucleus for found in timed for _, _, nucleus in found]
    vowels = vowel_classes(audio, np.array(nuclei, dtype=float) * HOP)
    sentences, k = [], 0
    for found in timed:
        syllables = []
        for start, end, _ in found:
            label, shape = vowels[k]
            k += 1
            syllables.append(Syllable("", label, (shape,), start, end, AUDIO_ONLY_CONFIDENCE))
        if syllables:
            sentences.append(Sentence(UNTRANSCRIBED, syllables[0].start, syllables[-1].end, tuple(syllables)))
    return Alignment(tuple(sentences), audio.duration, tuple(notes))


def _syllables(low: np.ndarray, energy: np.ndarray, part: Span) -> list[tuple[float, float, int]]:
    """(T,) smoothed dB of the 100-1000 Hz band and of the whole band (10 ms frames), one speaking part ->
    (start s, end s, nucleus frame) of each syllable in it, in order; CLOSURE_GAP left between two
    syllables around a closure."""
    first = max(int(part.start / HOP), 0)
    last = min(int(np.ceil(part.end / HOP)), len(low))
    if last - first < 3:
        return []
    band = low[first:last]
    peaks = find_peaks(band, prominence=NUCLEUS_PROMINENCE_DB, distance=max(1, round(MIN_SYLLABLE / HOP)))
    peaks = peaks[band[peaks] >= band.max() - NUCLEUS_RANGE_DB]
    if peaks.size == 0:
        peaks = np.array([int(np.argmax(band))])
    dips = [int(a + np.argmin(band[a:b + 1])) for a, b in zip(peaks, peaks[1:])]
    onset = int(peaks[0])
    while onset > 0 and band[onset - 1] >= band[peaks[0]] - EDGE_DB:
        onset -= 1
    offset = int(peaks[-1])
    while offset + 1 < len(band) and band[offset + 1] >= band[peaks[-1]] - EDGE_DB:
        offset += 1
    loud = energy[first:last]
    half = round(CLOSURE_GAP / HOP / 2)
    ends, starts = [], [onset]
    for k, dip in enumerate(dips):
        closed = min(loud[peaks[k]], loud[peaks[k + 1]]) - loud[dip] >= CLOSURE_DB
        ends.append(max(dip - half, peaks[k] + 1) if closed else dip)
        starts.append(min(dip + half, peaks[k + 1]) if closed else dip)
    ends.append(offset + 1)
    return [(round((first + a) * HOP, 3), round((first + b) * HOP, 3), first + int(nucleus))
            for a, b, nucleus in zip(starts, ends, peaks)]


def vowel_classes(audio: Audio, times: np.ndarray) -> list[tuple[str, str]]:
    """(N,) nucleus times in seconds -> (vowel class, mouth shape) of each: F1/F2 (Burg) at each time,
    median over +-FORMANT_FRAMES frames, z-scored over the N nuclei; classes and shapes as VOWEL_SHAPES."""
    if times.size == 0:
        return []
    import parselmouth  # Praat's formant tracker; imported here, as the pages only need `transcribed`

    sound = parselmouth.Sound(np.asarray(audio.samples, dtype=np.float64), sampling_frequency=float(audio.rate))
    formant = sound.to_formant_burg(time_step=FORMANT_STEP, maximum_formant=MAX_FORMANT_HZ)
    measured = np.full((times.size, 2), np.nan)
    for i, t in enumerate(times):
        around = t + FORMANT_STEP * np.arange(-FORMANT_FRAMES, FORMANT_FRAMES + 1)
        for j in (0, 1):
            values = np.array([formant.get_value_at_time(j + 1, float(s)) for s in around])
            if np.isfinite(values).any():
                measured[i, j] = float(np.nanmedian(values))
    z = np.zeros_like(measured)
    for j in (0, 1):
        column = measured[:, j]
        known = np.isfinite(column)
        if known.sum() > 1 and np.std(column[known]) > 0:
            z[known, j] = (column[known] - column[known].mean()) / column[known].std()
    return [_vowel(float(z1), float(z2)) for z1, z2 in z]


def _vowel(z1: float, z2: float) -> tuple[str, str]:
    """Lobanov z-scores of F1 and F2 -> (vowel class, mouth shape)."""
    if z1 > OPEN_Z:
        label = "open"
    elif z2 < ROUNDED_Z:
        label = "rounded"
    elif z2 > SPREAD_Z:
        label = "spread"
    else:
        label = "mid"
    wide, close = VOWEL_SHAPES[label]
    return label, wide if z1 > 0 else close
