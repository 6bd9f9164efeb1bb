"""Face geometry speed: pose_face per face state, and lift + rig per face.

Random states (pose within +-15 degrees, blink/smile/brow 0..1, a blend of two
mouth shapes) on both sample faces; prints the median microseconds per
pose_face call over repeated batches (wall clock, and CPU time of this process,
which a machine shared with other work disturbs less), the states per second
that gives on one core, and the one-off cost of lift + rig per face.
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path

import numpy as np

from cartoonface.face.lift import lift
from cartoonface.face.model import load_face
from cartoonface.face.mouth import MOUTH_SYMBOLS
from cartoonface.face.pose import pose_face, rig
from cartoonface.face.state import FaceState, Pose

SAMPLES = Path(__file__).resolve().parent.parent / "samples" / "faces"
STATES = 2000
BATCHES = 15


def random_states(n: int, seed: int = 0) -> list[FaceState]:
    """n random face states (seeded)."""
    rng = np.random.default_rng(seed)
    states = []
    for _ in range(n):
        a, b = rng.choice(MOUTH_SYMBOLS, 2, replace=False)
        w = float(rng.uniform())
        states.append(FaceState(
            pose=Pose(*(float(v) for v in rng.uniform(-15, 15, 3))),
            blink=float(rng.uniform()), smile=float(rng.uniform()), brow=float(rng.uniform()),
            mouth=((str(a), w), (str(b), 1.0 - w)),
        ))
    return states


def main() -> None:
    """Print the figures."""
    states = random_states(STATES)
    for name in ("female", "male"):
        face = load_face(SAMPLES / f"{name}.json")
        setups = []
        for _ in range(BATCHES):
            started = time.perf_counter()
            rig(lift(face))
            setups.append(time.perf_counter() - started)
        lifted = lift(face)
        rig(lifted)
        per_call, per_call_cpu = [], []
        for _ in range(BATCHES):
            started, started_cpu = time.perf_counter(), time.process_time()
            for state in states:
                pose_face(lifted, state)
            per_call.append((time.perf_counter() - started) / len(states))
            per_call_cpu.append((time.process_time() - started_cpu) / len(states))
        median = statistics.median(per_call)
        print(f"{name}: pose_face median {median * 1e6:.1f} us/state ({1 / median:,.0f} states/s), "
              f"CPU {statistics.median(per_call_cpu) * 1e6:.1f} us/state, "
              f"lift + rig {statistics.median(setups) * 1e3:.2f} ms")
