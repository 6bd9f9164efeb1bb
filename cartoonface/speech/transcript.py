"""Transcript text -> sentences -> spoken syllables (pinyin, zhuyin, mouth shapes).

Thesis 002, 3.3: "an entire transcript is segmented into sentences by punctuation marks"
and each character becomes its syllable; the thesis picked polyphone readings by hand, we
use pypinyin's phrase dictionary and let the user override a reading inline. Every rule
here (sentence ends, overrides, erhua, tone changes, numbers, Latin, emoji) is written out
in docs/mandarin-mouth-shapes.md.

Readings are the surface (spoken) tones, tone-numbered with 5 for the neutral tone and
"ü" for u-umlaut: "hang2", "ni2 hao3", "lü4", erhua "dianr3".
"""

from __future__ import annotations

import re
import unicodedata
from dataclasses import dataclass, field, replace
from functools import cache

import cn2an
from opencc import OpenCC
from pypinyin import Style, lazy_pinyin
from pypinyin.contrib.tone_convert import to_tone, to_tone3
from pypinyin.seg.simpleseg import seg
from pypinyin.style import convert as convert_style

from cartoonface.errors import TranscriptError
from cartoonface.speech.mouth_shapes import shapes_for, syllable_parts


@dataclass(frozen=True)
class SyllableText:
    """One spoken syllable.

    text: the characters it speaks ("行", "點兒"; for a number the Chinese digits we read,
    "二"; for a spelled letter the letter; "" for the later syllables of a Latin word read
    through an override); pinyin: surface reading, tone-numbered ("hang2", neutral 5,
    erhua "dianr3"); zhuyin: the same in Bopomofo ("ㄏㄤˊ", "ㄉㄧㄢˇㄦ"); shapes: its basic
    mouth shapes (mouth_shapes.shapes_for).
    """

    text: str
    pinyin: str
    zhuyin: str
    shapes: tuple[str, ...]


@dataclass(frozen=True)
class SentenceText:
    """One sentence of the transcript.

    text: as written (traditional characters kept, overrides' braces removed);
    syllables: what is spoken, in order; clause_ends: index of the last syllable before
    each comma-like mark inside the sentence (，、,：:— possible pauses, e.g. for nods);
    notes: what was skipped or guessed, for the user.
    """

    text: str
    syllables: tuple[SyllableText, ...]
    clause_ends: tuple[int, ...] = ()
    notes: tuple[str, ...] = ()


# Sentence ends (thesis 002, 3.3: sentences by punctuation marks). "." ends a sentence
# unless it stands between two digits (3.14).
_ENDS = frozenset("。！？；!?;…\n")
_CLOSERS = frozenset("”’」』）)》〉】]\"'")
_PAUSES = frozenset("，、,：:—–")

# Where 儿 is a word of its own (child, son) and not the erhua suffix: the pair it ends,
# or the character after it (儿子, 儿童). Our list of common words.
_REAL_ER_WORDS = frozenset({
    "女儿", "婴儿", "幼儿", "孤儿", "男儿", "健儿", "宠儿", "胎儿", "患儿", "少儿", "育儿",
    "托儿", "孙儿", "侄儿", "乳儿", "弃儿", "血儿", "生儿", "产儿", "运儿",
})
_REAL_ER_NEXT = frozenset("子童女孙媳科歌")

# 一 keeps tone 1 after these (ordinal 第一, word-final 统一 唯一 万一 单一 专一 之一 逐一,
# and inside numbers 十一 一一) and before a digit.
_YI_FIRST_AFTER = frozenset("第统唯万单专之逐初〇零一二三四五六七八九十百千")
_DIGIT_CHARS = frozenset("〇零一二三四五六七八九十")
# Doubled adjectives that keep their tone as adverbs (好好 hao2 hao3), not 姐姐-like nouns.
_AA_KEEP = frozenset("好早远满稳小老久饱紧短浅")

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
_SYMBOL_READINGS = {"℃": "摄氏度"}
_DATE_AFTER = frozenset("月日号")
# Citation readings of digits read one by one (no tone changes, no phrase look-up: pypinyin's
# phrase 一月 would say yi2).
_DIGIT_READINGS = {"零": "ling2", "一": "yi1", "二": "er4", "三": "san1", "四": "si4",
                   "五": "wu3", "六": "liu4", "七": "qi1", "八": "ba1", "九": "jiu3", "点": "dian3"}

_NUMBER_RE = re.compile(r"(\d{1,2}):(\d{2})(?!\d)|(\d{1,3}(?:,\d{3})+|\d+)(\.\d+)?(%)?", re.ASCII)
_READING_RE = re.compile(r"[a-zü]+r?[1-5]")
_HAN_RE = re.compile(r"[\u3007\u3400-\u4dbf\u4e00-\u9fff\uf900-\ufaff\U00020000-\U0003134f]")


@dataclass(frozen=True)
class _Unit:
    """A syllable on its way: shown text, the Hanzi to look up (or ""), a fixed reading."""

    text: str
    han: str = ""
    reading: str = ""
    no_sandhi: bool = False   # digit-by-digit numbers, spelled letters, overrides
    word: int = 0
    pinyin: str = ""


@dataclass
class _Sentence:
    text: str
    units: list[list[_Unit]] = field(default_factory=list)   # one list per sandhi domain
    pause_after: set[int] = field(default_factory=set)        # domains a comma-like mark follows
    notes: list[str] = field(default_factory=list)


def parse_transcript(text: str, source: str = "transcript") -> tuple[SentenceText, ...]:
    """Transcript text -> its sentences with their spoken syllables.

    text: the whole transcript (Simplified or Traditional Chinese, with optional inline
    overrides like 行{hang2}); source: the file or field name used in error messages.
    Raises TranscriptError for an empty transcript, a bad override (naming line, column
    and reading) or a transcript with no Mandarin syllable at all.
    """
    if not text.strip():
        raise TranscriptError(f"{source}: the transcript is empty; expected Mandarin text")
    clean, overrides = _strip_overrides(text, source)
    sentences: list[SentenceText] = []
    pending_notes: list[str] = []
    for start, end in _sentence_spans(clean):
        raw = _read_sentence(clean, start, end, overrides)
        if raw is None:
            continue
        sentence = _finish_sentence(raw)
        if not sentence.syllables:
            if sentences:
                sentences[-1] = replace(sentences[-1], notes=sentences[-1].notes + sentence.notes)
            else:
                pending_notes.extend(sentence.notes)
            continue
        if pending_notes:
            sentence = replace(sentence, notes=tuple(pending_notes) + sentence.notes)
            pending_notes = []
        sentences.append(sentence)
    if not sentences:
        raise TranscriptError(
            f"{source}: no Mandarin syllables found; expected Chinese text "
            "(Latin words, emoji and symbols alone are not read)")
    return tuple(sentences)


def _position(text: str, index: int) -> str:
    line = text.count("\n", 0, index) + 1
    column = index - (text.rfind("\n", 0, index) + 1) + 1
    return f"line {line}, column {column}"


def _strip_overrides(text: str, source: str) -> tuple[str, dict[int, tuple[str, ...]]]:
    """Remove `{reading}` overrides; return the clean text and {index in it: readings}.

    An override follows a Chinese character (one reading) or a Latin word (one or more,
    space-separated); the key is the index of that character or of the word's last letter.
    """
    clean: list[str] = []
    overrides: dict[int, tuple[str, ...]] = {}
    i = 0
    while i < len(text):
        ch = text[i]
        if ch == "}":
            raise TranscriptError(f"{source}: {_position(text, i)}: '}}' without an opening '{{'")
        if ch != "{":
            clean.append(ch)
            i += 1
            continue
        close = text.find("}", i + 1)
        if close < 0 or any(c in "{\n" for c in text[i + 1:close]):
            raise TranscriptError(
                f"{source}: {_position(text, i)}: '{{' without a closing '}}' on the same line; "
                "expected an override like 行{hang2}")
        where = f"{source}: {_position(text, i)}"
        tokens = text[i + 1:close].split()
        target = clean[-1] if clean else ""
        if _HAN_RE.fullmatch(target):
            if len(tokens) != 1:
                raise TranscriptError(
                    f"{where}: override {text[i:close + 1]!r} after {target!r} must give exactly "
                    "one reading, like 行{hang2}")
        elif not _is_latin(target):
            raise TranscriptError(
                f"{where}: override {text[i:close + 1]!r} must follow a Chinese character or a "
                "Latin word, like 行{hang2}")
        if len(clean) - 1 in overrides:
            raise TranscriptError(f"{where}: a second override for {target!r}")
        overrides[len(clean) - 1] = tuple(_override_reading(t, where, target) for t in tokens)
        i = close + 1
    return "".join(clean), overrides


def _override_reading(token: str, where: str, target: str) -> str:
    """A user's reading: tone-numbered (hang2) or tone-marked (háng) -> tone-numbered."""
    reading = token.lower().replace("v", "ü")
    if not any(c.isdigit() for c in reading):
        if to_tone3(reading, v_to_u=True) == reading:
            raise TranscriptError(
                f"{where}: reading {token!r} for {target!r} has no tone; expected tone-numbered "
                "pinyin like hang2 (5 for the neutral tone)")
        reading = to_tone3(reading, v_to_u=True)
    try:
        syllable_parts(reading)
    except TranscriptError:
        raise TranscriptError(
            f"{where}: reading {token!r} for {target!r} is not a Mandarin syllable; expected "
            "tone-numbered pinyin like hang2") from None
    return reading


def _sentence_spans(clean: str) -> list[tuple[int, int]]:
    """Split at sentence ends; closing quotes and brackets stay with their sentence."""
    spans = []
    start = i = 0
    while i < len(clean):
        if _ends_sentence(clean, i):
            j = i + 1
            while j < len(clean) and (_ends_sentence(clean, j) or clean[j] in _CLOSERS):
                j += 1
            spans.append((start, j))
            start = i = j
        else:
            i += 1
    if start < len(clean):
        spans.append((start, len(clean)))
    return spans


def _ends_sentence(clean: str, i: int) -> bool:
    ch = clean[i]
    if ch == ".":
        return not (0 < i < len(clean) - 1 and _ascii(clean[i - 1]).isdigit()
                    and _ascii(clean[i + 1]).isdigit())
    return ch in _ENDS


def _ascii(ch: str) -> str:
    """Full-width ASCII forms (digits, letters, ％ － ．) -> ASCII; other characters unchanged."""
    if "\uff01" <= ch <= "\uff5e":
        return chr(ord(ch) - 0xFEE0)
    return ch


def _is_latin(ch: str) -> bool:
    return bool(ch) and "a" <= _ascii(ch).lower() <= "z"


def _read_sentence(clean: str, start: int, end: int,
                   overrides: dict[int, tuple[str, ...]]) -> _Sentence | None:
    """Tokenise one sentence span of the clean text into sandhi domains of units."""
    text = clean[start:end].strip()
    if not text:
        return None
    sentence = _Sentence(text)
    domain: list[_Unit] = []

    def close_domain() -> None:
        nonlocal domain
        if domain:
            sentence.units.append(domain)
            domain = []

    ascii_text = "".join(_ascii(c) for c in clean[start:end])
    i = start
    while i < end:
        ch, a = clean[i], ascii_text[i - start]
        if _HAN_RE.fullmatch(ch):
            reading = overrides.get(i, ("",))[0]
            domain.append(_Unit(ch, han=ch, reading=reading, no_sandhi=bool(reading)))
            i += 1
        elif a == "-" and _negative(ascii_text, i - start):
            domain.append(_Unit("负", han="负"))
            i += 1
        elif "0" <= a <= "9":
            number = _NUMBER_RE.match(ascii_text, i - start)
            spoken, by_digit = _number_words(number, ascii_text[number.end():number.end() + 2])
            domain.extend(_Unit(c, han=c, reading=_DIGIT_READINGS.get(c, "") if by_digit else "",
                                no_sandhi=by_digit) for c in spoken)
            i = start + number.end()
        elif _is_latin(ch):
            j = i
            while j < end and _is_latin(clean[j]):
                j += 1
            close_domain()
            domain.extend(_latin_units(clean[i:j], overrides.get(j - 1), sentence.notes))
            close_domain()
            i = j
        elif ch in _SYMBOL_READINGS:
            domain.extend(_Unit(c, han=c) for c in _SYMBOL_READINGS[ch])
            i += 1
        else:
            if ch in _PAUSES:
                close_domain()
                if sentence.units:
                    sentence.pause_after.add(len(sentence.units) - 1)
            elif not (ch in _ENDS or ch in _CLOSERS or ch == "." or ch.isspace()):
                category = unicodedata.category(ch)
                if category[0] in "SLN" or category == "Co":
                    close_domain()
                    kind = "emoji or symbol" if category[0] == "S" else "not Mandarin"
                    sentence.notes.append(f"dropped {ch!r} ({kind}, not spoken) in {text!r}")
            i += 1
    close_domain()
    return sentence


def _negative(ascii_text: str, k: int) -> bool:
    """A '-' at k is a minus sign: a digit follows and no letter or digit precedes."""
    after = ascii_text[k + 1:k + 2]
    before = ascii_text[k - 1:k] if k else ""
    return after.isdigit() and not (before.isascii() and before.isalnum())


def _number_words(match: re.Match[str], following: str) -> tuple[str, bool]:
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
    return cn2an.an2cn(str(int(whole)), "low")


def _latin_units(word: str, readings: tuple[str, ...] | None, notes: list[str]) -> list[_Unit]:
    """A Latin word: its override readings, spelled letter names for an acronym, or nothing.

    Acronyms: all capitals, at most _ACRONYM_MAX letters, or a single letter.
    """
    if readings:
        return [_Unit(word if k == 0 else "", reading=r, no_sandhi=True)
                for k, r in enumerate(readings)]
    letters = "".join(_ascii(c) for c in word)
    if len(letters) == 1 or (letters.isupper() and len(letters) <= _ACRONYM_MAX):
        units = []
        for shown, letter in zip(word, letters.upper()):
            units.extend(_Unit(shown if k == 0 else "", reading=r, no_sandhi=True)
                         for k, r in enumerate(_LETTERS[letter]))
        return units
    notes.append(f"skipped the Latin word {word!r}: not read as Mandarin (write it in Chinese, "
                 f"or give its readings like {word}{{ha1 lou2}}, one per syllable)")
    return []


@cache
def _t2s() -> OpenCC:
    return OpenCC("t2s")


def _finish_sentence(raw: _Sentence) -> SentenceText:
    """Look up readings, merge erhua, apply tone changes, then build the syllables."""
    syllables: list[SyllableText] = []
    notes = list(raw.notes)
    ends: set[int] = set()
    for d, domain in enumerate(raw.units):
        for unit in _tone_changes(_erhua(_look_up(domain, notes))):
            syllables.append(SyllableText(unit.text, unit.pinyin, _zhuyin(unit.pinyin),
                                          shapes_for(unit.pinyin)))
        if d in raw.pause_after and syllables:
            ends.add(len(syllables) - 1)
    clause_ends = tuple(sorted(e for e in ends if e < len(syllables) - 1))
    return SentenceText(raw.text, tuple(syllables), clause_ends, tuple(notes))


def _look_up(domain: list[_Unit], notes: list[str]) -> list[_Unit]:
    """Give every unit its dictionary reading and word index (pypinyin, phrase aware).

    Hanzi are converted to Simplified first (pypinyin's phrases are keyed on Simplified:
    銀行 would read yin2 xing2); the shown text keeps the original characters.
    """
    hans = "".join(u.han for u in domain if u.han)
    simplified = _t2s().convert(hans) if hans else ""
    if len(simplified) != len(hans):
        simplified = "".join(_t2s().convert(c) or c for c in hans)
    words = seg(simplified) if simplified else []
    spans = []
    for index, word in enumerate(words):
        readings = lazy_pinyin(word, style=Style.TONE3, neutral_tone_with_five=True, v_to_u=True)
        if len(readings) != len(word):
            readings = [_reading_of(c) for c in word]
        spans.extend((index, c, r) for c, r in zip(word, readings))
    out = []
    k = 0
    for unit in domain:
        if not unit.han:
            out.append(replace(unit, word=-1 - len(out), pinyin=unit.reading))  # a word of its own
            continue
        index, simple, reading = spans[k]
        k += 1
        if not _READING_RE.fullmatch(reading) and simple != unit.han:
            reading = _reading_of(unit.han)   # OpenCC maps a few rare characters beyond pypinyin
        reading = unit.reading or reading
        if not _READING_RE.fullmatch(reading):
            notes.append(f"no reading known for {unit.text!r}; skipped (give one like "
                         f"{unit.text}{{hang2}})")
            continue
        out.append(replace(unit, han=simple, word=index, pinyin=reading))
    return out


def _reading_of(han: str) -> str:
    """pypinyin's reading of one character, tone-numbered ("" when it has none)."""
    readings = lazy_pinyin(han, style=Style.TONE3, neutral_tone_with_five=True, v_to_u=True)
    return readings[0] if len(readings) == 1 else ""


def _erhua(units: list[_Unit]) -> list[_Unit]:
    """Merge the erhua suffix 儿 into the syllable before it (点儿 -> dianr3).

    儿 stays a syllable of its own at the start of a domain, with an override, after
    er itself, or where it is a word (女儿, 儿子: _REAL_ER_WORDS, _REAL_ER_NEXT).
    """
    out: list[_Unit] = []
    for k, unit in enumerate(units):
        prev = out[-1] if out else None
        nxt = units[k + 1].han if k + 1 < len(units) else ""
        if (unit.han == "儿" and not unit.reading and prev is not None and prev.han
                and prev.han + "儿" not in _REAL_ER_WORDS and nxt not in _REAL_ER_NEXT
                and not syllable_parts(prev.pinyin).erhua
                and syllable_parts(prev.pinyin).final != "er"):
            out[-1] = replace(prev, text=prev.text + unit.text,
                              pinyin=prev.pinyin[:-1] + "r" + prev.pinyin[-1])
        else:
            out.append(unit)
    return out


def _tone(unit: _Unit | None) -> int:
    return int(unit.pinyin[-1]) if unit is not None else 0


def _tone_changes(units: list[_Unit]) -> list[_Unit]:
    """Surface tones: 一 and 不 first (on citation tones), then third-tone sandhi.

    不 before a 4th tone is bu2 also in A-not-A questions (用不用 yong4 bu2 yong4), as
    Biaobei's readers say it. Units with no_sandhi (overrides, digit-by-digit numbers,
    spelled letters) keep their reading but are context for their neighbours.
    """
    out = list(units)
    for k, unit in enumerate(units):
        if unit.no_sandhi or unit.han not in ("一", "不") or unit.pinyin.endswith("5"):
            continue
        prev = units[k - 1] if k else None
        nxt = units[k + 1] if k + 1 < len(units) else None
        base = "yi" if unit.han == "一" else "bu"
        if unit.han == "一" and nxt is not None and prev is not None and prev.han == nxt.han:
            tone = 5    # A一A: 看一看
        elif unit.han == "一" and (nxt is None or (prev is not None and prev.han in _YI_FIRST_AFTER)
                                   or nxt.han in _DIGIT_CHARS):
            tone = 1    # final, ordinal, word-final, inside numbers
        elif nxt is None:
            tone = 4    # 不 alone keeps its tone
        elif _tone(nxt) == 4:
            tone = 2    # 一定 yi2 ding4, 不是 bu2 shi4
        elif _tone(nxt) == 5:
            continue    # keep the dictionary's reading
        else:
            tone = 4    # 一天 yi4, 一年 yi4, 一起 yi4; 不好 bu4
        out[k] = replace(unit, pinyin=_with_tone(unit.pinyin, tone) if unit.pinyin.startswith(base)
                         else unit.pinyin)
    return _third_tones(_reduplicated(out))


def _reduplicated(units: list[_Unit]) -> list[_Unit]:
    """A doubled third-tone syllable takes the neutral tone on its second half (姐姐 jie3 jie5,
    奶奶, 嫂嫂, 想想), except adjectives doubled as adverbs (_AA_KEEP: 好好, 早早)."""
    out = list(units)
    for k in range(len(units) - 1):
        a, b = units[k], units[k + 1]
        if (a.han and a.han == b.han and a.han not in _AA_KEEP and a.han not in _DIGIT_CHARS
                and not b.no_sandhi
                and _tone(a) == 3 and _tone(b) == 3
                and (k == 0 or units[k - 1].han != a.han)
                and (k + 2 == len(units) or units[k + 2].han != a.han)):
            out[k + 1] = replace(b, pinyin=_with_tone(b.pinyin, 5))
    return out


def _with_tone(pinyin: str, tone: int) -> str:
    return pinyin[:-1] + str(tone)


def _third_tones(units: list[_Unit]) -> list[_Unit]:
    """3-3 sandhi: a third tone before a third tone is said as a second tone.

    Grouped by words (pypinyin's phrase segmentation; characters outside its phrase
    dictionary count as one-character words). First, inside each word every third tone
    but the last of a run becomes second (你好 ni2 hao3, 所有 suo2 you3). Then across word
    boundaries, right to left, a word's last syllable becomes second when the syllable after
    it is (still) third: 小 老板 -> xiao3 lao2 ban3, 保管 好 -> bao2 guan2 hao3, 我 很 好 ->
    wo3 hen2 hao3. On Biaobei's surface tones this beat left-to-right grouping (bench
    transcript). A neutral tone blocks it.
    """
    out = list(units)
    for k in range(len(out) - 1):
        if out[k].word == out[k + 1].word and _tone(units[k]) == 3 and _tone(units[k + 1]) == 3:
            out[k] = _second(out[k])
    for k in range(len(out) - 2, -1, -1):
        if out[k].word != out[k + 1].word and _tone(out[k]) == 3 and _tone(out[k + 1]) == 3:
            out[k] = _second(out[k])
    return out


def _second(unit: _Unit) -> _Unit:
    return unit if unit.no_sandhi else replace(unit, pinyin=_with_tone(unit.pinyin, 2))


def _zhuyin(pinyin: str) -> str:
    """Tone-numbered pinyin -> Bopomofo with its tone mark; erhua adds ㄦ ("ㄉㄧㄢˇㄦ")."""
    parts = syllable_parts(pinyin)
    base = pinyin[:-2] + pinyin[-1] if parts.erhua else pinyin
    bopomofo = convert_style(to_tone(base), Style.BOPOMOFO, strict=True)
    return bopomofo + ("ㄦ" if parts.erhua else "")
