"""Reconciling: lay the sentences of a transcript over the speaking parts of its recording.

Ours; the thesis (002, ch. 3) assumes one speaking part per sentence. The sentences are
laid over the speaking parts by a small dynamic programme that chooses where each sentence
ends among the pauses between parts, the energy dips inside parts and, as a last resort,
evenly spaced cut points. A sentence costs the squared log ratio of its speech time to the
time its syllable count predicts at the recording's mean rate; spanning a pause between
parts (merging) and cutting inside a part (splitting) cost extra. docs/alignment.md has
the details.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from cartoonface.speech.audio import Audio
from cartoonface.speech.sentences import Span, all_dips

# Reconciling costs (ours, tuned on synthetic recordings in tests/test_alignment.py; held-out
# checks on real recordings in tests/test_reconcile.py):
SIGMA = 0.35  # spread of a sentence's speaking rate around the recording's mean, as a log ratio
MERGE_COST = 1.5  # one sentence spanning a pause between speaking parts
DIP_COST = 2.0  # cutting inside a speaking part at an energy dip (less for a longer dip)
DIP_PLATEAU = 0.15  # seconds: a dip this long costs half of DIP_COST
FORCED_COST = 8.0  # cutting at an evenly spaced point with no dip (only when nothing else fits)
DIPS_PER_SECOND = 1.0  # longest dips kept per second of a part (at least MIN_DIPS)
MIN_DIPS = 3
# Sentence lengths (in cuts) whose costs are computed at once: the tables stay small (STEPS x cuts)
# however far a long sentence needs the search's window to grow.
STEPS = 64


@dataclass(frozen=True)
class _Cut:
    """A place where one sentence may end and the next begin: `left` end, `right` start (seconds)."""

    left: float
    right: float
    cost: float
    kind: str  # "start", "pause", "dip", "forced", "end"
    part: int  # index of the speaking part it is in (pause: the part before it)


def reconcile(audio: Audio, parts: tuple[Span, ...], counts: list[int],
              filtered: np.ndarray | None = None) -> tuple[Span, ...]:
    """Lay sentences of `counts` syllables over the speaking `parts` of `audio`
    (`filtered`: sentences.high_passed(audio) when the caller has it, for the dips).

    Returns one Span per sentence, in order. The spans cover the parts'
    speech and do not overlap; two consecutive spans touch (end == next
    start) where a part was cut between them (at a dip, or an evenly spaced
    point), and are apart where a pause between parts separates them.
    """
    cuts = _cuts(audio, parts, len(counts), filtered)
    speech_before = _speech_clock(parts)
    left = np.array([cut.left for cut in cuts])
    right = np.array([cut.right for cut in cuts])
    cost = np.array([cut.cost for cut in cuts])
    pauses_before = np.cumsum([cut.kind == "pause" for cut in cuts])
    at_left, at_right = speech_before(left), speech_before(right)
    rate = at_left[-1] / sum(counts)
    boundaries = _best_cuts(at_left, at_right, cost, pauses_before, np.array(counts) * rate)
    return tuple(
        Span(round(float(right[a]), 3), round(float(left[b]), 3)) for a, b in zip(boundaries, boundaries[1:])
    )


def _cuts(audio: Audio, parts: tuple[Span, ...], sentences: int, filtered: np.ndarray | None) -> list[_Cut]:
    """Every candidate cut in time order, between a "start" and an "end" cut."""
    cuts = [_Cut(parts[0].start, parts[0].start, 0.0, "start", 0)]
    for index, (part, part_dips) in enumerate(zip(parts, all_dips(audio, parts, filtered=filtered), strict=True)):
        found = sorted(part_dips, key=lambda dip: -dip[1])
        keep = max(MIN_DIPS, math.ceil(part.duration * DIPS_PER_SECOND))
        for time, plateau in sorted(found[:keep]):
            cuts.append(_Cut(time, time, DIP_COST * DIP_PLATEAU / (DIP_PLATEAU + plateau), "dip", index))
        if index + 1 < len(parts):
            cuts.append(_Cut(part.end, parts[index + 1].start, 0.0, "pause", index))
    # Evenly spaced cuts where a part has too few dips for the sentences its length could hold.
    speech = sum(part.duration for part in parts)
    spacing = min(0.25, speech / (2 * sentences))
    taken = {round(cut.left, 2) for cut in cuts}
    for index, part in enumerate(parts):
        room = sum(1 for cut in cuts if cut.kind == "dip" and cut.part == index)
        if room >= 2 * part.duration / speech * sentences:
            continue
        for time in np.arange(part.start + spacing, part.end - spacing / 2, spacing):
            if round(float(time), 2) not in taken:
                cuts.append(_Cut(round(float(time), 3), round(float(time), 3), FORCED_COST, "forced", index))
    cuts.append(_Cut(parts[-1].end, parts[-1].end, 0.0, "end", len(parts) - 1))
    return sorted(cuts, key=lambda cut: (cut.left, cut.kind != "start"))


def _speech_clock(parts: tuple[Span, ...]) -> Callable[[np.ndarray], np.ndarray]:
    """A function: times (k,) seconds -> seconds of speech (inside `parts`) before each time."""
    starts = np.array([part.start for part in parts])
    ends = np.array([part.end for part in parts])

    def before(times: np.ndarray) -> np.ndarray:
        return np.clip(times[:, None] - starts[None, :], 0, (ends - starts)[None, :]).sum(axis=1)

    return before


def _best_cuts(
    at_left: np.ndarray, at_right: np.ndarray, cost: np.ndarray, pauses_before: np.ndarray, expected: np.ndarray
) -> list[int]:
    """Indices of the chosen cuts: 0, one per sentence boundary, the last cut; minimum total cost.

    `at_left`/`at_right` (B,) speech seconds before each cut's left/right
    edge, `cost` (B,) of cutting there, `pauses_before` (B,) pauses up to
    and including each cut, `expected` (S,) speech seconds per sentence.
    """
    count = len(at_left)
    sentences = len(expected)
    window = min(count - 1, max(64, 4 * count // sentences))
    ends = np.arange(1, count)
    while True:
        table = np.full((sentences + 1, count), np.inf)
        choice = np.zeros((sentences + 1, count), dtype=np.int64)
        table[0, 0] = 0.0
        for k in range(1, sentences + 1):
            best = table[k, 1:]  # views: the sentence k ending at each cut b = 1 .. count - 1
            arg = choice[k, 1:]
            for first in range(1, window + 1, STEPS):
                # the sentence from cut b - step to cut b for STEPS steps at once: row j is step first + j
                a = ends[None, :] - np.arange(first, min(first + STEPS, window + 1))[:, None]
                inside = a >= 0
                a = np.where(inside, a, 0)
                speech = np.maximum(at_left[ends] - at_right[a], 1e-3)
                total = np.where(inside, table[k - 1, a]
                                 + (np.log(speech / expected[k - 1]) / SIGMA) ** 2
                                 + MERGE_COST * (pauses_before[ends - 1] - pauses_before[a])
                                 + np.where(ends < count - 1, cost[ends], 0.0), np.inf)
                step = total.argmin(axis=0)  # the shortest step of the least cost, as one step at a time
                least = total[step, ends - 1]
                better = least < best  # a tie keeps the shorter step of an earlier block
                best[better] = least[better]
                arg[better] = a[step, ends - 1][better]
            if k < sentences:
                table[k, count - 1] = np.inf
        if np.isfinite(table[sentences, count - 1]) or window >= count - 1:
            break
        window = min(count - 1, window * 2)
    path = [count - 1]
    for k in range(sentences, 0, -1):
        path.append(int(choice[k, path[-1]]))
    return path[::-1]


