"""A video frame's picture put together from layers: what never changes drawn once, each animated part once per look.

The document's rendered elements are cut into pieces in paint order: the root's rendered
children, and the rendered children of an animated plain group (a `<g>` with no attribute but
id, transform and data-*, so painting its children one by one over the picture is painting the
group: render/animation.py's `face` layer with its part tracks). The leading pieces without
animation (the background) make the base picture, drawn once. Every other piece is drawn
alone on a transparent canvas for each of its looks (the value indices of the animations it
depends on: its own, its ancestors') and pasted over the picture with its alpha (source-over,
as a renderer paints it over what lies below; exports/compositor.py). A piece is drawn only
inside its box: the pixels any of its looks covers, found once by drawing all its looks over
one another.

Only the root `<defs>` children a piece refers to (url(#id), href="#id", and what those refer
to) go into its document, so the renderer does not parse the whole face's gradients and clip
paths for every small piece.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from lxml import etree
from PIL import Image

from cartoonface.exports.frames import ANIMATIONS, FrameDocuments, Track

# Elements that paint nothing where they stand (definitions, style, animations): kept in every
# piece's document, never pieces themselves.
NON_RENDERING = {"defs", "style", "title", "desc", "metadata", "script", "clipPath", "mask", "pattern",
                 "linearGradient", "radialGradient", "symbol", "marker", "filter", *ANIMATIONS}
PLAIN_ATTRIBUTES = {"id", "transform"}  # besides data-*: a group with only these paints as its children do
GRADIENTS = {"linearGradient", "radialGradient"}
REFERENCE = re.compile(r"#([A-Za-z_][\w.:-]*)")
FOOTPRINT_SHRINK = 4  # a piece's footprint (the box it is drawn in) is found on a 4 times smaller canvas
Box = tuple[int, int, int, int]  # x, y, width, height in pixels of the picture


def _name(element: etree._Element) -> str:
    """The local tag name ('' for a comment or processing instruction)."""
    return etree.QName(element).localname if isinstance(element.tag, str) else ""


@dataclass(frozen=True)
class Piece:
    """A rendered element painted on its own: `chain` its ancestors below the root (outermost
    first), `tracks` the animations its look depends on (on it, inside it, on its ancestors)."""

    element: etree._Element
    chain: tuple[etree._Element, ...]
    tracks: tuple[Track, ...]

    def look(self, frame: int) -> tuple[int, ...]:
        """The value index of each of its animations at `frame`: equal looks are equal pictures."""
        return tuple(int(track.index[frame]) for track in self.tracks)


@dataclass(frozen=True)
class Canvas:
    """How the document's user units land on a picture of `width` x `height` px (the root's
    viewBox scaled to fit and centred, SVG's default preserveAspectRatio)."""

    width: int
    height: int
    scale: float  # px per user unit
    left: float  # px of user x = 0
    top: float  # px of user y = 0

    def view_box(self, box: Box) -> str:
        """The viewBox that draws the picture's pixels `box` on a canvas of the box's size."""
        x, y, width, height = box
        return f"{(x - self.left) / self.scale!r} {(y - self.top) / self.scale!r} " \
               f"{width / self.scale!r} {height / self.scale!r}"


class Layers:
    """The pieces of the animation `frames` for pictures of `size` px (width, height)."""

    def __init__(self, frames: FrameDocuments, size: tuple[int, int]) -> None:
        self.frames = frames
        root = frames.root
        view = [float(v) for v in root.get("viewBox", "").split()] or \
            [0.0, 0.0, float(root.get("width", "0")), float(root.get("height", "0"))]
        scale = min(size[0] / view[2], size[1] / view[3])
        self.canvas = Canvas(size[0], size[1], scale, (size[0] - view[2] * scale) / 2 - view[0] * scale,
                             (size[1] - view[3] * scale) / 2 - view[1] * scale)
        # the root's definitions: each child of a root <defs> with the ids inside it and the ids it refers to
        self.definitions: list[etree._Element] = []
        self.defined: dict[str, int] = {}
        self.refers: list[set[str]] = []
        self.flat: dict[int, str] = {}  # a gradient's stand-in of one opaque colour (drawing boxes)
        self.context: list[etree._Element] = []  # the root's other non-rendering children (its <style>)
        for child in root:
            if _name(child) == "defs":
                for definition in child:
                    if not isinstance(definition.tag, str):
                        continue
                    for node in definition.iter():
                        if node.get("id") is not None:
                            self.defined[str(node.get("id"))] = len(self.definitions)
                    self.refers.append(set(REFERENCE.findall(etree.tostring(definition, encoding="unicode"))))
                    self.definitions.append(definition)
                    if _name(definition) in GRADIENTS:
                        self.flat[len(self.definitions) - 1] = \
                            f'<{_name(definition)} id="{definition.get("id")}"><stop stop-color="#000"/></{_name(definition)}>'

            elif _name(child) in NON_RENDERING:
                self.context.append(child)
        pieces: list[Piece] = []
        self._split(root, (), pieces)
        # a piece's animations: on it or inside it, on its ancestors, and on no other piece's
        # element or ancestor (an animated definition of the root's)
        owner = {node: piece for piece in pieces for node in piece.element.iter()}
        holders = {ancestor for piece in pieces for ancestor in piece.chain}
        self.pieces = [Piece(p.element, p.chain, tuple(
            track for element, tracks in frames.tracks.items() for track in tracks
            if owner.get(element) is p or element in p.chain or (element not in owner and element not in holders)))
            for p in pieces]
        # the base: the leading pieces that never change
        lead = next((k for k, piece in enumerate(self.pieces) if piece.tracks), len(self.pieces))
        self.base, self.animated = self.pieces[:lead], self.pieces[lead:]

    def _split(self, element: etree._Element, chain: tuple[etree._Element, ...], out: list[Piece]) -> None:
        """Append the pieces of `element`'s rendered children (their ancestors below the root: `chain`)."""
        for child in element:
            if _name(child) in NON_RENDERING or not _name(child):
                continue
            rendered = [c for c in child if _name(c) and _name(c) not in NON_RENDERING]
            plain = _name(child) == "g" and all(name in PLAIN_ATTRIBUTES or name.startswith("data-")
                                                for name in child.attrib)
            if child in self.frames.dynamic and plain and len(rendered) >= 2:
                self._split(child, (*chain, child), out)
            else:
                out.append(Piece(child, chain, ()))

    def piece_text(self, piece: Piece, frame: int) -> str:
        """`piece` at `frame` inside its ancestors' start tags (their definitions too); '' when hidden."""
        opened, closing = [], []
        for ancestor in piece.chain:
            tag = self.frames.start_tag(ancestor, frame)
            if tag is None:
                return ""
            definitions = "".join(self.frames.text(child, frame) for child in ancestor
                                  if _name(child) in NON_RENDERING and _name(child) not in ANIMATIONS)
            opened.append(tag + definitions)
            closing.append(f"</{_name(ancestor)}>")
        return "".join(opened) + self.frames.text(piece.element, frame) + "".join(reversed(closing))

    def document(self, body: str, box: Box, frame: int = 0, footprint: bool = False) -> str:
        """An SVG document drawing `body` (piece texts) on a transparent canvas of the picture's
        pixels `box`, with the root's context and the definitions `body` refers to (at `frame`).

        `footprint`: drawn for finding where `body` draws: FOOTPRINT_SHRINK times smaller (the
        box grown to a multiple of it), the root's gradients as one opaque colour (a one-stop
        gradient paints its stop's colour, SVG 1.1 13.2.4: faster, and a gradient that is
        transparent somewhere never covers more than the opaque colour)."""
        context = "".join(self.frames.text(element, frame) for element in self.context)
        wanted: set[int] = set()
        todo = REFERENCE.findall(body + context)
        while todo:
            index = self.defined.get(todo.pop())
            if index is not None and index not in wanted:
                wanted.add(index)
                todo.extend(self.refers[index])
        definitions = "".join(self.flat[k] if footprint and k in self.flat
                              else self.frames.text(self.definitions[k], frame) for k in sorted(wanted))
        shrink = FOOTPRINT_SHRINK if footprint else 1
        width, height = -(-box[2] // shrink), -(-box[3] // shrink)
        tag = self.frames.start_tag(self.frames.root, frame, {
            "width": str(width), "height": str(height),
            "viewBox": self.canvas.view_box((box[0], box[1], width * shrink, height * shrink))})
        return f"{tag}{context}<defs>{definitions}</defs>{body}</svg>"

    def whole(self) -> Box:
        """The whole picture as a box."""
        return 0, 0, self.canvas.width, self.canvas.height


def bounds(picture: Image.Image, box: Box) -> Box | None:
    """The box (picture px) of the pixels of `picture` (RGBA, drawn in `box`) that are not fully
    transparent; None if none is."""
    inner = picture.getchannel("A").getbbox()
    if inner is None:
        return None
    return box[0] + inner[0], box[1] + inner[1], inner[2] - inner[0], inner[3] - inner[1]


def footprint_bounds(picture: Image.Image, box: Box, limit: tuple[int, int]) -> Box | None:
    """Where a document drawn with `footprint` (the picture's pixels `box`, shrunk) may paint at
    full size: its not fully transparent pixels grown by one shrunk pixel each way (an edge that
    covers a full-size pixel a little can cover its shrunk pixel too little to show), kept inside
    a picture of `limit` (width, height) px; None if nothing shows."""
    inner = picture.getchannel("A").getbbox()
    if inner is None:
        return None
    left, top = max(0, box[0] + (inner[0] - 1) * FOOTPRINT_SHRINK), max(0, box[1] + (inner[1] - 1) * FOOTPRINT_SHRINK)
    right = min(limit[0], box[0] + (inner[2] + 1) * FOOTPRINT_SHRINK)
    bottom = min(limit[1], box[1] + (inner[3] + 1) * FOOTPRINT_SHRINK)
    return left, top, right - left, bottom - top


def spills(seen: Box, box: Box, whole: Box) -> bool:
    """Whether what was drawn in `box` (`seen`: the bounds of its pixels) reaches an edge of the box
    that is not an edge of the picture `whole` (and so may go on beyond the box)."""
    return (seen[0] == box[0] > whole[0] or seen[1] == box[1] > whole[1]
            or seen[0] + seen[2] == box[0] + box[2] < whole[0] + whole[2]
            or seen[1] + seen[3] == box[1] + box[3] < whole[1] + whole[3])


def union(boxes: list[Box | None]) -> Box | None:
    """The smallest box holding every box given (None for none)."""
    real = [box for box in boxes if box is not None]
    if not real:
        return None
    left, top = min(b[0] for b in real), min(b[1] for b in real)
    right, bottom = max(b[0] + b[2] for b in real), max(b[1] + b[3] for b in real)
    return left, top, right - left, bottom - top
