"""Animation speed: schedule, timeline and frames for a 3-minute talk at 30 fps.

The alignment is synthetic (sentences of 4-12 syllables of 0.15-0.35 s with random
mouth shapes, 0.4-1.0 s pauses): this measures the animate/ stage alone.
Prints the median wall time of each step over repeated runs and how many frames
are distinct (what the SVG writer has left after merging identical neighbours).
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from cartoonface.animate.behaviour import schedule, speech_pauses
from cartoonface.animate.frames import sample_frames
from cartoonface.animate.timeline import build_timeline
from cartoonface.face.mouth import MOUTH_SYMBOLS
from cartoonface.speech.alignment import Alignment, Sentence, Syllable

DURATION = 180.0
FPS = 30
RUNS = 15


def synthetic_alignment(duration: float, seed: int = 0) -> Alignment:
    """A talk of `duration` seconds with random syllables and pauses."""
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


def main() -> None:
    alignment = synthetic_alignment(DURATION)
    times: dict[str, list[float]] = {"schedule": [], "timeline": [], "frames": [], "total": []}
    for run in range(RUNS):
        t0 = time.perf_counter()
        actions = schedule(alignment.duration, speech_pauses(alignment), seed=run)
        t1 = time.perf_counter()
        timeline = build_timeline(alignment, actions)
        t2 = time.perf_counter()
        frames = sample_frames(timeline, FPS)
        t3 = time.perf_counter()
        for name, value in zip(times, (t1 - t0, t2 - t1, t3 - t2, t3 - t0), strict=True):
            times[name].append(value * 1000)
    distinct = sum(a != b for a, b in zip(frames, frames[1:])) + 1
    print(f"input: {DURATION:.0f} s synthetic talk, {sum(len(s.syllables) for s in alignment.sentences)} syllables, "
          f"{len(actions)} actions, {FPS} fps, {len(frames)} frames")
    for name, values in times.items():
        print(f"{name}: median {statistics.median(values):.1f} ms over {RUNS} runs")
    print(f"frames differing from the previous one: {distinct} of {len(frames)} ({distinct / len(frames):.0%})")
