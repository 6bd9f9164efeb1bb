"""Driving the cartoon from a video (cartoonface/video/): speed, blinks, mouth, smoothing.

On the three GRID clips of ../shared/bench/av/grid/ (speaker 1, 360 x 288 at 25 fps, CC BY 4.0):

- speed: video frames tracked per second (decode + face mesh + measures, video/track.py) at
  360p (the clips joined) and at 720p (the same scaled to 900 x 720), wall and CPU time, and the
  whole `generate --video` in times real time with its animation.svg's weight per minute;
- blinks: the drawn blink (drive.blink_amounts >= BLINK_DRAWN) in runs against the hand labels
  of bench/video_blinks.csv (runs of frames whose iris both lids hide, labelled by looking at
  crops of the eyes frame by frame): a run found when it overlaps a labelled one; precision,
  recall, and frames agreeing. s1_bbaf2n tuned the thresholds; the other two are held out;
- mouth: the tracked opening, and the opening the cartoon draws (the blend's shapes' openings),
  against the speech envelope (RMS dB of the clip's sound over each frame): Pearson correlation
  and the lag of the best correlation within +-MAX_LAG frames (positive: the mouth after the sound);
- smoothing: the lag of the zero-phase low-pass (drive.low_pass) against the raw measures (the
  best cross-correlation), beside a causal filter of the same cut-off, and how much jitter is left
  (RMS of the second difference, smoothed over raw) on the turn and the mouth opening.

- larger head movement: bench/video_pose.py's clip (the GRID clips warped by +-15 degree sines of
  turn, tilt and roll, with their known angles): the cartoon's pose against them.

`python -m bench video`; `python -m bench.video sheet OUT.png` draws the contact sheet of
docs/video.md (video frames above the cartoon's frames at the same times).
"""

from __future__ import annotations

import csv
import subprocess
import sys
import tempfile
import time
from io import BytesIO
from pathlib import Path

import numpy as np
import soundfile
from PIL import Image, ImageDraw
from scipy.signal import butter, sosfilt

from cartoonface.data import SAMPLE_FACES
from cartoonface.exports.frames import FrameDocuments
from cartoonface.render.png import svg_to_png
from cartoonface.face.model import load_face
from cartoonface.pipeline import Options, generate
from cartoonface.speech.audio import ffmpeg_exe
from cartoonface.video.clip import Clip, extract_audio, frames, probe
from cartoonface.face.state import FaceState
from cartoonface.video.drive import (MOUTH_CUTOFF, SLOW_CUTOFF, VIDEO_SHAPES, blink_amounts, drive, low_pass,
                                     shape_measures, video_mouths)
from cartoonface.video.track import Tracking, track

GRID = Path(__file__).resolve().parents[1] / ".." / "shared" / "bench" / "av" / "grid"
CLIPS = ("s1_bbaf2n", "s1_lbak3a", "s1_pbai6p")
TUNING = ("s1_bbaf2n",)
LABELS = Path(__file__).with_name("video_blinks.csv")
BLINK_DRAWN = 0.5  # a frame whose blink is at least this shows closed eyes
MAX_LAG = 8  # frames (320 ms at 25 fps) searched either way for the best correlation
SPEED_ROUNDS = 3  # the joined clips tracked this many times; the median is reported
HIGH = (900, 720)  # the 720p clip: GRID's 5:4 frames scaled to 720 lines
SHEET_TIMES = (0.3, 0.95, 1.2, 1.5, 1.76, 2.05, 2.35)  # s of s1_bbaf2n shown in the contact sheet
SHEET_SIDE = 180  # px of each picture in the sheet


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(n,) bool -> [(first, last)] frame runs where it is True."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(int), [0]])))
    return [(int(a), int(b) - 1) for a, b in zip(edges[::2], edges[1::2])]


def labelled() -> dict[str, list[tuple[int, int]]]:
    """Clip name -> the hand-labelled closed-eye runs (first, last frame) of bench/video_blinks.csv."""
    out: dict[str, list[tuple[int, int]]] = {name: [] for name in CLIPS}
    with LABELS.open(encoding="utf-8") as handle:
        for row in csv.DictReader(handle):
            out[row["clip"]].append((int(row["first"]), int(row["last"])))
    return out


def blink_scores(found: list[tuple[int, int]], truth: list[tuple[int, int]], count: int) -> tuple[int, int, int, float]:
    """Runs found and labelled -> (found runs overlapping a label, runs found, labels, share of the
    `count` frames on which both agree whether the eyes are closed)."""
    hit = sum(any(a <= d and c <= b for c, d in truth) for a, b in found)
    def mask(spans: list[tuple[int, int]]) -> np.ndarray:
        out = np.zeros(count, dtype=bool)
        for a, b in spans:
            out[a:b + 1] = True
        return out
    return hit, len(found), len(truth), float(np.mean(mask(found) == mask(truth)))


def envelope(wav: Path, fps: float, count: int) -> np.ndarray:
    """(count,) RMS level in dB (floor -60 below the loudest) of the sound around each frame."""
    samples, rate = soundfile.read(str(wav), dtype="float32")
    hop = rate / fps
    levels = []
    for i in range(count):
        part = samples[int(i * hop):int((i + 1) * hop)]
        levels.append(float(np.sqrt(np.mean(part ** 2))) if len(part) else 0.0)
    db = 20 * np.log10(np.maximum(levels, 1e-9))
    return np.maximum(db, db.max() - 60)


def best_lag(a: np.ndarray, b: np.ndarray) -> tuple[float, int]:
    """(correlation at lag 0, lag in frames of the best correlation) of b after a, within MAX_LAG."""
    def corr(lag: int) -> float:
        x, y = (a[:len(a) - lag], b[lag:]) if lag >= 0 else (a[-lag:], b[:len(b) + lag])
        return float(np.corrcoef(x, y)[0, 1])
    lags = range(-MAX_LAG, MAX_LAG + 1)
    return corr(0), max(lags, key=corr)


def drawn_opening(tracking: Tracking) -> np.ndarray:
    """(n,) the opening (MNS0 of the female sample) of the mouth drive.py draws at each clip frame."""
    face = load_face(SAMPLE_FACES / "female.json")
    shapes = shape_measures(face)
    blends = video_mouths(tracking, np.arange(len(tracking.found)) / tracking.fps, face)
    return np.array([sum(w * shapes[VIDEO_SHAPES.index(s), 0] for s, w in blend) for blend in blends])


def joined(folder: Path, size: tuple[int, int] | None) -> Clip:
    """The three GRID clips one after the other as one MP4 in `folder` (scaled to `size`)."""
    out = folder / f"joined-{size}.mp4"
    inputs = [arg for name in CLIPS for arg in ("-i", str(GRID / f"{name}.mpg"))]
    graph = "".join(f"[{i}:v][{i}:a]" for i in range(len(CLIPS))) + f"concat=n={len(CLIPS)}:v=1:a=1[v][a]"
    if size is not None:
        graph = graph.replace("[v][a]", "[j][a];[j]scale=" + f"{size[0]}:{size[1]}[v]")
    subprocess.run([ffmpeg_exe(), "-nostdin", "-v", "error", "-y", *inputs, "-filter_complex", graph,
                    "-map", "[v]", "-map", "[a]", "-c:v", "libx264", "-crf", "18", "-c:a", "aac", str(out)], check=True)
    return probe(out)


def speed() -> None:
    """Print video frames tracked per second at 360p and 720p, and generate's speed in times real time."""
    with tempfile.TemporaryDirectory(prefix="bench-video-") as tmp:
        for label, size in (("360p", None), ("720p", HIGH)):
            clip = joined(Path(tmp), size)
            walls, cpus = [], []
            for _ in range(SPEED_ROUNDS):
                wall, cpu = time.perf_counter(), time.process_time()
                count = len(track(clip).found)
                walls.append(time.perf_counter() - wall)
                cpus.append(time.process_time() - cpu)
            print(f"{label} {clip.width}x{clip.height}: {count} frames tracked at "
                  f"{count / np.median(walls):.0f} frames/s wall, {count / np.median(cpus):.0f} per CPU second "
                  f"(median of {SPEED_ROUNDS}; real time is {clip.fps:g})")
            if size is None:
                wall = time.perf_counter()
                result = generate(SAMPLE_FACES / "female.json", None, None, Path(tmp) / "site", Options(), video=clip.path)
                took = time.perf_counter() - wall
                svg = (result.out_dir / "animation.svg").stat().st_size
                print(f"generate --video (360p, {result.duration:.1f} s): {took:.1f} s wall, "
                      f"{result.duration / took:.2f} x real time; animation.svg {svg / 1e6 / result.duration * 60:.2f} "
                      "MB per minute")


def accuracy() -> None:
    """Print blinks against the labels and the mouth against the speech envelope, per clip."""
    labels = labelled()
    for name in CLIPS:
        clip = probe(GRID / f"{name}.mpg")
        tracking = track(clip)
        count = len(tracking.found)
        opening = (tracking.measure("eye_left") + tracking.measure("eye_right")) / 2
        hit, found, truth, agree = blink_scores(runs(blink_amounts(opening) >= BLINK_DRAWN), labels[name], count)
        with tempfile.TemporaryDirectory(prefix="bench-video-") as tmp:
            level = envelope(extract_audio(clip, Path(tmp) / "sound.wav"), clip.fps, count)
        raw_r, raw_lag = best_lag(level, tracking.measure("mouth_open"))
        drawn_r, drawn_lag = best_lag(level, drawn_opening(tracking))
        half = "tuning" if name in TUNING else "held-out"
        print(f"{name} ({half}): blinks {hit}/{found} found runs on a label, {truth} labelled, frames agree "
              f"{agree:.1%}; mouth vs envelope r = {raw_r:.2f} (best at lag {raw_lag:+d} frames), "
              f"drawn r = {drawn_r:.2f} (lag {drawn_lag:+d})")
        smoothing(tracking)


def smoothing(tracking: Tracking) -> None:
    """Print the lag and jitter left by drive.low_pass against a causal filter of the same cut-off."""
    for label, raw, cutoff in (("turn", tracking.pose[:, 1], SLOW_CUTOFF),
                               ("mouth", tracking.measure("mouth_open"), MOUTH_CUTOFF)):
        still = low_pass(raw, tracking.fps, cutoff)
        causal = sosfilt(butter(2, cutoff, fs=tracking.fps, output="sos"), raw - raw[0]) + raw[0]
        jitter = [float(np.sqrt(np.mean(np.diff(x, 2) ** 2))) for x in (raw, still, causal)]
        ms = 1000 / tracking.fps
        print(f"  {label}: zero-phase lag {best_lag(raw, still)[1] * ms:+.0f} ms, jitter left "
              f"{jitter[1] / jitter[0]:.0%}; causal lag {best_lag(raw, causal)[1] * ms:+.0f} ms, "
              f"jitter left {jitter[2] / jitter[0]:.0%}")


def large_motion() -> None:
    """Print how the cartoon's pose follows bench/video_pose.py's clip with larger head movement (the
    GRID clips warped by +-15 degree sines of turn, then tilt, then roll): per moved axis, the
    correlation and the median / 90th percentile error of drive's pose against the known angles."""
    from bench.video_pose import write_clip

    with tempfile.TemporaryDirectory(prefix="bench-video-") as tmp:
        path = Path(tmp) / "large.mp4"
        write_clip(path)
        truth = np.loadtxt(path.with_suffix(".csv"), delimiter=",", skiprows=1)[:, 1:]
        tracking = track(probe(path))
    count = min(len(truth), len(tracking.found))
    face = load_face(SAMPLE_FACES / "female.json")
    states = drive(tracking, (FaceState(),) * count, round(tracking.fps), face)
    got = np.array([(s.pose.tilt, s.pose.turn, s.pose.roll) for s in states])
    part = count // 3
    for k, (axis, name) in enumerate(((1, "turn"), (0, "tilt"), (2, "roll"))):
        moved = slice(k * part, (k + 1) * part)
        error = np.abs(got[moved, axis] - truth[moved, axis])
        print(f"larger movement, {name} +-15: r = {np.corrcoef(got[moved, axis], truth[moved, axis])[0, 1]:.3f}, "
              f"error median {np.median(error):.1f} / 90th percentile {np.percentile(error, 90):.1f} degrees "
              f"(drawn {got[moved, axis].min():+.1f} .. {got[moved, axis].max():+.1f})")


def sheet(out: Path, name: str = CLIPS[0]) -> None:
    """Write the contact sheet: frames of GRID `name` at SHEET_TIMES above the female sample's
    cartoon at the same times (made by generate --video), a 256-colour PNG."""
    clip = probe(GRID / f"{name}.mpg")
    pictures = list(frames(clip))
    with tempfile.TemporaryDirectory(prefix="bench-video-") as tmp:
        result = generate(SAMPLE_FACES / "female.json", None, None, Path(tmp) / "site", Options(), video=clip.path)
        svg = (result.out_dir / "animation.svg").read_bytes()
    documents = FrameDocuments(svg, Options().fps, result.frames)
    side = SHEET_SIDE
    board = Image.new("RGB", (side * len(SHEET_TIMES), side * 2 + 16), "white")
    pen = ImageDraw.Draw(board)
    width, height = documents.view_size
    scale = side * 1.25 / width
    for k, t in enumerate(SHEET_TIMES):
        photo = Image.fromarray(pictures[min(len(pictures) - 1, round(t * clip.fps))])
        box = (photo.width - photo.height * 0.8) / 2
        board.paste(photo.crop((int(box), 0, int(photo.width - box), photo.height)).resize((side, side)), (k * side, 16))
        drawing = Image.open(BytesIO(svg_to_png(documents.document(round(t * Options().fps), int(width * scale),
                                                                int(height * scale)).encode())))
        left = (drawing.width - side) // 2
        top = int(drawing.height * 0.1)
        board.paste(drawing.convert("RGB").crop((left, top, left + side, top + side)), (k * side, side + 16))
        pen.text((k * side + 4, 2), f"{t:.2f} s", fill="black")
    board.quantize(256).save(out, optimize=True)


def main() -> None:
    """Print every figure."""
    speed()
    accuracy()
    large_motion()


if __name__ == "__main__":
    if sys.argv[1:2] == ["sheet"]:
        sheet(Path(sys.argv[2]))
    else:
        main()
