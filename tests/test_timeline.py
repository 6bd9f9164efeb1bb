"""Timeline: lip key frames from aligned syllables (thesis 002, 5.3/5.4) and behaviour tracks."""

from __future__ import annotations

import pytest

from cartoonface.animate.behaviour import Action
from cartoonface.animate.frames import states_at
from cartoonface.animate.timeline import CLOSURE_MS, FINAL_LENGTHENING, LAG_MS, LEAD_MS, REST, build_timeline
from cartoonface.face.emotion import EMOTIONS
from cartoonface.speech.records import Alignment, Sentence, Syllable
from cartoonface.speech.mouth_shapes import shape_onsets


def _syllable(shapes: tuple[str, ...], start: float, end: float) -> Syllable:
    return Syllable(text="x", pinyin="x1", shapes=shapes, start=start, end=end, confidence=1.0)


def _alignment() -> Alignment:
    """Two sentences separated by a 0.8 s pause; syllables of 1 to 4 shapes."""
    first = (
        _syllable(("a",), 0.50, 0.74),
        _syllable(("z", "i"), 0.74, 1.02),
        _syllable(("u", "a", "n"), 1.02, 1.38),
        _syllable(("h", "u", "a", "n"), 1.38, 1.80),
    )
    second = (
        _syllable(("f", "o"), 2.60, 2.90),
        _syllable(("i", "e"), 2.95, 3.30),
    )
    return Alignment(
        sentences=(Sentence("one", 0.50, 1.80, first), Sentence("two", 2.60, 3.30, second)),
        duration=4.2,
        notes=(),
    )


def _dominant(state) -> str:
    return max(state.mouth, key=lambda pair: pair[1])[0]


def _onsets(alignment):
    """(shape, time) of every key of thesis 5.3; before a pause (here: sentence-final) the
    onsets are fractions of the syllable without its phrase-final lengthening."""
    for sentence in alignment.sentences:
        for syllable in sentence.syllables:
            fractions = shape_onsets(len(syllable.shapes))
            length = syllable.end - syllable.start
            if syllable is sentence.syllables[-1]:
                length /= FINAL_LENGTHENING
            for shape, fraction in zip(syllable.shapes, fractions, strict=True):
                yield shape, syllable.start + fraction * length


def test_dominant_shape_at_each_onset_is_that_shape():
    alignment = _alignment()
    timeline = build_timeline(alignment, ())
    onsets = list(_onsets(alignment))
    states = states_at(timeline, [t for _, t in onsets])
    assert [_dominant(s) for s in states] == [shape for shape, _ in onsets]


def test_mouth_rests_in_pauses_and_before_and_after_speech():
    timeline = build_timeline(_alignment(), ())
    lead, lag = LEAD_MS / 1000, LAG_MS / 1000
    quiet = [0.0, 0.5 - lead - 0.05, 1.80 + lag + 0.01, 2.2, 2.60 - lead - 0.01, 3.30 + lag + 0.01, 4.1]
    for state in states_at(timeline, quiet):
        assert state.mouth == ((REST, 1.0),)


def test_mouth_opens_slightly_before_the_sound_and_closes_after():
    timeline = build_timeline(_alignment(), ())
    before, after = states_at(timeline, [0.5 - LEAD_MS / 2000, 3.30 + LAG_MS / 2000])
    assert 0 < dict(before.mouth).get(REST, 0) < 1
    assert 0 < dict(after.mouth).get(REST, 0) < 1
    # the last shape of a sentence holds until the sound ends
    assert states_at(timeline, [1.80])[0].mouth == (("n", 1.0),)


def test_key_frames_are_integer_ms_in_order():
    timeline = build_timeline(_alignment(), (Action("turn", 1.0, 0.5, 5.0), Action("blink", 1.2, 0.3, 1.0, 0.1, 0.15)))
    assert timeline.duration == 4200
    for track in timeline.tracks:
        times = [key.t for key in track.keys]
        assert all(isinstance(t, int) for t in times)
        assert times == sorted(times) and times[0] == 0 and times[-1] <= timeline.duration
    assert {t.name for t in timeline.tracks} == {"mouth", "blink", "brow", "tilt", "turn", "nod", "gaze_h", "gaze_v",
                                                 "smile", "lips", "breath", *(f"emotion:{name}" for name in EMOTIONS)}


def test_blink_and_brow_envelopes():
    actions = (Action("blink", 1.0, 0.3, 1.0, 0.1, 0.15), Action("brow", 2.0, 0.9, 0.6, 0.3, 0.3))
    timeline = build_timeline(_alignment(), actions)
    quiet, closed, shut_early, brow_up = states_at(timeline, [0.9, 1.12, 1.05, 2.45])
    assert quiet.blink == 0 and quiet.brow == 0
    assert closed.blink == pytest.approx(1.0)
    assert 0 < shut_early.blink < 1
    assert brow_up.brow == pytest.approx(0.6)


def test_turn_and_tilt_move_to_their_angle_and_stay():
    actions = (Action("turn", 1.0, 0.5, 6.0), Action("tilt", 1.0, 0.4, -3.0), Action("turn", 3.0, 0.5, -2.0))
    timeline = build_timeline(_alignment(), actions)
    start, middle, held, back = states_at(timeline, [0.5, 1.25, 2.5, 4.0])
    assert start.pose.turn == 0 and start.pose.roll == 0
    assert 0 < middle.pose.turn < 6
    assert held.pose.turn == pytest.approx(6.0) and held.pose.roll == pytest.approx(-3.0)
    assert back.pose.turn == pytest.approx(-2.0)


def test_nod_goes_down_holds_then_comes_back_up():
    nod = Action("nod", 1.0, 1.3, 4.0, 0.5, 0.5)  # down over 1.0-1.5, held to 1.8, up by 2.3
    timeline = build_timeline(_alignment(), (nod,))
    before, going, down, rising, after = (s.pose.tilt for s in states_at(timeline, [0.9, 1.25, 1.65, 2.05, 2.4]))
    assert before == 0 and after == 0
    assert down == pytest.approx(4.0)
    assert 0 < going < down and 0 < rising < down


def test_no_speech_is_rest_all_along():
    timeline = build_timeline(Alignment(sentences=(), duration=2.0, notes=()), ())
    assert {s.mouth for s in states_at(timeline, [0.0, 1.0, 1.99])} == {((REST, 1.0),)}


def _closed_frames(timeline, start: float, end: float, fps: int = 30) -> int:
    """Frames at `fps` between `start` and `end` s that show the closed mouth (pure REST)."""
    times = [k / fps for k in range(int(start * fps), int(end * fps) + 1) if start <= k / fps <= end]
    return sum(state.mouth == ((REST, 1.0),) for state in states_at(timeline, times))


@pytest.mark.parametrize("shapes", [("m", "a"), ("m", "a", "u"), ("m", "i", "e", "n")])
@pytest.mark.parametrize("length", [0.16, 0.2, 0.3])
@pytest.mark.parametrize("phase", [0.0, 0.011, 0.023])
def test_bilabial_closure_holds_at_least_two_frames_between_open_syllables(shapes, length, phase):
    # a b/p/m syllable right between two open vowels, at several positions against the frame clock
    start = 1.0 + phase
    syllables = (
        _syllable(("a",), start - 0.2, start),
        _syllable(shapes, start, start + length),
        _syllable(("a",), start + length, start + length + 0.2),
    )
    alignment = Alignment((Sentence("s", syllables[0].start, syllables[-1].end, syllables),), 2.5, ())
    timeline = build_timeline(alignment, ())
    assert _closed_frames(timeline, start - 0.1, start + length) >= 2
    # the vowels around it are open at their own key frames
    assert _dominant(states_at(timeline, [start - 0.2])[0]) == "a"
    assert _dominant(states_at(timeline, [start + length])[0]) == "a"


def test_bilabial_closure_keeps_the_syllables_shapes_in_order():
    syllables = (_syllable(("a",), 0.8, 1.0), _syllable(("m", "i", "a", "u"), 1.0, 1.21), _syllable(("a",), 1.21, 1.4))
    timeline = build_timeline(Alignment((Sentence("s", 0.8, 1.4, syllables),), 2.0, ()), ())
    keys = [k for k in timeline.track("mouth").keys if 1000 <= k.t < 1210]
    assert [k.value for k in keys if k.value != REST] == ["i", "a", "u"]
    assert [k.t for k in keys] == sorted(k.t for k in keys)


@pytest.mark.parametrize("length", [0.3, 0.45, 0.6])
def test_a_lengthened_final_reaches_its_widest_shape_in_its_first_part(length):
    # the last syllable of a sentence, followed by a pause: "hao" = h, a, u
    syllables = (_syllable(("i",), 0.5, 0.7), _syllable(("h", "a", "u"), 0.7, 0.7 + length))
    timeline = build_timeline(Alignment((Sentence("s", 0.5, 0.7 + length, syllables),), 2.0, ()), ())
    key = next(k.t / 1000 for k in timeline.track("mouth").keys if k.value == "a")
    plain = 0.7 + shape_onsets(3)[1] * length
    assert 0.7 < key < plain
    assert key - 0.7 < 0.5 * length
    # the last shape holds to the end of the sound
    assert _dominant(states_at(timeline, [0.7 + length])[0]) == "u"


@pytest.mark.parametrize("gap", [0.10, 0.12, 0.15])
def test_a_short_pause_closes_the_mouth_for_an_instant(gap):
    syllables = (_syllable(("a",), 0.5, 0.8), _syllable(("a",), 0.8 + gap, 1.1 + gap))
    timeline = build_timeline(Alignment((Sentence("s", 0.5, 1.1 + gap, syllables),), 2.0, ()), ())
    lag_share = LAG_MS / (LAG_MS + LEAD_MS)
    closed, before, after = states_at(timeline, [0.8 + gap * lag_share, 0.8, 0.8 + gap])
    assert closed.mouth == ((REST, 1.0),)
    assert before.mouth == (("a", 1.0),) and after.mouth == (("a", 1.0),)


def test_a_gap_shorter_than_a_pause_blends_straight_on():
    syllables = (_syllable(("a",), 0.5, 0.8), _syllable(("i",), 0.86, 1.1))
    timeline = build_timeline(Alignment((Sentence("s", 0.5, 1.1, syllables),), 2.0, ()), ())
    assert all(dict(s.mouth).get(REST, 0) == 0 for s in states_at(timeline, [0.8 + k * 0.01 for k in range(7)]))


def test_a_long_bilabial_syllable_opens_after_its_closure():
    # ba of 400 ms: closed lips for CLOSURE_MS, then the mouth opens towards a (at 81 % of it)
    syllables = (_syllable(("a",), 0.6, 0.8), _syllable(("m", "a"), 0.8, 1.2), _syllable(("a",), 1.2, 1.4))
    timeline = build_timeline(Alignment((Sentence("s", 0.6, 1.4, syllables),), 2.0, ()), ())
    closed, opening, opened = states_at(timeline, [0.8 + CLOSURE_MS / 1000, 1.0, 0.8 + shape_onsets(2)[1] * 0.4])
    assert closed.mouth == ((REST, 1.0),)
    assert 0 < dict(opening.mouth)["a"] < 1
    assert opened.mouth == (("a", 1.0),)
