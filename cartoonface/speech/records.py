"""The records of a timed transcript (Syllable, Sentence, Alignment) and their JSON form.

Each record checks itself when made: a bad one raises ValueError naming the field and
value; readers of user files (speech/textgrid.py) catch it and name the file.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from cartoonface.speech.mouth_shapes import MOUTH_SYMBOLS

# Thesis 002, 5.3: a syllable has at most four basic mouth shapes.
MAX_SHAPES = 4


def check_times(start: float, end: float, what: str) -> None:
    """Raise ValueError unless `start` and `end` (seconds) are finite and 0 <= start <= end.

    `what` names the record in the message ("syllable 'ni3'").
    """
    if not (math.isfinite(start) and math.isfinite(end)):
        raise ValueError(f"{what}: times {start!r}-{end!r} s; expected finite seconds")
    if start < 0:
        raise ValueError(f"{what}: start {start:g} s; expected 0 or later")
    if end < start:
        raise ValueError(f"{what}: ends at {end:g} s before it starts at {start:g} s; expected start <= end")


@dataclass(frozen=True)
class Syllable:
    """One spoken syllable: `text` (its character), tone-numbered `pinyin`, `shapes` (1-4 mouth-shape
    symbols), `start`/`end` seconds, `confidence` 0..1 of its timing."""

    text: str
    pinyin: str
    shapes: tuple[str, ...]
    start: float
    end: float
    confidence: float

    def __post_init__(self) -> None:
        what = f"syllable {self.pinyin!r} ({self.text!r})"
        if not self.pinyin.strip():
            raise ValueError(f"syllable {self.text!r}: empty pinyin; expected a reading like ni3")
        check_times(self.start, self.end, what)
        if not (math.isfinite(self.confidence) and 0.0 <= self.confidence <= 1.0):
            raise ValueError(f"{what}: confidence {self.confidence!r}; expected 0 to 1")
        if len(self.shapes) > MAX_SHAPES:
            raise ValueError(f"{what}: {len(self.shapes)} mouth shapes; expected at most {MAX_SHAPES}")
        for shape in self.shapes:
            if shape not in MOUTH_SYMBOLS:
                raise ValueError(f"{what}: mouth shape {shape!r}; expected one of {' '.join(MOUTH_SYMBOLS)}")


@dataclass(frozen=True)
class Sentence:
    """One transcript sentence: its `text`, `start`/`end` seconds, its syllables in order."""

    text: str
    start: float
    end: float
    syllables: tuple[Syllable, ...]

    def __post_init__(self) -> None:
        what = f"sentence {self.text!r}"
        if not self.text.strip():
            raise ValueError(f"sentence at {self.start!r} s: empty text; expected the sentence as written")
        check_times(self.start, self.end, what)
        for earlier, later in zip(self.syllables, self.syllables[1:]):
            if later.start < earlier.start:
                raise ValueError(f"{what}: syllable {later.pinyin!r} at {later.start:g} s starts before "
                                 f"{earlier.pinyin!r} at {earlier.start:g} s; expected syllables in time order")


@dataclass(frozen=True)
class Alignment:
    """Sentences in time order over a recording of `duration` seconds; `notes` tell the user what was
    merged, split or flagged while aligning."""

    sentences: tuple[Sentence, ...]
    duration: float
    notes: tuple[str, ...]

    def __post_init__(self) -> None:
        check_times(0.0, self.duration, "alignment duration")
        for earlier, later in zip(self.sentences, self.sentences[1:]):
            if later.start < earlier.start:
                raise ValueError(f"sentence {later.text!r} at {later.start:g} s starts before {earlier.text!r} "
                                 f"at {earlier.start:g} s; expected sentences in time order")


# Rounding slack for the confidence's hundredths: 0.29 * 100 is 28.999999999999996 in floats.
FLOOR_SLACK = 1e-9


def alignment_to_dict(alignment: Alignment) -> dict:
    """The alignment as JSON-ready data (format "cartoonface-alignment", version 1; docs/alignment.md).

    Times are seconds rounded to the millisecond, confidence rounded down to 0.01 (a syllable
    below the low-confidence threshold, a multiple of 0.01, stays below it when read back).
    """
    return {
        "format": "cartoonface-alignment",
        "version": 1,
        "duration": round(alignment.duration, 3),
        "notes": list(alignment.notes),
        "sentences": [
            {
                "text": sentence.text,
                "start": round(sentence.start, 3),
                "end": round(sentence.end, 3),
                "syllables": [
                    {
                        "text": s.text,
                        "pinyin": s.pinyin,
                        "shapes": list(s.shapes),
                        "start": round(s.start, 3),
                        "end": round(s.end, 3),
                        "confidence": math.floor(s.confidence * 100 + FLOOR_SLACK) / 100,
                    }
                    for s in sentence.syllables
                ],
            }
            for sentence in alignment.sentences
        ],
    }


