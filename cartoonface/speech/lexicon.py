"""Readings, words and Bopomofo of Simplified Hanzi from pypinyin's answers shipped as a table.

Importing pypinyin costs ~0.2 s of CPU at every start (it parses its 2.5 MB JSON phrase dictionary
and builds the set of every phrase's beginnings), for the few answers a transcript needs.
data/lexicon.txt holds those answers for every character and phrase of its dictionaries, written by
`python -m cartoonface.speech.lexicon_build` (which names the format; tests/test_lexicon.py checks
it against pypinyin); reading it costs ~35 ms of CPU, once, on first use. Readings are
tone-numbered with 5 for the neutral tone and "ü" ("hang2"), as speech/readings.py uses them.
"""

from __future__ import annotations

import itertools
import re
from dataclasses import dataclass
from functools import cache
from pathlib import Path

LEXICON = Path(__file__).resolve().parent.parent / "data" / "lexicon.txt"
SECTIONS = ("chars", "phrases", "readings", "prefixes", "zhuyin")


@dataclass(frozen=True)
class Lexicon:
    """The table: `hans` (the characters pypinyin reads), `chars` (character -> reading),
    `words` (phrase -> its readings space-separated, "" when they are its characters'; the
    beginning of a phrase that is no phrase -> None), `zhuyin` (pinyin -> Bopomofo)."""

    hans: re.Pattern[str]
    chars: dict[str, str]
    words: dict[str, str | None]
    zhuyin: dict[str, str]


@cache
def lexicon() -> Lexicon:
    """data/lexicon.txt read (once: it is the same for the whole process)."""
    lines = LEXICON.read_text(encoding="utf-8").split("\n")
    starts = [lines.index(f"[{name}]") for name in SECTIONS] + [len(lines) - 1]
    chars, phrases, readings, prefixes, zhuyin = (lines[a + 1:b] for a, b in itertools.pairwise(starts))
    by_char: dict[str, str] = {}
    for line in chars:
        reading, group = line.split("\t")
        by_char.update(dict.fromkeys(group, reading))
    words: dict[str, str | None] = dict.fromkeys(prefixes)
    words.update(dict.fromkeys(phrases, ""))
    for line in readings:
        phrase, said = line.split("\t")
        words[phrase] = said
    return Lexicon(re.compile(lines[1]), by_char, words, dict(line.split("\t") for line in zhuyin))


def reading(char: str) -> str:
    """pypinyin's reading of one character; the character itself when it has none."""
    return lexicon().chars.get(char, char)


def readings(word: str) -> list[str]:
    """The readings of a word of `words(text)`, one per character (pypinyin's phrase readings)."""
    said = lexicon().words.get(word)
    return said.split(" ") if said else [reading(c) for c in word]


def longest_words(text: str) -> list[str]:
    """`text` cut into words as pypinyin's strict maximum matching (pypinyin.seg.mmseg.seg.cut)
    does: from each position the longest phrase of its dictionary, else one character; where the
    rest of the text only begins a phrase, each of its characters."""
    words = lexicon().words
    out: list[str] = []
    start = 0
    while start < len(text):
        end, longest = start, start
        while end < len(text) and text[start:end + 1] in words:
            end += 1
            if words[text[start:end]] is not None:
                longest = end
        if longest > start:
            out.append(text[start:longest])
            start = longest
        elif end == len(text):  # pypinyin's last step: the whole rest begins a phrase
            out.extend(text[start:])
            start = end
        else:
            out.append(text[start])
            start += 1
    return out


def words(text: str) -> list[str]:
    """`text` in words as pypinyin.seg.simpleseg.seg gives them: runs of characters pypinyin does
    not read whole, and the `longest_words` of each run of those it reads."""
    hans = lexicon().hans
    out: list[str] = []
    for read, chars in itertools.groupby(text, key=lambda c: hans.match(c) is not None):
        run = "".join(chars)
        out.extend(longest_words(run) if read else [run])
    return out


def zhuyin_of(base: str) -> str | None:
    """Bopomofo of tone-numbered pinyin without erhua ("hang2" -> "ㄏㄤˊ"); None for a spelling
    none of pypinyin's characters has."""
    return lexicon().zhuyin.get(base)
