"""Face states per second: geometry (pose_face) + SVG path data (face_shapes), and the lxml drawing.

Target (issue 2): at least 5,000 states per second for pose_face + face_shapes on one core.
A varied, seeded set of states: poses within +-15 degrees, blink/smile/brow amounts and
two-shape mouth mixes. Each figure is the median of several timed passes over the set.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
import numpy as np

from cartoonface.data import SAMPLE_FACES
from cartoonface.face.lift import lift
from cartoonface.face.model import FaceModel, load_face
from cartoonface.face.mouth import MOUTH_SYMBOLS
from cartoonface.face.pose import pose_face
from cartoonface.face.state import FaceState, Pose
from cartoonface.render.geometry import face_shapes
from cartoonface.render.svg import face_group

STATES = 1000
PASSES = 9  # the machine is shared: many short passes, median and best reported


def varied_states(count: int, seed: int = 0) -> list[FaceState]:
    """`count` random face states (seeded): any pose, expression amounts, a mix of two mouth shapes."""
    rng = np.random.default_rng(seed)
    states = []
    for _ in range(count):
        tilt, turn, roll = rng.uniform(-15, 15, 3)
        blink, smile, brow, weight = rng.uniform(0, 1, 4)
        a, b = rng.choice(len(MOUTH_SYMBOLS), 2, replace=False)
        mouth = ((MOUTH_SYMBOLS[a], float(weight)), (MOUTH_SYMBOLS[b], 1.0 - float(weight)))
        states.append(FaceState(Pose(float(tilt), float(turn), float(roll)), float(blink), float(smile), float(brow),
                                mouth))
    return states


def rate(work: Callable[[], object], count: int) -> str:
    """"median/s (best/s)" items per second of `work` (which handles `count` items) over PASSES passes."""
    work()  # warm caches (compiled drawing plan, pose rig)
    times = []
    for _ in range(PASSES):
        started = time.perf_counter()
        work()
        times.append(time.perf_counter() - started)
    return f"{count / statistics.median(times):,.0f}/s (best {count / min(times):,.0f}/s)"


def main() -> None:
    """Print states per second for each step on the sample faces."""
    states = varied_states(STATES)
    for name in ("female", "male"):
        print_rates(name, load_face(SAMPLE_FACES / f"{name}.json"), states)


def print_rates(name: str, face: FaceModel, states: list[FaceState]) -> None:
    """Print the states per second of each step for one face."""
    lifted = lift(face)
    posed = [pose_face(lifted, s) for s in states]
    geometry = rate(lambda: [pose_face(lifted, s) for s in states], STATES)
    paths = rate(lambda: [face_shapes(p) for p in posed], STATES)
    both = rate(lambda: [face_shapes(pose_face(lifted, s)) for s in states], STATES)
    drawing = rate(lambda: [face_group(face, pose_face(lifted, s), "u") for s in states[:300]], 300)
    print(f"{name}: pose_face {geometry}; face_shapes {paths}; pose_face + face_shapes {both} (target 5,000/s); "
          f"pose_face + face_group (lxml <g>) {drawing}")


if __name__ == "__main__":
    main()
