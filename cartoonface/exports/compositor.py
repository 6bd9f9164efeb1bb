"""A video frame's picture put together from the pieces of exports/layers.py, drawn by librsvg.

The base pieces are drawn once into the picture under every frame; each animated piece is
drawn (librsvg through libvips, which hands over raw RGBA pixels) once per look inside its
box and pasted over it by its alpha. A compositor keeps its pictures between frames: the
pieces below the one with the most looks (the mouth's track) stay pasted in a picture kept
while their looks stay, and per frame only the regions the pieces covered are restored.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import pyvips
from PIL import Image

from cartoonface.exports.layers import Box, Layers, Piece, bounds, footprint_bounds, spills, union

PAD_COLOUR = "white"  # around a picture whose shape is not the video's, and under its transparent parts
OVERLAY = 64  # looks of a piece drawn over one another in one document to find its box
CACHE = 24  # looks of a piece a compositor keeps drawn (the hair of a swaying head comes back)
Region = tuple[int, int, int, int]  # left, top, right, bottom on the video, px
Sprite = tuple[tuple[int, int], Image.Image]  # a piece's picture (RGBA) and its top left corner on the video
# draws documents (a function over a list: a process pool's map, or `serial`)
Mapper = Callable[[Callable[[str], Image.Image], list[str]], list[Image.Image]]


def draw(document: str) -> Image.Image:
    """A static SVG document -> its RGBA picture (librsvg through libvips: raw pixels, no PNG).

    libvips starts threads when it draws: a process that has drawn must not fork afterwards
    (the child hangs), so write_video draws only in the worker processes it forks."""
    drawn = pyvips.Image.svgload_buffer(document.encode())
    return Image.frombuffer("RGBA", (drawn.width, drawn.height), drawn.write_to_memory(), "raw", "RGBA", 0, 1)


def one_thread() -> None:
    """Let libvips draw on the calling process's thread alone (processes share the cores) and
    keep no cache (no two documents drawn are alike)."""
    pyvips.concurrency_set(1)
    pyvips.cache_set_max(0)


@dataclass(frozen=True)
class Stage:
    """What a compositor puts frames together from: `base` (the video's size, white, the base
    pieces drawn at `offset`, the picture's top left corner on the video), each animated
    piece's box (picture px, None: never seen) and `split`, the index of the animated piece
    with the most looks."""

    layers: Layers
    base: Image.Image
    boxes: list[Box | None]
    offset: tuple[int, int]
    split: int


def serial(function: Callable[[str], Image.Image], documents: list[str]) -> list[Image.Image]:
    """`function` over `documents` in this process (a `Mapper`)."""
    return [function(document) for document in documents]


def stage(layers: Layers, distinct: Sequence[int], size: tuple[int, int], mapper: Mapper = serial) -> Stage:
    """The stage of `layers` for frames `distinct` on a video of `size` (width, height px): the
    base drawn once, each animated piece's box from all its looks drawn over one another
    (OVERLAY looks a document; `mapper(draw, documents)` draws them, e.g. a process pool's map)."""
    picture = (layers.canvas.width, layers.canvas.height)
    offset = ((size[0] - picture[0]) // 2, (size[1] - picture[1]) // 2)
    whole = layers.whole()
    documents = [layers.document("".join(layers.piece_text(piece, 0) for piece in layers.base), whole)]
    owners, counts = [], []
    for index, piece in enumerate(layers.animated):
        looks: dict[tuple[int, ...], int] = {}
        for frame in distinct:
            looks.setdefault(piece.look(frame), frame)
        shown = list(looks.values())
        counts.append(len(shown))
        for first in range(0, len(shown), OVERLAY):
            group = shown[first: first + OVERLAY]
            documents.append(layers.document("".join(layers.piece_text(piece, f) for f in group), whole, group[0],
                                             footprint=True))
            owners.append(index)
    pictures = mapper(draw, documents)
    base = Image.new("RGB", size, PAD_COLOUR)
    base.paste(pictures[0], offset, pictures[0])
    boxes: list[Box | None] = [None] * len(layers.animated)
    for owner, picture_drawn in zip(owners, pictures[1:], strict=True):
        boxes[owner] = union([boxes[owner], footprint_bounds(picture_drawn, whole, whole[2:])])
    split = max(range(len(counts)), key=counts.__getitem__, default=0)
    return Stage(layers, base, boxes, offset, split)


class Compositor:
    """Puts frames of a `Stage` together, keeping its pictures and latest drawn looks between frames."""

    def __init__(self, scene: Stage) -> None:
        self.scene = scene
        self.under = scene.base.copy()  # the base with the pieces below the split in `looks`
        self.picture = scene.base.copy()  # the last frame: `under` with the pieces above
        self.looks: tuple[tuple[int, ...], ...] | None = None
        self.under_dirty: Region | None = None  # where `under` differs from the base
        self.picture_dirty: Region | None = None  # where `picture` differs from `under`
        self.sprites: list[OrderedDict[tuple[int, ...], Sprite | None]] = [OrderedDict() for _ in scene.boxes]

    def frame(self, frame: int) -> Image.Image:
        """The picture of `frame` (RGB, the video's size); it is changed by the next call."""
        split = self.scene.split
        looks = tuple(piece.look(frame) for piece in self.scene.layers.animated)
        sprites = [self._cached(index, look, frame) for index, look in enumerate(looks)]
        changed = self.picture_dirty
        if looks[:split] != self.looks:
            changed = _union_region(changed, self.under_dirty)
            _restore(self.under, self.scene.base, self.under_dirty)
            self.under_dirty = _paste(self.under, sprites[:split])
            changed = _union_region(changed, self.under_dirty)
            self.looks = looks[:split]
        _restore(self.picture, self.under, changed)
        self.picture_dirty = _paste(self.picture, sprites[split:])
        return self.picture

    def _cached(self, index: int, look: tuple[int, ...], frame: int) -> Sprite | None:
        """Animated piece `index` in `look` (that of `frame`), from the latest CACHE looks or drawn."""
        box = self.scene.boxes[index]
        if box is None:
            return None
        cache = self.sprites[index]
        if look in cache:
            cache.move_to_end(look)
            return cache[look]
        sprite = cache[look] = self._sprite(self.scene.layers.animated[index], box, frame)
        if len(cache) > CACHE:
            cache.popitem(last=False)
        return sprite

    def _sprite(self, piece: Piece, box: Box, frame: int) -> Sprite | None:
        """`piece` at `frame` drawn in its `box`: its top left corner on the video and its RGBA
        picture cut to its visible pixels (None when nothing shows)."""
        layers = self.scene.layers
        text = layers.piece_text(piece, frame)
        drawn = draw(layers.document(text, box, frame))
        seen = bounds(drawn, box)
        if seen is None:
            return None
        whole = layers.whole()
        if spills(seen, box, whole):
            # drawn up to an edge of its box that is not the picture's: it may go on outside, draw it whole
            box = whole
            drawn = draw(layers.document(text, box, frame))
            seen = bounds(drawn, box)
            assert seen is not None
        x, y, width, height = seen
        cut = drawn.crop((x - box[0], y - box[1], x - box[0] + width, y - box[1] + height))
        return (x + self.scene.offset[0], y + self.scene.offset[1]), cut


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
