"""Emotions over time: their track, the blend with speech (seed 000 eq. 18) and the behaviour
fitted to them (animate/behaviour.py adapt_to_emotions)."""

from __future__ import annotations

import math

import numpy as np

from cartoonface.animate.behaviour import Action, adapt_to_emotions, emotion_at, schedule
from cartoonface.animate.frames import EASE_STEP, on_twos, states_at
from cartoonface.animate.timeline import LIPS_SPEAKING, build_timeline
from cartoonface.face.lift import lift
from cartoonface.face.model import load_face
from cartoonface.face.pose import pose_face
from cartoonface.face.state import FaceState
from cartoonface.speech.records import Alignment, Sentence, Syllable
from tests.conftest import ROOT

HAPPY = Action("emotion", 0.2, 3.6, 0.8, 0.4, 0.5, "happy")


def _alignment() -> Alignment:
    """One sentence 'a' 'a' from 1.0 to 2.0 s in 4 s of audio."""
    syllables = tuple(Syllable(text="啊", pinyin="a1", shapes=("a",), start=t, end=t + 0.5, confidence=1.0)
                      for t in (1.0, 1.5))
    return Alignment(sentences=(Sentence("啊啊", 1.0, 2.0, syllables),), duration=4.0, notes=())


def test_an_emotion_eases_in_holds_and_eases_out() -> None:
    timeline = build_timeline(_alignment(), (HAPPY,))
    times = np.arange(0, 4.0, 0.005)
    amounts = np.array([dict(s.emotion).get("happy", 0.0) for s in states_at(timeline, times)])
    assert amounts[times < 0.2].max() == 0 and amounts[times > 3.8].max() == 0
    held = amounts[(times >= 0.6) & (times <= 3.3)]
    assert (held == 0.8).all()
    rise = amounts[(times >= 0.2) & (times <= 0.6)]
    assert (np.diff(rise) >= 0).all()
    # in equal steps of at most EASE_STEP (to 0.01), as few as that allows
    levels = np.unique(rise)
    assert levels[0] == 0 and levels[-1] == 0.8 and len(levels) - 1 == math.ceil(0.8 / EASE_STEP)
    assert np.ptp(np.diff(levels)) <= 0.011 and np.diff(levels).max() <= EASE_STEP + 0.005
    # along smoothstep: slow at both ends of the rise, the middle step the shortest
    lasting = [int((rise == level).sum()) for level in levels[1:-1]]
    assert lasting[len(lasting) // 2] < min(lasting[0], lasting[-1])


def test_an_ease_is_drawn_on_twos() -> None:
    """on_twos: every second frame of an emotion's ease shows the emotion and gamma of the frame
    before, the mouth as it is; the ease's distinct drawings nearly halve."""
    timeline = build_timeline(_alignment(), (HAPPY,))
    frames = states_at(timeline, np.arange(0, 24) / 30)
    held = on_twos(frames)
    assert [s.mouth for s in held] == [s.mouth for s in frames]
    for i, (before, after) in enumerate(zip(frames, held, strict=True)):
        if i % 2:
            assert (after.emotion, after.lips) == (held[i - 1].emotion, held[i - 1].lips)
        else:
            assert after == before
    shown = [s.emotion for s in frames]
    assert len(set(held)) < len(set(frames)) and len({s.emotion for s in held}) < len(set(shown))


def test_the_lips_blend_gives_way_to_speech_and_comes_back() -> None:
    timeline = build_timeline(_alignment(), (HAPPY,))
    at_rest, talking, after = states_at(timeline, [0.5, 1.5, 3.0])
    assert at_rest.lips == 1.0 and after.lips == 1.0
    assert talking.lips == LIPS_SPEAKING


def test_a_happy_a_is_still_an_a_and_still_happy() -> None:
    """Seed 000 eq. 18: the 'a' opens as far as without the emotion (within 10 %), and its
    corners rise above the neutral 'a's as the happy face's do at rest."""
    face = load_face(ROOT / "samples" / "faces" / "female.json")
    lifted = lift(face)
    timeline = build_timeline(_alignment(), (HAPPY,))
    (state,) = states_at(timeline, [1.25])
    assert dict(state.mouth).get("a") == 1.0 and state.emotion == (("happy", 0.8),)
    happy = pose_face(lifted, state)
    plain = pose_face(lifted, FaceState(mouth=state.mouth))
    opening = (happy.p("2.3") - happy.p("2.2"))[1], (plain.p("2.3") - plain.p("2.2"))[1]
    assert abs(opening[0] - opening[1]) <= 0.1 * opening[1]
    for corner in ("8.3", "8.4"):
        assert happy.p(corner)[1] < plain.p(corner)[1] - 0.05 * face.fapu.mns0
    brows = [happy.p(n)[1] - plain.p(n)[1] for n in ("4.3", "4.4")]
    assert max(brows) < 0


def test_surprise_thins_the_blinks_and_holds_the_brows() -> None:
    plan = schedule(60.0, ((10.0, 10.8), (30.0, 31.0)), seed=2)
    surprised = adapt_to_emotions((*plan, Action("emotion", 0.0, 60.0, 1.0, 0.5, 0.5, "surprise")))
    happy = adapt_to_emotions((*plan, Action("emotion", 0.0, 60.0, 1.0, 0.5, 0.5, "happy")))

    def count(actions, kind):
        return sum(a.kind == kind for a in actions)

    assert count(plan, "blink") >= 10
    assert count(surprised, "blink") <= 0.5 * count(plan, "blink")
    assert count(surprised, "brow") <= 1  # one may start during the ease-in
    assert count(happy, "blink") == count(plan, "blink") and count(happy, "brow") == count(plan, "brow")
    assert adapt_to_emotions(plan) == plan


def test_emotion_at_follows_the_ramps() -> None:
    assert emotion_at((HAPPY,), 0.1) == {}
    assert emotion_at((HAPPY,), 0.4) == {"happy": 0.4}
    assert emotion_at((HAPPY,), 2.0) == {"happy": 0.8}
