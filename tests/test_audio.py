"""Decoding recordings: every format to the same mono samples, and a clear AudioError for bad files."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
import soundfile

from cartoonface.errors import AudioError
from cartoonface.speech.audio import BEGUN_NICENESS, MAX_SECONDS, ffmpeg_exe, load_audio, page_copy, page_copy_begun
from tests.conftest import speak

needs_espeak = pytest.mark.skipif(shutil.which("espeak-ng") is None, reason="espeak-ng is a Debian dependency")


def ffmpeg(*args: str) -> None:
    """Run the bundled ffmpeg quietly; fail the test when it fails."""
    subprocess.run([ffmpeg_exe(), "-nostdin", "-v", "error", "-y", *args], check=True)


@pytest.fixture(scope="module")
def speech(tmp_path_factory) -> Path:
    """A mono 22.05 kHz WAV of espeak-ng reading Mandarin pinyin."""
    if shutil.which("espeak-ng") is None:
        pytest.skip("espeak-ng is a Debian dependency (scripts/setup.sh)")
    path = tmp_path_factory.mktemp("speech") / "speech.wav"
    speak("ni3 hao3 shi4 jie4", path)
    return path


VARIANTS = {
    "s16.wav": ["-c:a", "pcm_s16le"],
    "u8.wav": ["-c:a", "pcm_u8"],
    "s24_stereo_44k.wav": ["-c:a", "pcm_s24le", "-ac", "2", "-ar", "44100"],
    "s32.wav": ["-c:a", "pcm_s32le"],
    "f32.wav": ["-c:a", "pcm_f32le"],
    "f64_8k.wav": ["-c:a", "pcm_f64le", "-ar", "8000"],
    "speech.mp3": [],
    "speech.ogg": [],
    "speech.opus": [],
    "speech.m4a": [],
    "speech.flac": [],
}


@needs_espeak
@pytest.mark.parametrize("name", sorted(VARIANTS))
def test_every_format_decodes_to_the_same_length(speech, tmp_path, name):
    reference = load_audio(speech)
    target = tmp_path / name
    ffmpeg("-i", str(speech), *VARIANTS[name], str(target))
    audio = load_audio(target)
    assert audio.samples.ndim == 1 and audio.samples.dtype == np.float32
    assert np.max(np.abs(audio.samples)) <= 1.0
    assert abs(audio.duration - reference.duration) < 0.03
    assert audio.source == str(target)
    if audio.rate == reference.rate and name.endswith(".wav"):
        # Lossless formats at the same rate hold the same signal.
        assert np.corrcoef(audio.samples, reference.samples)[0, 1] > 0.99


def test_stereo_is_mixed_to_mono(tmp_path):
    rate = 8000
    t = np.arange(rate) / rate
    left = 0.5 * np.sin(2 * np.pi * 220 * t)
    stereo = np.stack((left, np.zeros_like(left)), axis=1)
    soundfile.write(tmp_path / "stereo.wav", stereo, rate, subtype="PCM_16")
    audio = load_audio(tmp_path / "stereo.wav")
    assert audio.rate == rate
    assert np.allclose(audio.samples, left / 2, atol=1e-3)


def test_float_wav_out_of_range_is_clipped_and_finite(tmp_path):
    samples = np.sin(np.arange(8000) / 5) * 1.5
    samples[100:110] = np.nan
    samples[200] = np.inf
    soundfile.write(tmp_path / "float.wav", samples, 8000, subtype="FLOAT")
    audio = load_audio(tmp_path / "float.wav")
    assert np.all(np.isfinite(audio.samples))
    assert audio.samples.max() == 1.0 and audio.samples.min() == -1.0
    assert np.all(audio.samples[100:110] == 0)


def test_not_audio(tmp_path):
    path = tmp_path / "notes.wav"
    path.write_text("these are my notes, not a recording\n")
    with pytest.raises(AudioError, match="notes.wav: not a readable audio file"):
        load_audio(path)


def test_image_has_no_audio_stream(tmp_path):
    path = tmp_path / "picture.png"
    ffmpeg("-f", "lavfi", "-i", "color=c=red:s=16x16", "-frames:v", "1", str(path))
    with pytest.raises(AudioError, match="picture.png: .*no audio stream"):
        load_audio(path)


def test_empty_file(tmp_path):
    path = tmp_path / "empty.mp3"
    path.write_bytes(b"")
    with pytest.raises(AudioError, match="empty.mp3: the file is empty"):
        load_audio(path)


def test_missing_file(tmp_path):
    with pytest.raises(AudioError, match="nowhere.wav: no such audio file"):
        load_audio(tmp_path / "nowhere.wav")


def test_truncated_wav(tmp_path):
    whole = tmp_path / "whole.wav"
    soundfile.write(whole, np.random.default_rng(0).uniform(-0.5, 0.5, 16000), 16000, subtype="PCM_16")
    cut = tmp_path / "cut.wav"
    cut.write_bytes(whole.read_bytes()[:20000])
    with pytest.raises(AudioError, match="cut.wav: truncated WAV"):
        load_audio(cut)
    header_only = tmp_path / "header.wav"
    header_only.write_bytes(whole.read_bytes()[:30])
    with pytest.raises(AudioError, match="header.wav: truncated or corrupt"):
        load_audio(header_only)


def test_wav_without_samples(tmp_path):
    path = tmp_path / "nothing.wav"
    soundfile.write(path, np.zeros(0), 16000, subtype="PCM_16")
    with pytest.raises(AudioError, match="nothing.wav: the recording holds no samples"):
        load_audio(path)


@pytest.mark.parametrize("level", [0.0, 1e-5])
def test_silent_file(tmp_path, level):
    path = tmp_path / "silent.flac"
    soundfile.write(path, np.full(16000, level), 16000, subtype="PCM_24")
    with pytest.raises(AudioError, match="silent.flac: the recording is silent"):
        load_audio(path)


def test_over_thirty_minutes(tmp_path):
    rate = 1000  # a low rate keeps the file small: 30 minutes are 1.8 MB of 8-bit samples
    path = tmp_path / "long.wav"
    noise = np.random.default_rng(1).uniform(-0.5, 0.5, (MAX_SECONDS + 5) * rate)
    soundfile.write(path, noise, rate, subtype="PCM_U8")
    with pytest.raises(AudioError, match="long.wav: .*30 minutes"):
        load_audio(path)
    # Sun AU goes through ffmpeg (only WAV/FLAC/AIFF go through libsndfile).
    au = tmp_path / "long.au"
    soundfile.write(au, noise, rate, subtype="PCM_S8")
    with pytest.raises(AudioError, match="long.au: .*30 minutes"):
        load_audio(au)


@needs_espeak
@pytest.mark.parametrize("suffix", [".wav", ".flac"])
def test_page_copy_is_small_and_keeps_the_times(speech, suffix, tmp_path):
    source = tmp_path / f"speech{suffix}"
    ffmpeg("-i", str(speech), str(source))
    copy = page_copy(source, tmp_path / "site")
    assert copy.name == "audio.m4a"
    original, compressed = load_audio(speech), load_audio(copy)
    assert abs(compressed.duration - original.duration) < 0.03
    assert copy.stat().st_size * 8 / original.duration < 80_000  # bits per second: the 64 kbit/s AAC
    # The sound is where it was: the lag that best lines the two up is under a millisecond.
    a = original.samples[: original.rate * 2]
    b = np.interp(np.arange(len(a)) / original.rate, np.arange(len(compressed.samples)) / compressed.rate,
                  compressed.samples)
    lags = range(-original.rate // 20, original.rate // 20)
    best = max(lags, key=lambda lag: float(np.dot(a[max(lag, 0): len(a) + min(lag, 0)],
                                                  b[max(-lag, 0): len(b) - max(lag, 0)])))
    assert abs(best) / original.rate < 0.001


def children_niceness() -> dict[int, int]:
    """This process's child processes: pid -> niceness (from /proc)."""
    found = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:  # ended meanwhile
                continue
            if int(fields[1]) == os.getpid():
                found[int(entry.name)] = int(fields[16])
    return found


@pytest.fixture(scope="module")
def long_speech(tmp_path_factory) -> Path:
    """60 s of noise-like sound at 16 kHz: ffmpeg takes a while over it (~0.1 s of CPU)."""
    path = tmp_path_factory.mktemp("long") / "long.wav"
    rate = 16000
    t = np.arange(60 * rate) / rate
    soundfile.write(path, 0.3 * np.sin(2 * np.pi * 180 * t) * np.random.default_rng(3).random(t.size), rate,
                    subtype="PCM_16")
    return path


def test_a_begun_page_copy_runs_at_the_lowest_priority_and_makes_page_copys_file(long_speech, tmp_path):
    expected = page_copy(long_speech, tmp_path / "plain").read_bytes()
    with page_copy_begun(long_speech, tmp_path / "begun") as begun:
        assert BEGUN_NICENESS in children_niceness().values()  # ffmpeg, begun before we wait for it
        copy = begun.finish()  # still running: raised to our priority (or stopped and made again), then waited for
    assert copy == tmp_path / "begun" / "audio.m4a"
    assert copy.read_bytes() == expected
    assert sorted(p.name for p in copy.parent.iterdir()) == ["audio.m4a"]


@pytest.mark.skipif(os.geteuid() != 0, reason="only root may lower a niceness")
def test_a_hurried_page_copy_runs_at_our_priority(long_speech, tmp_path):
    before = set(children_niceness())
    with page_copy_begun(long_speech, tmp_path) as begun:
        begun.hurry()
        ours = os.getpriority(os.PRIO_PROCESS, 0)
        assert [nice for pid, nice in children_niceness().items() if pid not in before] in ([ours], [])  # [] : done
        begun.finish()


def test_leaving_a_begun_page_copy_stops_ffmpeg_and_leaves_no_part(long_speech, tmp_path):
    before = set(children_niceness())
    with page_copy_begun(long_speech, tmp_path):
        assert set(children_niceness()) - before  # ffmpeg is running
    assert not set(children_niceness()) - before
    assert list(tmp_path.iterdir()) == []


def test_a_begun_page_copy_of_a_bad_file_names_it(tmp_path):
    bad = tmp_path / "notes.wav"
    bad.write_text("not a recording")
    with page_copy_begun(bad, tmp_path / "out") as begun, pytest.raises(AudioError, match="notes.wav: cannot compress"):
        begun.finish()


@pytest.mark.skipif(os.geteuid() != 0, reason="needs root to run the copy as another user")
def test_a_begun_page_copy_that_cannot_be_raised_is_made_again(long_speech, tmp_path_factory):
    # An unprivileged user cannot lower a niceness: finish() then stops the low-priority ffmpeg and
    # begins it again at its own priority. Run as `nobody` in a child process, in a folder it may write.
    shared = Path(tempfile.mkdtemp(prefix="cartoonface-nobody-"))
    try:
        shared.chmod(0o777)
        source = shared / "long.wav"
        shutil.copy(long_speech, source)
        source.chmod(0o644)
        script = (
            "import sys; from cartoonface.speech.audio import page_copy_begun\n"
            "with page_copy_begun(sys.argv[1], sys.argv[2]) as begun:\n"
            "    print(begun.finish().stat().st_size)\n"
        )
        done = subprocess.run([sys.executable, "-c", script, str(source), str(shared / "out")],
                              user=65534, capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stderr
        made = shared / "out" / "audio.m4a"
        assert made.read_bytes() == page_copy(source, shared / "plain").read_bytes()
        assert sorted(p.name for p in made.parent.iterdir()) == ["audio.m4a"]
    finally:
        shutil.rmtree(shared)
