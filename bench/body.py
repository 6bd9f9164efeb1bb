"""The body (issue 11): breaths, SVG weight of the body's motion, Chromium playback with and without it.

Input: bench/generate.py's THCHS-30 news reading (built at bench time, never committed), 3
minutes for the schedule and the SVG size, its first minute for the browser. Announcer page,
newsroom, suit, female sample face, seed 0.

- breaths a minute, median seconds between breaths, median inhalation and depth (actions.json);
- animation.svg bytes per minute of audio (raw) per style, with the body's motion and with a
  still body (`pipeline.body_motion` replaced by one that never moves: the drawing is the same);
- Chromium playback of the 1-minute page with and without the motion, interleaved RUNS times:
  requestAnimationFrame callbacks a second over PLAY_MS of play, frames over 50 ms, the
  main thread's busy share (DevTools Performance.getMetrics TaskDuration per second of play)
  and the CPU time of the browser's processes per animation frame (from /proc; the wall-time
  figures swing with the machine's load, the CPU time much less).
"""

from __future__ import annotations

import json
import os
import statistics
import tempfile
from pathlib import Path

import numpy as np

import cartoonface.pipeline as pipeline
from bench.generate import CHROMIUM_ARGS, TARGET_SECONDS, build_input
from cartoonface.animate.body import BodyMotion
from cartoonface.data import SAMPLE_FACES
from cartoonface.pipeline import Options, generate

RUNS = 5
PLAY_MS = 8000
BROWSER_SECONDS = 60.0
SLOW_FRAME_MS = 50
MEASURE = """ms => new Promise(done => { const a = document.getElementById('cf-audio'); a.play();
  const times = []; const start = performance.now();
  function tick(t) { times.push(t); if (t - start < ms) requestAnimationFrame(tick); else done(times); }
  requestAnimationFrame(tick); })"""


def _cpu_seconds() -> float:
    """CPU seconds (user + system) used so far by this process's descendants (the Playwright driver
    and Chromium's processes), from /proc: less sensitive than wall time to a busy machine."""
    parents, times = {}, {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", encoding="ascii", errors="replace") as handle:
                fields = handle.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        parents[int(entry)] = int(fields[1])  # fields after the name: state, ppid, ..., utime (12th), stime (13th)
        times[int(entry)] = (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    mine, total = {os.getpid()}, 0.0
    changed = True
    while changed:
        changed = False
        for pid, parent in parents.items():
            if parent in mine and pid not in mine:
                mine.add(pid)
                changed = True
    for pid in mine - {os.getpid()}:
        total += times[pid]
    return total


def _still(states, breaths, fps) -> BodyMotion:
    """A body that never moves (the same drawing, no transforms)."""
    return BodyMotion(*(np.zeros(len(states)) for _ in range(3)))


def _sites(folder: Path, audio: Path, transcript: Path, style: str) -> tuple[Path, Path]:
    """Generate the announcer page with the body's motion and with a still body; return both folders."""
    options = Options(page="announcer", style=style, background="newsroom", clothes="suit")
    face = SAMPLE_FACES / "female.json"
    moving = generate(face, audio, transcript, folder / f"{style}-moving", options).out_dir
    real = pipeline.body_motion
    pipeline.body_motion = _still
    try:
        still = generate(face, audio, transcript, folder / f"{style}-still", options).out_dir
    finally:
        pipeline.body_motion = real
    return moving, still


def _playback(sites: dict[str, Path]) -> dict[str, list[tuple[float, int, float, float]]]:
    """(rAF per second, frames over SLOW_FRAME_MS, main-thread busy share, CPU ms of the browser per
    animation frame) per run of each site's page."""
    from playwright.sync_api import sync_playwright

    results: dict[str, list[tuple[float, int, float, float]]] = {name: [] for name in sites}
    with sync_playwright() as play:
        browser = play.chromium.launch(executable_path="/usr/bin/chromium", headless=True, args=CHROMIUM_ARGS)
        for _ in range(RUNS):
            for name, site in sites.items():
                page = browser.new_page(viewport={"width": 1280, "height": 800})
                page.goto((site / "index.html").as_uri(), wait_until="load")
                cdp = page.context.new_cdp_session(page)
                cdp.send("Performance.enable")
                before = {m["name"]: m["value"] for m in cdp.send("Performance.getMetrics")["metrics"]}
                cpu = _cpu_seconds()
                times = np.array(page.evaluate(MEASURE, PLAY_MS))
                cpu = _cpu_seconds() - cpu
                after = {m["name"]: m["value"] for m in cdp.send("Performance.getMetrics")["metrics"]}
                seconds = (times[-1] - times[0]) / 1000
                results[name].append((len(times) / seconds, int((np.diff(times) > SLOW_FRAME_MS).sum()),
                                      (after["TaskDuration"] - before["TaskDuration"]) / seconds,
                                      cpu * 1000 / len(times)))
                page.close()
        browser.close()
    return results


def main() -> None:
    """Print the figures."""
    with tempfile.TemporaryDirectory(prefix="cartoonface-body-") as tmp:
        folder = Path(tmp)
        audio, transcript, seconds = build_input(folder, TARGET_SECONDS)
        minutes = seconds / 60
        print(f"input: {seconds:.1f} s of THCHS-30 news reading; announcer page, newsroom, suit, female face")
        for style in ("announcer", "storyteller"):
            moving, still = _sites(folder, audio, transcript, style)
            actions = json.loads((moving / "actions.json").read_text(encoding="utf-8"))["actions"]
            breaths = [a for a in actions if a["kind"] == "breath"]
            gaps = np.diff([a["start"] for a in breaths])
            sizes = [(site / "animation.svg").stat().st_size / minutes / 1e6 for site in (moving, still)]
            print(f"{style}: {len(breaths) / minutes:.1f} breaths a minute, median {np.median(gaps):.2f} s apart, "
                  f"inhalation median {statistics.median(a['attack'] for a in breaths):.2f} s, depth median "
                  f"{statistics.median(a['amplitude'] for a in breaths):.2f}; animation.svg {sizes[0]:.3f} MB per minute "
                  f"raw with the body's motion, {sizes[1]:.3f} still ({(sizes[0] / sizes[1] - 1) * 100:+.1f} %)")
        (folder / "short").mkdir()
        short_audio, short_text, short = build_input(folder / "short", BROWSER_SECONDS)
        moving, still = _sites(folder / "short", short_audio, short_text, "announcer")
        results = _playback({"moving": moving, "still": still})
        for name, runs in results.items():
            rates, slow, busy, cpu = zip(*runs, strict=True)
            print(f"Chromium, {short:.0f} s page, body {name}, {RUNS} interleaved runs: rAF median {statistics.median(rates):.1f}/s "
                  f"({', '.join(f'{r:.1f}' for r in rates)}), frames over {SLOW_FRAME_MS} ms {', '.join(map(str, slow))}, "
                  f"main thread busy median {statistics.median(busy):.2f} ({', '.join(f'{b:.2f}' for b in busy)}), "
                  f"browser CPU per frame median {statistics.median(cpu):.1f} ms ({', '.join(f'{c:.1f}' for c in cpu)})")
