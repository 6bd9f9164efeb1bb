"""Frames: one quantised FaceState per frame, frame i at time i / fps."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cartoonface.animate.behaviour import schedule, speech_pauses
from cartoonface.animate.frames import HOLD_STEP, on_twos, sample_frames, states_at
from cartoonface.animate.timeline import build_timeline
from cartoonface.errors import InputError, OptionError
from cartoonface.face.mouth import MOUTH_SYMBOLS
from cartoonface.face.state import FaceState, Pose
from cartoonface.speech.records import Alignment, Sentence, Syllable
from tests.synthetic import synthetic_talk


@pytest.fixture(scope="module")
def timeline():
    alignment = synthetic_talk(30.0, seed=2)
    return build_timeline(alignment, schedule(alignment.duration, speech_pauses(alignment), seed=5))


@pytest.mark.parametrize("fps", [0, 11, 61, -30, 30.5, True, "30"])
def test_fps_outside_12_to_60_is_refused(timeline, fps):
    with pytest.raises(OptionError, match="fps") as caught:
        sample_frames(timeline, fps)
    assert isinstance(caught.value, InputError)


@pytest.mark.parametrize("fps", [12, 30, 60])
def test_one_state_per_frame_covering_the_audio(timeline, fps):
    frames = sample_frames(timeline, fps)
    assert len(frames) == math.ceil(timeline.duration / 1000 * fps)
    assert all(isinstance(f, FaceState) for f in frames)


def test_frame_i_shows_time_i_over_fps(timeline):
    frames = sample_frames(timeline, 25)
    picks = [0, 1, 137, 400, len(frames) - 1]
    assert [frames[i] for i in picks] == list(states_at(timeline, np.array(picks) / 25))


def test_values_are_quantised_and_in_range(timeline):
    for state in set(sample_frames(timeline, 30)):
        for angle in (state.pose.tilt, state.pose.turn, state.pose.roll):
            assert abs(angle) <= 15 and round(angle * 10) == pytest.approx(angle * 10, abs=1e-6)
        for amount in (state.blink, state.brow):
            assert 0 <= amount <= 1 and round(amount * 100) == pytest.approx(amount * 100, abs=1e-6)
        weights = [w for _, w in state.mouth]
        assert sum(weights) == pytest.approx(1.0)
        assert all(0 < w <= 1 and round(w * 100) == pytest.approx(w * 100, abs=1e-6) for w in weights)
        symbols = [s for s, _ in state.mouth]
        assert symbols == sorted(symbols, key=MOUTH_SYMBOLS.index) and len(set(symbols)) == len(symbols)


def test_identical_consecutive_frames_are_detectable(timeline):
    frames = sample_frames(timeline, 60)
    repeats = sum(a == b for a, b in zip(frames, frames[1:]))
    assert repeats > 0.05 * len(frames)
    assert 1 < len(set(frames)) < len(frames)


def test_mouth_weights_ease_in_and_out():
    """Between two key frames the weight of the new shape follows smoothstep: slow, fast, slow."""
    syllables = (Syllable("a", "a1", ("a",), 1.0, 2.0, 1.0), Syllable("o", "o1", ("o",), 2.0, 3.0, 1.0))
    timeline = build_timeline(Alignment((Sentence("ao", 1.0, 3.0, syllables),), 4.0, ()), ())
    times = np.linspace(1.0, 2.0, 11)
    weights = np.array([dict(s.mouth).get("o", 0.0) for s in states_at(timeline, times)])
    assert weights[0] == 0 and weights[-1] == 1 and weights[5] == pytest.approx(0.5)
    steps = np.diff(weights)
    assert np.all(steps >= 0)
    assert steps[0] < steps[5] > steps[-1]


def test_head_angles_ease_in_and_out(timeline):
    from cartoonface.animate.behaviour import Action

    alignment = Alignment((), 3.0, ())
    moved = build_timeline(alignment, (Action("turn", 1.0, 1.0, 10.0),))
    turns = np.array([s.pose.turn for s in states_at(moved, np.linspace(1.0, 2.0, 21))])
    steps = np.diff(turns)
    assert np.all(steps >= 0) and turns[10] == pytest.approx(5.0)
    assert steps[0] < steps[10] > steps[-1]


def _turning(rate: float, frames: int = 12) -> tuple[FaceState, ...]:
    """States turning the head at `rate` degrees per frame from 0, with the mouth moving."""
    return tuple(FaceState(pose=Pose(turn=rate * i), mouth=((("a", "m")[i % 2], 1.0),)) for i in range(frames))


def test_a_slow_head_move_is_drawn_on_twos():
    slow = _turning(HOLD_STEP * 0.8)
    held = on_twos(slow)
    for i, (before, after) in enumerate(zip(slow, held, strict=True)):
        assert after.mouth == before.mouth  # only the pose is held
        assert abs(after.pose.turn - before.pose.turn) < HOLD_STEP  # never further than one slow step
        if i % 2:
            assert after.pose == held[i - 1].pose
        else:
            assert after == before
    assert len({s.pose for s in held}) < len({s.pose for s in slow})


def test_a_fast_head_move_keeps_every_pose():
    fast = _turning(HOLD_STEP * 2)
    assert on_twos(fast) == fast
