"""The body under the head: shoulders that follow the head a little, late, and breathe.

`body_motion(states, breaths, fps)` turns the face's frames and the breath track into the
torso's motion per frame: a share of the head's sideways lean (Pose.roll) and turn
(Pose.turn), low-pass filtered so the shoulders follow late and smoothly, and the depth of
the breath. render/scenery.py maps it to pixels (torso_motion) and render/animation.py
writes it as a transform of the clothes layer. Our choices of numbers (docs/animation.md
"Breathing and the shoulders").
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cartoonface.face.state import FaceState

# The shoulders turn with the head by this share of its roll and turn: the neck takes most of
# a head movement, the trunk a little of it.
FOLLOW = 0.3
# Seconds: time constant of each of two first-order lags in series the shoulders' share goes
# through, so they start late (about 2 x FOLLOW_LAG behind the head) and ease in and out.
FOLLOW_LAG = 0.12


@dataclass(frozen=True)
class BodyMotion:
    """The torso per frame (frame i at i / fps s): `roll` and `turn` (n,) degrees (Pose's
    senses: roll positive leans the top to the image left, turn positive to the image right),
    `breath` (n,) depth of the breath 0..1."""

    roll: np.ndarray
    turn: np.ndarray
    breath: np.ndarray


def follow(angles: np.ndarray, fps: int) -> np.ndarray:
    """FOLLOW x `angles` ((n,) degrees, one per frame at `fps`) delayed and eased by two
    first-order lags of FOLLOW_LAG s in series, starting at rest at the first angle."""
    keep = float(np.exp(-1.0 / (fps * FOLLOW_LAG)))  # share of the lagged value kept from frame to frame
    ease = 1.0 - keep
    targets = (FOLLOW * np.asarray(angles, dtype=float)).tolist()
    if not targets:
        return np.zeros(0)
    # Both lags in one pass, each starting at rest at its own first input (the second's is the
    # first's first output); Python floats, as numpy's per-element arithmetic: the same bits.
    first = targets[0]
    second = keep * first + ease * first
    out = []
    for target in targets:
        first = keep * first + ease * target
        second = keep * second + ease * first
        out.append(second)
    return np.array(out)


def body_motion(states: Sequence[FaceState], breaths: np.ndarray, fps: int) -> BodyMotion:
    """The torso's motion for the face `states` and the breath depths `breaths` ((n,) 0..1,
    frames.sample_breaths), both one per frame at `fps` frames per second."""
    if len(breaths) != len(states):
        raise ValueError(f"{len(breaths)} breath depths for {len(states)} frames; expected one per frame")
    roll = np.array([state.pose.roll for state in states], dtype=float)
    turn = np.array([state.pose.turn for state in states], dtype=float)
    return BodyMotion(roll=follow(roll, fps), turn=follow(turn, fps), breath=np.asarray(breaths, dtype=float))
