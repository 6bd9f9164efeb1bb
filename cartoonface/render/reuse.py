"""Drawings shown as an affine transform of an earlier drawing of their track (issue 16).

Most distinct drawings of a track differ from an earlier one by little more than a small change
of head pose (under a turn of a fraction of a degree a part's points move almost affinely) or an
unseen change of the mouth mix. Such a drawing is written as `<use href="#fM"
transform="matrix(a b c d e f)">` of the earlier one (render/animation.py `_track_group`).

A drawing can be reused when it has the earlier drawing's *skeleton* (the same elements,
attributes and path commands; its numbers taken out) and a least-squares affine maps the earlier
drawing's points onto its own, every point within TOLERANCE px once the matrix is rounded as
written. The points are those of the parts as render/svg.py's face_parts drew them (tenths of a
pixel), before the compactor rounds them to whole pixels: what is shown is then the written form
of a drawing within TOLERANCE of the exact one (comparing the whole-pixel forms, the rounding of
both, up to 0.7 px each, would hide every match). The points are those a transform moves: every path point and control
point, eight points on each circle or ellipse (the axes' ends and the diagonals between: a
circle turned into an ellipse by shear or unequal scale is compared along its whole outline,
the differences being first-order sines of the angle, at most 1.08 times the largest of eight
samples), the points of the hoisted clip paths a drawing refers to (they are drawn in its user
space, so they move with it). A stroke scales with the transform: half the widest stroke times
the largest change of scale is added to the error. Gradients are in the shapes' bounding boxes
(render/svg.py's face_defs) and move with them. A drawing holding what this does not read (a
transform of its own, arcs, other shapes) is always written.

A part of a drawing still written in full (its mouth, an eye: find_alike) is reused on its own the
same way, its candidates found among all earlier parts of its skeleton by their shape once
normalised by a least-squares affine, not only among the recent ones.

The matrix found is written as short as the tolerance allows (_shortened, FORMS): a..d and e, f with
fewer decimals where every point stays within it, so most are a whole-pixel shift or the earlier
drawing itself unmoved (IDENTITY, which render/animation.py writes as that drawing): texts that gzip
finds again.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from itertools import repeat
from typing import NamedTuple

import numpy as np

from cartoonface.render.compact import PLACEHOLDER, SENTINEL, Form, Formed
from cartoonface.render.pathdata import Tenths, taken_or_read


# Largest distance (px) between a point of the earlier drawing as drawn, moved by the matrix as
# written, and the same point of the drawing it stands for (0.35 / 0.5 / 0.7 measured:
# docs/BENCHMARKS.md, "Reused drawings").
TOLERANCE = 0.5
# A drawing is compared with the last CANDIDATES drawings of its skeleton before it, the nearest in
# time first (pose changes slowly), and shown as a transform of the first written one that fits.
CANDIDATES = 16
# The matrix as fitted: a..d to 4 decimals (1e-4 of 400 px is 0.04 px), e and f to 1 (0.05 px).
LINEAR_DECIMALS = 4
SHIFT_DECIMALS = 1
# ... and as written (_shortened): the first of FORMS (decimals of a..d, of e and f; the shortest texts
# first) that keeps every point within the tolerance, a..d the fitted ones rounded, e and f put in the
# middle of the points' spread and rounded. Most reused parts are then a whole-pixel shift or the
# earlier one itself ("1 0 0 1 0 0", IDENTITY), which gzip finds again: docs/BENCHMARKS.md, "Gzipped
# weight".
FORMS = tuple((linear, shift) for linear in (0, 2, 3, LINEAR_DECIMALS) for shift in (0, SHIFT_DECIMALS))
IDENTITY = "1 0 0 1 0 0"
PAIR_POINTS = 1 << 15  # points of the pairs _pair_points gathers at a time (~0.5 MB an array: in cache)
# The affines are fitted on FIT_POINTS of each drawing's points, spread over it (a fit on a few
# dozen points is about as good as on all of them, and the pairs of a track fit in a few batches); the
# error is measured on them and, for a pair within the tolerance there, on all the points.
FIT_POINTS = 24
FIT_PAIRS = 8192  # candidate pairs fitted together (_choose): ~3 KB of temporaries each
# The pairs are first measured on COARSE of the samples, evenly spaced: most are far from the
# tolerance on them already (19 in 20 of the face track's pairs of drawings, half of its parts'), and
# only the others are measured on all.
COARSE = 4
# A part reused on its own (find_alike: the mouth, whose mix changes in every drawing of the face
# track) is compared with the ALIKE earlier parts of its skeleton nearest in shape, from all of
# them; the nearness of ROWS parts to all earlier ones is computed at a time (ROWS x parts floats).
ALIKE = 8
ROWS = 512
_DIAGONAL = np.sqrt(0.5)
_ELLIPSE = np.array([(1, 0), (0, 1), (-1, 0), (0, -1), (_DIAGONAL, _DIAGONAL), (_DIAGONAL, -_DIAGONAL),
                     (-_DIAGONAL, _DIAGONAL), (-_DIAGONAL, -_DIAGONAL)])  # eight points on a unit circle
_TAG = re.compile(r"<(\w+)")
_READ = frozenset(("path", "circle", "ellipse", "g", "clipPath"))  # the elements whose geometry shapes_of reads
_GEOMETRY = re.compile(r' (d|cx|cy|r|rx|ry)="([^"]*)"')  # the attributes whose numbers are points
_PAIRS = re.compile(r"[MLCSQTZ\d\s.,-]*")  # path data of absolute commands taking point pairs
_STROKE = re.compile(r' stroke-width="([\d.]+)"')
_LETTERS_TO_SPACES = str.maketrans({**{c: " " for c in "MLCSQTZHVAmlcsqtzhva,\x01"}})
# taken out of a skeleton (by bytes.translate: twice as fast as str.translate's deletion; UTF-8 holds
# these bytes only as these characters)
_NUMBER_CHARACTERS = b"0123456789."


class Shape(NamedTuple):
    """What a transform moves in a drawing (or one of its parts): `skeleton` (equal for drawings
    with the same elements, attributes and path commands), `points` (N, 2) px, and `stroke`,
    the widest stroke width (px) in it. (A named tuple: made at a third of a frozen dataclass's cost,
    for ten thousand parts and drawings.)"""

    skeleton: str
    points: np.ndarray
    stroke: float


@dataclass(frozen=True)
class Reuse:
    """Drawing `source` (a written one of the same track) transformed by `matrix` (the SVG text
    "a b c d e f") stands for the drawing; `error` is the largest distance (px) of a point."""

    source: int
    matrix: str
    error: float


@dataclass(frozen=True)
class _Layout:
    """How the K geometry numbers of a skeleton's parts make their P points (_layout): x and y
    interleaved, point = numbers[firsts] + weights * numbers[seconds] ((2P,) each; a path's weight
    0); `counts`, the numbers in each of its V geometry values, and `paths`, which of them are path
    data."""

    firsts: np.ndarray
    seconds: np.ndarray
    weights: np.ndarray
    counts: tuple[int, ...]
    paths: tuple[bool, ...]


Layouts = dict[str, _Layout | None]  # _layout of each skeleton met (read_parts' cache)


def _layout(names: Sequence[str], values: Sequence[str], rest: str) -> _Layout | None:
    """How the geometry numbers of a part (attributes `names` with `values`, in order; `rest` the
    text around them) make its points: a path's numbers in pairs (absolute commands of point
    pairs: face_parts' M, L, C, Z), eight points on each circle or ellipse (a centre plus a step
    times a radius). None for a part with other path data, elements, a transform or a circle
    without its centre."""
    if not set(_TAG.findall(rest)) <= _READ or " transform=" in rest:
        return None
    firsts: list[int] = []
    seconds: list[int] = []
    weights: list[float] = []
    unread: list[list[str]] = []
    numbers = [len(value.translate(_LETTERS_TO_SPACES).split()) for value in values]
    column = 0
    circle: dict[str, int] = {}

    def close() -> None:  # the circle or ellipse whose attributes `circle` holds (their columns)
        if circle and not {"cx", "cy"} <= set(circle):
            unread.append(sorted(circle))  # a centre at 0 by default: not read
        radii = (circle.get("r", circle.get("rx")), circle.get("r", circle.get("ry")))
        for unit in _ELLIPSE if circle else ():
            for centre, radius, step in zip((circle.get("cx", 0), circle.get("cy", 0)), radii, unit, strict=True):
                firsts.append(centre)
                seconds.append(centre if radius is None else radius)
                weights.append(0.0 if radius is None else float(step))
        circle.clear()

    for name, value, count in zip(names, values, numbers, strict=True):
        if name == "d":
            close()
            if not _PAIRS.fullmatch(value) or count % 2:
                return None
            firsts.extend(range(column, column + count))
            seconds.extend(range(column, column + count))
            weights.extend([0.0] * count)
        else:
            if name in circle:
                close()
            circle[name] = column
        column += count
    close()
    return None if unread else _Layout(np.array(firsts, dtype=int), np.array(seconds, dtype=int), np.array(weights),
                                       tuple(numbers), tuple(name == "d" for name in names))


@dataclass(frozen=True)
class Readings:
    """The geometry of parts read from their texts (read_parts), to make their Shapes from (shapes_from)
    here or in another process: pickled as a few hundred arrays, not one per part (a drawing
    helper reads the parts it drew, render/animation.py). Per skeleton with a _Layout: the
    skeleton, its layout, its widest stroke (px) and the geometry numbers (R, K) of its R parts;
    per part, its skeleton's number in them (`skeleton`, -1 for a part whose layout is None) and
    its row there (`row`), (P,) each."""

    skeletons: list[str]
    layouts: list[_Layout]
    strokes: list[float]
    numbers: list[np.ndarray]
    skeleton: np.ndarray
    row: np.ndarray


def shapes_of(parts: Sequence[Sequence[str]], tenths: Tenths | None = None) -> list[Shape | None]:
    """The Shape of each of `parts` as render/svg.py's face_parts drew it (the texts of its element
    and of the definitions, clip paths, it refers to; coordinates in tenths of a pixel). None for
    a part holding an element or attribute this does not read (a transform, an arc, a rect, ...).
    shapes_from of read_parts; `tenths` (render/pathdata.py's Tenths): the numbers of some of the
    path data as drawn, taken rather than read again."""
    return shapes_from(read_parts(parts, {}, tenths), range(len(parts)))


def read_parts(parts: Sequence[Sequence[str]], layouts: Layouts, tenths: Tenths | None = None,
               formed: Sequence[Formed | None] | None = None) -> Readings:
    """The Readings of `parts` (each the texts of its element and of its definitions): each part's
    skeleton (its texts with the numbers of its geometry values taken out), the numbers of all parts
    of one skeleton read in one go (_numbers) as the skeleton's _layout reads them (`layouts`
    caches it by skeleton). `tenths` (render/pathdata.py's Tenths): the numbers of some of the path
    data as drawn, taken rather than read again. `formed`: per part, the Form and slots it was drawn
    from (render/compact.py's Formed) or None: the geometry values of a part with one are its slots
    as its Form places them (_recipe), not cut out of its text (the same values: checked on the
    first part of each Form)."""
    members: dict[str, list[tuple[int, list[str]]]] = {}  # by skeleton: (part's index, its geometry values)
    recipes: dict[Form, _Recipe | None] = {}
    for index, texts in enumerate(parts):
        known = formed[index] if formed is not None else None
        recipe = None
        if known is not None:
            if known[0] not in recipes:
                recipes[known[0]] = _recipe(*known, texts)
            recipe = recipes[known[0]]
        if recipe is None or known is None:
            names, values, rest = _pieces(texts)
        else:
            rest, names, sources = recipe
            values = [known[1][slot] if slot >= 0 else text for slot, text in sources]
        skeleton = f"{rest}\x03{'|'.join(names)}\x03{_stripped(values)}"
        if skeleton not in layouts:
            layouts[skeleton] = _layout(names, values, rest)
        members.setdefault(skeleton, []).append((index, values))
    readings = Readings([], [], [], [], np.full(len(parts), -1, dtype=np.int32), np.zeros(len(parts), dtype=np.int32))
    for skeleton, group in members.items():
        layout = layouts[skeleton]
        if layout is None:
            continue
        indices = [index for index, _ in group]
        readings.skeleton[indices] = len(readings.skeletons)
        readings.row[indices] = np.arange(len(group), dtype=np.int32)
        readings.skeletons.append(skeleton)
        readings.layouts.append(layout)
        readings.strokes.append(max(map(float, _STROKE.findall(skeleton.partition("\x03")[0])), default=0.0))
        readings.numbers.append(_numbers([values for _, values in group], layout, tenths or {}))
    return readings


def _pieces(texts: Sequence[str]) -> tuple[list[str], list[str], str]:
    """The names and values of the geometry attributes (_GEOMETRY) of a part's `texts`, in order,
    and the text around them ("\x02" between the pieces)."""
    pieces = _GEOMETRY.split("".join(texts))
    return pieces[1::3], pieces[2::3], "\x02".join(pieces[0::3])


def _stripped(values: Sequence[str]) -> str:
    """Geometry `values` with their numbers' digits and points taken out ("\x01" between them)."""
    return "\x01".join(values).encode().translate(None, _NUMBER_CHARACTERS).decode()


# How the parts of one Form make their geometry values (read_parts): the text around them and
# their names (_pieces', the same for every part of the Form), and where each value comes from:
# (slot, "") or (-1, the value itself).
_Recipe = tuple[str, list[str], list[tuple[int, str]]]
# A geometry value of a Form's skeleton (compact._skeleton's): a path data's token "@k@" (the
# Form's k-th path slot), a position's or size's placeholder (SENTINEL + j: its j-th field).
_PLACEHOLDER = re.compile(PLACEHOLDER)


def _recipe(form: Form, slots: Sequence[str], texts: Sequence[str]) -> _Recipe | None:
    """The _Recipe of the parts of `form`, found in its skeleton and checked on one of them (its
    `slots` and `texts`); None when a slot fills something else than a geometry value (the text
    around them would change) or the part's values are not those its slots make."""
    names, values, rest = _pieces(texts)
    pieces = _GEOMETRY.split(form.skeleton)
    sources: list[tuple[int, str]] = []
    placed = set()  # the Form's fields placed in geometry values
    for value in pieces[2::3]:
        match = _PLACEHOLDER.fullmatch(value)
        if match is None:
            sources.append((-1, value))  # kept in the skeleton: the same in every part
        elif match.group(1) is not None:
            sources.append((form.paths[int(match.group(1))], ""))
        else:
            placed.add(field := int(match.group(2)) - SENTINEL)
            sources.append(form.fields[field][:2])
    if (pieces[1::3] != names or any(slot >= 0 for field, (slot, _, _) in enumerate(form.fields) if field not in placed)
            or [slots[slot] if slot >= 0 else text for slot, text in sources] != values):
        return None
    return rest, names, sources


def shapes_from(readings: Readings, indices: Iterable[int]) -> list[Shape | None]:
    """The Shape (None: not read) of each of the parts `indices` of `readings`: the points of all
    of one skeleton made in one go by its _layout, point = numbers[firsts] + weights * numbers[seconds]."""
    wanted = np.fromiter(indices, dtype=np.intp)
    skeletons = readings.skeleton[wanted]
    shapes: list[Shape | None] = [None] * len(wanted)
    order = np.argsort(skeletons, kind="stable")  # the parts of one skeleton together
    for places in np.split(order, np.flatnonzero(np.diff(skeletons[order])) + 1) if len(order) else ():
        number = int(skeletons[places[0]])
        if number < 0:
            continue
        layout = readings.layouts[number]
        numbers = readings.numbers[number][readings.row[wanted[places]]]
        points = (numbers[:, layout.firsts] + layout.weights * numbers[:, layout.seconds]).reshape(len(places), -1, 2)
        made = map(Shape, repeat(readings.skeletons[number]), points, repeat(readings.strokes[number]))
        for place, shape in zip(places.tolist(), made, strict=True):
            shapes[place] = shape
    return shapes


def _numbers(rows: Sequence[Sequence[str]], layout: _Layout, tenths: Tenths) -> np.ndarray:
    """The geometry numbers (R, K) of parts of one skeleton (`rows`: each part's values, as its
    `layout` reads them), value by value: a path data in `tenths` taken from there
    (pathdata.taken_or_read; a zero is written "0", never "-0"), the others read from their texts
    (_read)."""
    if not tenths or not any(layout.paths):
        return _read(["\x01".join(values) for values in rows], sum(layout.counts))
    columns = []
    for slot, (count, path) in enumerate(zip(layout.counts, layout.paths, strict=True)):
        values = [row[slot] for row in rows]
        column = taken_or_read(values, tenths, functools.partial(_read, count=count)) if path else None
        columns.append(_read(values, count) if column is None else column)
    return np.concatenate(columns, axis=1)


def _read(texts: Sequence[str], count: int) -> np.ndarray:
    """The numbers (R, `count`) of `texts` (R, each of `count` numbers between letters, commas and
    whitespace), read in one go."""
    return np.array(" ".join(texts).translate(_LETTERS_TO_SPACES).split(), dtype=float).reshape(len(texts), count)


def joined(drawings: Sequence[Sequence[Shape | None]]) -> list[Shape | None]:
    """The Shape of each of `drawings` made of its parts' Shapes (None if any is): their skeletons
    joined, their points one after another, the widest stroke. The points of the drawings whose
    parts have one skeleton each are put together in one go (parts of one skeleton have one number
    of points, shapes_of's)."""
    groups: dict[tuple[str, ...], list[tuple[int, list[Shape]]]] = {}  # by the parts' skeletons: the drawings
    for index, shapes in enumerate(drawings):
        present = [shape for shape in shapes if shape is not None]
        if len(present) == len(shapes):
            groups.setdefault(tuple([shape.skeleton for shape in present]), []).append((index, present))
    joined_shapes: list[Shape | None] = [None] * len(drawings)
    for skeletons, members in groups.items():
        skeleton = "|".join(skeletons)
        points = np.concatenate([_stacked([present[part].points for _, present in members]) for part in range(len(skeletons))],
                                axis=1)  # (D, N, 2)
        for (index, present), own in zip(members, points, strict=True):
            joined_shapes[index] = Shape(skeleton, own, max([shape.stroke for shape in present], default=0.0))
    return joined_shapes


def _inverses(points: np.ndarray) -> np.ndarray:
    """The pseudo-inverses (M, 3, N) of `points` (M, N, 2) with a column of ones (by the normal
    equations: 3 unknowns): times a target's points (N, 2), the least-squares affine (3, 2)
    mapping the points onto them."""
    design = np.concatenate([points, np.ones((*points.shape[:2], 1))], axis=2)
    transposed = np.transpose(design, (0, 2, 1))
    return np.linalg.pinv(transposed @ design) @ transposed


def _scale_change(linear: np.ndarray) -> np.ndarray:
    """The largest distance from 1 of the singular values of each 2x2 of `linear` (M, 2, 2)."""
    squares = np.sum(linear ** 2, axis=(1, 2))
    determinant = linear[:, 0, 0] * linear[:, 1, 1] - linear[:, 0, 1] * linear[:, 1, 0]
    root = np.sqrt(np.maximum(squares ** 2 - 4 * determinant ** 2, 0))
    return np.maximum(np.abs(np.sqrt((squares + root) / 2) - 1), np.abs(np.sqrt(np.maximum(squares - root, 0) / 2) - 1))


def fit(inverses: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """The least-squares affines (M, 2, 3) mapping the samples whose _inverses are `inverses`
    (M, 3, F) onto `targets` (M, F, 2), rounded as written (LINEAR_DECIMALS, SHIFT_DECIMALS)."""
    transposed = inverses @ targets  # (M, 3, 2): [[a b], [c d], [e f]]
    transposed[:, :2] = np.round(transposed[:, :2], LINEAR_DECIMALS)
    transposed[:, 2] = np.round(transposed[:, 2], SHIFT_DECIMALS)
    return np.transpose(transposed, (0, 2, 1))


def _near(samples: np.ndarray, columns: np.ndarray, matrices: np.ndarray, earlier: np.ndarray, later: np.ndarray,
          strokes: np.ndarray, largest: float, tolerance: float) -> tuple[np.ndarray, np.ndarray]:
    """Of pairs of samples (`earlier` and `later` (M,) index `samples` (D, F, 2), and `columns`, the
    same as (2, F, D), within `largest` px of 0), those whose `matrices` (M, 2, 3) put every sample
    of the earlier within `tolerance` px of the later's once widened by half the wider of their
    `strokes` (D,) times the matrix's largest change of scale: their positions (P,) and changes of
    scale (P,). Measured in single precision, on COARSE samples first (a sample's distance is the
    same number there: a pair farther there than the tolerance and the slack is farther on all), in
    double precision where single precision cannot tell: the same pairs as measured in double
    precision throughout."""
    slack = _single_slack(matrices, largest)
    coarse = columns[:, ::FIT_POINTS // COARSE]
    # np.take: the pairs last in memory too (an index gives them first, and the points' rows strided)
    maybe = np.flatnonzero(_largest_single(np.take(coarse, earlier, axis=2), matrices, np.take(coarse, later, axis=2))
                           - tolerance <= slack)
    sources, targets, slack = earlier[maybe], later[maybe], slack[maybe]
    single = _largest_single(np.take(columns, sources, axis=2), matrices[maybe], np.take(columns, targets, axis=2))
    scales = _scale_change(matrices[maybe, :, :2])
    widened = scales * np.maximum(strokes[sources], strokes[targets]) / 2
    total = widened + single
    near = total <= tolerance - slack
    unsure = np.flatnonzero(np.abs(total - tolerance) <= slack)
    near[unsure] = widened[unsure] + _largest(samples[sources[unsure]], matrices[maybe[unsure]],
                                              samples[targets[unsure]]) <= tolerance
    return maybe[near], scales[near]


def _single_slack(matrices: np.ndarray, largest: float) -> np.ndarray:
    """How far (M,) px fit's largest distance in single precision may be from the one in double
    precision (_largest_single, _largest), for `matrices` (M, 2, 3) and single precision points
    within `largest` px of 0: each of the eight roundings of a x + c y + e - t along an axis (a, c,
    e to single, two products, two sums, the difference) is within 2^-24 of |a||x| + |c||y| + |e| +
    |t|, and the distance's own (the two squares, their sum, its square root: _largest_single)
    within 2.5 * 2^-24 of the two axes' sum: the distance within 10.5 * 2^-24 of that sum, 2^-19
    over three times it. (The pairs found are those of double precision whatever the slack's last
    bits: only a bound is needed.)"""
    magnitudes = np.abs(matrices)  # summed by columns (a reduction along 4 numbers costs as much as 4 sums)
    linear = magnitudes[:, 0, 0] + magnitudes[:, 0, 1] + magnitudes[:, 1, 0] + magnitudes[:, 1, 1]
    return 2.0 ** -19 * (linear * largest + magnitudes[:, 0, 2] + magnitudes[:, 1, 2] + 2 * largest + 1)


class _Stacks(NamedTuple):
    """The points of D shapes stacked by point count N (_stacks): `points` by N, (K, N, 2) px of the
    K shapes of N points; `counts` (D,), each shape's N, and `rows` (D,), its row in that stack;
    `strokes` (D,) px, each shape's widest stroke."""

    points: dict[int, np.ndarray]
    counts: np.ndarray
    rows: np.ndarray
    strokes: np.ndarray


def _stacks(group: Sequence[Shape]) -> _Stacks:
    """The points of `group` stacked by point count: each shape's array copied once, the pairs' points
    then gathered from them (_pair_points)."""
    counts = np.array([len(shape.points) for shape in group], dtype=int)
    rows = np.empty(len(group), dtype=int)
    points = {}
    for count in np.unique(counts).tolist():
        members = np.flatnonzero(counts == count)
        rows[members] = np.arange(len(members))
        points[count] = _stacked([group[index].points for index in members.tolist()])
    return _Stacks(points, counts, rows, np.array([shape.stroke for shape in group]))


def _pair_points(stacks: _Stacks, sources: np.ndarray, targets: np.ndarray
                 ) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The pairs of the shapes of `stacks` (indices `sources`, `targets` (M,), of one point count each:
    one skeleton) grouped by point count N, at most PAIR_POINTS points at a time: the pairs'
    positions (M,) in `sources`, the sources' points and the targets' (M, N, 2)."""
    counts = stacks.counts[targets]
    for count in np.unique(counts).tolist():
        chosen = np.flatnonzero(counts == count)
        step = max(1, PAIR_POINTS // count)
        for start in range(0, len(chosen), step):
            rows = chosen[start:start + step]
            yield rows, stacks.points[count][stacks.rows[sources[rows]]], stacks.points[count][stacks.rows[targets[rows]]]


def _stacked(points: Sequence[np.ndarray]) -> np.ndarray:
    """`points`, arrays of one shape (N, 2), as one (M, N, 2): np.stack's, made at a fraction of its
    cost per array."""
    return np.concatenate(points).reshape(len(points), *points[0].shape)


def _errors(stacks: _Stacks, sources: np.ndarray, matrices: np.ndarray, targets: np.ndarray,
            scales: np.ndarray) -> np.ndarray:
    """For pairs of the shapes of `stacks` (indices `sources`, `targets` (M,), of one point count each:
    one skeleton), the largest distance (px) of the source's points mapped by `matrices` (M, 2, 3)
    from the target's, plus half the wider stroke times `scales` (M,), the matrix's largest change
    of scale: within it, every edge of the transformed drawing lies near the target's. (M,) px;
    the pairs computed together (_pair_points)."""
    largest = np.empty(len(sources))
    for rows, source_points, target_points in _pair_points(stacks, sources, targets):
        largest[rows] = _largest(source_points, matrices[rows], target_points)
    strokes = stacks.strokes
    return largest + scales * np.maximum(strokes[sources], strokes[targets]) / 2


def _offsets(sources: np.ndarray, matrices: np.ndarray, targets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The offsets along x and along y of points `sources` mapped by `matrices` from `targets` (x and
    y first: (2, ...) each), the matrices' numbers (2, 3, ...) broadcast against them: a x + c y + e - t,
    summed in that order in the arguments' precision (in place: two arrays made, not eight)."""
    product = np.empty(np.broadcast_shapes(sources.shape[1:], matrices.shape[2:]), dtype=np.result_type(sources, matrices))
    offsets = []
    for row in (0, 1):
        offset = sources[0] * matrices[row, 0]
        offset += np.multiply(sources[1], matrices[row, 1], out=product)
        offset += matrices[row, 2]
        offset -= targets[row]
        offsets.append(offset)
    return offsets[0], offsets[1]


def _row_maxima(values: np.ndarray) -> np.ndarray:
    """The largest (M,) of each row of `values` (M, N): by columns when the rows are short (a
    reduction along a row of a few dozen costs as much as copying it)."""
    return values.max(axis=1) if values.shape[1] > 64 else np.ascontiguousarray(values.T).max(axis=0)


def _largest(sources: np.ndarray, matrices: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """The largest distance (M,) px of `sources` (M, N, 2) mapped by `matrices` (M, 2, 3) from
    `targets` (M, N, 2), the hypotenuse of the _offsets: np.max(np.hypot(x, y), axis=1) to the bit,
    with np.hypot computed only where the squared distance is within 2^-40 of its largest. A point
    whose hypotenuse is the largest is one of them: np.hypot is within an ulp (2^-52) of the
    distance r, the square sum x^2 + y^2 within 2^-52 of r^2 (plus 3 * 2^-1075 when a square is
    subnormal, nothing to a largest of 2^-900 or more: below, every point is taken), so a hypotenuse
    at least the largest square sum's point's has a square sum within 2^-47 of the largest."""
    x, y = _offsets(np.moveaxis(sources, 2, 0), np.moveaxis(matrices, 0, 2)[..., None], np.moveaxis(targets, 2, 0))
    squares = x * x
    squares += y * y
    top = _row_maxima(squares)
    pairs, points = np.nonzero(squares >= np.where(top >= 2.0 ** -900, top * (1 - 2.0 ** -40), -1.0)[:, None])
    largest = np.full(len(top), -np.inf)
    np.maximum.at(largest, pairs, np.hypot(x[pairs, points], y[pairs, points]))
    return largest


def _largest_single(sources: np.ndarray, matrices: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """_largest's distances (M,) in single precision, for `sources` and `targets` (2, N, M) (x and y,
    point by point: a reduction over the points is then one pass of elementwise maxima) and
    `matrices` (M, 2, 3) made single: the square root of the largest square sum (within
    _single_slack of _largest's in double precision)."""
    x, y = _offsets(sources, np.moveaxis(matrices.astype(np.float32), 0, 2), targets)
    x *= x
    y *= y
    x += y
    return np.sqrt(x.max(axis=0))


def _matrix_texts(matrices: np.ndarray) -> list[str]:
    """`matrices` (P, 2, 3), rounded as fit rounds them, as the numbers of SVG's matrix(a b c d e f),
    short: "1 .0012 -.0012 1 .3 -1.2". Written once per distinct matrix (most are one of a few shifts)."""
    # the numbers in units of their last decimal: np.rint rounds halves to even, as round() does
    units = np.rint(matrices * [10.0 ** LINEAR_DECIMALS, 10.0 ** LINEAR_DECIMALS, 10.0 ** SHIFT_DECIMALS]).astype(np.int64)
    texts: dict[tuple[int, ...], str] = {}
    return [texts.get(key) or texts.setdefault(key, " ".join([*(_fixed(number, LINEAR_DECIMALS) for number in key[:4]),
                                                             *(_fixed(number, SHIFT_DECIMALS) for number in key[4:])]))
            for key in map(tuple, np.transpose(units, (0, 2, 1)).reshape(len(units), 6).tolist())]


@functools.lru_cache(maxsize=4096)
def _fixed(units: int, decimals: int) -> str:
    """`units` / 10 ** `decimals` written short: no trailing zeros, no leading zero, no "-0"
    (12500, 4 -> "1.25"; -12, 4 -> "-.0012"; 0 -> "0"). The matrices' numbers repeat (near 1 and 0)."""
    whole, fraction = divmod(abs(units), 10 ** decimals)
    sign = "-" if units < 0 else ""
    if not fraction:
        return f"{sign}{whole}" if whole else "0"
    return f"{sign}{whole or ''}.{fraction:0{decimals}d}".rstrip("0")


def _shortened(stacks: _Stacks, targets: np.ndarray, sources: np.ndarray, matrices: np.ndarray, errors: np.ndarray,
               tolerance: float) -> tuple[list[str], np.ndarray]:
    """The matrix texts and errors (P,) px, as _errors', of pairs of the shapes of `stacks` (`targets`,
    `sources` (P,), their fitted `matrices` (P, 2, 3) and its `errors` (P,)) in the first of FORMS within
    `tolerance`: a..d the fitted ones rounded to its decimals, e and f the middle of the spread of
    the target's points less the source's transformed, rounded to its decimals; the fitted matrix
    where none is (its e and f were fitted on the mean, not the middle). The pairs are checked
    together (_pair_points)."""
    matrices, errors = matrices.copy(), errors.copy()  # replaced by the forms that fit
    halves = np.maximum(stacks.strokes[targets], stacks.strokes[sources]) / 2
    for rows, source_points, target_points in _pair_points(stacks, sources, targets):
        # x and y apart, point by point (N, M): reduced along the points, contiguous
        (source_x, source_y), (target_x, target_y) = (np.ascontiguousarray(np.transpose(points, (2, 1, 0)))
                                                      for points in (source_points, target_points))
        left = np.arange(len(rows))  # the chunk's pairs no form fits yet
        for form, (linear_decimals, shift_decimals) in enumerate(FORMS):  # each on the pairs no earlier form fits
            if not len(left):
                break
            if not form or linear_decimals != FORMS[form - 1][0]:  # the points moved once per a..d
                linear = np.round(matrices[rows[left], :, :2], linear_decimals)  # (M, 2, 2)
                a, c, b, d = (linear[:, i, j] for i in (0, 1) for j in (0, 1))
                x, y, to_x, to_y = (values if len(left) == len(rows) else values[:, left]  # all at first: not copied
                                    for values in (source_x, source_y, target_x, target_y))
                residual = (to_x - (a * x + c * y), to_y - (b * x + d * y))  # (N, M) each
                middle = np.column_stack([(values.max(axis=0) + values.min(axis=0)) / 2 for values in residual])
                scale = _scale_change(linear) * halves[rows[left]]
            shift = np.round(middle, shift_decimals)
            off_x, off_y = (values - shift[:, axis] for axis, values in enumerate(residual))
            within = np.sqrt(np.max(off_x ** 2 + off_y ** 2, axis=0)) + scale
            fits = within <= tolerance
            matrices[rows[left[fits]]] = np.concatenate([linear[fits], shift[fits, :, None]], axis=2)
            errors[rows[left[fits]]] = within[fits]
            left, linear, middle, scale = (values[~fits] for values in (left, linear, middle, scale))
            residual = (residual[0][:, ~fits], residual[1][:, ~fits])
    return _matrix_texts(matrices), errors


def _pairs(skeletons: Sequence[str], candidates: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every pair of a drawing and one of the last `candidates` drawings of its skeleton before it
    (`skeletons` in order): the later's and the earlier's index, and how many drawings of the
    skeleton lie back from one to the other (1: the one just before). By lag, all skeletons at once
    (the order of the pairs is _choose's to make)."""
    groups: dict[str, list[int]] = {}
    for index, skeleton in enumerate(skeletons):
        groups.setdefault(skeleton, []).append(index)
    ordered = np.array([index for members in groups.values() for index in members], dtype=int)  # by skeleton
    sizes = np.array([len(members) for members in groups.values()], dtype=int)
    places = np.arange(len(ordered)) - np.repeat(np.cumsum(sizes) - sizes, sizes)  # in its skeleton's drawings
    later, earlier, lags = [], [], []
    for lag in range(1, candidates + 1):
        positions = np.flatnonzero(places >= lag)
        if not len(positions):
            break
        later.append(ordered[positions])
        earlier.append(ordered[positions - lag])
        lags.append(np.full(len(positions), lag))
    if not later:
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int), np.zeros(0, dtype=int)
    return np.concatenate(later), np.concatenate(earlier), np.concatenate(lags)


def _samples(stacks: _Stacks) -> np.ndarray:
    """FIT_POINTS points (F, 2) of each of the shapes of `stacks`, spread over its points: (D, F, 2),
    single precision (1e-4 px)."""
    samples = np.empty((len(stacks.counts), FIT_POINTS, 2), dtype=np.float32)
    for count, points in stacks.points.items():
        spread = np.linspace(0, count - 1, FIT_POINTS).round().astype(int)  # FIT_POINTS of the N points
        samples[stacks.counts == count] = points[:, spread]
    return samples


def _choose(shapes: Sequence[Shape | None],
            pairs: Callable[[Sequence[Shape], np.ndarray, np.ndarray], tuple[np.ndarray, ...]],
            tolerance: float) -> dict[int, Reuse]:
    """The drawings of `shapes` (in order) shown as a transform of an earlier written one: `pairs`
    (of the shapes with 3 points or more, their _samples and the samples' _inverses) gives the candidate pairs, the later's
    and the earlier's index and a rank (lower: tried first). The pairs are fitted together on the
    samples and those near on them found (_near); for each drawing the first candidate by rank that
    is written (not itself reused) and within `tolerance` px on all its points is taken."""
    numbers = [number for number, shape in enumerate(shapes) if shape is not None and len(shape.points) >= 3]
    group = [shape for shape in (shapes[number] for number in numbers) if shape is not None]
    if len(group) < 2:
        return {}
    stacks = _stacks(group)
    samples = _samples(stacks)
    inverses = _inverses(samples)
    later, earlier, ranks = pairs(group, samples, inverses)
    if not len(later):
        return {}
    columns, largest = np.ascontiguousarray(samples.transpose(2, 1, 0)), float(np.max(np.abs(samples)))
    # fitted FIT_PAIRS pairs at a time: all at once, a 30-minute recording's temporaries took ~1 GB
    found = []  # (the near pairs' positions, their matrices and changes of scale) of each batch
    for start in range(0, len(later), FIT_PAIRS):
        sources, targets = earlier[start:start + FIT_PAIRS], later[start:start + FIT_PAIRS]
        matrices = fit(inverses[sources], samples[targets])
        near, scales = _near(samples, columns, matrices, sources, targets, stacks.strokes, largest, tolerance)
        found.append((start + near, matrices[near], scales))
    near, matrices, scales = (np.concatenate(parts) for parts in zip(*found, strict=True))
    order = np.lexsort((ranks[near], later[near]))  # by drawing, the first candidate first
    near, matrices, scales = near[order], matrices[order], scales[order]
    errors = _errors(stacks, earlier[near], matrices, later[near], scales)
    within = np.flatnonzero(errors <= tolerance)
    written = [True] * len(group)
    chosen = []  # positions in near
    for position, target, source in zip(within.tolist(), later[near[within]].tolist(), earlier[near[within]].tolist(),
                                        strict=True):
        if written[target] and written[source]:
            chosen.append(position)
            written[target] = False
    targets, sources = later[near[chosen]], earlier[near[chosen]]
    texts, errors = _shortened(stacks, targets, sources, matrices[chosen], errors[chosen], tolerance)
    return {numbers[target]: Reuse(numbers[source], text, error)
            for target, source, text, error in zip(targets.tolist(), sources.tolist(), texts, errors.tolist(), strict=True)}


def find(shapes: Sequence[Shape | None], tolerance: float = TOLERANCE,
         candidates: int = CANDIDATES) -> dict[int, Reuse]:
    """For the drawings of one track (`shapes`, in order of first use), the ones that can be shown
    as a transform of an earlier written drawing: drawing number -> Reuse. Each drawing is fitted
    (the pairs together in batches, _choose, on FIT_POINTS points of each) to the last `candidates` drawings of its
    skeleton before it; the nearest in time that is written (not itself reused) and within
    `tolerance` px on all its points is taken."""
    return _choose(shapes, lambda group, samples, inverses: _pairs([shape.skeleton for shape in group], candidates), tolerance)


def _normalised(samples: np.ndarray, inverses: np.ndarray, references: np.ndarray) -> np.ndarray:
    """`samples` (M, F, 2; `inverses` their _inverses) each moved by the least-squares affine onto
    its reference (M, F, 2): (M, 2F). Shapes one affine apart become equal (the fit of T(X) onto R
    is the fit of X composed with T's inverse), so near ones here are near an affine of each other."""
    design = np.concatenate([samples, np.ones((*samples.shape[:2], 1), dtype=samples.dtype)], axis=2)
    return (design @ (inverses @ references)).reshape(len(samples), -1).astype(np.float32)


def _alike(group: Sequence[Shape], samples: np.ndarray, inverses: np.ndarray, candidates: int) -> tuple[np.ndarray, ...]:
    """Every pair of a shape of `group` (`samples` and `inverses` as _choose's) and one of the
    `candidates` earlier shapes of its skeleton nearest to it once both are _normalised (at any
    distance back in time): the later's and the earlier's index, and the rank of the earlier by
    that nearness (0: the nearest)."""
    groups: dict[str, list[int]] = {}
    for index, shape in enumerate(group):
        groups.setdefault(shape.skeleton, []).append(index)
    kept = [np.array(members) for members in groups.values() if len(members) >= 2]
    if not kept:
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int), np.zeros(0, dtype=int)
    # all skeletons normalised at once, each shape onto the first of its skeleton (a few calls, not a few per skeleton)
    sizes = [len(indices) for indices in kept]
    everyone = np.concatenate(kept)
    flats = _normalised(samples[everyone], inverses[everyone], samples[np.repeat([indices[0] for indices in kept], sizes)])
    squares = np.sum(flats ** 2, axis=1)
    later, earlier, ranks = [], [], []
    for indices, end in zip(kept, np.cumsum(sizes).tolist(), strict=True):
        flat, norms = flats[end - len(indices):end], squares[end - len(indices):end]
        for start in range(1, len(indices), ROWS):
            rows = np.arange(start, min(start + ROWS, len(indices)))
            distances = norms[rows, None] + norms[None, :rows[-1]] - 2 * flat[rows] @ flat[:rows[-1]].T  # (R, J)
            inside = distances[:, start:]  # the block's own columns: only the earlier ones count
            inside[np.arange(start, rows[-1])[None, :] >= rows[:, None]] = np.inf
            take = min(candidates, rows[-1])
            nearest = np.argpartition(distances, take - 1, axis=1)[:, :take]  # the nearest, unordered
            nearest = np.take_along_axis(nearest, np.argsort(np.take_along_axis(distances, nearest, axis=1), axis=1), axis=1)
            valid = nearest < rows[:, None]
            later.append(indices[np.broadcast_to(rows[:, None], nearest.shape)[valid]])
            earlier.append(indices[nearest[valid]])
            ranks.append(np.broadcast_to(np.arange(take), nearest.shape)[valid])
    return np.concatenate(later), np.concatenate(earlier), np.concatenate(ranks)


def find_alike(shapes: Sequence[Shape | None], tolerance: float = TOLERANCE,
               candidates: int = ALIKE) -> dict[int, Reuse]:
    """For parts (`shapes`, in order of first use: the mouths, eyes and face outlines of written drawings), the ones
    that can be shown as a transform of an earlier written part: number -> Reuse. Candidates are
    the `candidates` earlier parts of the same skeleton that are nearest once each is moved by a
    least-squares affine onto the first (_alike: an index over all earlier parts, not only recent
    ones); the nearest written one within `tolerance` px on all points is taken."""
    return _choose(shapes, lambda group, samples, inverses: _alike(group, samples, inverses, candidates), tolerance)
