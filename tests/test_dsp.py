"""speech/dsp.py against the scipy functions it replaces (the reference), on real speech."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import soundfile
from scipy import fft, signal

from cartoonface.speech import audio_only, dsp, features, sentences
from cartoonface.speech.audio import load_audio

STORY = Path(__file__).resolve().parents[1] / "samples" / "speech" / "story.wav"  # 22,050 Hz


@pytest.fixture(scope="module")
def speech() -> tuple[np.ndarray, int]:
    """The sample story's first 8 s: float32 samples and their rate."""
    samples, rate = soundfile.read(STORY, dtype="float32", frames=8 * 22050)
    return samples, rate


@pytest.mark.parametrize("rate", [16000, 22050, 44100])
def test_butterworth_sections_are_scipys(rate: int) -> None:
    for order in (1, 2, 3, 4):
        mine, reference = dsp.butter_highpass(order, 80.0, rate), signal.butter(order, 80.0, "highpass", fs=rate, output="sos")
        assert mine.shape == reference.shape
        # the same filter: the response on a grid of frequencies (scipy orders the sections its own way)
        grid = np.geomspace(10, rate / 2 * 0.99, 200)
        np.testing.assert_allclose(np.abs(signal.sosfreqz(mine, grid, fs=rate)[1]),
                                   np.abs(signal.sosfreqz(reference, grid, fs=rate)[1]), rtol=1e-9, atol=1e-12)
    # the one section of the order the segmentation uses is scipy's, coefficient by coefficient
    np.testing.assert_allclose(dsp.butter_highpass(2, 80.0, rate), signal.butter(2, 80.0, "highpass", fs=rate, output="sos"),
                               rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("order,cutoff", [(2, 80.0), (4, 300.0), (3, 50.0)])
def test_sos_filter_each_is_sosfilt(speech: tuple[np.ndarray, int], order: int, cutoff: float) -> None:
    samples, rate = speech
    sos = signal.butter(order, cutoff, "highpass", fs=rate, output="sos")
    for length in (len(samples), 2_000, 17, 1):  # many blocks, one block, shorter than the response
        mine = dsp.sos_filter_each(sos, [samples[:length]])[0]
        assert mine.dtype == np.float64 and mine.shape == (length,)
        np.testing.assert_allclose(mine, signal.sosfilt(sos, samples[:length]), rtol=0, atol=1e-12)


def test_sos_filter_each_filters_every_piece_from_rest(speech: tuple[np.ndarray, int], monkeypatch: pytest.MonkeyPatch) -> None:
    samples, rate = speech
    sos = signal.butter(2, 80.0, "highpass", fs=rate, output="sos")
    pieces = [samples[:rate], samples[rate : rate + 300], samples[:0], samples[2 * rate : 5 * rate], samples[-7:]]
    monkeypatch.setattr(dsp, "GROUP", 2)  # several groups of blocks: the overlap carried between them
    for mine, piece in zip(dsp.sos_filter_each(sos, pieces, np.float32), pieces, strict=True):
        assert mine.shape == piece.shape and mine.dtype == np.float32
        if len(piece):  # scipy refuses an empty signal
            np.testing.assert_allclose(mine, signal.sosfilt(sos, piece), rtol=0, atol=1e-7)


def test_sos_filter_each_is_the_same_to_the_bit_however_many_blocks_go_at_a_time(
        speech: tuple[np.ndarray, int], monkeypatch: pytest.MonkeyPatch) -> None:
    samples, rate = speech  # 8 s: about ten blocks
    sos = dsp.butter_highpass(2, 80.0, rate)
    pieces = [samples, samples[rate : 2 * rate]]
    outputs = []
    for group in (1, 3, 64):  # one block at a time, groups with a last one short, all at once
        monkeypatch.setattr(dsp, "GROUP", group)
        outputs.append([piece.tobytes() for piece in dsp.sos_filter_each(sos, pieces, np.float32)])
    assert outputs[1] == outputs[0] and outputs[2] == outputs[0]


def test_power_spectra_are_the_same_to_the_bit_however_many_frames_go_at_a_time(
        speech: tuple[np.ndarray, int], monkeypatch: pytest.MonkeyPatch) -> None:
    samples, rate = speech
    clip = features.to_rate(samples, rate)[: 3 * 16000 + 77]  # 3 s: 299 frames, the last batch short
    spectra = []
    for rows in (1, 64, 10_000):
        monkeypatch.setattr(features, "SPECTRUM_ROWS", rows)
        spectra.append(features.power_spectrum(clip))
    assert spectra[0].shape == (1 + (len(clip) - features.WINDOW) // 160, features.NFFT // 2 + 1)
    assert spectra[1].tobytes() == spectra[0].tobytes() and spectra[2].tobytes() == spectra[0].tobytes()


@pytest.mark.parametrize("up,down", [(1, 2), (1, 5), (160, 441), (16000, 22050), (3, 2), (2, 2)])
def test_resample_poly_is_scipys(speech: tuple[np.ndarray, int], monkeypatch: pytest.MonkeyPatch, up: int, down: int) -> None:
    samples, _ = speech
    monkeypatch.setattr(dsp, "CHUNK", 5_000)  # several chunks of outputs
    wide = samples[: 3 * 22050].astype(np.float64)
    mine = dsp.resample_poly(wide, up, down)
    assert mine.dtype == np.float64
    np.testing.assert_allclose(mine, signal.resample_poly(wide, up, down), rtol=0, atol=1e-12)
    # float32 stays float32 (scipy filters in float32; here the sums run in float64)
    single = dsp.resample_poly(samples[:22050], up, down)
    assert single.dtype == np.float32
    np.testing.assert_allclose(single, signal.resample_poly(samples[:22050], up, down), rtol=0, atol=2e-6)
    for length in (1, 2, 7, 40, 441):  # shorter than the filter
        np.testing.assert_allclose(dsp.resample_poly(wide[:length], up, down),
                                   signal.resample_poly(wide[:length], up, down), rtol=0, atol=1e-12)


def test_find_peaks_is_scipys(speech: tuple[np.ndarray, int]) -> None:
    samples, rate = speech
    bands = features.frames(samples, rate)
    # level curves as the segmenter and the aligner without transcript search them; rounded: flat tops
    for x in (bands.low, -bands.energy, np.round(bands.high / 3), bands.low[:5], bands.low[:2]):
        for distance, prominence in ((1, 0.0), (10, 3.0), (12, 3.0), (5, 10.0), (40, 1.0)):
            reference, _ = signal.find_peaks(x, distance=distance, prominence=prominence)
            np.testing.assert_array_equal(dsp.find_peaks(x, distance, prominence), reference)


def test_dct_matrix_is_the_orthonormal_dct(speech: tuple[np.ndarray, int]) -> None:
    samples, rate = speech
    logmel = features.frames(samples, rate).logmel
    for keep in (None, 13):
        reference = fft.dct(logmel, type=2, norm="ortho", axis=1)[:, :keep]
        np.testing.assert_allclose(logmel @ dsp.dct_matrix(logmel.shape[1], keep), reference, rtol=0, atol=1e-10)


def test_dips_from_the_whole_recordings_filter_are_the_parts_own() -> None:
    """The parts cut from the whole story's high-passed samples (the filter restarted only over its
    settling time at each part's start) are each part filtered from rest, to float32 rounding, and
    give the same dips."""
    audio = load_audio(STORY)
    whole = sentences.high_passed(audio)
    parts = sentences.find_speech_parts(audio, filtered=whole)
    assert len(parts) > 1 and parts == sentences.find_speech_parts(audio)
    cuts = [(int(part.start * audio.rate), int(part.end * audio.rate)) for part in parts]
    for mine, (first, last) in zip(sentences._restarted(audio, whole, cuts), cuts, strict=True):
        sos = signal.butter(sentences.HIGH_PASS_ORDER, sentences.HIGH_PASS_HZ, "highpass", fs=audio.rate, output="sos")
        np.testing.assert_allclose(mine, signal.sosfilt(sos, audio.samples[first:last]), rtol=0, atol=1e-7)
    found = sentences.all_dips(audio, parts, filtered=whole)
    assert sum(map(len, found)) > 0 and found == sentences.all_dips(audio, parts)


def test_the_analysis_is_the_same_with_scipys_filters(monkeypatch: pytest.MonkeyPatch) -> None:
    """The segmentation and the lip sync without a transcript (high-pass, resampling, peaks, MFCC)
    give the same parts and syllables as with the scipy functions themselves."""
    audio = load_audio(STORY)
    ours = audio_only.analyse_audio(audio)
    monkeypatch.setattr(sentences, "sos_filter_each", lambda sos, pieces, dtype: [
        signal.sosfilt(sos, p).astype(dtype) for p in pieces])
    monkeypatch.setattr(sentences, "resample_poly", signal.resample_poly)
    monkeypatch.setattr(sentences, "find_peaks", lambda x, distance, prominence: signal.find_peaks(
        x, distance=distance, prominence=prominence)[0])
    monkeypatch.setattr(audio_only, "find_peaks", lambda x, prominence, distance: signal.find_peaks(
        x, distance=distance, prominence=prominence)[0])
    monkeypatch.setattr(features, "resample_poly", signal.resample_poly)
    theirs = audio_only.analyse_audio(audio)
    assert len(ours.sentences) > 1
    assert ours == theirs


def test_generate_imports_no_scipy() -> None:
    """`cartoonface generate`'s library (pipeline and the analysis) starts without scipy."""
    import subprocess

    code = "import sys, cartoonface.pipeline, cartoonface.speech.analyse; print(any(m.startswith('scipy') for m in sys.modules))"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip() == "False"
