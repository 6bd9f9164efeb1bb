"""The animation as an MP4 video (H.264 + AAC): its SMIL frames resolved, drawn by resvg in layers, encoded by ffmpeg.

The video shows the frames of animation.svg itself: for each video frame the SMIL
animation is resolved at the frame's time (exports/frames.py). The picture is put together
from layers (exports/layers.py): the background drawn once, each animated piece (hair,
clothes, each face part track) drawn by resvg once per look inside its box and pasted over
it. Frames whose resolved animation is the same as the one before are put together once.
The frames go to the ffmpeg that imageio-ffmpeg bundles as raw RGB on a WIDTH x HEIGHT
canvas (the picture centred on white) and are encoded with the recording's sound.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import re
import subprocess
import tempfile
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass
from multiprocessing.pool import Pool
from multiprocessing.sharedctypes import Synchronized
from multiprocessing.synchronize import Condition
from pathlib import Path
from typing import IO

import numpy as np
import pyvips
from PIL import Image

from cartoonface.errors import AudioError, OptionError
from cartoonface.exports.frames import FrameDocuments
from cartoonface.exports.layers import Box, Layers, Piece, bounds, footprint_bounds, spills, union
from cartoonface.speech.audio import ffmpeg_exe

DEFAULT_SIZE = (1280, 720)  # 720p (issue 14)
MAX_SIDE = 3840  # px: 4K is the largest video made
MIN_SIDE = 16  # px
PAD_COLOUR = "white"  # around a picture whose shape is not the video's, and under its transparent parts
# H.264 for any player (yuv420p), x264's "veryfast" preset and "animation" tuning (flat colours),
# CRF 23 (x264's default quality); AAC sound at 128 kbit/s.
VIDEO_CODEC = ("-c:v", "libx264", "-preset", "veryfast", "-tune", "animation", "-crf", "23", "-pix_fmt", "yuv420p")
AUDIO_CODEC = ("-c:a", "aac", "-b:a", "128k")
# Distinct frames a worker process (one per core) puts together in one task before writing
# them (2.8 MB of raw RGB each at 720p).
BATCH = 12
OVERLAY = 64  # looks of a piece drawn over one another in one document to find its box
CACHE = 24  # looks of a piece a worker keeps drawn (the hair of a swaying head comes back)


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
    global _WORK
    count = max(1, math.ceil(round(duration * 1000) * rate / 1000))
    frames = FrameDocuments(svg, rate, count)
    picture = fit(frames.view_size, size)
    offset = ((size[0] - picture[0]) // 2, (size[1] - picture[1]) // 2)
    layers = Layers(frames, picture)
    keys = [frames.key(frame) for frame in range(count)]
    distinct = [frame for frame in range(count) if frame == 0 or keys[frame] != keys[frame - 1]]
    processes = len(os.sched_getaffinity(0))
    with multiprocessing.get_context("fork").Pool(processes, _start_worker) as pool:
        base, boxes = _base_and_boxes(layers, distinct, size, offset, pool)
    busiest = max(range(len(layers.animated)), default=0,
                  key=lambda k: len({layers.animated[k].look(frame) for frame in distinct}))
    temporary = out.with_name(f".{out.name}.{os.getpid()}.tmp.mp4")
    command = [
        ffmpeg_exe(), "-nostdin", "-v", "error", "-y",
        "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{size[0]}x{size[1]}", "-framerate", str(rate), "-i", "-",
        "-i", str(audio), "-map", "0:v:0", "-map", "1:a:0",
        *VIDEO_CODEC, *AUDIO_CODEC, "-movflags", "+faststart", "-t", f"{count / rate:.3f}",
        str(temporary),
    ]  # fmt: skip
    batches = [distinct[first: first + BATCH] for first in range(0, len(distinct), BATCH)]
    repeats = dict(zip(distinct, np.diff([*distinct, count]).tolist(), strict=True))
    context = multiprocessing.get_context("fork")
    with tempfile.TemporaryFile() as log:
        process = subprocess.Popen(command, stdin=subprocess.PIPE, stderr=log)
        try:
            assert process.stdin is not None
            _WORK = _Work(layers, base, boxes, offset, busiest, process.stdin.fileno(), context.Condition(),
                          context.Value("i", 0))
            with process.stdin, context.Pool(processes, _start_worker) as pool:
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


def _base_and_boxes(layers: Layers, distinct: list[int], size: tuple[int, int], offset: tuple[int, int],
                    pool: Pool) -> tuple[Image.Image, list[Box | None]]:
    """The picture under every frame (the video's `size`, white, the base pieces drawn at `offset`)
    and each animated piece's box (None: never seen), all looks of a piece drawn over one another
    (OVERLAY looks a document) on the `pool`."""
    whole = layers.whole()
    documents = [layers.document("".join(layers.piece_text(piece, 0) for piece in layers.base), whole)]
    owners = []
    for index, piece in enumerate(layers.animated):
        looks: dict[tuple[int, ...], int] = {}
        for frame in distinct:
            looks.setdefault(piece.look(frame), frame)
        shown = list(looks.values())
        for first in range(0, len(shown), OVERLAY):
            group = shown[first: first + OVERLAY]
            documents.append(layers.document("".join(layers.piece_text(piece, f) for f in group), whole, group[0],
                                             footprint=True))
            owners.append(index)
    pictures = pool.map(_draw, documents)
    base = Image.new("RGB", size, PAD_COLOUR)
    base.paste(pictures[0], offset, pictures[0])
    boxes: list[Box | None] = [None] * len(layers.animated)
    for owner, picture in zip(owners, pictures[1:], strict=True):
        boxes[owner] = union([boxes[owner], footprint_bounds(picture, whole, whole[2:])])
    return base, boxes


@dataclass(frozen=True)
class _Work:
    """What the worker processes put frames together from (set before they are forked)."""

    layers: Layers
    base: Image.Image  # the video's size, the base pieces drawn
    boxes: list[Box | None]  # of each animated piece, picture px
    offset: tuple[int, int]  # the picture's top left corner on the video, px
    # the pieces below the one with the most looks are pasted into a picture kept while
    # their looks stay, the rest over a copy of its part that they cover
    split: int
    output: int  # ffmpeg's standard input (file descriptor): the workers write their frames there in turn
    turn: Condition  # told when `written` moves on
    written: Synchronized[int]  # the number of batches written


Region = tuple[int, int, int, int]  # left, top, right, bottom on the video, px
Sprite = tuple[tuple[int, int], Image.Image]  # a piece's picture (RGBA) and its top left corner on the video


@dataclass
class _Canvas:
    """A worker's pictures: `under` the base with the pieces below the split in `looks` pasted
    over `under_dirty`, `frame` the last frame: `under` with the pieces above pasted over `frame_dirty`."""

    under: Image.Image
    frame: Image.Image
    looks: tuple[tuple[int, ...], ...] | None = None
    under_dirty: Region | None = None
    frame_dirty: Region | None = None


_WORK: _Work | None = None
_CANVAS: _Canvas | None = None
# per animated piece: its latest looks drawn (look -> its sprite, None when nothing shows)
_SPRITES: dict[int, OrderedDict[tuple[int, ...], Sprite | None]] = {}


def _compose(number: int, batch: list[int], repeats: list[int]) -> None:
    """Put together the frames `batch` (batch `number`), in a worker process, and when the batches
    before it are written, write each `repeats` times to ffmpeg as raw RGB (the video's width x
    height x 3 bytes)."""
    global _CANVAS
    assert _WORK is not None
    work, frames = _WORK, []
    if _CANVAS is None:
        _CANVAS = _Canvas(work.base.copy(), work.base.copy())
    canvas = _CANVAS
    for frame in batch:
        looks = tuple(piece.look(frame) for piece in work.layers.animated)
        sprites = [_cached(work, index, look, frame) for index, look in enumerate(looks)]
        changed = canvas.frame_dirty
        if looks[: work.split] != canvas.looks:
            changed = _union_region(changed, canvas.under_dirty)
            _restore(canvas.under, work.base, canvas.under_dirty)
            canvas.under_dirty = _paste(canvas.under, sprites[: work.split])
            changed = _union_region(changed, canvas.under_dirty)
            canvas.looks = looks[: work.split]
        _restore(canvas.frame, canvas.under, changed)
        canvas.frame_dirty = _paste(canvas.frame, sprites[work.split:])
        frames.append(canvas.frame.tobytes())
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


def _restore(picture: Image.Image, source: Image.Image, region: Region | None) -> None:
    """Copy `region` of `source` onto `picture` (nothing for None)."""
    if region is not None:
        picture.paste(source.crop(region), region[:2])


def _paste(picture: Image.Image, sprites: list[Sprite | None]) -> Region | None:
    """Paste `sprites` over `picture` by their alpha, in order; returns the region they cover."""
    covered = None
    for sprite in sprites:
        if sprite is not None:
            (x, y), image = sprite
            picture.paste(image, (x, y), image)
            covered = _union_region(covered, (x, y, x + image.width, y + image.height))
    return covered


def _union_region(one: Region | None, other: Region | None) -> Region | None:
    """The smallest (left, top, right, bottom) region holding both (None for none)."""
    if one is None or other is None:
        return one or other
    return min(one[0], other[0]), min(one[1], other[1]), max(one[2], other[2]), max(one[3], other[3])


def _cached(work: _Work, index: int, look: tuple[int, ...], frame: int) -> Sprite | None:
    """Animated piece `index` in `look` (that of `frame`), from the worker's latest CACHE looks or drawn."""
    box = work.boxes[index]
    if box is None:
        return None
    cache = _SPRITES.setdefault(index, OrderedDict())
    if look in cache:
        cache.move_to_end(look)
        return cache[look]
    sprite = cache[look] = _sprite(work, work.layers.animated[index], box, frame)
    if len(cache) > CACHE:
        cache.popitem(last=False)
    return sprite


def _sprite(work: _Work, piece: Piece, box: Box, frame: int) -> Sprite | None:
    """`piece` at `frame` drawn in its `box`: its top left corner on the video and its RGBA
    picture cut to its visible pixels (None when nothing shows)."""
    text = work.layers.piece_text(piece, frame)
    drawn = _draw(work.layers.document(text, box, frame))
    seen = bounds(drawn, box)
    if seen is None:
        return None
    whole = work.layers.whole()
    if spills(seen, box, whole):
        # drawn up to an edge of its box that is not the picture's: it may go on outside, draw it whole
        box = whole
        drawn = _draw(work.layers.document(text, box, frame))
        seen = bounds(drawn, box)
        assert seen is not None
    x, y, width, height = seen
    cut = drawn.crop((x - box[0], y - box[1], x - box[0] + width, y - box[1] + height))
    return (x + work.offset[0], y + work.offset[1]), cut


def _last_line(log: IO[bytes]) -> str:
    """The last line ffmpeg wrote to `log` (its error), or '?'."""
    log.seek(0)
    lines = log.read().decode("utf-8", "replace").strip().splitlines()
    return lines[-1][:200] if lines else "?"


def _start_worker() -> None:
    """A worker process draws on its own thread (the processes share the cores) and keeps no
    libvips cache (no two documents drawn are alike)."""
    pyvips.concurrency_set(1)
    pyvips.cache_set_max(0)


def _draw(document: str) -> Image.Image:
    """A static SVG document -> its RGBA picture (librsvg through libvips: raw pixels, no PNG)."""
    drawn = pyvips.Image.svgload_buffer(document.encode())
    return Image.frombuffer("RGBA", (drawn.width, drawn.height), drawn.write_to_memory(), "raw", "RGBA", 0, 1)
