"""speech/lexicon.py's table against pypinyin: readings, words, Bopomofo (issue 16's start-up)."""

from __future__ import annotations

import random
import subprocess
import sys
from importlib.metadata import version
from pathlib import Path

import pytest
from pypinyin.constants import PHRASES_DICT, PINYIN_DICT, RE_HANS
from pypinyin.seg.mmseg import seg as pypinyin_cut
from pypinyin.seg.simpleseg import seg as pypinyin_words

from cartoonface.speech.lexicon import LEXICON, lexicon, longest_words, reading, readings, words, zhuyin_of
from cartoonface.speech.lexicon_build import build, pypinyin_reading, pypinyin_readings, pypinyin_zhuyin
from cartoonface.speech.readings import to_simplified, zhuyin

ROOT = Path(__file__).resolve().parent.parent
PHRASES = sorted(PHRASES_DICT)
CHARS = [chr(code) for code in sorted(PINYIN_DICT)]


def test_the_shipped_table_is_the_one_the_installed_pypinyin_gives():
    text = LEXICON.read_text(encoding="utf-8")
    assert text.splitlines()[0].startswith(f"# pypinyin {version('pypinyin')}:")
    assert text == build()


def test_characters_read_as_pypinyin_reads_them():
    sample = CHARS[::37] + ["\u9fff", "\U0002a6e0", "a", "，", "3"]  # + some it has no reading for
    assert [reading(c) for c in sample] == [pypinyin_reading(c) or c for c in sample]
    assert all(reading(c) == c for c in sample[-4:])


def test_phrases_read_as_pypinyin_reads_them():
    sample = PHRASES[::23]
    assert [readings(p) for p in sample] == [pypinyin_readings(p) for p in sample]
    assert any(readings(p) != [reading(c) for c in p] for p in sample)  # the table's [readings] are used


def texts() -> list[str]:
    """The sample story, and random texts of phrases, beginnings of phrases, single characters,
    punctuation, Latin and characters pypinyin does not read (seeded: the same every run)."""
    rng = random.Random(16)
    prefixes = [word for word, said in lexicon().words.items() if said is None]
    pieces = [PHRASES, prefixes, CHARS, list("，。！ abc1\U0002a6e0\u3007")]
    made = ["".join(rng.choice(rng.choice(pieces)) for _ in range(rng.randint(1, 12))) for _ in range(400)]
    return [(ROOT / "samples" / "speech" / "story.txt").read_text(encoding="utf-8"), *made]


@pytest.mark.parametrize("simplify", [False, True])
def test_words_are_pypinyins_words(simplify):
    for text in texts():
        text = to_simplified(text) if simplify else text
        assert words(text) == pypinyin_words(text), text
        assert longest_words(text) == list(pypinyin_cut.cut(text)), text


def test_runs_pypinyin_does_not_read_are_words_of_their_own():
    outside = "\U0002a6e0"  # in speech/readings.py's HAN_RE, not in pypinyin's RE_HANS
    assert RE_HANS.match(outside) is None
    text = "我们" + outside + "你好"
    assert words(text) == pypinyin_words(text)
    assert outside in words(text)


def test_bopomofo_is_pypinyins():
    table = lexicon().zhuyin
    sample = sorted(table)[::7]
    assert [zhuyin_of(p) for p in sample] == [pypinyin_zhuyin(p) for p in sample]
    assert {p[-1] for p in table} == set("12345")


def test_a_spelling_no_character_has_gets_pypinyins_bopomofo():
    assert zhuyin_of("lue4") is None  # an English syllable's spelling (ü written u)
    assert zhuyin("lue4") == pypinyin_zhuyin("lue4")
    assert zhuyin("dianr3") == zhuyin_of("dian3") + "ㄦ"


def test_a_mandarin_transcript_needs_no_pypinyin():
    code = ("import sys\nfrom cartoonface.speech.transcript import parse_transcript\n"
            "parse_transcript('銀行的人说：一个小老板保管好了。')\n"
            "print(any(name.split('.')[0] == 'pypinyin' for name in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "False"
