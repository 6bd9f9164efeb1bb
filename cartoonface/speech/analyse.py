"""When each sentence and syllable of a transcript is spoken: the speech analyser (thesis 002, ch. 3).

`analyse` runs the whole of figure 3.1: split the recording into speaking
parts by silence (Alg. 3.1, `sentences.py`), parse the transcript into
sentences and syllables (`transcript.py`), reconcile the two when the number
of speaking parts differs from the number of sentences, then time the
syllables inside each sentence's stretch of audio (`align.py`, section 3.3)
and put them on one timeline.

Reconciling is in `reconcile.py`; the records made here are in `records.py`. Sentences that
end up sharing a speaking part are then aligned together, so the boundary
between them is the aligner's syllable boundary, not the dip. What was
merged or split is said in `Alignment.notes`. docs/alignment.md has the
details.
"""

from __future__ import annotations

import math
import re
from dataclasses import replace
from functools import partial
from collections.abc import Callable, Sequence
from concurrent.futures import Executor

import numpy as np

from cartoonface.errors import TranscriptError
from cartoonface.speech.align import MARGIN, align_syllables
from cartoonface.speech.audio import Audio
from cartoonface.speech.audio_only import analyse_audio
from cartoonface.speech.english import analyse_english, detect_language
from cartoonface.speech.features import HOP
from cartoonface.speech.lexicon import longest_words
from cartoonface.speech.readings import to_simplified
from cartoonface.speech.reconcile import reconcile
from cartoonface.speech.records import Alignment, Sentence, Syllable
from cartoonface.speech.sentences import Span, find_speech_parts, high_passed
from cartoonface.speech.stretches import FALLBACK_CONFIDENCE, FALLBACK_NOTE, spread_over_peaks, stretches, unfit
from cartoonface.speech.transcript import HAN_RE, SentenceText, parse_transcript
from cartoonface.workers import from_both_ends

# Mandarin is read at about 3-7 syllables per second of speech. More than MAX_RATE means the transcript
# is far longer than the recording (an error); more than FAST_RATE or fewer than MIN_RATE is aligned
# but flagged.
MAX_RATE = 12.0
FAST_RATE = 8.0
MIN_RATE = 1.0
# Syllables below this confidence (align.within_probability: the miss model's probability of the onset
# lying within 50 ms) are reported as low-confidence: the threshold of best out-of-fold F1 for "more
# than 50 ms off" over the aligner-alone tuning pool (Biaobei 000001-000035, its tempo, pitch and
# paragraph copies, espeak-ng readings of the same sentences at weight 0.5; 7 folds of 5 sentences):
# `.venv/bin/python -m bench.align fit`, F1 37.9 / 36.6 / 37.2 / 39.5 / 38.5 % at P(miss) 0.12 / 0.13 /
# 0.14 / 0.15 / 0.16 (docs/BENCHMARKS.md).
LOW_CONFIDENCE = 0.85
# Sentences sharing a speaking part are aligned in one call up to this many seconds (the aligner's
# cost grows with length times syllables); longer runs are aligned sentence by sentence at the cuts.
MAX_JOINT = 60.0
# Longer sentences are aligned in pieces of at most this many syllables (about 15 s of speech),
# cut at commas where possible: one alignment call over minutes of speech would take minutes.
MAX_PIECE = 60
# Share of the "segment" stage done when the transcript is read: its first reading loads the lexicon
# and OpenCC's tables, on the 25 s sample story about as long as the segmentation itself (the job's
# page then moves between the two: tests/test_web_progress.py).
READ_SHARE = 0.4


def analyse(
    audio: Audio,
    transcript_text: str | None,
    pause: tuple[float, float] | None = None,
    progress: Callable[[str, float], None] | None = None,
    source: str = "transcript",
    language: str | None = None,
    pool: Executor | None = None,
) -> Alignment:
    """Time every sentence and syllable of `transcript_text` in `audio`.

    `language` "zh" or "en" (english.LANGUAGES); None finds it from the transcript's script
    (english.detect_language). English is aligned by english.analyse_english.

    `pause` = (start, end) seconds of the first pause selects the thesis's
    segmentation mode (Alg. 3.1); None the automatic one. `progress(stage,
    fraction)` is called with stage "segment" then "align" and the fraction
    0..1 done of that stage. `source` names the transcript in messages.
    `transcript_text` None (no transcript): the lip sync from the audio alone (audio_only.py).
    `pool`: a one-process pool (workers.helper_pool) that aligns parts meanwhile, as many as it gets to.
    Raises TranscriptError for an empty transcript, one in another language
    (more Latin words than Chinese characters), one with no Mandarin
    syllables (from parse_transcript), or one far longer than the speech
    (over MAX_RATE syllables per second); OptionError for a pause outside
    the recording.
    """
    if transcript_text is None:
        return analyse_audio(audio, pause, progress)
    if (language or detect_language(transcript_text)) == "en":
        return analyse_english(audio, transcript_text, pause, progress, source)
    report = progress or (lambda stage, fraction: None)
    if not transcript_text.strip():
        raise TranscriptError(f"{source}: the transcript is empty; expected the text spoken in the recording")
    _check_language(transcript_text, source)
    notes: list[str] = []
    report("segment", 0.0)
    spoken = parse_transcript(transcript_text, source)  # every sentence has syllables
    for sentence in spoken:
        notes += sentence.notes
    report("segment", READ_SHARE)
    filtered = high_passed(audio)  # the energy of the segmentation and of the reconciling's dips
    parts = find_speech_parts(audio, pause, filtered)
    if not parts:
        parts = (Span(0.0, round(audio.duration, 3)),)
        notes.append("no speaking part told apart from noise: the whole recording is taken as speech")
    report("segment", 1.0)
    pieces, owners = sentence_pieces(spoken)
    counts = [len(piece.syllables) for piece in pieces]
    _check_rate(sum(counts), sum(part.duration for part in parts), source, notes)
    spans = reconcile(audio, parts, counts, filtered)
    jobs: list[tuple[list[SentenceText], Span]] = []
    for block in _blocks(spans, owners):
        span = Span(spans[block[0]].start, spans[block[-1]].end)
        if len(block) > 1 and span.duration <= MAX_JOINT:
            # Sentences sharing a speaking part are aligned together: the boundary between them
            # is where the aligner puts it, not the dip the reconciling chose.
            jobs.append(([pieces[k] for k in block], span))
        else:
            jobs += [([pieces[k]], spans[k]) for k in block]
    aligned = [timed for job in _align_jobs(audio, jobs, pool, report) for timed in job]
    report("align", 1.0)
    sentences = []
    for number, sentence in enumerate(spoken):
        syllables = tuple(s for (piece, _), owner in zip(aligned, owners) if owner == number for s in piece.syllables)
        sentences.append(Sentence(sentence.text, syllables[0].start, syllables[-1].end, syllables))
    notes += _merge_notes(sentences, parts) + _split_notes([piece for piece, _ in aligned], owners, spans, parts)
    posteriors = [p for number in range(len(spoken)) for (_, piece), owner in zip(aligned, owners) if owner == number
                  for p in piece]
    sentences, fallback_notes = _fall_back(audio, sentences, posteriors)
    notes += fallback_notes
    low = [s for sentence in sentences for s in sentence.syllables if s.confidence < LOW_CONFIDENCE]
    if low:
        notes.append(
            f"{len(low)} of {sum(counts)} syllables timed with low confidence (below {LOW_CONFIDENCE}), "
            f"first at {low[0].start:.2f} s: check them in the TextGrid"
        )
    return Alignment(tuple(sentences), audio.duration, tuple(notes))


def _check_language(text: str, source: str) -> None:
    """Refuse a transcript with more Latin words than Chinese characters (another language).

    Readings in braces (`OK{ou1 kei1}`) are not counted.
    """
    plain = re.sub(r"\{[^}]*\}", "", text)
    chinese = len(HAN_RE.findall(plain))
    latin = len(re.findall(r"[A-Za-z]+", plain))
    if latin > chinese:
        raise TranscriptError(
            f"{source}: the transcript looks like another language ({latin} Latin words, {chinese} Chinese "
            "characters); expected the Mandarin text spoken in the recording (give a Latin word its reading "
            "in braces, like OK{ou1 kei1})"
        )


def _check_rate(syllables: int, speech: float, source: str, notes: list[str]) -> None:
    """Refuse a transcript far too long for the speech; flag one far too short."""
    rate = syllables / max(speech, 1e-3)
    if rate > MAX_RATE:
        raise TranscriptError(
            f"{source}: {syllables} syllables to fit in {speech:.1f} s of speech ({rate:.0f} per second; "
            f"Mandarin is read at 3-7, at most {MAX_RATE:g} accepted): is this the transcript of this recording?"
        )
    if rate > FAST_RATE:
        notes.append(
            f"{rate:.1f} syllables per second of speech ({syllables} in {speech:.1f} s) is fast for Mandarin "
            "(3-7 is usual): the transcript may hold more than the recording says; timing is a best effort"
        )
    if rate < MIN_RATE:
        notes.append(
            f"only {rate:.1f} syllables per second of speech ({syllables} in {speech:.1f} s): the transcript "
            "may miss part of the recording, or the recording holds other sounds; timing is a best effort"
        )


def _blocks(spans: tuple[Span, ...], owners: list[int]) -> list[list[int]]:
    """Indices of the pieces in runs whose spans touch (cut inside one speaking part) or that
    are pieces of one sentence (`owners[k]`: the sentence of piece k). A long sentence without
    commas is cut into pieces by count, not at its pauses: aligned together, the aligner puts
    its pauses between the right syllables."""
    blocks = [[0]]
    for index in range(1, len(spans)):
        if spans[index - 1].end >= spans[index].start or owners[index - 1] == owners[index]:
            blocks[-1].append(index)
        else:
            blocks.append([index])
    return blocks


def word_lengths(texts: Sequence[str]) -> list[int]:
    """The characters each syllable speaks, in order ("" for the later syllables of a word
    read out as one token) -> syllables per word, by pypinyin's word segmentation (maximum
    matching over its phrase dictionary, on the Simplified text); the lengths sum to len(texts)."""
    ends, position = {0}, 0
    for word in longest_words(to_simplified("".join(texts))):
        position += len(word)
        ends.add(position)
    lengths: list[int] = []
    position = 0
    for text in texts:
        if not lengths or (text and position in ends):
            lengths.append(0)
        lengths[-1] += 1
        position += len(text)
    return lengths


def _align_jobs(audio: Audio, jobs: list[tuple[list[SentenceText], Span]], pool: Executor | None,
                report: Callable[[str, float], None]) -> list[list[tuple[Sentence, tuple[float, ...]]]]:
    """`_aligned` of each job (sentences, span), in order; with a `pool`, shared with it as they go
    (workers.from_both_ends): the pool takes the costliest first (by seconds times syllables: the
    aligner's cost, docs/BENCHMARKS.md "Analysis in parallel") and is sent only the samples each
    reads, this process the cheapest, until they meet; the pool, busy first with the pitch track,
    joins late by a time a split made beforehand could not know. `report("align", fraction)` as
    the jobs are done."""
    costs = [span.duration * sum(len(text.syllables) for text in texts) for texts, span in jobs]
    order = sorted(range(len(jobs)), key=lambda k: -costs[k])  # stable: equal costs in the jobs' order
    # The words of every job found here: the pool's process, forked before the transcript was read,
    # then needs no lexicon (speech/lexicon.py, ~35 ms to read).
    words = [[n for sentence in texts for n in word_lengths([s.text for s in sentence.syllables])] for texts, _ in jobs]
    timed = from_both_ends(pool, [(_aligned_part, (*_part_samples(audio, jobs[k][1]), *jobs[k], words[k]),
                                   partial(_aligned, audio, *jobs[k], words[k])) for k in order],
                           lambda done: report("align", done))
    done = dict(zip(order, timed))
    return [done[k] for k in range(len(jobs))]


def _part_samples(audio: Audio, span: Span) -> tuple[int, np.ndarray, int, int, str]:
    """(offset, samples, length, rate, source) of the samples around `span` that align_syllables
    reads (MARGIN frames either side) and what _aligned_part needs to put them back in place:
    the pool is sent these, not the whole recording (12 MB for 3 minutes, per job)."""
    reach = MARGIN * int(round(HOP * audio.rate)) + 1
    first = max(int(round(span.start * audio.rate)) - reach, 0)
    last = min(int(round(span.end * audio.rate)) + reach, len(audio.samples))
    return first, audio.samples[first:max(last, first)], len(audio.samples), audio.rate, audio.source


def _aligned_part(offset: int, samples: np.ndarray, length: int, rate: int, source: str, texts: list[SentenceText],
                  span: Span, words: list[int]) -> list[tuple[Sentence, tuple[float, ...]]]:
    """`_aligned(audio, texts, span, words)` from `_part_samples(audio, span)`: the recording rebuilt with
    zeros where the aligner does not read, so the result is the same."""
    whole = np.zeros(length, dtype=samples.dtype)
    whole[offset:offset + len(samples)] = samples
    return _aligned(Audio(whole, rate, source), texts, span, words)


def _aligned(audio: Audio, texts: list[SentenceText], span: Span,
             words: list[int]) -> list[tuple[Sentence, tuple[float, ...]]]:
    """Time the syllables of the sentences `texts`, spoken in this order inside `span` of `audio`
    (pauses likelier between words (`words`: syllables per word, word_lengths of each sentence in
    turn), and always possible between sentences): each sentence with the aligner's posterior of
    each of its syllables (SyllableTiming.posterior)."""
    pinyin = [syllable.pinyin for sentence in texts for syllable in sentence.syllables]
    timings = list(align_syllables(audio, span, pinyin, words))
    sentences = []
    for sentence in texts:
        mine, timings = timings[:len(sentence.syllables)], timings[len(sentence.syllables):]
        syllables = tuple(
            Syllable(text.text, text.pinyin, tuple(text.shapes), timing.start, timing.end, timing.confidence)
            for text, timing in zip(sentence.syllables, mine)
        )
        sentences.append((Sentence(sentence.text, syllables[0].start, syllables[-1].end, syllables),
                          tuple(t.posterior for t in mine)))
    return sentences


def _fall_back(audio: Audio, sentences: list[Sentence], posteriors: list[float]) -> tuple[list[Sentence], list[str]]:
    """Sentences with each stretch (run of syllables between pauses, stretches.py) whose timing is
    unfit (judged by the aligner's posteriors, one per syllable in order) timed again over its
    loudness peaks; and a note naming each such sentence and time range."""
    timed = [s for sentence in sentences for s in sentence.syllables]
    firsts: set[int] = set()
    owner: list[int] = []
    for number, sentence in enumerate(sentences):
        firsts.add(len(owner))
        owner += [number] * len(sentence.syllables)
    starts = np.array([s.start for s in timed])
    ends = np.array([s.end for s in timed])
    posterior = np.array(posteriors)
    notes = []
    for a, b in stretches(starts, ends, firsts):
        if not unfit(starts[a:b], ends[a:b], posterior[a:b]):
            continue
        start, end = float(starts[a]), float(ends[b - 1])
        for k, (onset, offset) in zip(range(a, b), spread_over_peaks(audio, start, end, b - a)):
            timed[k] = replace(timed[k], start=onset, end=offset,
                               confidence=min(timed[k].confidence, FALLBACK_CONFIDENCE))
        number = owner[a]
        notes.append(f"sentence {number + 1} {_quote(sentences[number].text)} {start:.2f}-{end:.2f} s: {FALLBACK_NOTE}")
    if not notes:
        return sentences, []
    result = []
    for number, sentence in enumerate(sentences):
        syllables = tuple(s for s, o in zip(timed, owner) if o == number)
        result.append(Sentence(sentence.text, syllables[0].start, syllables[-1].end, syllables))
    return result, notes


def _merge_notes(sentences: list[Sentence], parts: tuple[Span, ...]) -> list[str]:
    """Say which sentences span several speaking parts (merged), for the user."""
    notes = []
    for number, sentence in enumerate(sentences, start=1):
        inside = [i for i, part in enumerate(parts) if part.start < sentence.end and sentence.start < part.end]
        if len(inside) > 1:
            notes.append(
                f"sentence {number} {_quote(sentence.text)}: speaking parts {inside[0] + 1}-{inside[-1] + 1} "
                f"merged (the speaker paused {len(inside) - 1} time(s) inside it)"
            )
    return notes


def _split_notes(
    pieces: list[Sentence], owners: list[int], spans: tuple[Span, ...], parts: tuple[Span, ...]
) -> list[str]:
    """Say where a speaking part holding several sentences was split, at the aligned boundary.

    `pieces` are the aligned units, `owners` the sentence index of each (a long
    sentence is aligned in several pieces), `spans` their reconciled stretches.
    """
    notes = []
    for k in range(1, len(pieces)):
        if spans[k - 1].end < spans[k].start or owners[k - 1] == owners[k]:
            continue  # separated by a pause between parts, or pieces of one sentence
        time = (pieces[k - 1].end + pieces[k].start) / 2
        index = min(range(len(parts)), key=lambda i: max(parts[i].start - time, time - parts[i].end, 0.0))
        part = parts[index]
        notes.append(
            f"speaking part {index + 1} ({part.start:.2f}-{part.end:.2f} s) split at {time:.2f} s, "
            f"between sentences {owners[k - 1] + 1} and {owners[k] + 1} (no pause there)"
        )
    return notes


def sentence_pieces(sentences: tuple[SentenceText, ...]) -> tuple[list[SentenceText], list[int]]:
    """Sentences cut into pieces of at most MAX_PIECE syllables; (pieces, index of each one's sentence).

    A long sentence is cut at its commas (clause ends) where it can, else evenly,
    so that no single alignment call gets minutes of speech.
    """
    pieces, owners = [], []
    for number, sentence in enumerate(sentences):
        syllables = sentence.syllables
        ends = sorted({end + 1 for end in sentence.clause_ends if 0 <= end + 1 < len(syllables)} | {len(syllables)})
        cuts, start = [], 0
        for index, end in enumerate(ends):
            following = ends[index + 1] if index + 1 < len(ends) else None
            if following is None or following - start > MAX_PIECE:
                cuts.append(end)
                start = end
        bounds = [0]
        for cut in cuts:
            length = cut - bounds[-1]
            chunks = math.ceil(length / MAX_PIECE)
            bounds += [bounds[-1] + round(length * (k + 1) / chunks) for k in range(chunks)]
        for a, b in zip(bounds, bounds[1:]):
            pieces.append(SentenceText(sentence.text, syllables[a:b]))
            owners.append(number)
    return pieces, owners


def _quote(text: str, limit: int = 16) -> str:
    """A short quotation of a sentence for notes."""
    return f"«{text[:limit]}…»" if len(text) > limit else f"«{text}»"
