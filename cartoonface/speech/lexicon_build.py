"""Writes data/lexicon.txt, pypinyin's answers that speech/lexicon.py looks up (issue 16).

    .venv/bin/python -m cartoonface.speech.lexicon_build           # rewrite the table
    .venv/bin/python -m cartoonface.speech.lexicon_build --check   # exit 1 unless it is up to date

Run it again when pypinyin or OpenCC's dictionary changes (tests/test_lexicon.py fails when the
installed pypinyin is not the one the table names). The functions here are the reference the
table is built from and tested against: pypinyin called as speech/readings.py called it before
the table (tone-numbered, 5 for the neutral tone, "ü").

The readings are pypinyin's data (MIT licence; its dictionaries come from the pinyin-data and
phrase-pinyin-data projects, MIT), reshaped: the licence travels with the wheel's dependency on pypinyin.

The file, UTF-8, one entry a line, in sections (lexicon.py reads them):

- a comment line naming pypinyin's version, then pypinyin's RE_HANS pattern (the characters it
  reads; its segmentation splits the text at the others);
- `[chars]`: `reading<TAB>characters`, every character of pypinyin's dictionary grouped by the
  reading `reading(char)` gives it;
- `[phrases]`: the phrases of pypinyin's phrase dictionary that read as their characters do;
- `[readings]`: `phrase<TAB>readings` (space-separated) for the others;
- `[prefixes]`: the beginnings of phrases that are no phrase (its maximum matching reads on
  while the text so far begins a phrase);
- `[zhuyin]`: `pinyin<TAB>Bopomofo` for every spelling of the dictionary in tones 1 to 5.
"""

from __future__ import annotations

import sys
from collections import defaultdict
from importlib.metadata import version

from pypinyin import Style, lazy_pinyin
from pypinyin.constants import PHRASES_DICT, PINYIN_DICT, RE_HANS
from pypinyin.contrib.tone_convert import to_tone, to_tone3
from pypinyin.style import convert as convert_style

from cartoonface.speech.lexicon import LEXICON, SECTIONS


def pypinyin_reading(char: str) -> str:
    """pypinyin's reading of one character, tone-numbered ("" when it gives more or fewer than one)."""
    readings = lazy_pinyin(char, style=Style.TONE3, neutral_tone_with_five=True, v_to_u=True)
    return readings[0] if len(readings) == 1 else ""


def pypinyin_readings(word: str) -> list[str]:
    """pypinyin's readings of a word (a phrase, or one character): one per character, each
    character alone when pypinyin gives another number of readings."""
    readings = lazy_pinyin(word, style=Style.TONE3, neutral_tone_with_five=True, v_to_u=True)
    return readings if len(readings) == len(word) else [pypinyin_reading(c) for c in word]


def pypinyin_zhuyin(base: str) -> str:
    """Tone-numbered pinyin without erhua ("hang2") -> Bopomofo with its tone mark, by pypinyin."""
    return str(convert_style(to_tone(base), Style.BOPOMOFO, strict=True))


def spellings() -> set[str]:
    """Every toneless spelling of pypinyin's character dictionary, "ü" kept."""
    plain = set()
    for readings in PINYIN_DICT.values():
        for reading in readings.split(","):
            plain.add(to_tone3(reading, v_to_u=True).rstrip("1234"))
    return {spelling for spelling in plain if spelling.isalpha()}  # not the syllabic nasals' combining tone marks


def build() -> str:
    """The text of data/lexicon.txt from the installed pypinyin."""
    chars = {chr(code): pypinyin_reading(chr(code)) for code in sorted(PINYIN_DICT)}
    grouped: dict[str, list[str]] = defaultdict(list)
    for char, reading in chars.items():
        grouped[reading].append(char)
    phrases, readings = [], []
    for phrase in sorted(PHRASES_DICT):
        said = pypinyin_readings(phrase)
        if said == [chars.get(c, c) for c in phrase]:
            phrases.append(phrase)
        else:
            readings.append(f"{phrase}\t{' '.join(said)}")
    prefixes = sorted({phrase[:end] for phrase in PHRASES_DICT for end in range(1, len(phrase))} - PHRASES_DICT.keys())
    zhuyin = [f"{spelling}{tone}\t{pypinyin_zhuyin(f'{spelling}{tone}')}"
              for spelling in sorted(spellings()) for tone in range(1, 6)]
    parts = {"chars": [f"{reading}\t{''.join(group)}" for reading, group in sorted(grouped.items())],
             "phrases": phrases, "readings": readings, "prefixes": prefixes, "zhuyin": zhuyin}
    assert tuple(parts) == SECTIONS
    head = [f"# pypinyin {version('pypinyin')}: written by python -m cartoonface.speech.lexicon_build", RE_HANS.pattern]
    lines = head + [line for name, entries in parts.items() for line in [f"[{name}]", *entries]]
    return "\n".join(lines) + "\n"


def main(argv: list[str]) -> int:
    """Write the table, or with --check report whether the shipped one is the one build() makes."""
    text = build()
    if "--check" in argv:
        same = LEXICON.read_text(encoding="utf-8") == text
        print(f"{LEXICON}: {'up to date' if same else 'out of date: run python -m cartoonface.speech.lexicon_build'}")
        return 0 if same else 1
    LEXICON.write_text(text, encoding="utf-8")
    print(f"{LEXICON}: {len(text.encode())} bytes")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
