"""English words inside a Mandarin transcript: syllables, nearest pinyin, English mouth shapes."""

from __future__ import annotations

import random

import pytest

from cartoonface.errors import TranscriptError
from cartoonface.speech.align import initial_class
from cartoonface.speech.analyse import analyse
from cartoonface.speech.english import PHONE_SHAPE, VOWELS, dictionary, pronounce
from cartoonface.speech.english_in_mandarin import english_syllables, mandarin_syllables, split_syllables
from cartoonface.speech.mouth_shapes import MOUTH_SYMBOLS
from cartoonface.speech.pinyin import syllable_parts
from cartoonface.speech.records import Alignment
from cartoonface.speech.textgrid import read_textgrid, write_textgrid
from cartoonface.speech.transcript import parse_transcript
from tests.synthetic import noisy, recording


@pytest.fixture(scope="module")
def words() -> list[tuple[str, tuple[str, ...]]]:
    """500 dictionary words with their phones, a seeded sample."""
    entries = sorted(dictionary().items())
    return random.Random(14).sample(entries, 500)


def test_a_word_is_cut_into_one_syllable_per_vowel(words):
    for _, phones in words:
        parts = split_syllables(phones)
        assert tuple(p for part in parts for p in part) == phones
        if any(p in VOWELS for p in phones):
            assert all(sum(p in VOWELS for p in part) == 1 for part in parts)


def test_every_syllable_reads_as_a_mandarin_syllable_with_english_shapes(words):
    known = mandarin_syllables()
    for _, phones in words:
        for syllable in english_syllables(phones):
            parts = syllable_parts(syllable.pinyin)  # raises when it is not pinyin
            assert syllable.pinyin[:-1] in known or parts.final in ("m", "n", "ng")
            assert 1 <= len(syllable.shapes) <= 4 and set(syllable.shapes) <= set(MOUTH_SYMBOLS)
            assert set(syllable.shapes) <= {PHONE_SHAPE[p] for p in syllable.phones}
            vowel = [PHONE_SHAPE[p] for p in syllable.phones if p in VOWELS]
            assert set(vowel) <= set(syllable.shapes)  # the nucleus is never dropped


# English onset consonant -> the aligner's class of the Mandarin initial it should get.
ONSET_CLASS = {"P": "aspirated", "T": "aspirated", "K": "aspirated", "B": "closure", "D": "closure",
               "G": "closure", "F": "frication", "S": "frication", "SH": "frication", "HH": "frication",
               "M": "sonorant", "N": "sonorant", "L": "sonorant", "R": "sonorant"}


def test_the_onset_consonant_gives_an_initial_of_its_class(words):
    checked = 0
    for _, phones in words:
        for syllable in english_syllables(phones):
            first = syllable.phones[0]
            if first in ONSET_CLASS:
                initial = syllable_parts(syllable.pinyin).initial
                assert initial_class(initial) == ONSET_CLASS[first], (syllable, initial)
                checked += 1
            elif first in VOWELS:
                assert syllable_parts(syllable.pinyin).initial == ""
    assert checked > 300


def test_english_word_in_a_sentence_shows_the_word_and_english_shapes():
    (sentence,) = parse_transcript("我用Python写了一个program。")
    texts = [s.text for s in sentence.syllables]
    phones, known = pronounce("python")
    assert known
    first = texts.index("Python")
    count = sum(p in VOWELS for p in phones)
    assert texts[first + 1 : first + count] == [""] * (count - 1)  # the word on its first syllable
    shapes = [shape for s in sentence.syllables[first : first + count] for shape in s.shapes]
    assert shapes[0] == PHONE_SHAPE["P"] == "m"  # the lips close for the English /p/
    assert set(shapes) <= {PHONE_SHAPE[p] for p in phones}
    assert not sentence.notes


def test_apostrophes_keep_a_word_whole():
    (sentence,) = parse_transcript("我don't知道。")
    assert [s.text for s in sentence.syllables][1:3] == ["don't", "知"]


def test_override_still_wins():
    (sentence,) = parse_transcript("我爱Python{pai4 sen1}。")
    assert [s.pinyin for s in sentence.syllables][2:] == ["pai4", "sen1"]
    assert sentence.syllables[2].shapes != english_syllables(pronounce("python")[0])[0].shapes


def test_a_word_outside_the_dictionary_is_read_from_its_spelling_with_a_note():
    assert "zorblax" not in dictionary()
    (sentence,) = parse_transcript("我见过Zorblax。")
    assert "Zorblax" in [s.text for s in sentence.syllables]
    assert any("Zorblax" in note and "spelling" in note for note in sentence.notes)


def test_a_word_without_vowels_outside_the_dictionary_is_spelled():
    assert "xkcd" not in dictionary()
    (sentence,) = parse_transcript("我看xkcd漫画。")
    assert [s.text for s in sentence.syllables if s.text.isascii() and s.text] == ["x", "k", "c", "d"]


def test_accented_letters_are_read_and_other_letters_refused_naming_the_word():
    (sentence,) = parse_transcript("一杯café。")
    assert "café" in [s.text for s in sentence.syllables]
    with pytest.raises(TranscriptError, match=r"story.txt: line 2, column 3: the word 'Straße'.*'ß'"):
        parse_transcript("你好\n我爱Straße的风。", source="story.txt")
    # columns count what the user wrote, overrides included
    with pytest.raises(TranscriptError, match=r"line 1, column 16: the word 'Ørsted'"):
        parse_transcript("我爱Python{pai4}，Ørsted。")


def test_english_alone_is_not_a_mandarin_transcript():
    with pytest.raises(TranscriptError, match="no Mandarin syllables"):
        parse_transcript("Hello world, good morning.")


def test_english_shapes_survive_the_aligner_and_the_textgrid():
    samples, _ = recording([9], [])
    alignment = analyse(noisy(samples), "我用Python写代码了。", source="story.txt", language="zh")
    records = [s for sentence in alignment.sentences for s in sentence.syllables]
    (sentence,) = parse_transcript("我用Python写代码了。")
    assert [s.shapes for s in records] == [s.shapes for s in sentence.syllables]
    assert all(a.end <= b.start + 1e-9 for a, b in zip(records, records[1:]))
    back = read_textgrid(write_textgrid(alignment), "t.TextGrid")
    assert isinstance(back, Alignment)
    assert [s.shapes for sentence in back.sentences for s in sentence.syllables] == [s.shapes for s in records]
    assert [s.text for sentence in back.sentences for s in sentence.syllables][2] == "Python"
