"""F0 of speech by Boersma's autocorrelation method (Boersma 1993), as Praat's "Sound: To Pitch
(ac)..." with its standard settings and a Hanning window, in numpy.

Praat through parselmouth took 0.09 s of CPU to import (its whole program is set up at load) and
0.24 s per 3 minutes at 40 ms steps; this takes ~0.1 s and imports nothing but numpy. The accent
peaks (animate/prosody.py) it gives differ from Praat's about as much as Praat's own differ when
its frames are moved by half a step (`bench pitch_step`; docs/BENCHMARKS.md, "track").

Per frame (every `step` s, centred in the recording as Praat places them): the samples of a window
of PERIODS periods of the pitch floor less their local mean (over two floor periods), Hanning
windowed; their autocorrelation divided by the window's (Boersma's correction) and by its value at
lag 0. Candidates: its maxima above half the voicing threshold at lags of pitches from the floor
up, placed by parabolic interpolation (Praat refines them by sinc interpolation), at most
CANDIDATES - 1 of them, strongest first after the octave cost; besides, the unvoiced candidate,
the stronger the quieter the frame against the recording's peak. The track is the path through
the candidates that maximises their strengths less the octave-jump and voicing-change costs
(Viterbi), as Praat's path finder does.
"""

from __future__ import annotations

import numpy as np

from cartoonface.speech.dsp import resample_poly

# Praat's standard values for To Pitch (ac) (Praat's manual, "Sound: To Pitch (ac)..."): the window
# is PERIODS periods of the pitch floor long; the candidates and the path's costs.
PERIODS = 3.0
CANDIDATES = 15  # the unvoiced one included ("Max. number of candidates")
SILENCE_THRESHOLD = 0.03  # frames whose peak is below this share of the recording's are silent
VOICING_THRESHOLD = 0.45  # the unvoiced candidate's strength in a loud frame
OCTAVE_COST = 0.01  # per octave: favours higher candidates (a perfectly periodic signal's own)
OCTAVE_JUMP_COST = 0.35  # per octave between voiced frames, for 10 ms steps
VOICED_UNVOICED_COST = 0.14  # per change of voicing, for 10 ms steps
COST_STEP = 0.01  # s: the step the two costs above are given for (Praat scales them by COST_STEP / step)
# Below this rate the recording is first up-sampled by a whole factor: the autocorrelation's
# parabolic interpolation is then as fine as Praat's sinc interpolation (the sample story at 8 kHz:
# 7 % of F0s over 1 % from Praat's, none once up-sampled to 16 kHz; none at 16 kHz or above).
MIN_RATE = 16000  # Hz
CHUNK = 128  # frames analysed at a time: their windows and spectra (~1 MB) are freed memory used again,
# where 2048 at a time (~30 MB) made fresh pages for each: 9,000-13,000 page faults against 2,000-3,400
# and 0.03 s more of CPU on 190 s


def pitch_track(samples: np.ndarray, rate: int, step: float, floor: float, ceiling: float) -> tuple[np.ndarray, np.ndarray]:
    """F0 of mono `samples` ((n,) float, any scale) at `rate` Hz, a frame every `step` s, between
    `floor` and `ceiling` Hz. Returns (times (m,) s, f0 (m,) Hz with NaN where unvoiced); m = 0
    when the recording is shorter than a window."""
    x = np.asarray(samples, dtype=np.float32)
    if rate < MIN_RATE:
        factor = -(-MIN_RATE // rate)
        x, rate = resample_poly(x, factor, 1).astype(np.float32, copy=False), rate * factor
    length = int(PERIODS / floor * rate) // 2 * 2  # window, samples (even, as Praat's)
    period = int(rate / floor)
    count = int(np.floor((len(x) / rate - PERIODS / floor) / step + 1e-9)) + 1 if len(x) >= length else 0
    if count < 1:
        return np.zeros(0), np.zeros(0)
    times = 0.5 * len(x) / rate + (np.arange(count) - 0.5 * (count - 1)) * step
    lefts = np.floor(times * rate - 0.5).astype(np.int64)  # the sample just before each frame's centre
    loudest = float(np.abs(x - np.float32(x.mean())).max())
    frequency, strength = _candidates(x, lefts, length, period, rate, loudest, floor, ceiling)
    return times, _path(frequency, strength, step)


def _candidates(x: np.ndarray, lefts: np.ndarray, length: int, period: int, rate: int, loudest: float,
                floor: float, ceiling: float) -> tuple[np.ndarray, np.ndarray]:
    """Each frame's candidates: (frequency, strength) (m, CANDIDATES) each, column 0 the unvoiced one
    (frequency NaN), the voiced ones' strength less the octave cost, missing ones NaN / -inf.
    `x`: the recording (float32); `lefts` (m,): the sample just before each frame's centre;
    `loudest`: the recording's largest distance from its mean."""
    half = length // 2
    size = 1 << int(length * 1.5 - 1).bit_length()  # room for lags up to half a window (Praat's depth 0.5)
    taper = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(1, length + 1) / (length + 1))
    own = np.fft.irfft(np.abs(np.fft.rfft(taper, size)) ** 2, size)[: half + 1]
    own /= own[0]
    top = min(int(length / PERIODS) + 2, half)  # the longest lag: a period of the floor
    lags = np.arange(2, top)
    windows = np.lib.stride_tricks.sliding_window_view(x, length)
    frequency = np.full((len(lefts), CANDIDATES), np.nan)
    strength = np.full((len(lefts), CANDIDATES), -np.inf)
    for first in range(0, len(lefts), CHUNK):
        rows = slice(first, min(first + CHUNK, len(lefts)))
        frames = windows[lefts[rows] - half + 1].astype(np.float64)  # (c, length)
        # the local mean over two floor periods about the centre, and the peak within half a period
        frames -= frames[:, half - period + 1: half + period + 1].mean(axis=1, keepdims=True)
        peak = np.abs(frames[:, half - period // 2: half + period // 2 + 2]).max(axis=1)
        intensity = np.minimum(peak / loudest, 1.0) if loudest > 0 else np.zeros(len(frames))
        strength[rows, 0] = VOICING_THRESHOLD + np.maximum(
            0.0, 2 - intensity / (SILENCE_THRESHOLD / (1 + VOICING_THRESHOLD)))
        frames *= taper
        spectrum = np.fft.rfft(frames, size, axis=1)
        ac = np.fft.irfft(spectrum.real ** 2 + spectrum.imag ** 2, size, axis=1)[:, : top + 1]
        zero = ac[:, :1] * own[: top + 1]
        r = np.divide(ac, zero, out=np.zeros_like(ac), where=zero > 0)
        here, before, after = r[:, 2:top], r[:, 1:top - 1], r[:, 3:top + 1]
        voiced = (here > 0.5 * VOICING_THRESHOLD) & (here > before) & (here >= after)
        rise, bend = 0.5 * (after - before), 2 * here - before - after
        bend[~voiced] = 1.0
        lag = lags + rise / bend
        value = here + 0.5 * rise * rise / bend
        np.divide(1.0, value, out=value, where=value > 1)  # high values of short windows reflected around 1
        voiced &= lag >= rate / ceiling
        # Praat ranks by strength less the octave cost (favouring high pitches) and keeps the strongest
        row, column = np.nonzero(voiced)
        ranked = value[row, column] - OCTAVE_COST * np.log2(ceiling / rate * lag[row, column])
        order = np.lexsort((-ranked, row))  # by frame, the strongest first
        row, column, ranked = row[order], column[order], ranked[order]
        place = np.arange(len(row)) - np.searchsorted(row, row)  # rank within its frame
        kept = place < CANDIDATES - 1
        row, column, place = row[kept] + first, column[kept], place[kept] + 1
        strength[row, place] = ranked[kept]
        frequency[row, place] = rate / lag[row - first, column]
    return frequency, strength


def _path(frequency: np.ndarray, strength: np.ndarray, step: float) -> np.ndarray:
    """The F0 (m,) (NaN: unvoiced) of the path through the candidates ((m, k) frequency and strength,
    _candidates') with the highest sum of strengths less the costs of its octave jumps and voicing
    changes (scaled to the frame step `step` s, as Praat does)."""
    scale = COST_STEP / step
    jump, change = OCTAVE_JUMP_COST * scale, VOICED_UNVOICED_COST * scale
    used = int(np.isfinite(strength).sum(axis=1).max())  # columns any frame fills (the unvoiced first)
    octave = np.log2(frequency[:, :used])
    gain = strength[:, :used]
    voiced = np.isfinite(octave)
    score = gain[0].copy()
    back = np.zeros((len(gain), used), dtype=np.int64)
    for first in range(1, len(gain), CHUNK):
        rows = slice(first, min(first + CHUNK, len(gain)))
        previous = slice(first - 1, rows.stop - 1)
        # cost[i, a, b]: from candidate a of frame i - 1 to candidate b of frame i
        both = voiced[previous, :, None] & voiced[rows, None, :]
        cost = np.where(both, jump * np.abs(np.nan_to_num(octave[previous, :, None] - octave[rows, None, :])),
                        np.where(voiced[previous, :, None] != voiced[rows, None, :], change, 0.0))
        moves = gain[rows, None, :] - cost
        for i, move in enumerate(moves, first):
            total = score[:, None] + move
            back[i] = total.argmax(axis=0)
            score = total.max(axis=0)
    f0 = np.empty(len(gain))
    choice = int(score.argmax())
    for i in range(len(gain) - 1, -1, -1):
        f0[i] = frequency[i, choice]
        choice = int(back[i, choice])
    return f0
