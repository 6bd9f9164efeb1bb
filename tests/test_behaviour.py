"""Behaviour scheduler: statistics of a 10-minute schedule with a fixed seed (thesis 002, ch. 4)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from cartoonface.animate import behaviour
from cartoonface.animate.behaviour import Action, schedule, speech_pauses
from cartoonface.speech.records import Alignment, Sentence

DURATION = 600.0


def _pauses(seed: int = 7) -> tuple[tuple[float, float], ...]:
    """Sentence pauses of a 10-minute talk: 2-9 s sentences, 0.3-1.2 s silences."""
    rng = np.random.default_rng(seed)
    pauses, t = [], 1.0
    while True:
        t += rng.uniform(2.0, 9.0)
        gap = rng.uniform(0.3, 1.2)
        if t + gap >= DURATION:
            return tuple(pauses)
        pauses.append((round(t, 3), round(t + gap, 3)))
        t += gap


@pytest.fixture(scope="module")
def plan() -> tuple[Action, ...]:
    return schedule(DURATION, _pauses(), seed=1234)


def _of(plan, kind):
    return [a for a in plan if a.kind == kind]


def _intervals(actions):
    """Time from the end of each action to the start of the next (thesis 002, 4.2)."""
    return np.array([b.start - a.end for a, b in zip(actions, actions[1:])])


def test_blink_intervals_fit_gamma_2_148(plan):
    intervals = _intervals(_of(plan, "blink"))
    assert len(intervals) > 100
    result = stats.kstest(intervals, stats.gamma(a=behaviour.BLINK_ALPHA, scale=behaviour.BLINK_THETA).cdf)
    assert result.pvalue > 0.01


def test_blink_intervals_reject_a_wrong_distribution(plan):
    """The KS test above has power: the same intervals do not fit an exponential of equal mean."""
    intervals = _intervals(_of(plan, "blink"))
    mean = behaviour.BLINK_ALPHA * behaviour.BLINK_THETA
    assert stats.kstest(intervals, stats.expon(scale=mean).cdf).pvalue < 0.01


def test_blink_interval_sampler_matches_gamma():
    rng = np.random.Generator(np.random.PCG64(5))
    draws = np.array([behaviour.blink_interval(rng) for _ in range(2000)])
    assert stats.kstest(draws, stats.gamma(a=2, scale=1.48).cdf).pvalue > 0.01


def test_blink_shape_closes_faster_than_it_opens(plan):
    for blink in _of(plan, "blink"):
        assert blink.attack < blink.release
        assert blink.attack + blink.release < blink.duration
        assert blink.amplitude == pytest.approx(1.0)


@pytest.mark.parametrize(
    ("kind", "interval", "length"),
    [
        ("brow", behaviour.BROW_INTERVAL, behaviour.BROW_DURATION),
        ("tilt", behaviour.TILT_INTERVAL, behaviour.TILT_DURATION),
        ("turn", behaviour.TURN_INTERVAL, behaviour.TURN_DURATION),
    ],
)
def test_uniform_intervals_and_durations_stay_in_range(plan, kind, interval, length):
    actions = _of(plan, kind)
    assert len(actions) > 20
    nods = _of(plan, "nod")
    durations = np.array([a.duration for a in actions])
    assert durations.min() >= length[0] - 1e-9 and durations.max() <= length[1] + 1e-9
    # the draws spread over the range rather than sitting in one corner
    assert durations.max() - durations.min() > 0.5 * (length[1] - length[0])
    for a, b in zip(actions, actions[1:]):
        gap = b.start - a.end
        assert gap >= interval[0] - 1e-9
        # a move put off by a nod counts its interval from the nod's end
        nod_between = [n for n in nods if a.end <= n.start and n.end <= b.start]
        if nod_between:
            gap = b.start - max(n.end for n in nod_between)
        assert gap <= interval[1] + 1e-9, (kind, a, b)
    first_gap = actions[0].start
    assert interval[0] - 1e-9 <= first_gap


def test_nods_sit_before_pauses(plan):
    pauses = _pauses()
    nods = _of(plan, "nod")
    assert len(nods) > 0.8 * len(pauses)
    starts = [p[0] for p in pauses]
    for nod in nods:
        hold_start = nod.start + nod.attack  # head is down: end of d1
        pause = min(starts, key=lambda s: abs(s - (nod.end - nod.release)))
        t1 = pause - hold_start
        assert behaviour.NOD_T1[0] - 1e-3 <= t1 <= behaviour.NOD_T1[1] + 1e-3
        assert behaviour.NOD_D1[0] - 1e-3 <= nod.attack <= behaviour.NOD_D1[1] + 1e-3
        assert behaviour.NOD_D2[0] - 1e-3 <= nod.release <= behaviour.NOD_D2[1] + 1e-3
        # the head comes back up from the start of the pause
        assert nod.end - nod.release == pytest.approx(pause, abs=1e-3)
        assert nod.amplitude > 0


def test_no_tilt_or_turn_overlaps_a_nod(plan):
    nods = _of(plan, "nod")
    for move in _of(plan, "tilt") + _of(plan, "turn"):
        for nod in nods:
            assert move.end <= nod.start or nod.end <= move.start, (move, nod)


def test_actions_of_one_kind_never_overlap_and_stay_inside_the_audio(plan):
    for kind in behaviour.KINDS:
        actions = _of(plan, kind)
        assert all(a.end <= b.start for a, b in zip(actions, actions[1:]))
    assert all(0 <= a.start and a.end <= DURATION for a in plan)


def test_amplitudes_within_limits(plan):
    for action in plan:
        if action.kind in behaviour.ANGLE_KINDS:
            assert abs(action.amplitude) <= 15
        else:
            assert 0 <= action.amplitude <= 1
    turns = [a.amplitude for a in _of(plan, "turn")]
    assert min(turns) < 0 < max(turns)


def test_same_seed_same_schedule_different_seed_different():
    pauses = _pauses()
    assert schedule(DURATION, pauses, 3) == schedule(DURATION, pauses, 3)
    assert schedule(DURATION, pauses, 3) != schedule(DURATION, pauses, 4)


def test_pauses_do_not_change_blinks():
    with_pauses = schedule(120.0, _pauses()[:10], 9)
    without = schedule(120.0, (), 9)
    assert _of(with_pauses, "blink") == _of(without, "blink")
    assert not _of(without, "nod")


def test_schedule_is_sorted(plan):
    assert [a.start for a in plan] == sorted(a.start for a in plan)


@pytest.mark.parametrize("seed", range(5))
def test_short_audio_gets_a_valid_schedule(seed):
    """2 s of speech with a pause at 1.2 s: room for a nod before it, so the schedule is not
    empty, and every action stays inside the audio."""
    plan = schedule(2.0, ((1.2, 1.6),), seed)
    assert plan, "a 2 s recording with a pause gets at least one action"
    assert all(0 <= a.start and a.end <= 2.0 for a in plan)


def test_speech_pauses_from_sentences():
    sentences = tuple(Sentence("s", start, end, ()) for start, end in ((0.5, 2.0), (2.6, 4.0), (4.0, 5.0)))
    assert speech_pauses(Alignment(sentences, 6.0, ())) == ((2.0, 2.6), (5.0, 6.0))
    assert speech_pauses(Alignment(sentences, 5.0, ())) == ((2.0, 2.6),)


@pytest.mark.parametrize("kind", ["tilt", "turn"])
def test_head_moves_alternate_sides(plan, kind):
    targets = [a.amplitude for a in _of(plan, kind)]
    assert all(a * b < 0 for a, b in zip(targets, targets[1:]))
