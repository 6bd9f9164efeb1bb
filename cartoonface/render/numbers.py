"""Numbers as SVG text: the one place the render modules turn floats into attribute text.

`number_text` / `number_texts` write coordinates of the face drawing rounded to 0.1 px
with the fewest characters (".5", "-12.3"); `number_texts` formats a whole array through
a table of every tenth (the hot path of render/geometry.py's face_shapes).
`decimal_text` writes a number with at most a given number of decimals and a leading zero
("0.5"): the scenery's coordinates, SMIL clock values and key times (`fraction_texts`: many
key times at once, the same text). The two round ties
differently (number_text rounds value * 10 half to even, decimal_text rounds the exact
binary value) and write .5 differently, so each caller keeps the text it always wrote.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence

import numpy as np

# Coordinates are written in tenths of a pixel: the finest step a screen shows.
TENTHS = 10


# number_texts reads a table of every tenth of a pixel in +-REACH tenths, made in blocks of BLOCK
# tenths as numbers need them: a drawing's numbers span a few blocks of its canvas, so a process makes
# a tenth of the table (~1 ms instead of ~11 ms for all of it).
REACH = 1 << 15
BLOCK = 1000


def _positive_texts(start: int, stop: int) -> list[str]:
    """_tenths_text of every tenth in [start, stop) (0 <= start, both multiples of TENTHS), made
    from the whole parts' texts (3x faster than calling it for each)."""
    fractions = [f".{digit}" for digit in range(1, TENTHS)]
    return [text for whole in range(start // TENTHS, stop // TENTHS)
            for head in (str(whole),)
            for text in (head, *((head if whole else "") + fraction for fraction in fractions))]


@functools.lru_cache(maxsize=2 * REACH // BLOCK + 2)
def _block(index: int) -> np.ndarray:
    """_tenths_text of every tenth in [index BLOCK, (index + 1) BLOCK), (BLOCK,) texts."""
    if index >= 0:
        return np.array(_positive_texts(index * BLOCK, (index + 1) * BLOCK), dtype=object)
    # "-" and the text of each opposite, from -(index BLOCK) down to -((index + 1) BLOCK) + 1
    start = -(index + 1) * BLOCK
    positive = _positive_texts(start, start + BLOCK + TENTHS)
    return np.array(["-" + positive[opposite - start] for opposite in range(start + BLOCK, start, -1)], dtype=object)


@functools.lru_cache(maxsize=256)
def _blocks(first: int, last: int) -> np.ndarray:
    """The texts of the blocks `first` .. `last` (_block's) as one array."""
    return np.concatenate([_block(index) for index in range(first, last + 1)])


def _tenths_text(tenths: int) -> str:
    """The shortest SVG number text for `tenths`/10: 12, 12.5, .5, -.5."""
    sign = "-" if tenths < 0 else ""
    whole, frac = divmod(abs(tenths), TENTHS)
    if frac == 0:
        return f"{sign}{whole}"
    return f"{sign}{whole or ''}.{frac}"


def number_texts(values: np.ndarray) -> tuple[str, ...]:
    """Takes any float array (pixels); returns its values, flattened, as SVG number text
    rounded to 0.1 px with the fewest characters."""
    return tuple(tenths_texts(rounded_tenths(values)))


_NARROW = np.iinfo(np.int32)


def rounded_tenths(values: np.ndarray) -> np.ndarray:
    """Any float array (pixels) in whole tenths of a pixel, as number_texts rounds them (same shape):
    int32 where they all fit (a drawing's always: the rows the drawing compares and keeps by the
    thousand are half as many bytes), else int64."""
    scaled = np.rint(np.asarray(values, dtype=float) * TENTHS)
    fits = not scaled.size or _NARROW.min <= scaled.min() and scaled.max() <= _NARROW.max
    return scaled.astype(np.int32 if fits else np.int64)


def tenths_texts(tenths: np.ndarray) -> list[str]:
    """number_texts of values given in whole tenths (rounded_tenths' integers), flattened, as a list
    (the drawing slices it: a process writes ~a million numbers, not copied into a tuple)."""
    tenths = np.asarray(tenths).ravel()
    if not tenths.size:
        return []
    low, high = int(tenths.min()), int(tenths.max())
    if low < -REACH or high >= REACH:
        return [_tenths_text(int(v)) for v in tenths]
    first = low // BLOCK
    texts: list[str] = _blocks(first, high // BLOCK)[tenths - first * BLOCK].tolist()
    return texts


def template_frame(template: str) -> tuple[str, ...]:
    """`template`, a text with "%s" slots (and no other "%"), as the frame `fill` writes: its
    pieces with an empty slot between each two (2 k + 1 strings for k slots)."""
    pieces = template.split("%s")
    frame = [""] * (2 * len(pieces) - 1)
    frame[0::2] = pieces
    return tuple(frame)


def fill(frame: tuple[str, ...], texts: Sequence[str]) -> str:
    """`template % texts` for the `frame` of template_frame(template) (len(texts) its slots):
    one join, twice as fast as the %-format on a drawing's ~1,000 numbers."""
    joined = list(frame)
    joined[1::2] = texts
    return "".join(joined)


def number_text(value: float) -> str:
    """One number (pixels) as SVG text rounded to 0.1 px, e.g. 12.5 -> "12.5", 3.0 -> "3"."""
    return _tenths_text(int(round(float(value) * TENTHS)))


def decimal_text(value: float, decimals: int) -> str:
    """`value` rounded to `decimals` (>= 1) decimals, trailing zeros and a trailing "." dropped,
    e.g. (12.0, 1) -> "12", (0.25, 3) -> "0.25", (-0.04, 1) -> "-0"."""
    return f"{value:.{decimals}f}".rstrip("0").rstrip(".")


def fraction_texts(numerators: Sequence[int], decimals: int) -> list[str]:
    """decimal_text(n / 10 ** decimals, decimals) of each of the whole `numerators` n
    (0 <= n < 10 ** decimals, decimals <= 15): the digits of n after "0." with the trailing zeros
    cut off ("0.0012300" -> "0.00123", "0.0000000" -> "0"), which is decimal_text's text, since the
    double nearest n / 10 ** decimals rounds back to n; no float formatted, 1.6x faster."""
    padded = f"0.{{:0{decimals}d}}".format
    return [text.rstrip("0").rstrip(".") for text in map(padded, numerators)]


def distinct_rows(rows: np.ndarray) -> tuple[np.ndarray, list[int]]:
    """The distinct rows of `rows` (n, k), k > 0, in the order first seen, (u, k), and each row's
    number among them (n): the rows compared as bytes (3x faster than np.unique), cut by one
    tolist of them viewed as one void each (a third faster than slicing the bytes)."""
    keys = np.ascontiguousarray(rows).view(f"V{rows.itemsize * rows.shape[1]}").ravel().tolist()
    seen: dict[bytes, int] = {}
    numbers = [seen.setdefault(key, len(seen)) for key in keys]
    return np.frombuffer(b"".join(seen), dtype=rows.dtype).reshape(len(seen), rows.shape[1]), numbers
