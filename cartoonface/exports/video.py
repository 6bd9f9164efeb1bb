"""The animation as an MP4 video (H.264 + AAC): its SMIL frames resolved, rasterised by resvg, encoded by ffmpeg.

The video shows the frames of animation.svg itself: for each video frame the SMIL
animation is resolved at the frame's time (`<set>` intervals, discrete `<animate>` and
`<animateTransform>`; docs/output.md describes what render/animation.py writes), the
drawings a frame does not show are left out (of each track's `<defs>` only the one its
`<use>` points at), and the static document that remains is drawn by resvg.
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
from dataclasses import dataclass
from pathlib import Path
from typing import IO
from xml.sax.saxutils import escape, quoteattr

import numpy as np
import resvg_py
from lxml import etree

from cartoonface.errors import AudioError, OptionError
from cartoonface.speech.audio import ffmpeg_exe

SVG_NS = "http://www.w3.org/2000/svg"
XLINK_NS = "http://www.w3.org/1999/xlink"
DEFAULT_SIZE = (1280, 720)  # 720p (issue 14)
MAX_SIDE = 3840  # px: 4K is the largest video made
MIN_SIDE = 16  # px
# Every frame is looked up half a millisecond after its start: the animation's times are whole
# milliseconds (render/animation.py frame_ms), so a frame starting on an interval's boundary
# is read inside the interval that begins there.
LOOKUP_OFFSET = 0.5  # ms
PAD_COLOUR = "white"  # around a picture whose shape is not the video's
# H.264 for any player (yuv420p), x264's "veryfast" preset and "animation" tuning (flat colours),
# CRF 23 (x264's default quality); AAC sound at 128 kbit/s.
VIDEO_CODEC = ("-c:v", "libx264", "-preset", "veryfast", "-tune", "animation", "-crf", "23", "-pix_fmt", "yuv420p")
AUDIO_CODEC = ("-c:a", "aac", "-b:a", "128k")
ANIMATIONS = {"set", "animate", "animateTransform"}
# Distinct frames drawn by the worker processes (one per core) in one batch: enough to keep
# them busy, few enough that the batch's documents (~60 kB each) stay small in memory.
BATCH = 48


@dataclass(frozen=True)
class Track:
    """One animation element resolved over the video's frames: it sets `attribute` of its
    parent to values[index[k]] at frame k (index -1: not active, the attribute as written)."""

    attribute: str
    values: tuple[str, ...]
    index: np.ndarray  # (frames,) int
    additive: bool  # an <animateTransform additive="sum">: appended to the written transform


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


def _ms(value: str) -> float:
    """An SMIL clock value in seconds ('1.25', '1.25s') -> milliseconds."""
    return float(value.strip().removesuffix("s")) * 1000


def _set_track(element: etree._Element, times: np.ndarray) -> Track:
    """A `<set>`: active in each [begin, end) (end: the first end after the begin, or begin + dur);
    with fill="freeze" it holds its value from its first begin on."""
    begins = [_ms(v) for v in element.get("begin", "0").split(";") if v.strip()]
    if element.get("fill") == "freeze":
        spans = [(min(begins), math.inf)]
    elif element.get("dur") is not None:
        spans = [(b, b + _ms(element.get("dur", "0"))) for b in begins]
    else:
        ends = sorted(_ms(v) for v in element.get("end", "").split(";") if v.strip())
        spans = [(b, next((e for e in ends if e > b), math.inf)) for b in begins]
    change = np.zeros(len(times) + 1, dtype=np.int64)
    for begin, end in spans:
        change[np.searchsorted(times, begin)] += 1
        change[np.searchsorted(times, end)] -= 1
    active = np.cumsum(change[:-1]) > 0
    return Track(element.get("attributeName", ""), (element.get("to", ""),), np.where(active, 0, -1), False)


def _discrete_track(element: etree._Element, times: np.ndarray) -> Track:
    """A discrete `<animate>`/`<animateTransform>` with values and keyTimes over one `dur`, frozen at the end."""
    values = [v.strip() for v in element.get("values", "").split(";") if v.strip()]
    keys = [float(v) for v in element.get("keyTimes", "").split(";") if v.strip()][: len(values)]
    duration = _ms(element.get("dur", "0"))
    index = np.searchsorted(np.array(keys) * duration, np.minimum(times, duration), side="right") - 1
    if element.get("fill") != "freeze":
        index = np.where(times >= duration, -1, index)
    if etree.QName(element).localname == "animateTransform":
        kind = element.get("type", "translate")
        values = [f"{kind}({v})" for v in values]
    additive = element.get("additive") == "sum"
    return Track(element.get("attributeName", ""), tuple(values), index, additive)


class FrameDocuments:
    """The static SVG document of the animation at each of `count` frames of `fps`.

    `svg`: the animation document (UTF-8 bytes). Parts with no animation inside are
    serialised once; per frame only the animated elements and their ancestors are written.
    """

    def __init__(self, svg: bytes, fps: int, count: int) -> None:
        parser = etree.XMLParser(huge_tree=True, remove_blank_text=True)
        self.root = etree.fromstring(svg, parser)
        times = np.arange(count) * 1000 / fps + LOOKUP_OFFSET
        self.tracks: dict[etree._Element, list[Track]] = {}
        for element in self.root.iter(*(f"{{{SVG_NS}}}{name}" for name in ANIMATIONS)):
            parent = element.getparent()
            make = _set_track if etree.QName(element).localname == "set" else _discrete_track
            self.tracks.setdefault(parent, []).append(make(element, times))
        # a track's drawings (render/animation.py: `<defs>` of `<g id>` beside one `<use>` whose
        # href a discrete <animate> moves): per frame only the drawing shown is written
        self.shown_by: dict[etree._Element, tuple[etree._Element, dict[str, etree._Element]]] = {}
        for parent in self.tracks:
            defs = parent.getprevious()
            if etree.QName(parent).localname == "use" and defs is not None and etree.QName(defs).localname == "defs":
                self.shown_by[defs] = (parent, {str(child.get("id")): child for child in defs})
        self.dynamic: set[etree._Element] = set(self.shown_by)
        for parent in self.tracks:
            node = parent
            while node is not None and node not in self.dynamic:
                self.dynamic.add(node)
                node = node.getparent()
        self.static: dict[etree._Element, str] = {}
        view = [float(v) for v in self.root.get("viewBox", "0 0 0 0").split()]
        self.view_size = (view[2], view[3]) if len(view) == 4 else (float(self.root.get("width", "0")),
                                                                    float(self.root.get("height", "0")))

    def key(self, frame: int) -> tuple[int, ...]:
        """What decides frame `frame`'s picture: the value index of every animation."""
        return tuple(int(track.index[frame]) for tracks in self.tracks.values() for track in tracks)

    def document(self, frame: int, width: int, height: int) -> str:
        """The static SVG document of frame `frame`, its root sized `width` x `height` px."""
        return self._element(self.root, frame, {"width": str(width), "height": str(height)})

    def _element(self, element: etree._Element, frame: int, override: dict[str, str] | None = None) -> str:
        """`element` as text at `frame` (empty when the frame hides it)."""
        if element not in self.dynamic:
            text = self.static.get(element)
            if text is None:
                text = etree.tostring(element, encoding="unicode", with_tail=False)
                self.static[element] = text
            return text
        if element in self.shown_by:
            use, drawings = self.shown_by[element]
            drawing = drawings.get(self._attributes(use, frame).get("href", "").removeprefix("#"))
            return "" if drawing is None else f"<defs>{self._element(drawing, frame)}</defs>"
        attributes = self._attributes(element, frame)
        if attributes.get("visibility") == "hidden":
            return ""
        attributes.update(override or {})
        if element is self.root:
            attributes.update({"xmlns": SVG_NS, "xmlns:xlink": XLINK_NS})
        tag = etree.QName(element).localname
        children = "".join(self._element(child, frame) for child in element
                           if not isinstance(child.tag, str) or etree.QName(child).localname not in ANIMATIONS)
        opening = "".join(f" {name}={quoteattr(value)}" for name, value in attributes.items())
        return f"<{tag}{opening}>{escape(element.text or '')}{children}</{tag}>"

    def _attributes(self, element: etree._Element, frame: int) -> dict[str, str]:
        """`element`'s attributes as its animations set them at `frame`."""
        attributes = {self._name(name): value for name, value in element.attrib.items()}
        for track in self.tracks.get(element, ()):
            index = int(track.index[frame])
            if index >= 0:
                value = track.values[index]
                written = attributes.get(track.attribute)
                attributes[track.attribute] = f"{written} {value}" if track.additive and written else value
        return attributes

    @staticmethod
    def _name(name: str) -> str:
        """An attribute's name as written in the document ('{xlink}href' -> 'xlink:href')."""
        qname = etree.QName(name)
        return f"xlink:{qname.localname}" if qname.namespace == XLINK_NS else qname.localname


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
