"""The progress a job reports (what the web app's job page shows): on a 4-minute recording (the
sample story ten times), when each stage starts as a share of the wall time, how many reports
come, the longest wait between two, and how far the reported fraction is from the share of
the time gone by.

Run: .venv/bin/python -m bench web_progress
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
import soundfile

from cartoonface.pipeline import STAGES, Options, generate

ROOT = Path(__file__).resolve().parent.parent
SPEECH = ROOT / "samples" / "speech"
REPEATS = 10  # the 24.7 s story ten times: 4.1 minutes


def main() -> None:
    """Print the figures for one generate of the repeated story with the first sample face."""
    samples, rate = soundfile.read(SPEECH / "story.wav", dtype="int16")
    text = (SPEECH / "story.txt").read_text(encoding="utf-8")
    with tempfile.TemporaryDirectory() as tmp:
        recording, transcript = Path(tmp) / "long.wav", Path(tmp) / "long.txt"
        soundfile.write(recording, np.tile(samples, REPEATS), rate)
        transcript.write_text(text * REPEATS, encoding="utf-8")
        calls: list[tuple[float, str, float]] = []
        start = time.perf_counter()

        def progress(stage: str, fraction: float) -> None:
            calls.append((time.perf_counter() - start, stage, fraction))

        generate(sorted((ROOT / "samples" / "faces").glob("*.json"))[0], recording, transcript,
                 Path(tmp) / "site", Options(), progress)
        total = time.perf_counter() - start
    print(f"recording {len(samples) * REPEATS / rate:.1f} s; generate {total:.2f} s; {len(calls)} reports")
    starts: dict[str, float] = {}
    for at, stage, _ in calls:
        starts.setdefault(stage, at)
    for name, share in STAGES:
        print(f"  {name:9s} starts at {starts[name] / total:6.1%} of the time (reported as {share:.0%})")
    times = [at for at, _, _ in calls] + [total]
    gaps = [later - earlier for earlier, later in zip(times, times[1:])]
    longest = max(range(len(gaps)), key=gaps.__getitem__)
    print(f"longest wait between reports {gaps[longest]:.2f} s ({gaps[longest] / total:.1%} of the time, "
          f"after {calls[longest][1]} {calls[longest][2]:.3f}); median {statistics.median(gaps) * 1000:.0f} ms")
    print(f"largest |fraction - share of the time gone by| {max(abs(f - at / total) for at, _, f in calls):.3f}")
