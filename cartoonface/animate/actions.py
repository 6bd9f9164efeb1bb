"""actions.json: the behaviour schedule written out for a person to edit and read back.

Format (docs/actions.md)::

    {"format": "cartoonface-actions", "version": 1,
     "actions": [{"kind": "nod", "start": 2.31, "duration": 1.2, "amplitude": 4.5,
                  "attack": 0.5, "release": 0.4},
                 {"kind": "emotion", "emotion": "happy", "start": 0.5, "duration": 3.0,
                  "amplitude": 0.8, "attack": 0.4, "release": 0.6}, ...]}

`actions_to_json` / `save_actions` write it; `actions_from_json` / `load_actions`
read and validate it against the audio's duration and raise ActionsError naming
the action's index and field.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from pathlib import Path

from cartoonface.animate.behaviour import ANGLE_KINDS, ENVELOPE_KINDS, KINDS, TIME_SLACK, Action
from cartoonface.errors import ActionsError
from cartoonface.face.emotion import EMOTIONS
from cartoonface.face.state import MAX_ANGLE
from cartoonface.files import read_user_text, write_text_atomic

FORMAT = "cartoonface-actions"
VERSION = 1
REQUIRED = ("kind", "start", "duration", "amplitude")
OPTIONAL = ("attack", "release")
EMOTION_FIELD = "emotion"  # required for kind "emotion" (its name), refused for the others
# An envelope action written without attack/release rises over a third of its
# duration and falls over a third (our default, documented in docs/actions.md).
DEFAULT_RAMP = 1 / 3


def actions_to_json(actions: Sequence[Action]) -> str:
    """The actions as actions.json text (UTF-8, one action per line), sorted by start."""
    rows = []
    for action in sorted(actions, key=lambda a: (a.start, KINDS.index(a.kind), a.emotion)):
        row: dict[str, object] = {"kind": action.kind}
        if action.emotion:
            row[EMOTION_FIELD] = action.emotion
        row |= {"start": action.start, "duration": action.duration, "amplitude": action.amplitude}
        if action.kind in ENVELOPE_KINDS:
            row |= {"attack": action.attack, "release": action.release}
        rows.append("    " + json.dumps(row, ensure_ascii=False))
    body = ",\n".join(rows)
    actions_text = f"[\n{body}\n  ]" if rows else "[]"
    return f'{{\n  "format": "{FORMAT}",\n  "version": {VERSION},\n  "actions": {actions_text}\n}}\n'


def save_actions(path: str | os.PathLike[str], actions: Sequence[Action]) -> Path:
    """Write actions.json atomically at `path`; return the path."""
    return write_text_atomic(path, actions_to_json(actions))


def load_actions(path: str | os.PathLike[str], duration: float) -> tuple[Action, ...]:
    """Read and validate the actions file at `path` for audio of `duration` seconds."""
    text = read_user_text(path, ActionsError, "actions file")
    return actions_from_json(text, str(path), duration)


def actions_from_json(text: str, source: str, duration: float) -> tuple[Action, ...]:
    """Parse actions.json `text` (named `source` in messages) for audio of `duration` s.

    Returns the actions sorted by start. Raises ActionsError naming the index
    and field at fault: unknown kind or field, non-number, negative or zero
    duration, angle beyond 15 degrees, amount outside 0..1, a time past the end
    of the audio, attack + release longer than the action, or two actions of
    one kind overlapping.
    """
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ActionsError(f"{source}: not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})") from None
    if not isinstance(data, dict):
        raise ActionsError(f"{source}: expected a JSON object with format, version and actions")
    if data.get("format") != FORMAT:
        raise ActionsError(f"{source}: field 'format' is {data.get('format')!r}; expected {FORMAT!r}")
    if data.get("version") != VERSION:
        raise ActionsError(
            f"{source}: field 'version' is {data.get('version')!r}; this program reads version {VERSION}"
        )
    unknown = sorted(set(data) - {"format", "version", "actions"})
    if unknown:
        raise ActionsError(f"{source}: unknown field {unknown[0]!r}; expected format, version, actions")
    rows = data.get("actions")
    if not isinstance(rows, list):
        raise ActionsError(f"{source}: field 'actions' must be a list of actions")
    actions = [_action(row, f"{source}: actions[{i}]", duration) for i, row in enumerate(rows)]
    _check_overlaps(actions, source)
    return tuple(sorted(actions, key=lambda a: (a.start, KINDS.index(a.kind), a.emotion)))


def _action(row: object, where: str, duration: float) -> Action:
    """One validated Action from the JSON object `row`; `where` prefixes messages."""
    if not isinstance(row, dict):
        raise ActionsError(f"{where}: expected an object with kind, start, duration, amplitude")
    fields = REQUIRED + OPTIONAL + (EMOTION_FIELD,)
    for key in row:
        if key not in fields:
            raise ActionsError(f"{where}.{key}: unknown field; expected {', '.join(fields)}")
    for key in REQUIRED:
        if key not in row:
            raise ActionsError(f"{where}.{key}: missing")
    kind = row["kind"]
    if kind not in KINDS:
        raise ActionsError(f"{where}.kind: unknown kind {kind!r}; expected one of {', '.join(KINDS)}")
    emotion = row.get(EMOTION_FIELD, "")
    if kind == "emotion" and EMOTION_FIELD not in row:
        raise ActionsError(f"{where}.{EMOTION_FIELD}: missing; expected one of {', '.join(EMOTIONS)}")
    if kind == "emotion" and emotion not in EMOTIONS:
        raise ActionsError(f"{where}.{EMOTION_FIELD}: unknown emotion {emotion!r}; expected one of {', '.join(EMOTIONS)}")
    if kind != "emotion" and EMOTION_FIELD in row:
        raise ActionsError(f"{where}.{EMOTION_FIELD}: a {kind} has no emotion; remove {EMOTION_FIELD!r}")
    start, length, amplitude = (_number(row, key, where) for key in ("start", "duration", "amplitude"))
    if start < 0:
        raise ActionsError(f"{where}.start: {start} is negative; expected seconds from 0")
    if length <= 0:
        raise ActionsError(f"{where}.duration: {length} must be more than 0 seconds")
    if start > duration + TIME_SLACK:
        raise ActionsError(f"{where}.start: {start} s is past the end of the audio ({duration:.3f} s)")
    if start + length > duration + TIME_SLACK:
        raise ActionsError(
            f"{where}.duration: the action ends at {start + length:.3f} s, past the end of the audio ({duration:.3f} s)"
        )
    if kind in ANGLE_KINDS and abs(amplitude) > MAX_ANGLE:
        raise ActionsError(f"{where}.amplitude: angle {amplitude} degrees; expected -{MAX_ANGLE:g}..{MAX_ANGLE:g}")
    if kind not in ANGLE_KINDS and not 0 <= amplitude <= 1:
        what = "an intensity" if kind == "emotion" else "an amount"
        raise ActionsError(f"{where}.amplitude: {amplitude}; expected {what} from 0 to 1 for a {kind}")
    if kind not in ENVELOPE_KINDS:
        for key in OPTIONAL:
            if key in row:
                raise ActionsError(f"{where}.{key}: a {kind} moves over its whole duration; remove {key!r}")
        return _made(where, kind, round(start, 3), round(length, 3), amplitude)
    ramps = [_number(row, key, where) if key in row else round(DEFAULT_RAMP * length, 3) for key in OPTIONAL]
    for key, value in zip(OPTIONAL, ramps, strict=True):
        if value < 0:
            raise ActionsError(f"{where}.{key}: {value} is negative; expected seconds from 0")
    if ramps[0] + ramps[1] > length + TIME_SLACK:
        raise ActionsError(
            f"{where}.release: attack + release ({ramps[0] + ramps[1]:g} s) exceed the duration ({length:g} s)"
        )
    return _made(where, kind, round(start, 3), round(length, 3), amplitude, round(ramps[0], 3), round(ramps[1], 3),
                 emotion)


def _made(where: str, kind: str, start: float, length: float, amplitude: float,
          attack: float = 0.0, release: float = 0.0, emotion: str = "") -> Action:
    """The Action of these fields; its own check's ValueError becomes an ActionsError prefixed by `where`."""
    try:
        return Action(kind, start, length, amplitude, attack, release, emotion)
    except ValueError as exc:
        raise ActionsError(f"{where}: {exc}") from None


def _number(row: dict, key: str, where: str) -> float:
    """row[key] as a finite float, else ActionsError naming the field."""
    value = row[key]
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ActionsError(f"{where}.{key}: {value!r} is not a number")
    return float(value)


def _check_overlaps(actions: Sequence[Action], source: str) -> None:
    """ActionsError if two actions of the same kind (for emotions: of the same emotion)
    overlap in time (indices as in the file)."""
    for kind, emotion in {(a.kind, a.emotion) for a in actions}:
        same = sorted((a.start, i, a) for i, a in enumerate(actions) if (a.kind, a.emotion) == (kind, emotion))
        what = f"{emotion} emotion" if emotion else kind
        for (_, i, first), (_, j, second) in zip(same, same[1:]):
            if second.start < first.end - TIME_SLACK:
                raise ActionsError(
                    f"{source}: actions[{j}].start: this {what} at {second.start:g} s starts before "
                    f"actions[{i}] (a {what} until {first.end:g} s) ends; actions of one kind must not overlap"
                )
