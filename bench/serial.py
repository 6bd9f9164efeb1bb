"""CPU of the serial stages of one `generate` run (issue 16, branch small).

The stages one process runs alone, the other core idle: the checks before "decode", "decode",
"schedule", "frames" and "pages" (docs/BENCHMARKS.md, "The serial stages around the SVG"). One
run of `pipeline.generate` on bench/generate.py's 3-minute input, in this process: the processor
seconds (time.process_time) of each stage from its progress report to the next, and their sum
("serial"). Run it in a fresh process each time (the first run pays the lazy imports, as the
command does) and alternate the checkouts:

    for i in 1 2 3 4 5 6; do (cd ../main && .venv/bin/python -m bench.serial /tmp/benchinput); \
        .venv/bin/python -m bench.serial /tmp/benchinput; done

`FOLDER` (optional): a folder holding speech.wav and transcript.txt, made by build_input when missing.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

from bench.generate import build_input
from cartoonface.data import SAMPLE_FACES
from cartoonface.pipeline import generate

SERIAL = ("checks", "decode", "schedule", "frames", "pages")


def main(folder: Path | None = None) -> None:
    """Print `stage cpu-seconds` per stage of one run on the input in `folder` (None: made in a
    temporary one), then the serial stages' sum."""
    if folder is None:
        with tempfile.TemporaryDirectory() as made:
            return main(Path(made))
    if not (folder / "speech.wav").is_file():
        folder.mkdir(parents=True, exist_ok=True)
        build_input(folder)
    marks: list[tuple[str, float]] = [("checks", time.process_time())]

    def progress(stage: str, _share: float) -> None:
        if stage != marks[-1][0]:
            marks.append((stage, time.process_time()))

    with tempfile.TemporaryDirectory() as out:
        generate(SAMPLE_FACES / "female.json", folder / "speech.wav", folder / "transcript.txt", Path(out) / "site",
                 progress=progress)
        marks.append(("end", time.process_time()))
    seconds = {stage: after - at for (stage, at), (_, after) in zip(marks, marks[1:])}
    for stage, cpu in seconds.items():
        print(f"{stage:9s} {cpu:.4f}")
    print(f"{'serial':9s} {sum(seconds[stage] for stage in SERIAL):.4f}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else None)
