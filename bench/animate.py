"""Animation speed: schedule, timeline and frames for a 3-minute talk at 30 fps.

The alignment is synthetic (sentences of 4-12 syllables of 0.15-0.35 s with random
mouth shapes, 0.4-1.0 s pauses): this measures the animate/ stage alone.
Prints the median wall time of each step over repeated runs and how many frames
are distinct (what the SVG writer has left after merging identical neighbours).
"""

from __future__ import annotations

import statistics
import time


from cartoonface.animate.behaviour import schedule, speech_pauses
from cartoonface.animate.frames import sample_frames
from cartoonface.animate.timeline import build_timeline
from tests.synthetic import synthetic_talk

DURATION = 180.0
FPS = 30
RUNS = 15


def main() -> None:
    alignment = synthetic_talk(DURATION)
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
