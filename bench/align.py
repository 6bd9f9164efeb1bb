"""Syllable-aligner accuracy and speed on the real Mandarin recordings in ../shared/bench/zh/.

For every set: the error of each syllable onset against the reference (median and 90th
percentile in ms, share within 20 / 50 / 100 ms) for `align_syllables` and for an
equal-split baseline over the same speaking parts, and the speed in times real time.

Speaking parts come from the reference itself: each run of syllables between two `sil`
intervals is one part, from the first syllable's start to the last one's end (short `sp`
pauses and Chao's unlabelled gaps stay inside the part). Because the first onset of a part
is then given, the table also reports the share within 50 ms over the inner onsets only,
the median signed error per initial class, and (independent of the aligner) where each
reference puts its onsets relative to two acoustic landmarks.
Biaobei is also run on the speaking parts that the project's segmenter
(sentences.find_speech_parts, automatic mode) finds, whose edges are looser, and a second
Chao run widens every part by up to 0.25 s of the surrounding silence, so that the first
onset has to be found too.

Issue 17 material, made from Biaobei with exact references (each half separately): the
recordings time-stretched to 0.8x and 1.25x speed and pitch-shifted by +-4 semitones with sox
(reference times divided by the tempo); paragraphs of PARAGRAPH consecutive recordings joined
with their own leading and trailing silence (the natural pauses) and aligned as one part; and
the whole analyser (`analyse.analyse`: segmenter, reconciling, aligner) run on each recording
and on each paragraph with the transcript's punctuation kept or removed. For every set the
confidence is scored as a detector of misses: of the onsets flagged below
analyse.LOW_CONFIDENCE, the share more than 50 ms off (precision), of those off, the share
flagged (recall), and their F1; with the median signed onset error (a constant lead or lag
against a reference's convention) and, for the analyser's sets, the number of stretches the
analyser timed again over loudness peaks (stretches.py).

The same held-out and tuning split of Biaobei's sentences read by espeak-ng (ESPEAK_VOICES: variants,
rates, pitches; `espeak_reading`) gives synthetic speech with exact references, espeak-ng's word
events; the project's sample story is scored against them the same way.

`python -m bench.align fit` fits the aligner's miss model (align.MISS_BIAS, MISS_WEIGHTS: the
confidence) on the aligner-alone tuning pool (with the espeak-ng readings, at the weight chosen there)
and prints the out-of-fold F1 of the low-confidence flag per threshold (folds of FOLD recordings),
from which analyse.LOW_CONFIDENCE is chosen.
"""

from __future__ import annotations

import csv
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import soundfile

from cartoonface.speech.align import FEATURES, align_details, align_syllables, initial_class, syllable_type
from cartoonface.speech.analyse import LOW_CONFIDENCE, analyse
from cartoonface.speech import textgrid
from cartoonface.speech.audio import Audio
from tests.espeak import Voice, synthesize
from tests.espeak import story as read_story
from samples.speech.make_speech import HERE as STORY
from cartoonface.speech.features import HOP, frames
from cartoonface.speech.sentences import Span, find_speech_parts
from cartoonface.speech.stretches import FALLBACK_NOTE
from cartoonface.speech.transcript import parse_transcript

ZH = Path(__file__).resolve().parents[1].parent / "shared" / "bench" / "zh"
TUNING = range(1, 36)     # Biaobei 000001-000035: the only sentences the aligner was tuned on
SILENCE = {"sil", "[SIL]"}
LOOSE = 0.25              # seconds of surrounding silence added to each part in the loose run
PARAGRAPH = 5             # Biaobei recordings joined into one unpunctuated paragraph
TEMPI = (0.8, 1.25)       # speed factors of the time-stretched copies (issue 17)
SEMITONES = (-4, 4)       # pitch shifts of the pitch-shifted copies (issue 17)
THRESHOLDS = (0.8, 0.83, 0.85, 0.87, 0.9)  # low-confidence thresholds scored on the pooled sets
FOLD = 5                  # recordings per cross-validation fold of the miss model (fit_confidence)
L2 = 1.0                  # weight of the miss model's squared weights (on standardised features)
MISS_LIMITS = np.round(np.arange(0.02, 0.4, 0.01), 2)  # P(miss) thresholds tried by cross-validation
ESPEAK_WEIGHTS = (0.0, 0.25, 0.5, 1.0)  # weights of an espeak-ng onset against a Biaobei one tried in the fit
# espeak-ng readings of the Biaobei transcripts (issue 17, fourth round): the plain voice, the sample
# story's own (variant f3 at 150 words a minute, samples/speech/make_speech.py) and two more voices,
# rates and pitches, so that no one voice's way of speaking reads as misses
ESPEAK_VOICES = (Voice(), Voice("f3", 150), Voice("m3", 210, 35), Voice("f2", 130, 70))
SOUND_FLOOR_DB = 50.0     # an espeak-ng reading ends at its last sample within this many dB of its peak
PUNCTUATION = re.compile(r"[^\w]|_")  # everything but letters and digits (Han characters are letters)


@dataclass(frozen=True)
class Part:
    """One speaking part: span in seconds, its syllables, the reference onset of each."""

    start: float
    end: float
    syllables: tuple[str, ...]
    onsets: tuple[float, ...]


@dataclass(frozen=True)
class Recording:
    """One recording, its reference speaking parts and its transcript as written ("" when none)."""

    name: str
    audio: Audio
    parts: tuple[Part, ...]
    text: str = ""


def read_tiers(path: Path) -> dict[str, list[tuple[float, float, str]]]:
    """Interval tiers of a Praat TextGrid file (speech/textgrid.py's reader): name -> [(xmin, xmax, text)]."""
    _, tiers = textgrid.read_tiers(path.read_text(encoding="utf-8"), str(path))
    return {name: [(i.start, i.end, i.text) for i in items] for name, items in tiers.items()}


def load_audio(path: Path) -> Audio:
    samples, rate = soundfile.read(path, dtype="float32", always_2d=True)
    return Audio(samples=samples.mean(axis=1), rate=rate, source=str(path))


def parts_from_intervals(intervals: list[tuple[float, float, str | None]]) -> tuple[Part, ...]:
    """Speaking parts from (xmin, xmax, pinyin or None for a gap) runs between silences (None text = sil)."""
    parts: list[Part] = []
    run: list[tuple[float, float, str | None]] = []
    for xmin, xmax, label in intervals + [(0.0, 0.0, "sil")]:
        if label in SILENCE:
            syll = [(a, b, s) for a, b, s in run if s]
            if syll:
                parts.append(Part(syll[0][0], syll[-1][1], tuple(s for _, _, s in syll), tuple(a for a, _, _ in syll)))
            run = []
        else:
            run.append((xmin, xmax, label))
    return tuple(parts)


def biaobei() -> list[Recording]:
    table = {row["id"]: row["hanzi_meta"]
             for row in csv.DictReader((ZH / "biaobei" / "transcripts.tsv").open(encoding="utf-8"), delimiter="\t")}
    out = []
    for grid in sorted((ZH / "biaobei" / "TextGrid").glob("*.TextGrid")):
        tier = read_tiers(grid)["syllables_pinyin"]
        rows = [(a, b, None if t == "sp" else t) for a, b, t in tier]
        out.append(Recording(grid.stem, load_audio(ZH / "biaobei" / "wav" / f"{grid.stem}.wav"), parts_from_intervals(rows),
                             table.get(grid.stem, "")))
    return out


def sox_copy(recording: Recording, effect: list[str], tempo: float) -> Recording:
    """The recording passed through sox `effect` (e.g. ["tempo", "-s", "0.8"]), its reference
    times divided by `tempo` (the speed factor; 1 for a pitch shift, which keeps the length)."""
    with tempfile.TemporaryDirectory() as folder:
        source, target = Path(folder) / "in.wav", Path(folder) / "out.wav"
        soundfile.write(source, recording.audio.samples, recording.audio.rate, subtype="FLOAT")
        subprocess.run(["sox", str(source), str(target), *effect], check=True, capture_output=True)
        audio = load_audio(target)
    parts = tuple(Part(p.start / tempo, p.end / tempo, p.syllables, tuple(o / tempo for o in p.onsets))
                  for p in recording.parts)
    return Recording(recording.name, Audio(audio.samples, audio.rate, recording.name), parts, recording.text)


def stretched(recordings: list[Recording], tempo: float) -> list[Recording]:
    """Time-stretched copies (sox tempo, speech mode): `tempo` times the speed, same pitch."""
    return [sox_copy(r, ["tempo", "-s", f"{tempo}"], tempo) for r in recordings]


def pitched(recordings: list[Recording], semitones: int) -> list[Recording]:
    """Pitch-shifted copies (sox pitch), same timing."""
    return [sox_copy(r, ["pitch", f"{100 * semitones}"], 1.0) for r in recordings]


def transcribed(recordings: list[Recording]) -> list[Recording]:
    """The recordings whose transcript reads as many syllables as their reference has (the
    analyser's onsets are compared with the reference's one by one; erhua written as a
    separate 儿 syllable in the reference is one syllable in ours)."""
    return [r for r in recordings
            if sum(len(s.syllables) for s in parse_transcript(r.text)) == sum(len(p.syllables) for p in r.parts)]


def paragraphs(recordings: list[Recording], size: int = PARAGRAPH) -> list[Recording]:
    """Runs of `size` consecutive recordings joined end to end with their own leading and
    trailing silence (the natural pauses between sentences), each run one speaking part from
    its first syllable onset to its last syllable end, its text the transcripts joined."""
    out = []
    for k in range(0, len(recordings) - size + 1, size):
        run = recordings[k:k + size]
        offset, end = 0.0, 0.0
        samples: list[np.ndarray] = []
        syllables: list[str] = []
        onsets: list[float] = []
        for r in run:
            samples.append(r.audio.samples)
            for p in r.parts:
                syllables += p.syllables
                onsets += [offset + o for o in p.onsets]
            end = offset + r.parts[-1].end
            offset += r.audio.samples.size / r.audio.rate
        audio = Audio(np.concatenate(samples), run[0].audio.rate, f"{run[0].name}-{run[-1].name}")
        part = Part(onsets[0], end, tuple(syllables), tuple(onsets))
        out.append(Recording(audio.source, audio, (part,), "".join(r.text for r in run)))
    return out


def sound_end(samples: np.ndarray) -> int:
    """(n,) samples -> index after the last one within SOUND_FLOOR_DB of the loudest."""
    loud = np.abs(samples) >= np.abs(samples).max() * 10 ** (-SOUND_FLOOR_DB / 20)
    return int(np.nonzero(loud)[0][-1]) + 1


def espeak_reading(recording: Recording, voice: Voice) -> Recording | None:
    """The recording's transcript read by espeak-ng in `voice`: the pinyin our transcript parser
    gives it, a comma after each clause and a full stop after each sentence (espeak-ng's own pauses
    there), as one speaking part from the first onset to the end of the sound, espeak-ng's word
    events the reference onsets; None when espeak-ng is missing or reads another syllable count.
    Named after the recording, so it falls in the same cross-validation fold."""
    sentences = parse_transcript(recording.text)
    tokens = [s.pinyin + ("." if k == len(sentence.syllables) - 1 else "," if k in sentence.clause_ends else "")
              for sentence in sentences for k, s in enumerate(sentence.syllables)]
    spoken = synthesize(tokens, voice) if tokens else None
    if spoken is None:
        return None
    syllables = tuple(t.rstrip(".,") for t in tokens)
    part = Part(spoken.onsets[0], sound_end(spoken.samples) / spoken.rate, syllables, spoken.onsets)
    name = f"{recording.name}-espeak-{voice.variant or 'plain'}"
    return Recording(name, Audio(spoken.samples, spoken.rate, name), (part,), recording.text)


def espeak_readings(recordings: list[Recording], voice: Voice) -> list[Recording]:
    """`espeak_reading` of each recording with a transcript, those espeak-ng could read."""
    readings = (espeak_reading(r, voice) for r in recordings if r.text)
    return [r for r in readings if r is not None]


def story() -> Recording:
    """The project's sample samples/speech/story.wav with the onsets of espeak-ng's word events,
    read again as make_speech.py made it (the same samples, checked), as one part."""
    text = (STORY / "story.txt").read_text(encoding="utf-8")
    audio = load_audio(STORY / "story.wav")
    spoken = read_story()
    if spoken is None or not np.array_equal(spoken.samples, audio.samples[:spoken.samples.size]):
        raise RuntimeError("espeak-ng does not read story.txt as samples/speech/story.wav")
    syllables = tuple(s.pinyin for sentence in parse_transcript(text) for s in sentence.syllables)
    part = Part(spoken.onsets[0], sound_end(audio.samples) / audio.rate, syllables, spoken.onsets)
    return Recording("story", audio, (part,), text)


def aishell3() -> list[Recording]:
    """SSB00050015 by its character tier, SSB16240001 by its phone tier (syllable = its phones)."""
    folder = ZH / "aishell3_charsiu"
    table = {row["wav"]: row for row in csv.DictReader((folder / "transcripts.tsv").open(encoding="utf-8"), delimiter="\t")}
    out = []
    for wav, row in table.items():
        tiers = read_tiers(folder / wav.replace("_16k.wav", ".TextGrid"))
        pinyin = row["pinyin"].split()
        if "words" in tiers:
            words = [t for t in tiers["words"] if t[2] not in SILENCE]
            rows = [(a, b, p) for (a, b, _), p in zip(words, pinyin)]
        else:
            phones = [t for t in tiers["phones"] if t[2] not in SILENCE]
            rows, k = [], 0
            for p, spelled in zip(pinyin, row["phone_tier_syllables"].split()):
                n = len(spelled.split("+"))
                rows.append((phones[k][0], phones[k + n - 1][1], p))
                k += n
        first, last = rows[0][0], rows[-1][1]
        intervals = [(0.0, first, "sil"), *rows, (last, last, "sil")]
        out.append(Recording(wav, load_audio(folder / wav), parts_from_intervals(intervals)))
    return out


def chao(loose: bool) -> list[Recording]:
    folder = ZH / "chao1922_tone_change"
    tier = read_tiers(folder / "chao1922_tone_paradigm.TextGrid")["hehe"]
    rows = [(a, b, t if t else None) for a, b, t in tier]
    parts = parts_from_intervals(rows)
    if loose:
        silences = [(a, b) for a, b, t in tier if t == "sil"]
        widened = []
        for p in parts:
            before = max((b - a for a, b in silences if abs(b - p.start) < 1e-6), default=0.0)
            after = max((b - a for a, b in silences if abs(a - p.end) < 1e-6), default=0.0)
            widened.append(Part(p.start - min(LOOSE, before / 2), p.end + min(LOOSE, after / 2), p.syllables, p.onsets))
        parts = tuple(widened)
    return [Recording("chao1922", load_audio(folder / "chao1922_tone_paradigm.wav"), parts)]


def segmenter_parts(recording: Recording) -> Recording:
    """The same recording and reference syllables, cut into the speaking parts that
    cartoonface.speech.sentences.find_speech_parts finds (automatic mode); each syllable goes
    to the part nearest its reference middle."""
    spans = find_speech_parts(recording.audio)
    syllables = [(o, s) for part in recording.parts for o, s in zip(part.onsets, part.syllables)]
    ends = [o for part in recording.parts for o in (*part.onsets[1:], part.end)]
    groups: list[list[tuple[float, str]]] = [[] for _ in spans]
    for (onset, pinyin), end in zip(syllables, ends):
        middle = (onset + end) / 2
        nearest = min(range(len(spans)), key=lambda k: max(spans[k].start - middle, middle - spans[k].end, 0.0))
        groups[nearest].append((onset, pinyin))
    parts = tuple(Part(span.start, span.end, tuple(p for _, p in g), tuple(o for o, _ in g))
                  for span, g in zip(spans, groups) if g)
    return Recording(recording.name, recording.audio, parts)


def _warp(cost: np.ndarray) -> np.ndarray:
    """(T, S) frame distances -> (T,) template frame matched to each real frame: DTW with
    steps (1, 0), (1, 1), (1, 2) from (0, 0) to (T - 1, S - 1)."""
    rows, cols = cost.shape
    total = np.full((rows, cols), np.inf)
    total[0, 0] = cost[0, 0]
    step = np.zeros((rows, cols), dtype=np.int8)
    columns = np.arange(cols)
    for i in range(1, rows):
        prev = total[i - 1]
        options = np.stack([prev, np.r_[np.inf, prev[:-1]], np.r_[np.inf, np.inf, prev[:-2]]])
        step[i] = options.argmin(axis=0)
        total[i] = cost[i] + options[step[i], columns]
    path, j = np.zeros(rows, dtype=int), cols - 1
    for i in range(rows - 1, -1, -1):
        path[i] = j
        j = max(j - int(step[i, j]), 0)
    return path


def espeak_dtw(audio: Audio, part: Part) -> np.ndarray:
    """Approach (b) of the issue, for comparison: espeak-ng speaks the part's syllables, its
    cepstra (c1-c12, mean/variance normalised, linearly stretched to the part's length) are
    warped onto the part's by DTW and the synthetic syllable onsets mapped through the path.
    Falls back to the equal split when espeak-ng does not read the syllables one by one."""
    synth = synthesize(part.syllables)
    if synth is None:
        return equal_split(part)
    loud = np.flatnonzero(np.abs(synth.samples) > 0.02 * np.abs(synth.samples).max())
    template = frames(synth.samples[:loud[-1] + 1], synth.rate).mfcc[:, 1:]
    real = frames(audio.samples[int(part.start * audio.rate):int(part.end * audio.rate)], audio.rate).mfcc[:, 1:]
    stretch = (len(template) - 1) / max(len(real) - 1, 1)
    template = template[np.round(np.arange(len(real)) * stretch).astype(int)]
    a, b = ((x - x.mean(axis=0)) / (x.std(axis=0) + 1e-6) for x in (real, template))
    path = _warp(((a[:, None, :] - b[None, :, :]) ** 2).sum(axis=2))
    return part.start + HOP * np.searchsorted(path, np.array(synth.onsets) / HOP / stretch)


def equal_split(part: Part) -> np.ndarray:
    """Baseline onsets: the part cut into syllables of equal length."""
    n = len(part.syllables)
    return part.start + (part.end - part.start) * np.arange(n) / n


@dataclass(frozen=True, eq=False)
class Result:
    """Per onset (N,): absolute `errors` of the aligner, of the equal-split `base` and of
    espeak+DTW `dtw` (empty when not run), in s rounded to 1 us (references and onsets on a
    10 ms grid give errors of exactly 50 ms that float arithmetic would put either side of
    the limit); `inner` mask (not the first onset of a part); `signed` aligner errors (s);
    initial `classes`; aligner `confidence`. Aligner CPU `seconds`, `speech` seconds; `fallbacks`:
    stretches the analyser timed again over loudness peaks (0 for the aligner alone)."""

    errors: np.ndarray
    base: np.ndarray
    dtw: np.ndarray
    inner: np.ndarray
    signed: np.ndarray
    classes: np.ndarray
    seconds: float
    speech: float
    confidence: np.ndarray
    fallbacks: int = 0


def evaluate(recordings: list[Recording], with_dtw: bool = False) -> Result:
    """Onset errors of the aligner, the baseline and (`with_dtw`) espeak+DTW over every part."""
    signed: list[float] = []
    classes: list[str] = []
    base: list[float] = []
    warped: list[float] = []
    inner: list[bool] = []
    confidence: list[float] = []
    seconds = speech = 0.0
    for rec in recordings:
        for part in rec.parts:
            started = time.process_time()
            timings = align_syllables(rec.audio, Span(part.start, part.end), part.syllables)
            seconds += time.process_time() - started
            speech += part.end - part.start
            reference = np.array(part.onsets)
            signed.extend(np.array([t.start for t in timings]) - reference)
            classes.extend(initial_class(syllable_type(p).initial) for p in part.syllables)
            base.extend(np.abs(equal_split(part) - reference))
            if with_dtw:
                warped.extend(np.abs(espeak_dtw(rec.audio, part) - reference))
            inner.extend([False] + [True] * (len(part.onsets) - 1))
            confidence.extend(t.confidence for t in timings)
    def rounded(x: list[float] | np.ndarray) -> np.ndarray:
        return np.round(np.array(x), 6)
    return Result(rounded(np.abs(signed)), rounded(base), rounded(warped), np.array(inner), np.array(signed),
                  np.array(classes), seconds, speech, np.array(confidence))


def evaluate_pipeline(recordings: list[Recording], unpunctuated: bool) -> Result:
    """Onset errors of `analyse` (automatic segmentation) on each whole recording against its
    reference parts, the transcript without punctuation when `unpunctuated`. Equal split over
    the reference parts as the baseline; `inner` marks onsets not first in a reference part."""
    signed: list[float] = []
    classes: list[str] = []
    base: list[float] = []
    inner: list[bool] = []
    confidence: list[float] = []
    seconds = speech = 0.0
    fallbacks = 0
    for rec in recordings:
        text = PUNCTUATION.sub("", rec.text) if unpunctuated else rec.text
        started = time.process_time()
        alignment = analyse(rec.audio, text)
        elapsed = time.process_time() - started
        fallbacks += sum(FALLBACK_NOTE in note for note in alignment.notes)
        timed = [s for sentence in alignment.sentences for s in sentence.syllables]
        reference = np.array([o for p in rec.parts for o in p.onsets])
        if len(timed) != reference.size:
            raise ValueError(f"{rec.name}: the transcript gives {len(timed)} syllables, the reference {reference.size}")
        seconds += elapsed
        speech += sum(p.end - p.start for p in rec.parts)
        signed.extend(np.array([s.start for s in timed]) - reference)
        classes.extend(initial_class(syllable_type(p).initial) for part in rec.parts for p in part.syllables)
        for part in rec.parts:
            base.extend(np.abs(equal_split(part) - np.array(part.onsets)))
            inner.extend([False] + [True] * (len(part.onsets) - 1))
        confidence.extend(s.confidence for s in timed)
    rounded = np.round(np.array(signed), 6)
    return Result(np.abs(rounded), np.round(np.array(base), 6), np.array([]), np.array(inner, dtype=bool),
                  np.array(signed), np.array(classes), seconds, speech, np.array(confidence), fallbacks)


def flag_scores(errors: np.ndarray, confidence: np.ndarray,
                threshold: float = LOW_CONFIDENCE) -> tuple[int, int, float, float, float]:
    """(N,) onset errors (s) and confidences -> (flagged, misses, precision, recall, F1) of
    'confidence below `threshold`' as a detector of onsets more than 50 ms off (precision nan
    when nothing is flagged, recall nan when nothing is off; F1 0 when there are no hits)."""
    flagged, miss = confidence < threshold, errors > 0.05
    hits = int(np.sum(flagged & miss))
    precision = hits / flagged.sum() if flagged.any() else float("nan")
    recall = hits / miss.sum() if miss.any() else float("nan")
    f1 = 2 * hits / (flagged.sum() + miss.sum()) if hits else 0.0
    return int(flagged.sum()), int(miss.sum()), precision, recall, f1


def onset_table(recordings: list[Recording]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The aligner over every reference part -> (N, len(FEATURES)) align.onset_features, (N,) onset
    errors in s (rounded as in `Result`), (N,) fold of each onset (its recording's number // FOLD); onsets
    of duration-prior splits left out."""
    rows, errors, folds = [], [], []
    for rec in recordings:
        for part in rec.parts:
            timings, features = align_details(rec.audio, Span(part.start, part.end), part.syllables)
            error = np.round(np.abs(np.array([t.start for t in timings]) - np.array(part.onsets)), 6)
            rows.append(features)
            errors.append(error)
            folds.append(np.full(len(timings), int(rec.name.split("-")[0]) // FOLD))
    table, error, fold = np.concatenate(rows), np.concatenate(errors), np.concatenate(folds)
    known = ~np.isnan(table).any(axis=1)
    return table[known], error[known], fold[known]


def fit_logistic(table: np.ndarray, miss: np.ndarray, weight: np.ndarray | None = None,
                 l2: float = L2) -> tuple[float, np.ndarray]:
    """(N, F) features, (N,) bool misses, (N,) weight of each onset (None: all 1) -> (bias, (F,)
    weights) of P(miss) = logistic(bias + features . weights), weighted maximum likelihood with l2
    times the squared weights of the standardised features subtracted (Newton's method)."""
    weight = np.ones(len(table)) if weight is None else weight
    mean, scale = table.mean(axis=0), table.std(axis=0) + 1e-9
    design = np.c_[np.ones(len(table)), (table - mean) / scale]
    ridge = l2 * np.diag(np.r_[0.0, np.ones(table.shape[1])])
    w = np.zeros(design.shape[1])
    for _ in range(50):
        p = 1.0 / (1.0 + np.exp(-design @ w))
        hessian = (design * (weight * p * (1 - p))[:, None]).T @ design + ridge
        w -= np.linalg.solve(hessian, design.T @ (weight * (p - miss)) + ridge @ w)
    weights = w[1:] / scale
    return float(w[0] - weights @ mean), weights


def out_of_fold(table: np.ndarray, miss: np.ndarray, fold: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """(N,) P(miss) of each onset by the miss model fitted on the other folds (`fit_logistic`)."""
    held = np.zeros(miss.size)
    for k in np.unique(fold):
        bias, weights = fit_logistic(table[fold != k], miss[fold != k], weight[fold != k])
        held[fold == k] = 1.0 / (1.0 + np.exp(-(bias + table[fold == k] @ weights)))
    return held


def fit_confidence() -> None:
    """Fit the miss model (align.MISS_BIAS, MISS_WEIGHTS) on the aligner-alone tuning pool (Biaobei's
    copies and the espeak-ng readings of the same sentences) and choose by cross-validation on it the
    weight of an espeak-ng onset (ESPEAK_WEIGHTS) and the low-confidence threshold: print the
    out-of-fold F1 per weight (over all onsets, Biaobei's and espeak-ng's), the coefficients, the F1 per P(miss) threshold at the
    chosen weight and the best threshold as a confidence threshold."""
    tuning = [r for r in biaobei() if int(r.name) in TUNING]
    sets = [tuning, *(stretched(tuning, t) for t in TEMPI), *(pitched(tuning, s) for s in SEMITONES), paragraphs(tuning)]
    voices = [espeak_readings(tuning, voice) for voice in ESPEAK_VOICES]
    tables = [onset_table(s) for s in sets + voices]
    table, error, fold = (np.concatenate([t[k] for t in tables]) for k in range(3))
    espeak = np.concatenate([np.full(t[1].size, k >= len(sets)) for k, t in enumerate(tables)])
    miss = error > 0.05
    print(f"tuning pool: {miss[~espeak].sum()} of {(~espeak).sum()} Biaobei onsets and {miss[espeak].sum()} of "
          f"{espeak.sum()} espeak-ng onsets off by > 50 ms")
    best_f1, chosen, best, chosen_scores = -1.0, 0.0, 0.0, [0.0]
    for share in ESPEAK_WEIGHTS:
        weight = np.where(espeak, share, 1.0)
        held = out_of_fold(table, miss, fold, weight)
        scores = [flag_scores(error, 1.0 - held, 1.0 - limit)[4] for limit in MISS_LIMITS]
        limit = MISS_LIMITS[int(np.argmax(scores))]
        parts = {"Biaobei": ~espeak, "espeak-ng": espeak}
        print(f"espeak-ng weight {share:g}: out-of-fold F1 {100 * max(scores):.1f}% at P(miss) {limit:g} ("
              + ", ".join(f"{name} {100 * flag_scores(error[m], 1.0 - held[m], 1.0 - limit)[4]:.1f}%"
                          for name, m in parts.items()) + ")")
        if max(scores) > best_f1:
            best_f1, chosen, best, chosen_scores = max(scores), share, limit, scores
    bias, weights = fit_logistic(table, miss, np.where(espeak, chosen, 1.0))
    print(f"chosen espeak-ng weight {chosen:g}")
    print("MISS_BIAS =", round(bias, 3), "MISS_WEIGHTS =", {n: round(float(w), 3) for n, w in zip(FEATURES, weights)})
    print("out-of-fold F1 per P(miss) threshold: "
          + " ".join(f"{t:g}: {100 * f:.1f}" for t, f in zip(MISS_LIMITS, chosen_scores)))
    print(f"best: P(miss) >= {best:g}, i.e. confidence below {1 - best:g}")


def by_class(result: Result) -> str:
    """Per initial class over the inner onsets: count, median signed error (ms; positive = the
    aligner's onset is later than the reference) and share within 50 ms."""
    cells = []
    for name in ("closure", "aspirated", "frication", "sonorant", "glide", "none"):
        mask = (result.classes == name) & result.inner
        if mask.any():
            cells.append(f"{name} n={mask.sum()} {1000 * np.median(result.signed[mask]):+.0f} ms "
                         f"{100 * np.mean(result.errors[mask] <= 0.05):.0f}%")
    return "  by initial (inner onsets: n, median signed error, within 50 ms): " + ", ".join(cells)


def landmarks(recordings: list[Recording]) -> str:
    """Where each reference sets inner onsets, per initial class: median ms from the steepest
    100-1000 Hz fall (closure / frication start, end of the vowel before) and from the steepest
    3-8 kHz rise (burst or frication) within 80 ms of the reference onset to that onset
    (positive: the reference onset comes later). Independent of the aligner."""
    offsets: dict[str, list[tuple[float, float]]] = {}
    for rec in recordings:
        feats = frames(rec.audio.samples, rec.audio.rate)
        low, high = (np.pad(np.convolve(x, np.ones(3) / 3, mode="same"), 2, mode="edge") for x in (feats.low, feats.high))
        fall, rise = low[:-4] - low[4:], high[4:] - high[:-4]
        for part in rec.parts:
            for onset, pinyin in list(zip(part.onsets, part.syllables))[1:]:
                k = int(round((onset - 0.0125) / HOP))
                near = np.arange(k - 8, k + 9)
                if near[0] < 0 or near[-1] >= fall.size:
                    continue
                offsets.setdefault(initial_class(syllable_type(pinyin).initial), []).append(
                    (HOP * (k - near[np.argmax(fall[near])]), HOP * (k - near[np.argmax(rise[near])])))
    cells = [f"{name} n={len(v)} {1000 * np.median([a for a, _ in v]):+.0f} / {1000 * np.median([b for _, b in v]):+.0f}"
             for name, v in offsets.items()]
    return "  reference onset after the steepest low-band fall / high-band rise (median ms): " + ", ".join(sorted(cells))


def row(label: str, errors: np.ndarray, inner: np.ndarray) -> str:
    ms = errors * 1000
    within = [100 * np.mean(ms <= limit) for limit in (20, 50, 100)]
    inner50 = 100 * np.mean(ms[inner] <= 50) if inner.any() else float("nan")
    return (f"  {label:<12} n={len(ms):4d}  median {np.median(ms):6.1f} ms  p90 {np.percentile(ms, 90):6.1f} ms"
            f"  within 20/50/100 ms {within[0]:5.1f}% {within[1]:5.1f}% {within[2]:5.1f}%  inner@50 {inner50:5.1f}%")


def report(name: str, recordings: list[Recording], with_dtw: bool = False, with_landmarks: bool = False,
           unpunctuated: bool | None = None) -> Result:
    """Print the figures of one set (module docstring) and return its Result: the aligner's over
    the reference parts, or with `unpunctuated` given the whole analyser's on each recording with
    its transcript's punctuation removed (True) or kept (False) (recordings whose transcript gives
    another syllable count than the reference are to be left out first: see `transcribed`)."""
    result = evaluate(recordings, with_dtw) if unpunctuated is None else evaluate_pipeline(recordings, unpunctuated)
    print(f"{name}: {sum(len(r.parts) for r in recordings)} parts, {result.speech:.1f} s of speech, "
          f"aligner {result.speech / max(result.seconds, 1e-9):.0f}x real time (CPU time)")
    print(row("aligner", result.errors, result.inner))
    print(row("equal split", result.base, result.inner))
    if with_dtw:
        print(row("espeak+DTW", result.dtw, result.inner))
    print(by_class(result))
    if with_landmarks:
        print(landmarks(recordings))
    bad = result.errors > 0.05
    conf = result.confidence
    if bad.any() and (~bad).any():
        print(f"  mean confidence: onsets within 50 ms {conf[~bad].mean():.2f}, beyond {conf[bad].mean():.2f}")
    flagged, misses, precision, recall, f1 = flag_scores(result.errors, conf)
    print(f"  low confidence (< {LOW_CONFIDENCE}) as a miss detector: {flagged} flagged, {misses} off by > 50 ms,"
          f" precision {100 * precision:.1f}%, recall {100 * recall:.1f}%, F1 {100 * f1:.1f}%")
    print(f"  median signed onset error (positive: later than the reference): all {1000 * np.median(result.signed):+.1f} ms,"
          f" inner {1000 * np.median(result.signed[result.inner]):+.1f} ms")
    if unpunctuated is not None:
        print(f"  stretches timed again over loudness peaks: {result.fallbacks}")
    return result


def pooled_flags(label: str, results: list[Result]) -> None:
    """Print precision / recall / F1 of the low-confidence flag at THRESHOLDS over the onsets of
    `results` pooled (the threshold is chosen on the tuning half's pool), and how well the
    confidence ranks the misses whatever the threshold: average precision (mean over the misses
    of the precision of flagging every onset as unsure as that miss) and AUC (the chance that a
    miss has a lower confidence than a hit)."""
    errors = np.concatenate([r.errors for r in results])
    confidence = np.concatenate([r.confidence for r in results])
    miss = errors > 0.05
    order = np.argsort(confidence, kind="stable")
    precision_at = np.cumsum(miss[order]) / np.arange(1, errors.size + 1)
    average_precision = float(np.mean(precision_at[miss[order]]))
    auc = float(np.mean(confidence[miss][:, None] < confidence[~miss][None, :]))
    print(f"{label}, pooled: confidence ranks the misses with average precision {100 * average_precision:.1f}%, "
          f"AUC {100 * auc:.1f}%")
    cells = []
    for threshold in THRESHOLDS:
        flagged, _, precision, recall, f1 = flag_scores(errors, confidence, threshold)
        cells.append(f"{threshold:g}: {flagged} flagged, P {100 * precision:.1f} R {100 * recall:.1f} F1 {100 * f1:.1f}")
    print(f"{label}, pooled ({int(np.sum(errors > 0.05))} of {errors.size} onsets off by > 50 ms), "
          f"low-confidence flag at " + "; ".join(cells))


def main() -> None:
    records = biaobei()
    tuning = [r for r in records if int(r.name) in TUNING]
    held_out = [r for r in records if int(r.name) not in TUNING]
    plain = {"tuning": report("Biaobei tuning 000001-000035", tuning, with_dtw=True, with_landmarks=True),
             "held-out": report("Biaobei held-out 000036-000070", held_out, with_dtw=True, with_landmarks=True)}
    report("Biaobei tuning, segmenter parts", [segmenter_parts(r) for r in tuning])
    report("Biaobei held-out, segmenter parts", [segmenter_parts(r) for r in held_out])
    report("AISHELL-3 (2 speakers)", aishell3(), with_dtw=True, with_landmarks=True)
    report("Chao 1922, reference parts", chao(loose=False), with_landmarks=True)
    report(f"Chao 1922, parts widened by <= {LOOSE} s", chao(loose=True))
    for label, half in (("tuning", tuning), ("held-out", held_out)):
        pool = [plain[label]]
        for tempo in TEMPI:
            pool.append(report(f"Biaobei {label}, tempo {tempo}x (sox tempo)", stretched(half, tempo)))
        for semitones in SEMITONES:
            pool.append(report(f"Biaobei {label}, pitch {semitones:+d} semitones (sox pitch)", pitched(half, semitones)))
        pool.append(report(f"Biaobei {label}, paragraphs of {PARAGRAPH} recordings as one part", paragraphs(half)))
        readable = transcribed(half)
        for mode in ("kept", "removed"):
            report(f"Biaobei {label}, analyse, punctuation {mode}", readable, unpunctuated=mode == "removed")
        pool.append(report(f"Biaobei {label}, paragraphs of {PARAGRAPH}, analyse, punctuation removed",
                           paragraphs(readable), unpunctuated=True))
        pooled_flags(f"Biaobei {label}: plain, tempi, pitches, paragraphs, analysed paragraphs", pool)
        voices = [espeak_readings(half, voice) for voice in ESPEAK_VOICES]
        spoken = [report(f"espeak-ng {label}, voice {voice}", readings) for voice, readings in zip(ESPEAK_VOICES, voices)]
        spoken.append(report(f"espeak-ng {label}, the {len(voices)} voices, analyse", [r for v in voices for r in v],
                             unpunctuated=False))
        pooled_flags(f"espeak-ng {label}: {len(voices)} voices aligned alone, analysed", spoken)
    report("The sample story (samples/speech/story.wav), analyse", [story()], unpunctuated=False)


if __name__ == "__main__":
    fit_confidence() if sys.argv[1:] == ["fit"] else main()
