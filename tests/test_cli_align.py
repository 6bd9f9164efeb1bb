"""`cartoonface align` run as a user would: outputs, thesis mode, and bad inputs exiting 2 without a traceback."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import soundfile

from cartoonface.cli import main
from cartoonface.speech.audio import load_audio
from cartoonface.speech.sentences import find_speech_parts
from cartoonface.speech.textgrid import read_textgrid
from tests.conftest import run_cli, speak

pytestmark = pytest.mark.skipif(shutil.which("espeak-ng") is None, reason="espeak-ng is a Debian dependency")

TEXTS = ["你好，我是老师。", "今天天气很好！"]


@pytest.fixture(scope="module")
def speech(tmp_path_factory) -> tuple[Path, Path]:
    """(recording.wav of two espeak-ng sentences with a 0.8 s pause, transcript.txt)."""
    folder = tmp_path_factory.mktemp("cli-align")
    pieces = []
    for index, text in enumerate(TEXTS):
        path = folder / f"{index}.wav"
        speak(text, path)
        samples, rate = soundfile.read(path, dtype="float32")
        pieces += [samples, np.zeros(int(0.8 * rate), np.float32)]
    recording = folder / "recording.wav"
    soundfile.write(recording, np.concatenate(pieces), rate, subtype="PCM_16")
    transcript = folder / "transcript.txt"
    transcript.write_text("".join(TEXTS) + "\n", encoding="utf-8")
    return recording, transcript


def test_align_writes_textgrid_and_json(speech, tmp_path):
    recording, transcript = speech
    out = tmp_path / "out.TextGrid"
    done = run_cli("align", recording, "--transcript", transcript, "-o", out, "--json", tmp_path / "out.json")
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr
    assert "align" in done.stderr and "100%" in done.stderr
    alignment = read_textgrid(out.read_text(encoding="utf-8"), str(out))
    data = json.loads((tmp_path / "out.json").read_text(encoding="utf-8"))
    assert data["format"] == "cartoonface-alignment" and data["version"] == 1
    assert [s["text"] for s in data["sentences"]] == [s.text for s in alignment.sentences]
    syllables = [s for sentence in data["sentences"] for s in sentence["syllables"]]
    assert len(syllables) == sum(len(s.syllables) for s in alignment.sentences) >= 10
    assert all(s["start"] < s["end"] and 1 <= len(s["shapes"]) <= 4 for s in syllables)
    assert abs(data["duration"] - load_audio(recording).duration) < 0.001
    summary = done.stdout.strip().splitlines()[-1]
    assert f"{len(data['sentences'])} sentences, {len(syllables)} syllables" in summary


def test_align_in_thesis_mode(speech, tmp_path):
    recording, transcript = speech
    parts = find_speech_parts(load_audio(recording))
    pause = f"{parts[0].end + 0.1:.2f},{parts[1].start - 0.1:.2f}"
    out = tmp_path / "thesis.TextGrid"
    done = run_cli("align", recording, "--transcript", transcript, "-o", out, "--pause", pause)
    assert done.returncode == 0, done.stderr
    alignment = read_textgrid(out.read_text(encoding="utf-8"), str(out))
    assert alignment.sentences[-1].start > parts[1].start - 0.1


def bad_audio(folder: Path, kind: str) -> Path:
    """A bad recording of the given kind in `folder`."""
    path = folder / f"{kind}.wav"
    if kind == "text":
        path.write_text("not a recording at all\n")
    elif kind == "empty":
        path.write_bytes(b"")
    elif kind == "silent":
        soundfile.write(path, np.zeros(16000), 16000, subtype="PCM_16")
    elif kind == "truncated":
        soundfile.write(path, np.random.default_rng(0).uniform(-0.3, 0.3, 16000), 16000, subtype="PCM_16")
        path.write_bytes(path.read_bytes()[:9000])
    return path


@pytest.mark.parametrize(
    ("kind", "message"),
    [
        ("text", "not a readable audio file"),
        ("empty", "the file is empty"),
        ("silent", "the recording is silent"),
        ("truncated", "truncated WAV"),
    ],
)
def test_bad_audio_exits_2(speech, tmp_path, kind, message):
    _, transcript = speech
    path = bad_audio(tmp_path, kind)
    done = run_cli("align", path, "--transcript", transcript, "-o", tmp_path / "out.TextGrid")
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    assert f"{path}: {message}" in done.stderr
    assert not (tmp_path / "out.TextGrid").exists()


@pytest.mark.parametrize(
    ("transcript", "extra", "message"),
    [
        ("", (), "the transcript is empty"),
        ("今天天气很好我们一起去公园散步吧。" * 6, (), "is this the transcript"),
        (None, (), "no such transcript file"),
        ("你好。", ("--pause", "a,b"), "--pause 'a,b': expected START,END"),
        ("你好。", ("--pause", "50,60"), "pause 50,60: expected START,END"),
    ],
)
def test_bad_transcript_or_option_exits_2(speech, tmp_path, capsys, transcript, extra, message):
    # In-process main() (the same entry point as the console script) keeps these cases fast.
    recording, _ = speech
    path = tmp_path / "transcript.txt"
    if transcript is not None:
        path.write_text(transcript, encoding="utf-8")
    code = main(["align", str(recording), "--transcript", str(path), "-o", str(tmp_path / "out.TextGrid"), *extra])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "cartoonface: error: " in err and message in err
    assert not (tmp_path / "out.TextGrid").exists()


def test_wrong_language_transcript_is_refused(speech, tmp_path, capsys):
    recording, _ = speech
    path = tmp_path / "english.txt"
    path.write_text("Hello, I am the teacher. The weather is fine today!", encoding="utf-8")
    code = main(["align", str(recording), "--transcript", str(path), "-o", str(tmp_path / "out.TextGrid"),
                 "--language", "zh"])
    err = capsys.readouterr().err
    assert code == 2
    assert f"{path}: the transcript looks like another language" in err
