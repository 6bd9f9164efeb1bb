"""Where the eyes look: fixations and saccades of a talking face.

`saccades(speech, pauses, rng, style)` returns the gaze shifts that move the
eyes between the viewer and places aside (behaviour.py turns them into
`gaze_h` / `gaze_v` actions), as conversational gaze studies describe a speaker:

- Kendon (1967), "Some functions of gaze-direction in social interaction",
  Acta Psychologica 26: a speaker looks away as a long utterance begins and
  back at the listener as it ends; so a glance away starts a sentence (with
  the style's share) and the eyes are back on the viewer END_LOOK seconds
  before the sentence ends.
- Argyle and Cook (1976), "Gaze and Mutual Gaze": a speaker looks at the
  listener for a share of the time only, in glances of a few seconds; the
  styles (style.py) set how often and how long the eyes go away.
- Lee, Badler and Badler (2002), "Eyes Alive", SIGGRAPH: saccade magnitudes
  follow P(A) = 15.7 exp(-A / 6.9) % (A in degrees), i.e. an exponential of
  scale MAGNITUDE_SCALE; a saccade lasts D = D0 + d A with D0 = 25 ms and
  d = 2.4 ms per degree (the "main sequence" of Bahill, Clark and Stark 1975,
  "The main sequence, a tool for studying human eye movements", Math. Biosci. 24).
  Between saccades the eyes fixate; while looking at the viewer they dart
  between points of the viewer's face (small saccades within DART_RADIUS).
- Eye-head coordination (Freedman 2008, "Coordination of the eyes and head
  during visual orienting", Exp. Brain Res. 190): a gaze shift combines a
  saccade with a head movement, the eyes leading; so most darts go with the
  head's turns and nods, towards where the head goes, and the eyes settle
  back on the viewer's centre as the head arrives. (This also keeps the SVG
  small: the eyes are redrawn during a head movement anyway.)
- In long pauses the eyes look down or aside (thinking, or reading on) and
  come back before the speech resumes.

Each gaze shift is one saccade to a new (h, v) angle, held until the next.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cartoonface.animate.style import Style

# Lee, Badler and Badler (2002), after Bahill et al. (1975): D = D0 + d A.
SACCADE_D0 = 0.025  # seconds
SACCADE_SLOPE = 0.0024  # seconds per degree
# Lee, Badler and Badler (2002): magnitude distribution P(A) = 15.7 exp(-A / 6.9) %.
MAGNITUDE_SCALE = 6.9  # degrees
# Glances away: drawn from that distribution and kept in AWAY_RANGE degrees
# (our choice: under 4 degrees a glance away reads as a dart; Bahill et al. 1975
# find most natural saccades within 15 degrees, and the drawn eye keeps its
# iris inside the lids up to about 12).
AWAY_RANGE = (4.0, 12.0)
# Direction of a glance away (our choice; "Eyes Alive" finds horizontal saccades
# the most common): aside, aside and a little up, or down.
AWAY_DIRECTIONS = (("aside", 0.7), ("up", 0.1), ("down", 0.2))
UP_SHARE = 0.5  # a glance "up" rises by this share of its size while going aside
# Looking down in a long pause: a fixed depth range (our choice).
DOWN_RANGE = (5.0, 10.0)  # degrees
# Darts: while looking at the viewer the eyes jump between the viewer's eyes
# and mouth, the places people fixate on a talking face (Vatikiotis-Bateson,
# Eigsti, Yano and Munhall 1998, "Eye movement of perceivers during audiovisual
# speech perception", Percept. Psychophys. 60). At 1 m the viewer's eyes are
# about 1.8 degrees either side of their middle and the mouth about 4 degrees
# below; we draw 3 degrees each way (an eye turns about 0.55 px per degree at
# d = 100 px, so smaller darts would not show) and keep to these few points,
# so that eye drawings repeat and the SVG stays small.
DART_POINTS = ((0.0, 0.0), (-3.0, 0.0), (3.0, 0.0), (0.0, 3.0))
DART_RADIUS = 3.0  # degrees: the farthest dart point from the viewer's centre
MIN_FIXATION = 0.1  # seconds: the shortest fixation between two saccades ("Eyes Alive")
END_LOOK = 0.5  # seconds before a sentence ends when the eyes are back on the viewer (Kendon 1967)
MIN_SENTENCE = 1.5  # seconds: shorter sentences start without a glance away
LONG_PAUSE = 0.7  # seconds: a pause at least this long may get a look down or aside
PAUSE_LEAD = (0.05, 0.25)  # seconds after the pause starts that the look begins
PAUSE_BACK = 0.2  # seconds before the speech resumes that the eyes are back
START_DELAY = (0.0, 0.3)  # seconds after a sentence starts that its glance away begins
# The longest saccade a glance away can make (back from the farthest diagonal).
LONGEST_SACCADE = SACCADE_D0 + SACCADE_SLOPE * (math.hypot(AWAY_RANGE[1], DOWN_RANGE[1]) + DART_RADIUS)


@dataclass(frozen=True)
class Saccade:
    """A gaze shift starting at `start` s, lasting `duration` s, to `h`, `v` degrees
    away from the viewer (h positive towards the image right, v positive down)."""

    start: float
    duration: float
    h: float
    v: float

    @property
    def end(self) -> float:
        """Time in seconds when the eyes arrive."""
        return self.start + self.duration


def saccade_duration(magnitude: float) -> float:
    """Seconds a saccade of `magnitude` degrees lasts (main sequence, rounded to ms)."""
    return round(SACCADE_D0 + SACCADE_SLOPE * magnitude, 3)


def saccades(
    speech: Sequence[tuple[float, float]],
    pauses: Sequence[tuple[float, float]],
    rng: np.random.Generator,
    style: Style,
    head_moves: Sequence[tuple[float, float, float, float]] = (),
) -> list[Saccade]:
    """The saccades of a face speaking in `speech` spans with `pauses` between.

    `speech`, `pauses`: (start, end) seconds, each sorted and non-overlapping.
    `head_moves`: (start, end, h, v) of the head's turns and nods, h and v the
    sign of the movement (+1 towards the image right / down, -1, or 0).
    Returns saccades sorted by start, each changing the gaze: no two overlap,
    every fixation lasts at least MIN_FIXATION, the eyes start on the viewer
    (0, 0) and are within DART_RADIUS of it END_LOOK before each sentence ends,
    and every angle is within AWAY_RANGE / DOWN_RANGE.
    """
    parts = sorted([(s, e, True) for s, e in speech] + [(s, e, False) for s, e in pauses])
    shifts = _Shifts()
    moves = sorted(head_moves)
    for start, end, speaking in parts:
        if speaking:
            inside = [move for move in moves if start <= move[0] and move[1] <= end - END_LOOK]
            _sentence(shifts, start, end, rng, style, inside)
        else:
            _pause(shifts, start, end, rng, style)
    return shifts.made


class _Shifts:
    """Saccades made so far: the current gaze and when the last one ended."""

    def __init__(self) -> None:
        self.made: list[Saccade] = []
        self.gaze = (0.0, 0.0)
        self.free = 0.0

    def to(self, start: float, h: float, v: float) -> float | None:
        """A saccade to (h, v) degrees at `start` s; None (nothing made) if it is too
        soon after the last one, else the time it ends."""
        start = round(start, 3)
        if start < self.free + MIN_FIXATION:
            return None
        h, v = round(h, 1), round(v, 1)
        magnitude = math.hypot(h - self.gaze[0], v - self.gaze[1])
        if magnitude == 0:
            return start
        self.made.append(Saccade(start, saccade_duration(magnitude), h, v))
        self.gaze, self.free = (h, v), self.made[-1].end
        return self.free


def _away(rng: np.random.Generator) -> tuple[float, float]:
    """(h, v) degrees of one glance away: size from the "Eyes Alive" law (to whole
    degrees, so drawings repeat), direction by AWAY_DIRECTIONS."""
    size = float(np.clip(round(rng.exponential(MAGNITUDE_SCALE)), *AWAY_RANGE))
    names, shares = zip(*AWAY_DIRECTIONS, strict=True)
    direction = names[int(rng.choice(len(names), p=np.array(shares)))]
    side = 1.0 if rng.random() < 0.5 else -1.0
    if direction == "down":
        return 0.0, float(np.clip(size, *DOWN_RANGE))
    if direction == "up":
        return side * size, -UP_SHARE * size
    return side * size, 0.0


def _dart(rng: np.random.Generator) -> tuple[float, float]:
    """(h, v) degrees of one of DART_POINTS on the viewer's face, drawn uniformly."""
    return DART_POINTS[int(rng.integers(len(DART_POINTS)))]


def _sentence(
    shifts: _Shifts,
    start: float,
    end: float,
    rng: np.random.Generator,
    style: Style,
    moves: Sequence[tuple[float, float, float, float]],
) -> None:
    """A glance away at the start (style.look_away), back on the viewer, then darts
    until END_LOOK (and a saccade) before the end: with the head `moves` (style.head_darts of them)
    and at style.dart_interval intervals."""
    back_by = end - END_LOOK - LONGEST_SACCADE
    t = start
    if end - start >= MIN_SENTENCE and rng.random() < style.look_away:
        away_at = start + rng.uniform(*START_DELAY)
        back_at = min(away_at + rng.uniform(*style.away_hold), back_by)
        if back_at - away_at >= MIN_FIXATION * 2 and shifts.to(away_at, *_away(rng)) is not None:
            t = shifts.to(back_at, *_dart(rng)) or shifts.to(back_by, *_dart(rng)) or t
    elif shifts.gaze != (0.0, 0.0) and shifts.to(start, *_dart(rng)) is not None:
        t = start
    events: list[tuple[float, tuple[float, float]]] = []
    for move_start, move_end, h, v in moves:
        if move_start >= t and rng.random() < style.head_darts:
            events += [(move_start, (DART_RADIUS * h, DART_RADIUS * v)), (move_end, (0.0, 0.0))]
    while True:
        t += rng.uniform(*style.dart_interval)
        if t > back_by:
            break
        events.append((t, _dart(rng)))
    for when, target in sorted(events):
        shifts.to(when, *target)


def _pause(shifts: _Shifts, start: float, end: float, rng: np.random.Generator, style: Style) -> None:
    """In a long pause, with the style's share: a look down or aside, back PAUSE_BACK before it ends."""
    if end - start < LONG_PAUSE or rng.random() >= style.pause_look:
        return
    look_at, back_at = start + rng.uniform(*PAUSE_LEAD), end - PAUSE_BACK
    if back_at - look_at < 2 * MIN_FIXATION:
        return
    target = (0.0, float(round(rng.uniform(*DOWN_RANGE)))) if rng.random() < 0.5 else _away(rng)
    if shifts.to(look_at, *target) is not None:
        shifts.to(back_at, 0.0, 0.0)
