"""A video clip of a talking person: probe it, decode its frames and its sound (issue 15).

The bundled ffmpeg (speech/audio.ffmpeg_exe) does all the decoding: `probe` reads the
container's header (format, size, frame rate, duration, whether it has sound), `frames`
pipes the pictures as raw RGB at the clip's rate (at most MAX_FPS, frames no larger than
MAX_SIZE), `extract_audio` writes the first sound track as a mono WAV. Every failure is a
VideoError naming the file and what was expected.
"""

from __future__ import annotations

import math
import re
import subprocess
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cartoonface.errors import InputError
from cartoonface.speech.audio import ffmpeg_reason, ffmpeg_exe

# Longest clip accepted (issue 15: up to 10 minutes).
MAX_SECONDS = 10 * 60
# Frames are tracked at the clip's own rate up to this many per second (phones film at 60;
# the cartoon is drawn at 12..60 fps, most often 30, and a face moves little in 1/60 s).
MAX_FPS = 30.0
# Frames larger than this (width, height; portrait clips turned) are scaled down to fit: the
# face mesh looks at a 192 x 192 crop, so 4K frames would only cost time to convert.
MAX_SIZE = (1280, 720)
# Containers accepted, as ffmpeg names its demuxers (issue 15: MP4, WebM, MOV, MPEG-1).
FORMATS = {"mov,mp4,m4a,3gp,3g2,mj2": "MP4/MOV", "matroska,webm": "WebM", "mpeg": "MPEG-1"}
EXPECTED = "expected a video (MP4, WebM, MOV or MPEG-1) of at most 10 minutes"
# What probe reads from `ffmpeg -i`'s header dump.
_INPUT = re.compile(r"^Input #0, ([^ ]+), from")
_DURATION = re.compile(r"Duration: (\d+):(\d\d):(\d\d(?:\.\d+)?)")
_VIDEO = re.compile(r"Stream #0:\d+.*?: Video: .*?(\d{2,5})x(\d{2,5})")
_RATE = re.compile(r"([\d.]+) (fps|tbr)")
_ROTATE = re.compile(r"(?:rotate\s*:\s*|rotation of )(-?[\d.]+)")


class VideoError(InputError):
    """A video clip cannot be used: missing, corrupt, not a supported format, too long, no face."""


@dataclass(frozen=True)
class Clip:
    """A probed clip: `path`, container `format` (a FORMATS value), `width` x `height` of the
    decoded frames (after MAX_SIZE), `fps` of the decoded frames (<= MAX_FPS), `duration`
    seconds, `has_audio`."""

    path: Path
    format: str
    width: int
    height: int
    fps: float
    duration: float
    has_audio: bool

    @property
    def frame_count(self) -> int:
        """Frames `frames` yields, about (the container's duration times the rate)."""
        return max(1, round(self.duration * self.fps))


def probe(path: str | Path) -> Clip:
    """Read the header of the clip at `path` -> Clip. VideoError when it is missing, empty,
    not a video ffmpeg can read, a container not in FORMATS, or longer than MAX_SECONDS."""
    file = Path(path)
    if not file.is_file():
        raise VideoError(f"{file}: no such video file")
    if file.stat().st_size == 0:
        raise VideoError(f"{file}: the file is empty (0 bytes); {EXPECTED}")
    done = subprocess.run([ffmpeg_exe(), "-nostdin", "-hide_banner", "-i", str(file)],
                          capture_output=True, text=True, errors="replace")
    header = done.stderr.splitlines()
    container = next((m.group(1).rstrip(",") for line in header if (m := _INPUT.match(line))), None)
    if container is None:
        raise VideoError(f"{file}: not a readable video ({ffmpeg_reason(done.stderr)}); {EXPECTED}")
    if container not in FORMATS:
        raise VideoError(f"{file}: a {container} file is not supported; {EXPECTED}")
    # a picture attached to a recording (an M4A's or MP3's cover) is no video
    video = next((line for line in header if _VIDEO.search(line) and "attached pic" not in line), None)
    if video is None:
        raise VideoError(f"{file}: the file holds no pictures (no video stream); {EXPECTED}")
    width, height = (int(v) for v in _VIDEO.search(video).groups())  # type: ignore[union-attr]
    rates = {unit: float(value) for value, unit in _RATE.findall(video)}
    rate = rates.get("fps") or rates.get("tbr") or 0.0
    duration = next((int(h) * 3600 + int(m) * 60 + float(s)
                     for line in header for h, m, s in _DURATION.findall(line)), 0.0)
    if not 0 < rate < 1000 or duration <= 0:
        raise VideoError(f"{file}: cannot tell the clip's frame rate or length (a damaged file?); {EXPECTED}")
    if duration > MAX_SECONDS:
        raise VideoError(f"{file}: the clip lasts {duration / 60:.1f} minutes; at most "
                         f"{MAX_SECONDS // 60} minutes are accepted (cut it into parts)")
    if any(abs(float(m.group(1))) % 180 == 90 for line in header if (m := _ROTATE.search(line))):
        width, height = height, width  # a phone's portrait clip: ffmpeg turns the frames upright
    scale = min(1.0, MAX_SIZE[0] / max(width, height), MAX_SIZE[1] / min(width, height))
    width, height = _even(width * scale), _even(height * scale)
    has_audio = any(": Audio: " in line and line.lstrip().startswith("Stream #0:") for line in header)
    return Clip(path=file, format=FORMATS[container], width=width, height=height,
                fps=min(rate, MAX_FPS), duration=duration, has_audio=has_audio)


def _even(size: float) -> int:
    """A frame side in whole pixels, rounded down to an even number (at least 2)."""
    return max(2, int(size) // 2 * 2)


def frames(clip: Clip) -> Iterator[np.ndarray]:
    """The clip's pictures in order: (clip.height, clip.width, 3) uint8 RGB arrays, clip.fps
    per second from time 0 (frame i shows time i / clip.fps). VideoError when ffmpeg stops
    on damaged data before any picture, or the clip holds none."""
    size = clip.width * clip.height * 3
    command = [ffmpeg_exe(), "-nostdin", "-v", "error", "-i", str(clip.path), "-map", "0:v:0", "-an",
               "-vf", f"fps={clip.fps:g},scale={clip.width}:{clip.height}",
               "-f", "rawvideo", "-pix_fmt", "rgb24", "-"]
    # ffmpeg's complaints go to a file: a pipe left unread could fill and stall it
    log = tempfile.TemporaryFile()
    process = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=log)
    assert process.stdout is not None
    count = 0
    try:
        while True:
            data = process.stdout.read(size)
            if len(data) < size:
                break
            count += 1
            yield np.frombuffer(data, dtype=np.uint8).reshape(clip.height, clip.width, 3)
        if count == 0:
            process.wait()
            log.seek(0)
            stderr = log.read().decode(errors="replace")
            raise VideoError(f"{clip.path}: no picture could be decoded ({ffmpeg_reason(stderr)}); {EXPECTED}")
    finally:
        if process.poll() is None:
            process.kill()
        process.wait()
        process.stdout.close()
        log.close()


def extract_audio(clip: Clip, wav: Path) -> Path:
    """Write the clip's first sound track to `wav` (mono 16-bit PCM at its own rate); return `wav`.
    VideoError when the clip has no sound or ffmpeg cannot decode it."""
    if not clip.has_audio:
        raise VideoError(f"{clip.path}: the clip has no sound track")
    done = subprocess.run([ffmpeg_exe(), "-nostdin", "-v", "error", "-y", "-i", str(clip.path), "-map", "0:a:0",
                           "-vn", "-ac", "1", "-c:a", "pcm_s16le", "-t", str(math.ceil(clip.duration) + 1),
                           "-f", "wav", str(wav)], capture_output=True, text=True, errors="replace")
    if done.returncode != 0 or not wav.is_file() or wav.stat().st_size <= 44:
        raise VideoError(f"{clip.path}: its sound track cannot be decoded ({ffmpeg_reason(done.stderr)})")
    return wav
