"""The few filters of scipy.signal and scipy.fft that the speech analysis uses, in numpy.

Importing scipy.signal costs ~0.6 s of every `cartoonface generate` (it imports scipy.stats,
scipy.interpolate, ...) and scipy.fft ~0.15 s, for five functions. These give scipy's numbers
within float rounding (tests/test_dsp.py compares them on real speech):

- `butter_highpass` + `sos_filter_each`: scipy.signal.butter(order, cutoff, "highpass", fs=rate,
  output="sos") and scipy.signal.sosfilt (zero initial state) on each of several signals;
- `resample_poly`: scipy.signal.resample_poly with its defaults (Kaiser window, beta 5; zeros
  outside the signal);
- `find_peaks`: scipy.signal.find_peaks with `distance` and `prominence` only;
- `dct_matrix`: scipy.fft.dct(type=2, norm="ortho") as a matrix (x @ dct_matrix(n)).
"""

from __future__ import annotations

from collections.abc import Sequence
from math import gcd

import numpy as np

# The IIR filter runs as the FIR of its impulse response, cut where the response's envelope
# (the largest pole radius to the power n) has fallen below DECAY: far below float64 rounding.
DECAY = 1e-20
# FFT length of the overlap-add blocks of `sos_filter_each` (at least 4x the impulse response):
# 2**14 was the fastest of 2**13..2**16 on 190 s at 16 kHz, and a whole-signal FFT was 5x slower.
BLOCK = 1 << 14
# Blocks filtered at a time: 8 x 2**14 x 16 bytes, 2 MB of spectra, stay in the processor's cache (64 took
# 2.5x as long on a process's first call, 145 against 58 ms of CPU on 190 s at 16 kHz; each block is
# transformed on its own, so the output is the same to the bit: tests/test_dsp.py).
GROUP = 8
# resample_poly's default FIR: a windowed sinc of 2 * HALF_LENGTH * max(up, down) + 1 taps,
# Kaiser window with this beta (scipy.signal.resample_poly, window=("kaiser", 5.0)).
HALF_LENGTH = 10
KAISER_BETA = 5.0
CHUNK = 1 << 18  # outputs of resample_poly computed at a time (the samples they read: a few MB)


def butter_highpass(order: int, cutoff: float, rate: float) -> np.ndarray:
    """Second-order sections (sections, 6) [b0, b1, b2, 1, a1, a2] of a digital Butterworth
    high-pass of `order` with its -3 dB point at `cutoff` Hz for samples at `rate` Hz.

    The analog prototype's poles lie evenly on the left half of the unit circle; the cutoff is
    pre-warped, the low-pass turned into a high-pass (s -> w / s: the zeros at s = 0) and mapped
    by the bilinear transform (zeros at z = 1); each conjugate pair of poles is one section, a
    real pole (odd order) a first-order one; the gain sits in the first section, as scipy's."""
    k = np.arange(1, order + 1)
    prototype = np.exp(1j * np.pi * (2 * k + order - 1) / (2 * order))
    warped = 2 * rate * np.tan(np.pi * cutoff / rate)
    analog = warped / prototype
    poles = (2 * rate + analog) / (2 * rate - analog)
    gain = float(np.real((2 * rate) ** order / np.prod(2 * rate - analog)))
    sections = [[1.0, -2.0, 1.0, 1.0, -2 * pole.real, abs(pole) ** 2] for pole in poles[: order // 2]]
    if order % 2:
        sections.append([1.0, -1.0, 0.0, 1.0, -poles[order // 2].real, 0.0])
    sos = np.array(sections)
    sos[0, :3] *= gain
    return sos


def sos_filter_each(sos: np.ndarray, pieces: Sequence[np.ndarray], dtype: type = np.float64) -> list[np.ndarray]:
    """Each of `pieces` ((n_i,) samples) through the stable IIR sections `sos` (sections, 6) from a
    zero state, as scipy.signal.sosfilt on each, in one pass, given as `dtype` (the sums run in
    float64): the pieces are joined with zeros
    between them as long as the impulse response, so each piece's response has died out (below
    DECAY) before the next begins.

    numpy has no recursive filter, and a loop in Python would take seconds; the filter's response
    is applied in the frequency domain instead, block by block (overlap-add), the blocks longer
    than the impulse response's tail, so no block's output wraps around; GROUP blocks at a time,
    so the temporary spectra stay small on long recordings."""
    tail = settling(sos)
    starts = np.cumsum([0] + [len(piece) + tail for piece in pieces])
    length = int(starts[-1]) - tail
    size = min(max(BLOCK, _power_of_two(4 * tail)), max(_power_of_two(length + tail), _power_of_two(2 * tail)))
    hop = size - tail
    dtype_in = np.result_type(np.float32, *pieces)
    if len(pieces) == 1:  # nothing to join: read in place (a fresh copy of 3 minutes is 12 MB of page faults)
        joined = np.asarray(pieces[0], dtype=dtype_in)
    else:
        joined = np.zeros(max(length, 0), dtype=dtype_in)
        for start, piece in zip(starts, pieces):
            joined[start : start + len(piece)] = piece
    delay = np.exp(-2j * np.pi * np.fft.rfftfreq(size))  # z ** -1 on the FFT's frequencies
    response = np.ones(len(delay), dtype=complex)
    for section in sos:
        response *= np.polyval(section[2::-1], delay) / np.polyval(section[5:2:-1], delay)
    out: np.ndarray = np.empty(len(joined), dtype=dtype)
    carry = np.zeros(tail)  # the last block's output beyond its hop, added to the next block's start
    for first in range(0, len(joined), GROUP * hop):
        chunk = joined[first : first + GROUP * hop]
        count = -(-len(chunk) // hop)
        padded = np.zeros(count * hop)
        padded[: len(chunk)] = chunk
        blocks = np.fft.irfft(np.fft.rfft(padded.reshape(count, hop), size, axis=1) * response, size, axis=1)
        body = blocks[:, :hop].copy()
        body[1:, :tail] += blocks[:-1, hop:]
        body[0, :tail] += carry
        carry = blocks[-1, hop:]
        out[first : first + len(chunk)] = body.ravel()[: len(chunk)]
    return [out[start : start + len(piece)] for start, piece in zip(starts, pieces)]


def settling(sos: np.ndarray) -> int:
    """Samples after which the impulse response of the stable sections `sos` (sections, 6) has died
    out: its envelope (the largest pole radius to the power n) is below DECAY. The filter's output
    that many samples into a signal no longer depends on where the signal started."""
    radius = max(float(np.abs(np.roots(section[3:])).max(initial=0.0)) for section in sos)
    return int(np.ceil(np.log(DECAY) / np.log(radius))) if radius > 0 else 3 * len(sos)


def _power_of_two(n: int) -> int:
    """The smallest power of two >= n (n >= 1)."""
    return 1 << (int(n) - 1).bit_length()


def lowpass_fir(taps: int, cutoff: float) -> np.ndarray:
    """(taps,) linear-phase low-pass FIR: a sinc cut at `cutoff` (share of the Nyquist frequency),
    Kaiser window (KAISER_BETA), gain 1 at 0 Hz; scipy.signal.firwin(taps, cutoff, window=("kaiser", 5.0))."""
    m = np.arange(taps) - (taps - 1) / 2
    h = cutoff * np.sinc(cutoff * m) * np.kaiser(taps, KAISER_BETA)
    return h / h.sum()


def resample_poly(samples: np.ndarray, up: int, down: int) -> np.ndarray:
    """(n,) samples at rate r -> (ceil(n * up / down),) at r * up / down, as scipy.signal.resample_poly
    with its defaults: up-sampled by `up` (zeros between samples), low-passed by `lowpass_fir`
    (scaled by `up`) centred on each output, down-sampled by `down`. Float input keeps its dtype
    (the sums run in float64); other input gives float64.

    Polyphase: output m sits at t = m * down + half (half: the filter's centre) of the up-sampled
    signal, where only the filter taps t - up * i, those of phase t mod up, meet samples: output
    m = sum_k h[t mod up + up * k] * x[t // up - k]. The outputs of one phase are every up-th one,
    and their samples advance by `down`: one strided matrix-vector product per phase, over CHUNK
    outputs at a time (the samples they read copied as float64)."""
    samples = np.asarray(samples)
    dtype = samples.dtype if samples.dtype.kind == "f" else np.dtype(np.float64)
    g = gcd(int(up), int(down))
    up, down = int(up) // g, int(down) // g
    if up == down == 1:
        return samples.astype(dtype, copy=True)
    half = HALF_LENGTH * max(up, down)
    h = lowpass_fir(2 * half + 1, 1.0 / max(up, down)) * up
    taps = -(-len(h) // up)  # taps per phase
    h = np.concatenate((h, np.zeros(taps * up - len(h))))
    n_out = -(-len(samples) * up // down)
    out = np.empty(n_out, dtype=dtype)
    step = up * max(1, CHUNK // up)  # outputs per chunk: whole periods of the phases
    for begin in range(0, n_out, step):
        end = min(begin + step, n_out)
        # the samples outputs begin..end-1 read, zeros beyond the signal
        low, high = (begin * down + half) // up - taps + 1, ((end - 1) * down + half) // up + 1
        segment = np.zeros(high - low)
        inside = slice(max(low, 0), min(high, len(samples)))
        segment[inside.start - low : inside.stop - low] = samples[inside]
        windows = np.lib.stride_tricks.sliding_window_view(segment, taps)  # windows[s] = x[low + s:][:taps]
        for first in range(begin, min(begin + up, end)):
            t = first * down + half
            rows = windows[t // up - taps + 1 - low :: down][: len(range(first, end, up))]
            out[first:end:up] = rows @ h[t % up :: up][::-1]
    return out


def find_peaks(x: np.ndarray, distance: int = 1, prominence: float = 0.0) -> np.ndarray:
    """Indices (k,) of the peaks of `x` (n,), in order, as scipy.signal.find_peaks(x, distance=,
    prominence=)[0]: local maxima (a flat top's middle, rounded down; not at either end), of which
    the highest are kept first and those nearer than `distance` samples to a kept one dropped; then
    those whose prominence (height above the higher of the lowest points on either side before a
    higher sample or the end) is below `prominence`."""
    x = np.asarray(x, dtype=np.float64)
    peaks = _local_maxima(x)
    if distance > 1 and len(peaks) > 1:
        peaks = peaks[_apart(peaks, x[peaks], int(np.ceil(distance)))]
    return np.array([p for p in peaks if _prominence(x, int(p)) >= prominence], dtype=np.intp)


def _local_maxima(x: np.ndarray) -> np.ndarray:
    """Indices of the samples (or middles of flat runs) higher than both neighbours' runs, in order;
    runs at either end of `x` do not count."""
    if len(x) < 3:
        return np.zeros(0, dtype=np.intp)
    starts = np.flatnonzero(np.concatenate(([True], x[1:] != x[:-1])))
    ends = np.append(starts[1:], len(x)) - 1
    values = x[starts]
    inner = np.arange(1, len(starts) - 1)
    top = inner[(values[inner - 1] < values[inner]) & (values[inner + 1] < values[inner])]
    return (starts[top] + ends[top]) // 2


def _apart(peaks: np.ndarray, heights: np.ndarray, distance: int) -> np.ndarray:
    """Boolean mask (k,) of the peaks kept: from the highest down (ties in np.argsort's order, as
    scipy), each peak still kept drops its neighbours closer than `distance`."""
    keep = np.ones(len(peaks), dtype=bool)
    for j in np.argsort(heights)[::-1]:
        if not keep[j]:
            continue
        k = j - 1
        while k >= 0 and peaks[j] - peaks[k] < distance:
            keep[k] = False
            k -= 1
        k = j + 1
        while k < len(peaks) and peaks[k] - peaks[j] < distance:
            keep[k] = False
            k += 1
    return keep


def _prominence(x: np.ndarray, peak: int) -> float:
    """x[peak] minus the higher of the minima of x on either side up to a higher sample (or the end)."""
    higher = np.flatnonzero(x > x[peak])
    cut = np.searchsorted(higher, peak)
    left = higher[cut - 1] + 1 if cut > 0 else 0
    right = higher[cut] if cut < len(higher) else len(x)
    return float(x[peak] - max(x[left : peak + 1].min(), x[peak:right].min()))


def dct_matrix(n: int, keep: int | None = None) -> np.ndarray:
    """(n, keep) matrix D with x @ D = scipy.fft.dct(x, type=2, norm="ortho")[..., :keep] for x (..., n):
    D[i, k] = sqrt(2 / n) cos(pi k (2 i + 1) / (2 n)), the k = 0 column scaled by 1 / sqrt(2)."""
    k = np.arange(n if keep is None else keep)
    i = np.arange(n)[:, None]
    matrix = np.sqrt(2.0 / n) * np.cos(np.pi * k * (2 * i + 1) / (2 * n))
    matrix[:, 0] /= np.sqrt(2.0)
    return matrix
