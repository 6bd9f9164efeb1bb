"""Start-up and analysis CPU of `generate`, checkout against checkout (issue 16; branch dsp).

`python -m bench.startup [TREE ...]` (default: this checkout) runs, in rounds alternating between
the trees (each with its own `.venv`), fresh processes that

- import what `cartoonface generate` imports (the CLI module, the pipeline, exports.video): wall
  and CPU seconds of the imports, and whether scipy got imported; then the CPU seconds with the
  transcript read as well (`parse_transcript`: its first use loads speech/lexicon.py's table);
- run `analyse` on bench/generate.py's 190 s input (after one warm-up run in the same process):
  CPU seconds of its segment stage (transcript, speaking parts), of the reconciling (dips) and of
  the alignment, one process, no helper.

It prints the median of each figure per tree. The machine is shared: CPU time is the figure to
compare, wall time only on a quiet machine.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from bench.generate import build_input

ROUNDS = 5
IMPORTS = """
import json, os, sys, time
from pathlib import Path
started = time.perf_counter()
import cartoonface.cli.generate, cartoonface.pipeline, cartoonface.exports.video
wall = time.perf_counter() - started
times = os.times()
scipy = any(name.split(".")[0] == "scipy" for name in sys.modules)
from cartoonface.speech.transcript import parse_transcript
parse_transcript(Path(sys.argv[1]).read_text(encoding="utf-8"))
read = os.times()
print(json.dumps({"import wall": wall, "import CPU": times.user + times.system,
                  "+ transcript CPU": read.user + read.system, "scipy": scipy}))
"""
ANALYSIS = """
import json, sys, time
from pathlib import Path
from cartoonface.speech.analyse import analyse
from cartoonface.speech.audio import load_audio
audio, text = load_audio(Path(sys.argv[1])), Path(sys.argv[2]).read_text(encoding="utf-8")
analyse(audio, text)
marks = []
started = time.process_time()
analyse(audio, text, progress=lambda stage, fraction: marks.append((stage, time.process_time() - started)))
total = time.process_time() - started
segment = max(t for stage, t in marks if stage == "segment")
align = min(t for stage, t in marks if stage == "align")
print(json.dumps({"segment CPU": segment, "reconcile CPU": align - segment, "align CPU": total - align}))
"""


def measure(tree: Path, audio: Path, transcript: Path) -> dict[str, float]:
    """One round in `tree`: the figures of IMPORTS and ANALYSIS, each in a fresh process."""
    python = str(tree / ".venv" / "bin" / "python")
    figures: dict[str, float] = {}
    for code, args in ((IMPORTS, [str(transcript)]), (ANALYSIS, [str(audio), str(transcript)])):
        done = subprocess.run([python, "-c", code, *args], cwd=tree, capture_output=True, text=True, check=True)
        figures.update(json.loads(done.stdout.splitlines()[-1]))
    return figures


def main() -> None:
    """Alternate the trees named on the command line (default: this checkout), ROUNDS rounds."""
    # checkouts among the arguments (`python -m bench startup` passes the module's name too)
    trees = [Path(arg).resolve() for arg in sys.argv[1:] if (Path(arg) / ".venv").is_dir()] or [Path.cwd()]
    with tempfile.TemporaryDirectory(prefix="cartoonface-bench-") as tmp:
        audio, transcript, _ = build_input(Path(tmp))
        rounds: dict[Path, list[dict[str, float]]] = {tree: [] for tree in trees}
        for _ in range(ROUNDS):
            for tree in trees:
                rounds[tree].append(measure(tree, audio, transcript))
    for tree, runs in rounds.items():
        medians = {key: statistics.median(float(run[key]) for run in runs) for key in runs[0] if key != "scipy"}
        scipy = sum(bool(run["scipy"]) for run in runs)
        print(f"{tree}: " + ", ".join(f"{key} {value:.3f} s" for key, value in medians.items())
              + f"; scipy imported in {scipy} of {len(runs)} (medians of {len(runs)})")


if __name__ == "__main__":
    main()
