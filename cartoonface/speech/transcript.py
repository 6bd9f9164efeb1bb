"""Transcript text -> sentences -> spoken syllables (pinyin, zhuyin, mouth shapes).

Thesis 002, 3.3: "an entire transcript is segmented into sentences by punctuation marks"
and each character becomes its syllable; the thesis picked polyphone readings by hand, we
use pypinyin's phrase dictionary and let the user override a reading inline. This module
tokenises: sentence ends, inline overrides, Han characters, numbers, Latin words, emoji.
Numbers, symbols and Latin letters are read out by `normalise.py`; readings, erhua and
tone changes come from `readings.py`. Every rule is written out in
docs/mandarin-mouth-shapes.md.

Readings are the surface (spoken) tones, tone-numbered with 5 for the neutral tone and
"ü" for u-umlaut: "hang2", "ni2 hao3", "lü4", erhua "dianr3".

Emotion markup (docs/emotions.md): `[happy]` or `[happy 0.6]` before a sentence or inside
one sets that emotion (face/emotion.py EMOTIONS, intensity 0..1, default 1) to the end of
the sentence; with a closing `[/happy]` (or `[/]`, closing the latest open mark) it lasts
to there instead, across sentences. Marks are never read and never count as syllables;
`emotion_marks` returns them as spans of syllables.
"""

from __future__ import annotations

import itertools
import math
import unicodedata
from collections.abc import Callable
from dataclasses import dataclass, field, replace

from cartoonface.errors import TranscriptError
from cartoonface.face.emotion import EMOTIONS
from cartoonface.speech.mouth_shapes import shapes_for
from cartoonface.speech.normalise import (
    DIGIT_READINGS,
    NUMBER_RE,
    SYMBOL_READINGS,
    ascii_form,
    is_latin,
    latin_units,
    number_words,
)
from cartoonface.speech.pinyin import syllable_parts
from cartoonface.speech.readings import HAN_RE, Unit, erhua, look_up, position_of, tone_changes, zhuyin


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
_APOSTROPHES = frozenset("'\u2019")  # inside a Latin word: don't, it’s

# Emotion markup: a mark is replaced by this invisible character (a word joiner, which
# _read_sentence skips) so every position in the text stays where the user wrote it.
MARK_FILL = "\u2060"
MARK_CLOSE_ANY = "/"  # [/] closes the latest open mark



@dataclass
class _Sentence:
    text: str
    units: list[list[Unit]] = field(default_factory=list)   # one list per sandhi domain
    pause_after: set[int] = field(default_factory=set)        # domains a comma-like mark follows
    notes: list[str] = field(default_factory=list)
    english: int = 0                                          # units read from English words


def parse_transcript(text: str, source: str = "transcript") -> tuple[SentenceText, ...]:
    """Transcript text -> its sentences with their spoken syllables.

    text: the whole transcript (Simplified or Traditional Chinese, with optional inline
    overrides like 行{hang2}); source: the file or field name used in error messages.
    Raises TranscriptError for an empty transcript, a bad override (naming line, column
    and reading) or a transcript with no Mandarin syllable at all.
    """
    if not text.strip():
        raise TranscriptError(f"{source}: the transcript is empty; expected Mandarin text")
    text, _ = _strip_marks(text, source)
    clean, overrides, origin = _strip_overrides(text, source)
    sentences: list[SentenceText] = []
    pending_notes: list[str] = []
    mandarin = False  # a syllable not from an English word
    for start, end in _sentence_spans(clean):
        raw = _read_sentence(clean, start, end, overrides, lambda i: f"{source}: {position_of(text, origin[i])}")
        if raw is None:
            continue
        mandarin = mandarin or raw.english < sum(map(len, raw.units))
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
    if not sentences or not mandarin:
        raise TranscriptError(
            f"{source}: no Mandarin syllables found; expected Chinese text "
            "(English words, emoji and symbols alone are not a Mandarin transcript)")
    return tuple(sentences)


def _strip_overrides(text: str, source: str) -> tuple[str, dict[int, tuple[str, ...]], list[int]]:
    """Remove `{reading}` overrides; return the clean text, {index in it: readings} and the
    index in `text` of each character of the clean text.

    An override follows a Chinese character (one reading) or a Latin word (one or more,
    space-separated); the key is the index of that character or of the word's last letter.
    """
    clean: list[str] = []
    origin: list[int] = []
    overrides: dict[int, tuple[str, ...]] = {}
    i = 0
    while i < len(text):
        ch = text[i]
        if ch == "}":
            raise TranscriptError(f"{source}: {position_of(text, i)}: '}}' without an opening '{{'")
        if ch != "{":
            clean.append(ch)
            origin.append(i)
            i += 1
            continue
        close = text.find("}", i + 1)
        if close < 0 or any(c in "{\n" for c in text[i + 1:close]):
            raise TranscriptError(
                f"{source}: {position_of(text, i)}: '{{' without a closing '}}' on the same line; "
                "expected an override like 行{hang2}")
        where = f"{source}: {position_of(text, i)}"
        tokens = text[i + 1:close].split()
        target = clean[-1] if clean else ""
        if HAN_RE.fullmatch(target):
            if len(tokens) != 1:
                raise TranscriptError(
                    f"{where}: override {text[i:close + 1]!r} after {target!r} must give exactly "
                    "one reading, like 行{hang2}")
        elif not is_latin(target):
            raise TranscriptError(
                f"{where}: override {text[i:close + 1]!r} must follow a Chinese character or a "
                "Latin word, like 行{hang2}")
        if len(clean) - 1 in overrides:
            raise TranscriptError(f"{where}: a second override for {target!r}")
        overrides[len(clean) - 1] = tuple(_override_reading(t, where, target) for t in tokens)
        i = close + 1
    return "".join(clean), overrides, origin


def _override_reading(token: str, where: str, target: str) -> str:
    """A user's reading: tone-numbered (hang2) or tone-marked (háng) -> tone-numbered."""
    reading = token.lower().replace("v", "ü")
    if not any(c.isdigit() for c in reading):
        from pypinyin.contrib.tone_convert import to_tone3  # only for tone marks: pypinyin takes 0.2 s to import

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
        return not (0 < i < len(clean) - 1 and ascii_form(clean[i - 1]).isdigit()
                    and ascii_form(clean[i + 1]).isdigit())
    return ch in _ENDS


def _read_sentence(clean: str, start: int, end: int, overrides: dict[int, tuple[str, ...]],
                   locate: Callable[[int], str]) -> _Sentence | None:
    """Tokenise one sentence span of the clean text into sandhi domains of units;
    `locate(i)` names where index i of the clean text was written ("source: line L, column C")."""
    text = clean[start:end].replace(MARK_FILL, "").strip()
    if not text:
        return None
    sentence = _Sentence(text)
    domain: list[Unit] = []

    def close_domain() -> None:
        nonlocal domain
        if domain:
            sentence.units.append(domain)
            domain = []

    ascii_text = "".join(ascii_form(c) for c in clean[start:end])
    i = start
    while i < end:
        ch, a = clean[i], ascii_text[i - start]
        if HAN_RE.fullmatch(ch):
            reading = overrides.get(i, ("",))[0]
            domain.append(Unit(ch, han=ch, reading=reading, no_sandhi=bool(reading)))
            i += 1
        elif a == "-" and _negative(ascii_text, i - start):
            domain.append(Unit("负", han="负"))
            i += 1
        elif "0" <= a <= "9":
            number = NUMBER_RE.match(ascii_text, i - start)
            assert number is not None  # NUMBER_RE matches at every ASCII digit
            spoken, by_digit = number_words(number, ascii_text[number.end():number.end() + 2])
            domain.extend(Unit(c, han=c, reading=DIGIT_READINGS.get(c, "") if by_digit else "",
                                no_sandhi=by_digit) for c in spoken)
            i = start + number.end()
        elif is_latin(ch):
            j = i + 1
            while j < end and (is_latin(clean[j]) or (clean[j] in _APOSTROPHES and j + 1 < end
                                                      and is_latin(clean[j + 1]))):
                j += 1
            close_domain()
            units = latin_units(clean[i:j], overrides.get(j - 1), sentence.notes, locate(i))
            sentence.english += sum(bool(u.shapes) for u in units)
            domain.extend(units)
            close_domain()
            i = j
        elif ch in SYMBOL_READINGS:
            domain.extend(Unit(c, han=c) for c in SYMBOL_READINGS[ch])
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


def _finish_sentence(raw: _Sentence) -> SentenceText:
    """Look up readings, merge erhua, apply tone changes, then build the syllables."""
    syllables: list[SyllableText] = []
    notes = list(raw.notes)
    ends: set[int] = set()
    for d, domain in enumerate(raw.units):
        for unit in tone_changes(erhua(look_up(domain, notes))):
            syllables.append(SyllableText(unit.text, unit.pinyin, zhuyin(unit.pinyin),
                                          unit.shapes or shapes_for(unit.pinyin)))
        if d in raw.pause_after and syllables:
            ends.add(len(syllables) - 1)
    clause_ends = tuple(sorted(e for e in ends if e < len(syllables) - 1))
    return SentenceText(raw.text, tuple(syllables), clause_ends, tuple(notes))




@dataclass(frozen=True)
class EmotionMark:
    """An emotion the transcript's markup sets: `name` (EMOTIONS), `intensity` 0..1, over
    the syllables `first`..`last` (inclusive indices into all the transcript's syllables in
    order, as parse_transcript's sentences hold them); `where`: "line L, column C" of the mark."""

    name: str
    intensity: float
    first: int
    last: int
    where: str


@dataclass(frozen=True)
class _Tag:
    start: int  # index of '[' in the text
    end: int  # index after ']'
    name: str  # an emotion, or "" for a closing mark
    closes: str  # for a closing mark: the emotion it closes, or MARK_CLOSE_ANY
    intensity: float


def _strip_marks(text: str, source: str) -> tuple[str, list[_Tag]]:
    """The text with every emotion mark filled by MARK_FILL (same length), and the marks.
    TranscriptError naming line and column for a '[' without ']' on its line, a ']' without
    '[', an unknown emotion, or an intensity that is not a number from 0 to 1."""
    if "[" not in text and "]" not in text:
        return text, []
    tags: list[_Tag] = []
    out = list(text)
    i = 0
    while i < len(text):
        ch = text[i]
        if ch == "]":
            raise TranscriptError(f"{source}: {position_of(text, i)}: ']' without an opening '['; "
                                  "expected an emotion mark like [happy]")
        if ch != "[":
            i += 1
            continue
        close = text.find("]", i + 1)
        if close < 0 or any(c in "[\n" for c in text[i + 1:close]):
            raise TranscriptError(f"{source}: {position_of(text, i)}: '[' without a closing ']' on the same line; "
                                  "expected an emotion mark like [happy] or [happy 0.5]")
        tags.append(_tag(text[i + 1:close], i, close + 1, f"{source}: {position_of(text, i)}"))
        out[i:close + 1] = MARK_FILL * (close + 1 - i)
        i = close + 1
    return "".join(out), tags


def _tag(inside: str, start: int, end: int, where: str) -> _Tag:
    """The mark `[inside]` at text[start:end]; TranscriptError (prefixed by `where`) if broken."""
    words = inside.split()
    choices = ", ".join(EMOTIONS)
    if not words:
        raise TranscriptError(f"{where}: empty mark '[]'; expected an emotion mark like [happy] ({choices})")
    if words[0].startswith(MARK_CLOSE_ANY):
        closes = words[0][1:] or MARK_CLOSE_ANY
        if len(words) > 1 or (closes != MARK_CLOSE_ANY and closes not in EMOTIONS):
            raise TranscriptError(f"{where}: closing mark [{inside}]; expected [/] or [/NAME] with NAME one of "
                                  f"{choices}")
        return _Tag(start, end, "", closes, 0.0)
    name = words[0].lower()
    if name not in EMOTIONS:
        raise TranscriptError(f"{where}: unknown emotion {words[0]!r} in [{inside}]; expected one of {choices}")
    if len(words) > 2:
        raise TranscriptError(f"{where}: mark [{inside}]; expected [NAME] or [NAME INTENSITY] like [{name} 0.5]")
    intensity = 1.0
    if len(words) == 2:
        try:
            intensity = float(words[1])
        except ValueError:
            intensity = math.nan
        if not 0.0 <= intensity <= 1.0:
            raise TranscriptError(f"{where}: intensity {words[1]!r} in [{inside}]; expected a number from 0 to 1")
    return _Tag(start, end, name, "", intensity)


def emotion_marks(text: str, source: str = "transcript") -> tuple[EmotionMark, ...]:
    """The emotion marks of a transcript as syllable spans (see the module docstring).

    An open mark without its closing one lasts to the end of the sentence it stands in
    (or before). TranscriptError naming line and column for broken markup (see
    _strip_marks), a closing mark with nothing open to close, or a mark over no syllable.
    """
    filled, tags = _strip_marks(text, source)
    if not tags:
        return ()
    spans = _sentence_spans(filled)
    open_marks: list[_Tag] = []
    ranges: list[tuple[_Tag, int]] = []  # (opening tag, end position in the text)
    for tag in tags:
        if tag.name:
            open_marks.append(tag)
            continue
        match = [t for t in open_marks if tag.closes in (MARK_CLOSE_ANY, t.name)]
        if not match:
            raise TranscriptError(f"{source}: {position_of(text, tag.start)}: closing mark "
                                  f"[/{'' if tag.closes == MARK_CLOSE_ANY else tag.closes}] with no open mark "
                                  "to close; expected it after a mark like [happy]")
        open_marks.remove(match[-1])
        ranges.append((match[-1], tag.start))
    for tag in open_marks:
        ranges.append((tag, _sentence_end(filled, spans, tag.end)))
    cuts = sorted({p for tag, end in ranges for p in (tag.end, end)})
    counts = dict(zip(cuts, itertools.accumulate(_count(filled, a, b, source) for a, b in zip([0] + cuts, cuts)),
                      strict=True))
    marks = []
    for tag, end in sorted(ranges, key=lambda r: r[0].start):
        first, last = counts[tag.end], counts[end] - 1
        if last < first:
            raise TranscriptError(f"{source}: {position_of(text, tag.start)}: the mark [{tag.name}] stands over no "
                                  "spoken syllable; expected it before the words it colours")
        marks.append(EmotionMark(tag.name, tag.intensity, first, last, position_of(text, tag.start)))
    return tuple(marks)


def _sentence_end(filled: str, spans: list[tuple[int, int]], at: int) -> int:
    """The end of the sentence span holding the first character at or after `at` that is
    neither space nor a mark (the end of the text if none)."""
    while at < len(filled) and (filled[at].isspace() or filled[at] == MARK_FILL):
        at += 1
    for start, end in spans:
        if start <= at < end:
            return end
    return len(filled)


def _count(filled: str, first: int, last: int, source: str) -> int:
    """How many syllables `filled[first:last]` of a (mark-filled) transcript speaks."""
    clean, overrides, origin = _strip_overrides(filled[first:last], source)
    total = 0
    for start, end in _sentence_spans(clean):
        raw = _read_sentence(clean, start, end, overrides,
                             lambda i: f"{source}: {position_of(filled, first + origin[i])}")
        if raw is not None:
            total += len(_finish_sentence(raw).syllables)
    return total
