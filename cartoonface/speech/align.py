"""Syllable timing inside one speaking part, without a Mandarin acoustic model.

The thesis (002, section 3.3) aligned syllables with an HMM and Mandarin acoustic models we
cannot ship. This module finds the N known syllables of a speaking part by dynamic
programming over 10 ms frames: the part is cut into exactly N syllables, optionally with
pauses between them (and before the first / after the last), maximising

    sum over syllables of  onset evidence at its start (by the class of its initial)
                         + log duration prior (by syllable type, scaled to the speaking rate
                                                of its stretch)
    + sum over pauses of   their frames' silence evidence + the energy fall where the pause
                           starts + the rise where it ends - a fixed penalty.

Onset evidence: the syllable starts where the vowel of the one before it ends, i.e. where the
100-1000 Hz band energy falls (stops, affricates, fricatives: their closure or frication
begins) or sits in a dip (nasals, laterals, glides, vowel-initial syllables; a dip of the
1000-3000 Hz band counts too, at a lower weight). Each class's evidence is moved by a small
lead (ONSET_LEAD): a sonorant's dip is deepest inside the consonant, after the syllable has
started. The fall and dip measures, the leads, the duration factors per syllable type and the
pause penalty were tuned on Biaobei sentences 000001-000035 only (bench/align.py;
docs/BENCHMARKS.md).

Pauses: silence is quiet both below 1 kHz and above 3 kHz (a voiceless fricative or
aspiration is quiet only below 1 kHz, and is part of its syllable). A pause inside the part
(Biaobei's `sp`, at least 0.1 s: shorter silences are taken for stop closures) or silence at
its edges (at least 0.04 s) is modelled as a gap: the syllable before it ends where the
silence starts, the next starts where it ends.
Otherwise one syllable ends where the next starts. Each stretch between pauses has its own
speaking rate: the duration prior expects the part's mean rate times one of RATES, the DP
choosing per stretch (at a small cost), so a reader who slows down or speeds up after a pause
does not push syllables over it. Syllables are ordered, do not overlap and
lie inside the span; without detected silence at the edges the first starts at span.start
and the last ends at span.end.

Confidence: the probability, by a small miss model (logistic regression, MISS_WEIGHTS), that the
onset lies within 50 ms of the truth, from the aligner's posterior and the evidence around the
onset (onset_features). The posterior is the probability that the onset lies within 50 ms of
where the best cut puts it, over all cuts weighted by exp(score / TEMPERATURE) (forward-backward:
the same dynamic programme summed instead of maximised, forward and on the time-reversed
problem), times the part's signal quality (its loudness range), with each stretch at the rate the
best cut chose. It is low where other cuts score nearly as well, also when they move a whole
stretch by one syllable; it is kept with each syllable (SyllableTiming.posterior).

Never fails: a part too short for its syllables, silence or noise, an empty or odd pinyin
all give a duration-prior split with low confidence.

Another approach, espeak-ng speech of the same syllables warped onto the recording by
DTW, was measured (bench/align.py) far below this one, also as a prior for it, so it is not used.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, Sequence

import numpy as np

from cartoonface.speech.audio import MIN_RECORDED, digital_silence, quantum
from cartoonface.speech.features import HOP, WINDOW_SECONDS, bands, smooth
from cartoonface.speech.pinyin import split_initial

if TYPE_CHECKING:
    from cartoonface.speech.audio import Audio


class SpanLike(Protocol):
    """Anything with a start and an end in seconds (sentences.Span)."""

    @property
    def start(self) -> float: ...

    @property
    def end(self) -> float: ...


@dataclass(frozen=True)
class SyllableTiming:
    """One syllable: start and end in seconds (absolute in the recording), confidence 0..1 (the
    miss model's probability that the onset lies within 50 ms: within_probability) and the
    aligner's own posterior 0..1 it rests on (the stretch check, stretches.unfit, judges by it)."""

    start: float
    end: float
    confidence: float
    posterior: float


@dataclass(frozen=True)
class SyllableType:
    """What the duration prior and onset evidence need of a pinyin syllable.

    initial: pinyin initial ("" when none; y and w count as initials here), final: the rest
    without tone digit and erhua r, tone 1-5 (5 = neutral or unknown), erhua: ends in r.
    """

    initial: str
    final: str
    tone: int
    erhua: bool


# Initial classes (standard Mandarin phonology): closure = silent stop or affricate onset,
# frication = voiceless fricative, sonorant = nasal, lateral or r, glide = y/w, none = vowel.
_CLASS = {**dict.fromkeys(("b", "d", "g", "z", "zh", "j"), "closure"),
          **dict.fromkeys(("p", "t", "k", "c", "ch", "q"), "aspirated"),
          **dict.fromkeys(("f", "s", "sh", "x", "h"), "frication"),
          **dict.fromkeys(("m", "n", "l", "r"), "sonorant"),
          **dict.fromkeys(("y", "w"), "glide"),
          "": "none"}


def initial_class(initial: str) -> str:
    """Pinyin initial ("" for none, y/w included) -> its class: "closure", "aspirated",
    "frication", "sonorant", "glide" or "none" (an unknown initial counts as "none")."""
    return _CLASS.get(initial, "none")


def syllable_type(pinyin: str) -> SyllableType:
    """Tone-numbered pinyin ("hang2", "wanr1", "lü4", "lv4") -> SyllableType; never raises."""
    text = re.sub(r"[^a-z0-9]", "", pinyin.lower().replace("ü", "v").replace("u:", "v"))
    tone = 5
    if text and text[-1].isdigit():
        tone = int(text[-1]) if text[-1] in "12345" else 5
        text = text[:-1]
    erhua = len(text) > 2 and text.endswith("r") and text != "er"
    if erhua:
        text = text[:-1]
    initial, final = split_initial(text, glides=True)
    return SyllableType(initial, final, tone, erhua)


# Relative duration of a syllable by type, multiplied together; fitted on Biaobei 000001-000035
# (log-linear least squares of each syllable's share of its part): see docs/BENCHMARKS.md.
_INITIAL_FACTOR = {"closure": 1.0, "aspirated": 1.09, "frication": 1.08, "sonorant": 0.98,
                   "glide": 0.875, "none": 0.84}
_FINAL_LETTER_FACTOR = 1.057    # per letter of the final beyond the first
_NASAL_FACTOR = 1.054           # final ends in n / ng
_TONE_FACTOR = {1: 1.0, 2: 1.01, 3: 1.0, 4: 0.97, 5: 0.91}
# Only one erhua syllable in the tuning sentences (fit 1.47): 1.15 chosen as a moderate guess.
_ERHUA_FACTOR = 1.15
_LAST_FACTOR = 1.40              # last syllable of the part (phrase-final lengthening)


def relative_durations(syllables: Sequence[str]) -> np.ndarray:
    """(N,) relative duration weights of the syllables of one part (mean 1)."""
    weights: list[float] = []
    for k, pinyin in enumerate(syllables):
        t = syllable_type(pinyin)
        w = _INITIAL_FACTOR[initial_class(t.initial)] * _TONE_FACTOR[t.tone]
        w *= _FINAL_LETTER_FACTOR ** max(len(t.final) - 1, 0)
        w *= _NASAL_FACTOR if t.final.endswith(("n", "ng")) else 1.0
        w *= _ERHUA_FACTOR if t.erhua else 1.0
        w *= _LAST_FACTOR if k == len(syllables) - 1 else 1.0
        weights.append(w)
    relative = np.array(weights, dtype=float)
    return relative / relative.mean() if relative.size else relative


# Tuned on Biaobei 000001-000035 (bench/align.py).
DURATION_SPREAD = 0.35     # sd of log(duration / expected duration)
FALL_WEIGHT = 0.2          # per dB of band-energy fall across an obstruent onset
DIP_WEIGHT = 0.1           # per dB of dip depth at a sonorant / glide / vowel onset
DIP_CAP = 8.0              # dB: deeper dips are closures or pauses, no likelier onsets of these
MID_DIP_SHARE = 0.4        # weight of a 1-3 kHz dip next to a 0.1-1 kHz one (the larger counts):
                           # a nasal's murmur or a glide can keep the low band up while F2/F3 drop
SILENCE_SCALE = 6.0        # dB below the silence threshold worth one unit of pause evidence
SILENCE_CLIP = (-3.0, 1.0)  # pause evidence per frame is kept within these bounds (a loud frame
                            # costs at most 3 units, a quiet one earns at most 1)
# The part's level range: its loud level is this percentile of its 100-1000 Hz frames, its floor
# this percentile of the frames of the part and its margins. Digital silence (audio.DIGITAL_SILENCE)
# is no noise floor: exact zeros between joined sentences would put the floor 40 dB under the real
# one, and the pauses inside the part would count as speech; its frames are set to the floor of
# the recorded frames first (_lift_digital_silence).
LOUD_PERCENTILE = 95.0
FLOOR_PERCENTILE = 5.0
# Digital silence is set no higher than this many dB under the loud level of its band (100-1000,
# 1000-3000, 3000-8000 Hz): a noise gate also silences the quietest speech, whose level is then
# no noise floor. Natural recordings span 55-75 dB in each band (Biaobei 000001-000035); a noisy
# one far less in the high band (room noise there at -60 dBFS lies ~35 dB under espeak-ng speech,
# tests/test_silence.py), so that band's limit is lower. Chosen on Biaobei 000001-000035
# (bench/silence.py: 45-60 dB tried).
LOW_NOISE_RANGE_DB = 70.0
MID_NOISE_RANGE_DB = 60.0
HIGH_NOISE_RANGE_DB = 50.0
SILENCE_SHARE = 0.3        # frames below floor + this share of the range are silent
MIN_RANGE_DB = 10.0        # a part with a smaller range is noise or silence: duration-prior split
QUALITY_RANGE_DB = 20.0    # dB of range above MIN_RANGE_DB at which the signal quality reaches 1
PAUSE_PENALTY = 3.0        # per pause, in units of evidence
# Phrase breaks fall at word boundaries, likelier after longer words: with the words known
# (align_syllables' `words`), a pause inside a word costs INSIDE_WORD_PAUSE more, one after a
# word of k syllables AFTER_WORD_PAUSE * min(k - 1, LONG_WORD) less. Tuned on Biaobei
# 000001-000035 read as unpunctuated paragraphs (bench/align.py; docs/BENCHMARKS.md).
INSIDE_WORD_PAUSE = 2.0
AFTER_WORD_PAUSE = 0.5
LONG_WORD = 2
MIN_PAUSE = 10             # frames: shorter silences are closures, not pauses
EDGE_MIN_PAUSE = 4         # frames: the same for silence before the first / after the last syllable
MIN_FRAMES = 3             # frames: the shortest syllable
LONGEST_SHARE = 4          # a syllable lasts at most this many times its expected duration
# Each stretch between pauses is read at its own rate: its syllables are expected to last one of
# RATES times their duration at the part's mean rate, the DP choosing the rate per stretch at a cost
# (log-normal, sd RATE_SPREAD) paid once per stretch. Biaobei 000001-000035 and its copies: within 50 ms
# unchanged for rates 1.25 or 1.4 and sd 0.15 or 0.2 (0.3 and 0.5 lost one paragraph onset); espeak-ng
# sentences read at 0.7x then 1.4x in one part: 30 -> 90 % for all four (tests/test_align.py). The
# narrowest is kept: with 1.4 / 0.2 one held-out paragraph lost 15 onsets (a stretch read "slower"
# took a syllable of the next, a "faster" one made up for it; docs/BENCHMARKS.md), so this choice was
# made after seeing held-out data. Three rates cost about 1.2-1.6x the time of one.
RATES = np.array([1 / 1.25, 1.0, 1.25])
RATE_SPREAD = 0.15
SMOOTH_FRAMES = 3          # band levels are smoothed over this many frames (30 ms)
CHANGE_FRAMES = 2          # a fall or rise is measured from this many frames before to as many after
CHANGE_CAP_DB = 30.0       # larger falls and rises count as this (a step into digital silence is no likelier)
DIP_REACH = 12             # frames (120 ms) either side whose highest level a dip is measured against
MINIMUM_REACH = 3          # frames either side within which a dip must be the (near) lowest
MINIMUM_TOLERANCE_DB = 1.0  # dB above the nearby minimum still counted as the minimum
MARGIN = 20                # frames of context read on each side of the span
SURE_DISTANCE = 5          # frames: an onset within this of the best cut's counts as right (50 ms)
# Confidence = the posterior probability of the onset lying within SURE_DISTANCE of the best cut's,
# every cut weighted by exp(score / TEMPERATURE). Chosen on Biaobei 000001-000035 and its tempo, pitch
# and paragraph copies as the temperature at which the posterior best ranks the onsets more than
# 50 ms off (average precision 0.208 / 0.223 / 0.243 / 0.254 / 0.250 at 0.7 / 1 / 1.25 / 1.5 / 2;
# bench/align.py, docs/BENCHMARKS.md). It is not calibrated: lower temperatures give truer
# probabilities (log loss 0.44 at 1.5, 0.20 at 0.7) but rank worse.
TEMPERATURE = 1.5
BAND = 50                  # frames: the posterior sums over cuts ending each syllable within this of
                           # the best cut's end (0.5 s, a slip of two syllables; summing over the whole
                           # part took 2.3-2.9x the time and ranked misses no better)
LOW_CONFIDENCE = 0.1       # confidence of a fallback (duration-prior) split
# The confidence shipped is a miss model over the posterior and the evidence around the onset
# (onset_features): the probability that the onset lies within 50 ms, 1 - logistic(MISS_BIAS +
# sum of MISS_WEIGHTS times FEATURES). Fitted by L2-regularised logistic regression (weight 1 on the
# standardised features) on the aligner-alone tuning pool only: Biaobei 000001-000035 as parts, its
# tempo 0.8x / 1.25x, pitch -4 / +4 copies and paragraphs of 5, and espeak-ng reading the same
# sentences in four voices, rates and pitches, each of its onsets weighted 0.5 (chosen by
# cross-validation among 0 / 0.25 / 0.5 / 1: one professional voice alone taught that a female
# espeak-ng voice's dips and low posteriors are misses). `.venv/bin/python -m bench.align fit`,
# docs/BENCHMARKS.md. The features were chosen among those candidates by grouped cross-validation on
# the Biaobei pool (7 folds of 5 recordings): the posterior alone, with its stretch's mean, and with
# the syllable before's duration, dips and the pause edges.
FEATURES = ("posterior", "stretch", "duration_before", "dips_before", "pause_edge")
MISS_BIAS = -3.376
MISS_WEIGHTS = {"posterior": -0.631, "stretch": -0.938, "duration_before": 3.835, "dips_before": 0.138,
                "pause_edge": 0.267}
DEEP_DIP_DB = 3.0          # dB: a dip this deep inside a syllable parts two loudness peaks
DIP_EDGE_FRAMES = 3        # frames at each end of a syllable where its dips are not counted
LOGIT_FLOOR = 1e-3         # probabilities are kept this far from 0 and 1 before their log odds
# Frames by which a class's onset precedes the peak of its evidence (negative: follows it).
# The dip of a nasal, lateral or r is deepest inside the consonant, about 20 ms after the
# consonant (and the syllable) starts; a glide's after ~10 ms; the steepest fall into a stop
# closure comes ~10 ms before the closure is complete, where the reference puts the onset.
# Each is the rounded median signed error per class on Biaobei 000001-000035 with no lead.
ONSET_LEAD = {"closure": -1, "aspirated": -1, "frication": 0, "sonorant": 2, "glide": 1, "none": 0}
FRICATION_RANGE = 0.4      # share of the 3-8 kHz range above its floor that is no silence
FRICATION_FLOOR = 10.0     # dB above the 3-8 kHz floor that is always tolerated in a silence
                           # (no effect on Biaobei; checked on Chao 1922, whose high band is noise)


def edge_evidence(low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """(T,) smoothed dB of 100-1000 Hz and 3000-8000 Hz -> (2, T): evidence that a pause
    starts at each position (the low band falls) and that one ends (either band rises)."""
    def change(x):
        pad = np.pad(x, CHANGE_FRAMES, mode="edge")
        return pad[2 * CHANGE_FRAMES:] - pad[:-2 * CHANGE_FRAMES]
    rise = np.maximum(change(low), change(high))
    return FALL_WEIGHT * np.clip(np.stack([-change(low), rise]), 0.0, CHANGE_CAP_DB)


def _earlier(x: np.ndarray, frames: int) -> np.ndarray:
    """(T,) evidence moved `frames` positions earlier (later when negative), zero-filled."""
    if frames == 0:
        return x
    out = np.zeros_like(x)
    if frames > 0:
        out[:-frames] = x[frames:]
    else:
        out[-frames:] = x[:frames]
    return out


def _dip(band: np.ndarray) -> np.ndarray:
    """(T,) smoothed dB of one band -> (T,) dB depth of the dip at each local minimum (0 elsewhere),
    below the lower of the highest levels within DIP_REACH frames before and after, capped at DIP_CAP."""
    pad = np.pad(band, DIP_REACH, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(pad, DIP_REACH)
    left, right = windows[:-DIP_REACH - 1].max(axis=1), windows[DIP_REACH + 1:].max(axis=1)
    dip = np.minimum(left, right) - band
    # only at (near) local minima: a flat quiet stretch is one dip, not many
    inner = pad[DIP_REACH - MINIMUM_REACH:-(DIP_REACH - MINIMUM_REACH)]
    nearby = np.lib.stride_tricks.sliding_window_view(inner, 2 * MINIMUM_REACH + 1).min(axis=1)
    return np.clip(np.where(band <= nearby + MINIMUM_TOLERANCE_DB, dip, 0.0), 0.0, DIP_CAP)


def onset_evidence(low: np.ndarray, mid: np.ndarray, low_dip: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """(T,) smoothed 100-1000 Hz and 1000-3000 Hz dB per boundary position -> for each initial
    class, (T,) evidence that a syllable of that class starts there (higher is likelier), each
    moved by the class's ONSET_LEAD. `low_dip`: `_dip(low)` when already computed."""
    pad = np.pad(low, CHANGE_FRAMES, mode="edge")
    fall = FALL_WEIGHT * np.clip(pad[:-2 * CHANGE_FRAMES] - pad[2 * CHANGE_FRAMES:], 0.0, CHANGE_CAP_DB)
    dip = DIP_WEIGHT * np.maximum(_dip(low) if low_dip is None else low_dip, MID_DIP_SHARE * _dip(mid))
    measure = {"closure": fall, "aspirated": fall, "frication": fall, "sonorant": dip, "glide": dip, "none": dip}
    return {c: _earlier(x, ONSET_LEAD[c]) for c, x in measure.items()}


_NEG = -1e18                # score of an impossible cut


def _duration_score(d: np.ndarray, mean: float) -> np.ndarray:
    """(D,) durations in frames, the expected duration -> (D,) log duration prior."""
    ratio = np.log(np.maximum(d, 1) / mean)
    return -0.5 * (ratio / DURATION_SPREAD) ** 2


def _duration_scores(ends: np.ndarray, d: np.ndarray, mean: float, pace: np.ndarray) -> np.ndarray:
    """(K,) consecutive end positions, (D,) consecutive ascending durations in frames, the expected
    duration at the part's own rate and (T + 1,) log pace per position -> (K, D) log duration prior
    of a syllable lasting d frames up to each end, or (1, D) when it is the same for every end: its
    expected duration is scaled by exp of the mean pace at its two ends (the same forwards and
    time-reversed)."""
    read = pace[max(ends[0] - d[-1], 0):ends[-1] + 1]
    if np.all(read == read[0]):  # one pace (the usual case): on one row, the mean of two equal paces is that pace
        local = read[:1, None]
    else:
        local = 0.5 * (pace[ends][:, None] + _before(pace, ends, d, pace[0]))
    ratio = np.log(np.maximum(d, 1) / mean)[None, :] - local
    return -0.5 * (ratio / DURATION_SPREAD) ** 2


def _before(x: np.ndarray, ends: np.ndarray, d: np.ndarray, fill: float) -> np.ndarray:
    """(T,) values, (K,) consecutive positions, (D,) consecutive ascending durations -> (K, D)
    x[ends[j] - d[m]], `fill` where that position is negative: a read-only view of `x` reversed and
    padded (no index arrays: the DP's candidates cost a pass over memory, not a gather; each row
    runs forwards through memory, which numpy copies ~1.2x as fast as backwards)."""
    padded = np.concatenate([x[::-1], np.full(d[-1], fill)])  # padded[p] = x[T - 1 - p]
    first = len(x) - 1 - ends[-1] + d[0]  # the last row's first value
    windows = np.lib.stride_tricks.as_strided(padded[first:], (ends.size, d.size), padded.strides * 2, writeable=False)
    return windows[::-1]


@dataclass(frozen=True)
class _Lattice:
    """Forward dynamic-programming tables over boundary positions k = 0..T and stretch rates r
    (see _forward)."""

    after_syllable: np.ndarray   # (N + 1, R, T + 1) best score with i syllables done, the last ending
                                 # at k, its stretch read at rate r
    after_pause: np.ndarray      # (N + 1, T + 1) the best of those followed by a pause ending at k
    pause_from: np.ndarray       # (N + 1, T + 1) where that pause started
    rate_before: np.ndarray      # (N + 1, T + 1) the best rate of a stretch ending at k (before a pause)
    length: np.ndarray           # (N, R, T + 1) frames of syllable i when it ends at k at rate r (0 where
                                 # no whole cut ends it)
    fresh_won: np.ndarray        # (N, R, T + 1) whether syllable i starting at k at rate r follows a pause


def pause_penalties(count: int, words: Sequence[int] | None) -> np.ndarray:
    """(count + 1,) cost of a pause after i syllables of `count`, i = 0..count: PAUSE_PENALTY,
    and with `words` (syllables per word, in order, summing to `count`; None: unknown) more
    inside a word and less after a long one (INSIDE_WORD_PAUSE, AFTER_WORD_PAUSE)."""
    penalty = np.full(count + 1, PAUSE_PENALTY)
    if words is None or sum(words) != count or min(words, default=1) < 1:
        return penalty
    ends = np.cumsum(words)
    inside = np.ones(count + 1, dtype=bool)
    inside[0] = inside[-1] = False
    inside[ends] = False
    penalty[inside] += INSIDE_WORD_PAUSE
    penalty[ends[:-1]] -= AFTER_WORD_PAUSE * np.minimum(np.array(words[:-1]) - 1, LONG_WORD)
    return penalty


def rate_costs() -> np.ndarray:
    """(R,) cost of reading a stretch at each of RATES (log-normal prior, sd RATE_SPREAD)."""
    return 0.5 * (np.log(RATES) / RATE_SPREAD) ** 2


def _forward(evidence: np.ndarray, silence: np.ndarray, edges: np.ndarray, means: np.ndarray,
             penalty: np.ndarray) -> _Lattice:
    """Score every cut of T frames into N syllables with optional pauses between and around them,
    each stretch between pauses read at one of RATES.

    evidence: (N, T + 1) onset evidence of syllable i starting at boundary k when no pause
    precedes it (row 0 unused: the part's start is given); silence: (T,) per-frame pause
    evidence; edges: (2, T + 1) evidence that a pause starts (sound falls) / ends (sound
    rises) at k; means: (N,) expected durations in frames at the part's rate; penalty: (N + 1,)
    cost of a pause after i syllables. A stretch read at rate r expects its syllables to last r
    times their means, and costs rate_costs()[r] once. T >= N * MIN_FRAMES.

    Syllable i is scored only where it can end on a whole cut: after the MIN_FRAMES of each
    syllable up to it and before those of each after it. Elsewhere its scores stay _NEG: a
    boundary that cannot reach the part's end leads only to others that cannot, and one before the
    syllables up to it fit held a score near _NEG, which no cut takes; so every whole cut's score
    and the best cut are those of the whole tables (tests/test_align_lattice.py).
    """
    n, positions = evidence.shape
    total = positions - 1
    cost = rate_costs()
    rates = len(RATES)
    cum = np.concatenate([[0.0], np.cumsum(silence)])
    after_syllable = np.full((n + 1, rates, positions), _NEG)
    after_pause = np.full((n + 1, positions), _NEG)
    pause_from = np.zeros((n + 1, positions), dtype=int)
    rate_before = np.zeros((n + 1, positions), dtype=int)
    length = np.zeros((n, rates, positions), dtype=int)
    fresh_won = np.zeros((n, rates, positions), dtype=bool)
    after_syllable[0, :, 0] = -cost
    k = np.arange(positions)
    for i in range(n + 1):
        # pause: best start s <= k - gap of  after_syllable[i, r, s] + edges[0, s] - cum[s], any r
        rate_before[i] = after_syllable[i].argmax(axis=0)
        base = after_syllable[i].max(axis=0) + edges[0] - cum
        best = np.maximum.accumulate(base)
        arg = np.maximum.accumulate(np.where(base >= best, k, 0))
        gap = EDGE_MIN_PAUSE if i in (0, n) else MIN_PAUSE
        shifted = np.full(positions, _NEG)
        shifted[gap:] = best[:-gap]
        after_pause[i] = shifted + cum - penalty[i] + edges[1]
        pause_from[i, gap:] = arg[:-gap]
        if i == n:
            break
        ends = slice((i + 1) * MIN_FRAMES, total - (n - 1 - i) * MIN_FRAMES + 1)
        for r in range(rates):
            # a syllable goes on its stretch at rate r, or starts a new stretch after a pause
            direct = after_syllable[i, r] + evidence[i]
            fresh = after_pause[i] - cost[r]
            start_score = np.maximum(direct, fresh)
            fresh_won[i, r] = fresh > direct
            mean = means[i] * RATES[r]
            longest = min(total, int(LONGEST_SHARE * mean) + MIN_FRAMES)
            d = np.arange(MIN_FRAMES, max(longest, MIN_FRAMES) + 1)
            # impossible starts before frame 0
            cand = np.array(_before(start_score, k[ends], d, _NEG))  # copied first: adding to the view is slower
            cand += _duration_score(d, mean)
            choice = cand.argmax(axis=1)
            after_syllable[i + 1, r, ends] = cand[np.arange(len(cand)), choice]
            length[i, r, ends] = d[choice]
    return _Lattice(after_syllable, after_pause, pause_from, rate_before, length, fresh_won)


def _best_cut(lattice: _Lattice) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(starts, ends, rate) (N,) each of the best cut: boundary indices, starts[i] < ends[i] <=
    starts[i + 1], and the index into RATES of each syllable's stretch."""
    n, _, positions = lattice.length.shape
    starts, ends, rate = (np.zeros(n, dtype=int) for _ in range(3))
    pos = positions - 1
    in_pause = lattice.after_pause[n, pos] > lattice.after_syllable[n, :, pos].max()
    r = int(lattice.after_syllable[n, :, pos].argmax())
    for i in range(n, 0, -1):
        if in_pause:
            pos = lattice.pause_from[i, pos]
            r = int(lattice.rate_before[i, pos])
        ends[i - 1] = pos
        rate[i - 1] = r
        starts[i - 1] = pos - lattice.length[i - 1, r, pos]
        in_pause = lattice.fresh_won[i - 1, r, starts[i - 1]]
        pos = starts[i - 1]
    return starts, ends, rate


def _soft_forward(evidence: np.ndarray, silence: np.ndarray, edges: np.ndarray, means: np.ndarray,
                  penalty: np.ndarray, pace: np.ndarray, temperature: float,
                  starts: np.ndarray, ends: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The forward pass of `_forward` (same first arguments) summed over cuts instead of maximised:
    every score divided by `temperature`, the best of the alternatives replaced by their
    log-sum-exp, over the cuts that end each syllable i within BAND frames of ends[i] (the best
    cut's starts and ends, (N,) each). Returns (after_syllable, after_pause), (N + 1, T + 1) and
    (N, T + 1): log of the summed exp(score / temperature) of those cuts with i syllables done,
    the last ending at k (then a pause ending at k); _NEG or near it (below _NEG / 2) where there
    are none.

    The pauses before syllable i are summed only where they are read (where its counted cuts start,
    and BAND frames either side of starts[i] for the posterior), from where syllable i - 1's
    counted cuts end on (before, no cut is counted, and a log-sum-exp is the same without terms
    near _NEG): every value read is the one the sums over the whole part give
    (tests/test_align_lattice.py)."""
    n, positions = evidence.shape
    total = positions - 1
    evidence, silence, edges, penalty = (x / temperature for x in (evidence, silence, edges, penalty))
    cum = np.concatenate([[0.0], np.cumsum(silence)])
    after_syllable = np.full((n + 1, positions), _NEG)
    after_pause = np.full((n, positions), _NEG)
    after_syllable[0, 0] = 0.0
    scale = np.exp(pace.max())
    reached = 0  # the first position where after_syllable[i] may hold a cut
    for i in range(n):
        longest = min(total, int(LONGEST_SHARE * means[i] * scale) + MIN_FRAMES)
        d = np.arange(MIN_FRAMES, max(longest, MIN_FRAMES) + 1)
        first, last = max(ends[i] - BAND, 0), min(ends[i] + BAND, total)
        low = max(min(starts[i] - BAND, first - d[-1]), 0)  # the first position read
        gap = EDGE_MIN_PAUSE if i == 0 else MIN_PAUSE
        if reached + gap <= last:
            summed = np.logaddexp.accumulate(after_syllable[i, reached:last - gap + 1] + edges[0, reached:last - gap + 1]
                                             - cum[reached:last - gap + 1])
            after_pause[i, reached + gap:last + 1] = (summed + cum[reached + gap:last + 1] - penalty[i]
                                                      + edges[1, reached + gap:last + 1])
        start_score = np.logaddexp(after_syllable[i, low:last + 1] + evidence[i, low:last + 1], after_pause[i, low:last + 1])
        band = np.arange(first, last + 1)
        cand = np.array(_before(start_score, band - low, d, _NEG))  # copied first, as in _forward
        cand += _duration_scores(band, d, means[i], pace) / temperature
        after_syllable[i + 1, band] = _log_sum_exp(cand)
        reached = first
    return after_syllable, after_pause


def _log_sum_exp(x: np.ndarray) -> np.ndarray:
    """(R, C) -> (R,) log of the sum of exp over each row, without overflow."""
    top = x[np.arange(len(x)), x.argmax(axis=1)]  # the max: numpy's argmax is 2-3x faster over short rows
    shifted = x - top[:, None]
    return top + np.log(np.exp(shifted, out=shifted).sum(axis=1))


def _onset_posteriors(evidence: np.ndarray, silence: np.ndarray, edges: np.ndarray, means: np.ndarray,
                      penalty: np.ndarray, pace: np.ndarray, starts: np.ndarray, ends: np.ndarray,
                      temperature: float) -> np.ndarray:
    """(N,) posterior probability that syllable i's onset lies within SURE_DISTANCE frames of
    starts[i], given the best cut's (N,) starts and ends, every cut (of those whose syllables
    end within BAND frames of the best cut's) weighted by exp(score / temperature); pace: (T + 1,)
    as `_duration_scores`; other arguments as `_forward`. The onset's distribution is the
    forward sum up to k times the sum over the rest, which is the forward sum of the
    time-reversed problem (syllables and frames reversed, pause edges swapped, each boundary
    keeping its evidence)."""
    n, positions = evidence.shape
    total = positions - 1
    syllable, pause = _soft_forward(evidence, silence, edges, means, penalty, pace, temperature, starts, ends)
    flipped = np.zeros_like(evidence)
    flipped[1:] = evidence[:0:-1, ::-1]
    backward, _ = _soft_forward(flipped, silence[::-1], edges[::-1, ::-1], means[::-1], penalty[::-1],
                                pace[::-1], temperature, total - ends[::-1], total - starts[::-1])
    onset = evidence / temperature
    onset[0] = 0.0
    # row i: onset i at each k, the forward sum up to k times the reversed problem's from k on
    score = np.logaddexp(syllable[:n] + onset, pause) + backward[n:0:-1, ::-1]
    near = [_log_sum_exp(row[None, max(s - SURE_DISTANCE, 0):s + SURE_DISTANCE + 1])[0] for row, s in zip(score, starts)]
    return np.exp(np.array(near) - _log_sum_exp(score))


def prior_split(span: SpanLike, syllables: Sequence[str], confidence: float) -> tuple[SyllableTiming, ...]:
    """The span cut in proportion to the duration prior, every syllable with `confidence`
    (a span ending before it starts is taken as empty)."""
    weights = relative_durations(syllables)
    edges = span.start + max(span.end - span.start, 0.0) * np.concatenate([[0.0], np.cumsum(weights)]) / max(weights.sum(), 1e-9)
    edges[-1] = max(span.end, span.start)
    return tuple(SyllableTiming(float(a), float(b), confidence, confidence) for a, b in zip(edges[:-1], edges[1:]))


def align_syllables(audio: Audio, span: SpanLike, syllables: Sequence[str],
                    words: Sequence[int] | None = None) -> tuple[SyllableTiming, ...]:
    """Start, end and confidence of each of `syllables` (tone-numbered pinyin) inside `span`.

    `words`: syllables per word of the text, in order (None: not known); pauses then fall
    at word boundaries rather than inside words (pause_penalties).

    audio: samples (n,) float mono and rate; span: .start/.end in seconds. Returns one
    SyllableTiming per syllable, in order, inside the span (see the module docstring for
    pauses). Never raises for odd input: an empty list gives (), a span too short, silent or
    outside the audio gives a duration-prior split with low confidence.
    """
    return align_details(audio, span, syllables, words)[0]


def align_details(audio: Audio, span: SpanLike, syllables: Sequence[str],
                  words: Sequence[int] | None = None) -> tuple[tuple[SyllableTiming, ...], np.ndarray]:
    """`align_syllables` (same arguments) and the (N, len(FEATURES)) `onset_features` its
    confidences were computed from (rows of nan for a duration-prior split), for fitting the
    miss model (bench/align.py)."""
    unknown = np.full((len(syllables), len(FEATURES)), np.nan)
    n = len(syllables)
    if n == 0:
        return (), unknown
    total = int(round((span.end - span.start) / HOP))
    if total < n * MIN_FRAMES or audio.rate <= 0:
        return prior_split(span, syllables, LOW_CONFIDENCE), unknown
    first = int(round(span.start * audio.rate)) - MARGIN * int(round(HOP * audio.rate))
    last = int(round(span.end * audio.rate)) + MARGIN * int(round(HOP * audio.rate))
    clip = np.asarray(audio.samples[max(first, 0):max(last, 0)], dtype=np.float64)
    step = quantum(clip)  # of the recorded samples: the zeros padded on below lie off a DC-offset grid
    clip = np.concatenate([np.zeros(max(-first, 0)), clip, np.zeros(max(last - max(first, 0) - clip.size - max(-first, 0), 0))])
    low, mid, high = bands(clip, audio.rate)
    recorded = ~_dead_frames(clip, audio.rate, low.size, step)
    low = smooth(_lift_digital_silence(low, recorded, LOW_NOISE_RANGE_DB), SMOOTH_FRAMES)
    mid = smooth(_lift_digital_silence(mid, recorded, MID_NOISE_RANGE_DB), SMOOTH_FRAMES)
    high = smooth(_lift_digital_silence(high, recorded, HIGH_NOISE_RANGE_DB), SMOOTH_FRAMES)
    # boundary k (time span.start + k * HOP) sits at the centre of feature frame MARGIN + k - 1.
    index = np.clip(MARGIN + np.arange(total + 1) - 1, 0, low.size - 1)
    inner = low[index[:-1]]
    loud = np.percentile(inner, LOUD_PERCENTILE)
    floor = np.percentile(low, FLOOR_PERCENTILE)
    if not np.isfinite(loud) or loud - floor < MIN_RANGE_DB:
        return prior_split(span, syllables, LOW_CONFIDENCE), unknown
    threshold = floor + SILENCE_SHARE * (loud - floor)
    silence = np.minimum(np.clip((threshold - inner) / SILENCE_SCALE, *SILENCE_CLIP),
                         _high_band_silence(high, index[:-1]))
    speech_frames = max(float(np.sum(inner > threshold)), n * MIN_FRAMES)
    means = relative_durations(syllables) * speech_frames / n
    low_dip = _dip(low)
    by_class = onset_evidence(low, mid, low_dip)
    evidence = np.stack([by_class[initial_class(syllable_type(p).initial)][index] for p in syllables])
    edges = edge_evidence(low, high)[:, index]
    evidence[0] = 0.0
    penalty = pause_penalties(n, words)
    starts, ends, rate = _best_cut(_forward(evidence, silence, edges, means, penalty))
    # the posterior sums over cuts with each syllable's stretch at the rate the best cut chose
    pace = np.zeros(total + 1)
    for a, b, r in zip(starts, ends, rate):
        pace[a:b + 1] = np.log(RATES[r])
    quality = float(np.clip((loud - floor - MIN_RANGE_DB) / QUALITY_RANGE_DB, 0.0, 1.0))
    posterior = quality * _onset_posteriors(evidence, silence, edges, means, penalty, pace, starts, ends, TEMPERATURE)
    features = onset_features(posterior, starts, ends, means * RATES[rate], low_dip[index], edges)
    confidence = within_probability(features)
    # boundary k of `total` sits at span.start + k * HOP; stretched by under half a frame so
    # that k = 0 and k = total are exactly the span's ends
    times = span.start + (span.end - span.start) * np.stack([starts, ends], axis=1) / total
    return tuple(SyllableTiming(float(a), float(b), float(c), float(p))
                 for (a, b), c, p in zip(times, confidence, posterior)), features


def _logit(p: np.ndarray) -> np.ndarray:
    """(N,) probabilities -> (N,) log odds, the probabilities kept within LOGIT_FLOOR of 0 and 1."""
    q = np.clip(p, LOGIT_FLOOR, 1.0 - LOGIT_FLOOR)
    return np.log(q / (1.0 - q))


def onset_features(posterior: np.ndarray, starts: np.ndarray, ends: np.ndarray, expected: np.ndarray,
                   dips: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """The evidence on each onset of the best cut that the miss model weighs (MISS_WEIGHTS).

    posterior: (N,) confidences of the onsets (posterior times signal quality); starts, ends: (N,)
    boundary indices of the best cut (a syllable followed by a pause ends before the next starts);
    expected: (N,) expected frames of each syllable at its stretch's rate; dips: (T + 1,) dB depth
    of the 100-1000 Hz dip at each boundary (`_dip`); edges: (2, T + 1) `edge_evidence`.
    Returns (N, len(FEATURES)), one column per name in FEATURES:
    posterior: log odds of the onset's own posterior; stretch: log odds of the mean posterior of its
    stretch (the syllables between two pauses of the best cut); duration_before: |log(duration /
    expected)| of the syllable before (0 for the first); dips_before: dips of at least DEEP_DIP_DB
    inside the syllable before (away from its edges: a second loudness peak, a syllable it may have
    swallowed); pause_edge: the fall / rise evidence of a pause that ends at the onset or starts at
    the end of its syllable (0 with no pause next to it).
    """
    n = posterior.size
    gap_before = np.r_[False, starts[1:] > ends[:-1]]
    gap_after = np.r_[gap_before[1:], False]
    stretch = np.cumsum(gap_before)
    stretch_mean = (np.bincount(stretch, weights=posterior) / np.bincount(stretch))[stretch]
    duration = np.abs(np.log((ends - starts) / expected))
    inner = [dips[a + DIP_EDGE_FRAMES:max(b - DIP_EDGE_FRAMES, a + DIP_EDGE_FRAMES)] for a, b in zip(starts, ends)]
    deep = np.array([np.sum(d >= DEEP_DIP_DB) for d in inner], dtype=float)
    pause_edge = np.where(gap_before, edges[1, starts], 0.0) + np.where(gap_after, edges[0, ends], 0.0)
    before = np.r_[0.0, np.ones(n - 1)]
    return np.stack([_logit(posterior), _logit(stretch_mean), before * np.r_[0.0, duration[:-1]],
                     before * np.r_[0.0, deep[:-1]], pause_edge], axis=1)


def within_probability(features: np.ndarray) -> np.ndarray:
    """(N, len(FEATURES)) `onset_features` -> (N,) the miss model's probability that each onset lies
    within 50 ms of the truth: 1 - logistic(MISS_BIAS + features . MISS_WEIGHTS)."""
    weights = np.array([MISS_WEIGHTS[name] for name in FEATURES])
    return 1.0 / (1.0 + np.exp(MISS_BIAS + features @ weights))


def _lift_digital_silence(band: np.ndarray, recorded: np.ndarray, most_below: float | None) -> np.ndarray:
    """(T,) dB of one band, (T,) bool frames of recorded sound -> the band with its digital-silence
    frames set to the FLOOR_PERCENTILE of the recorded ones, as if the gap held the recording's own
    noise (a faint dither in the gaps gives the same timing as natural pauses), but at least
    `most_below` dB (None: no limit) under the LOUD_PERCENTILE of the recorded frames. Unchanged
    when fewer than MIN_RECORDED of the frames are recorded."""
    if recorded.all() or recorded.mean() < MIN_RECORDED:
        return band
    kept = band[recorded]
    floor = np.percentile(kept, FLOOR_PERCENTILE)
    if most_below is not None:
        floor = min(floor, np.percentile(kept, LOUD_PERCENTILE) - most_below)
    return np.where(recorded, band, floor)


def _dead_frames(clip: np.ndarray, rate: int, count: int, step: float) -> np.ndarray:
    """(count,) bool: feature frame i (25 ms from i * HOP s of the (n,) `clip` at `rate` Hz, whose
    samples lie on an integer grid of `step`, 0 for none) holds only digital silence
    (audio.digital_silence); frames past the clip's end count as silent."""
    blocks = digital_silence(clip, rate, HOP, step)
    covered = int(np.ceil(WINDOW_SECONDS / HOP))
    padded = np.concatenate([blocks, np.ones(count + covered, dtype=bool)])
    return np.all(np.lib.stride_tricks.sliding_window_view(padded, covered)[:count], axis=1)


def _high_band_silence(high: np.ndarray, inner: np.ndarray) -> np.ndarray:
    """(T_all,) smoothed 3-8 kHz dB of the clip, (T,) indices of the span's frames -> (T,)
    silence evidence of that band alone: a voiceless fricative or aspiration is quiet below
    1 kHz but loud above 3 kHz, and is no pause. The band counts as quiet below its floor plus
    FRICATION_RANGE of its range, and always within FRICATION_FLOOR dB of its floor (noisy or
    band-limited recordings, whose range in this band is mostly noise)."""
    band = high[inner]
    floor = np.percentile(high, FLOOR_PERCENTILE)
    threshold = floor + max(FRICATION_RANGE * (np.percentile(band, LOUD_PERCENTILE) - floor), FRICATION_FLOOR)
    return np.clip((threshold - band) / SILENCE_SCALE, *SILENCE_CLIP)
