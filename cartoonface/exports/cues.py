"""Mouth cues in the output formats of Rhubarb Lip Sync (TSV, JSON, XML with its shapes A-H and X).

Rhubarb Lip Sync's README ("Mouth shapes", "Output formats") defines nine mouth shapes and
three files that tools and plugins (After Effects, Spine, Godot, Blender, ...) read. Each
of the twelve Mandarin shapes (thesis 002, 5.2.2; face/mouth.py) becomes the Rhubarb
shape that looks most like it (RHUBARB_SHAPE; docs/exports.md gives the reasons); time
without a syllable is X. Cues follow the alignment's `mouth shapes` tier (the shapes of
each syllable at the onsets of thesis 002, 5.3), so they agree with alignment.TextGrid.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from html import escape  # with quote=False: & < > as xml.sax.saxutils.escape (which imports urllib.request)

from cartoonface.speech.mouth_shapes import shape_onsets
from cartoonface.speech.records import Alignment

# Rhubarb's README, "Mouth shapes": A closed (P B M), B slightly open with clenched teeth
# (most consonants, EE), C open (EH, AE), D wide open (AA), E slightly rounded (AO, ER),
# F puckered (UW, OW, W), G upper teeth on the lower lip (F, V), H tongue raised behind the
# upper teeth (long L), X idle, mouth at rest.
RHUBARB_SHAPES = ("A", "B", "C", "D", "E", "F", "G", "H", "X")
REST = "X"
# The twelve shapes of thesis 002, 5.2.2 (face/mouth.py MOUTH_SHAPES) -> Rhubarb's; docs/exports.md.
RHUBARB_SHAPE: dict[str, str] = {
    "m": "A",   # b p m: lips shut
    "f": "G",   # upper teeth resting on the lower lip
    "h'": "B",  # d t n l j q x: narrow opening, teeth close
    "h": "C",   # g k h, e eng er: medium oval
    "r": "B",   # zh ch sh r: teeth close, lips slightly rounded
    "z": "B",   # z c s: teeth almost closed
    "a": "D",   # wide open, jaw dropped
    "i": "B",   # spread lips, teeth nearly together (Rhubarb's EE)
    "u": "F",   # small and puckered
    "e": "C",   # mid-spread, half open (Rhubarb's EH)
    "o": "E",   # round, corners in
    "n": "H",   # open, the tongue tip up behind the upper teeth
}
FORMATS = ("tsv", "json", "xml")
CUES_STEM = "mouth-cues"
# Rhubarb writes times in whole hundredths of a second (README, "Output formats").
CENTISECONDS = 100
# Float slack when truncating a duration to hundredths (1.23 s stored as 1.2299999...).
TRUNCATE_SLACK = 1e-6


@dataclass(frozen=True)
class Cue:
    """One mouth cue: Rhubarb shape `value` from `start` to `end`, whole hundredths of a second."""

    start: int
    end: int
    value: str


def mouth_cues(alignment: Alignment) -> tuple[Cue, ...]:
    """The alignment's mouth shapes as Rhubarb cues covering 0 .. the duration (truncated to 0.01 s).

    Every syllable's shapes start at the onsets of thesis 002, 5.3; gaps are X. Boundaries are
    rounded to hundredths; cues left empty by the rounding are dropped and equal neighbours
    merged, so the cues tile the timeline in order, each at least 0.01 s long.
    """
    end = _truncated(alignment.duration)
    marks: list[tuple[int, str]] = [(0, REST)]
    for sentence in alignment.sentences:
        for syllable in sentence.syllables:
            if not syllable.shapes:
                continue
            length = syllable.end - syllable.start
            for fraction, shape in zip(shape_onsets(len(syllable.shapes)), syllable.shapes, strict=True):
                marks.append((_hundredths(syllable.start + fraction * length), RHUBARB_SHAPE[shape]))
            marks.append((_hundredths(syllable.end), REST))
    cues: list[Cue] = []
    for index, (start, value) in enumerate(marks):
        stop = min(marks[index + 1][0] if index + 1 < len(marks) else end, end)
        start = max(start, cues[-1].end if cues else 0)
        if stop <= start:
            continue
        if cues and cues[-1].value == value:
            cues[-1] = Cue(cues[-1].start, stop, value)
        else:
            cues.append(Cue(start, stop, value))
    return tuple(cues)


def _hundredths(seconds: float) -> int:
    """Seconds -> the nearest whole hundredth."""
    return round(seconds * CENTISECONDS)


def _truncated(seconds: float) -> int:
    """Seconds -> whole hundredths, truncated (Rhubarb truncates the duration)."""
    return math.floor(seconds * CENTISECONDS + TRUNCATE_SLACK)


def _seconds(hundredths: int) -> str:
    """Hundredths of a second -> '1.25' (two decimals, as Rhubarb writes them)."""
    return f"{hundredths // CENTISECONDS}.{hundredths % CENTISECONDS:02d}"


def cues_text(cues: tuple[Cue, ...], duration: float, fmt: str, sound_file: str) -> str:
    """The cues as the text of a Rhubarb output file in `fmt` ("tsv", "json" or "xml").

    `duration` (seconds, truncated to 0.01 s) and `sound_file` (the recording's name) fill
    the metadata of JSON and XML; TSV ends with a line at the duration with a closed mouth.
    Raises ValueError for another format.
    """
    total = _truncated(duration)
    if fmt == "tsv":
        lines = [f"{_seconds(cue.start)}\t{cue.value}" for cue in cues]
        return "\n".join(lines + [f"{_seconds(total)}\t{REST}"]) + "\n"
    if fmt == "json":
        rows = ",\n".join(f'    {{ "start": {_seconds(c.start)}, "end": {_seconds(c.end)}, "value": "{c.value}" }}'
                          for c in cues)
        return ('{\n  "metadata": {\n'
                f'    "soundFile": {json.dumps(sound_file, ensure_ascii=False)},\n'
                f'    "duration": {_seconds(total)}\n  }},\n'
                f'  "mouthCues": [\n{rows}\n  ]\n}}\n')
    if fmt == "xml":
        rows = "\n".join(f'    <mouthCue start="{_seconds(c.start)}" end="{_seconds(c.end)}">{c.value}</mouthCue>'
                         for c in cues)
        return ('<?xml version="1.0" encoding="utf-8"?>\n<rhubarbResult>\n  <metadata>\n'
                f"    <soundFile>{escape(sound_file, quote=False)}</soundFile>\n    <duration>{_seconds(total)}</duration>\n"
                f"  </metadata>\n  <mouthCues>\n{rows}\n  </mouthCues>\n</rhubarbResult>\n")
    raise ValueError(f"cue format {fmt!r}: expected one of {', '.join(FORMATS)}")


def cues_name(fmt: str) -> str:
    """File name of the cues in `fmt` inside an output folder: mouth-cues.<fmt>."""
    return f"{CUES_STEM}.{fmt}"
