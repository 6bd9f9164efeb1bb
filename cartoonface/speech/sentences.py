"""Sentence utterances by silence (thesis 002, section 3.2, Alg. 3.1).

Two modes:

* the thesis's mode (`pause=(start, end)`): the user selects the first
  pause between sentences; its loudest frame V and its length give the noise
  level V * c2 and the shortest sentence pause (end - start) * c1;
* the automatic mode (default): the noise floor and the speech level are
  learned from the distribution of frame energies of the whole recording,
  speech is told from noise by voicing, and the shortest sentence pause is
  learned from the lengths of the pauses in the recording. No initial
  silence is needed. docs/alignment.md explains the rules and constants.

Both work on the energy of 10 ms frames of the recording high-passed at
80 Hz (damping rumble and the fundamental of mains hum), which takes about
two seconds for 30 minutes of audio.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cartoonface.errors import OptionError
from cartoonface.speech.audio import MIN_RECORDED, Audio, digital_silence
from cartoonface.speech.dsp import butter_highpass, find_peaks, resample_poly, settling, sos_filter_each

# thesis 002, Alg. 3.1 step 3 and the paragraph after it: c1 = 0.95.
C1 = 0.95
# thesis 002, Alg. 3.1 step 4 and the paragraph after it: c2 = 1.45. The
# thesis says "volume" without a unit; we apply c2 to the linear RMS
# amplitude of a frame (+3.2 dB), because a product on a dB scale depends on
# the arbitrary reference level (45 dB * 1.45 = 65 dB would swallow speech).
C2 = 1.45

HOP = 0.01  # seconds per energy frame
SMOOTH_FRAMES = 3  # frame energies are smoothed over this many frames (30 ms)
HIGH_PASS_HZ = 80.0  # damps rumble and the 50/60 Hz fundamental of mains hum in the energy
HIGH_PASS_ORDER = 2  # Butterworth order of that high-pass
# Automatic mode: frames louder than floor + max(MIN_CONTRAST_DB, SHARE * (speech - floor)) are sound.
# The floor is a percentile of the frames that hold recorded sound (not digital silence).
FLOOR_PERCENTILE = 5.0
SPEECH_PERCENTILE = 98.0
MIN_CONTRAST_DB = 6.0
THRESHOLD_SHARE = 0.3
# Sound runs closer than this belong to one syllable group (consonant closures are shorter).
JOIN_GAP = 0.15
# A group is speech when at least VOICED_MIN seconds of it are voiced (Mandarin syllables all carry a voiced final).
VOICED_MIN = 0.05
VOICING_R = 0.5  # normalised autocorrelation peak at a pitch lag (70..400 Hz) that counts as voiced
PITCH_RANGE_HZ = (70.0, 400.0)
VOICING_RATE = 8000  # Hz: voicing is measured on the audio decimated to about this rate
VOICING_WINDOW = 0.04  # seconds of audio per voicing measurement (two periods at 50 Hz)
VOICING_STEP = 2  # voicing is measured on every second 10 ms frame (half the cost, 20 ms resolution)
# Windows measured per FFT block: their spectra (256 x 512 x 16 bytes, 2 MB) stay in the processor's cache
# (4096 took 1.8x as long, ~95 against ~53 ms of CPU on 190 s; each window's transform is its own, so the
# voicing is the same to the bit: tests/test_sentences.py).
VOICING_CHUNK = 256
# Frames whose mean squares are computed at a time: their float64 squares (1.3 MB at 16 kHz) stay in the
# processor's cache, where all of 190 s at once made 24 MB of fresh memory.
POWER_ROWS = 1024
# Unvoiced sound kept before the first / after the last voiced frame of a group (fricatives, aspiration).
UNVOICED_EDGE = 0.2
# A group whose loudest frame is this far below the speech level is a click or a breath, not speech.
GROUP_BELOW_SPEECH_DB = 25.0
# Learned sentence pause: kept between these bounds (a pause of PAUSE_MAX or more always ends a part).
PAUSE_MIN, PAUSE_MAX = 0.25, 0.6
# Pause classes whose geometric means differ less than this are one class. A class of pauses
# whose geometric mean is SENTENCE_PAUSE or more holds pauses between sentences.
CLUSTER_RATIO = 1.5
SENTENCE_PAUSE = 0.35
# Silence kept around each speaking part, so soft onsets and releases are not cut.
PAD = 0.05
# Thesis mode: a selected pause whose noise level V * c2 reaches this share of the speech peaks
# (99th percentile of frame RMS) holds speech, not silence, and is refused.
LOUD_PAUSE = 0.5
PEAK_PERCENTILE = 99.0
POWER_EPSILON = 1e-12  # added to a frame's mean square before taking dB (-120 dB: digital silence)
# Parts shorter than this are clicks, not speech (both modes).
MIN_PART = 0.06
# Split candidates inside a part (dips): at least DIP_MARGIN s from its ends, on the energy
# smoothed over DIP_SMOOTH_FRAMES frames, at least DIP_DISTANCE s apart and DIP_PROMINENCE_DB
# deep; a dip's plateau is how long the energy stays within PLATEAU_DB of its minimum.
DIP_MARGIN = 0.25
DIP_SMOOTH_FRAMES = 5
DIP_DISTANCE = 0.12
DIP_PROMINENCE_DB = 3.0
PLATEAU_DB = 6.0


@dataclass(frozen=True)
class Span:
    """A stretch of the recording from `start` to `end` seconds."""

    start: float
    end: float

    @property
    def duration(self) -> float:
        """Length in seconds."""
        return self.end - self.start


def find_speech_parts(audio: Audio, pause: tuple[float, float] | None = None,
                      filtered: np.ndarray | None = None) -> tuple[Span, ...]:
    """Split `audio` into speaking parts separated by sentence pauses (Alg. 3.1).

    `pause` = (start, end) seconds of the first pause between sentences
    selects the thesis's mode; None (default) the automatic mode. `filtered`: `high_passed(audio)`
    when the caller has it (it also serves `all_dips`). Returns the
    speaking parts in time order (possibly one part covering all speech).
    Raises OptionError when `pause` lies outside the recording or is empty.
    """
    power = _frame_power(high_passed(audio) if filtered is None else filtered, audio.rate)
    if pause is not None:
        return _thesis_parts(audio, power, pause)
    return _automatic_parts(audio, power)


def frame_power(audio: Audio) -> np.ndarray:
    """Mean square of each 10 ms frame of the 80 Hz high-passed audio, smoothed over 30 ms; shape (frames,)."""
    return _frame_power(high_passed(audio), audio.rate)


def high_passed(audio: Audio) -> np.ndarray:
    """(n,) float32: the samples of `audio` high-passed at HIGH_PASS_HZ from a zero state."""
    return _high_passed(audio.rate, [audio.samples])[0]


def _high_passed(rate: int, pieces: list[np.ndarray]) -> list[np.ndarray]:
    """Each of `pieces` ((n_i,) samples at `rate` Hz) high-passed at HIGH_PASS_HZ from a zero state, float32."""
    sos = butter_highpass(HIGH_PASS_ORDER, HIGH_PASS_HZ, rate)
    return sos_filter_each(sos, pieces, np.float32)


def _frame_power(filtered: np.ndarray, rate: int) -> np.ndarray:
    """(n,) high-passed float32 samples at `rate` Hz -> frame_power's (frames,) smoothed mean squares."""
    hop = max(1, round(rate * HOP))
    count = max(1, len(filtered) // hop)
    samples = np.asarray(filtered, dtype=np.float32)
    if len(samples) < hop:  # one frame, zero-padded
        samples = np.concatenate([samples, np.zeros(hop - len(samples), dtype=np.float32)])
    frames = samples[:count * hop].reshape(count, hop)
    power = np.empty(count)
    for first in range(0, count, POWER_ROWS):  # each row's mean on its own: the same bits in any batch
        power[first:first + POWER_ROWS] = np.mean(np.square(frames[first:first + POWER_ROWS], dtype=np.float64), axis=1)
    return np.convolve(power, np.ones(SMOOTH_FRAMES) / SMOOTH_FRAMES, mode="same")


def _thesis_parts(audio: Audio, power: np.ndarray, pause: tuple[float, float]) -> tuple[Span, ...]:
    """Alg. 3.1 steps 2-8 with the user's first pause."""
    start, end = (float(value) for value in pause)
    if not (0 <= start < end <= audio.duration) or end - start < 2 * HOP:
        raise OptionError(
            f"pause {start:g},{end:g}: expected START,END seconds of the first pause between sentences, "
            f"with 0 <= START < END <= {audio.duration:.2f} (the recording's length)"
        )
    rms = np.sqrt(power)
    inside = rms[int(np.ceil(start / HOP)) : max(int(np.ceil(start / HOP)) + 1, int(end / HOP))]
    v_noise = float(inside.max()) * C2  # steps 2 and 4
    d_pause = (end - start) * C1  # step 3
    if v_noise >= LOUD_PAUSE * np.percentile(rms, PEAK_PERCENTILE):
        raise OptionError(
            f"pause {start:g},{end:g}: not a silence (its loudest frame is as loud as the speech); "
            "expected START,END of the quiet pause between the first two sentences"
        )
    # Steps 5-8: silences (quieter than v_noise) of at least d_pause; the rest are speaking parts.
    # The whole recording is searched (not only from t_s), so a leading silence is cut off too.
    sounding = _runs(rms >= v_noise)
    if not sounding:
        return ()
    parts = _join(sounding, round(d_pause / HOP))
    return tuple(
        Span(round(first * HOP, 3), round(min(last * HOP, audio.duration), 3))
        for first, last in parts
        if (last - first) * HOP >= MIN_PART
    )


def _automatic_parts(audio: Audio, power: np.ndarray) -> tuple[Span, ...]:
    """Speaking parts with the noise floor, speech level and pause length learned from the recording."""
    level = 10 * np.log10(power + POWER_EPSILON)
    floor = float(np.percentile(_recorded(audio, level), FLOOR_PERCENTILE))
    loud = float(np.percentile(level, SPEECH_PERCENTILE))
    threshold = floor + max(MIN_CONTRAST_DB, THRESHOLD_SHARE * (loud - floor))
    runs = _runs(level > threshold)
    if not runs:
        return ()
    groups = _join(runs, round(JOIN_GAP / HOP))
    voiced = _voiced_frames(audio, groups)
    speech = []
    for (first, last), flags in zip(groups, voiced, strict=True):
        hits = np.flatnonzero(flags)  # voicing is measured on every VOICING_STEP-th frame
        if len(hits) * HOP * VOICING_STEP < VOICED_MIN or level[first:last].max() < loud - GROUP_BELOW_SPEECH_DB:
            continue
        edge = round(UNVOICED_EDGE / HOP)
        speech.append((max(first, first + hits[0] * VOICING_STEP - edge),
                       min(last, first + hits[-1] * VOICING_STEP + 1 + edge)))
    if not speech:
        return ()
    gaps = np.array([(b[0] - a[1]) * HOP for a, b in zip(speech, speech[1:])])
    parts = _join(speech, round(learn_pause(gaps) / HOP))
    spans = []
    for index, (first, last) in enumerate(parts):
        before = parts[index - 1][1] if index else 0
        after = parts[index + 1][0] if index + 1 < len(parts) else len(level)
        start = max(first - round(PAD / HOP), (before + first) // 2 if index else 0) * HOP
        end = min(last + round(PAD / HOP), (last + after) // 2 if index + 1 < len(parts) else len(level)) * HOP
        spans.append(Span(round(start, 3), round(min(end, audio.duration), 3)))
    return tuple(span for span in spans if span.duration >= MIN_PART)


def _recorded(audio: Audio, level: np.ndarray) -> np.ndarray:
    """The frame levels (frames,) of `audio` without its digital silence (audio.DIGITAL_SILENCE):
    exact zeros, a gate's near-zero or a constant are no noise floor. All of them when fewer
    than MIN_RECORDED of the frames hold recorded sound."""
    dead = np.zeros(len(level), dtype=bool)
    blocks = digital_silence(audio.samples, audio.rate, HOP)[: len(level)]
    dead[: len(blocks)] = blocks
    return level if np.mean(~dead) < MIN_RECORDED else level[~dead]


def learn_pause(gaps: np.ndarray) -> float:
    """The shortest sentence pause (seconds) learned from the pause lengths `gaps` (seconds, any order).

    The log pause lengths are split into a short and a long class by Otsu's
    rule (largest between-class variance); classes less than CLUSTER_RATIO
    apart are one class. When the short (or only) class is short (geometric
    mean below SENTENCE_PAUSE) it holds pauses inside sentences: the
    threshold lies midway (in log) between the classes, or is PAUSE_MAX
    without a long class. Otherwise every pause is a sentence pause: the
    threshold is 0.95 (c1 of Alg. 3.1) of the shortest. No pauses: PAUSE_MAX.
    The result is kept within PAUSE_MIN..PAUSE_MAX.
    """
    values = np.log(np.sort(gaps[gaps > 0]))
    if len(values) == 0:
        return PAUSE_MAX
    count = len(values)
    short_count = count
    if count > 1:
        left = np.arange(1, count)
        left_mean = np.cumsum(values)[:-1] / left
        right_mean = (values.sum() - np.cumsum(values)[:-1]) / (count - left)
        best = int(np.argmax(left * (count - left) * (right_mean - left_mean) ** 2))
        if right_mean[best] - left_mean[best] >= np.log(CLUSTER_RATIO):
            short_count = best + 1
    if values[:short_count].mean() >= np.log(SENTENCE_PAUSE):
        threshold = C1 * np.exp(values[0])
    elif short_count < count:
        threshold = np.exp((values[short_count - 1] + values[short_count]) / 2)
    else:
        threshold = PAUSE_MAX
    return float(np.clip(threshold, PAUSE_MIN, PAUSE_MAX))


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Half-open index ranges [first, last) where the boolean `mask` (n,) is True, in order."""
    padded = np.concatenate(([False], mask, [False])).astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))


def _join(runs: list[tuple[int, int]], max_gap: int) -> list[tuple[int, int]]:
    """Merge frame ranges separated by fewer than `max_gap` frames."""
    joined = [list(runs[0])]
    for first, last in runs[1:]:
        if first - joined[-1][1] < max_gap:
            joined[-1][1] = last
        else:
            joined.append([first, last])
    return [(first, last) for first, last in joined]


def _voiced_frames(audio: Audio, groups: list[tuple[int, int]]) -> list[np.ndarray]:
    """For each frame range in `groups`, a boolean array: voicing of every VOICING_STEP-th 10 ms frame.

    Voiced = the normalised autocorrelation of a 40 ms window (audio low-passed
    and decimated to about 8 kHz) peaks above VOICING_R at a lag of a pitch in
    PITCH_RANGE_HZ.
    """
    factor = max(1, audio.rate // VOICING_RATE)
    low = resample_poly(audio.samples, 1, factor).astype(np.float32, copy=False) if factor > 1 else audio.samples
    rate = audio.rate / factor
    window = round(VOICING_WINDOW * rate)
    hop = rate * HOP
    lag_lo, lag_hi = int(rate / PITCH_RANGE_HZ[1]), int(np.ceil(rate / PITCH_RANGE_HZ[0]))
    # the circular autocorrelation equals the linear one up to lag_hi when nfft >= window + lag_hi
    nfft = 1 << int(window + lag_hi - 1).bit_length()
    padded = np.concatenate((low, np.zeros(window, dtype=np.float32)))
    frames_of = [np.arange(first, last, VOICING_STEP) for first, last in groups]
    every = np.concatenate(frames_of)
    starts = np.minimum((every * hop).astype(np.int64), len(low) - 1)
    result = np.empty(len(every), dtype=bool)
    correction = window / (window - np.arange(lag_lo, lag_hi + 1))
    taper = np.hanning(window)
    windows = np.zeros((min(VOICING_CHUNK, len(every)), nfft))  # zero-padded to nfft once, not by each rfft
    for chunk in range(0, len(every), VOICING_CHUNK):
        idx = starts[chunk : chunk + VOICING_CHUNK, None] + np.arange(window)
        block = padded[idx]
        block = block - block.mean(axis=1, keepdims=True)
        rows = windows[: len(idx)]
        np.multiply(block, taper, out=rows[:, :window])
        spectrum = np.fft.rfft(rows, axis=1)
        acf = np.fft.irfft(spectrum.real ** 2 + spectrum.imag ** 2, n=nfft, axis=1)  # no square root
        energy = np.maximum(acf[:, 0], 1e-12)
        peak = np.max(acf[:, lag_lo : lag_hi + 1] * correction, axis=1) / energy
        result[chunk : chunk + VOICING_CHUNK] = peak > VOICING_R
    split = np.cumsum([len(f) for f in frames_of])[:-1]
    return np.split(result, split)


def dips(audio: Audio, span: Span, margin: float = DIP_MARGIN) -> tuple[tuple[float, float], ...]:
    """Candidate places to split the speaking part `span`: local energy minima inside it.

    Returns (time seconds, plateau seconds) pairs, time order, at least
    `margin` seconds from either end; `plateau` is how long the energy stays
    within PLATEAU_DB of the minimum, so a real pause scores longer than a dip
    between two syllables.
    """
    return all_dips(audio, (span,), margin)[0]


def all_dips(audio: Audio, spans: tuple[Span, ...], margin: float = DIP_MARGIN,
             filtered: np.ndarray | None = None) -> list[tuple[tuple[float, float], ...]]:
    """`dips` of each of `spans`, each part high-passed on its own (from a zero state) but all in one
    pass; `filtered`: `high_passed(audio)`, when the caller has it, gives the parts for less work."""
    cuts = [(int(span.start * audio.rate), int(span.end * audio.rate)) for span in spans]
    parts = (_high_passed(audio.rate, [audio.samples[first:last] for first, last in cuts]) if filtered is None
             else _restarted(audio, filtered, cuts))
    return [_dips(_frame_power(part, audio.rate), span, margin) if len(part) / audio.rate >= 2 * margin + HOP else ()
            for part, span in zip(parts, spans, strict=True)]


def _restarted(audio: Audio, filtered: np.ndarray, cuts: list[tuple[int, int]]) -> list[np.ndarray]:
    """The samples [first, last) of each of `cuts` high-passed from a zero state, from `filtered` ((n,),
    the whole recording high-passed): past the filter's settling time (dsp.settling, ~0.13 s at 16 kHz)
    into a part the two agree (the response to the samples before the part has died out, below
    dsp.DECAY), so only each part's first samples are filtered again, on their own (as float rounding)."""
    settle = settling(butter_highpass(HIGH_PASS_ORDER, HIGH_PASS_HZ, audio.rate))
    heads = _high_passed(audio.rate, [audio.samples[first:min(first + settle, last)] for first, last in cuts])
    return [np.concatenate((head, filtered[first + len(head):last])) for head, (first, last) in zip(heads, cuts)]


def _dips(power: np.ndarray, span: Span, margin: float) -> tuple[tuple[float, float], ...]:
    """`dips` of the part `span` from its frame_power (frames,)."""
    level = 10 * np.log10(power + POWER_EPSILON)
    level = np.convolve(level, np.ones(DIP_SMOOTH_FRAMES) / DIP_SMOOTH_FRAMES, mode="same")
    edge = round(margin / HOP)
    minima = find_peaks(-level[edge:-edge], distance=round(DIP_DISTANCE / HOP), prominence=DIP_PROMINENCE_DB)
    found = []
    for index in minima + edge:
        near = level <= level[index] + PLATEAU_DB
        left = index
        while left > 0 and near[left - 1]:
            left -= 1
        right = index
        while right + 1 < len(level) and near[right + 1]:
            right += 1
        found.append((round(span.start + (left + right + 1) / 2 * HOP, 3), (right - left + 1) * HOP))
    return tuple(found)
