"""Tone-numbered pinyin syllables split into their parts: the one pinyin parser of the project.

`split_initial` cuts a spelling after its initial (INITIALS, longest first; y and w on
request, as spelling initials); `syllable_parts` splits a whole syllable the Zhuyin way
(initial, medial, final, tone, erhua) and refuses what is not a Mandarin syllable. Pinyin
is tone-numbered ("hang2", neutral tone 5, "ü" or "v" for u-umlaut, erhua as a trailing
"r" before the tone: "dianr3").
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from cartoonface.errors import TranscriptError

# The 21 initials of standard Mandarin, two-letter ones first so that "zh" wins over "z".
INITIALS = ("zh", "ch", "sh", "b", "p", "m", "f", "d", "t", "n", "l", "g", "k", "h",
            "j", "q", "x", "r", "z", "c", "s")
# y and w: spelling of a syllable with no initial (yan = ian), counted as initials where asked.
GLIDES = ("y", "w")
# Syllabic nasals and interjections pypinyin produces (嗯 n, ng; 呣 m; 噷 hm; 哼 hng).
SYLLABIC_NASALS = frozenset({"n", "ng", "m", "hm", "hng"})


# Full (unabbreviated, y/w-free) finals -> (medial, rhyme).
_FINALS: dict[str, tuple[str, str]] = {
    "a": ("", "a"), "o": ("", "o"), "e": ("", "e"), "ê": ("", "ê"), "er": ("", "er"),
    "ai": ("", "ai"), "ei": ("", "ei"), "ao": ("", "ao"), "ou": ("", "ou"),
    "an": ("", "an"), "en": ("", "en"), "ang": ("", "ang"), "eng": ("", "eng"),
    "ong": ("u", "eng"),
    "i": ("", "i"), "ia": ("i", "a"), "io": ("i", "o"), "ie": ("i", "ê"), "iai": ("i", "ai"),
    "iao": ("i", "ao"), "iou": ("i", "ou"), "ian": ("i", "an"), "in": ("i", "en"),
    "iang": ("i", "ang"), "ing": ("i", "eng"), "iong": ("ü", "eng"),
    "u": ("", "u"), "ua": ("u", "a"), "uo": ("u", "o"), "uai": ("u", "ai"),
    "uei": ("u", "ei"), "uan": ("u", "an"), "uen": ("u", "en"), "uang": ("u", "ang"),
    "ueng": ("u", "eng"),
    "ü": ("", "ü"), "üe": ("ü", "ê"), "üan": ("ü", "an"), "ün": ("ü", "en"),
}

# Spellings -> full finals: the y/w forms of syllables without an initial, and the
# abbreviations iu, ui, un of the Pinyin scheme.
_ZERO_INITIAL: dict[str, str] = {
    "yi": "i", "ya": "ia", "yo": "io", "ye": "ie", "yai": "iai", "yao": "iao", "you": "iou",
    "yan": "ian", "yin": "in", "yang": "iang", "ying": "ing", "yong": "iong",
    "yu": "ü", "yue": "üe", "yuan": "üan", "yun": "ün",
    "wu": "u", "wa": "ua", "wo": "uo", "wai": "uai", "wei": "uei", "wan": "uan",
    "wen": "uen", "wang": "uang", "weng": "ueng", "wong": "ueng",
}
_ABBREVIATED = {"iu": "iou", "ui": "uei", "un": "uen"}
_NOT_FRONT = frozenset({"g", "k", "h", "z", "c", "s", "zh", "ch", "sh", "r"})

_SYLLABLE_RE = re.compile(r"([a-zêü]+?)(r?)([1-5])")


def split_initial(spelling: str, glides: bool = False) -> tuple[str, str]:
    """A toneless pinyin spelling ("zhuang", "yuan") -> (initial, the rest).

    The initial is the longest of INITIALS (and of GLIDES when `glides`) that the spelling
    starts with and that leaves something after it; "" when none ("an" -> ("", "an")).
    """
    for initial in INITIALS + GLIDES if glides else INITIALS:
        if spelling.startswith(initial) and len(spelling) > len(initial):
            return initial, spelling[len(initial):]
    return "", spelling


@dataclass(frozen=True)
class SyllableParts:
    """A tone-numbered pinyin syllable split the Zhuyin way.

    initial: one of the 21 initials or "" (y/w are spelling, not initials);
    medial: "i", "u", "ü" or ""; final: the rhyme ("a", "o", "e", "ê", "ai", "ei", "ao",
    "ou", "an", "en", "ang", "eng", "er", "i", "u", "ü", "-i" for the apical vowel of
    zi/ci/si/zhi/chi/shi/ri, or "n", "ng", "m" for syllabic nasals); tone: 1-5 (5 neutral);
    erhua: the syllable ends in a retroflex r ("dianr3").
    """

    initial: str
    medial: str
    final: str
    tone: int
    erhua: bool = False


def syllable_parts(pinyin: str) -> SyllableParts:
    """Split tone-numbered pinyin ("zhuang4", "lü4", "lv4", "yuan2", "dianr3") into its parts.

    Raises TranscriptError naming the value when it is not a Mandarin syllable with a tone
    number 1-5.
    """
    text = pinyin.strip().lower().replace("u:", "ü").replace("v", "ü")
    match = _SYLLABLE_RE.fullmatch(text)
    if match is None:
        raise TranscriptError(
            f"pinyin {pinyin!r}: expected a Mandarin syllable with a tone number 1-5, like hang2")
    body, r, tone = match.group(1), match.group(2), int(match.group(3))
    if body == "e" and r:  # the syllable er itself, not an erhua e
        body, r = "er", ""
    if body in SYLLABIC_NASALS:
        initial = "h" if body.startswith("h") else ""
        return SyllableParts(initial, "", body.removeprefix("h"), tone, bool(r))
    initial, rest = split_initial(body)
    if not initial:
        rest = _ZERO_INITIAL.get(rest, rest)
        if rest and rest[0] in "iuü" and body[0] not in "yw" and rest not in ("i", "u", "ü"):
            rest = ""  # a medial needs y/w when there is no initial ("ia" is spelt "ya")
    elif initial in ("j", "q", "x") and rest.startswith("u"):
        rest = "ü" + rest[1:]  # ju, que, xuan, jun spell u-umlaut as u
    elif initial in ("n", "l") and rest == "ue":
        rest = "üe"  # nue, lue: older spelling of nüe, lüe
    rest = _ABBREVIATED.get(rest, rest)
    if initial in ("z", "c", "s", "zh", "ch", "sh", "r") and rest == "i":
        rest = "-i"
    if rest == "-i":
        medial, final = "", "-i"
    elif rest in _FINALS:
        medial, final = _FINALS[rest]
    else:
        raise TranscriptError(f"pinyin {pinyin!r}: {body!r} is not a Mandarin syllable")
    front = medial in ("i", "ü") or final in ("i", "ü")
    umlaut = medial == "ü" or final == "ü"
    if ((initial in ("j", "q", "x") and not front)
            or (initial in _NOT_FRONT and front)
            or (umlaut and initial not in ("", "n", "l", "j", "q", "x"))):
        raise TranscriptError(f"pinyin {pinyin!r}: {body!r} is not a Mandarin syllable "
                              "(j, q, x go only with i and ü; g, k, h, z, c, s, zh, ch, sh, r "
                              "never; ü only after n, l, j, q, x)")
    return SyllableParts(initial, medial, final, tone, bool(r))
