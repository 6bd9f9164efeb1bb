"""Records that check themselves: Syllable, Sentence, Alignment, TextGrid Interval, Action.

Each bad record is made directly and must raise ValueError naming the field; a good one
next to it must be accepted (so the check is not simply refusing everything).
"""

from __future__ import annotations

import math

import pytest

from cartoonface.animate.behaviour import Action
from cartoonface.errors import AlignmentError
from cartoonface.face.state import MAX_ANGLE
from cartoonface.speech.records import Alignment, Sentence, Syllable
from cartoonface.speech.textgrid import Interval, read_textgrid, write_textgrid

GOOD_SYLLABLE = dict(text="你", pinyin="ni3", shapes=("h'", "i"), start=0.1, end=0.3, confidence=0.8)


def syllable(**changes: object) -> Syllable:
    return Syllable(**{**GOOD_SYLLABLE, **changes})  # type: ignore[arg-type]


def test_good_records_are_accepted():
    first = syllable()
    second = syllable(text="好", pinyin="hao3", shapes=("a", "u"), start=0.3, end=0.5)
    sentence = Sentence("你好", 0.1, 0.5, (first, second))
    assert Alignment((sentence,), 1.0, ()).sentences[0].syllables == (first, second)
    assert Interval(0.0, 0.0, "").end == 0.0
    assert Action("nod", 0.0, 1.0, MAX_ANGLE, 0.3, 0.4).end == 1.0


@pytest.mark.parametrize("changes, field", [
    ({"start": -0.1}, "start"),
    ({"end": 0.05}, "before it starts"),
    ({"start": math.nan}, "finite"),
    ({"end": math.inf}, "finite"),
    ({"confidence": 1.5}, "confidence"),
    ({"confidence": math.nan}, "confidence"),
    ({"pinyin": " "}, "pinyin"),
    ({"shapes": ("a", "i", "u", "o", "e")}, "at most"),
    ({"shapes": ("x",)}, "mouth shape"),
])
def test_bad_syllables_are_refused(changes, field):
    with pytest.raises(ValueError, match=field):
        syllable(**changes)


def test_bad_sentences_are_refused():
    early, late = syllable(start=0.1, end=0.2), syllable(start=0.3, end=0.4)
    with pytest.raises(ValueError, match="empty text"):
        Sentence(" ", 0.1, 0.4, (early, late))
    with pytest.raises(ValueError, match="before it starts"):
        Sentence("你你", 0.4, 0.1, (early, late))
    with pytest.raises(ValueError, match="time order"):
        Sentence("你你", 0.1, 0.4, (late, early))


def test_bad_alignments_are_refused():
    first, second = Sentence("一", 0.0, 1.0, ()), Sentence("二", 1.0, 2.0, ())
    with pytest.raises(ValueError, match="time order"):
        Alignment((second, first), 3.0, ())
    with pytest.raises(ValueError, match="finite"):
        Alignment((first, second), math.nan, ())
    with pytest.raises(ValueError, match="before it starts"):
        Alignment((first, second), -1.0, ())


@pytest.mark.parametrize("start, end", [(-1.0, 1.0), (2.0, 1.0), (math.nan, 1.0), (0.0, math.inf)])
def test_bad_intervals_are_refused(start, end):
    with pytest.raises(ValueError, match="interval 'x'"):
        Interval(start, end, "x")


def test_textgrid_reader_names_the_file_for_a_negative_time():
    good = Alignment((Sentence("你", 0.0, 0.3, (syllable(start=0.0),)),), 1.0, ())
    first = "intervals [1]:\n            xmin = 0 "
    text = write_textgrid(good).replace(first, first.replace("0 ", "-0.1 "), 1)
    assert "xmin = -0.1 " in text
    with pytest.raises(AlignmentError, match=r"edited\.TextGrid, line \d+: tier sentences, .*start -0\.1"):
        read_textgrid(text, "edited.TextGrid")


@pytest.mark.parametrize("fields, field", [
    (("wink", 0.0, 1.0, 0.5), "kind"),
    (("blink", -0.1, 1.0, 1.0), "start"),
    (("blink", 0.0, 0.0, 1.0), "duration"),
    (("blink", 0.0, math.nan, 1.0), "finite"),
    (("blink", 0.0, 1.0, 1.5), "amplitude"),
    (("tilt", 0.0, 1.0, MAX_ANGLE + 1), "angle"),
    (("tilt", 0.0, 1.0, 3.0, 0.2, 0.0), "whole duration"),
    (("brow", 0.0, 1.0, 0.5, 0.6, 0.6), "exceed the duration"),
    (("brow", 0.0, 1.0, 0.5, -0.1, 0.2), "attack"),
])
def test_bad_actions_are_refused(fields, field):
    with pytest.raises(ValueError, match=field):
        Action(*fields)


@pytest.mark.parametrize("confidence", [0.29, 0.8, 1.0])
def test_json_confidence_keeps_a_flagged_syllable_below_its_threshold(confidence):
    from cartoonface.speech.analyse import LOW_CONFIDENCE
    from cartoonface.speech.records import alignment_to_dict

    def written(value: float) -> float:
        one = syllable(confidence=value)
        data = alignment_to_dict(Alignment((Sentence("你", 0.1, 0.3, (one,)),), 1.0, ()))
        return data["sentences"][0]["syllables"][0]["confidence"]

    assert written(LOW_CONFIDENCE - 0.004) < LOW_CONFIDENCE
    assert written(confidence) == confidence  # hundredths themselves are kept
