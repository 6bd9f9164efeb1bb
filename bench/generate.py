"""End-to-end `generate` on a 3-minute Mandarin recording built from real THCHS-30 speech.

The input is made at bench time in a temporary folder (never committed): the THCHS-30
recordings of ../shared/bench/zh/thchs30_mfa_example that have a Hanzi transcript, one after
another with 0.4 s of silence between them, repeated until 3 minutes are reached; the
transcript is their Hanzi, one utterance a line ending in "。".

Figures (issue 4, "Done means"):
- wall time of `pipeline.generate` (median of RUNS, in-process), CPU time of the process and its
  children (ffmpeg, the second drawing process) and the share of each stage; the wall time of the
  `cartoonface generate` command itself (imports included; issue 16's target: under 1.8 s for
  3 minutes); `--profile`: a cProfile of one run instead; `--minutes M`: M minutes of input
  instead of 3 (issue 16 also measures 30);
- peak memory (max RSS of a child process doing one run);
- SVG bytes per minute of audio, raw and gzipped (issue 16's targets: at most 1 MB and 150 KB at 30 fps),
  and how they split between the shared definitions and the part tracks;
- page-ready time in headless Chromium (navigation start to two animation frames after the load
  event of index.html from file://, median of RUNS; target < 1 s), and the SVG-vs-audio gap after
  2 s of play. bench/page.py splits that time.
"""

from __future__ import annotations

import csv
import gzip
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import soundfile

from cartoonface.data import SAMPLE_FACES
from cartoonface.pipeline import Options, Result, generate
from cartoonface.render.animation import PARTS_ID

ROOT = Path(__file__).resolve().parents[1]
THCHS = ROOT.parent / "shared" / "bench" / "zh" / "thchs30_mfa_example"
TARGET_SECONDS = 180.0
GAP = 0.4  # seconds of silence between utterances
RUNS = 3
LONG = 600.0  # s of input from which one run is timed instead of RUNS
PROFILE_LINES = 40  # functions `--profile` prints
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--autoplay-policy=no-user-gesture-required", "--mute-audio",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run"]
# Set before the page's own scripts: "page ready", ms from navigation start to two animation frames after `load`.
READY_PROBE = """addEventListener('load', () => requestAnimationFrame(() => requestAnimationFrame(() => {
    window.__cfReady = performance.now(); })));"""


def build_input(folder: Path, target: float = TARGET_SECONDS) -> tuple[Path, Path, float]:
    """Write speech.wav and transcript.txt (THCHS-30 sentences with GAP s between them, repeated
    until >= `target` seconds) into `folder`; return their paths and the seconds of audio."""
    with (THCHS / "transcripts.tsv").open(encoding="utf-8") as handle:
        rows = [row for row in csv.DictReader(handle, delimiter="\t") if row["hanzi"].strip()]
    pieces, lines, total, rate = [], [], 0.0, None
    while total < target:
        for row in rows:
            samples, rate = soundfile.read(THCHS / row["wav"], dtype="float32")
            pieces += [samples, np.zeros(round(GAP * rate), dtype=np.float32)]
            lines.append(row["hanzi"].strip() + "。")
            total += len(samples) / rate + GAP
            if total >= target:
                break
    audio, transcript = folder / "speech.wav", folder / "transcript.txt"
    soundfile.write(audio, np.concatenate(pieces), rate, subtype="PCM_16")
    transcript.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return audio, transcript, total


def children_cpu() -> float:
    """CPU seconds of this process's ended children (ffmpeg, the second drawing process)."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def timed_run(face: Path, audio: Path, transcript: Path,
              out: Path) -> tuple[float, float, dict[str, float], Result, dict[str, float]]:
    """One generate(); return wall seconds, CPU seconds of this process and its children, wall
    seconds per stage, the Result, and CPU seconds of this process alone per stage.

    The machine is shared: CPU time shows the work done even when other jobs stretch the wall time.
    """
    marks: list[tuple[str, float, float]] = []
    started, cpu = time.perf_counter(), time.process_time() + children_cpu()
    result = generate(face, audio, transcript, out, Options(),
                      lambda stage, _: marks.append((stage, time.perf_counter(), time.process_time())))
    end, own, cpu = time.perf_counter(), time.process_time(), time.process_time() + children_cpu() - cpu
    stages: dict[str, float] = {}
    cpu_stages: dict[str, float] = {}
    for (stage, at, used), (_, after, later) in zip(marks, [*marks[1:], ("end", end, own)], strict=True):
        stages[stage] = stages.get(stage, 0.0) + after - at
        cpu_stages[stage] = cpu_stages.get(stage, 0.0) + later - used
    return end - started, cpu, stages, result, cpu_stages


def command_wall(face: Path, audio: Path, transcript: Path, out: Path) -> float:
    """Wall seconds of one `cartoonface generate` command (a fresh process: imports included)."""
    started = time.perf_counter()
    subprocess.run([sys.executable, "-m", "cartoonface", "generate", "--face", str(face), "--audio", str(audio),
                    "--transcript", str(transcript), "-o", str(out)], check=True, capture_output=True)
    return time.perf_counter() - started


def peak_memory(face: Path, audio: Path, transcript: Path, out: Path) -> float:
    """Max RSS in MB of a fresh process running one generate()."""
    code = ("import sys; from pathlib import Path; from cartoonface.pipeline import generate; "
            "generate(Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3]), Path(sys.argv[4]))")
    subprocess.run([sys.executable, "-c", code, str(face), str(audio), str(transcript), str(out)], check=True)
    return resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024


def page_ready(index: Path) -> tuple[list[float], float]:
    """Ready times (s: load + two frames) of `index` in headless Chromium, and |SVG - audio| time after 2 s of play."""
    from playwright.sync_api import sync_playwright

    loads = []
    with sync_playwright() as play:
        browser = play.chromium.launch(executable_path="/usr/bin/chromium", headless=True, args=CHROMIUM_ARGS)
        for _ in range(RUNS):
            page = browser.new_page()
            page.add_init_script(READY_PROBE)
            page.goto(index.as_uri(), wait_until="load")
            page.wait_for_function("window.__cfReady !== undefined")
            loads.append(page.evaluate("window.__cfReady") / 1000)
            page.close()
        page = browser.new_page()
        page.goto(index.as_uri(), wait_until="load")
        page.evaluate("document.getElementById('cf-audio').play()")
        page.wait_for_timeout(2000)
        # Read in an animation frame callback, after the page script's own (see tests/test_browser.py).
        gap = page.evaluate("new Promise(done => requestAnimationFrame(() => done(Math.abs("
                            "document.getElementById('cf-face').getCurrentTime()"
                            " - document.getElementById('cf-audio').currentTime))))")
        browser.close()
    return loads, gap


def bytes_by_track(svg: bytes, minutes: float) -> str:
    """Raw / gzipped KB per minute of the document's <defs>, of the shared parts' and of each part track
    (`<g data-part>`), with the track's number of drawings and of those reused (render/reuse.py:
    a `<use>` with a transform), as one line."""
    from lxml import etree

    root = etree.fromstring(svg)
    ns = "{http://www.w3.org/2000/svg}"
    parts = root.find(f"{ns}defs[@id='{PARTS_ID}']")  # the parts several drawings share (render/animation.py)
    pieces = ([("defs", root.find(f"{ns}defs"))] + ([("shared parts", parts)] if parts is not None else [])
              + [(g.get("data-part"), g) for g in root.iter(f"{ns}g") if g.get("data-part")])
    texts = []
    for name, element in pieces:
        data = etree.tostring(element)
        drawings = list(element.find(f"{ns}defs")) if name != "defs" and element.find(f"{ns}defs") is not None else []
        reused = sum(node.tag == f"{ns}use" and node.get("transform") is not None for node in drawings)
        texts.append(f"{name} {len(data) / minutes / 1e3:.0f}/{len(gzip.compress(data, 6)) / minutes / 1e3:.0f}"
                     + (f" ({len(drawings)} drawings, {reused} reused)" if drawings else ""))
    return "KB per minute raw/gzipped: " + ", ".join(texts)


def profile(face: Path, audio: Path, transcript: Path, out: Path, lines: int = PROFILE_LINES) -> None:
    """Print where one generate() spends its time (cProfile, this process only: the second
    drawing process and ffmpeg are not in it): the `lines` functions of most cumulative time."""
    import cProfile
    import pstats

    profiler = cProfile.Profile()
    profiler.runcall(generate, face, audio, transcript, out, Options())
    pstats.Stats(profiler, stream=sys.stdout).sort_stats("cumulative").print_stats(lines)


def main() -> None:
    """Build the input, run generate RUNS times, print the figures (`--profile`: one profiled
    run instead; `--quick`: the times alone, without the command, memory, sizes and Chromium)."""
    face = sorted(SAMPLE_FACES.glob("*.json"))[0]
    args = sys.argv[1:]
    target = float(args[args.index("--minutes") + 1]) * 60 if "--minutes" in args else TARGET_SECONDS
    if "--profile" in args:
        with tempfile.TemporaryDirectory(prefix="cartoonface-bench-") as tmp:
            profile(face, *build_input(Path(tmp), target)[:2], Path(tmp) / "out")
        return
    with tempfile.TemporaryDirectory(prefix="cartoonface-bench-") as tmp:
        folder = Path(tmp)
        audio, transcript, seconds = build_input(folder, target)
        print(f"input: {seconds:.1f} s of THCHS-30 speech ({seconds / 60:.2f} min), face {face.name}")
        walls, cpus, stage_runs, cpu_runs = [], [], [], []
        runs = RUNS if seconds < LONG else 1
        for run in range(runs):
            wall, cpu, stages, result, cpu_stages = timed_run(face, audio, transcript, folder / f"out{run}")
            walls.append(wall)
            cpus.append(cpu)
            stage_runs.append(stages)
            cpu_runs.append(cpu_stages)
        wall = statistics.median(walls)
        print(f"generate wall time: median {wall:.2f} s of {runs} (runs {', '.join(f'{w:.2f}' for w in walls)}); "
              f"{result.duration / wall:.0f}x real time; CPU time (with children) median {statistics.median(cpus):.2f} s; "
              f"{result.frames} frames at 30 fps; load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
        shares = {stage: statistics.median(s.get(stage, 0.0) for s in stage_runs) for stage in stage_runs[0]}
        print("stages (median s): " + ", ".join(f"{stage} {value:.2f}" for stage, value in shares.items()))
        own = {stage: statistics.median(s.get(stage, 0.0) for s in cpu_runs) for stage in cpu_runs[0]}
        print("CPU of this process per stage (median s): " + ", ".join(f"{stage} {value:.2f}" for stage, value in own.items()))
        if "--quick" in sys.argv[1:]:  # for A/B runs: the times alone
            return
        print(f"`cartoonface generate` command wall time (imports included, one run): "
              f"{command_wall(face, audio, transcript, folder / 'cli'):.2f} s")
        print(f"peak memory (max RSS, one run in a fresh process): {peak_memory(face, audio, transcript, folder / 'mem'):.0f} MB")
        svg = (result.out_dir / "animation.svg").read_bytes()
        minutes = result.duration / 60
        raw, packed = len(svg) / minutes, len(gzip.compress(svg, 6)) / minutes
        print(f"SVG per minute: {raw / 1e6:.2f} MB raw, {packed / 1e3:.0f} KB gzipped "
              f"(targets <= 1 MB, <= 150 KB); whole folder {result.size / 1e6:.1f} MB")
        print(bytes_by_track(svg, minutes))
        loads, gap = page_ready(result.out_dir / "index.html")
        print(f"page ready in headless Chromium: median {statistics.median(loads):.2f} s of {RUNS} "
              f"({', '.join(f'{x:.2f}' for x in loads)}; load + two frames); SVG-audio gap after 2 s of play {gap * 1000:.0f} ms")


if __name__ == "__main__":
    main()
