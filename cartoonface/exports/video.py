"""The animation as an MP4 video (H.264 + AAC): its SMIL frames resolved, rasterised by resvg, encoded by ffmpeg.

The video shows the frames of animation.svg itself: for each video frame the SMIL
animation is resolved at the frame's time (exports/frames.py) and the static document
that remains is drawn by resvg.
Frames whose resolved document is the same as the one before are drawn once. The PNG
frames are piped to the ffmpeg that imageio-ffmpeg bundles, which centres them on a
WIDTH x HEIGHT canvas and encodes them with the recording's sound.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import re
import subprocess
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import IO

import resvg_py

from cartoonface.errors import AudioError, OptionError
from cartoonface.exports.frames import FrameDocuments
from cartoonface.speech.audio import ffmpeg_exe

DEFAULT_SIZE = (1280, 720)  # 720p (issue 14)
MAX_SIDE = 3840  # px: 4K is the largest video made
MIN_SIDE = 16  # px
PAD_COLOUR = "white"  # around a picture whose shape is not the video's
# H.264 for any player (yuv420p), x264's "veryfast" preset and "animation" tuning (flat colours),
# CRF 23 (x264's default quality); AAC sound at 128 kbit/s.
VIDEO_CODEC = ("-c:v", "libx264", "-preset", "veryfast", "-tune", "animation", "-crf", "23", "-pix_fmt", "yuv420p")
AUDIO_CODEC = ("-c:a", "aac", "-b:a", "128k")
# Distinct frames drawn by the worker processes (one per core) in one batch: enough to keep
# them busy, few enough that the batch's documents (~60 kB each) stay small in memory.
BATCH = 48


def parse_size(text: str) -> tuple[int, int]:
    """'1280x720' -> (1280, 720); OptionError unless two whole numbers MIN_SIDE..MAX_SIDE, both even."""
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if not match:
        raise OptionError(f"--size {text!r}: expected WIDTHxHEIGHT in pixels, e.g. 1280x720")
    width, height = int(match[1]), int(match[2])
    for side in (width, height):
        if not MIN_SIDE <= side <= MAX_SIDE or side % 2:
            raise OptionError(f"--size {text!r}: expected even sides from {MIN_SIDE} to {MAX_SIDE} pixels (H.264)")
    return width, height


def fit(view: tuple[float, float], size: tuple[int, int]) -> tuple[int, int]:
    """The largest picture of `view`'s shape inside `size` (px, both even)."""
    scale = min(size[0] / view[0], size[1] / view[1])
    return (min(size[0], 2 * round(view[0] * scale / 2)), min(size[1], 2 * round(view[1] * scale / 2)))


def write_video(svg: bytes, rate: int, duration: float, audio: Path, out: Path,
                size: tuple[int, int] = DEFAULT_SIZE, progress: Callable[[str, float], None] | None = None) -> int:
    """Render the animation `svg` (made at `rate` frames per second, the video's rate too) over
    `duration` seconds with the recording `audio` into the MP4 file `out` (written under a
    temporary name, then renamed).

    `size`: the video's width and height (px); the picture is centred on it. `progress("video",
    fraction)` is told as frames are encoded. Returns the number of frames drawn (identical
    consecutive frames are drawn once, on as many processes as there are cores). Raises
    AudioError when ffmpeg fails.
    """
    count = max(1, math.ceil(round(duration * 1000) * rate / 1000))
    frames = FrameDocuments(svg, rate, count)
    width, height = fit(frames.view_size, size)
    temporary = out.with_name(f".{out.name}.{os.getpid()}.tmp.mp4")
    command = [
        ffmpeg_exe(), "-nostdin", "-v", "error", "-y",
        "-f", "image2pipe", "-c:v", "png", "-framerate", str(rate), "-i", "-",
        "-i", str(audio), "-map", "0:v:0", "-map", "1:a:0",
        "-vf", f"pad={size[0]}:{size[1]}:(ow-iw)/2:(oh-ih)/2:color={PAD_COLOUR}",
        *VIDEO_CODEC, *AUDIO_CODEC, "-movflags", "+faststart", "-t", f"{count / rate:.3f}",
        str(temporary),
    ]  # fmt: skip
    keys = [frames.key(frame) for frame in range(count)]
    distinct = [frame for frame in range(count) if frame == 0 or keys[frame] != keys[frame - 1]]
    with tempfile.TemporaryFile() as log:
        process = subprocess.Popen(command, stdin=subprocess.PIPE, stderr=log)
        try:
            assert process.stdin is not None
            with process.stdin, multiprocessing.get_context("fork").Pool(len(os.sched_getaffinity(0))) as pool:
                for first in range(0, len(distinct), BATCH):
                    batch = distinct[first: first + BATCH]
                    pictures = pool.map(_draw, [frames.document(frame, width, height) for frame in batch])
                    last = first + BATCH >= len(distinct)
                    ends = distinct[first + 1: first + BATCH + 1] + ([count] if last else [])
                    for frame, end, png in zip(batch, ends, pictures, strict=True):
                        process.stdin.write(png * (end - frame))
                    if progress is not None:
                        progress("video", ends[-1] / count)
            if process.wait() != 0 or not temporary.is_file():
                raise AudioError(f"{out}: ffmpeg could not make the video ({_last_line(log)})")
            os.replace(temporary, out)
        except BrokenPipeError:
            process.wait()
            raise AudioError(f"{out}: ffmpeg stopped making the video ({_last_line(log)})") from None
        finally:
            if process.poll() is None:
                process.kill()
                process.wait()
            temporary.unlink(missing_ok=True)
    return len(distinct)


def _last_line(log: IO[bytes]) -> str:
    """The last line ffmpeg wrote to `log` (its error), or '?'."""
    log.seek(0)
    lines = log.read().decode("utf-8", "replace").strip().splitlines()
    return lines[-1][:200] if lines else "?"


def _draw(document: str) -> bytes:
    """One frame's static SVG document -> PNG bytes (resvg, no system fonts: the face has no text)."""
    return bytes(resvg_py.svg_to_bytes(svg_string=document, skip_system_fonts=True))
