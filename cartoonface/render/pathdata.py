"""Compact SVG path data for the animation: whole pixels, relative commands, simplified polylines.

render/geometry.py writes each part as absolute commands in tenths of a pixel. An
animation repeats a part in thousands of frames, so `compacted` rewrites them:

- every coordinate is rounded to a whole pixel of the face canvas (the canvas is
  drawn at about its own size, so this is what a screen shows);
- commands become relative (`m l c s q z`), a repeated command letter is left out
  and a comma is written only where the next number has no minus sign; a cubic
  whose first control point mirrors the previous one (geometry's smooth joins)
  is written as `s` without it;
- runs of straight segments (the corner-cut hair and eyebrows, Chaikin with eight
  points per edge) keep only the points that the Douglas-Peucker rule needs to stay
  within TOLERANCE of the full polyline. The points are chosen once per outline on
  its first drawing and the same ones are kept in every pose, so an outline does not
  shimmer as vertices come and go between frames.

All paths with one command skeleton (the same commands, different numbers) are done
together with numpy. Paths with other commands (H, V, S, T, A, relative ones) are
left as they are.

"On its first drawing" is the first path data of the skeleton in sorted order, so paths
compacted in two processes (render/animation.py's drawing processes, `compacted`) are put
together (`merged`, and `compacted` going on from a `done`) by comparing those firsts: where
one side's first comes later, its paths of that skeleton are compacted again with the other's.
The result is the one a single call over all the paths gives, for path data that writes out
every command, as the drawing does (a skeleton mixing such path data with path data that repeats
a command implicitly is left as it is by one call, but each side may hold only the first kind).
"""

from __future__ import annotations

import functools
import re
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from cartoonface.render.numbers import TENTHS

TOLERANCE = 0.5  # pixels: a dropped point lies closer than this to the simplified line
MIRROR = 2  # pixels: a first control point this close to the mirrored one is left out (`s`)
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
_ARITY = {"M": 2, "L": 2, "C": 6, "Q": 4, "Z": 0}
_LETTERS = "".join(chr(c) for c in range(65, 91)) + "".join(chr(c) for c in range(97, 123))
# what _groups deletes to leave the letters, as bytes: bytes.translate deletes at twice the
# speed of str.translate (UTF-8 writes no other character with these bytes)
_NOT_LETTERS = b"0123456789.,+- \t\n\r"
_LETTERS_TO_SPACES = {ord(c): " " for c in _LETTERS + ","}
_SEPARATOR = "|"  # between the paths _plain_numbers reads together


@dataclass(frozen=True)
class _Plan:
    """How to write every path of one skeleton from its (n, 2P) absolute rounded coordinates.

    `columns` (K,): the coordinate columns written; `references` (K,): the column each is
    relative to (-1: none); `prefixes` (K,) object: command letters written before each
    number; `after_letter` (K,): the number follows a letter (no separator); `tail`: letters
    after the last number."""

    columns: np.ndarray
    references: np.ndarray
    prefixes: np.ndarray
    after_letter: np.ndarray
    tail: str


def _commands(skeleton: str, count: int) -> list[tuple[str, int]] | None:
    """The skeleton, either the command letters alone ('MCCZ', each command written out) or
    'M# #C# # ...' with '#' for numbers, as (letter, arity) commands, one per repetition; `count`
    numbers in all. None for anything but absolute M/L/C/Q/Z or when the numbers do not fit."""
    if "#" not in skeleton:
        commands = [(letter, _ARITY.get(letter, -1)) for letter in skeleton]
        if any(arity < 0 for _, arity in commands) or sum(a for _, a in commands) != count:
            return None
        return commands if commands and commands[0][0] == "M" else None
    commands = []
    for letter, marks in re.findall(r"([A-Za-z])([^A-Za-z]*)", skeleton):
        count = marks.count("#")
        arity = _ARITY.get(letter)
        if arity is None or (arity == 0 and count) or (arity and (count == 0 or count % arity)):
            return None
        if arity == 0:
            commands.append((letter, 0))
            continue
        for repeat in range(count // arity):
            commands.append(("L" if letter == "M" and repeat else letter, arity))
    if not commands or commands[0][0] != "M":
        return None
    return commands


def simplify(points: np.ndarray) -> np.ndarray:
    """Douglas-Peucker on a polyline `points` (n, 2): a bool mask (n,) of the points to keep
    (the ends always) so that no dropped point is farther than TOLERANCE from the kept
    segment that replaces it."""
    keep = np.zeros(len(points), dtype=bool)
    keep[[0, -1]] = True
    stack = [(0, len(points) - 1)]
    while stack:
        first, last = stack.pop()
        if last - first < 2:
            continue
        chord = points[last] - points[first]
        offsets = points[first + 1 : last] - points[first]
        # Distance to the segment (not the infinite line), so a point past either end counts in full.
        share = np.clip(offsets @ chord / max(float(chord @ chord), 1e-12), 0.0, 1.0)
        gaps = offsets - share[:, None] * chord
        distance = np.hypot(gaps[:, 0], gaps[:, 1])
        worst = int(np.argmax(distance))
        if distance[worst] > TOLERANCE:
            keep[first + 1 + worst] = True
            stack += [(first, first + 1 + worst), (first + 1 + worst, last)]
    return keep


def _smooth(commands: list[tuple[str, int]], spans: list[list[int]], kept: list[bool],
            rounded: np.ndarray) -> np.ndarray:
    """(n, len(commands)) bool: which cubics of each path in `rounded` (n, 2P) may be written
    as `s` (first control point left out, taken as the mirror of the previous one's second):
    those following a kept cubic whose first control point is within MIRROR px of that mirror.
    Geometry's Catmull-Rom joins are smooth by construction (the rounding of three points
    moves the mirror by up to 2 px), its corners are not; a control point moved by 2 px moves
    the curve by less than 0.9 px."""
    xy = rounded.reshape(len(rounded), -1, 2)
    smooth = np.zeros((len(rounded), len(commands)), dtype=bool)
    previous = None
    for index, ((letter, _), span, keep) in enumerate(zip(commands, spans, kept, strict=True)):
        if not keep:
            continue
        if letter == "C" and previous is not None:
            _, second, end = spans[previous]
            mirror = 2 * xy[:, end] - xy[:, second]
            smooth[:, index] = np.all(np.abs(xy[:, span[0]] - mirror) <= MIRROR, axis=1)
        previous = index if letter == "C" else None
    return smooth


def _kept(commands: list[tuple[str, int]], spans: list[list[int]], first: np.ndarray) -> list[bool]:
    """Which commands stay: every one but the linetos that Douglas-Peucker drops on `first`
    (2P,), the rounded coordinates of one path of the skeleton."""
    points = first.reshape(-1, 2).astype(float)
    kept = [True] * len(commands)
    index = 0
    while index < len(commands):  # runs of linetos after some start point
        if commands[index][0] != "L" or index == 0:
            index += 1
            continue
        end = index
        while end < len(commands) and commands[end][0] == "L":
            end += 1
        start_point = spans[index - 1][-1] if spans[index - 1] else None
        if start_point is not None and end - index >= 2:
            rows = [start_point] + [spans[k][0] for k in range(index, end)]
            mask = simplify(points[rows])
            for k, keep in zip(range(index, end), mask[1:].tolist(), strict=True):
                kept[k] = keep
        index = end
    return kept


def _spans(commands: list[tuple[str, int]]) -> list[list[int]]:
    """The point indices each command writes (its control points, then its end point)."""
    spans, point = [], 0
    for _, arity in commands:
        spans.append(list(range(point, point + arity // 2)))
        point += arity // 2
    return spans


def _plan(commands: list[tuple[str, int]], spans: list[list[int]], kept: list[bool],
          smooth: tuple[bool, ...]) -> _Plan:
    """The writing plan of `commands` keeping the `kept` ones, cubics marked `smooth` as `s`."""
    columns, references, prefixes, after = [], [], [], []
    current, subpath, previous, pending = -1, -1, "", ""
    for (letter, _), span, keep, mirrored in zip(commands, spans, kept, smooth, strict=True):
        if not keep:
            continue
        if letter == "Z":
            pending += "z"
            current, previous = subpath, "z"
            continue
        lower = "s" if mirrored else letter.lower()
        span = span[1:] if mirrored else span
        if lower != previous or lower == "m":
            pending += lower
        for position, point_index in enumerate(span):
            for axis in (0, 1):
                columns.append(2 * point_index + axis)
                references.append(2 * current + axis if current >= 0 else -1)
                prefixes.append(pending if position == 0 and axis == 0 else "")
                after.append(bool(pending) if position == 0 and axis == 0 else False)
                pending = "" if position == 0 and axis == 0 else pending
        current = span[-1]
        if letter == "M":
            subpath = current
        previous = lower
    prefix_array = np.empty(len(prefixes), dtype=object)
    prefix_array[:] = prefixes
    return _Plan(np.array(columns, dtype=np.intp), np.array(references, dtype=np.intp), prefix_array,
                 np.array(after, dtype=bool), pending)


@functools.lru_cache(maxsize=8)
def _texts(limit: int) -> np.ndarray:
    """Number texts for -limit..limit (index value + limit): plain ('5', '-5'), then (index
    value + 3 limit + 1) with a separating comma where one is needed (',5', '-5')."""
    values = range(-limit, limit + 1)
    return np.array([str(v) for v in values] + [str(v) if v < 0 else f",{v}" for v in values], dtype=object)


@functools.lru_cache(maxsize=64)
def _lettered_texts(letters: str, limit: int) -> np.ndarray:
    """The plain number texts of _texts(limit) after command `letters` ('c5', 'c-5'): (2 limit + 1,)."""
    return letters + _texts(limit)[:2 * limit + 1]


def _write(plan: _Plan, rounded: np.ndarray) -> list[str]:
    """Path texts of the rows of `rounded` (n, 2P) integer absolute coordinates."""
    values = rounded[:, plan.columns]
    bases = np.where(plan.references >= 0, rounded[:, np.maximum(plan.references, 0)], 0)
    relative = values - bases
    limit = 1 << max(int(np.abs(relative).max(initial=0)).bit_length(), 10)
    # one look-up in the plain texts then the comma ones; the numbers after letters (few) looked up
    # again in the texts after those letters (made once: no string added per number)
    numbers = _texts(limit)[relative + limit + np.where(plan.after_letter, 0, 2 * limit + 1)]
    lettered = np.flatnonzero(plan.prefixes != "")
    for letters, columns in _by_letters(plan.prefixes[lettered].tolist(), lettered.tolist()).items():
        numbers[:, columns] = _lettered_texts(letters, limit)[relative[:, columns] + limit]
    return ["".join(row) + plan.tail for row in numbers.tolist()]


def _by_letters(letters: list[str], columns: list[int]) -> dict[str, list[int]]:
    """The `columns` by the `letters` before their numbers."""
    grouped: dict[str, list[int]] = {}
    for prefix, column in zip(letters, columns, strict=True):
        grouped.setdefault(prefix, []).append(column)
    return grouped


def _plain_numbers(paths: list[str], tenths: Tenths | None = None) -> np.ndarray | None:
    """The numbers of `paths` (path data of plain numbers: letters, commas, spaces and signs
    between them) as an (n, k) float array, k each; None when they hold different counts or a
    text that is no number. Those `tenths` (Tenths) has are taken from it (taken_or_read), the
    others read by _read_numbers (a few cut chin shadows among thousands written from tenths)."""
    return taken_or_read(paths, tenths or {}, _read_numbers)


def taken_or_read(paths: Sequence[str], tenths: Tenths, read: Callable[[list[str]], np.ndarray | None]
                  ) -> np.ndarray | None:
    """The numbers (n, k) of the path data `paths`: those `tenths` has taken from it, not read
    (tenths / 10 is the value strtod reads of the tenths' text, both the double nearest the
    decimal, but for the sign of a zero, which no one here sees), the others read by `read` ((m, k)
    of m path data, or None); None when `read` gives None or the paths hold different counts."""
    known = list(map(tenths.get, paths))
    unknown = [index for index, row in enumerate(known) if row is None]
    read_rows = read([paths[index] for index in unknown]) if unknown else None
    rows = [row for row in known if row is not None]
    counts = set(map(len, rows)) | ({read_rows.shape[1]} if read_rows is not None else set())
    if unknown and read_rows is None or len(counts) != 1:
        return None
    numbers = np.empty((len(paths), counts.pop()))
    if rows:  # all of them (most groups): no index
        numbers[[index for index, row in enumerate(known) if row is not None] if unknown else slice(None)] = (
            np.concatenate(rows).reshape(len(rows), -1) / TENTHS)
    if read_rows is not None:
        numbers[unknown] = read_rows
    return numbers


def _read_numbers(paths: list[str]) -> np.ndarray | None:
    """The numbers of `paths` (as _plain_numbers') read by one np.fromstring (C's strtod: the
    values float() gives), "nan" between the paths: (n, k); None when they hold different counts
    or a text that is no number."""
    text = _SEPARATOR.join(paths).translate(_LETTERS_TO_SPACES).replace("-", " -").replace(_SEPARATOR, " nan ")
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)  # numpy's word for text it cannot read
        try:
            flat = np.fromstring(text, dtype=float, sep=" ")
        except DeprecationWarning:
            return None
    ends = np.flatnonzero(np.isnan(flat))
    counts = np.diff(np.concatenate(([-1], ends, [len(flat)]))) - 1
    if np.any(counts != counts[0]):
        return None
    return flat[~np.isnan(flat)].reshape(len(paths), int(counts[0]))


# Path data written from whole tenths of a pixel (render/geometry.py), by their text: those numbers
# in the order written ((k,) integers: numbers.rounded_tenths'), as render/numbers.py's tenths_texts wrote them.
Tenths = Mapping[str, np.ndarray]
Extent = tuple[float, float, float, float]  # x0, y0, x1, y1: a box of path data's points


@dataclass(frozen=True)
class Compacted:
    """Path data compacted: `compact` maps each path data string to its compact form (see the
    module docstring); `extents` gives each compact path data written (a path left as it is has
    none) the box (x0, y0, x1, y1) of every point and control point it writes, read off the rounded
    numbers (render/compact.py's merge_alike would otherwise parse the text); `firsts`: the first (in
    sorted order) path data of each skeleton with linetos, whose points Douglas-Peucker keeps in
    all of them (_kept), and `members` all the path data of each such skeleton compacted with it
    (sorted; what `merged` compacts again where another first comes earlier), `rows` their numbers
    rounded to whole pixels ((n, 2P) integers, int16 where they fit, a row per member: `merged`
    compacts them again without reading their text), `kept` the commands Douglas-Peucker keeps of
    them (_kept of the first's row: `merged` compares the two sides' instead of simplifying again).
    Paths compacted in two processes are put together by `merged`."""

    compact: dict[str, str]
    extents: dict[str, Extent]
    firsts: dict[str, str]
    members: dict[str, list[str]]
    rows: dict[str, np.ndarray] = field(default_factory=dict, compare=False)  # members' (equal members: equal rows)
    kept: dict[str, list[bool]] = field(default_factory=dict, compare=False)


def compacted(paths: Iterable[str], done: Compacted | None = None,
              tenths: Tenths | None = None) -> Compacted:
    """The Compacted of `paths`, going on from `done` (a Compacted of other paths,
    or of some of these and others): its compact forms are taken where its first path data of a
    skeleton is the first of these paths too (so its points are the ones kept), the others are
    compacted here. `tenths` (Tenths): the numbers of some of `paths` as they were written, not
    read again (the same compact forms)."""
    known = Compacted(dict(done.compact), dict(done.extents), {}, {}) if done else Compacted({}, {}, {}, {})
    distinct = set(paths)
    new = _groups(d for d in distinct if d not in known.compact)
    firsts = done.firsts if done else {}
    # skeletons whose first path data is not among these, or comes after a new one: done again
    stale = {skeleton for skeleton, first in firsts.items()
             if first not in distinct or skeleton in new and min(new[skeleton]) < first}
    every = _groups(distinct) if stale else {}
    for skeleton, first in firsts.items():
        if skeleton not in stale and done:
            known.firsts[skeleton] = first
            known.members[skeleton], known.rows[skeleton] = done.members[skeleton], done.rows[skeleton]
            known.kept[skeleton] = done.kept[skeleton]
        elif skeleton in every:
            _compact_group(skeleton, every[skeleton], known, tenths)
    for skeleton, members in new.items():
        if skeleton not in stale:  # compacted with the first, whose points are kept
            before = (known.members[skeleton], known.rows[skeleton]) if skeleton in known.members else None
            _compact_group(skeleton, [firsts[skeleton], *members] if skeleton in firsts else members, known, tenths)
            if before:
                _join(skeleton, before, known)
    return known


def merged(first: Compacted, second: Compacted) -> Compacted:
    """The Compacted of the paths of `first` and `second` together, as compacted of all of them
    gives it: where a skeleton's first path data differs, the paths of the side whose first comes
    later are compacted again with the other's (its points kept)."""
    done = Compacted({**first.compact, **second.compact}, {**first.extents, **second.extents},
                     {**first.firsts, **second.firsts}, {**first.members, **second.members}, {**first.rows, **second.rows},
                     {**first.kept, **second.kept})
    for skeleton, one in first.firsts.items():
        other = second.firsts.get(skeleton)
        if other is None:
            continue
        if one != other:  # the later side's members compacted again from their rows, after the earlier first's
            earlier, later = (first, second) if one < other else (second, first)
            done.firsts[skeleton], done.kept[skeleton] = earlier.firsts[skeleton], earlier.kept[skeleton]
            if earlier.kept[skeleton] != later.kept[skeleton]:  # else the later side's forms stand
                rows = np.concatenate((earlier.rows[skeleton][:1], later.rows[skeleton])).astype(np.int64)
                _compact_group(skeleton, [earlier.firsts[skeleton], *later.members[skeleton]], done, rounded=rows,
                               kept=earlier.kept[skeleton])
        done.members[skeleton], done.rows[skeleton] = first.members[skeleton], first.rows[skeleton]
        _join(skeleton, (second.members[skeleton], second.rows[skeleton]), done)
    return done


def changed_forms(own: Compacted, done: Compacted) -> set[str]:
    """The compact forms of `own` that `done` (`merged` of it and others) writes otherwise: those
    of the members of a skeleton whose first path data another side has earlier (`merged`
    compacts them again; no other path data changes)."""
    return {form for skeleton, first in own.firsts.items() if done.firsts.get(skeleton) != first
            for d in own.members[skeleton] if done.compact[d] != (form := own.compact[d])}


def _join(skeleton: str, other: tuple[list[str], np.ndarray], done: Compacted) -> None:
    """Add the members `other` (sorted path data and their rows, Compacted's) of `skeleton` to
    those of `done` (kept sorted, each once)."""
    both = [*done.members[skeleton], *other[0]]
    where = dict(zip(both, range(len(both))))  # each member's row (equal members: equal rows)
    members = sorted(where)
    done.members[skeleton] = members
    done.rows[skeleton] = np.concatenate((done.rows[skeleton], other[1]))[[where[d] for d in members]]


def _groups(paths: Iterable[str]) -> dict[str, list[str]]:
    """The distinct `paths` by skeleton: the command letters when every number is plain (no
    exponent), else the text with "#" for each number."""
    groups: dict[str, list[str]] = {}
    for d in paths:
        letters = d.encode().translate(None, _NOT_LETTERS).decode()
        groups.setdefault(letters if "e" not in letters and "E" not in letters else _NUMBER.sub("#", d), []).append(d)
    return groups


def _compact_group(skeleton: str, members: list[str], done: Compacted,
                   tenths: Tenths | None = None, rounded: np.ndarray | None = None, kept: list[bool] | None = None) -> None:
    """Compact the distinct path data `members` of one `skeleton` into `done` (a skeleton with
    linetos: sorted in place, the first one's points kept in all); `tenths` (Tenths) has the numbers of some of them;
    `rounded`, when given, all their numbers rounded to whole pixels, a row per member in their
    (sorted) order: they are not read; `kept`, when given, _kept of the first's (Compacted.kept)."""
    if rounded is None:
        if "L" in skeleton:  # the first's points are kept in all (_kept); else no member's order counts
            members.sort()
        if "#" in skeleton:
            texts = [_NUMBER.findall(d) for d in members]
            numbers = np.array(texts, dtype=float) if len({len(row) for row in texts}) == 1 else None
        else:
            numbers = _plain_numbers(members, tenths)
        commands = _commands(skeleton, numbers.shape[1]) if numbers is not None else None
        if commands is None or numbers is None:
            done.compact.update((d, d) for d in members)
            return
        rounded = np.rint(numbers).astype(np.int64)
    else:
        commands = _commands(skeleton, rounded.shape[1])
        assert commands is not None, skeleton  # rows are kept of compacted members only
    if "L" in skeleton:
        done.firsts[skeleton] = members[0]
        done.members[skeleton] = members
        # kept in as few bits as they fit in (16 on a canvas): a quarter of the bytes a drawing process sends
        bound = np.abs(rounded).max(initial=0)
        done.rows[skeleton] = rounded.astype(np.int16 if bound < 1 << 15 else np.int32 if bound < 1 << 31 else np.int64)
    spans = _spans(commands)
    kept = _kept(commands, spans, rounded[0]) if kept is None else kept
    if "L" in skeleton:
        done.kept[skeleton] = kept
    smooth = _smooth(commands, spans, kept, rounded)
    for pattern, rows in _alike_rows(smooth):
        plan = _plan(commands, spans, kept, pattern)
        written = _write(plan, rounded[rows])
        done.compact.update(zip([members[i] for i in rows], written, strict=True))
        done.extents.update(zip(written, _extents(plan, rounded[rows]), strict=True))


def _alike_rows(marks: np.ndarray) -> list[tuple[tuple[bool, ...], np.ndarray]]:
    """The distinct rows of the bool array `marks` (n, k) and where each occurs: (row, indices).
    Rows packed into bytes and sorted as one 1-D array (np.unique with axis=0 is 10x slower)."""
    packed = np.ascontiguousarray(np.packbits(marks, axis=1)).reshape(len(marks), -1)
    keys = packed.view(f"V{max(packed.shape[1], 1)}").ravel() if packed.shape[1] else np.zeros(len(marks), "V1")
    _, first, which = np.unique(keys, return_index=True, return_inverse=True)
    return [(tuple(marks[row].tolist()), np.flatnonzero(which.reshape(-1) == number))
            for number, row in enumerate(first.tolist())]


def _extents(plan: _Plan, rounded: np.ndarray) -> list[Extent]:
    """The box of the points `plan` writes of each row of `rounded` (n, 2P) absolute coordinates."""
    xs, ys = (rounded[:, plan.columns[plan.columns % 2 == axis]] for axis in (0, 1))
    boxes = np.column_stack([xs.min(axis=1), ys.min(axis=1), xs.max(axis=1), ys.max(axis=1)]).astype(float)
    return list(map(tuple, boxes.tolist()))
