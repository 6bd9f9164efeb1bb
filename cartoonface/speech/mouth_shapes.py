"""Mandarin syllables -> basic mouth-shape symbols and their onsets inside the syllable.

Thesis 002, section 5.2.2 defines twelve basic mouth shapes; Tables 5.5 (initials) and
5.6 (finals) say which shapes a syllable is made of, and the prose after Table 5.6 gives
the rules that adjust the sequence. Section 5.3 gives when each shape of a syllable starts.

The extraction of Tables 5.5/5.6 is garbled (the Bopomofo glyphs are replaced by wrong
ones). The tables below are rebuilt from the member counts that survive, the symbol names,
the shape geometry of 5.2.2, the standard inventory of 21 initials and 38 Zhuyin finals
(16 single + 22 combined), and the worked examples; docs/mandarin-mouth-shapes.md explains
every choice. Pinyin here is tone-numbered ("hang2", neutral tone 5, "ü" or "v" for u-umlaut,
erhua as a trailing "r" before the tone: "dianr3").
"""

from __future__ import annotations


from cartoonface.face.mouth import MOUTH_SYMBOLS  # the twelve shapes of thesis 002 5.2.2, one definition
from cartoonface.speech.pinyin import syllable_parts

__all__ = ["MOUTH_SYMBOLS", "shape_onsets", "shapes_for"]

# Table 5.5 rebuilt (thesis 002, 5.2.2): the shape of each of the 21 initials.
# Surviving member counts: m 3, f 1, h' 6, h 3, r 4, z 3. m = bilabials (as in Table 5.3),
# f = labiodental, r = the four retroflexes (the glyph that survives is the r initial),
# z = the three dental sibilants (the glyph that survives is the z initial), h = the three
# velars (the glyph that survives is the h initial; shape h is the wider, more open one).
# h' keeps the rest of Chen and Tsai's h' class (Table 5.3): seven initials where six
# glyphs survive; Table 5.3 lost glyphs the same way (15 of its 17 survive).
INITIAL_SHAPE: dict[str, str] = {
    "b": "m", "p": "m", "m": "m",
    "f": "f",
    "d": "h'", "t": "h'", "n": "h'", "l": "h'", "j": "h'", "q": "h'", "x": "h'",
    "g": "h", "k": "h", "h": "h",
    "zh": "r", "ch": "r", "sh": "r", "r": "r",
    "z": "z", "c": "z", "s": "z",
}

# Table 5.6 rebuilt (thesis 002, 5.2.2): the shapes of each rhyme (the final without its
# medial). Singles: a, e (the Zhuyin e-hat), i, o, u (u and u-umlaut: two members),
# n (the en rhyme, moved into class n by the prose: "pronounced with wider lip corners"),
# h (three members: the e rhyme, shown by the worked example "he -> h'h"; eng, since ang is
# the combination "ah"; and er, the remaining final, a mid central vowel like e).
# Combinations: au, ou, an, ah, ei, ai. The apical vowel after z/c/s/zh/ch/sh/r has no
# Zhuyin final; we give it shape i, which makes the syllable "zhi" two shapes, as in the
# 5.3 example of a two-shape syllable.
RHYME_SHAPES: dict[str, tuple[str, ...]] = {
    "a": ("a",), "o": ("o",), "e": ("h",), "ê": ("e",),
    "i": ("i",), "u": ("u",), "ü": ("u",), "-i": ("i",),
    "ai": ("a", "i"), "ei": ("e", "i"), "ao": ("a", "u"), "ou": ("o", "u"),
    "an": ("a", "n"), "en": ("n",), "ang": ("a", "h"), "eng": ("h",), "er": ("h",),
}

# Medials (Zhuyin i, u, u-umlaut) take the shape of the same single final (Table 5.6).
MEDIAL_SHAPE: dict[str, str] = {"i": "i", "u": "u", "ü": "u"}

# Shapes of the syllabic nasals and interjections (pinyin.SYLLABIC_NASALS: 嗯 n, ng; 呣 m; 噷 hm; 哼 hng).
SYLLABIC: dict[str, tuple[str, ...]] = {
    "n": ("n",), "ng": ("h",), "m": ("m",), "hm": ("h", "m"), "hng": ("h",),
}

# Thesis 002, 5.3: for a syllable of 2, 3 or 4 shapes, the proportions of the syllable's
# duration from one shape's start to the next. The text says the second shape "is given at
# the time with a proportion" p1, the third at p2, ... Read as start points the 3- and
# 4-shape cases would go backwards (39.75% < 43.37%, 21.15% < 24.5%), so they are the
# lengths of the consecutive intervals: shape k+1 starts at p1 + ... + pk. The first number
# keeps its literal reading (second shape at 80.95%, 43.37%, 24.5%) and the last shape gets
# the rest (19.05%, 16.88%, 28.47%).
SHAPE_INTERVALS: dict[int, tuple[float, ...]] = {
    1: (),
    2: (0.8095,),
    3: (0.4337, 0.3975),
    4: (0.2450, 0.2115, 0.2588),
}

# Thesis 002, 5.2.2 prose after Table 5.6: h' and h are dropped before these symbols,
# kept before a (and before n and h, which the rule does not name; "he -> h'h" in 5.2.2).
_DROPS_INITIAL = frozenset("iueo")

# Erhua (our rule, not the thesis's): a rhyme ending in -i or -n loses that coda and the
# syllable ends in the shape of er (h); the apical vowel is replaced by it.
_ERHUA_LOSES_CODA = frozenset({"ai", "ei", "an", "en", "-i"})

def shapes_for(pinyin: str) -> tuple[str, ...]:
    """Tone-numbered pinyin -> its basic mouth shapes, 1-4 symbols from MOUTH_SYMBOLS.

    Tables 5.5/5.6 rebuilt, then the rules of thesis 002 5.2.2: the an rhyme after a medial
    i/ü becomes "en"; o after shape m becomes "uo"; h'/h is dropped before i, u, e, o.
    Ours: erhua (see _ERHUA_LOSES_CODA), equal neighbours merged into one held shape, and
    at most 4 shapes (5.3: "four basic mouth shapes at most"). Raises TranscriptError for a
    value that is not a syllable.
    """
    parts = syllable_parts(pinyin)
    if parts.final in ("n", "ng", "m"):
        shapes = list(SYLLABIC[("h" if parts.initial else "") + parts.final])
        if parts.erhua:
            shapes.append("h")
        return _finish(shapes)
    shapes = [INITIAL_SHAPE[parts.initial]] if parts.initial else []
    if parts.medial:
        shapes.append(MEDIAL_SHAPE[parts.medial])
    rhyme = list(RHYME_SHAPES[parts.final])
    if parts.final == "an" and parts.medial in ("i", "ü"):
        rhyme = ["e", "n"]  # thesis 002 5.2.2: "an" -> "en" after the finals i, ü
    if parts.final == "o" and not parts.medial and shapes == ["m"]:
        rhyme = ["u", "o"]  # thesis 002 5.2.2: "o" -> "uo" after the symbol m
    if parts.erhua:
        if parts.final in _ERHUA_LOSES_CODA:
            rhyme = rhyme[:-1]
        rhyme.append("h")
    shapes += rhyme
    if len(shapes) > 1 and shapes[0] in ("h'", "h") and parts.initial and shapes[1] in _DROPS_INITIAL:
        shapes = shapes[1:]  # thesis 002 5.2.2: the pre-posture is missed before i, u, e, o
    return _finish(shapes)


def _finish(shapes: list[str]) -> tuple[str, ...]:
    """Merge equal neighbours (one held shape) and keep at most 4 (drop the next-to-last)."""
    merged = [s for k, s in enumerate(shapes) if k == 0 or s != shapes[k - 1]]
    while len(merged) > 4:
        del merged[-2]
    return tuple(merged)


def shape_onsets(n: int) -> tuple[float, ...]:
    """Where each of n (1-4) shapes of a syllable starts, as fractions of its duration.

    Returns n increasing values in [0, 1), the first 0 (thesis 002 5.3, SHAPE_INTERVALS).
    Raises ValueError for n outside 1-4 (shapes_for never gives such n).
    """
    if n not in SHAPE_INTERVALS:
        raise ValueError(f"a syllable has 1-4 mouth shapes, not {n}")
    onsets = [0.0]
    for interval in SHAPE_INTERVALS[n]:
        onsets.append(round(onsets[-1] + interval, 6))
    return tuple(onsets)
