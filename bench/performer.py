"""The performer's behaviour per style over 10 minutes of real Mandarin speech.

Input built at bench time in a temporary folder (never committed): the THCHS-30 recordings
of ../shared/bench/zh/thchs30_mfa_example that have a Hanzi transcript, one after another
with 0.4 s of silence, repeated until TARGET_SECONDS (bench/generate.py build_input).
It is aligned once; then for each style (animate/style.py) the schedule of seed 0 is drawn
with the recording's pitch peaks, sampled at 30 fps with the idle sway, and measured:

- blinks per minute (target 10.5-32.5, the range the thesis's Gamma(2, 1.48 s) is built on);
- gaze shifts (saccades) per minute, glances away (beyond the darts on the viewer's face)
  per minute, and the share of frames with the eyes on the viewer's face;
- head motion from the frames: range (5th-95th percentile) of tilt (nod), turn and roll
  in degrees, and the median / 95th percentile speed of the head in degrees per second
  over the frames where it moves;
- share of eyebrow raises fully up within 100 ms of a pitch peak, and the same for the
  schedule drawn without peaks (chance, the thesis's random placement);
- nods and smiles per minute;
- animation.svg bytes per minute of audio (raw) at 30 fps.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from bench.generate import build_input
from cartoonface.animate.behaviour import schedule, speech_pauses, speech_spans
from cartoonface.animate.frames import frame_times, on_twos, states_at
from cartoonface.animate.gaze import DART_RADIUS
from cartoonface.animate.idle import sway
from cartoonface.animate.prosody import pitch_peaks
from cartoonface.animate.style import STYLES
from cartoonface.animate.timeline import build_timeline
from cartoonface.data import SAMPLE_FACES
from cartoonface.face.model import load_face
from cartoonface.render.animation import animation_svg
from cartoonface.speech.analyse import analyse
from cartoonface.speech.audio import load_audio

TARGET_SECONDS = 600.0
FPS = 30
SEED = 0
PEAK_WINDOW = 0.1  # seconds: a brow "on" a peak is fully up within this of it
MOVING = 0.05  # degrees per frame: slower head frames count as still
BLINK_RATE = (10.5, 32.5)  # per minute: the target range


def near_share(starts: np.ndarray, peaks: np.ndarray) -> float:
    """Share of `starts` (seconds) within PEAK_WINDOW of one of `peaks`."""
    if not len(starts) or not len(peaks):
        return 0.0
    gaps = np.abs(starts[:, None] - peaks[None, :]).min(axis=1)
    return float(np.mean(gaps <= PEAK_WINDOW + 1e-9))


def measure(name: str, alignment, peaks: tuple[float, ...], face) -> None:
    """Print the figures of style `name` on `alignment` with pitch `peaks`."""
    style = STYLES[name]
    duration = alignment.duration
    minutes = duration / 60
    pauses = speech_pauses(alignment)
    speech = speech_spans(alignment)
    plan = schedule(duration, pauses, SEED, style=style, peaks=peaks, speech=speech)
    chance = schedule(duration, pauses, SEED, style=style, peaks=(), speech=speech)
    timeline = build_timeline(alignment, plan)
    times = frame_times(timeline, FPS)
    states = states_at(timeline, times, sway(times, SEED, style.sway_peak))
    kinds = [a.kind for a in plan]
    saccades = {a.start for a in plan if a.kind in ("gaze_h", "gaze_v")}
    gaze = np.array([(s.gaze_h, s.gaze_v) for s in states])
    on_viewer = np.hypot(gaze[:, 0], gaze[:, 1]) <= DART_RADIUS + 1e-9
    away = int(np.sum(on_viewer[:-1] & ~on_viewer[1:]))
    pose = np.array([(s.pose.tilt, s.pose.turn, s.pose.roll) for s in states])
    low, high = np.percentile(pose, 5, axis=0), np.percentile(pose, 95, axis=0)
    speed = np.abs(np.diff(pose, axis=0)).max(axis=1)
    moving = speed[speed > MOVING] * FPS
    brow_peaks = [np.array([a.start + a.attack for a in p if a.kind == "brow"]) for p in (plan, chance)]
    peak_times = np.array(peaks)
    blinks = kinds.count("blink") / minutes
    started = time.perf_counter()
    svg = animation_svg(face, on_twos(states), FPS)  # drawn as generate draws them
    svg_seconds = time.perf_counter() - started
    print(f"style {name}: {duration:.1f} s, {len(states)} frames")
    print(f"  blinks per minute {blinks:.1f} (target {BLINK_RATE[0]}-{BLINK_RATE[1]}: "
          f"{'ok' if BLINK_RATE[0] <= blinks <= BLINK_RATE[1] else 'OUT'})")
    print(f"  gaze shifts per minute {len(saccades) / minutes:.1f}, glances away per minute {away / minutes:.1f}, "
          f"eyes on the viewer's face {100 * on_viewer.mean():.0f} % of frames")
    print("  head range p5..p95 (deg): " + ", ".join(
        f"{axis} {lo:+.1f}..{hi:+.1f}" for axis, lo, hi in zip(("nod/tilt", "turn", "roll"), low, high, strict=True)))
    print(f"  head speed while moving (deg/s): median {np.median(moving):.1f}, p95 {np.percentile(moving, 95):.1f}; "
          f"moving {100 * len(moving) / len(speed):.0f} % of frames")
    print(f"  brow raises per minute {kinds.count('brow') / minutes:.1f}, within {PEAK_WINDOW * 1000:.0f} ms of a "
          f"pitch peak {100 * near_share(brow_peaks[0], peak_times):.0f} % "
          f"(without peaks, by chance: {100 * near_share(brow_peaks[1], peak_times):.0f} %)")
    print(f"  nods per minute {kinds.count('nod') / minutes:.1f}, smiles per minute {kinds.count('smile') / minutes:.1f}")
    print(f"  animation.svg {len(svg) / minutes / 1e6:.2f} MB per minute raw at {FPS} fps "
          f"(target < 1.5), drawn in {svg_seconds:.1f} s")


def main() -> None:
    """Build the 10-minute input, align it, and print the figures of every style."""
    face = load_face(SAMPLE_FACES / "female.json")
    with tempfile.TemporaryDirectory() as tmp:
        audio_path, transcript, _ = build_input(Path(tmp), TARGET_SECONDS)
        text = transcript.read_text(encoding="utf-8")
        recording = load_audio(audio_path)
        started = time.perf_counter()
        alignment = analyse(recording, text)
        peaks = pitch_peaks(recording, alignment)
        print(f"input: {recording.duration:.1f} s of THCHS-30 speech, {len(alignment.sentences)} sentences, "
              f"{len(peaks)} pitch peaks ({len(peaks) / recording.duration * 60:.0f} per minute); "
              f"aligned in {time.perf_counter() - started:.1f} s")
    for name in STYLES:
        measure(name, alignment, peaks, face)


if __name__ == "__main__":
    main()
