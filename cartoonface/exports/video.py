"""The animation as an MP4 video (H.264 + AAC): its SMIL frames resolved, drawn in layers, encoded by ffmpeg.

The video shows the frames of animation.svg itself: for each video frame the SMIL
animation is resolved at the frame's time (exports/frames.py) and the picture is put
together from its pieces (exports/layers.py, exports/compositor.py): the background drawn
once, each animated piece (hair, clothes, each face part track) drawn by librsvg once per
look inside its box and pasted over it. Frames whose resolved animation is the same as the
one before are put together once. Worker processes (one per core) put batches of frames
together and write them in turn to the ffmpeg that imageio-ffmpeg bundles, as raw RGB on a
WIDTH x HEIGHT canvas (the picture centred on white), which encodes them with the
recording's sound.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import re
import subprocess
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from multiprocessing.sharedctypes import Synchronized
from multiprocessing.synchronize import Condition
from pathlib import Path
from typing import IO, TYPE_CHECKING

import numpy as np

from cartoonface.errors import AudioError, OptionError
from cartoonface.render.pages import AUDIO_STEM
from cartoonface.speech.audio import ffmpeg_exe

if TYPE_CHECKING:
    from cartoonface.exports.compositor import Compositor, Stage

DEFAULT_SIZE = (1280, 720)  # 720p (issue 14)
MAX_SIDE = 3840  # px: 4K is the largest video made
MIN_SIDE = 16  # px
# H.264 for any player (yuv420p), x264's "veryfast" preset and "animation" tuning (flat colours),
# CRF 23 (x264's default quality); AAC sound at 128 kbit/s.
VIDEO_CODEC = ("-c:v", "libx264", "-preset", "veryfast", "-tune", "animation", "-crf", "23", "-pix_fmt", "yuv420p")
AUDIO_CODEC = ("-c:a", "aac", "-b:a", "128k")
# Distinct frames a worker process (one per core) puts together in one task before writing
# them: 12 (2.8 MB of raw RGB each at 720p), fewer when they would hold more than BATCH_BYTES.
BATCH = 12
BATCH_BYTES = 40_000_000


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
    fraction)` is told as frames are encoded. Returns the number of frames put together
    (identical consecutive frames are put together once, on as many processes as there are
    cores). Raises AudioError when ffmpeg fails.
    """
    # imported here: `generate` without --mp4 needs only parse_size (PIL and pyvips take ~0.07 s)
    from cartoonface.exports.compositor import one_thread, stage
    from cartoonface.exports.frames import FrameDocuments
    from cartoonface.exports.layers import Layers

    global _WORK
    count = max(1, math.ceil(round(duration * 1000) * rate / 1000))
    frames = FrameDocuments(svg, rate, count)
    layers = Layers(frames, fit(frames.view_size, size))
    keys = [frames.key(frame) for frame in range(count)]
    distinct = [frame for frame in range(count) if frame == 0 or keys[frame] != keys[frame - 1]]
    processes = len(os.sched_getaffinity(0))
    context = multiprocessing.get_context("fork")
    with context.Pool(processes, one_thread) as pool:
        scene = stage(layers, distinct, size, pool.map)
    temporary = out.with_name(f".{out.name}.{os.getpid()}.tmp.mp4")
    command = [
        ffmpeg_exe(), "-nostdin", "-v", "error", "-y",
        "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{size[0]}x{size[1]}", "-framerate", str(rate), "-i", "-",
        "-i", str(audio), "-map", "0:v:0", "-map", "1:a:0",
        *VIDEO_CODEC, *AUDIO_CODEC, "-movflags", "+faststart", "-t", f"{count / rate:.3f}",
        str(temporary),
    ]  # fmt: skip
    batch = max(1, min(BATCH, BATCH_BYTES // (size[0] * size[1] * 3)))
    batches = [distinct[first: first + batch] for first in range(0, len(distinct), batch)]
    repeats = dict(zip(distinct, np.diff([*distinct, count]).tolist(), strict=True))
    with tempfile.TemporaryFile() as log:
        process = subprocess.Popen(command, stdin=subprocess.PIPE, stderr=log)
        try:
            assert process.stdin is not None
            _WORK = _Work(scene, process.stdin.fileno(), context.Condition(), context.Value("i", 0))
            with process.stdin, context.Pool(processes, one_thread) as pool:
                tasks = [pool.apply_async(_compose, (number, batch, [repeats[frame] for frame in batch]))
                         for number, batch in enumerate(batches)]
                for task, end in zip(tasks, [*(batch[0] for batch in batches[1:]), count], strict=True):
                    task.get()
                    if progress is not None:
                        progress("video", end / count)
            if process.wait() != 0 or not temporary.is_file():
                raise AudioError(f"{out}: ffmpeg could not make the video ({_last_line(log)})")
            os.replace(temporary, out)
        except BrokenPipeError:
            process.wait()
            raise AudioError(f"{out}: ffmpeg stopped making the video ({_last_line(log)})") from None
        finally:
            _WORK = None
            if process.poll() is None:
                process.kill()
                process.wait()
            temporary.unlink(missing_ok=True)
    return len(distinct)


def write_site_video(site: Path, rate: int, duration: float, recording: Path | None, out: Path,
                     size: tuple[int, int] = DEFAULT_SIZE,
                     progress: Callable[[str, float], None] | None = None) -> int:
    """write_video of the generated page folder `site` (its animation.svg, made at `rate` fps,
    `duration` s) with the sound of `recording`, or of the page's own audio (audio.m4a) when there
    is none (the input was a video of the speaker). Used by `generate --mp4` and web jobs."""
    sound = site / f"{AUDIO_STEM}.m4a" if recording is None else recording
    return write_video((site / "animation.svg").read_bytes(), rate, duration, sound, out, size, progress)


@dataclass(frozen=True)
class _Work:
    """What the worker processes put frames together from and write to (set before they are forked)."""

    scene: Stage
    output: int  # ffmpeg's standard input (file descriptor): the workers write their frames there in turn
    turn: Condition  # told when `written` moves on
    written: Synchronized[int]  # the number of batches written


_WORK: _Work | None = None
_COMPOSITOR: Compositor | None = None  # a worker's own


def _compose(number: int, batch: list[int], repeats: list[int]) -> None:
    """Put together the frames `batch` (batch `number`), in a worker process, and when the batches
    before it are written, write each `repeats` times to ffmpeg as raw RGB (the video's width x
    height x 3 bytes)."""
    global _COMPOSITOR
    assert _WORK is not None
    work = _WORK
    if _COMPOSITOR is None:
        from cartoonface.exports.compositor import Compositor  # already imported by write_video (forked)

        _COMPOSITOR = Compositor(work.scene)
    frames = [_COMPOSITOR.frame(frame).tobytes() for frame in batch]
    with work.turn:
        work.turn.wait_for(lambda: work.written.value == number)
        for raw, times in zip(frames, repeats, strict=True):
            for _ in range(times):
                _write(work.output, raw)
        work.written.value = number + 1
        work.turn.notify_all()


def _write(output: int, data: bytes) -> None:
    """All of `data` to the file descriptor `output` (a pipe takes it in parts)."""
    view = memoryview(data)
    while view:
        view = view[os.write(output, view):]


def _last_line(log: IO[bytes]) -> str:
    """The last line ffmpeg wrote to `log` (its error), or '?'."""
    log.seek(0)
    lines = log.read().decode("utf-8", "replace").strip().splitlines()
    return lines[-1][:200] if lines else "?"
