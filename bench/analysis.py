"""The analysis's critical path in `generate` (issue 16): its pieces' CPU, and when it ends on two cores.

generate's analysis runs in two processes (workers.py): this one decodes the recording, reads the
transcript, segments and reconciles ("pre"), the forked helper decodes it too and computes the
pitch track ("pitch"); then both align the parts (workers.from_both_ends: the helper the costliest
first, this process the cheapest, until they meet). Each piece's CPU is measured in a fresh process,
as generate meets it (first calls: fresh memory, cold caches), on bench generate's 190 s input;
`ends` models the two processes on two idle cores (the executor hands a job and the next
workers.AHEAD - 1 to its process, after which it cannot be taken back), so the figure does not
depend on the machine's load as a wall clock does. Options: `--rounds N` (default 5).

The command (`cartoonface generate`) reaches the analysis after its interpreter's start and imports
("start", measured in a fresh process running the command up to its "decode" report), and begins the
pitch track before those imports in a child of its own (cli/generate.py `begun`, "begun": that child's
CPU, forked once the command's process has spent "fork"); the second model puts that child on the
other core from then on, then the helper's jobs, against the helper's own track begun at "start".
"""

from __future__ import annotations

import ast
import gc
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cartoonface.speech.analyse as analyse
from bench.generate import build_input
from cartoonface.animate.prosody import recording_pitch
from cartoonface.data import SAMPLE_FACES
from cartoonface.speech.audio import Audio, load_audio
from cartoonface.speech.records import Sentence
from cartoonface.speech.sentences import Span
from cartoonface.speech.transcript import SentenceText
from cartoonface.workers import AHEAD

ROUNDS = 5
# A fresh process running the command on argv[1:] until generate reports "decode" (its setup done):
# prints the CPU seconds its process had spent then and when it forked begun's child.
START = """
import sys, time
import cartoonface.cli as cli, cartoonface.cli.generate as command, cartoonface.cli.progress as progress
spent = {}
begun = command.begun
def timed(argv):
    spent["fork"] = time.process_time()
    return begun(argv)
def stop(self, stage, fraction):
    spent["start"] = time.process_time()
    print(spent)
    raise SystemExit(0)
command.begun, progress.ProgressBar.__call__ = timed, stop
cli.main(sys.argv[1:])
"""
# A fresh process that has imported the command's package only: begun's child's CPU seconds.
BEGUN = """
import resource, sys
from cartoonface.cli.generate import begun
begun(sys.argv[1:])[1]()
used = resource.getrusage(resource.RUSAGE_CHILDREN)
print(used.ru_utime + used.ru_stime)
"""


def pieces(audio: Path, transcript: Path) -> dict[str, object]:
    """{"pre": s, "pitch": s, "jobs": [s, ...]}: CPU seconds of this process's share before the
    alignment, of the helper's pitch track (in a child forked at once, as generate's), and of each
    alignment job (in the jobs' order), all done in this process one after another."""
    gc.disable()  # generate runs under workers.collector_paused
    reader, writer = os.pipe()
    if os.fork() == 0:  # the helper: forked before any of the analysis
        started = time.process_time()
        recording_pitch(audio)
        os.write(writer, str(time.process_time() - started).encode())
        os._exit(0)
    os.wait()
    pitch = float(os.read(reader, 64))
    first: list[float] = []  # when the first alignment job began
    jobs: list[tuple[float, float]] = []  # (its span's start, CPU seconds) of each job
    aligned = analyse._aligned

    def timed(audio: Audio, texts: list[SentenceText], span: Span,
              words: list[int]) -> list[tuple[Sentence, tuple[float, ...]]]:
        if not first:
            first.append(time.process_time())
        started = time.process_time()
        result = aligned(audio, texts, span, words)
        jobs.append((span.start, time.process_time() - started))
        return result

    analyse._aligned = timed
    started = time.process_time()
    analyse.analyse(load_audio(audio), transcript.read_text(encoding="utf-8"))
    return {"pre": first[0] - started, "pitch": pitch, "jobs": [cost for _, cost in sorted(jobs)]}


def ends(pre: float, pitch: float, jobs: list[float], ahead: int) -> float:
    """Seconds after the analysis starts at which both processes are done, on two idle cores:
    this process does `pre`, then jobs from the cheapest end; the helper `pitch`, then the jobs it
    is given from the costliest end, `ahead` not yet done at a time, topped up whenever this process
    is between jobs (workers.from_both_ends)."""
    order = sorted(range(len(jobs)), key=lambda k: -jobs[k])
    finish: list[float] = []  # when each job given to the helper is done, in the order given
    front, back, now = 0, len(order), pre
    while front < back:
        while front < back and sum(1 for done in finish if done > now) < ahead:
            finish.append(max(finish[-1] if finish else pitch, now) + jobs[order[front]])
            front += 1
        if front < back:
            back -= 1
            now += jobs[order[back]]
    return max([now, *finish])


def command_start(audio: Path, transcript: Path) -> dict[str, float]:
    """{"fork": s, "start": s, "begun": s}: CPU seconds of a fresh `cartoonface generate` process when it
    forks begun's child and when its analysis begins (START), and of that child (BEGUN)."""
    argv = ["generate", "--face", str(SAMPLE_FACES / "female.json"), "--audio", str(audio), "--transcript",
            str(transcript), "-o", str(audio.parent / "out")]
    spent = ast.literal_eval(subprocess.run([sys.executable, "-c", START, *argv], capture_output=True, text=True,
                                            check=True).stdout.strip().splitlines()[-1])
    child = subprocess.run([sys.executable, "-c", BEGUN, "--audio", str(audio)], capture_output=True, text=True, check=True)
    return {**spent, "begun": float(child.stdout)}


def main() -> None:
    """Measure the pieces ROUNDS times (fresh processes), print their medians and the modelled end."""
    args = sys.argv[1:]
    if "--pieces" in args:  # a fresh process measuring one round
        print(json.dumps(pieces(Path(args[args.index("--pieces") + 1]), Path(args[args.index("--pieces") + 2]))))
        return
    rounds = int(args[args.index("--rounds") + 1]) if "--rounds" in args else ROUNDS
    with tempfile.TemporaryDirectory(prefix="cartoonface-bench-") as tmp:
        audio, transcript, seconds = build_input(Path(tmp))
        runs = [json.loads(subprocess.run([sys.executable, "-m", "bench.analysis", "--pieces", str(audio), str(transcript)],
                                          capture_output=True, text=True, check=True).stdout) for _ in range(rounds)]
        starts = [command_start(audio, transcript) for _ in range(rounds)]
    pre, pitch = (statistics.median(run[name] for run in runs) for name in ("pre", "pitch"))
    fork, start, early = (statistics.median(run[name] for run in starts) for name in ("fork", "start", "begun"))
    jobs = [statistics.median(costs) for costs in zip(*(run["jobs"] for run in runs))]
    work = pre + pitch + sum(jobs)
    print(f"input: {seconds:.1f} s; CPU, median of {rounds} fresh processes: before the alignment {pre:.3f} s, "
          f"pitch track (helper) {pitch:.3f} s, alignment {sum(jobs):.3f} s in {len(jobs)} jobs")
    print(f"analysis on two idle cores (model): ends at {ends(pre, pitch, jobs, AHEAD):.3f} s; "
          f"all its work {work:.3f} s, half of it {work / 2:.3f} s (no split ends sooner)")
    print(f"the command: its analysis begins after {start:.3f} s of CPU (interpreter, imports, setup); the pitch "
          f"track begun at {fork:.3f} s takes {early:.3f} s in its child; on two idle cores the analysis ends at "
          f"{ends(start + pre, fork + early, jobs, AHEAD):.3f} s after the interpreter starts (the helper's own "
          f"track: {start + ends(pre, pitch, jobs, AHEAD):.3f} s)")


if __name__ == "__main__":
    main()
