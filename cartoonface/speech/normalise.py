"""Numbers, symbols and Latin letters in a transcript -> the Chinese that is read out.

Times 12:30, years, long digit runs, dates, decimals, percentages, 两 before measure words,
spelled acronyms with Mandarin letter names, English words (english_in_mandarin.py), and
full-width ASCII forms. The rules are
written out in docs/mandarin-mouth-shapes.md.
"""

from __future__ import annotations

import re
import unicodedata

from cartoonface.errors import TranscriptError
from cartoonface.speech.english import VOWELS, english_letters, pronounce
from cartoonface.speech.english_in_mandarin import english_syllables
from cartoonface.speech.readings import Unit

# Letter names as Mandarin speakers say them (our approximation), for spelled acronyms.
_LETTERS: dict[str, tuple[str, ...]] = {
    "A": ("ei1",), "B": ("bi4",), "C": ("xi1",), "D": ("di4",), "E": ("yi4",),
    "F": ("ai2", "fu5"), "G": ("ji4",), "H": ("ai2", "qi1"), "I": ("ai4",), "J": ("zhei4",),
    "K": ("kei4",), "L": ("ai4", "lou5"), "M": ("ai2", "mu5"), "N": ("en1",), "O": ("ou1",),
    "P": ("pi1",), "Q": ("qiu1",), "R": ("a4", "er5"), "S": ("ai2", "si5"), "T": ("ti1",),
    "U": ("you1",), "V": ("wei1",), "W": ("da2", "bu5", "liu5"), "X": ("ai2", "ke4", "si5"),
    "Y": ("wai1",), "Z": ("zei4",),
}
_ACRONYM_MAX = 6

# Measure words after which the number 2 is read 两 (两个, 两点).
_LIANG_BEFORE = frozenset("个位只次天件条张本名岁种点斤双对口年周")
SYMBOL_READINGS = {"℃": "摄氏度"}
_DATE_AFTER = frozenset("月日号")
# Citation readings of digits read one by one (no tone changes, no phrase look-up: pypinyin's
# phrase 一月 would say yi2).
DIGIT_READINGS = {"零": "ling2", "一": "yi1", "二": "er4", "三": "san1", "四": "si4",
                   "五": "wu3", "六": "liu4", "七": "qi1", "八": "ba1", "九": "jiu3", "点": "dian3"}

NUMBER_RE = re.compile(r"(\d{1,2}):(\d{2})(?!\d)|(\d{1,3}(?:,\d{3})+|\d+)(\.\d+)?(%)?", re.ASCII)


def ascii_form(ch: str) -> str:
    """Full-width ASCII forms (digits, letters, ％ － ．) -> ASCII; other characters unchanged."""
    if "\uff01" <= ch <= "\uff5e":
        return chr(ord(ch) - 0xFEE0)
    return ch


def is_latin(ch: str) -> bool:
    """A letter of the Latin script: a-z, their full-width forms, and accented or other
    Latin letters (é, ø, ß; those not English are refused by latin_units)."""
    if not ch:
        return False
    if "a" <= ascii_form(ch).lower() <= "z":
        return True
    return ch.isalpha() and unicodedata.name(ch, "").startswith("LATIN")


def number_words(match: re.Match[str], following: str) -> tuple[str, bool]:
    """A matched number -> (the Chinese characters to read, read digit by digit?).

    following: the text after the number. Times 12:30 read 十二点三十; years (4 digits
    before 年; 2 before 年代), runs of 7+ digits (phone
    numbers, codes), runs starting with 0 and 1 in dates (1月, 1日, 1号: yi1, no tone change)
    digit by digit; 2 before a measure word 两;
    decimals 三点一四; percentages 百分之五十; thousands separators ignored. cn2an reads
    the cardinals.
    """
    if match.group(1):
        return _cardinal(match.group(1)) + "点" + _cardinal(match.group(2)), False
    whole = match.group(3).replace(",", "")
    decimals, percent = match.group(4), match.group(5)
    plain = not decimals and not percent
    nxt = following[:1]
    by_digit = (len(whole) >= 7 or (whole.startswith("0") and len(whole) > 1)
                or (nxt == "年" and len(whole) == 4 and plain)
                or (following.startswith("年代") and len(whole) == 2 and plain)
                or (whole == "1" and nxt in _DATE_AFTER and plain))
    if by_digit:
        spoken = _digits(whole)
    elif whole == "2" and plain and nxt in _LIANG_BEFORE:
        spoken = "两"
    else:
        spoken = _cardinal(whole)
    if decimals:
        spoken += "点" + _digits(decimals[1:])
    if percent:
        spoken = "百分之" + spoken
    return spoken, by_digit


def _digits(digits: str) -> str:
    return "".join("零一二三四五六七八九"[int(d)] for d in digits)


def _cardinal(whole: str) -> str:
    import cn2an  # only for a transcript with numbers: its import takes ~0.1 s of every command (issue 16)

    return cn2an.an2cn(str(int(whole)), "low")


def latin_units(word: str, readings: tuple[str, ...] | None, notes: list[str], where: str) -> list[Unit]:
    """A Latin word of a Mandarin transcript -> its syllables as units.

    Its override readings when given; letter names (_LETTERS) for an acronym (all capitals,
    at most _ACRONYM_MAX letters) or a single letter; otherwise its English pronunciation
    (english.pronounce: dictionary, else letter-to-sound, with a note) cut into syllables, each
    with the nearest Mandarin reading and the mouth shapes of its English phones
    (english_in_mandarin); a word the letter-to-sound rules give no vowel ("xkcd") is spelled.
    The word is shown on its first unit. Raises TranscriptError starting with `where` (source,
    line, column) for a word with a letter that is not English (after accents are dropped).
    """
    if readings:
        return [Unit(word if k == 0 else "", reading=r, no_sandhi=True)
                for k, r in enumerate(readings)]
    letters = english_letters("".join(ascii_form(c) for c in word))
    if not re.fullmatch(r"[a-z]+(?:'[a-z]+)*", letters, re.IGNORECASE):
        strange = next(c for c, plain in zip(word, letters) if not ("a" <= plain.lower() <= "z" or plain == "'"))
        raise TranscriptError(
            f"{where}: the word {word!r} has no pronunciation ({strange!r} is not an English letter); "
            f"expected English or Chinese, or give its readings like {word}{{ou1 si1}}, one per syllable")
    spelled = letters.replace("'", "")
    if len(spelled) == 1 or (spelled.isupper() and len(spelled) <= _ACRONYM_MAX):
        return _spelled(word, spelled)
    phones, known = pronounce(letters.lower())
    if not any(phone in VOWELS for phone in phones):
        return _spelled(word, spelled)
    syllables = english_syllables(phones)
    if not known:
        notes.append(f"read the English word {word!r} from its spelling (not in the dictionary) as "
                     f"{' '.join(s.pinyin for s in syllables)}; if it is said otherwise, give its "
                     f"readings in braces, one per syllable, like {word}{{ha1 lou2}}")
    return [Unit(word if k == 0 else "", reading=s.pinyin, no_sandhi=True, shapes=s.shapes)
            for k, s in enumerate(syllables)]


def _spelled(shown: str, letters: str) -> list[Unit]:
    """Units of the Mandarin letter names of `letters` (a-z), each letter shown on its first."""
    units: list[Unit] = []
    letter_chars = [c for c in shown if c not in "'’"]
    for char, letter in zip(letter_chars, letters.upper()):
        units.extend(Unit(char if k == 0 else "", reading=r, no_sandhi=True)
                     for k, r in enumerate(_LETTERS[letter]))
    return units
