"""Synthetic inputs shared by tests and benchmarks."""

from __future__ import annotations

import io
import wave

import numpy as np

from cartoonface.face.mouth import MOUTH_SYMBOLS
from cartoonface.speech.records import Alignment, Sentence, Syllable


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
