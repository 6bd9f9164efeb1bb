"""Readings of Chinese characters in context: dictionary look-up, erhua and tone sandhi.

Thesis 002, 3.3 picked polyphone readings by hand; we use pypinyin's phrase dictionary
(on Simplified characters; its answers as speech/lexicon.py's table) and then say the surface
tones: 一 and 不, doubled syllables, third-tone sandhi. docs/mandarin-mouth-shapes.md writes
every rule out. Readings are tone-numbered with 5 for the neutral tone and "ü" for u-umlaut:
"hang2", erhua "dianr3".
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace
from functools import cache

from opencc import OpenCC

from cartoonface.speech.lexicon import reading, readings, words, zhuyin_of
from cartoonface.speech.pinyin import syllable_parts

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

_READING_RE = re.compile(r"[a-zü]+r?[1-5]")
# Han characters: CJK Unified Ideographs with extensions A-H, compatibility ideographs, 〇.
HAN_RE = re.compile(r"[\u3007\u3400-\u4dbf\u4e00-\u9fff\uf900-\ufaff\U00020000-\U0003134f]")

@dataclass(frozen=True)
class Unit:
    """A syllable on its way: shown text, the Hanzi to look up (or ""), a fixed reading, and
    for a syllable of an English word the mouth shapes of its English phones (else ())."""

    text: str
    han: str = ""
    reading: str = ""
    no_sandhi: bool = False   # digit-by-digit numbers, spelled letters, overrides, English words
    word: int = 0
    pinyin: str = ""
    shapes: tuple[str, ...] = ()


@cache
def _t2s() -> OpenCC:
    return OpenCC("t2s")


def to_simplified(hans: str) -> str:
    """Hanzi `hans` in Simplified characters, one for one (pypinyin's phrases are keyed on
    Simplified: 銀行 would read yin2 xing2 and not be found as a word)."""
    simplified = _t2s().convert(hans) if hans else ""
    if len(simplified) != len(hans):
        simplified = "".join(_t2s().convert(c) or c for c in hans)
    return simplified


def look_up(domain: list[Unit], notes: list[str]) -> list[Unit]:
    """Give every unit its dictionary reading and word index (pypinyin, phrase aware).

    Hanzi are converted to Simplified first (pypinyin's phrases are keyed on Simplified:
    銀行 would read yin2 xing2); the shown text keeps the original characters.
    """
    hans = "".join(u.han for u in domain if u.han)
    simplified = to_simplified(hans)
    spans: list[tuple[int, str, str]] = []
    for index, word in enumerate(words(simplified) if simplified else []):
        spans.extend((index, c, r) for c, r in zip(word, readings(word)))
    out: list[Unit] = []
    k = 0
    for unit in domain:
        if not unit.han:
            out.append(replace(unit, word=-1 - len(out), pinyin=unit.reading))  # a word of its own
            continue
        index, simple, said = spans[k]
        k += 1
        if not _READING_RE.fullmatch(said) and simple != unit.han:
            said = reading(unit.han)   # OpenCC maps a few rare characters beyond pypinyin
        said = unit.reading or said
        if not _READING_RE.fullmatch(said):
            notes.append(f"no reading known for {unit.text!r}; skipped (give one like "
                         f"{unit.text}{{hang2}})")
            continue
        out.append(replace(unit, han=simple, word=index, pinyin=said))
    return out


def position_of(text: str, index: int) -> str:
    """Where `index` of `text` is, as a person counts: "line L, column C" (both from 1)."""
    line = text.count("\n", 0, index) + 1
    column = index - (text.rfind("\n", 0, index) + 1) + 1
    return f"line {line}, column {column}"


def erhua(units: list[Unit]) -> list[Unit]:
    """Merge the erhua suffix 儿 into the syllable before it (点儿 -> dianr3).

    儿 stays a syllable of its own at the start of a domain, with an override, after
    er itself, or where it is a word (女儿, 儿子: _REAL_ER_WORDS, _REAL_ER_NEXT).
    """
    out: list[Unit] = []
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


def _tone(unit: Unit | None) -> int:
    return int(unit.pinyin[-1]) if unit is not None else 0


def tone_changes(units: list[Unit]) -> list[Unit]:
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


def _reduplicated(units: list[Unit]) -> list[Unit]:
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


def _third_tones(units: list[Unit]) -> list[Unit]:
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


def _second(unit: Unit) -> Unit:
    return unit if unit.no_sandhi else replace(unit, pinyin=_with_tone(unit.pinyin, 2))


@cache  # a few hundred distinct syllables recur through a text
def zhuyin(pinyin: str) -> str:
    """Tone-numbered pinyin -> Bopomofo with its tone mark; erhua adds ㄦ ("ㄉㄧㄢˇㄦ")."""
    parts = syllable_parts(pinyin)
    base = pinyin[:-2] + pinyin[-1] if parts.erhua else pinyin
    bopomofo = zhuyin_of(base)
    if bopomofo is None:  # a spelling no character has (a reading in the transcript, an English syllable)
        from cartoonface.speech.lexicon_build import pypinyin_zhuyin  # pypinyin (0.2 s to import) only then

        bopomofo = pypinyin_zhuyin(base)
    return bopomofo + ("ㄦ" if parts.erhua else "")
