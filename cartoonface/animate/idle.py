"""Idle head motion: a small continuous sway under the scheduled tilts, turns and nods.

A still head between scheduled moves looks frozen; people's heads drift all
the time. `sway(times, seed, peak)` is smooth noise: per axis a sum of
COMPONENTS sines with periods drawn in PERIODS and random phases, weighted
1, 1/2, 1/3 and scaled so it never exceeds its peak. `with_sway` adds it to
the poses of sampled frames. Reproducible from the seed; our choice of
numbers (docs/animation.md "Idle motion").
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cartoonface.face.state import MAX_ANGLE, FaceState, trusted_pose, trusted_state

COMPONENTS = 3
PERIODS = (2.5, 9.0)  # seconds: slow, like a breathing or standing sway
# Share of the peak per axis (tilt about X, turn about Y, roll about Z): the
# roll is drawn as a rotation of the whole head (cheap in the SVG, render/animation.py),
# tilt and turn redraw the face and move less.
AXES = (0.0, 0.0, 1.0)
# A child of the seed no other random stream uses (behaviour.schedule uses 0-7).
SWAY_STREAM = 8
ANGLE_STEP = 1  # decimals: angles to 0.1 degree, as frames.py quantises them


def sway(times: np.ndarray, seed: int, peak: float) -> np.ndarray:
    """(n, 3) degrees (tilt, turn, roll) of sway at `times` ((n,) seconds), each within AXES x `peak`."""
    child = np.random.SeedSequence(seed).spawn(SWAY_STREAM + 1)[SWAY_STREAM]
    rng = np.random.Generator(np.random.PCG64(child))
    t = np.asarray(times, dtype=float)
    weights = 1.0 / np.arange(1, COMPONENTS + 1)
    out = np.zeros((len(t), len(AXES)))
    for axis, share in enumerate(AXES):
        periods = rng.uniform(*PERIODS, size=COMPONENTS)
        phases = rng.uniform(0.0, 2 * np.pi, size=COMPONENTS)
        waves = np.sin(2 * np.pi * t[:, None] / periods + phases) @ weights
        out[:, axis] = share * peak * waves / weights.sum()
    return out


def with_sway(states: Sequence[FaceState], fps: int, seed: int, peak: float) -> tuple[FaceState, ...]:
    """`states` (frame i at i / fps s) with the sway of `seed` and `peak` degrees added to each pose.

    Angles are rounded to 0.1 degree and kept within +-MAX_ANGLE; identical
    consecutive states stay equal (and are the same object).
    """
    angles = sway(np.arange(len(states)) / fps, seed, peak)
    out: list[FaceState] = []
    previous: tuple | None = None
    for state, (tilt, turn, roll) in zip(states, angles.tolist(), strict=True):
        pose = state.pose
        values = (
            _angle(pose.tilt + tilt),
            _angle(pose.turn + turn),
            _angle(pose.roll + roll),
        )
        key = (state, values)
        if out and key == previous:
            out.append(out[-1])
            continue
        out.append(trusted_state(state, pose=trusted_pose(*values)))  # angles clamped and rounded: in range
        previous = key
    return tuple(out)


def _angle(value: float) -> float:
    """`value` degrees rounded to 0.1 and kept within +-MAX_ANGLE (no negative zero)."""
    return round(min(max(value, -MAX_ANGLE), MAX_ANGLE), ANGLE_STEP) + 0.0
