"""idle.with_sway's angles: vectorised, yet each one Python's round(x, 1) of the clamped sum."""

import numpy as np

from cartoonface.animate.idle import rounded_angles, sway, with_sway
from cartoonface.face.state import MAX_ANGLE, FaceState, Pose

FPS = 30


def _round(value: float) -> float:
    """The scalar definition: clamped to +-MAX_ANGLE, Python's round to 0.1, no negative zero."""
    return round(min(max(value, -MAX_ANGLE), MAX_ANGLE), 1) + 0.0


def test_rounded_angles_round_as_python_does_next_to_halves_too():
    halves = (np.arange(-160, 161) + 0.5) / 10  # k/10 + 0.05: decided by the decimal value, not by 10 x
    values = np.concatenate([halves, np.nextafter(halves, 99.0), np.nextafter(halves, -99.0),
                             np.random.default_rng(3).uniform(-20, 20, 5000), [-0.0, -0.04, 0.04]])
    got = rounded_angles(values)
    expected = [_round(value) for value in values.tolist()]
    assert got.tolist() == expected
    assert not np.signbit(got[got == 0]).any()


def test_with_sway_adds_the_sway_to_each_pose_and_rounds_it():
    poses = [Pose(tilt=2.3, turn=-1.1, roll=0.4)] * 40 + [Pose(roll=14.9)] * 40 + [Pose(roll=-14.9)] * 40
    states = tuple(FaceState(pose=pose) for pose in poses)
    swayed = with_sway(states, FPS, 2, 1.5)
    added = sway(np.arange(len(states)) / FPS, 2, 1.5)
    for state, after, (tilt, turn, roll) in zip(states, swayed, added.tolist(), strict=True):
        pose = state.pose
        assert (after.pose.tilt, after.pose.turn, after.pose.roll) == (
            _round(pose.tilt + tilt), _round(pose.turn + turn), _round(pose.roll + roll))
        assert after.mouth == state.mouth and after.blink == state.blink
    for a, b in zip(swayed, swayed[1:]):
        assert (a == b) == (a is b)
