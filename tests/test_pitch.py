"""speech/pitch.py: Praat's autocorrelation pitch analysis in numpy, checked against Praat itself
(parselmouth) on real speech, and by properties on tones and silence."""

from pathlib import Path

import numpy as np
import parselmouth
import pytest

from cartoonface.speech.audio import load_audio
from cartoonface.speech.dsp import resample_poly
from cartoonface.speech.pitch import pitch_track

ROOT = Path(__file__).resolve().parents[1]
SPEECH = [ROOT / "samples" / "speech" / "story.wav",
          ROOT.parent / "shared" / "bench" / "zh" / "biaobei" / "wav" / "000001.wav"]
RATE = 16000


def praat(samples: np.ndarray, rate: int, step: float) -> tuple[np.ndarray, np.ndarray]:
    """Praat's To Pitch (ac) with its standard settings, 75-500 Hz, unvoiced as NaN."""
    pitch = parselmouth.Sound(np.asarray(samples, dtype=np.float64), sampling_frequency=float(rate)).to_pitch_ac(
        time_step=step, pitch_floor=75.0, pitch_ceiling=500.0)
    f0 = np.array(pitch.selected_array["frequency"], dtype=float)
    f0[f0 <= 0] = np.nan
    return np.array(pitch.xs()), f0


@pytest.mark.parametrize("path", SPEECH, ids=lambda path: path.name)
@pytest.mark.parametrize("step", [0.04, 0.01])
def test_real_speech_gives_praats_frames_voicing_and_f0(path, step):
    if not path.exists():
        pytest.skip(f"{path} is not here")
    audio = load_audio(path)
    times, f0 = pitch_track(audio.samples, audio.rate, step, 75.0, 500.0)
    their_times, theirs = praat(audio.samples, audio.rate, step)
    assert np.allclose(times, their_times, atol=1e-9)
    voiced, their_voiced = np.isfinite(f0), np.isfinite(theirs)
    assert their_voiced.mean() > 0.3  # speech: the comparison means something
    assert (voiced == their_voiced).mean() > 0.99
    both = voiced & their_voiced
    assert (np.abs(f0[both] / theirs[both] - 1) < 0.01).mean() > 0.99
    assert (np.abs(f0[both] / theirs[both] - 1) < 0.002).mean() > 0.96  # parabolic against Praat's sinc interpolation


@pytest.mark.parametrize("rate", [8000, 11025])
def test_a_recording_at_a_telephone_rate_gives_praats_f0_too(rate):
    audio = load_audio(SPEECH[0])
    low = resample_poly(audio.samples, rate, audio.rate).astype(np.float32)
    times, f0 = pitch_track(low, rate, 0.04, 75.0, 500.0)
    their_times, theirs = praat(low, rate, 0.04)
    assert np.allclose(times, their_times, atol=1e-9)
    voiced, their_voiced = np.isfinite(f0), np.isfinite(theirs)
    assert (voiced == their_voiced).mean() > 0.99
    both = voiced & their_voiced
    assert (np.abs(f0[both] / theirs[both] - 1) < 0.01).mean() > 0.99


@pytest.mark.parametrize("f0", [90.0, 180.0, 310.0])
def test_a_voice_like_tone_is_voiced_at_its_pitch_throughout(f0):
    t = np.arange(int(1.2 * RATE)) / RATE
    tone = sum(np.sin(2 * np.pi * k * f0 * t) / k for k in range(1, 8))  # a buzz: falling harmonics
    noisy = tone + 0.05 * np.random.default_rng(0).standard_normal(len(t))
    times, track = pitch_track((0.3 * noisy / np.abs(noisy).max()).astype(np.float32), RATE, 0.02, 75.0, 500.0)
    assert len(times) > 40 and np.isfinite(track).all()
    assert np.abs(track / f0 - 1).max() < 0.01


def test_silence_is_unvoiced_and_a_louder_copy_gives_the_same_track():
    audio = load_audio(SPEECH[0])
    quiet = np.concatenate((np.zeros(audio.rate, dtype=np.float32), audio.samples[: 3 * audio.rate]))
    times, f0 = pitch_track(quiet, audio.rate, 0.04, 75.0, 500.0)
    assert np.isnan(f0[times < 0.95]).all() and np.isfinite(f0).any()
    _, louder = pitch_track(quiet * 3, audio.rate, 0.04, 75.0, 500.0)
    assert np.allclose(f0, louder, rtol=1e-4, equal_nan=True)


def test_a_recording_shorter_than_a_window_has_no_frames_and_zeros_are_unvoiced():
    times, f0 = pitch_track(np.zeros(300, dtype=np.float32), RATE, 0.04, 75.0, 500.0)
    assert len(times) == len(f0) == 0
    times, f0 = pitch_track(np.zeros(RATE, dtype=np.float32), RATE, 0.04, 75.0, 500.0)
    assert len(times) > 0 and np.isnan(f0).all()
