"""Memory and time of drawing a face whose hair outline has many points (issue 12).

A synthetic face: the female sample with its hair outline resampled by arc length to H
points (past the model reader's cap, MAX_HAIR_POINTS). Each H runs in a fresh process so
that its max RSS is its own: the first `face_shapes` call (compiles the drawing's maps)
under tracemalloc, then a second call (maps cached).
"""

from __future__ import annotations

import dataclasses
import resource
import subprocess
import sys
import time
import tracemalloc

import numpy as np

from cartoonface.data import SAMPLE_FACES
from cartoonface.face.lift import lift
from cartoonface.face.model import load_face
from cartoonface.face.pose import pose_face
from cartoonface.face.state import FaceState, Pose
from cartoonface.render.geometry import face_shapes

HAIR_COUNTS = (400, 2000, 5000, 30000)
MIB = 2**20


def resampled(outline: np.ndarray, count: int) -> np.ndarray:
    """`count` points (count, 2) evenly spaced by arc length along the closed `outline` (n, 2)."""
    closed = np.vstack([outline, outline[:1]])
    along = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(closed, axis=0), axis=1))])
    at = np.linspace(0.0, along[-1], count, endpoint=False)
    return np.column_stack([np.interp(at, along, closed[:, 0]), np.interp(at, along, closed[:, 1])])


def measure(count: int) -> str:
    """One line: tracemalloc peak and time of the first draw, the later draw's time, max RSS."""
    face = load_face(SAMPLE_FACES / "female.json")
    face = dataclasses.replace(face, hair=resampled(face.hair, count))
    posed = pose_face(lift(face), FaceState(Pose(5.0, 10.0, 3.0), 0.2, 0.3, 0.1, (("a", 1.0),)))
    tracemalloc.start()
    started = time.perf_counter()
    face_shapes(posed)
    first = time.perf_counter() - started
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    started = time.perf_counter()
    face_shapes(posed)
    later = time.perf_counter() - started
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # Linux: KiB
    return (f"H={count:,}: first draw {first * 1000:.0f} ms, tracemalloc peak {peak / MIB:.1f} MiB, "
            f"later draw {later * 1000:.1f} ms, max RSS {rss:.0f} MiB")


def main() -> None:
    """Print the figures for each H of HAIR_COUNTS, each measured in its own process."""
    for count in HAIR_COUNTS:
        run = subprocess.run([sys.executable, "-m", "bench.face_hair", str(count)], capture_output=True, text=True,
                             check=True)
        print(run.stdout.strip(), flush=True)


if __name__ == "__main__":
    if len(sys.argv) > 1:
        print(measure(int(sys.argv[1])))
    else:
        main()
