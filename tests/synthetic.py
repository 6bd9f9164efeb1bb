"""Synthetic inputs shared by tests and benchmarks."""

from __future__ import annotations

import io
import wave

import numpy as np

from cartoonface.face.mouth import MOUTH_SYMBOLS
from cartoonface.speech.audio import Audio
from cartoonface.speech.records import Alignment, Sentence, Syllable
from cartoonface.speech.sentences import Span


RATE = 16000  # Hz: sample rate of the synthetic recordings below


def syllables(count: int, seed: int, level: float = 0.3) -> np.ndarray:
    """`count` speech-like syllables: voiced harmonic tones 0.16-0.26 s with 30-60 ms gaps; float32 samples."""
    rng = np.random.default_rng(seed)
    pieces = []
    for _ in range(count):
        length = rng.uniform(0.16, 0.26)
        t = np.arange(int(length * RATE)) / RATE
        f0 = rng.uniform(110, 230) * (1 + 0.15 * t / length * rng.choice([-1, 1]))
        phase = 2 * np.pi * np.cumsum(f0) / RATE
        tone = sum(np.sin(k * phase) / k for k in range(1, 8))
        envelope = np.sin(np.pi * t / length) ** 0.5
        pieces.append(level * rng.uniform(0.5, 1.0) * tone / 2.6 * envelope)
        pieces.append(np.zeros(int(rng.uniform(0.03, 0.06) * RATE)))
    return np.concatenate(pieces[:-1]).astype(np.float32)


def recording(
    counts: list[int], pauses: list[float], lead: float = 0.5, tail: float = 0.5, seed: int = 1
) -> tuple[np.ndarray, list[Span]]:
    """Sentences of `counts` syllables separated by `pauses` seconds; returns (samples, true spans)."""
    parts = [np.zeros(int(lead * RATE), np.float32)]
    truth: list[Span] = []
    position = lead
    for index, count in enumerate(counts):
        sentence = syllables(count, seed + index)
        truth.append(Span(position, position + len(sentence) / RATE))
        parts.append(sentence)
        position += len(sentence) / RATE
        gap = pauses[index] if index < len(pauses) else tail
        parts.append(np.zeros(int(gap * RATE), np.float32))
        position += int(gap * RATE) / RATE
    return np.concatenate(parts), truth


def noisy(samples: np.ndarray, snr_db: float = 40.0, seed: int = 0) -> Audio:
    """`samples` plus white noise `snr_db` below their RMS over the loud parts, as an Audio."""
    rng = np.random.default_rng(seed)
    loud = np.sqrt(np.mean(samples[np.abs(samples) > 0.01] ** 2))
    noise = rng.normal(0, loud * 10 ** (-snr_db / 20), len(samples))
    return Audio((samples + noise).astype(np.float32), RATE, "synthetic")


def synthetic_talk(duration: float, seed: int = 0) -> Alignment:
    """An alignment of `duration` seconds: sentences of 4-12 syllables of 0.15-0.35 s with
    1-4 random mouth shapes each, separated by 0.4-1.0 s pauses, starting at 0.6 s."""
    rng = np.random.default_rng(seed)
    sentences, t = [], 0.6
    while t < duration - 5:
        syllables = []
        for _ in range(int(rng.integers(4, 13))):
            length = float(rng.uniform(0.15, 0.35))
            shapes = tuple(str(s) for s in rng.choice(MOUTH_SYMBOLS, size=int(rng.integers(1, 5))))
            syllables.append(Syllable("x", "x1", shapes, round(t, 3), round(t + length, 3), 1.0))
            t += length
        sentences.append(Sentence("s", syllables[0].start, syllables[-1].end, tuple(syllables)))
        t += float(rng.uniform(0.4, 1.0))
    return Alignment(tuple(sentences), duration, ())


def wav_bytes(samples: np.ndarray, rate: int) -> bytes:
    """16-bit mono WAV bytes of float samples in [-1, 1]."""
    buffer = io.BytesIO()
    with wave.open(buffer, "wb") as out:
        out.setnchannels(1)
        out.setsampwidth(2)
        out.setframerate(rate)
        out.writeframes((np.clip(samples, -1, 1) * 32767).astype("<i2").tobytes())
    return buffer.getvalue()
