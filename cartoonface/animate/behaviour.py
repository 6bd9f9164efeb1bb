"""Statistical behaviour of an announcer's face: blinks, eyebrow raises, head movements.

`schedule(duration, pauses, seed)` draws the timing of every non-speech facial
behaviour of thesis 002, chapter 4, as a tuple of `Action` values that the
timeline turns into key frames and that a user can edit (actions.json).

Kinds and what they drive (Pose is (tilt, turn, roll) about X, Y, Z):

- ``blink``: both eyes close and reopen; `amplitude` is the closed amount 0..1.
- ``brow``: both eyebrows rise and fall back; `amplitude` is the raise 0..1.
- ``tilt``: the thesis's "head tilting" (4.5.1), a sideways lean, i.e. Pose.roll
  about Z; the head moves to the angle `amplitude` (degrees) over `duration`
  and stays there until the next tilt.
- ``turn``: the thesis's "horizontal head turning" (4.5.2), Pose.turn about Y;
  moves to `amplitude` degrees over `duration` and stays.
- ``nod``: the thesis's "vertical head turning" (4.5.3), Pose.tilt about X; the
  head goes down by `amplitude` degrees over `attack`, holds, and comes back up
  over `release`.

- ``gaze_h``, ``gaze_v``: a saccade of the eyes (gaze.py) to `amplitude`
  degrees away from the viewer (towards the image right / down), over
  `duration`; the eyes stay there until the next saccade.
- ``smile``: a slight smile rises and fades; `amplitude` is the smile 0..1.
- ``emotion``: one of face/emotion.py's EMOTIONS (the action's `emotion`)
  rises to the intensity `amplitude` 0..1 and fades (the ease in and out is
  `attack` and `release`); the user sets these (transcript markup, actions.json,
  a default mood), `schedule` draws none. Emotions of different names may
  overlap (one fades into the next); `adapt_to_emotions` thins the blinks and
  scales the brow raises and smiles drawn during one (EMOTION_ADAPT).
- ``breath``: an inhalation in a pause (over `attack`) and the slow fall of the chest
  while the next words are spoken (over `release`); `amplitude` is its depth 0..1
  (render/scenery.py: how far the shoulders rise).

Envelope kinds (blink, brow, nod, smile, emotion, breath) rise from 0 to `amplitude` over `attack`
seconds, hold, and fall back to 0 over `release` seconds, all inside
`duration`. Amplitudes are docs/animation.md's announcer-like choices; a
`Style` (style.py) scales them and adds the performer's behaviour on the voice:
brows and beat nods on pitch peaks (prosody.py), gaze, smiles.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from cartoonface.animate.gaze import Saccade, saccades
from cartoonface.animate.style import ANNOUNCER, Style
from cartoonface.face.emotion import EMOTIONS
from cartoonface.face.state import MAX_ANGLE  # degrees: the pose limit of the face model, also the gaze limit

KINDS = ("blink", "brow", "tilt", "turn", "nod", "gaze_h", "gaze_v", "smile", "emotion", "breath")
ENVELOPE_KINDS = ("blink", "brow", "nod", "smile", "emotion", "breath")
ANGLE_KINDS = ("tilt", "turn", "nod", "gaze_h", "gaze_v")

# Blinks: intervals Gamma(alpha=2, theta=1.48 s), thesis 002, section 4.3 (Lin and Tsai [3]).
# The thesis measures a behaviour's interval from the end of one to the start of
# the next (section 4.2); we use that definition for blinks as well, so blinks
# never overlap.
BLINK_ALPHA = 2
BLINK_THETA = 1.48
# Blink shape: closing faster than opening. Stern, Walrath and Goldstein (1984):
# about 100 ms to full closure; Sforza et al., Ophthalmic Physiol Opt 28(4), 2008:
# closing 40-47 % faster than opening; Kwon et al., J R Soc Interface 10(85), 2013:
# phases closing, closed, opening. We use 0.10 s close, 0.05 s closed, 0.15 s open.
BLINK_CLOSE = 0.10
BLINK_CLOSED = 0.05
BLINK_OPEN = 0.15
BLINK_AMOUNT = 1.0

# Uniform intervals and durations (seconds), drawn with two decimals as in
# thesis 002, section 4.4 ("[0.90, 12.54] is divided into 1165 discrete numbers").
BROW_INTERVAL = (0.90, 12.54)  # thesis 002, section 4.4 (mean 6.72, sd 5.82)
BROW_DURATION = (0.51, 0.99)  # thesis 002, section 4.4 (mean 0.75, sd 0.24)
TILT_INTERVAL = (0.0, 6.64)  # thesis 002, section 4.5.1 ([0, 3.32] doubled for a normal pace)
TILT_DURATION = (0.4, 1.0)  # thesis 002, section 4.5.1 ([0.2, 0.5] doubled)
TURN_INTERVAL = (0.08, 7.92)  # thesis 002, Table 4.7 (adjusted interval)
TURN_DURATION = (0.4, 0.92)  # thesis 002, Table 4.7 (adjusted interval)
# Nods, thesis 002, section 4.5.3 and Table 4.12: the nod goes down during
# [t_silence - t1 - d1, t_silence - t1], the head stays down for t1 and rises
# during [t_silence, t_silence + d2], t_silence being the start of a pause.
NOD_T1 = (0.07, 0.35)
NOD_D1 = (0.34, 0.94)
NOD_D2 = (0.34, 0.70)

# Amplitudes: our choice (the thesis gives none); small, like a news announcer.
BROW_AMOUNT = (0.40, 0.80)  # share of the full eyebrow raise of the face model
# Tilt and turn targets alternate sides of the centre (so every move is seen)
# with a size uniform in [A/3, A]: A = 3 degrees for a lean, 6 for a turn.
TILT_ANGLE = 3.0
TURN_ANGLE = 6.0
NOD_ANGLE = (3.0, 6.0)  # nod depth in degrees, head down
BROW_RAMP = 0.3  # a brow raise rises over 30 % of its duration and falls over 30 %

# On the voice (our choices, docs/animation.md "On the voice"): a brow raise
# whose drawn start lies within BROW_SNAP seconds of a pitch peak is moved so
# that it is fully up at the peak, as speakers raise the brows on accented
# syllables (Cave et al. 1996, "About the relationship between eyebrow movements
# and F0 variations", ICSLP; Flecha-Garcia 2010, Speech Communication 52).
BROW_SNAP = 1.5
# Beat nods (storyteller): a small nod down onto an accented syllable.
BEAT_DEPTH = (1.5, 3.0)  # degrees, before the style's head factor
BEAT_ATTACK = (0.15, 0.25)  # seconds down, the head lowest at the peak
BEAT_HOLD = 0.05  # seconds
BEAT_RELEASE = (0.30, 0.45)  # seconds back up
# Slight smiles around sentence ends, reaching into the pause after them.
SMILE_AMOUNT = (0.15, 0.35)  # share of the full smile of the face model
SMILE_LEAD = (0.3, 0.8)  # seconds before the sentence end that the smile starts
SMILE_ATTACK = (0.3, 0.5)  # seconds
SMILE_HOLD = (0.5, 1.5)  # seconds
SMILE_RELEASE = (0.4, 0.7)  # seconds
SMILE_GAP = 4.0  # seconds: at least this long between two smiles

# Breaths (docs/animation.md "Breathing"). Readers breathe at grammatical boundaries, at
# consistent places from one reading to the next (Winkworth, Davis, Ellis and Adams 1994,
# "Variability and consistency in speech breathing during reading", JSHR 37:535-556), so a
# breath is taken in every pause between sentences long enough for one, and in the silence
# before the first sentence. A speech inhalation is quick and the air goes out slowly over
# the words that follow (Hixon, Goldman and Mead 1973, "Kinematics of the chest wall during
# speech production", JSHR 16:78-115); it is longer and deeper before a longer utterance
# (Whalen and Kinsella-Shaw 1997, Phonetica 54:138-152; Winkworth et al. 1994).
BREATH_PAUSE = 0.25  # seconds: the shortest silence that holds an inhalation (our choice)
BREATH_INHALE = (0.30, 0.60)  # seconds an inhalation takes, cut to the pause (our choice)
BREATH_LEAD = 0.05  # seconds: the inhalation ends this long before the speech resumes
BREATH_INTERVAL = 2.0  # seconds: a pause this soon after the last breath's is spoken through (our choice)
BREATH_EXHALE = 6.0  # seconds: at most this long for the chest to sink back over the words
BREATH_FULL = 6.0  # seconds of speech after a breath that make it a full one (depth 1)
BREATH_DEPTH = (0.4, 1.0)  # depth before a short / a long utterance, in between by its length
BREATH_JITTER = 0.1  # depths drawn up to this much below the length's depth
# A child of the seed no other random stream uses: schedule uses 0-7, idle.py's sway 8.
BREATH_STREAM = 16


# How an emotion at intensity 1 changes the drawn behaviour (our choice, after the
# descriptions of each expression): blink rate factor (<= 1: blinks are thinned;
# the eyes of a surprised face stay open, Ekman and Friesen's "eyes wide open"),
# brow raise factor (the brows of surprise and fear are raised already and stay
# there; frowning brows do not rise) and smile factor (no smile in a negative mood).
# An intensity e scales each factor's departure from 1 by e.
EMOTION_ADAPT: dict[str, tuple[float, float, float]] = {
    "happy": (1.0, 1.0, 1.0),
    "sad": (0.8, 0.4, 0.0),
    "angry": (0.7, 0.0, 0.0),
    "fear": (1.0, 0.0, 0.0),
    "surprise": (0.3, 0.0, 0.0),
    "disgust": (0.9, 0.2, 0.0),
    "wink": (1.0, 1.0, 1.0),
}
TIME_SLACK = 0.0005  # seconds: times are kept to the ms, so limits (attack + release <= duration, ...) allow this


@dataclass(frozen=True)
class Action:
    """One facial behaviour: `kind` in KINDS, `start` and `duration` in seconds.

    `amplitude`: 0..1 for blink/brow, degrees for tilt/turn (target angle) and nod
    (depth, positive = head down). `attack`/`release` (seconds) shape the
    envelope kinds: time to reach `amplitude` and time to return to 0; for a
    nod they are the thesis's d1 and d2, and the hold between them is t1. They
    are 0 for tilt and turn, which move over their whole duration.
    """

    kind: str
    start: float
    duration: float
    amplitude: float
    attack: float = 0.0
    release: float = 0.0
    emotion: str = ""  # the emotion of an "emotion" action (face/emotion.py EMOTIONS), else ""

    def __post_init__(self) -> None:
        """Raise ValueError naming the field unless the action is one the timeline can play."""
        if self.kind not in KINDS:
            raise ValueError(f"action kind {self.kind!r}; expected one of {', '.join(KINDS)}")
        for name in ("start", "duration", "amplitude", "attack", "release"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"{self.kind} {name} {getattr(self, name)!r}; expected a finite number")
        if self.start < 0:
            raise ValueError(f"{self.kind} start {self.start:g} s; expected 0 or later")
        if self.duration <= 0:
            raise ValueError(f"{self.kind} duration {self.duration:g} s; expected more than 0")
        if self.attack < 0 or self.release < 0:
            raise ValueError(f"{self.kind} attack {self.attack:g} s, release {self.release:g} s; expected 0 or more")
        if self.kind in ENVELOPE_KINDS and self.attack + self.release > self.duration + TIME_SLACK:
            raise ValueError(f"{self.kind} attack + release {self.attack + self.release:g} s exceed the duration "
                             f"{self.duration:g} s")
        if self.kind not in ENVELOPE_KINDS and (self.attack or self.release):
            raise ValueError(f"{self.kind} moves over its whole duration; expected attack and release 0")
        if self.kind in ANGLE_KINDS and abs(self.amplitude) > MAX_ANGLE:
            raise ValueError(f"{self.kind} angle {self.amplitude:g} degrees; expected -{MAX_ANGLE:g} to {MAX_ANGLE:g}")
        if self.kind not in ANGLE_KINDS and not 0.0 <= self.amplitude <= 1.0:
            raise ValueError(f"{self.kind} amplitude {self.amplitude:g}; expected an amount from 0 to 1")
        if self.kind == "emotion" and self.emotion not in EMOTIONS:
            raise ValueError(f"emotion {self.emotion!r} is unknown; expected one of {', '.join(EMOTIONS)}")
        if self.kind != "emotion" and self.emotion:
            raise ValueError(f"a {self.kind} has no emotion; expected emotion ''")

    @property
    def end(self) -> float:
        """Time in seconds when the behaviour is over."""
        return self.start + self.duration


def schedule(
    duration: float,
    pauses: Sequence[tuple[float, float]],
    seed: int,
    *,
    style: Style = ANNOUNCER,
    peaks: Sequence[float] = (),
    speech: Sequence[tuple[float, float]] | None = None,
    breath_pauses: Sequence[tuple[float, float]] | None = None,
) -> tuple[Action, ...]:
    """Draw the behaviour of a face talking for `duration` seconds.

    `pauses`: (start, end) seconds of the silent parts of the speech (see
    `speech_pauses`); a nod is placed before each pause where it fits.
    `seed`: any int; the same arguments give the same schedule. Each kind has
    its own random stream, so e.g. the pauses do not change the blinks.
    `style`: the performance style (style.py) scaling head angles and rates.
    `peaks`: seconds of pitch peaks (prosody.py): brow raises move onto them,
    and the style's share of them gets a beat nod. `speech`: (start, end) of the
    sentences (default: the stretches between `pauses`), for gaze and smiles.
    `breath_pauses`: (start, end) of the silences a breath may be taken in
    (default: `pauses`; the pipeline gives silences_of(alignment), the pauses
    inside sentences too).
    Returns every action sorted by start, all inside [0, duration]; no tilt or
    turn overlaps a nod; actions of one kind never overlap.
    """
    streams = np.random.SeedSequence(seed).spawn(8)
    blink_rng, brow_rng, tilt_rng, turn_rng, nod_rng, beat_rng, gaze_rng, smile_rng = (
        np.random.Generator(np.random.PCG64(child)) for child in streams
    )
    spans = _speech_spans(duration, pauses) if speech is None else tuple(sorted(speech))
    nods = _nods(duration, pauses, nod_rng, style.head)
    nods = _with_beat_nods(nods, duration, peaks, beat_rng, style)
    busy = tuple((nod.start, nod.end) for nod in nods)
    turns = _moves("turn", duration, TURN_INTERVAL, TURN_DURATION, TURN_ANGLE * style.head, busy, turn_rng)
    head_moves = [(nod.start, nod.start + nod.attack, 0.0, 1.0) for nod in nods]
    head_moves += [(turn.start, turn.end, math.copysign(1.0, turn.amplitude - before), 0.0)
                   for before, turn in zip([0.0] + [t.amplitude for t in turns], turns)]
    actions = (
        *_blinks(duration, blink_rng),
        *_brows(duration, brow_rng, style.brow_rate, peaks),
        *_moves("tilt", duration, TILT_INTERVAL, TILT_DURATION, TILT_ANGLE * style.head, busy, tilt_rng),
        *turns,
        *nods,
        *_gaze(saccades(spans, pauses, gaze_rng, style, head_moves), duration),
        *_smiles(duration, spans, smile_rng, style.smile_share),
        *_breaths(duration, pauses if breath_pauses is None else breath_pauses, spans, _stream(seed, BREATH_STREAM)),
    )
    return tuple(sorted(actions, key=lambda a: (a.start, KINDS.index(a.kind))))


def _stream(seed: int, child: int) -> np.random.Generator:
    """The random stream number `child` of `seed` (a PCG64 of SeedSequence(seed)'s child)."""
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed).spawn(child + 1)[child]))


def _gaze(shifts: Sequence[Saccade], duration: float) -> list[Action]:
    """gaze_h / gaze_v actions of the `shifts` that end by `duration` s: one per axis the shift changes."""
    actions: list[Action] = []
    h, v = 0.0, 0.0
    for shift in shifts:
        if shift.end > duration:
            break
        if shift.h != h:
            actions.append(Action("gaze_h", shift.start, shift.duration, shift.h))
        if shift.v != v:
            actions.append(Action("gaze_v", shift.start, shift.duration, shift.v))
        h, v = shift.h, shift.v
    return actions


def _speech_spans(duration: float, pauses: Sequence[tuple[float, float]]) -> tuple[tuple[float, float], ...]:
    """(start, end) seconds of the stretches of [0, duration] between `pauses`."""
    edges = [0.0, *(t for pause in sorted(pauses) for t in pause), duration]
    return tuple((a, b) for a, b in zip(edges[::2], edges[1::2], strict=True) if b > a)


def speech_spans(alignment) -> tuple[tuple[float, float], ...]:
    """(start, end) seconds of each sentence of an Alignment: where the speaker talks."""
    return tuple((sentence.start, sentence.end) for sentence in alignment.sentences)


def speech_pauses(alignment) -> tuple[tuple[float, float], ...]:
    """The pauses of an Alignment: (start, end) seconds of the silence after each sentence.

    The silence between consecutive sentences, and after the last one if the
    recording goes on; leading silence is no pause (nothing is said before it).
    """
    sentences = sorted(alignment.sentences, key=lambda s: s.start)
    ends = [s.end for s in sentences]
    starts = [s.start for s in sentences[1:]] + [alignment.duration]
    return tuple((end, nxt) for end, nxt in zip(ends, starts, strict=True) if nxt > end)


def silences_of(alignment, shortest: float = BREATH_PAUSE) -> tuple[tuple[float, float], ...]:
    """(start, end) seconds of every silence of at least `shortest` s between two syllables of an
    Alignment (inside sentences and between them) and after the last one: where a reader may
    breathe (Winkworth et al. 1994: at grammatical boundaries, which the pauses of read
    speech mark)."""
    syllables = sorted((s for sentence in alignment.sentences for s in sentence.syllables), key=lambda s: s.start)
    ends = [s.end for s in syllables]
    starts = [s.start for s in syllables[1:]] + [alignment.duration]
    return tuple((end, nxt) for end, nxt in zip(ends, starts, strict=True) if nxt - end >= shortest)


def blink_interval(rng: np.random.Generator) -> float:
    """One Gamma(2, 1.48 s) interval drawn as thesis 002, section 4.3 does.

    X = -theta * log(U1 * U2) with U1, U2 uniform on (0, 1]: the sum of two
    exponential waiting times of rate 1/theta.
    """
    product = math.prod(1.0 - rng.random() for _ in range(BLINK_ALPHA))
    return -BLINK_THETA * math.log(product)


def _uniform2(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    """A value drawn uniformly among the two-decimal numbers of `bounds` (thesis 002, 4.4)."""
    low, high = round(bounds[0] * 100), round(bounds[1] * 100)
    return int(rng.integers(low, high + 1)) / 100


def _round_to_ms(t: float) -> float:
    """`t` seconds rounded to whole milliseconds, still in seconds (the resolution of the timeline)."""
    return round(t, 3)


def _blinks(duration: float, rng: np.random.Generator) -> list[Action]:
    length = _round_to_ms(BLINK_CLOSE + BLINK_CLOSED + BLINK_OPEN)
    blinks: list[Action] = []
    end = 0.0
    while True:
        start = _round_to_ms(end + blink_interval(rng))
        if start + length > duration:
            return blinks
        blinks.append(Action("blink", start, length, BLINK_AMOUNT, BLINK_CLOSE, BLINK_OPEN))
        end = blinks[-1].end


def _brows(duration: float, rng: np.random.Generator, rate: float, peaks: Sequence[float]) -> list[Action]:
    """Brow raises at the thesis's intervals divided by `rate`; a raise drawn within
    BROW_SNAP s of one of `peaks` (seconds) moves to be fully up at the nearest."""
    brows: list[Action] = []
    end = 0.0
    peak_times = np.array(sorted(peaks), dtype=float)
    while True:
        start = _round_to_ms(end + _uniform2(rng, BROW_INTERVAL) / rate)
        length = _uniform2(rng, BROW_DURATION)
        amount = round(float(rng.uniform(*BROW_AMOUNT)), 2)
        ramp = _round_to_ms(BROW_RAMP * length)
        usable = peak_times[(peak_times - ramp >= end) & (np.abs(peak_times - ramp - start) <= BROW_SNAP)]
        if len(usable):
            start = _round_to_ms(float(usable[np.argmin(np.abs(usable - ramp - start))]) - ramp)
        if start + length > duration:
            return brows
        brows.append(Action("brow", start, length, amount, ramp, ramp))
        end = brows[-1].end


def _moves(
    kind: str,
    duration: float,
    interval: tuple[float, float],
    length: tuple[float, float],
    angle: float,
    busy: Sequence[tuple[float, float]],
    rng: np.random.Generator,
) -> list[Action]:
    """Head tilts or turns: each waits its interval after the previous move or nod.

    Targets alternate sides of the centre, the first side drawn at random.
    A move that would overlap a nod (`busy` spans) is put off: its interval is
    counted again from the end of that nod.
    """
    moves: list[Action] = []
    end = 0.0
    side = 1.0 if rng.random() < 0.5 else -1.0
    while True:
        gap, span = _uniform2(rng, interval), _uniform2(rng, length)
        side = -side
        target = round(side * float(rng.uniform(angle / 3, angle)), 1)
        start = _round_to_ms(end + gap)
        blocking = _overlap(start, start + span, busy)
        while blocking is not None:
            start = _round_to_ms(blocking[1] + gap)
            blocking = _overlap(start, start + span, busy)
        if start + span > duration:
            return moves
        moves.append(Action(kind, start, span, target))
        end = moves[-1].end


def _overlap(start: float, end: float, spans: Sequence[tuple[float, float]]) -> tuple[float, float] | None:
    """The first of `spans` that overlaps [start, end], or None."""
    return next((span for span in spans if start < span[1] and span[0] < end), None)


def _nods(
    duration: float, pauses: Sequence[tuple[float, float]], rng: np.random.Generator, head: float = 1.0
) -> list[Action]:
    """One nod before each pause (thesis 002, 4.5.3), skipped where it would not fit.

    Depths are NOD_ANGLE times `head` (the style's factor), at most MAX_ANGLE.
    A nod is skipped when it would start before 0, end after `duration`, or
    overlap the previous nod (pauses closer together than a nod is long).
    """
    nods: list[Action] = []
    for pause_start, _ in sorted(pauses):
        t1, d1, d2 = _uniform2(rng, NOD_T1), _uniform2(rng, NOD_D1), _uniform2(rng, NOD_D2)
        depth = round(min(float(rng.uniform(*NOD_ANGLE)) * head, MAX_ANGLE), 1)
        start = _round_to_ms(pause_start - t1 - d1)
        end = pause_start + d2
        if start < 0 or end > duration or (nods and start < nods[-1].end):
            continue
        nods.append(Action("nod", start, _round_to_ms(end - start), depth, d1, d2))
    return nods


def _with_beat_nods(
    nods: list[Action], duration: float, peaks: Sequence[float], rng: np.random.Generator, style: Style
) -> list[Action]:
    """`nods` plus a small nod, lowest at the peak, on the style's share of `peaks`
    (seconds) where it fits inside [0, duration] without touching another nod."""
    out = list(nods)
    for peak in sorted(peaks):
        if rng.random() >= style.beat_nods:
            continue
        attack, release = _uniform2(rng, BEAT_ATTACK), _uniform2(rng, BEAT_RELEASE)
        depth = round(float(rng.uniform(*BEAT_DEPTH)) * style.head, 1)
        start = _round_to_ms(peak - attack)
        end = _round_to_ms(peak + BEAT_HOLD + release)
        if start < 0 or end > duration or _overlap(start, end, [(n.start, n.end) for n in out]) is not None:
            continue
        out.append(Action("nod", start, _round_to_ms(end - start), depth, attack, release))
    return sorted(out, key=lambda a: a.start)


def _smiles(
    duration: float, speech: Sequence[tuple[float, float]], rng: np.random.Generator, share: float
) -> list[Action]:
    """A slight smile around `share` of the sentence ends (`speech` (start, end) seconds),
    at least SMILE_GAP s apart and inside [0, duration]."""
    smiles: list[Action] = []
    for _, sentence_end in speech:
        if rng.random() >= share:
            continue
        start = _round_to_ms(max(sentence_end - _uniform2(rng, SMILE_LEAD), 0.0))
        attack, hold, release = (_uniform2(rng, bounds) for bounds in (SMILE_ATTACK, SMILE_HOLD, SMILE_RELEASE))
        amount = round(float(rng.uniform(*SMILE_AMOUNT)), 2)
        length = _round_to_ms(attack + hold + release)
        if start + length > duration or (smiles and start < smiles[-1].end + SMILE_GAP):
            continue
        smiles.append(Action("smile", start, length, amount, attack, release))
    return smiles


def emotion_at(actions: Sequence[Action], t: float) -> dict[str, float]:
    """{emotion: intensity} of the "emotion" `actions` at `t` seconds (linear ramps over
    attack and release; the timeline eases them, this is the amount for adapting)."""
    out: dict[str, float] = {}
    for action in actions:
        if action.kind != "emotion" or not action.start <= t <= action.end:
            continue
        rise = (t - action.start) / action.attack if action.attack else 1.0
        fall = (action.end - t) / action.release if action.release else 1.0
        out[action.emotion] = out.get(action.emotion, 0.0) + action.amplitude * min(1.0, rise, fall)
    return out


def adapt_to_emotions(actions: Sequence[Action]) -> tuple[Action, ...]:
    """`actions` with the behaviour drawn during an emotion changed by EMOTION_ADAPT: blinks
    thinned (deterministically: a blink is kept each time the running sum of the rate factor
    reaches 1), brow raises and smiles scaled (dropped at 0). Without emotions: unchanged."""
    moods = [a for a in actions if a.kind == "emotion"]
    if not moods:
        return tuple(actions)
    kept: list[Action] = []
    credit = 0.0
    for action in sorted(actions, key=lambda a: (a.start, KINDS.index(a.kind))):
        column = {"blink": 0, "brow": 1, "smile": 2}.get(action.kind)
        if column is None:
            kept.append(action)
            continue
        factor = 1.0
        for name, amount in emotion_at(moods, action.start).items():
            factor -= min(amount, 1.0) * (1.0 - EMOTION_ADAPT[name][column])
        factor = max(factor, 0.0)
        if column == 0:
            credit += factor
            if credit >= 1.0 - TIME_SLACK:
                credit -= 1.0
                kept.append(action)
        elif round(action.amplitude * factor, 2) > 0:
            kept.append(replace(action, amplitude=round(action.amplitude * factor, 2)))
    return tuple(kept)


# An emotion set by the transcript's markup is fully there when its first marked syllable
# starts and holds through its last; it eases in over this long before and out after (our
# choice: about a breath; shortened where the audio starts or ends sooner).
EMOTION_EASE = 0.4


def marked_spans(alignment, marks: Sequence) -> tuple[tuple[str, float, float, float], ...] | None:
    """(name, intensity, start, end seconds) of each transcript mark (speech/transcript.py
    EmotionMark: syllable indices) over the Alignment's syllables in time order; None when the
    alignment holds another number of syllables than the marks were counted on (an edited
    TextGrid of other text)."""
    syllables = sorted((s for sentence in alignment.sentences for s in sentence.syllables), key=lambda s: s.start)
    if marks and max(mark.last for mark in marks) >= len(syllables):
        return None
    return tuple((m.name, m.intensity, syllables[m.first].start, syllables[m.last].end) for m in marks)


def emotion_actions(spans: Sequence[tuple[str, float, float, float]], duration: float,
                    default: tuple[str, float] | None = None) -> tuple[Action, ...]:
    """The "emotion" actions of marked speech `spans` ((name, intensity, start, end) seconds)
    in audio of `duration` s, each easing in over EMOTION_EASE before its start and out after
    its end (overlapping spans of one emotion join, at the larger intensity); `default` (name,
    intensity) holds everywhere else, cross-fading into and out of the marked spans of other
    emotions (next to a marked span of its own emotion the default fades to neutral and back,
    over EMOTION_EASE or a third of its stretch, as one emotion's actions never overlap)."""
    marked: list[Action] = []
    for name, intensity, start, end in sorted(spans, key=lambda s: (s[2], s[0])):
        begin, finish = _round_to_ms(max(0.0, start - EMOTION_EASE)), _round_to_ms(min(duration, end + EMOTION_EASE))
        same = [a for a in marked if a.emotion == name and a.end > begin - TIME_SLACK]
        if same:
            marked.remove(same[-1])
            begin, intensity = same[-1].start, max(intensity, same[-1].amplitude)
        attack = _round_to_ms(min(EMOTION_EASE, start - begin)) if not same else same[-1].attack
        release = _round_to_ms(max(0.0, finish - max(end, begin + attack)))
        marked.append(Action("emotion", begin, _round_to_ms(finish - begin), float(intensity), max(attack, 0.0),
                             release, name))
    actions = list(marked)
    if default is not None:
        name, intensity = default[0], float(default[1])
        # covered stretches (start, end, attack, release), merged; a stretch holding the default's own
        # emotion is cut out without overlap (actions of one emotion never overlap), others cross-fade
        edges: list[tuple[float, float, float, float]] = []
        for action in sorted(marked, key=lambda a: a.start):
            rise, fall = (0.0, 0.0) if action.emotion == name else (action.attack, action.release)
            if edges and action.start < edges[-1][1]:
                first = edges[-1]
                edges[-1] = (first[0], max(first[1], action.end), first[2], fall if action.end >= first[1] else first[3])
            else:
                edges.append((action.start, action.end, rise, fall))
        start, attack = 0.0, 0.0
        for begin, end, rise, fall in edges:
            stop = _round_to_ms(begin + rise)
            if stop > start:
                length = _round_to_ms(stop - start)
                actions.append(Action("emotion", start, length, intensity, min(attack, length / 2),
                                      min(rise or _ramp(length), length / 2), name))
            start, attack = _round_to_ms(end - fall), fall or _ramp(duration - end)
        if duration > start:
            length = _round_to_ms(duration - start)
            actions.append(Action("emotion", start, length, intensity, min(attack, length / 2), 0.0, name))
    return tuple(sorted(actions, key=lambda a: (a.start, a.emotion)))


def _ramp(length: float) -> float:
    """The ease of a default mood's stretch of `length` s next to its own emotion: EMOTION_EASE
    or a third of the stretch, whichever is shorter (ms)."""
    return _round_to_ms(min(EMOTION_EASE, max(length, 0.0) / 3))


def _breaths(
    duration: float,
    pauses: Sequence[tuple[float, float]],
    speech: Sequence[tuple[float, float]],
    rng: np.random.Generator,
) -> list[Action]:
    """A breath in the silence before the first of `speech` (sentence (start, end) seconds)
    and in each of `pauses` (start, end) of at least BREATH_PAUSE s that speech follows and
    that ends BREATH_INTERVAL s or more after the last silence breathed in.

    The inhalation (attack, BREATH_INHALE, cut to the silence) ends BREATH_LEAD s before the
    speech resumes; the exhalation (release) lasts over the words up to the next breath's
    silence, at most BREATH_EXHALE s; the depth grows with that stretch of speech (BREATH_DEPTH up to
    BREATH_FULL s of it). So breaths never overlap and stay inside [0, duration].
    """
    first = min((start for start, _ in speech), default=duration)
    chosen: list[tuple[float, float]] = []
    for begin, end in sorted([(0.0, first)] + [pause for pause in pauses if pause[1] < duration]):
        if end - begin >= BREATH_PAUSE and (not chosen or end - chosen[-1][1] >= BREATH_INTERVAL):
            chosen.append((begin, end))
    breaths: list[Action] = []
    for (begin, end), after in zip(chosen, [*chosen[1:], (duration, duration)]):
        inhale_end = _round_to_ms(end - BREATH_LEAD)
        start = math.ceil(max(inhale_end - _uniform2(rng, BREATH_INHALE), begin) * 1000) / 1000
        # whole ms, a ms before the next breath's silence (or the end): breaths never touch
        exhale_end = (math.floor(min(after[0], inhale_end + BREATH_EXHALE) * 1000) - 1) / 1000
        talk = after[0] - end
        if talk <= 0 or start >= inhale_end or (breaths and start < breaths[-1].end):
            continue
        inhale, exhale = _round_to_ms(inhale_end - start), _round_to_ms(exhale_end - inhale_end)
        low, high = BREATH_DEPTH
        depth = low + (high - low) * min(talk / BREATH_FULL, 1.0) - float(rng.uniform(0.0, BREATH_JITTER))
        breaths.append(Action("breath", start, _round_to_ms(exhale_end - start), round(max(depth, 0.0), 2), inhale, exhale))
    return breaths
