"""prosody.pitch_peaks: the syllables' highest voiced F0 found for all syllables at once, as a
plain loop over each syllable's frames finds it."""

import math

import numpy as np
import pytest

from cartoonface.animate.prosody import PEAK_MIN, SEMITONES, pitch_peaks
from cartoonface.speech.records import Alignment, Sentence, Syllable


def _peaks_by_loop(times, f0, alignment):
    """The definition: per syllable the first voiced frame of highest semitones in [start, end); a
    peak is at least PEAK_MIN and above both neighbours in its sentence."""
    semitones = SEMITONES * np.log2(f0 / np.median(f0[np.isfinite(f0)]))
    peaks = []
    for sentence in alignment.sentences:
        tops = []
        for syllable in sentence.syllables:
            inside = [j for j in range(len(times)) if syllable.start <= times[j] < syllable.end and np.isfinite(f0[j])]
            best = max(inside, key=lambda j: (semitones[j], -j), default=None)
            tops.append((-math.inf, 0.0) if best is None else (float(semitones[best]), float(times[best])))
        for i, (height, when) in enumerate(tops):
            before = tops[i - 1][0] if i > 0 else -math.inf
            after = tops[i + 1][0] if i + 1 < len(tops) else -math.inf
            if height >= PEAK_MIN and height > before and height > after:
                peaks.append(round(when, 3))
    return tuple(sorted(peaks))


@pytest.mark.parametrize("seed", range(6))
def test_peaks_are_those_of_a_loop_over_each_syllable(seed):
    rng = np.random.default_rng(seed)
    times = np.arange(600) * 0.01 + 0.005
    f0 = rng.uniform(80, 300, len(times))
    f0[rng.random(len(times)) < 0.4] = np.nan
    if seed % 2:
        f0 = np.round(f0 / 40) * 40  # equal maxima in a syllable: the first frame counts
    sentences, t = [], 0.0
    for _ in range(3):
        syllables = []
        for _ in range(6):
            length = float(rng.uniform(0.0, 0.4))  # some hold no frame
            syllables.append(Syllable("x", "a1", ("a",), round(t, 3), round(t + length, 3), 1.0))
            t += length + float(rng.uniform(0.0, 0.1))
        sentences.append(Sentence("x" * 6, syllables[0].start, syllables[-1].end, tuple(syllables)))
    alignment = Alignment(tuple(sentences), t + 0.5, ())
    expected = _peaks_by_loop(times, f0, alignment)
    assert expected  # the case has peaks to find
    assert pitch_peaks(None, alignment, (times, f0)) == expected
