"""Frame features of speech for the syllable aligner: log-mel spectra, MFCCs, band energies.

Every function works on 16 kHz mono samples cut into 25 ms Hann windows every 10 ms
(frame i covers [i * 0.01, i * 0.01 + 0.025) s; its centre is at i * 0.01 + 0.0125 s).
"""

from __future__ import annotations

from dataclasses import dataclass
from math import gcd

import numpy as np

from cartoonface.speech.dsp import dct_matrix, resample_poly

RATE = 16000
HOP = 0.010          # seconds between frames
WINDOW = 400         # samples (25 ms at 16 kHz)
WINDOW_SECONDS = WINDOW / RATE
NFFT = 512
MELS = 40
CEPSTRA = 13
MEL_RANGE_HZ = (50.0, 7600.0)  # the mel filter bank's lowest and highest edge
PRE_EMPHASIS = 0.97            # x[n] - 0.97 x[n - 1] before the spectrum (the usual HTK/Kaldi value)
# Frequency bands (Hz) of Frames.low, .mid, .high: the first formant and voicing (stops and
# pauses silence it), the second formant, frication and bursts.
LOW_BAND = (100.0, 1000.0)
MID_BAND = (1000.0, 3000.0)
HIGH_BAND = (3000.0, 8000.0)
POWER_FLOOR = 1e-10   # added to a band's power before dB: digital silence is -100 dB
MEL_FLOOR = 1e-8      # added to a mel band's energy before its log
# Frames whose spectra are computed at a time: their windows and spectra (~1 MB) stay in the processor's
# cache (all of a 10 s part at once took ~1.5x as long, in a process's first calls; each frame's transform
# is its own, so the spectra are the same to the bit: tests/test_dsp.py).
SPECTRUM_ROWS = 128


@dataclass(frozen=True)
class Frames:
    """Features of one stretch of audio, one row per 10 ms frame.

    logmel: (T, 40) natural-log mel band energies; mfcc: (T, 13); energy: (T,) dB of the
    whole band; low, mid, high: (T,) dB of 100-1000, 1000-3000 and 3000-8000 Hz.
    """

    logmel: np.ndarray
    mfcc: np.ndarray
    energy: np.ndarray
    low: np.ndarray
    mid: np.ndarray
    high: np.ndarray


def to_rate(samples: np.ndarray, rate: int) -> np.ndarray:
    """Resample (n,) float samples from `rate` Hz to 16 kHz; returns float64 (m,)."""
    samples = np.asarray(samples, dtype=np.float64)
    if rate == RATE:
        return samples
    g = gcd(int(rate), RATE)
    return resample_poly(samples, RATE // g, int(rate) // g)


def mel_filters() -> np.ndarray:
    """Triangular mel filter bank, (NFFT // 2 + 1, 40), MEL_RANGE_HZ."""
    def mel(f):
        return 2595.0 * np.log10(1.0 + f / 700.0)  # O'Shaughnessy's mel scale

    lowest, highest = MEL_RANGE_HZ
    edges = 700.0 * (10 ** (np.linspace(mel(lowest), mel(highest), MELS + 2) / 2595.0) - 1.0)
    freqs = np.fft.rfftfreq(NFFT, 1.0 / RATE)
    bank = np.zeros((freqs.size, MELS))
    for m in range(MELS):
        lo, mid, hi = edges[m:m + 3]
        bank[:, m] = np.clip(np.minimum((freqs - lo) / (mid - lo), (hi - freqs) / (hi - mid)), 0.0, None)
    return bank


_BANK = mel_filters()
_DCT = dct_matrix(MELS, CEPSTRA)
_HANN = np.hanning(WINDOW)


def power_spectrum(samples: np.ndarray) -> np.ndarray:
    """(n,) 16 kHz samples -> (T, 257) power spectra of pre-emphasised Hann-windowed frames.

    T = max(1, 1 + (n - 400) // 160); shorter input is zero-padded to one frame.
    """
    x = np.append(samples[:1], samples[1:] - PRE_EMPHASIS * samples[:-1]) if samples.size else np.zeros(1)
    if x.size < WINDOW:
        x = np.pad(x, (0, WINDOW - x.size))
    hop = int(RATE * HOP)
    count = 1 + (x.size - WINDOW) // hop
    power = np.empty((count, NFFT // 2 + 1))
    windows = np.zeros((min(SPECTRUM_ROWS, count), NFFT))  # zero-padded to NFFT once, not by each rfft
    for first in range(0, count, SPECTRUM_ROWS):
        index = np.arange(WINDOW)[None, :] + hop * np.arange(first, min(first + SPECTRUM_ROWS, count))[:, None]
        rows = windows[:len(index)]
        np.multiply(x[index], _HANN, out=rows[:, :WINDOW])
        power[first:first + SPECTRUM_ROWS] = np.abs(np.fft.rfft(rows, axis=1)) ** 2
    return power


def band_db(power: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """(T, 257) power spectra -> (T,) dB of the energy between lo and hi Hz."""
    freqs = np.fft.rfftfreq(NFFT, 1.0 / RATE)
    band = (freqs >= lo) & (freqs < hi)
    return 10.0 * np.log10(power[:, band].sum(axis=1) + POWER_FLOOR)


def frames(samples: np.ndarray, rate: int) -> Frames:
    """(n,) mono samples at `rate` Hz -> Frames at 100 frames per second."""
    power = power_spectrum(to_rate(samples, rate))
    # einsum rather than a BLAS product: a small product on a loaded machine is slowed many
    # times by BLAS threads waiting for cores (measured in bench/align.py)
    logmel = np.log(np.einsum("tf,fm->tm", power, _BANK) + MEL_FLOOR)
    low, mid, high = _bands(power)
    return Frames(
        logmel=logmel,
        mfcc=np.einsum("tm,mc->tc", logmel, _DCT),  # the orthonormal DCT-II's first CEPSTRA
        energy=band_db(power, 0.0, RATE / 2),
        low=low,
        mid=mid,
        high=high,
    )


def bands(samples: np.ndarray, rate: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(n,) mono samples at `rate` Hz -> (T,) dB of LOW_BAND, MID_BAND and HIGH_BAND per 10 ms frame:
    Frames.low, .mid and .high alone (what the aligner reads), without the mel spectra's cost."""
    return _bands(power_spectrum(to_rate(samples, rate)))


def _bands(power: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(T, 257) power spectra -> (T,) dB of LOW_BAND, MID_BAND, HIGH_BAND."""
    return band_db(power, *LOW_BAND), band_db(power, *MID_BAND), band_db(power, *HIGH_BAND)


def smooth(x: np.ndarray, width: int) -> np.ndarray:
    """(T,) values -> (T,) their moving mean over `width` frames (edges repeated)."""
    return np.convolve(np.pad(x, width // 2, mode="edge"), np.ones(width) / width, mode="valid")
