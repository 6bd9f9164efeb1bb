"""The SMIL animation of animation.svg resolved frame by frame (for the MP4 export, exports/video.py).

For each video frame the animation is resolved at the frame's time (`<set>` intervals,
discrete `<animate>` and `<animateTransform>`; docs/output.md describes what
render/animation.py writes) and the drawings a frame does not show are left out (of each
track's `<defs>` only the one its `<use>` points at, and the earlier drawing it shows transformed
when it is a reused one, render/reuse.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from xml.sax.saxutils import escape, quoteattr

import numpy as np
from lxml import etree

SVG_NS = "http://www.w3.org/2000/svg"
XLINK_NS = "http://www.w3.org/1999/xlink"
# Every frame is looked up half a millisecond after its start: the animation's times are whole
# milliseconds (render/animation.py frame_ms), so a frame starting on an interval's boundary
# is read inside the interval that begins there.
LOOKUP_OFFSET = 0.5  # ms
ANIMATIONS = {"set", "animate", "animateTransform"}


@dataclass(frozen=True)
class Track:
    """One animation element resolved over the video's frames: it sets `attribute` of its
    parent to values[index[k]] at frame k (index -1: not active, the attribute as written)."""

    attribute: str
    values: tuple[str, ...]
    index: np.ndarray  # (frames,) int
    additive: bool  # an <animateTransform additive="sum">: appended to the written transform


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
        return self.text(self.root, frame, {"width": str(width), "height": str(height)})

    def text(self, element: etree._Element, frame: int, override: dict[str, str] | None = None) -> str:
        """`element` as text at `frame` (empty when the frame hides it); `override`: attributes of its own replaced."""
        if element not in self.dynamic:
            text = self.static.get(element)
            if text is None:
                text = etree.tostring(element, encoding="unicode", with_tail=False)
                self.static[element] = text
            return text
        if element in self.shown_by:
            use, drawings = self.shown_by[element]
            drawing = drawings.get(self._attributes(use, frame).get("href", "").removeprefix("#"))
            if drawing is None:
                return ""
            # a reused drawing (render/reuse.py) is a <use> of an earlier drawing of the track
            source = drawings.get(drawing.get("href", "").removeprefix("#")) if drawing.get("href") else None
            shown = "" if source is None else self.text(source, frame)
            return f"<defs>{shown}{self.text(drawing, frame)}</defs>"
        opening = self.start_tag(element, frame, override)
        if opening is None:
            return ""
        tag = etree.QName(element).localname
        children = "".join(self.text(child, frame) for child in element
                           if not isinstance(child.tag, str) or etree.QName(child).localname not in ANIMATIONS)
        return f"{opening}{escape(element.text or '')}{children}</{tag}>"

    def start_tag(self, element: etree._Element, frame: int, override: dict[str, str] | None = None) -> str | None:
        """`element`'s start tag with its attributes as its animations set them at `frame` and `override`
        replacing some (None when the frame hides it: visibility="hidden")."""
        attributes = self._attributes(element, frame)
        if attributes.get("visibility") == "hidden":
            return None
        attributes.update(override or {})
        if element is self.root:
            attributes.update({"xmlns": SVG_NS, "xmlns:xlink": XLINK_NS})
        opening = "".join(f" {name}={quoteattr(value)}" for name, value in attributes.items())
        return f"<{etree.QName(element).localname}{opening}>"

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
