"""The animation timeline: key frames of the mouth and of every behaviour (thesis 002, 5.4).

A Timeline holds one Track per animated quantity, each a tuple of Keyframes at
integer milliseconds, so boundaries never drift. frames.py interpolates between
them. Tracks:

- ``mouth``: a basic mouth shape symbol per key frame (MOUTH_SYMBOLS); the
  syllables' 1-4 shapes at the in-syllable onsets of thesis 5.3, rest shape
  ``m`` in pauses and before/after speech.
- ``blink``, ``brow``: amounts 0..1.
- ``tilt`` (sideways lean, Pose.roll), ``turn`` (Pose.turn), ``nod`` (depth
  of the nod in degrees, Pose.tilt): see behaviour.py for the kinds.
- ``gaze_h``, ``gaze_v``: the eyes' angles away from the viewer, degrees.
- ``smile``: amount 0..1.
- ``emotion:NAME`` for each NAME of face/emotion.py's EMOTIONS: its intensity
  0..1 (the "emotion" actions, after `adapt_to_emotions` has fitted the other
  behaviour to them).
- ``lips``: gamma of seed 000 eq. 18, the share of the emotions' lip
  displacement shown: 1 at rest, LIPS_SPEAKING while a sentence is spoken.
- ``breath``: depth of the breath 0..1 (the chest and shoulders; frames.breaths_at).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from cartoonface.animate.behaviour import KINDS, Action, adapt_to_emotions
from cartoonface.face.emotion import EMOTIONS
from cartoonface.speech.align import MIN_PAUSE
from cartoonface.speech.features import HOP
from cartoonface.speech.mouth_shapes import shape_onsets

REST = "m"  # the closed mouth shown when nothing is said (thesis 002, 5.2.2: shape m, lips closed)
# Lead-in and lead-out, our choice: the lips start to move before the sound is
# heard and close just after it, as people do (visible articulation precedes
# the acoustic onset by roughly 100 ms). 80 ms is between two and three frames
# at 30 fps: the mouth visibly opens ahead of the syllable without looking early.
LEAD_MS = 80
LAG_MS = 80
# A pause shorter than LAG_MS + LEAD_MS but at least this long (the aligner's shortest pause
# inside a speaking part, speech/align.py MIN_PAUSE, 100 ms) still closes the mouth, for an
# instant: lag and lead shrink in proportion. Shorter gaps blend straight on.
SHORT_PAUSE_MS = round(MIN_PAUSE * HOP * 1000)
# Lips closed for b, p, m (thesis 002, 5.2.2: their shape is m): held this long from the
# syllable's start, the stop closure or nasal murmur (bilabial closures of read Mandarin last
# about 50-100 ms). 70 ms holds the closed mouth over at least 2 frames at 30 fps.
CLOSURE_MS = 70
# The lips part quickly at the release of a bilabial: the next shape is reached within this
# (our choice: under one frame at 30 fps); a syllable too short for CLOSURE_MS + RELEASE_MS
# before its next shape holds the closure for what is left.
RELEASE_MS = 20
# Phrase-final lengthening: the last syllable before a pause lasts about 1.4 times as long
# (speech/align.py's duration prior, fitted on Biaobei 000001-000035). The extra length is the
# final vowel held; the 5.3 onsets are taken of the unlengthened syllable.
FINAL_LENGTHENING = 1.4
# A b/p/m syllable whose next shape comes too early for the closure moves its later shapes
# (towards its end), keeping at least this share of their time (our choice).
CLOSURE_KEEP = 0.5
# Seed 000 eq. 18's gamma while talking (our choice): the mouth shapes alone open and shape
# the lips, the emotion keeps its mouth corners (face/emotion.py LIP_POINTS: the corners of a
# happy 'a' still rise; the dropped jaw of surprise gives way to the syllables, and a
# surprised 'm' closes). At rest gamma is 1. It changes over LIPS_EASE_MS before a sentence
# starts and after it ends (pauses shorter than twice that keep it), like the lead-in and
# lead-out of the lips.
LIPS_SPEAKING = 0.0
LIPS_EASE_MS = 200
MOUTH_EASING = "smoothstep"
AMOUNT_EASING = "smoothstep"
ANGLE_EASING = "cosine"
BREATH_EASING = "smoothstep"  # the chest eases in and out of each inhalation like the amounts


@dataclass(frozen=True)
class Keyframe:
    """A value a track reaches at time `t` (integer ms from the start of the audio).

    `value` is a mouth symbol (str) on the mouth track, a float elsewhere
    (an amount 0..1 or an angle in degrees).
    """

    t: int
    value: float | str


@dataclass(frozen=True)
class Track:
    """Key frames of one quantity, sorted by time; `easing` names the interpolation (frames.py)."""

    name: str
    keys: tuple[Keyframe, ...]
    easing: str


@dataclass(frozen=True)
class Timeline:
    """All tracks of an animation `duration` ms long."""

    duration: int
    tracks: tuple[Track, ...]

    def track(self, name: str) -> Track:
        """The track called `name` (KeyError if there is none)."""
        for track in self.tracks:
            if track.name == name:
                return track
        raise KeyError(name)

    @property
    def names(self) -> tuple[str, ...]:
        """The names of the tracks, in order."""
        return tuple(track.name for track in self.tracks)


def build_timeline(alignment, actions: Sequence[Action]) -> Timeline:
    """Key frames for an Alignment (speech/records.py) and behaviour `actions`.

    Returns a Timeline of alignment.duration (rounded to ms) with the tracks
    mouth, blink, brow, tilt, turn, nod, gaze_h, gaze_v, smile, emotion:NAME for
    each emotion, lips and breath. The blinks, brow raises and smiles are first
    fitted to the emotions (behaviour.adapt_to_emotions).
    """
    duration = round(alignment.duration * 1000)
    syllables = sorted((syl for sentence in alignment.sentences for syl in sentence.syllables), key=lambda s: s.start)
    actions = adapt_to_emotions(actions)
    by_kind = {kind: sorted((a for a in actions if a.kind == kind), key=lambda a: a.start) for kind in KINDS}
    feelings = tuple(
        Track(f"emotion:{name}", envelope_keys([a for a in by_kind["emotion"] if a.emotion == name]), AMOUNT_EASING)
        for name in EMOTIONS)
    return Timeline(
        duration,
        (
            Track("mouth", mouth_keys(syllables, duration), MOUTH_EASING),
            Track("blink", envelope_keys(by_kind["blink"]), AMOUNT_EASING),
            Track("brow", envelope_keys(by_kind["brow"]), AMOUNT_EASING),
            Track("tilt", move_keys(by_kind["tilt"]), ANGLE_EASING),
            Track("turn", move_keys(by_kind["turn"]), ANGLE_EASING),
            Track("nod", envelope_keys(by_kind["nod"]), ANGLE_EASING),
            Track("gaze_h", move_keys(by_kind["gaze_h"]), ANGLE_EASING),
            Track("gaze_v", move_keys(by_kind["gaze_v"]), ANGLE_EASING),
            Track("smile", envelope_keys(by_kind["smile"]), AMOUNT_EASING),
            *feelings,
            Track("lips", lips_keys([(s.start, s.end) for s in alignment.sentences]), AMOUNT_EASING),
            Track("breath", envelope_keys(by_kind["breath"]), BREATH_EASING),
        ),
    )


def lips_keys(spans: Sequence[tuple[float, float]]) -> tuple[Keyframe, ...]:
    """Key frames of gamma (seed 000 eq. 18) for sentences spoken over `spans` ((start, end)
    seconds): 1, easing to LIPS_SPEAKING over LIPS_EASE_MS before each stretch of speech and
    back to 1 over LIPS_EASE_MS after it; stretches closer than 2 LIPS_EASE_MS join."""
    joined: list[list[int]] = []
    for start, end in sorted((_seconds_to_ms(a), _seconds_to_ms(b)) for a, b in spans):
        if joined and start - joined[-1][1] < 2 * LIPS_EASE_MS:
            joined[-1][1] = max(joined[-1][1], end)
        else:
            joined.append([start, end])
    keys = [Keyframe(0, 1.0)]
    for start, end in joined:
        keys += [Keyframe(max(start - LIPS_EASE_MS, 0), 1.0), Keyframe(start, LIPS_SPEAKING),
                 Keyframe(end, LIPS_SPEAKING), Keyframe(end + LIPS_EASE_MS, 1.0)]
    return _monotonic(keys)


def mouth_keys(syllables: Sequence, duration: int) -> tuple[Keyframe, ...]:
    """Mouth key frames for `syllables` (with start, end in s and shapes) sorted by start.

    Each shape of a syllable is a key frame at start + onset * (end - start),
    onsets from speech.mouth_shapes.shape_onsets (thesis 002, 5.3); before a
    pause (or at the end) the onsets are taken of the syllable without its
    phrase-final lengthening (FINAL_LENGTHENING), so the widest shape comes
    inside the vowel and the last shape holds through the lengthened end.
    A syllable that starts with closed lips (b, p, m: shape REST) holds them
    CLOSURE_MS and opens within RELEASE_MS; its later shapes move towards its
    end for that when needed, as far as the syllable allows (_closure_times). Where
    the gap to the next syllable leaves room for LAG_MS + LEAD_MS, the mouth
    holds the last shape to the end of the sound, closes to REST within
    LAG_MS, and reopens from REST LEAD_MS before the next syllable; a gap of
    SHORT_PAUSE_MS up to that closes it at one instant (lag and lead shrunk
    in proportion); shorter gaps blend straight from one syllable into the
    next. `duration` in ms.
    """
    keys = [Keyframe(0, REST)]
    previous_end = None
    for index, syllable in enumerate(syllables):
        start, end = _seconds_to_ms(syllable.start), _seconds_to_ms(syllable.end)
        gap = None if previous_end is None else start - previous_end
        if gap is None or gap >= SHORT_PAUSE_MS:
            lag, lead = LAG_MS, LEAD_MS
            if gap is not None and gap < LAG_MS + LEAD_MS:
                lag = round(gap * LAG_MS / (LAG_MS + LEAD_MS))
                lead = gap - lag
            if previous_end is not None:
                keys += [Keyframe(previous_end, keys[-1].value), Keyframe(previous_end + lag, REST)]
            keys.append(Keyframe(max(start - lead, 0), REST))
        following = syllables[index + 1] if index + 1 < len(syllables) else None
        paused = following is None or _seconds_to_ms(following.start) - end >= LAG_MS + LEAD_MS
        shaped = round((end - start) / FINAL_LENGTHENING) if paused else end - start
        times = [start + round(onset * shaped) for onset in shape_onsets(len(syllable.shapes))]
        if syllable.shapes[0] == REST and len(times) > 1:
            times = _closure_times(times, start + shaped)
        for shape, t in zip(syllable.shapes, times, strict=True):
            keys.append(Keyframe(t, shape))
        hold = min(CLOSURE_MS, times[1] - RELEASE_MS - start) if len(times) > 1 else 0
        if syllable.shapes[0] == REST and hold > 0:
            keys.insert(len(keys) - len(times) + 1, Keyframe(start + hold, REST))
        previous_end = end
    if previous_end is not None:
        keys += [Keyframe(previous_end, keys[-1].value), Keyframe(min(previous_end + LAG_MS, duration), REST)]
    keys.append(Keyframe(duration, REST))
    return _monotonic(keys)


def _closure_times(times: list[int], end: int) -> list[int]:
    """Key times (ms) of a syllable that starts with closed lips, whose shapes end at `end`:
    the later keys moved (linearly, towards `end`) so that the second comes CLOSURE_MS +
    RELEASE_MS after the first, but keep at least half of their time (CLOSURE_KEEP)."""
    wanted = times[0] + CLOSURE_MS + RELEASE_MS
    if times[1] >= wanted:
        return times
    target = min(wanted, round(times[1] + (1 - CLOSURE_KEEP) * (end - times[1])))
    scale = (end - target) / max(end - times[1], 1)
    return [times[0]] + [target + round((t - times[1]) * scale) for t in times[1:]]


def envelope_keys(actions: Sequence[Action]) -> tuple[Keyframe, ...]:
    """Key frames of rise-hold-fall actions (blink, brow, nod) sorted by start.

    Per action: 0 at start, amplitude after `attack`, amplitude until `release`
    before the end, 0 at the end. Before, between and after: 0.
    """
    keys = [Keyframe(0, 0.0)]
    for action in actions:
        start, end = _seconds_to_ms(action.start), _seconds_to_ms(action.end)
        keys += [
            Keyframe(start, 0.0),
            Keyframe(start + _seconds_to_ms(action.attack), action.amplitude),
            Keyframe(end - _seconds_to_ms(action.release), action.amplitude),
            Keyframe(end, 0.0),
        ]
    return _monotonic(keys)


def move_keys(actions: Sequence[Action]) -> tuple[Keyframe, ...]:
    """Key frames of head and eye moves (tilt, turn, gaze_h, gaze_v) sorted by start.

    The angle starts at 0; each move goes from the angle held so far to its
    amplitude between its start and its end, and that angle holds until the
    next move.
    """
    keys = [Keyframe(0, 0.0)]
    for action in actions:
        keys += [Keyframe(_seconds_to_ms(action.start), keys[-1].value), Keyframe(_seconds_to_ms(action.end), action.amplitude)]
    return _monotonic(keys)


def _seconds_to_ms(seconds: float) -> int:
    """`seconds` as a whole number of milliseconds (an int)."""
    return round(seconds * 1000)


def _monotonic(keys: list[Keyframe]) -> tuple[Keyframe, ...]:
    """Keys with times made non-decreasing and at least 0 (later keys never move earlier ones).

    Equal times make a step; frames.py takes the last key at a time.
    """
    fixed, latest = [], 0
    for key in keys:
        latest = max(latest, key.t)
        fixed.append(key if key.t == latest else Keyframe(latest, key.value))
    return tuple(fixed)
