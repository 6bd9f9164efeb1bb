"""`cartoonface generate --video` run as a user would, on a real GRID clip (tests/data/grid).

The frames of the animation.svg it writes are resolved with lxml (exports/frames.FrameDocuments)
and drawn (resvg): the cartoon's mouth opens where the speaker talks and its eyes close where
his do (hand labels: bench/video_blinks.csv)."""

from __future__ import annotations

import csv
from io import BytesIO
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from cartoonface.exports.frames import FrameDocuments
from cartoonface.render.png import svg_to_png
from cartoonface.face.model import load_face
from tests.conftest import run_cli
from tests.clips import GRID, LABELS, make_clip

ROOT = Path(__file__).resolve().parent.parent
FACE = ROOT / "samples" / "faces" / "female.json"
FPS = 30
MOUTH_SHOWN = 50  # pixels of the mouth's inside: an opening anyone sees (the drawing is 400 x 480)
NEAR = 30  # a pixel within this sum of channel differences shows the palette colour


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> tuple[Path, str]:
    out = tmp_path_factory.mktemp("video") / "site"
    done = run_cli("generate", "--face", str(FACE), "--video", str(GRID), "-o", str(out))
    assert done.returncode == 0, done.stderr
    return out, done.stdout + done.stderr


def colour_counts(folder: Path, frames: list[int], colour: str) -> np.ndarray:
    """(len(frames),) pixels of `colour` ('#rrggbb') in each frame of folder/animation.svg."""
    svg = (folder / "animation.svg").read_bytes()
    count = max(frames) + 1
    documents = FrameDocuments(svg, FPS, count)
    width, height = (int(v) for v in documents.view_size)
    target = np.array([int(colour[i:i + 2], 16) for i in (1, 3, 5)])
    out = []
    for frame in frames:
        picture = np.asarray(Image.open(BytesIO(svg_to_png(documents.document(frame, width, height).encode()))).convert("RGB"))
        out.append(int((np.abs(picture.astype(int) - target).sum(axis=2) < NEAR).sum()))
    return np.array(out)


def test_the_page_folder_is_written_with_the_clip_sound(site):
    folder, output = site
    for name in ("index.html", "animation.svg", "audio.m4a", "alignment.TextGrid", "actions.json"):
        assert (folder / name).is_file(), name
    assert "3.0 s of audio" in output and "open" in output
    assert "<audio" in (folder / "index.html").read_text(encoding="utf-8")


def test_without_a_transcript_the_notes_say_the_mouth_follows_the_video(site):
    _, output = site
    note = next(line for line in output.splitlines() if "no transcript" in line)
    assert "follows the video" in note and "lip sync comes from the audio alone" not in note


def test_the_eyes_close_where_the_speaker_blinks(site):
    folder, _ = site
    with LABELS.open(encoding="utf-8") as handle:
        runs = [(int(r["first"]), int(r["last"])) for r in csv.DictReader(handle) if r["clip"] == GRID.stem]
    # the middle of each labelled closure (25 fps) as a cartoon frame, and open-eyed frames before any
    shut = [round((first + last) / 2 / 25 * FPS) for first, last in runs]
    open_frames = list(range(0, round(runs[0][0] / 25 * FPS) - 6, 5))
    iris = load_face(FACE).palette.iris
    counts = colour_counts(folder, shut + open_frames, iris)
    assert counts[: len(shut)].max() < 0.6 * np.median(counts[len(shut):])


def test_the_mouth_opens_where_the_speaker_talks(site):
    folder, _ = site
    words = [line.split() for line in GRID.with_suffix(".align").read_text().splitlines()]
    speaking, silent = [], []
    for frame in range(0, 88, 2):
        t = frame / FPS
        word = next(w for start, end, w in words if int(start) / 25000 <= t < int(end) / 25000)
        (silent if word in ("sil", "sp") else speaking).append(frame)
    counts = colour_counts(folder, speaking + silent, load_face(FACE).palette.mouth)
    talk, rest = counts[: len(speaking)], counts[len(speaking):]
    # shut in most of the silence (the lips part a little before a word's sound starts), open in the words
    assert np.median(rest) == 0 and np.mean(talk) > 3 * np.mean(rest) + 10
    assert np.percentile(talk, 75) > MOUTH_SHOWN


def test_a_clip_without_sound_makes_a_silent_page_and_says_so(tmp_path):
    mute = make_clip(tmp_path / "mute.mp4", "-i", str(GRID), "-an", "-c:v", "libx264", "-preset", "ultrafast")
    out = tmp_path / "site"
    done = run_cli("generate", "--face", str(FACE), "--video", str(mute), "-o", str(out))
    assert done.returncode == 0, done.stderr
    assert "no sound" in done.stderr and (out / "audio.m4a").is_file()


@pytest.mark.parametrize("make, expected", [
    (lambda tmp: make_clip(tmp / "pattern.mp4", "-f", "lavfi", "-i", "testsrc=size=160x120:rate=10", "-t", "1",
                           "-c:v", "libx264", "-preset", "ultrafast"), "face was found in 0 of 10 frames"),
    (lambda tmp: make_clip(tmp / "clip.avi", "-f", "lavfi", "-i", "color=c=gray:size=64x48:rate=10", "-t", "1"),
     "not supported"),
    (lambda tmp: tmp / "missing.mp4", "no such video file"),
])
def test_bad_clips_exit_2_with_one_line_and_no_output(tmp_path, make, expected):
    clip = make(tmp_path)
    out = tmp_path / "site"
    done = run_cli("generate", "--face", str(FACE), "--video", str(clip), "-o", str(out))
    assert done.returncode == 2 and expected in done.stderr and str(clip) in done.stderr
    assert "Traceback" not in done.stderr and not out.exists()


def test_a_transcript_needs_the_clip_sound(tmp_path):
    mute = make_clip(tmp_path / "mute.mp4", "-i", str(GRID), "-an", "-c:v", "libx264", "-preset", "ultrafast")
    text = tmp_path / "words.txt"
    text.write_text("place blue at i six please", encoding="utf-8")
    done = run_cli("generate", "--face", str(FACE), "--video", str(mute), "--transcript", str(text),
                   "-o", str(tmp_path / "site"))
    assert done.returncode == 2 and "no sound track to align the transcript" in done.stderr


def test_audio_and_video_are_one_or_the_other(tmp_path):
    done = run_cli("generate", "--face", str(FACE), "--video", str(GRID), "--audio", str(GRID),
                   "-o", str(tmp_path / "site"))
    assert done.returncode == 2 and "not allowed with" in done.stderr
    done = run_cli("generate", "--face", str(FACE), "-o", str(tmp_path / "site"))
    assert done.returncode == 2 and "--audio" in done.stderr and "--video" in done.stderr


def test_a_transcript_aligns_the_clip_sound_and_the_mp4_export_still_works(tmp_path):
    text = tmp_path / "words.txt"
    text.write_text("place blue at i six please", encoding="utf-8")
    out, mp4 = tmp_path / "site", tmp_path / "cartoon.mp4"
    done = run_cli("generate", "--face", str(FACE), "--video", str(GRID), "--transcript", str(text),
                   "-o", str(out), "--mp4", str(mp4), "--size", "160x120")
    assert done.returncode == 0, done.stderr
    grid = (out / "alignment.TextGrid").read_text(encoding="utf-8")
    assert "please" in grid and "six" in grid
    assert mp4.stat().st_size > 1000
