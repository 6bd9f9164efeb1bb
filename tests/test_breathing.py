"""Breaths taken in the pauses (issue 11, "Body"): the schedule, actions.json and the timeline."""

from __future__ import annotations

import json

import numpy as np
import pytest

from cartoonface.animate.actions import actions_from_json, actions_to_json
from cartoonface.animate.behaviour import BREATH_INTERVAL, BREATH_LEAD, BREATH_PAUSE, Action, schedule
from cartoonface.animate.frames import breaths_at, sample_breaths
from cartoonface.animate.timeline import build_timeline
from cartoonface.errors import ActionsError
from cartoonface.speech.records import Alignment, Sentence

DURATION = 60.0
# sentences of 2-7 s with pauses of 0.15-1.0 s, the first after 0.6 s of silence
LENGTHS = (4.0, 2.0, 7.0, 3.0, 5.5, 2.5, 6.0, 4.5, 3.5, 5.0, 2.0, 4.0)
GAPS = (0.6, 0.5, 0.15, 0.8, 0.3, 1.0, 0.4, 0.2, 0.7, 0.5, 0.9, 0.45)


def _speech() -> tuple[tuple[float, float], ...]:
    spans, t = [], 0.0
    for gap, length in zip(GAPS, LENGTHS, strict=True):
        spans.append((t + gap, t + gap + length))
        t += gap + length
    return tuple(spans)


def _pauses(speech):
    return tuple((a[1], b[0]) for a, b in zip(speech, speech[1:]))


def _breaths(seed=0):
    speech = _speech()
    return [a for a in schedule(DURATION, _pauses(speech), seed, speech=speech) if a.kind == "breath"]


def _silences(speech):
    return [(0.0, speech[0][0]), *_pauses(speech)]


def test_a_breath_in_every_pause_long_enough_and_none_while_speaking():
    speech = _speech()
    breaths = _breaths()
    long_enough = [s for s in _silences(speech) if s[1] - s[0] >= BREATH_PAUSE]
    assert len(long_enough) < len(_silences(speech))  # the short pauses are left out
    assert all(b[1] - a[1] >= BREATH_INTERVAL for a, b in zip(long_enough, long_enough[1:]))  # none spoken through
    assert len(breaths) == len(long_enough)
    for breath, (begin, end) in zip(breaths, long_enough, strict=True):
        inhaled = breath.start + breath.attack
        assert begin - 1e-9 <= breath.start and inhaled <= end - BREATH_LEAD + 1e-3  # breathing in in the silence
        assert breath.attack < breath.release  # quick in, slow out over the words


def test_deeper_breaths_before_longer_stretches_of_speech():
    breaths = _breaths()
    resumes = [b.start + b.attack + BREATH_LEAD for b in breaths]  # the speech after each breath starts
    talk = [later.start - resume for later, resume in zip(breaths[1:], resumes)]  # to the next breath
    assert np.corrcoef(talk, [b.amplitude for b in breaths[:-1]])[0, 1] > 0.8
    assert all(0 < b.amplitude <= 1 for b in breaths)


def test_breaths_are_reproducible_from_the_seed_and_do_not_change_the_rest():
    speech = _speech()
    assert _breaths(3) == _breaths(3)
    assert _breaths(3) != _breaths(4)
    plan = schedule(DURATION, _pauses(speech), 3, speech=speech)
    others = [a for a in plan if a.kind != "breath"]
    assert others  # the other kinds are drawn from their own streams, as before breaths existed
    assert all(a.end <= b.start for a, b in zip(_breaths(3), _breaths(3)[1:]))


def test_breaths_round_trip_through_actions_json():
    speech = _speech()
    plan = schedule(DURATION, _pauses(speech), 2, speech=speech)
    assert any(a.kind == "breath" for a in plan)
    assert actions_from_json(actions_to_json(plan), "actions.json", DURATION) == plan


def _doc(*rows: dict) -> str:
    return json.dumps({"format": "cartoonface-actions", "version": 1, "actions": list(rows)})


@pytest.mark.parametrize(
    ("row", "field", "words"),
    [
        ({"amplitude": 1.5}, "actions[0].amplitude", "0 to 1"),
        ({"amplitude": -0.2}, "actions[0].amplitude", "0 to 1"),
        ({"attack": 0.5, "release": 3.0}, "actions[0].release", "exceed the duration"),
        ({"duration": 0}, "actions[0].duration", "more than 0"),
        ({"start": 59.0}, "actions[0].duration", "past the end"),
        ({"depth": 0.5}, "actions[0].depth", "unknown field"),
    ],
)
def test_bad_breaths_are_refused_naming_the_field(row, field, words):
    good = {"kind": "breath", "start": 10.0, "duration": 3.0, "amplitude": 0.6, "attack": 0.4, "release": 2.6}
    with pytest.raises(ActionsError) as error:
        actions_from_json(_doc({**good, **row}), "actions.json", DURATION)
    assert field in str(error.value) and words in str(error.value)


def test_overlapping_breaths_are_refused():
    first = {"kind": "breath", "start": 10.0, "duration": 3.0, "amplitude": 0.6, "attack": 0.4, "release": 2.6}
    with pytest.raises(ActionsError, match=r"actions\[1\].start.*breath"):
        actions_from_json(_doc(first, {**first, "start": 12.0}), "actions.json", DURATION)


def test_the_chest_rises_in_the_pause_and_sinks_over_the_words():
    breath = Action("breath", 2.0, 4.0, 0.8, 0.5, 3.5)
    sentences = (Sentence("a", 0.5, 2.0, ()), Sentence("b", 2.55, 6.0, ()))
    timeline = build_timeline(Alignment(sentences, 8.0, ()), (breath,))
    before, top, middle, after = breaths_at(timeline, [1.9, 2.5, 4.25, 6.5])
    assert before == 0 and top == pytest.approx(0.8) and 0 < middle < top and after == 0
    depths = sample_breaths(timeline, 30)
    assert len(depths) == 240
    rising = np.diff(depths[60:75])  # 2.0-2.5 s
    assert (rising >= 0).all() and rising.sum() > 0.7


def test_breaths_are_also_taken_in_the_pauses_inside_sentences():
    from cartoonface.animate.behaviour import silences_of
    from cartoonface.speech.records import Syllable

    def syllables(*times):
        return tuple(Syllable("你", "ni3", ("n", "i"), start, end, 1.0) for start, end in times)

    sentences = (Sentence("a", 0.5, 9.0, syllables((0.5, 4.0), (4.1, 5.0), (5.6, 9.0))),
                 Sentence("b", 9.5, 12.0, syllables((9.5, 12.0))))
    alignment = Alignment(sentences, 13.0, ())
    silences = silences_of(alignment)
    assert silences == ((5.0, 5.6), (9.0, 9.5), (12.0, 13.0))  # the 0.1 s gap is too short to breathe
    speech = ((0.5, 9.0), (9.5, 12.0))
    plan = schedule(13.0, ((9.0, 9.5), (12.0, 13.0)), 1, speech=speech, breath_pauses=silences)
    inhaled = [a.start + a.attack for a in plan if a.kind == "breath"]
    assert len(inhaled) == 3 and 5.0 < inhaled[1] < 5.6  # before the sentence, at its inner pause, between
    close = schedule(13.0, ((9.0, 9.5), (12.0, 13.0)), 1, speech=speech, breath_pauses=((5.0, 5.6), (6.5, 7.0)))
    assert len([a for a in close if a.kind == "breath"]) == 2  # 6.5-7.0 comes too soon after 5.0-5.6
