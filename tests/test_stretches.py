"""The stretch check and its fallback: timings that cannot drift past a stretch's edges."""

from __future__ import annotations

import re

import numpy as np
import pytest

from cartoonface.speech.analyse import analyse
from cartoonface.speech.audio import Audio
from cartoonface.speech.stretches import FALLBACK_CONFIDENCE, spread_over_peaks, stretches, unfit
from tests.espeak import synthesize

FIRST = ["ni3", "hao3", "wo3", "men5", "jin1", "tian1", "qu4", "gong1", "yuan2", "wan2"]
SECOND = ["ta1", "shuo1", "ming2", "tian1", "xia4", "yu3", "ba5", "zai4", "jia1", "li3"]
TEXT = "你好我们今天去公园玩。他说明天下雨吧在家里。"
PAUSE = 0.6       # s of silence before, between and after the two sentences
NOISE = 0.035     # amplitude of white noise over the whole recording: it lowers the aligner's confidence
NOTE = re.compile(r"sentence (\d+) «(.+?)» (\d+\.\d\d)-(\d+\.\d\d) s: timing uncertain, syllables spread over loudness peaks")


def speech(syllables: list[str]):
    spoken = synthesize(syllables)
    if spoken is None:
        pytest.skip("espeak-ng is not available")
    return spoken


def test_stretches_end_at_pauses_and_at_sentence_starts():
    starts = np.array([0.0, 0.2, 0.4, 0.9, 1.1, 1.3])
    ends = np.array([0.2, 0.4, 0.6, 1.1, 1.3, 1.5])
    assert stretches(starts, ends, {0}) == [(0, 3), (3, 6)]
    assert stretches(starts, ends, {0, 5}) == [(0, 3), (3, 5), (5, 6)]


def test_a_sure_timing_is_fit_and_an_unsure_or_lopsided_one_is_not():
    starts, ends = np.array([0.0, 0.2, 0.4, 0.6]), np.array([0.2, 0.4, 0.6, 0.8])
    lopsided = np.array([0.0, 0.05, 0.1, 0.15]), np.array([0.05, 0.1, 0.15, 0.8])
    assert not unfit(starts, ends, np.full(4, 0.9))
    assert unfit(starts, ends, np.full(4, 0.2))
    assert unfit(*lopsided, np.full(4, 0.5)) and not unfit(*lopsided, np.full(4, 0.9))


def test_peaks_find_espeak_onsets_inside_the_edges_better_than_an_even_split():
    spoken = speech(FIRST)
    rate = spoken.rate
    samples = np.concatenate([np.zeros(int(PAUSE * rate)), spoken.samples, np.zeros(int(PAUSE * rate))])
    reference = np.array(spoken.onsets) + PAUSE
    end = PAUSE + spoken.samples.size / rate
    timed = spread_over_peaks(Audio(samples.astype(np.float32), rate, "espeak"), reference[0], end, len(FIRST))
    onsets = np.array([start for start, _ in timed])
    assert len(timed) == len(FIRST) and timed[0][0] == reference[0] and timed[-1][1] == end
    assert all(a <= b for (_, a), (b, _) in zip(timed, timed[1:])) and all(s <= e for s, e in timed)
    even = reference[0] + (end - reference[0]) * np.arange(len(FIRST)) / len(FIRST)
    assert np.median(np.abs(onsets - reference)) < np.median(np.abs(even - reference)) / 2


def test_an_unsure_stretch_is_spread_inside_its_edges_and_named_in_a_note():
    first, second = speech(FIRST), speech(SECOND)
    rate = first.rate
    pause = np.zeros(int(PAUSE * rate))
    samples = np.concatenate([pause, first.samples, pause, second.samples, pause])
    samples = samples + NOISE * np.random.default_rng(1).standard_normal(samples.size)
    alignment = analyse(Audio(samples.astype(np.float32), rate, "noisy espeak"), TEXT)
    notes = [NOTE.fullmatch(note) for note in alignment.notes]
    found = [match for match in notes if match]
    assert found, alignment.notes
    for match in found:
        sentence = alignment.sentences[int(match[1]) - 1]
        start, end = float(match[3]), float(match[4])
        assert sentence.text.startswith(match[2].rstrip("…"))
        spread = [s for s in sentence.syllables if start - 0.005 <= s.start and s.end <= end + 0.005]
        assert len(spread) >= 3 and all(s.confidence <= FALLBACK_CONFIDENCE for s in spread)
