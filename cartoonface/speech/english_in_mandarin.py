"""English words inside a Mandarin transcript -> syllables the Mandarin aligner can time.

An English word ("Python" in 我用Python写代码) is read with its English pronunciation
(english.pronounce: the CMU dictionary inside the pocketsphinx wheel, else the letter-to-sound
rules), cut into syllables, one per vowel nucleus (consonants between two vowels go to the
second syllable as far as English allows them at the start of a word: `ONSETS`). Each syllable
gets
- as its pinyin the nearest Mandarin syllable (onset -> nearest initial, nucleus and nasal
  coda -> nearest final, `INITIALS` and `FINALS`; the first combination that is a real Mandarin
  syllable), so the aligner's duration and onset models (align.py) apply to it, and
- as its mouth shapes those of its own English phones by seed 000 Table 1
  (english.PHONE_SHAPE), equal neighbours merged and at most four (thesis 002, 5.3), so the lips
  show the English sounds.
docs/mandarin-mouth-shapes.md ("Latin letters and English words") has the tables and reasons.
"""

from __future__ import annotations

import unicodedata
from dataclasses import dataclass
from functools import cache

from cartoonface.speech.english import PHONE_SHAPE, VOWELS

# Onsets English allows at the start of a word (ARPAbet), for cutting consonants between vowels
# (the maximal-onset rule): every single consonant but NG, and these clusters.
ONSETS = frozenset({
    ("P", "R"), ("B", "R"), ("F", "R"), ("K", "R"), ("G", "R"), ("T", "R"), ("D", "R"), ("TH", "R"),
    ("SH", "R"), ("P", "L"), ("B", "L"), ("F", "L"), ("K", "L"), ("G", "L"), ("S", "L"),
    ("S", "P"), ("S", "T"), ("S", "K"), ("S", "M"), ("S", "N"), ("S", "W"), ("S", "F"),
    ("T", "W"), ("D", "W"), ("K", "W"), ("G", "W"), ("TH", "W"),
    ("P", "Y"), ("B", "Y"), ("F", "Y"), ("V", "Y"), ("K", "Y"), ("G", "Y"), ("M", "Y"), ("HH", "Y"),
    ("S", "P", "R"), ("S", "T", "R"), ("S", "K", "R"), ("S", "P", "L"), ("S", "K", "W"),
    ("S", "P", "Y"), ("S", "K", "Y"),
})

# Onset consonant (the first of the onset) -> Mandarin initials, nearest first (ours, by manner
# first, then place: the aligner's onset evidence goes by manner, align.initial_class). "" = no
# initial. V and W are said w, TH s and DH d by most Mandarin speakers; Z (a fricative) is s.
INITIALS: dict[str, tuple[str, ...]] = {
    "P": ("p",), "B": ("b",), "M": ("m",), "F": ("f",), "V": ("w", "f"),
    "T": ("t",), "D": ("d",), "N": ("n",), "L": ("l",), "R": ("r", "l"),
    "K": ("k", "q"), "G": ("g", "j"), "HH": ("h", "x"),
    "S": ("s", "x"), "Z": ("s", "x"), "TH": ("s", "x"), "DH": ("d",),
    "SH": ("sh", "x"), "ZH": ("r", "x"), "CH": ("ch", "q"), "JH": ("zh", "j"),
    "W": ("w", ""), "Y": ("y", ""),
}
# Before a final in i (i, in, ing) the dental and retroflex sibilants are said as the
# alveolo-palatal ones (s + i spells the apical vowel of 思, not "see").
PALATAL = {"s": "x", "sh": "x", "z": "j", "zh": "j", "c": "q", "ch": "q"}

# Nucleus vowel -> Mandarin finals nearest first, without a coda, before N or M (Mandarin has
# no -m), before NG. Other codas (stops, fricatives, L, R) have no Mandarin final: they are left
# out of the pinyin and kept in the mouth shapes.
FINALS: dict[str, tuple[tuple[str, ...], tuple[str, ...], tuple[str, ...]]] = {
    "AA": (("a",), ("an",), ("ang",)),
    "AE": (("ai", "a"), ("an",), ("ang",)),
    "AH": (("e", "a"), ("en", "an"), ("eng", "ang")),
    "AO": (("ao", "o", "uo"), ("uan", "an"), ("ang", "ong")),
    "AW": (("ao",), ("uan", "an"), ("ang",)),
    "AY": (("ai", "ei"), ("an",), ("ang",)),
    "EH": (("ai", "ei", "e"), ("en", "an"), ("eng",)),
    "ER": (("e", "er"), ("en",), ("eng",)),
    "EY": (("ei", "ai"), ("en", "ei"), ("eng",)),
    "IH": (("i", "ei"), ("in", "en"), ("ing", "eng")),
    "IY": (("i", "ei"), ("in", "en"), ("ing", "eng")),
    "OW": (("ou", "o", "uo"), ("ong", "un"), ("ong",)),
    "OY": (("uai", "ai"), ("an",), ("ang",)),
    "UH": (("u",), ("un", "en"), ("ong", "eng")),
    "UW": (("u",), ("un", "en"), ("ong", "eng")),
}
NASAL_CODA = {"N": 1, "M": 1, "NG": 2}  # coda consonant -> index into a FINALS row
# Last resorts when no initial + final of the tables makes a Mandarin syllable.
FALLBACK_FINALS = ("e", "o", "u")
# Spelling of a final without an initial (pinyin's y/w spellings).
ZERO_INITIAL = {"i": "yi", "in": "yin", "ing": "ying", "u": "wu", "un": "wen", "ong": "weng",
                "uo": "wo", "uai": "wai", "uan": "wan", "ei": "ei"}
# Tones: 1 (duration factor 1 in align.py); the schwa AH of a word of two or more syllables is
# unstressed, said short: the neutral tone 5 (align._TONE_FACTOR 0.91).
TONE = 1
UNSTRESSED_TONE = 5
# Consonants, most visible first: when a syllable has more than four shapes (thesis 002, 5.3)
# the shapes of the least visible consonants go (lips closed and lip-under-teeth stay longest).
VISIBILITY = ("B", "M", "P", "F", "V", "W", "R", "CH", "JH", "SH", "ZH", "S", "Z", "TH", "DH",
              "L", "D", "T", "N", "NG", "G", "K", "HH", "Y")
MAX_SHAPES = 4


@dataclass(frozen=True)
class EnglishSyllable:
    """One syllable of an English word: its ARPAbet `phones` (one vowel among them), the
    nearest Mandarin `pinyin` (tone-numbered) and its mouth `shapes` (1-4 symbols)."""

    phones: tuple[str, ...]
    pinyin: str
    shapes: tuple[str, ...]


@cache
def mandarin_syllables() -> frozenset[str]:
    """Every toneless pinyin spelling pypinyin's character dictionary reads (ü as u)."""
    from pypinyin.pinyin_dict import pinyin_dict  # English inside Mandarin only: pypinyin takes 0.2 s to import

    spellings = set()
    for readings in pinyin_dict.values():
        for reading in readings.split(","):
            plain = unicodedata.normalize("NFD", reading)
            spellings.add("".join(c for c in plain if not unicodedata.combining(c)))
    return frozenset(spellings)


def split_syllables(phones: tuple[str, ...]) -> list[tuple[str, ...]]:
    """ARPAbet phones of a word -> its syllables, one per vowel (english.VOWELS); the
    consonants between two vowels start the second as far as ONSETS allow. A word without a
    vowel ("hmm") is one syllable."""
    nuclei = [k for k, phone in enumerate(phones) if phone in VOWELS]
    if not nuclei:
        return [phones] if phones else []
    cuts = [0]
    for before, after in zip(nuclei, nuclei[1:]):
        cut = after
        while cut - 1 > before and _onset(phones[cut - 1 : after]):
            cut -= 1
        cuts.append(cut)
    cuts.append(len(phones))
    return [phones[a:b] for a, b in zip(cuts, cuts[1:])]


def _onset(consonants: tuple[str, ...]) -> bool:
    return len(consonants) == 1 and consonants[0] != "NG" or consonants in ONSETS


def nearest_pinyin(syllable: tuple[str, ...], unstressed: bool = False) -> str:
    """ARPAbet phones of one syllable -> the nearest tone-numbered Mandarin syllable.

    Initials of the first consonant (INITIALS) tried in order, each with the finals of the
    vowel and its nasal coda (FINALS), then the vowel's open finals, then FALLBACK_FINALS; the
    first spelling `mandarin_syllables` knows wins. A syllable without a vowel ("hmm") is the
    syllabic nasal m, hm or n when it has a nasal. Tone TONE, or UNSTRESSED_TONE when
    `unstressed`.
    """
    tone = str(UNSTRESSED_TONE if unstressed else TONE)
    vowels = [k for k, phone in enumerate(syllable) if phone in VOWELS]
    nasal = next((p for p in syllable if p in NASAL_CODA), "")
    if not vowels and nasal:
        return ("hm" if syllable[0] == "HH" and nasal == "M" else "m" if nasal == "M" else "n") + tone
    nucleus = vowels[0] if vowels else len(syllable)
    onset = syllable[0] if nucleus else ""
    coda = syllable[nucleus + 1] if nucleus + 1 < len(syllable) else ""
    row = FINALS[syllable[nucleus]] if vowels else ((), (), ())
    finals = (*row[NASAL_CODA.get(coda, 0)], *row[0], *FALLBACK_FINALS)
    known = mandarin_syllables()
    for initial in (*INITIALS[onset], "") if onset else ("",):
        for final in finals:
            spelling = _spelling(initial, final)
            if spelling in known:
                return spelling + tone
    raise AssertionError(f"no Mandarin syllable for {syllable}")  # "" + "e" is one


def _spelling(initial: str, final: str) -> str:
    """Initial + final as pinyin spells them (x before i for s, yi for a lone i)."""
    if not initial:
        return ZERO_INITIAL.get(final, final)
    if final.startswith("i"):
        initial = PALATAL.get(initial, initial)
    return initial + final


def syllable_shapes(syllable: tuple[str, ...]) -> tuple[str, ...]:
    """ARPAbet phones of one syllable -> its mouth shapes by seed 000 Table 1
    (english.PHONE_SHAPE), equal neighbours merged, at most MAX_SHAPES (the least visible
    consonants dropped first, VISIBILITY)."""
    items = [(PHONE_SHAPE[phone], phone) for phone in syllable]
    while True:
        merged = [item for k, item in enumerate(items) if k == 0 or item[0] != items[k - 1][0]]
        if len(merged) <= MAX_SHAPES:
            return tuple(shape for shape, _ in merged)
        consonants = [k for k, (_, phone) in enumerate(merged) if phone not in VOWELS]
        worst = max(reversed(consonants), key=lambda k: VISIBILITY.index(merged[k][1]))
        items = merged[:worst] + merged[worst + 1 :]


def english_syllables(phones: tuple[str, ...]) -> tuple[EnglishSyllable, ...]:
    """ARPAbet phones of a word -> its syllables with nearest pinyin and mouth shapes."""
    parts = split_syllables(phones)
    return tuple(EnglishSyllable(part, nearest_pinyin(part, len(parts) > 1 and "AH" in part), syllable_shapes(part))
                 for part in parts)
