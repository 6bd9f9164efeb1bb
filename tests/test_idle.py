"""The idle sway added as frames are sampled: each angle Python's round(x, 1) of the clamped sum."""

import dataclasses

import numpy as np
import pytest

from cartoonface.animate.behaviour import schedule, speech_pauses
from cartoonface.animate.frames import frame_times, states_at
from cartoonface.animate.idle import rounded_angles, sway
from cartoonface.animate.timeline import Keyframe, Track, build_timeline
from cartoonface.errors import OptionError
from cartoonface.face.state import MAX_ANGLE
from tests.synthetic import synthetic_talk

FPS = 30


@pytest.fixture(scope="module")
def timeline():
    alignment = synthetic_talk(20.0, seed=4)
    return build_timeline(alignment, schedule(alignment.duration, speech_pauses(alignment), seed=1))


def _round(value: float) -> float:
    """The scalar definition: clamped to +-MAX_ANGLE, Python's round to 0.1, no negative zero."""
    return round(min(max(value, -MAX_ANGLE), MAX_ANGLE), 1) + 0.0


def test_rounded_angles_round_as_python_does_next_to_halves_too():
    halves = (np.arange(-160, 161) + 0.5) / 10  # k/10 + 0.05: decided by the decimal value, not by 10 x
    values = np.concatenate([halves, np.nextafter(halves, 99.0), np.nextafter(halves, -99.0),
                             np.random.default_rng(3).uniform(-20, 20, 5000), [-0.0, -0.04, 0.04]])
    got = rounded_angles(values)
    assert got.tolist() == [_round(value) for value in values.tolist()]
    assert not np.signbit(got[got == 0]).any()


@pytest.mark.parametrize("peak", [1.5, 40.0])  # 40: the sums reach the +-MAX_ANGLE clamp
def test_the_sway_is_added_to_each_sampled_pose_and_rounded(timeline, peak):
    times = frame_times(timeline, FPS)
    added = sway(times, 2, peak)
    still = states_at(timeline, times)
    swayed = states_at(timeline, times, added)
    assert len(swayed) == len(still)
    for before, after, (tilt, turn, roll) in zip(still, swayed, added.tolist(), strict=True):
        pose = before.pose
        assert (after.pose.tilt, after.pose.turn, after.pose.roll) == (
            _round(pose.tilt + tilt), _round(pose.turn + turn), _round(pose.roll + roll))
        assert dataclasses.replace(after, pose=pose) == before
    for a, b in zip(swayed, swayed[1:]):
        assert (a == b) == (a is b)


def test_an_angle_out_of_range_is_named_before_the_sway_clamps_it(timeline):
    wild = Track("tilt", (Keyframe(0, 0.0), Keyframe(1000, MAX_ANGLE + 5)), "cosine")
    broken = dataclasses.replace(timeline, tracks=tuple(wild if t.name == "tilt" else t for t in timeline.tracks))
    times = frame_times(broken, FPS)
    with pytest.raises(OptionError, match="roll"):
        states_at(broken, times, sway(times, 0, 1.0))
