"""Idle head motion: a small continuous sway under the scheduled tilts, turns and nods.

A still head between scheduled moves looks frozen; people's heads drift all
the time. `sway(times, seed, peak)` is smooth noise: per axis a sum of
COMPONENTS sines with periods drawn in PERIODS and random phases, weighted
1, 1/2, 1/3 and scaled so it never exceeds its peak. frames.states_at adds it to
the poses of the sampled frames (`rounded_angles`: the sums to 0.1 degree).
Reproducible from the seed; our choice of numbers (docs/animation.md "Idle motion").
"""

from __future__ import annotations

import numpy as np

from cartoonface.face.state import MAX_ANGLE

COMPONENTS = 3
PERIODS = (2.5, 9.0)  # seconds: slow, like a breathing or standing sway
# Share of the peak per axis (tilt about X, turn about Y, roll about Z): the
# roll is drawn as a rotation of the whole head (cheap in the SVG, render/animation.py),
# tilt and turn redraw the face and move less.
AXES = (0.0, 0.0, 1.0)
# A child of the seed no other random stream uses (behaviour.schedule uses 0-7).
SWAY_STREAM = 8
ANGLE_STEP = 1  # decimals: angles to 0.1 degree, as frames.py quantises them
# |10 x - (k + 1/2)| below this is left to round(): the product 10 x of an angle within MAX_ANGLE is
# off by less than 1e-13, so rint decides every value further from a half as round() does.
TIE_MARGIN = 1e-6


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


def rounded_angles(values: np.ndarray) -> np.ndarray:
    """`values` (any shape, degrees) kept within +-MAX_ANGLE and rounded to 0.1 exactly as Python's
    round(x, 1) does (the decimal value of x, half to even), without negative zero.

    rint(10 x) / 10 is that result wherever 10 x is not next to a half (its product's error is far
    smaller than the margin); the few values next to one are rounded by round() itself.
    """
    clamped = np.clip(values, -MAX_ANGLE, MAX_ANGLE)
    scaled = clamped * 10**ANGLE_STEP
    out = np.rint(scaled) / 10**ANGLE_STEP + 0.0
    near_half = np.abs(scaled - np.floor(scaled) - 0.5) < TIE_MARGIN
    out[near_half] = [round(value, ANGLE_STEP) + 0.0 for value in clamped[near_half].tolist()]
    return out
