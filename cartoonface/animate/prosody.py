"""Pitch peaks of a recording: where a speaker accents a syllable.

`pitch_peaks(audio, alignment)` returns the times of the F0 maxima of the
syllables that stand out from their neighbours, the places where speakers
raise their brows and nod (Cave et al. 1996; Flecha-Garcia 2010; see
docs/animation.md "On the voice"). F0 comes from Praat's autocorrelation
method (Boersma 1993), in numpy (speech/pitch.py).

A syllable is a peak when its highest F0, in semitones above the median F0
of the whole recording, is at least PEAK_MIN semitones and higher than the
highest F0 of the syllables just before and after it in its sentence. In
Mandarin every syllable carries a lexical tone, so the high tones 1 and 4
peak everywhere; comparing with the neighbours keeps the local maxima of
the intonation, which is what an accent raises.
"""

from __future__ import annotations

import math
import os

import numpy as np

from cartoonface.speech import pitch as speech_pitch
from cartoonface.speech.audio import load_audio

# Praat's pitch analysis settings (our choice). 40 ms steps: Praat's window for To Pitch (ac) is
# 3 periods of the floor, 40 ms at 75 Hz (Praat's manual, "Sound: To Pitch..."), so the windows
# tile the recording and every sample is analysed once; a syllable of 150-300 ms gets 4-7 frames
# and a peak's time is known to 20 ms, well inside the 100 ms a brow is judged by. Other syllables
# peak than with 20 ms steps on 6-11 % of them, as many as with 20 ms steps whose frames are moved
# by half a step (6-10 %: which frame of a flat top is highest), and Praat's track took 0.24 s of
# CPU per 3 minutes instead of 0.47 s (`bench pitch_step`; docs/BENCHMARKS.md, "step"; speech/pitch.py
# does the same analysis in ~0.12 s, "track"). 75-500 Hz covers adult male and female speakers
# (Praat's defaults are 75 and 600 Hz).
TIME_STEP = 0.04  # seconds
PITCH_FLOOR = 75.0  # Hz
PITCH_CEILING = 500.0  # Hz
SEMITONES = 12.0  # semitones per octave
PEAK_MIN = 1.0  # semitones above the recording's median F0 for a peak (our choice)


def pitch_track(samples: np.ndarray, rate: int) -> tuple[np.ndarray, np.ndarray]:
    """F0 of mono `samples` ((n,) float in [-1, 1]) at `rate` Hz (speech/pitch.py: Praat's
    autocorrelation method) every TIME_STEP s between PITCH_FLOOR and PITCH_CEILING.

    Returns (times (m,) seconds, f0 (m,) Hz with NaN where unvoiced).
    """
    return speech_pitch.pitch_track(samples, rate, TIME_STEP, PITCH_FLOOR, PITCH_CEILING)


def recording_pitch(path: str | os.PathLike[str]) -> tuple[np.ndarray, np.ndarray]:
    """pitch_track (times (m,) s, f0 (m,) Hz) of the recording at `path`, decoded here (a process
    of its own: generate's helper, or the one the command forks before its imports)."""
    recording = load_audio(path)
    return pitch_track(recording.samples, recording.rate)


def pitch_peaks(audio, alignment, track: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[float, ...]:
    """Seconds of the accent peaks of an Audio (speech/audio.py) and its Alignment, sorted.

    One time per peak syllable: the frame of its highest F0 (rounded to ms).
    Empty when the recording has no voiced frame. `track`: the audio's pitch_track when already
    computed (generate computes it in a second process during the analysis).
    """
    times, f0 = pitch_track(audio.samples, audio.rate) if track is None else track
    voiced = f0[np.isfinite(f0)]
    if not len(voiced):
        return ()
    semitones = SEMITONES * np.log2(f0 / float(np.median(voiced)))
    syllables = [syllable for sentence in alignment.sentences for syllable in sentence.syllables]
    heights, whens = _tops(times, semitones, np.array([s.start for s in syllables], dtype=float),
                           np.array([s.end for s in syllables], dtype=float))
    peaks = []
    first = 0
    for sentence in alignment.sentences:
        stop = first + len(sentence.syllables)
        for i in range(first, stop):
            before = heights[i - 1] if i > first else -math.inf
            after = heights[i + 1] if i + 1 < stop else -math.inf
            if heights[i] >= PEAK_MIN and heights[i] > before and heights[i] > after:
                peaks.append(round(whens[i], 3))
        first = stop
    return tuple(sorted(peaks))


def _tops(times: np.ndarray, semitones: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> tuple[list[float], list[float]]:
    """For each of n syllables [starts, ends) (s): the highest semitones among the voiced frames in it
    and the time of the first frame reaching it, of `times` ((m,) s, ascending) and `semitones`
    ((m,), NaN unvoiced); (-inf, start) without one. The frames are found by bisection and the
    maxima taken over all syllables at once (30 minutes: O(n log m), no Python loop per syllable)."""
    first = np.searchsorted(times, starts, side="left")
    lengths = np.maximum(np.searchsorted(times, ends, side="left") - first, 0)
    owner = np.repeat(np.arange(len(starts)), lengths)  # the syllable of each frame inside one
    frame = np.arange(int(lengths.sum())) - np.repeat(np.cumsum(lengths) - lengths - first, lengths)
    values = semitones[frame]
    voiced = np.isfinite(values)
    highest = np.full(len(starts), -np.inf)
    np.maximum.at(highest, owner[voiced], values[voiced])
    reached = voiced & (values == highest[owner])
    top = np.full(len(starts), len(times))
    np.minimum.at(top, owner[reached], frame[reached])
    found = top < len(times)
    index = np.minimum(top, len(times) - 1)
    return (np.where(found, semitones[index], -np.inf).tolist(),
            np.where(found, times[index], starts).tolist())
