"""Video clips for the video tests: the GRID clip shipped in tests/data/grid (CC BY 4.0) and
clips made by the bundled ffmpeg."""

from __future__ import annotations

import subprocess
from pathlib import Path

from cartoonface.speech.audio import ffmpeg_exe

GRID = Path(__file__).resolve().parent / "data" / "grid" / "s1_pbai6p.mpg"
# Hand-labelled blinks of the GRID clips (bench/video.py says how they were labelled).
LABELS = Path(__file__).resolve().parent.parent / "bench" / "video_blinks.csv"


def make_clip(path: Path, *args: str) -> Path:
    """A clip made by the bundled ffmpeg from lavfi sources: `args` between the binary and `path`."""
    subprocess.run([ffmpeg_exe(), "-nostdin", "-v", "error", "-y", *args, str(path)], check=True)
    return path
