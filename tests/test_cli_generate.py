"""`cartoonface generate` run as a user would: progress, summary, and exit 2 on bad input."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from cartoonface.cli.generate import begun
from tests.conftest import run_cli, spoken_inputs

pytestmark = pytest.mark.skipif(not shutil.which("espeak-ng"), reason="needs espeak-ng")

ROOT = Path(__file__).resolve().parent.parent
FACE = ROOT / "samples" / "faces" / "female.json"
TEXT = "你好。谢谢你。"


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> tuple[Path, Path]:
    """A short espeak-ng recording and its transcript file."""
    return spoken_inputs(tmp_path_factory.mktemp("cli"), TEXT, speed=150)


def generate_args(speech: Path, transcript: Path, out: Path, *extra: str) -> list[str]:
    """The command line of one run."""
    return ["generate", "--face", str(FACE), "--audio", str(speech), "--transcript", str(transcript),
            "-o", str(out), *extra]


def test_generate_prints_progress_and_a_summary(inputs, tmp_path):
    speech, transcript = inputs
    out = tmp_path / "site"
    done = run_cli(*generate_args(speech, transcript, out, "--page", "announcer", "--title", "新闻",
                                  "--background", "newsroom", "--clothes", "shirt", "--fps", "24", "--seed", "9"))
    assert done.returncode == 0, done.stderr
    assert "100%" in done.stderr and "svg" in done.stderr
    lines = done.stdout.strip().splitlines()
    assert len(lines) == 1
    size = sum(p.stat().st_size for p in out.rglob("*") if p.is_file())
    assert f"{size / 1e6:.1f} MB" in lines[0]
    assert " frames" in lines[0] and " s of audio" in lines[0] and str(out) in lines[0]
    assert (out / "index.html").is_file() and 'id="cf-face"' in (out / "index.html").read_text(encoding="utf-8")


def bad_actions(tmp_path: Path, **action) -> str:
    path = tmp_path / "actions.json"
    path.write_text(json.dumps({"format": "cartoonface-actions", "version": 1, "actions": [action]}), encoding="utf-8")
    return str(path)


@pytest.mark.parametrize("case", ["missing audio", "unreadable audio", "transcript does not match", "fps 0",
                                  "angle 40", "past the end", "missing face"])
def test_bad_input_exits_2_with_one_line_and_no_folder(case, inputs, tmp_path):
    speech, transcript = inputs
    extra: list[str] = []
    expect = ""
    if case == "missing audio":
        speech = tmp_path / "gone.wav"
        expect = "gone.wav"
    elif case == "unreadable audio":
        speech = tmp_path / "noise.wav"
        speech.write_bytes(b"RIFF\x00\x00\x00\x00WAVEjunkjunk")
        expect = "noise.wav"
    elif case == "transcript does not match":
        transcript = tmp_path / "long.txt"
        transcript.write_text("这是一段很长的文字，" * 40, encoding="utf-8")
        expect = "long.txt"
    elif case == "fps 0":
        extra = ["--fps", "0"]
        expect = "fps"
    elif case == "angle 40":
        extra = ["--actions", bad_actions(tmp_path, kind="turn", start=0.1, duration=0.5, amplitude=40)]
        expect = "40"
    elif case == "past the end":
        extra = ["--actions", bad_actions(tmp_path, kind="blink", start=99, duration=0.3, amplitude=1)]
        expect = "actions.json"
    else:
        extra = ["--face", str(tmp_path / "noface.json")]
        expect = "noface.json"
    out = tmp_path / "out"
    done = run_cli(*generate_args(speech, transcript, out), *extra)
    assert done.returncode == 2
    message = [line for line in done.stderr.splitlines() if line.startswith("cartoonface: error:")]
    assert len(message) == 1 and expect in message[0], done.stderr
    assert "Traceback" not in done.stderr
    assert not out.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out")]


def test_unwritable_output_is_a_one_line_error(inputs, tmp_path):
    speech, transcript = inputs
    blocker = tmp_path / "notes.txt"  # a file where a folder would have to be made
    blocker.write_text("keep", encoding="utf-8")
    done = run_cli(*generate_args(speech, transcript, blocker / "site"))
    assert done.returncode == 2
    assert "Traceback" not in done.stderr and "cannot write the output folder" in done.stderr
    assert blocker.read_text(encoding="utf-8") == "keep"


STORY = ROOT / "samples" / "speech" / "story.wav"
# A fresh interpreter begins the track as `cartoonface generate` does, before the library's imports;
# prints whether numpy was imported by then, the children it had, whether the track is the one
# prosody computes here and whether this process ever imported the tracker (speech/pitch.py) to get it.
BEGUN = """
import multiprocessing, sys
from cartoonface.cli.generate import begun
recording, pitch = begun(sys.argv[1:])
print("numpy" in sys.modules, len(multiprocessing.active_children()))
times, f0 = pitch()
taken_here = "cartoonface.speech.pitch" in sys.modules
import numpy as np
from cartoonface.animate.prosody import recording_pitch
mine = recording_pitch(recording)
print(np.array_equal(times, mine[0]) and np.array_equal(f0, mine[1], equal_nan=True), taken_here)
"""


@pytest.mark.parametrize("form", ["--audio PATH", "--audio=PATH"])
def test_the_pitch_track_is_begun_in_a_child_before_the_librarys_imports(form):
    audio = ["--audio", str(STORY)] if form == "--audio PATH" else [f"--audio={STORY}"]
    done = subprocess.run([sys.executable, "-c", BEGUN, "--face", str(FACE), *audio, "-o", "out"],
                          capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["False", "1", "True", "False"]


@pytest.mark.parametrize("argv", [["--face", str(FACE), "-o", "out"], ["--video", "clip.mp4", "-o", "out"],
                                  ["--audio", str(STORY), "--actions", "edited.json"], ["--audio"]])
def test_no_track_is_begun_without_a_recording_or_with_edited_actions(argv):
    assert begun(argv) is None  # the edited actions need no pitch peaks


def _processes_naming(text: str) -> list[int]:
    """The processes whose command line holds `text` (the command and the helpers it forked)."""
    found = []
    for entry in Path("/proc").iterdir():
        try:
            if entry.name.isdigit() and text in (entry / "cmdline").read_bytes().decode(errors="replace"):
                found.append(int(entry.name))
        except OSError:  # ended meanwhile
            continue
    return found


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads /proc")
def test_sigterm_during_the_analysis_ends_the_command_and_its_helpers(tmp_path):
    out = tmp_path / "terminated-site"
    transcript = STORY.with_suffix(".txt")
    with subprocess.Popen([sys.executable, "-m", "cartoonface", *generate_args(STORY, transcript, out)],
                          stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True, cwd=ROOT) as command:
        try:
            assert command.stderr is not None
            for line in command.stderr:  # a line per stage when stderr is no terminal
                if "segment" in line:
                    break
            assert len(_processes_naming(str(out))) >= 2  # the command and a helper it forked
            command.send_signal(signal.SIGTERM)
            assert command.wait(timeout=30) == 128 + signal.SIGTERM  # the signal's default: -15
            deadline = time.monotonic() + 10
            while _processes_naming(str(out)) and time.monotonic() < deadline:
                time.sleep(0.1)
            assert not _processes_naming(str(out))  # no helper left waiting to send its result
            assert "terminated" in command.stderr.read()  # read once no helper holds the pipe
            assert not out.exists()
        finally:
            command.kill()
            for pid in _processes_naming(str(out)):
                os.kill(pid, signal.SIGKILL)


def test_an_early_error_is_the_only_thing_said_and_nothing_is_left_running(tmp_path):
    # the transcript is refused before the pitch track begun in a child is taken: the child ends
    # with the command and says nothing (it inherits the command's SIGTERM handler). The recording
    # is long enough (175 s) that its track (~70 KB) does not fit in a pipe: the child is still
    # sending it when the command ends
    import soundfile

    samples, rate = soundfile.read(STORY, dtype="float32")
    long = tmp_path / "long.wav"
    soundfile.write(long, np.tile(samples, -(-175 * rate // len(samples))), rate)
    transcript = tmp_path / "empty.txt"
    transcript.write_text("  \n", encoding="utf-8")
    done = subprocess.run([sys.executable, "-m", "cartoonface", *generate_args(long, transcript, tmp_path / "site")],
                          capture_output=True, text=True, cwd=ROOT, timeout=120)  # returns: no child holds its pipes
    assert done.returncode == 2
    errors = [line for line in done.stderr.splitlines() if line.startswith("cartoonface:")]
    assert errors == [f"cartoonface: error: {transcript}: the transcript is empty; expected the text spoken in the recording"]
    assert not (tmp_path / "site").exists()
