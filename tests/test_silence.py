"""Silence however it was recorded: the same speech with natural pauses, exact-zero gaps, a noise
gate, a DC offset, at -40 dB or as 8-bit audio gives nearly the same syllable onsets, and the
mouth is closed in every silent stretch."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
import soundfile

from cartoonface.animate.frames import sample_frames
from cartoonface.animate.timeline import REST, build_timeline
from cartoonface.speech.analyse import analyse
from cartoonface.speech.records import Alignment
from cartoonface.speech.audio import GRID_CHUNK, GRID_PROBE, Audio, digital_silence, load_audio, quantum
from tests.conftest import speak

pytestmark = pytest.mark.skipif(shutil.which("espeak-ng") is None, reason="espeak-ng is a Debian dependency (scripts/setup.sh)")

# Each sentence has a comma: the reader's own short pause inside it must stay a pause.
TEXTS = ["我们今天去公园，一起散步吧。", "天气非常好，大家都很高兴。", "明天还要早起，不能太晚。"]
ROOM_NOISE = 10 ** (-60 / 20)  # RMS of the room noise of the "natural" recording (-60 dBFS)
PAUSE = 0.7                     # seconds between sentences in the natural recording
GAP = 0.3                       # seconds of exact zeros between the cut sentences
EDGE = 0.05                     # seconds kept around each sentence's sound when it is cut
FPS = 30
NEAR_SPEECH = 0.12              # seconds: frames this close to sound may be opening or closing


def _sentences(folder: Path) -> list[np.ndarray]:
    """Each sentence read by espeak-ng, with its leading and trailing silence cut off."""
    out = []
    for index, text in enumerate(TEXTS):
        audio = load_audio(speak(text, folder / f"{index}.wav"))
        loud = np.flatnonzero(np.abs(audio.samples) > 0.01)
        out.append(audio.samples[loud[0] : loud[-1] + 1])
    return out


@pytest.fixture(scope="module")
def speech(tmp_path_factory) -> dict[str, object]:
    """The natural recording (room noise throughout, PAUSE between sentences) and the same
    sentences cut to their sound plus EDGE and joined by GAP of exact zeros, with where each
    condition's sentences start (s) and the sound (s) of each."""
    folder = tmp_path_factory.mktemp("silence")
    sentences = _sentences(folder)
    rate = load_audio(folder / "0.wav").rate
    rng = np.random.default_rng(0)
    pause = np.zeros(int(PAUSE * rate), np.float32)
    natural = np.concatenate([pause, *(x for s in sentences for x in (s, pause))])
    natural = natural + rng.normal(0, ROOM_NOISE, natural.size).astype(np.float32)
    edge = int(EDGE * rate)
    gap = np.zeros(int(GAP * rate), np.float32)
    pieces, natural_starts, zero_starts, position = [gap], [], [], len(gap)
    for index, sentence in enumerate(sentences):
        start = len(pause) * (index + 1) + sum(len(s) for s in sentences[:index])
        natural_starts.append(start / rate)
        piece = natural[start - edge : start + len(sentence) + edge]
        zero_starts.append((position + edge) / rate)
        pieces += [piece, gap]
        position += len(piece) + len(gap)
    sounds = [len(s) / rate for s in sentences]
    return {"rate": rate, "natural": natural, "zeros": np.concatenate(pieces), "natural_starts": natural_starts,
            "zero_starts": zero_starts, "sounds": sounds, "folder": folder}


def _stored(samples: np.ndarray, rate: int, path: Path, subtype: str) -> Audio:
    """`samples` written as a WAV of `subtype` and read back as a user's file would be."""
    soundfile.write(path, np.clip(samples, -1, 1), rate, subtype=subtype)
    return load_audio(path)


def _gated(samples: np.ndarray, rate: int) -> np.ndarray:
    """A noise gate: 10 ms blocks quieter than -40 dB below the peak, after 50 ms of them, x 1e-4."""
    hop = rate // 100
    count = len(samples) // hop
    blocks = samples[: count * hop].reshape(count, hop)
    quiet = np.sqrt(np.mean(blocks**2, axis=1)) < np.abs(samples).max() * 10 ** (-40 / 20)
    run = np.zeros(count, dtype=int)
    for k in range(count):
        run[k] = run[k - 1] + 1 if quiet[k] and k else int(quiet[k])
    gain = np.where(run > 5, 1e-4, 1.0).repeat(hop)
    out = samples.copy()
    out[: count * hop] *= gain.astype(np.float32)
    return out


def _onsets(alignment: Alignment, starts: list[float]) -> np.ndarray:
    """Syllable onsets (s) relative to the start of their sentence's sound."""
    return np.array([syl.start - starts[k] for k, s in enumerate(alignment.sentences) for syl in s.syllables])


def _conditions(speech) -> dict[str, tuple[Audio, list[float]]]:
    rate, folder = speech["rate"], speech["folder"]
    natural, zeros = speech["natural"], speech["zeros"]
    peak = np.abs(natural).max()
    return {
        "zeros": (_stored(zeros, rate, folder / "zeros.wav", "FLOAT"), speech["zero_starts"]),
        "gate": (_stored(_gated(natural, rate), rate, folder / "gate.wav", "FLOAT"), speech["natural_starts"]),
        "dc": (_stored(natural + 0.1, rate, folder / "dc.wav", "FLOAT"), speech["natural_starts"]),
        "-40 dB": (_stored(natural / peak * 0.01, rate, folder / "quiet.wav", "PCM_16"), speech["natural_starts"]),
        "8-bit": (_stored(natural, rate, folder / "8bit.wav", "PCM_U8"), speech["natural_starts"]),
    }


@pytest.mark.parametrize("condition", ["zeros", "gate", "dc", "-40 dB", "8-bit"])
def test_onsets_do_not_depend_on_how_the_silence_was_recorded(speech, condition):
    text = "".join(TEXTS)
    reference = analyse(_stored(speech["natural"], speech["rate"], speech["folder"] / "natural.wav", "FLOAT"), text)
    audio, starts = _conditions(speech)[condition]
    alignment = analyse(audio, text)
    ours, theirs = _onsets(alignment, starts), _onsets(reference, speech["natural_starts"])
    assert len(ours) == len(theirs)
    assert np.mean(np.abs(ours - theirs) <= 0.05) >= 0.9, np.round(ours - theirs, 3)
    # the first syllable starts with the sound, not at the start of the gap before it
    for k, sentence in enumerate(alignment.sentences):
        assert abs(sentence.start - starts[k]) < 0.1
        assert abs(sentence.end - (starts[k] + speech["sounds"][k])) < 0.15


@pytest.mark.parametrize("condition", ["natural", "zeros", "gate", "-40 dB"])
def test_mouth_is_closed_in_every_silent_stretch(speech, condition):
    if condition == "natural":
        audio = Audio(speech["natural"], speech["rate"], "natural")
        starts = speech["natural_starts"]
    else:
        audio, starts = _conditions(speech)[condition]
    states = sample_frames(build_timeline(analyse(audio, "".join(TEXTS)), ()), FPS)
    times = np.arange(len(states)) / FPS
    sounding = np.zeros(len(states), dtype=bool)
    for start, length in zip(starts, speech["sounds"], strict=True):
        sounding |= (times > start - NEAR_SPEECH) & (times < start + length + NEAR_SPEECH)
    silent = [state.mouth for state, busy in zip(states, sounding, strict=True) if not busy]
    assert len(silent) > 10  # before the first, between and after the sentences
    assert set(silent) == {((REST, 1.0),)}


def test_digital_silence_is_told_from_quiet_recorded_sound():
    rng = np.random.default_rng(1)
    quiet = rng.normal(0, 10 ** (-70 / 20), 1600)  # room noise at -70 dBFS is recorded sound
    flicker = rng.integers(-1, 2, 1600) / 32768  # the last bit of a 16-bit file flickering
    samples = np.concatenate([np.zeros(1600), np.full(1600, 0.1), quiet, flicker, 0.3 * np.sin(np.arange(1600))])
    assert digital_silence(samples, 16000, 0.1).tolist() == [True, True, False, True, False]


def test_flicker_of_an_8_bit_grid_is_digital_silence_but_the_same_level_in_float_audio_is_sound():
    rng = np.random.default_rng(2)
    lsb = 2 / 256  # one step of 8-bit audio
    flicker = rng.integers(-1, 2, 1600) * lsb
    speech = np.round(0.3 * np.sin(np.arange(1600)) / lsb) * lsb
    on_grid = np.concatenate([np.zeros(1600), flicker, speech]) - 0.01  # a removed DC offset shifts the grid
    assert quantum(on_grid) == lsb
    assert digital_silence(on_grid, 16000, 0.1).tolist() == [True, True, False]
    off_grid = on_grid + rng.normal(0, 1e-4, on_grid.size)  # the same levels recorded as float
    assert quantum(off_grid) == 0.0
    assert digital_silence(off_grid, 16000, 0.1).tolist() == [False, False, False]


def test_quantum_names_the_coarsest_integer_grid_the_samples_lie_on():
    rng = np.random.default_rng(3)
    for bits in (8, 12, 16):
        samples = rng.integers(-(2 ** (bits - 1)), 2 ** (bits - 1), 4000) * (2 / 2**bits) + 0.003
        assert quantum(samples) == 2 / 2**bits


def test_one_sample_off_the_grid_anywhere_makes_it_no_grid():
    rng = np.random.default_rng(4)
    samples = rng.integers(-2048, 2048, 3 * GRID_CHUNK) * (2 / 4096)  # a 12-bit grid
    assert quantum(samples) == 2 / 4096
    for where in (0, GRID_PROBE - 1, GRID_PROBE, GRID_CHUNK + 5, samples.size - 1):  # first samples, chunks, end
        off = samples.copy()
        off[where] += 0.3 * 2 / 4096  # between two steps of every finer grid too
        assert quantum(off) == 0.0, where
