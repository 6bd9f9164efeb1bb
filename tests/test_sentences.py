"""Sentence utterances by silence (Alg. 3.1): both modes on synthesised speech-like audio."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from cartoonface.errors import OptionError
from cartoonface.speech.audio import Audio, load_audio
from cartoonface.speech import sentences
from cartoonface.speech.sentences import Span, dips, find_speech_parts, learn_pause
from tests.conftest import ROOT, speak
from tests.synthetic import RATE, noisy, recording


def assert_matches(found: tuple[Span, ...], truth: list[Span], tolerance: float = 0.12) -> None:
    """Each found part starts and ends within `tolerance` seconds of the true sentence."""
    assert len(found) == len(truth), (found, truth)
    for part, sentence in zip(found, truth, strict=True):
        assert abs(part.start - sentence.start) < tolerance, (part, sentence)
        assert abs(part.end - sentence.end) < tolerance, (part, sentence)


def test_three_sentences_with_silence_around():
    samples, truth = recording([8, 12, 6], [0.7, 0.8])
    assert_matches(find_speech_parts(noisy(samples)), truth)


def test_no_leading_silence():
    samples, truth = recording([10, 7, 9], [0.6, 0.6], lead=0.0)
    found = find_speech_parts(noisy(samples))
    assert found[0].start == 0.0
    assert_matches(found, truth)


def test_trailing_noise_is_not_speech():
    samples, truth = recording([9, 9], [0.7], tail=0.3)
    hiss = np.random.default_rng(5).normal(0, 0.05, 2 * RATE).astype(np.float32)
    audio = noisy(np.concatenate((samples, hiss)))
    found = find_speech_parts(audio)
    assert_matches(found, truth)
    assert found[-1].end < len(samples) / RATE


def test_one_long_sentence_stays_one_part():
    samples, truth = recording([60], [])
    assert samples.size / RATE > 12
    assert_matches(find_speech_parts(noisy(samples)), truth)


def test_two_second_pause_and_short_pauses():
    samples, truth = recording([7, 9, 8, 6], [0.6, 2.0, 0.6])
    assert_matches(find_speech_parts(noisy(samples)), truth)


def test_long_pauses_only_still_split():
    samples, truth = recording([5, 5, 5], [1.2, 2.4])
    assert_matches(find_speech_parts(noisy(samples)), truth)


def test_clipping_does_not_change_parts():
    samples, truth = recording([8, 10, 7], [0.7, 0.9])
    clipped = np.clip(samples * 30, -1, 1)
    assert np.mean(np.abs(clipped) >= 1) > 0.05
    assert_matches(find_speech_parts(noisy(clipped)), truth)


def test_mains_hum_is_ignored():
    samples, truth = recording([8, 10, 7], [0.7, 0.9])
    t = np.arange(len(samples)) / RATE
    hum = 0.05 * np.sin(2 * np.pi * 50 * t) + 0.02 * np.sin(2 * np.pi * 150 * t)
    assert_matches(find_speech_parts(noisy(samples + hum.astype(np.float32))), truth)


def test_noisy_recording():
    samples, truth = recording([8, 10, 7], [0.7, 0.9])
    assert_matches(find_speech_parts(noisy(samples, snr_db=20)), truth)


def test_thesis_mode_with_the_first_pause():
    samples, truth = recording([8, 10, 7], [0.7, 0.9])
    audio = noisy(samples)
    pause = (truth[0].end + 0.05, truth[1].start - 0.05)
    assert_matches(find_speech_parts(audio, pause=pause), truth, tolerance=0.05)


def test_thesis_mode_pause_shorter_than_the_others_is_needed():
    # c1 = 0.95: a pause clearly shorter than the selected one does not split.
    samples, truth = recording([8, 10, 7], [1.0, 0.4])
    audio = noisy(samples)
    found = find_speech_parts(audio, pause=(truth[0].end + 0.02, truth[1].start - 0.02))
    assert len(found) == 2
    assert abs(found[1].end - truth[2].end) < 0.05


@pytest.mark.parametrize("pause", [(-1.0, 0.5), (2.0, 1.0), (0.0, 99.0), (1.0, 1.005)])
def test_thesis_mode_rejects_a_pause_outside_the_recording(pause):
    samples, _ = recording([5, 5], [0.7])
    with pytest.raises(OptionError, match="pause"):
        find_speech_parts(noisy(samples), pause=pause)


def test_thesis_mode_refuses_a_pause_holding_speech():
    samples, truth = recording([8, 10], [0.7])
    with pytest.raises(OptionError, match="not a silence"):
        find_speech_parts(noisy(samples), pause=(truth[0].start + 0.2, truth[0].end - 0.2))


def test_learned_pause_separates_two_clusters():
    syllable_gaps = np.full(30, 0.06)
    sentence_gaps = np.array([0.42, 0.45, 0.5])
    learned = learn_pause(np.concatenate((syllable_gaps, sentence_gaps)))
    assert syllable_gaps.max() < learned <= sentence_gaps.min()
    assert learn_pause(syllable_gaps) > syllable_gaps.max()


def test_learned_pause_with_one_class_of_pauses():
    # Only pauses between sentences (a steady reader): every one of them ends a part.
    sentence_gaps = np.array([0.41, 0.44, 0.47, 0.5, 0.52, 0.55])
    assert learn_pause(sentence_gaps) <= sentence_gaps.min()
    # Only short pauses inside one long sentence: none does.
    comma_gaps = np.array([0.16, 0.2, 0.22, 0.25, 0.27])
    assert learn_pause(comma_gaps) > comma_gaps.max()
    # Two classes of long pauses (isolated words, sentence breaks): all end a part.
    assert learn_pause(np.array([0.5, 0.52, 0.55, 0.6, 1.0, 1.1])) <= 0.5


def test_dips_prefer_a_real_pause():
    samples, truth = recording([6, 6], [0.22], lead=0.0, tail=0.0)
    audio = noisy(samples)
    found = dips(audio, Span(0.0, audio.duration))
    longest = max(found, key=lambda item: item[1])
    assert truth[0].end - 0.03 < longest[0] < truth[1].start + 0.03
    assert all(0.25 <= time <= audio.duration - 0.25 for time, _ in found)


def test_voicing_is_the_same_however_many_windows_go_at_a_time(monkeypatch):
    audio = load_audio(ROOT / "samples" / "speech" / "story.wav")
    groups = [(0, 300), (450, 900), (1000, 1003)]  # 10 ms frames: three ranges, one of two windows
    found = []
    for chunk in (1, 37, 4096):  # a window at a time, blocks with a short last one, all at once
        monkeypatch.setattr(sentences, "VOICING_CHUNK", chunk)
        found.append([flags.tolist() for flags in sentences._voiced_frames(audio, groups)])
    assert any(any(flags) for flags in found[0]) and not all(all(flags) for flags in found[0])  # voiced and not
    assert found[1] == found[0] and found[2] == found[0]


def espeak(text: str, path: Path) -> Path:
    """Synthesise pinyin `text` with espeak-ng's Mandarin voice into WAV `path`."""
    speak(text, path)
    return path


@pytest.mark.skipif(shutil.which("espeak-ng") is None, reason="espeak-ng is a Debian dependency (scripts/setup.sh)")
def test_espeak_sentences(tmp_path):
    texts = ["ni3 hao3 wo3 shi4 lao3 shi1", "jin1 tian1 tian1 qi4 hen3 hao3", "wo3 men5 qu4 gong1 yuan2 ba5"]
    pieces, truth, position = [], [], 0.0
    for index, text in enumerate(texts):
        audio = load_audio(espeak(text, tmp_path / f"{index}.wav"))
        loud = np.flatnonzero(np.abs(audio.samples) > 0.02)
        speech = audio.samples[loud[0] : loud[-1] + 1]
        truth.append(Span(position, position + len(speech) / audio.rate))
        pause = np.zeros(int(0.8 * audio.rate), np.float32)
        pieces += [speech, pause]
        position += (len(speech) + len(pause)) / audio.rate
    joined = Audio(np.concatenate(pieces), audio.rate, "espeak")
    assert_matches(find_speech_parts(joined), truth, tolerance=0.1)
