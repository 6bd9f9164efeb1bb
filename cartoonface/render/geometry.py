"""Curves of the cartoon face: Bezier arcs, corner cutting, and each part's SVG path data.

Thesis 002, Alg. 2.2 draws the face with `arc(P1..Pn)`, "a curve composed by the
points P1..Pn" (its Fig. 2.8 is missing from the text), as cubic Bezier curves for the
contours and as corner-cutting subdivision curves for the eyebrows and the hair.

How `arc(P1..Pn)` becomes cubic Bezier control points (our choice, Fig. 2.8 being lost):
the curve passes through every point; piece i runs from P_i to P_i+1 with control points
P_i + T_i/3 and P_i+1 - T_i+1/3 (a cubic Hermite spline). The tangent at an inner point is
the Catmull-Rom tangent T_i = (P_i+1 - P_i-1)/2. At an end of the arc the tangent is the
"natural" one, T_1 = (3 (P_2 - P_1) - T_2)/2, which makes the curvature vanish there, unless a
neighbour point beyond the end is given (see `contour`).

How the arcs of a closed contour join: Alg. 2.2 lists each contour as several arcs that
share their end points. Where the thesis's figure shows a soft outline (the face: forehead,
cheeks, jaw) the joins are smooth: each shared point gets the Catmull-Rom tangent from its
neighbours on both arcs. Where a real corner is drawn (eye corners, mouth corners, the
Cupid's bow at 8.1, the tips of the eyebrows) the arcs keep their own natural end tangents
and meet at an angle.

Corner cutting (Chaikin): every edge (P, Q) of the polygon is replaced by the two points
3/4 P + 1/4 Q and 1/4 P + 3/4 Q; an open arc keeps its two end points so that the two arcs
of an eyebrow meet at pointed tips. Every new point is a convex combination of old ones, so
the curve stays inside the control polygon's convex hull.

All of this is linear in the points. `face_shapes` therefore compiles, once per face layout,
the maps from the posed points to every control point of every part, and a format
template; drawing a state is then matrix products, a rounding to 0.1 px (what a screen
shows), a table look-up of the number strings and one string format. The hair's map is a
sparse banded (8 H, H) matrix (each corner-cut point mixes at most three neighbouring hair
points), so memory and time grow linearly with the hair point count H; the other parts'
map is a small dense matrix over the named points only.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from cartoonface.face.lift import FRONT_NAMES, LIFTED_NAMES
from cartoonface.render.numbers import distinct_rows, fill, rounded_tenths, template_frame, tenths_texts

# Eyebrows and hair: rounds of corner cutting. Three rounds turn each polygon edge into
# eight short pieces, which read as a smooth outline at the sizes a face is drawn.
CHAIKIN_ROUNDS = 3

class Posed(Protocol):
    """What `face_shapes` reads from a `cartoonface.face.pose.PosedFace` (`nose_side` an int) and
    `all_face_shapes` from a `PosedFaces` (each array with a leading axis of S faces, `nose_side`
    (S,)); read-only."""

    @property
    def xy(self) -> np.ndarray: ...
    @property
    def hair(self) -> np.ndarray: ...
    @property
    def front(self) -> np.ndarray: ...
    @property
    def nose_side(self) -> int | np.ndarray: ...


def arc(points: np.ndarray, before: np.ndarray | None = None, after: np.ndarray | None = None) -> np.ndarray:
    """Cubic Bezier pieces of the curve through `points`.

    Takes `points` (n, D), n >= 2 (D = 2 for image points; any D works, the map is linear),
    and optionally the neighbour `before` the first point and `after` the last (D,) that
    set the end tangents (smooth joins in a contour); without them the ends are natural.
    Returns (n-1, 3, D): for piece i the first control point, the second control point
    and the end point (the start of piece i is points[i], or the end of piece i-1).
    """
    pts = np.asarray(points, dtype=float)
    n = len(pts)
    if n < 2:
        raise ValueError("arc needs at least two points")
    tangents = np.empty_like(pts)
    tangents[1:-1] = (pts[2:] - pts[:-2]) / 2
    if before is not None:
        tangents[0] = (pts[1] - np.asarray(before, dtype=float)) / 2
    if after is not None:
        tangents[-1] = (np.asarray(after, dtype=float) - pts[-2]) / 2
    if n == 2 and before is None and after is None:
        tangents[:] = pts[1] - pts[0]
    else:
        if before is None:
            tangents[0] = (3 * (pts[1] - pts[0]) - tangents[1]) / 2
        if after is None:
            tangents[-1] = (3 * (pts[-1] - pts[-2]) - tangents[-2]) / 2
    pieces = np.empty((n - 1, 3, pts.shape[1]))
    pieces[:, 0] = pts[:-1] + tangents[:-1] / 3
    pieces[:, 1] = pts[1:] - tangents[1:] / 3
    pieces[:, 2] = pts[1:]
    return pieces


def contour(arcs: list[np.ndarray], smooth: bool) -> np.ndarray:
    """Bezier pieces of a closed contour made of arcs that share their end points.

    Takes `arcs`, a list of (n_i, D) arrays where each arc ends where the next one starts
    (and the last ends where the first starts), and `smooth`: True joins them with
    Catmull-Rom tangents across the shared points, False leaves corners there.
    Returns (sum(n_i - 1), 3, D) Bezier pieces starting at arcs[0][0].
    """
    count = len(arcs)
    pieces = []
    for i, points in enumerate(arcs):
        before = arcs[i - 1][-2] if smooth else None
        after = arcs[(i + 1) % count][1] if smooth else None
        pieces.append(arc(points, before, after))
    return np.concatenate(pieces)


def chaikin(points: np.ndarray, rounds: int = CHAIKIN_ROUNDS, closed: bool = False) -> np.ndarray:
    """Corner-cutting subdivision of a polygon.

    Takes `points` (n, D) and the number of `rounds`; an open polygon keeps its first and
    last points, a `closed` one wraps around. Returns the refined polygon: (2n, D) per round
    for both kinds (open: the two end points plus two cuts on each of the n-1 edges).
    """
    pts = np.asarray(points, dtype=float)
    for _ in range(rounds):
        nxt = np.roll(pts, -1, axis=0) if closed else pts[1:]
        cur = pts if closed else pts[:-1]
        cuts = np.empty((2 * len(cur), pts.shape[1]))
        cuts[0::2] = 0.75 * cur + 0.25 * nxt
        cuts[1::2] = 0.25 * cur + 0.75 * nxt
        pts = cuts if closed else np.concatenate([pts[:1], cuts, pts[-1:]])
    return pts


# The parts, thesis 002 Alg. 2.2 steps 2-13 (with Alg. 2.3 step 8 for the nose), by the
# point names of cartoonface.face.lift.LIFTED_NAMES. Left and right follow the thesis's
# wording ("the left eye" is drawn from 3.12, 3.2, 3.8, 3.4), which is the image left. Each
# entry: part name, kind, arcs. The ears (steps 4-5) are the open arc(10.8, 10.2, A) in the
# thesis, which turns sharply at 10.2 (A lies just below it) and reads as a pointed elf ear.
# We draw each ear as a smooth closed loop 10.8, E', 10.2, A, where E' (see DERIVED) lies
# below 10.2 by 0.6 of the ear's attachment A -> 10.8: the outer rim runs parallel to the
# face, the top is round, and the loop closes from A to 10.8 behind the face.
# Kinds: "smooth"/"corner" closed Bezier contours, "open" separate Bezier arcs (one sub-path
# each), "cut" a closed shape of open corner-cut arcs (eyebrows).
FRONT_CROWN = tuple(name for name in FRONT_NAMES if name.startswith("crown"))
FRONT_HAIRLINE = tuple(name for name in FRONT_NAMES if name.startswith("hairline"))
FACE_CONTOUR = (("11.2", "11.2a", "11.1", "11.3a", "11.3"), ("11.3", "10.9", "2.13"),
         ("2.13", "2.1", "2.14"), ("2.14", "10.10", "11.2"))        # step 3
_NOSE_TAIL = (("9.14", "9.2", "9.4"), ("9.13", "9.1", "9.5"), ("D", "9.15", "E"))  # step 6
PARTS: tuple[tuple[str, str, tuple[tuple[str, ...], ...]], ...] = (
    ("face", "smooth", FACE_CONTOUR),
    # the hair's front layer (face/lift.py): the crown, down to the right temple, the
    # hairline over the forehead, up from the left temple; corners at the temples
    ("fringe", "corner", (FRONT_CROWN, (FRONT_CROWN[-1], "11.3"), ("11.3", *FRONT_HAIRLINE, "11.2"),
                          ("11.2", FRONT_CROWN[0]))),
    ("ear_l", "smooth", (("10.8", "ear_l", "10.2", "A"), ("A", "10.8"))),  # step 4, closed
    ("ear_r", "smooth", (("10.7", "ear_r", "10.1", "B"), ("B", "10.7"))),  # step 5
    ("nose", "open", (("9.6", "C", "9.14"), *_NOSE_TAIL)),               # step 6
    ("brow_l", "cut", (("4.6", "4.4a", "4.4", "4.2"), ("4.2", "G", "F", "4.6"))),  # step 7
    ("brow_r", "cut", (("4.5", "4.3a", "4.3", "4.1"), ("4.1", "H", "I", "4.5"))),  # step 8
    ("eye_l", "corner", (("3.12", "3.2", "3.8"), ("3.8", "3.4", "3.12"))),         # step 9
    ("eye_r", "corner", (("3.7", "3.1", "3.11"), ("3.11", "3.3", "3.7"))),         # step 10
    ("lid_l", "open", (("3.12", "3.2", "3.8"),)),    # upper lid line, drawn bolder
    ("lid_r", "open", (("3.7", "3.1", "3.11"),)),
)  # the mouth (step 13): render/mouth.py
# Points made for the drawing as linear combinations of named points: (coefficient, name).
DERIVED: dict[str, tuple[tuple[float, str], ...]] = {
    "ear_l": ((1.0, "10.2"), (0.6, "10.8"), (-0.6, "A")),
    "ear_r": ((1.0, "10.1"), (0.6, "10.7"), (-0.6, "B")),
}
# Thesis 002, Alg. 2.3 step 8: when the head turns the other way (beta > 0) the nose
# bridge is drawn on the visible side, arc(9.7, C, 9.13) instead of arc(9.6, C, 9.14).
_NOSE_OTHER_SIDE = ("nose", "open", (("9.7", "C", "9.13"), *_NOSE_TAIL))
# Which PosedFace.nose_side value selects that variant (pose.py: +1 for turn > 0).
NOSE_SIDE_OTHER = 1


@dataclass(frozen=True)
class _Plan:
    """A compiled drawing: `hair` (8 H, H) sparse maps the H hair points to the hair's
    coordinates, written first; `matrix` (K, N) maps the N posed points (xy) to the K
    coordinates of the other parts, written next; `names` lists the parts in that order, and
    `frames` (numbers.template_frame) and `slots` give each its path data's template and the
    range [start, end) of the (8 H + K) * 2 numbers it takes."""

    hair: RowMix
    matrix: np.ndarray
    names: tuple[str, ...]
    frames: tuple[tuple[str, ...], ...]
    slots: tuple[tuple[int, int], ...]


def _move(rows: list[np.ndarray], start: np.ndarray, pieces: np.ndarray) -> str:
    """Append the start point and Bezier pieces to `rows`; return "M..C.." template text."""
    rows.append(start)
    rows.extend(pieces.reshape(-1, pieces.shape[-1]))
    return "M%s %s" + "C%s %s %s %s %s %s" * len(pieces)


def _polygon(rows: list[np.ndarray], points: np.ndarray) -> str:
    """Append polygon vertices to `rows`; return closed "M..L..Z" template text."""
    rows.extend(points)
    return "M%s %s" + "L%s %s" * (len(points) - 1) + "Z"


def hypots(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """math.hypot of each pair of `x`, `y` (arrays of one shape, pixels; that shape): as the
    drawing of one state at a time computed them (np.hypot may differ in the last bit)."""
    return np.array(list(map(math.hypot, x.ravel().tolist(), y.ravel().tolist())), dtype=float).reshape(np.shape(x))


def inside(point: np.ndarray, polygon: np.ndarray) -> bool:
    """Whether `point` (2,) lies inside `polygon` ((n, 2), in order), by the even-odd rule."""
    x, y = point
    result = False
    for (x1, y1), (x2, y2) in zip(polygon, np.roll(polygon, -1, axis=0)):
        if (y1 > y) != (y2 > y) and x < x1 + (y - y1) * (x2 - x1) / (y2 - y1):
            result = not result
    return result


@dataclass(frozen=True)
class RowMix:
    """A sparse (R, C) matrix stored by rows (numpy only: scipy.sparse costs ~0.1 s of every
    start-up): row r holds `weights[r, k]` at column `columns[r, k]`, both (R, K), in column
    order, rows with fewer than K terms padded with weight 0 at column 0."""

    columns: np.ndarray
    weights: np.ndarray
    shape: tuple[int, int]

    def __matmul__(self, x: np.ndarray) -> np.ndarray:
        """The product with `x` (C, M): (R, M), each row's terms added in column order."""
        out = self.weights[:, :1] * x[self.columns[:, 0]]
        for k in range(1, self.columns.shape[1]):
            out += self.weights[:, k:k + 1] * x[self.columns[:, k]]
        return out


def chaikin_closed_operator(count: int, rounds: int = CHAIKIN_ROUNDS) -> RowMix:
    """The sparse matrix of `chaikin(points, rounds, closed=True)` for `count` points.

    Returns a (2**rounds * count, count) RowMix M with M @ points equal to the corner
    cut polygon: every row holds at most three non-zeros (neighbouring points; two after one
    round), so its size is linear in `count`. The weights are the same dyadic fractions
    `chaikin` uses, multiplied and added exactly.
    """
    rows, columns = np.arange(count), np.arange(count)
    weights: np.ndarray = np.ones(count)
    size = count
    for _ in range(rounds):
        # new row 2i = 3/4 row i + 1/4 row i+1, new row 2i+1 = 1/4 row i + 3/4 row i+1 (cyclic):
        # each term of row r goes to new rows 2r, 2r+1 and (as row i+1 of i = r-1) 2r-2, 2r-1
        targets = np.concatenate([2 * rows, 2 * rows + 1, 2 * rows - 2, 2 * rows - 1]) % (2 * size)
        shares = np.concatenate([0.75 * weights, 0.25 * weights, 0.25 * weights, 0.75 * weights])
        keys, where = np.unique(targets * count + np.tile(columns, 4), return_inverse=True)
        weights = np.bincount(where, shares)
        rows, columns, size = keys // count, keys % count, 2 * size
    starts = np.searchsorted(rows, np.arange(size))
    place = np.arange(len(rows)) - starts[rows]  # each term's place in its row
    width = int(place.max()) + 1
    table_columns, table_weights = np.zeros((size, width), dtype=np.intp), np.zeros((size, width))
    table_columns[rows, place], table_weights[rows, place] = columns, weights
    return RowMix(table_columns, table_weights, (size, count))


@functools.lru_cache(maxsize=32)
def _plan(names: tuple[str, ...], hair_count: int, nose_side: int) -> _Plan:
    """Compile the linear maps and template for points named `names` plus `hair_count` hair
    points, with the nose drawn for `nose_side`."""
    basis = np.eye(len(names))
    rows_of = {name: basis[i] for i, name in enumerate(names)}
    for name, terms in DERIVED.items():
        rows_of[name] = sum(coefficient * rows_of[point] for coefficient, point in terms)
    rows: list[np.ndarray] = []
    hair = chaikin_closed_operator(hair_count)
    texts = ["M%s %s" + "L%s %s" * (hair.shape[0] - 1) + "Z"]
    part_names = ["hair"]
    parts = [_NOSE_OTHER_SIDE if p[0] == "nose" and nose_side == NOSE_SIDE_OTHER else p for p in PARTS]
    for name, kind, arc_names in parts:
        arcs = [np.array([rows_of[n] for n in arc_]) for arc_ in arc_names]
        if kind in ("smooth", "corner"):
            texts.append(_move(rows, arcs[0][0], contour(arcs, kind == "smooth")) + "Z")
        elif kind == "open":
            texts.append("".join(_move(rows, a[0], arc(a)) for a in arcs))
        else:  # "cut": open corner-cut arcs joined end to end into one closed outline
            outline = np.concatenate([chaikin(a)[:-1] for a in arcs])
            texts.append(_polygon(rows, outline))
        part_names.append(name)
    ends = np.cumsum([text.count("%s") for text in texts]).tolist()
    return _Plan(hair, np.array(rows), tuple(part_names), tuple(template_frame(text) for text in texts),
                 tuple(zip([0, *ends[:-1]], ends, strict=True)))


def face_shapes(posed: Posed) -> dict[str, str]:
    """SVG path data of every drawn part of a posed face (thesis 002, Alg. 2.2 steps 2-13).

    Takes a `cartoonface.face.pose.PosedFace` (`xy` (N, 2) image pixels in LIFTED_NAMES
    order with the outline points on their silhouettes, `hair` (H, 2), `front` (F, 2) in
    FRONT_NAMES order, `nose_side`). Returns {part: path d} for "hair" (the back layer),
    "face", "fringe" (the hair's front layer), "ear_l", "ear_r", "nose", "brow_l", "brow_r", "eye_l", "eye_r", "lid_l",
    "lid_r" (the mouth: render/mouth.py); coordinates in pixels rounded to 0.1.
    """
    return all_face_shapes(_Stacked(posed))[0]


class _Stacked:
    """One posed face as a stack of one (what all_face_shapes reads)."""

    def __init__(self, posed: Posed) -> None:
        self.xy = np.asarray(posed.xy, dtype=float)[None]
        self.hair = np.asarray(posed.hair, dtype=float).reshape(1, -1, 2)
        self.front = np.asarray(posed.front, dtype=float)[None]
        self.nose_side = np.array([int(posed.nose_side)])


def all_face_shapes(posed: Posed) -> list[dict[str, str]]:
    """face_shapes of S posed faces at once (a `cartoonface.face.pose.PosedFaces`: `xy` (S, N, 2),
    `hair` (S, H, 2), `front` (S, F, 2), `nose_side` (S,)): all_face_shape_columns' path data of
    each face, by part."""
    columns = all_face_shape_columns(posed)
    return [{name: texts[which[index]] for name, (texts, _, which) in columns.items()} for index in range(len(posed.xy))]


def all_face_shape_columns(posed: Posed) -> dict[str, tuple[list[str], list[np.ndarray], list[int]]]:
    """The path data of S posed faces (as all_face_shapes reads them) by part, in face_shapes'
    order: the part's distinct path data, their numbers in whole tenths of a pixel as written
    ((k,) integers each, numbers.rounded_tenths': render/pathdata.py's Tenths) and, per face, the
    number of its own among them. The maps are applied to all faces by stacked products (each
    slice the product of one face, so the same numbers), the hair's to each distinct hair outline
    once (a pose shown with many mouths has one). A part whose numbers, in tenths, are those of another face of the stack
    (the hair, the ears, the nose under one pose with another mouth) is written once (_written)."""
    count = len(posed.xy)
    hair = np.asarray(posed.hair, dtype=float)
    names = LIFTED_NAMES + FRONT_NAMES
    plans = {side: _plan(names, hair.shape[1], side) for side in {int(side) for side in np.atleast_1d(posed.nose_side)}}
    plan = next(iter(plans.values()))
    outlines, outline_of = distinct_rows(hair.reshape(count, -1))
    outlines = outlines.reshape(len(outlines), -1, 2)
    # the sparse map on the U distinct hair outlines side by side: (8 H, H) @ (H, 2 U); each
    # column alone, so the same numbers as for one face
    wide = plan.hair @ outlines.transpose(1, 0, 2).reshape(hair.shape[1], -1)
    written = plan.hair.shape[0]
    paths, rows, numbers = _written(plan.frames[0], rounded_tenths(wide.reshape(written, len(outlines), 2)
                                                                   .transpose(1, 0, 2)).reshape(len(outlines), -1))
    shapes = {"hair": (paths, rows, [numbers[outline] for outline in outline_of])}
    coordinates = np.empty((count, len(plan.matrix), 2))
    # each axis of each face's points as a column (S, 2, N, 1): matrix-vector products, as
    # face_shapes made them one face at a time (4x faster than one product with (N, 2))
    columns = np.ascontiguousarray(np.concatenate([posed.xy, posed.front], axis=1).transpose(0, 2, 1))[..., None]
    sides = np.asarray(posed.nose_side).reshape(-1)
    for side, side_plan in plans.items():
        chosen = np.flatnonzero(sides == side)
        coordinates[chosen] = (side_plan.matrix @ columns[chosen])[..., 0].transpose(0, 2, 1)
    tenths = rounded_tenths(coordinates).reshape(count, -1)
    shapes.update((name, ([], [], [0] * count)) for name in plan.names[1:])
    for side, side_plan in plans.items():
        chosen = np.flatnonzero(sides == side)
        for name, frame, (start, end) in zip(side_plan.names[1:], side_plan.frames[1:], side_plan.slots[1:],
                                             strict=True):
            texts, distinct, numbers = _written(frame, tenths[chosen, start - 2 * written:end - 2 * written])
            paths, rows, which = shapes[name]
            if len(plans) == 1:
                shapes[name] = texts, distinct, numbers
                continue
            for index, number in zip(chosen.tolist(), numbers, strict=True):
                which[index] = len(paths) + number  # after the other nose side's
            paths += texts
            rows += distinct
    return shapes


def _written(frame: tuple[str, ...], tenths: np.ndarray) -> tuple[list[str], list[np.ndarray], list[int]]:
    """The path data of the `frame` (numbers.template_frame) of each row of `tenths` (n, k: the
    numbers in whole tenths of a pixel), written once per distinct row: those texts, in the order
    first seen, their rows ((k,) each) and each row's number among them (n)."""
    distinct, numbers = distinct_rows(tenths)
    texts, width = tenths_texts(distinct), tenths.shape[1]
    return ([fill(frame, texts[row * width:(row + 1) * width]).replace(" -", "-") for row in range(len(distinct))],
            list(distinct), numbers)
