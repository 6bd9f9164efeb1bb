"""Praat TextGrid output and input of an alignment, so it can be checked and corrected in Praat.

Three interval tiers: `sentences` (the sentence text), `syllables` (the
character and its tone-numbered pinyin, `你 ni3`; only the pinyin when the
text is the pinyin itself) and `mouth shapes` (one interval per basic mouth
shape, starting at the in-syllable onsets of thesis 002, section 5.3). Empty
intervals fill the time between labelled ones, as Praat requires.

Reading accepts Praat's long and short text formats, in UTF-8 or (`load_textgrid`)
UTF-16, which Praat uses when saving Chinese text. Sentences and
syllables come from their tiers; a syllable's shapes from the labels of the
`mouth shapes` intervals inside it (their boundaries are not kept: the onsets
are always those of 5.3), or from its pinyin when that tier is absent.
Confidence is not stored: syllables read back have confidence 1 (checked by
a person). See docs/alignment.md.
"""

from __future__ import annotations

import codecs
import os
import re
from dataclasses import dataclass, replace
from pathlib import Path

from cartoonface.errors import AlignmentError, TranscriptError
from cartoonface.speech.english import HELD, PHONE_SHAPE
from cartoonface.speech.records import Alignment, Sentence, Syllable, check_times
from cartoonface.speech.mouth_shapes import MOUTH_SYMBOLS, shape_onsets, shapes_for

TIERS = ("sentences", "syllables", "mouth shapes")
# An English alignment (its records are ARPAbet phones, speech/english.py) has words and phones instead of syllables.
ENGLISH_TIERS = ("sentences", "words", "phones", "mouth shapes")
# Times are written with 6 decimals (1 microsecond): a round trip keeps every time to the ms.
_DECIMALS = 6
# Boundary slack when placing syllables in sentences and shapes in syllables (seconds).
_SLACK = 1e-4


@dataclass(frozen=True)
class Interval:
    """One interval of a tier: `start`, `end` seconds (0 <= start <= end), `text` ("" when unlabelled)."""

    start: float
    end: float
    text: str

    def __post_init__(self) -> None:
        check_times(self.start, self.end, f"interval {self.text!r}")


# An interval to write: (start s, end s, text). Plain tuples, not Intervals: they are made from the
# alignment's records, whose times are checked already, and thousands are made per minute (issue 16).
Span = tuple[float, float, str]


def write_textgrid(alignment: Alignment) -> str:
    """The alignment as a Praat TextGrid in the long text format; returns its text (UTF-8 to write)."""
    sentences = [(s.start, s.end, s.text) for s in alignment.sentences]
    syllables = []
    shapes: list[Span] = []
    for sentence in alignment.sentences:
        for syllable in sentence.syllables:
            syllables.append((syllable.start, syllable.end, _syllable_label(syllable)))
            shapes += _shape_intervals(syllable)
    duration = max([alignment.duration] + [end for _, end, _ in sentences])
    if is_english(alignment):
        records = [s for sentence in alignment.sentences for s in sentence.syllables]
        words = _word_intervals(records)
        phones = [(s.start, s.end, s.pinyin) for s in records]
        shapes = [(s.start, s.end, s.shapes[0]) for s in records]  # one shape per phone (english.HELD)
        named = zip(ENGLISH_TIERS, (sentences, words, phones, shapes), strict=True)
    else:
        named = zip(TIERS, (sentences, syllables, shapes), strict=True)
    tiers = [(name, _fill(items, duration)) for name, items in named]
    lines = [
        'File type = "ooTextFile"',
        'Object class = "TextGrid"',
        "",
        "xmin = 0 ",
        f"xmax = {_number(duration)} ",
        "tiers? <exists> ",
        f"size = {len(tiers)} ",
        "item []: ",
    ]
    for number, (name, intervals) in enumerate(tiers, start=1):
        lines += [
            f"    item [{number}]:",
            '        class = "IntervalTier" ',
            f"        name = {_quote(name)} ",
            "        xmin = 0 ",
            f"        xmax = {_number(duration)} ",
            f"        intervals: size = {len(intervals)} ",
        ]
        for index, (start, end, text) in enumerate(intervals, start=1):
            lines += [
                f"        intervals [{index}]:",
                f"            xmin = {_number(start)} ",
                f"            xmax = {_number(end)} ",
                f"            text = {_quote(text)} ",
            ]
    return "\n".join(lines) + "\n"


def is_english(alignment: Alignment) -> bool:
    """True when the alignment's records are English phones (ARPAbet, english.PHONE_SHAPE), not syllables."""
    records = [s for sentence in alignment.sentences for s in sentence.syllables]
    return bool(records) and all(s.pinyin in PHONE_SHAPE for s in records)


def _word_intervals(phones: list[Syllable]) -> list[Span]:
    """English words from phone records: a word starts at a record with text and ends with the last
    phone before the next word's."""
    words: list[Span] = []
    for phone in phones:
        if phone.text or not words:
            words.append((phone.start, phone.end, phone.text))
        else:
            words[-1] = (words[-1][0], phone.end, words[-1][2])
    return words


def _syllable_label(syllable: Syllable) -> str:
    """`text pinyin`, or only the pinyin when the text is empty, the pinyin itself or holds a space."""
    if not syllable.text or syllable.text == syllable.pinyin or " " in syllable.text:
        return syllable.pinyin
    return f"{syllable.text} {syllable.pinyin}"


def _shape_intervals(syllable: Syllable) -> list[Span]:
    """The syllable's mouth shapes as intervals starting at the onsets of thesis 002, 5.3."""
    if not syllable.shapes:
        return []
    length = syllable.end - syllable.start
    starts = [syllable.start + fraction * length for fraction in shape_onsets(len(syllable.shapes))]
    ends = starts[1:] + [syllable.end]
    return list(zip(starts, ends, syllable.shapes, strict=True))


def _fill(items: list[Span], duration: float) -> list[Span]:
    """Labelled intervals with empty ones between them, covering 0..duration without gaps."""
    filled: list[Span] = []
    position = 0.0
    reached = 0.0  # _rounded(position)
    for item_start, item_end, text in items:
        start = max(item_start, position)
        begun = _rounded(start)
        if begun > reached:
            filled.append((position, start, ""))
        ended = _rounded(item_end)
        if ended > begun:
            filled.append((start, item_end, text))
            position, reached = item_end, ended
    if _rounded(duration) > reached:
        filled.append((position, duration, ""))
    return filled


def _rounded(value: float) -> float:
    return round(value, _DECIMALS)


def _number(value: float) -> str:
    """A time with at most 6 decimals, without trailing zeros (`0`, `1.25`)."""
    text = f"{value:.{_DECIMALS}f}".rstrip("0").rstrip(".")
    return "0" if text in ("", "-0") else text


def _quote(text: str) -> str:
    """A Praat string literal: double quotes, inner quotes doubled, one line."""
    return '"' + " ".join(text.splitlines()).replace('"', '""') + '"'


# Praat's text formats: strings, numbers and <flags>; every other word (xmin =, item [1]:) is a comment.
_TOKEN = re.compile(
    r'"(?P<string>(?:[^"]|"")*)"'
    r"|(?P<skip>\[\s*\d*\s*\]|![^\n]*)"
    r"|(?P<flag><[A-Za-z]+>)"
    r"|(?P<number>[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)(?![\w.])"
    r"|(?P<word>[^\s\"]+)"
)


@dataclass(frozen=True)
class _Token:
    kind: str
    value: str
    line: int


class _Reader:
    """Reads the values of a TextGrid in order, with the line of each for error messages."""

    def __init__(self, text: str, source: str) -> None:
        self.source = source
        self.tokens = []
        for match in _TOKEN.finditer(text):
            kind = match.lastgroup
            if kind is None or kind in ("skip", "word"):
                continue
            line = text.count("\n", 0, match.start()) + 1
            value = match.group(kind)
            self.tokens.append(_Token(kind, value.replace('""', '"') if kind == "string" else value, line))
        self.position = 0

    def fail(self, what: str) -> AlignmentError:
        if self.position < len(self.tokens):
            token = self.tokens[self.position]
            found = f'"{token.value}"' if token.kind == "string" else token.value
            return AlignmentError(f"{self.source}, line {token.line}: expected {what}, found {found}")
        return AlignmentError(f"{self.source}: the TextGrid ends early; expected {what}")

    def next(self, kind: str, what: str) -> _Token:
        if self.position >= len(self.tokens) or self.tokens[self.position].kind != kind:
            raise self.fail(what)
        token = self.tokens[self.position]
        self.position += 1
        return token

    def string(self, what: str) -> str:
        return self.next("string", what).value

    def number(self, what: str) -> float:
        return float(self.next("number", what).value)

    def count(self, what: str) -> int:
        token = self.next("number", what)
        if not token.value.isdigit():
            self.position -= 1
            raise self.fail(what)
        return int(token.value)


def load_textgrid(path: str | os.PathLike[str]) -> Alignment:
    """Read the TextGrid file at `path` into an Alignment (see read_textgrid).

    Accepts UTF-8 (with or without a BOM) and UTF-16 with a BOM, which is what
    Praat writes for text outside Latin-1 such as Chinese. Raises
    AlignmentError when the file is missing or cannot be decoded.
    """
    file = Path(path)
    try:
        data = file.read_bytes()
    except FileNotFoundError:
        raise AlignmentError(f"{file}: no such TextGrid file") from None
    except OSError as exc:
        raise AlignmentError(f"{file}: cannot read the TextGrid ({exc.strerror})") from None
    encoding = "utf-16" if data[:2] in (codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE) else "utf-8-sig"
    try:
        text = data.decode(encoding)
    except UnicodeDecodeError:
        raise AlignmentError(f"{file}: not a text file in UTF-8 or UTF-16; expected a Praat TextGrid") from None
    return read_textgrid(text, str(file))


def read_textgrid(text: str, source: str) -> Alignment:
    """Parse a TextGrid `text` (long or short format) read from `source` into an Alignment.

    Raises AlignmentError naming `source`, the line or tier and what was
    expected, when the file is not an interval TextGrid with the tiers
    `sentences` and `syllables`, when intervals are out of order, or when a
    syllable lies outside every sentence.
    """
    duration, tiers = read_tiers(text, source)
    english = "syllables" not in tiers and "phones" in tiers
    if english:
        tiers["syllables"] = _phone_syllables(tiers, source)
    for name in TIERS[:2]:
        if name not in tiers:
            raise AlignmentError(f"{source}: no interval tier named {name!r}; expected tiers {', '.join(TIERS)}")
    labelled = {name: [item for item in items if item.text] for name, items in tiers.items()}
    alignment = _alignment(labelled, duration, source)
    if not english:
        return alignment
    # A phone inside a word (labelled with the phone alone) has no text, as english.py makes it.
    sentences = tuple(replace(sentence, syllables=tuple(_english_phone(s) for s in sentence.syllables))
                      for sentence in alignment.sentences)
    return replace(alignment, sentences=sentences)


def _english_phone(record: Syllable) -> Syllable:
    """A phone record read back as english.py makes it: no text inside a word (the label was the
    phone alone), its one shape held (english.phone_shapes)."""
    text = "" if record.text == record.pinyin else record.text
    return replace(record, text=text, shapes=(record.shapes[0],) * HELD)


def _phone_syllables(tiers: dict[str, list[Interval]], source: str) -> list[Interval]:
    """The labelled intervals of an English `phones` tier as syllable intervals `word PHONE` (the word
    on the phone where a `words` interval starts). Without a `mouth shapes` tier one is added from
    the phones (english.PHONE_SHAPE). AlignmentError naming a label that is not an ARPAbet phone."""
    starts = {_rounded(item.start): item.text for item in tiers.get("words", []) if item.text}
    syllables, shapes = [], []
    for item in tiers["phones"]:
        if not item.text:
            continue
        if item.text not in PHONE_SHAPE:
            raise AlignmentError(f"{source}: tier phones, label {item.text!r} at {item.start:g} s; expected an "
                                 f"ARPAbet phone ({' '.join(sorted(PHONE_SHAPE))})")
        word = starts.get(_rounded(item.start), "")
        syllables.append(Interval(item.start, item.end, f"{word} {item.text}" if word else item.text))
        shapes.append(Interval(item.start, item.end, PHONE_SHAPE[item.text]))
    tiers.setdefault(TIERS[2], shapes)
    return syllables


def read_tiers(text: str, source: str) -> tuple[float, dict[str, list[Interval]]]:
    """Parse any interval TextGrid `text` (long or short format) read from `source`.

    Returns (xmax of the TextGrid in seconds, {tier name: every interval in time order,
    labels stripped, "" for an unlabelled one}); point tiers are skipped. Raises
    AlignmentError naming `source` and the line when the text is not a TextGrid or an
    interval is empty, negative or overlaps the one before.
    """
    reader = _Reader(text, source)
    if reader.string('"ooTextFile" (a Praat text file)') != "ooTextFile":
        reader.position -= 1
        raise reader.fail('"ooTextFile" (a Praat text file)')
    if reader.string('"TextGrid"') != "TextGrid":
        reader.position -= 1
        raise reader.fail('"TextGrid"')
    reader.number("xmin of the TextGrid")
    duration = reader.number("xmax of the TextGrid")
    if reader.next("flag", "<exists>").value != "<exists>":
        raise AlignmentError(f"{source}: the TextGrid has no tiers; expected {', '.join(TIERS)}")
    tiers: dict[str, list[Interval]] = {}
    for _ in range(reader.count("the number of tiers")):
        kind = reader.string('the tier class "IntervalTier"')
        name = reader.string("the tier name")
        reader.number(f"xmin of tier {name}")
        reader.number(f"xmax of tier {name}")
        size = reader.count(f"the number of intervals in tier {name}")
        if kind == "TextTier":  # point tiers are allowed and ignored
            for _ in range(size):
                reader.number(f"a point time in tier {name}")
                reader.string(f"a point label in tier {name}")
            continue
        if kind != "IntervalTier":
            reader.position -= 5
            raise reader.fail('"IntervalTier" or "TextTier"')
        tiers[name] = _read_intervals(reader, name, size)
    return duration, tiers


def _read_intervals(reader: _Reader, name: str, size: int) -> list[Interval]:
    """Read `size` intervals of tier `name` in time order, labels stripped."""
    intervals = []
    previous = None
    for index in range(1, size + 1):
        line = reader.tokens[reader.position].line if reader.position < len(reader.tokens) else 0
        start = reader.number(f"xmin of interval {index} of tier {name}")
        end = reader.number(f"xmax of interval {index} of tier {name}")
        label = reader.string(f"the text of interval {index} of tier {name}")
        if end <= start or (previous is not None and start < previous - _SLACK):
            raise AlignmentError(
                f"{reader.source}, line {line}: tier {name}, interval {index} ({start:g}-{end:g} s) "
                "is empty or overlaps the one before; expected increasing times"
            )
        previous = end
        try:
            intervals.append(Interval(start, end, label.strip()))
        except ValueError as exc:
            raise AlignmentError(f"{reader.source}, line {line}: tier {name}, {exc}") from None
    return intervals


def _alignment(tiers: dict[str, list[Interval]], duration: float, source: str) -> Alignment:
    """Build the Alignment from the labelled intervals of each tier."""
    shapes = tiers.get(TIERS[2], [])
    sentences = []
    pending = list(tiers["syllables"])
    for sentence in tiers["sentences"]:
        inside = [s for s in pending if s.start >= sentence.start - _SLACK and s.end <= sentence.end + _SLACK]
        pending = [s for s in pending if s not in inside]
        syllables = tuple(_syllable(item, shapes, source) for item in inside)
        try:
            sentences.append(Sentence(sentence.text, sentence.start, sentence.end, syllables))
        except ValueError as exc:
            raise AlignmentError(f"{source}: tier sentences, {exc}") from None
    if pending:
        item = pending[0]
        raise AlignmentError(
            f"{source}: tier syllables, interval {item.text!r} ({item.start:g}-{item.end:g} s) lies outside "
            "every interval of tier sentences; expected each syllable inside a sentence"
        )
    try:
        return Alignment(tuple(sentences), duration, (f"timing read from {source}",))
    except ValueError as exc:
        raise AlignmentError(f"{source}: {exc}") from None


def _syllable(item: Interval, shapes: list[Interval], source: str) -> Syllable:
    """A syllable from its `text pinyin` label, with the shape labels inside it (or from its pinyin)."""
    text, _, pinyin = item.text.rpartition(" ")
    text = text.strip() or pinyin
    inside = tuple(s.text for s in shapes if s.start >= item.start - _SLACK and s.end <= item.end + _SLACK)
    for symbol in inside:
        if symbol not in MOUTH_SYMBOLS:
            raise AlignmentError(
                f"{source}: tier mouth shapes, label {symbol!r} at {item.start:g} s; "
                f"expected one of {' '.join(MOUTH_SYMBOLS)}"
            )
    if len(inside) > 4:
        raise AlignmentError(
            f"{source}: tier mouth shapes, {len(inside)} shapes in syllable {item.text!r} at {item.start:g} s; "
            "expected 1 to 4"
        )
    if not inside:
        try:
            inside = shapes_for(pinyin)
        except TranscriptError as exc:
            raise AlignmentError(
                f"{source}: tier syllables, label {item.text!r} at {item.start:g} s: {exc}; "
                "expected `text pinyin` such as `你 ni3`, or a mouth shapes tier"
            ) from None
    try:
        return Syllable(text, pinyin, inside, item.start, item.end, 1.0)
    except ValueError as exc:
        raise AlignmentError(f"{source}: tier syllables, {exc}") from None
