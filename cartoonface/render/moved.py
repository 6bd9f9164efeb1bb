"""Reused drawings moved by the track's own `<use>` in the page, not stored as `<use>`s (issue 16).

render/animation.py writes a drawing that is an affine map of an earlier one of its track (render/
reuse.py) as `<use id="fN" href="#fM" transform="matrix(a b c d e f)"/>` in the track's `<defs>`.
Chromium builds the shadow tree of every `<use>` in a document, displayed or not: each such drawing
costs a clone of its source (~6.5 us per cloned element against ~2 us for an element parsed, during
the page's first style update; docs/BENCHMARKS.md "Page style work"). In the page, `moved_tracks`
drops those drawings: the track's shown `<use>` points at the source instead and takes the matrix
from four discrete `<animateTransform additive="sum">` (translate, rotate, skewX, scale: any affine
map with a positive determinant, composed in document order) on the key times of its `href` where
their value changes.
A reused mouth whose basic shape (`data-shape`) differs from its source's is kept as written, so the
drawing the page shows still names the shape it shows.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from itertools import compress
from operator import ne

# As render/animation.py's _track_group writes them (lxml: attributes in the order given).
REUSED = re.compile(r'<use id="(f\w+)" href="#(f\w+)" transform="matrix\(([^)]*)\)"(?: data-shape="([^"]*)")?/>')
SHAPED = re.compile(r'<g id="(f\w+)" data-shape="([^"]*)"')
SHOWN = re.compile(r'</defs><use href="#(\w+)"><animate attributeName="href" calcMode="discrete" '
                   r'values="([^"]*)" keyTimes="([^"]*)"( dur="[^"]*" fill="freeze")/></use>')
KINDS = ("translate", "rotate", "skewX", "scale")
IDENTITY = ("0", "0", "0", "1")
DECIMALS = 6  # degrees and scales: 1e-6 of a degree or of the scale moves a point 400 px out by < 0.01 px


def _number(value: float) -> str:
    """`value` with at most DECIMALS decimals, no trailing zeros."""
    text = f"{value:.{DECIMALS}f}".rstrip("0").rstrip(".")
    return "0" if text in ("", "-0") else text


def affine_steps(matrix: str) -> tuple[str, str, str, str]:
    """The numbers of SVG's `matrix(a b c d e f)` (text) as translate(e f) rotate(deg) skewX(deg)
    scale(sx sy) values, whose product in that order is the matrix (determinant > 0)."""
    a, b, c, d, e, f = (float(v) for v in matrix.replace(",", " ").split())
    scale_x = math.hypot(a, b)
    scale_y = (a * d - b * c) / scale_x
    return (f"{_number(e)},{_number(f)}", _number(math.degrees(math.atan2(b, a))),
            _number(math.degrees(math.atan((a * c + b * d) / (scale_x * scale_y)))),
            f"{_number(scale_x)},{_number(scale_y)}")


def _changes(kind: str, values: Sequence[str], times: Sequence[str], timing: str) -> str:
    """A discrete additive `<animateTransform>` of `kind` holding `values` from `times` (key times,
    the first 0), each value written only where it changes (most runs show a drawing as written:
    identity)."""
    kept = [0, *compress(range(1, len(values)), map(ne, values[1:], values))]  # C loops: ~10,000 values a track
    return (f'<animateTransform attributeName="transform" type="{kind}" calcMode="discrete" additive="sum" '
            f'values="{";".join(values[index] for index in kept)}" '
            f'keyTimes="{";".join(times[index] for index in kept)}"{timing}/>')


def moved_tracks(text: str) -> str:
    """The tracks of an animation document `text` (as render/animation.py writes it) with their
    reused drawings shown by moving their source (module docstring); anything else as written."""
    shapes = dict(SHAPED.findall(text))
    moves: dict[str, tuple[str, tuple[str, str, str, str]]] = {}
    steps_of: dict[str, tuple[str, str, str, str]] = {}  # by matrix: a quarter of them are distinct

    def dropped(found: re.Match[str]) -> str:
        name, source, matrix, shape = found.groups()
        if shape is not None and shapes.get(source) != shape:
            return found.group(0)
        steps = steps_of.get(matrix)
        if steps is None:
            steps = steps_of[matrix] = affine_steps(matrix)
        moves[name] = (source, steps)
        return ""

    def shown(found: re.Match[str]) -> str:
        first, values, times, timing = found.groups()
        sources, steps = zip(*[moves.get(value[1:], (value[1:], IDENTITY)) for value in values.split(";")])
        if all(step == IDENTITY for step in steps):
            return found.group(0)
        keys = times.split(";")
        transforms = "".join(_changes(kind, column, keys, timing) for kind, column in zip(KINDS, zip(*steps)))
        return (f'</defs><use href="#{moves.get(first, (first,))[0]}"><animate attributeName="href" '
                f'calcMode="discrete" values="#{";#".join(sources)}" keyTimes="{times}"{timing}/>{transforms}</use>')

    return SHOWN.sub(shown, REUSED.sub(dropped, text))
