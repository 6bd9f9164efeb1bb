"""The performer: gaze, brows and nods on the voice, smiles, idle sway, styles."""

from __future__ import annotations

import numpy as np
import pytest

from cartoonface.animate import gaze
from cartoonface.animate.actions import actions_from_json, actions_to_json
from cartoonface.animate.behaviour import ANGLE_KINDS, KINDS, MAX_ANGLE, schedule, speech_pauses
from cartoonface.animate.frames import frame_times, sample_frames, states_at
from cartoonface.animate.idle import sway
from cartoonface.animate.prosody import pitch_peaks
from cartoonface.animate.style import ANNOUNCER, PAGE_STYLES, STORYTELLER, STYLES
from cartoonface.animate.timeline import build_timeline
from cartoonface.errors import OptionError
from cartoonface.face.lift import lift
from cartoonface.face.model import load_face
from cartoonface.face.pose import pose_face
from cartoonface.face.state import MAX_GAZE, FaceState
from cartoonface.pipeline import Options, check_options
from cartoonface.speech.audio import Audio
from tests.conftest import run_cli
from tests.synthetic import synthetic_talk

DURATION = 600.0
FPS = 30


@pytest.fixture(scope="module")
def talk():
    return synthetic_talk(DURATION, seed=3)


def _speech(talk):
    return tuple((s.start, s.end) for s in talk.sentences)


def _peaks(talk, every: int = 3) -> tuple[float, ...]:
    """Every `every`-th syllable's middle as a pitch peak."""
    syllables = [syl for s in talk.sentences for syl in s.syllables]
    return tuple(round((syl.start + syl.end) / 2, 3) for syl in syllables[::every])


def _plan(talk, style=ANNOUNCER, seed=11, peaks=None):
    return schedule(DURATION, speech_pauses(talk), seed, style=style,
                    peaks=_peaks(talk) if peaks is None else peaks, speech=_speech(talk))


def _saccades(plan):
    """(start, duration) of each gaze shift (a gaze_h and a gaze_v at one start are one shift)."""
    return sorted({(a.start, a.duration) for a in plan if a.kind in ("gaze_h", "gaze_v")})


def _gaze_at(plan, kind, t):
    """The gaze angle of `kind` held at time `t` (after every move of that kind that ended by t)."""
    done = [a for a in plan if a.kind == kind and a.end <= t + 1e-9]
    return done[-1].amplitude if done else 0.0


@pytest.mark.parametrize("style", list(STYLES.values()), ids=list(STYLES))
def test_gaze_shifts_happen_and_stay_within_the_limits(talk, style):
    plan = _plan(talk, style)
    shifts = _saccades(plan)
    assert len(shifts) > DURATION / 60  # more than one a minute
    angles = [a.amplitude for a in plan if a.kind in ("gaze_h", "gaze_v")]
    assert max(abs(a) for a in angles) <= max(gaze.AWAY_RANGE[1], gaze.DOWN_RANGE[1]) <= MAX_GAZE
    assert any(abs(a) >= gaze.AWAY_RANGE[0] for a in angles)  # some glances really go away
    states = sample_frames(build_timeline(talk, plan), FPS)
    assert max(max(abs(s.gaze_h), abs(s.gaze_v)) for s in states) <= MAX_GAZE
    assert {s.gaze_h for s in states} != {0.0}


def test_saccade_durations_and_fixations_follow_the_cited_ranges(talk):
    plan = _plan(talk, STORYTELLER)
    shifts = _saccades(plan)
    longest = gaze.saccade_duration(float(np.hypot(2 * gaze.AWAY_RANGE[1], gaze.DOWN_RANGE[1])))
    durations = np.array([d for _, d in shifts])
    assert durations.min() >= gaze.SACCADE_D0 and durations.max() <= longest <= 0.1
    starts = np.array([s for s, _ in shifts])
    ends = starts + durations
    fixations = starts[1:] - ends[:-1]
    assert fixations.min() >= gaze.MIN_FIXATION - 1e-9
    # each saccade lasts what the main sequence gives for its size
    h = v = 0.0
    for start, length in shifts:
        new_h = next((a.amplitude for a in plan if a.kind == "gaze_h" and a.start == start), h)
        new_v = next((a.amplitude for a in plan if a.kind == "gaze_v" and a.start == start), v)
        assert length == gaze.saccade_duration(float(np.hypot(new_h - h, new_v - v)))
        h, v = new_h, new_v


def test_eyes_are_back_on_the_viewer_before_each_sentence_ends(talk):
    plan = _plan(talk, STORYTELLER)
    for start, end in _speech(talk):
        t = end - gaze.END_LOOK
        if t > start:
            offset = np.hypot(_gaze_at(plan, "gaze_h", t), _gaze_at(plan, "gaze_v", t))
            assert offset <= gaze.DART_RADIUS + 1e-9


def _apex_near(plan, peaks, window=0.1):
    """Share of brow raises fully up within `window` s of a peak."""
    brows = [a for a in plan if a.kind == "brow"]
    peak_times = np.array(peaks)
    near = [np.min(np.abs(peak_times - (b.start + b.attack))) <= window for b in brows]
    return float(np.mean(near))


def test_brows_sit_on_pitch_peaks_far_more_often_than_chance(talk):
    peaks = _peaks(talk, every=5)
    placed = _plan(talk, peaks=peaks)
    chance = _plan(talk, peaks=())
    assert _apex_near(placed, peaks) > 0.6
    assert _apex_near(placed, peaks) > 2 * _apex_near(chance, peaks)


def test_storyteller_nods_on_peaks_and_announcer_only_before_pauses(talk):
    peaks = _peaks(talk, every=4)
    pause_starts = np.array([p[0] for p in speech_pauses(talk)])
    for style, expect_beats in ((ANNOUNCER, False), (STORYTELLER, True)):
        nods = [a for a in _plan(talk, style, peaks=peaks) if a.kind == "nod"]
        beats = [n for n in nods if np.min(np.abs(np.array(peaks) - (n.start + n.attack))) < 1e-6]
        assert bool(beats) == expect_beats
        others = [n for n in nods if n not in beats]
        assert all(np.min(np.abs(pause_starts - n.end)) < 1.5 for n in others)


def test_smiles_are_slight_and_come_at_sentence_ends(talk):
    plan = _plan(talk, STORYTELLER)
    smiles = [a for a in plan if a.kind == "smile"]
    assert smiles
    ends = np.array([e for _, e in _speech(talk)])
    for smile in smiles:
        assert 0 < smile.amplitude <= 0.5
        assert np.min(np.abs(ends - smile.start)) <= 1.0


def _motion(plan):
    """Summed head angle travelled (turn and tilt moves, nods down and up) and counts."""
    travel = 0.0
    for kind in ("turn", "tilt"):
        angles = [0.0] + [a.amplitude for a in plan if a.kind == kind]
        travel += float(np.abs(np.diff(angles)).sum())
    travel += 2 * sum(a.amplitude for a in plan if a.kind == "nod")
    return travel


def test_storyteller_moves_more_than_announcer(talk):
    for seed in (1, 2, 3):
        calm, lively = _plan(talk, ANNOUNCER, seed), _plan(talk, STORYTELLER, seed)
        assert _motion(lively) > 1.3 * _motion(calm)
        assert len(_saccades(lively)) > len(_saccades(calm))
        assert sum(a.kind == "brow" for a in lively) > sum(a.kind == "brow" for a in calm)
    assert np.ptp(sway(np.arange(300) / FPS, 0, STORYTELLER.sway_peak)) > \
        np.ptp(sway(np.arange(300) / FPS, 0, ANNOUNCER.sway_peak))


def test_same_seed_same_schedule_and_round_trip(talk):
    plan = _plan(talk, STORYTELLER, seed=5)
    assert plan == _plan(talk, STORYTELLER, seed=5)
    assert plan != _plan(talk, STORYTELLER, seed=6)
    assert {a.kind for a in plan} == set(KINDS) - {"emotion"}  # emotions are the user's, never drawn
    assert actions_from_json(actions_to_json(plan), "actions.json", DURATION) == plan
    for action in plan:
        if action.kind in ANGLE_KINDS:
            assert abs(action.amplitude) <= MAX_ANGLE


def test_sway_is_small_smooth_and_seeded():
    times = np.arange(60 * FPS) / FPS
    peak = 1.2
    one = sway(times, 4, peak)
    assert np.abs(one).max() <= peak + 1e-9
    assert np.abs(one).max() > peak / 4  # it does move
    assert np.abs(np.diff(one, axis=0)).max() < peak * 2 * np.pi / 2.5 / FPS + 1e-9  # no faster than its fastest wave
    assert np.array_equal(one, sway(times, 4, peak))
    assert not np.array_equal(one, sway(times, 5, peak))


def test_the_sway_moves_the_head_and_keeps_equal_frames_equal():
    timeline = build_timeline(synthetic_talk(3.0, seed=1), ())
    times = frame_times(timeline, FPS)
    swayed = states_at(timeline, times, sway(times, 0, 1.0))
    rolls = [s.pose.roll for s in swayed]
    assert len(set(rolls)) > 3 and max(abs(r) for r in rolls) <= 1.0
    for a, b in zip(swayed, swayed[1:]):
        assert (a == b) == (a is b)


def test_gaze_turns_the_pupils_its_way(root):
    face = lift(load_face(root / "samples" / "faces" / "female.json"))
    centre = pose_face(face, FaceState()).pupils
    for h, v in ((8, 0), (-8, 0), (0, 8), (0, -8)):
        moved = pose_face(face, FaceState(gaze_h=h, gaze_v=v)).pupils - centre
        along, across = (moved[:, 0], moved[:, 1]) if h else (moved[:, 1], moved[:, 0])
        assert np.all(np.sign(along) == np.sign(h + v)) and np.all(np.abs(along) > 2.0)
        assert np.all(np.abs(across) < 0.5)
    with pytest.raises(OptionError, match="gaze_h"):
        FaceState(gaze_h=MAX_GAZE + 1)


def _voice(talk, high: set[int], rate: int = 16000) -> Audio:
    """A buzz (continuous phase) at 130 Hz on every syllable, 200 Hz on the syllables numbered in `high`."""
    t = np.arange(int(talk.duration * rate)) / rate
    f0 = np.zeros_like(t)
    syllables = [syl for s in talk.sentences for syl in s.syllables]
    for i, syl in enumerate(syllables):
        f0[(t >= syl.start) & (t < syl.end)] = 200.0 if i in high else 130.0
    phase = 2 * np.pi * np.cumsum(f0) / rate
    samples = np.where(f0 > 0, sum(0.3 / k * np.sin(k * phase) for k in range(1, 4)), 0.0)
    return Audio(samples.astype(np.float32), rate, "voice")


def test_pitch_peaks_find_the_high_syllables():
    talk = synthetic_talk(20.0, seed=1)
    syllables = [syl for s in talk.sentences for syl in s.syllables]
    high = set(range(2, len(syllables), 5))
    peaks = np.array(pitch_peaks(_voice(talk, high), talk))
    assert len(peaks)
    for i, syl in enumerate(syllables):
        found = bool(np.any((peaks >= syl.start) & (peaks < syl.end)))
        assert found == (i in high), (i, syl.start)


def test_style_option_is_checked_and_pages_have_defaults():
    assert set(PAGE_STYLES.values()) <= set(STYLES)
    check_options(Options(style="storyteller"))
    with pytest.raises(OptionError, match="style 'lively'"):
        check_options(Options(style="lively"))


def test_cli_refuses_an_unknown_style(tmp_path):
    done = run_cli("generate", "--face", "f.json", "--audio", "a.wav", "--transcript", "t.txt",
                   "-o", tmp_path / "out", "--style", "lively")
    assert done.returncode == 2
    assert "--style" in done.stderr and "lively" in done.stderr
    assert not (tmp_path / "out").exists()
