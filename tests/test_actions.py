"""actions.json: round trip of a schedule and a clear ActionsError for every bad field."""

from __future__ import annotations

import json

import pytest

from cartoonface.animate.actions import actions_from_json, actions_to_json, load_actions, save_actions
from cartoonface.animate.behaviour import Action, schedule
from cartoonface.errors import ActionsError, InputError

DURATION = 60.0


def _doc(*rows: dict) -> str:
    return json.dumps({"format": "cartoonface-actions", "version": 1, "actions": list(rows)})


GOOD = {"kind": "turn", "start": 1.0, "duration": 0.5, "amplitude": 5.0}
MOOD = {"kind": "emotion", "emotion": "happy", "start": 1.0, "duration": 3.0, "amplitude": 0.8, "attack": 0.5,
        "release": 0.5}


def test_emotions_round_trip_and_different_ones_may_overlap():
    """Two emotions cross-fading (happy fading out while sad fades in) are kept; the same
    emotion twice at once is refused."""
    text = _doc(MOOD, {**MOOD, "emotion": "sad", "start": 3.5})
    happy, sad = actions_from_json(text, "a.json", DURATION)
    assert (happy.emotion, sad.emotion) == ("happy", "sad") and happy.end > sad.start
    assert happy == Action("emotion", 1.0, 3.0, 0.8, 0.5, 0.5, "happy")
    assert actions_from_json(actions_to_json((happy, sad)), "b.json", DURATION) == (happy, sad)
    with pytest.raises(ActionsError, match=r"actions\[1\]\.start.*happy emotion"):
        actions_from_json(_doc(MOOD, {**MOOD, "start": 3.5}), "a.json", DURATION)


def test_schedule_round_trips_through_a_file(tmp_path):
    plan = schedule(DURATION, ((10.0, 10.8), (25.0, 25.5)), seed=3)
    path = save_actions(tmp_path / "actions.json", plan)
    assert load_actions(path, DURATION) == plan
    assert json.loads(path.read_text(encoding="utf-8"))["version"] == 1


def test_edited_file_is_read_sorted_with_default_ramps():
    text = _doc(
        {"kind": "brow", "start": 5.0, "duration": 0.9, "amplitude": 0.5},
        {"kind": "nod", "start": 2.0, "duration": 1.2, "amplitude": -4.0, "attack": 0.4, "release": 0.5},
    )
    brow, nod = actions_from_json(text, "edited.json", DURATION)[::-1]
    assert nod == Action("nod", 2.0, 1.2, -4.0, 0.4, 0.5)
    assert brow.kind == "brow" and brow.attack == brow.release and brow.attack + brow.release < brow.duration


def test_deleting_and_moving_actions_is_kept():
    plan = schedule(DURATION, ((10.0, 10.8),), seed=1)
    rows = json.loads(actions_to_json(plan))["actions"]
    kept = [row for row in rows if row["kind"] != "turn"]
    kept[0]["start"] = round(kept[0]["start"] + 0.01, 3)
    read = actions_from_json(_doc(*kept), "x.json", DURATION)
    assert not [a for a in read if a.kind == "turn"]
    assert len(read) == len(kept)


@pytest.mark.parametrize(
    ("row", "field", "words"),
    [
        ({**GOOD, "kind": "wink"}, "actions[1].kind", "unknown kind"),
        ({**GOOD, "duration": -0.2}, "actions[1].duration", "more than 0"),
        ({**GOOD, "duration": 0}, "actions[1].duration", "more than 0"),
        ({**GOOD, "amplitude": 40}, "actions[1].amplitude", "degrees"),
        ({**GOOD, "kind": "nod", "amplitude": -15.5}, "actions[1].amplitude", "degrees"),
        ({**GOOD, "kind": "brow", "amplitude": 1.5}, "actions[1].amplitude", "0 to 1"),
        ({**GOOD, "start": 61.0}, "actions[1].start", "past the end"),
        ({**GOOD, "start": 59.8}, "actions[1].duration", "past the end"),
        ({**GOOD, "start": -1}, "actions[1].start", "negative"),
        ({**GOOD, "start": "soon"}, "actions[1].start", "not a number"),
        ({**GOOD, "start": True}, "actions[1].start", "not a number"),
        ({**GOOD, "strat": 1.0}, "actions[1].strat", "unknown field"),
        ({"kind": "tilt", "start": 1.0, "duration": 0.5}, "actions[1].amplitude", "missing"),
        ({**GOOD, "attack": 0.2}, "actions[1].attack", "remove"),
        ({**GOOD, "kind": "blink", "amplitude": 1, "attack": 0.3, "release": 0.3}, "actions[1].release", "exceed"),
        ({**GOOD, "kind": "blink", "amplitude": 1, "attack": -0.1}, "actions[1].attack", "negative"),
        ("blink", "actions[1]", "expected an object"),
        ({**MOOD, "emotion": "joy"}, "actions[1].emotion", "unknown emotion 'joy'"),
        ({k: v for k, v in MOOD.items() if k != "emotion"}, "actions[1].emotion", "missing"),
        ({**MOOD, "amplitude": 1.5}, "actions[1].amplitude", "intensity from 0 to 1"),
        ({**GOOD, "emotion": "sad"}, "actions[1].emotion", "has no emotion"),
    ],
)
def test_bad_field_names_index_and_field(row, field, words):
    first = {"kind": "blink", "start": 30.0, "duration": 0.3, "amplitude": 1.0, "attack": 0.1, "release": 0.15}
    with pytest.raises(ActionsError) as caught:
        actions_from_json(_doc(first, row), "my-actions.json", DURATION)
    message = str(caught.value)
    assert message.startswith("my-actions.json")
    assert field in message and words in message


def test_overlapping_actions_of_one_kind_are_refused_naming_both():
    text = _doc(GOOD, {**GOOD, "start": 1.2})
    with pytest.raises(ActionsError, match=r"actions\[1\]\.start.*actions\[0\]"):
        actions_from_json(text, "a.json", DURATION)
    # different kinds may overlap
    assert len(actions_from_json(_doc(GOOD, {**GOOD, "kind": "tilt"}), "a.json", DURATION)) == 2


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("{not json", "not valid JSON"),
        ("[]", "JSON object"),
        (json.dumps({"format": "other", "version": 1, "actions": []}), "'format'"),
        (json.dumps({"format": "cartoonface-actions", "version": 9, "actions": []}), "'version'"),
        (json.dumps({"format": "cartoonface-actions", "version": 1, "actions": {}}), "'actions'"),
        (json.dumps({"format": "cartoonface-actions", "version": 1, "actions": [], "x": 1}), "'x'"),
    ],
)
def test_bad_documents(text, words):
    with pytest.raises(ActionsError, match=words):
        actions_from_json(text, "b.json", DURATION)


def test_missing_file_is_an_input_error(tmp_path):
    with pytest.raises(InputError, match="no such actions file"):
        load_actions(tmp_path / "nope.json", DURATION)


def test_empty_schedule_round_trips():
    assert actions_from_json(actions_to_json(()), "e.json", DURATION) == ()
