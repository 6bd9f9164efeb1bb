"""The SVG compactor of render/animation.py: many drawings of one face written small.

`Writer` takes every state's drawing (the texts of its parts, render/svg.py's face_parts),
keeps each distinct part once, and tidies it: path data in whole pixels as relative
commands (render/pathdata.py), groups that only pass on style dissolved into their
children, positions rounded, every other presentation attribute moved to a CSS class
(the most used classes named by one letter), a path with its clip path's outline drawn
as a `<use>` of it, per-state definitions (clip paths) renamed by content with short
base-36 ids. `share` then puts a part shown in several drawings once into `<defs>` and
shows it with `<use>` (a part of one element with no `<g>` around it), and `merge_alike` writes
consecutive paths of one opaque style lying apart (the brows) as one path: fewer elements for the
browser to build (docs/BENCHMARKS.md, "Fewer elements").

Speed (docs/BENCHMARKS.md, "Speed of the SVG stage"): the parts come as text, and tidying a
part depends only on its skeleton, the text with its path data (numbered by their compact
forms, so alike ones stay alike), positions and sizes taken out; so one part of each skeleton is
tidied as lxml elements and the others' values are filled into its text. The style classes
are renamed and the clip paths several drawings hold alike taken out on those texts, and the
distinct tidy drawings stay texts (one per top-level element, as lxml writes it in the document):
`share` and `merge_alike` work on those texts and render/animation.py writes the tracks around them
as text, spliced into the document's bytes, so the drawings are never parsed nor serialized again
("The SVG stage's tail as text"). The drawing processes (render/animation.py)
each number their own distinct parts, compact their path data and make their skeletons
(`drawn_parts`: a part handed on with its Form and slots, render/svg.py's, has its path data,
skeleton and values from them, not cut out of its text: `form_of` finds once where a drawing
function writes its slots; docs/BENCHMARKS.md, "vals"); the parent collects the drawings by those numbers (`Writer.collected`: its own
half's, with their templates and tidy texts, `Writer.prepare`, while the helper's half comes),
puts the path data together (render/pathdata.py's merged) and goes on from there, making again
only the skeletons whose path data the other process's first path data changed ("Finishing in
parallel", "The SVG stage's middle", "The SVG stage's middle, halved").
"""

from __future__ import annotations

import functools
import html
import itertools
import operator
import re
from bisect import bisect_right
from collections import Counter
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, replace
from itertools import accumulate, chain, compress, groupby
from typing import NamedTuple

from lxml import etree

from cartoonface.render.elements import SVG, Part, element, markup, parse_elements
from cartoonface.render.pathdata import Compacted, Extent, Tenths, changed_forms, compacted

# Elements that only define something referenced by id: a part's own ones (per state, from
# face_parts) go with the part, renamed so each distinct part drawing has its own.
DEFINITIONS = tuple(f"{{{SVG}}}{tag}" for tag in ("clipPath", "linearGradient", "radialGradient", "mask",
                                                  "pattern", "filter", "marker", "symbol"))
# Attributes that place an element (rounded to whole pixels, kept on it). Every other
# attribute but KEPT ones and references to per-state definitions is style: a CSS class.
POSITIONS = frozenset(("cx", "cy", "x", "y", "x1", "y1", "x2", "y2"))
KEPT = frozenset(("d", "r", "rx", "ry", "width", "height", "points", "clip-path", "mask", "transform", "href",
                  "offset", "id"))
# KEPT sizes (not rounded) that change from state to state (a mouth's gloss and tongue, the cheeks'
# blush): taken out of a part's skeleton as written, as positions are, so that parts differing only
# in them are tidied by one template (a fifth as many: docs/BENCHMARKS.md, "The SVG stage's middle, halved").
SIZES = frozenset(("r", "rx", "ry", "width", "height"))
# Properties a <g> passes on to its children by inheritance (SVG 1.1, property index): a group
# with no other attribute can be dissolved into its children. Not opacity, which applies to
# the group as a whole.
# Shapes a clip-path can move onto from a `<g>` around it alone (_dissolve); not a `<use>`,
# whose x and y would move the clip.
SHAPES = frozenset(f"{{{SVG}}}{tag}" for tag in ("path", "circle", "ellipse", "rect", "line", "polyline", "polygon"))
INHERITED = frozenset(("fill", "fill-opacity", "fill-rule", "stroke", "stroke-width", "stroke-linecap",
                       "stroke-linejoin", "stroke-opacity", "stroke-miterlimit", "stroke-dasharray",
                       "stroke-dashoffset", "color"))
_REFERENCE = re.compile(r"url\(#([^)]+)\)")
_ID = re.compile(r' id="[^"]*"')  # an id attribute in serialized SVG (_content)
_TAG = re.compile(r"<[^\s/>]+")  # an element's start tag up to its name
_OWN_ID = re.compile(r'<[^>]*? id="([^"]*)"')  # the id in an element's start tag
# Path data read by _extent: a command letter and its numbers.
_COMMAND = re.compile(r"([MmLlHhVvCcSsQqTtZz])([^A-Za-z]*)")
_UNREAD = re.compile(r"[^MmLlHhVvCcSsQqTtZzEe\d\s,.+-]")  # arcs, anything else _extent does not read
_PATH_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
_ARITY = {"m": 2, "l": 2, "h": 1, "v": 1, "c": 6, "s": 4, "q": 4, "t": 2, "z": 0}
# merge_alike joins paths whose extents (with their control points) lie at least this many pixels
# apart beyond half their stroke width: antialiasing reaches 1 px.
MERGE_GAP = 1.0
_START = re.compile(r"^[Mm][^A-Za-z]*")  # path data's first move (_kind)
_FIRST_MOVE = re.compile(r"m\s*([-+.\d]+)[\s,]*([-+]?[.\d]+)[\s,]*")  # a relative first move's point (_absolute_start)
_MOVE = re.compile(rb' d="[Mm][^A-Za-z"]*')  # path data's first move in a definition's text (_hoist)
_PATH_DATA = re.compile(r' d="([^"]*)"')
# An element's text read without parsing it (the tidy drawings, as lxml wrote them: attribute values
# in double quotes, ">" in them escaped): an attribute, any tag (closing "/"), the start of the first path.
_ATTRIBUTE = re.compile(r' ([^\s=]+)="([^"]*)"')
_ANY_TAG = re.compile(r'<(/?)[^>]*>')
_FIRST_PATH = re.compile(r'<path[\s/>]')
_CLASS = re.compile(r' class="([^"]*)"')  # a style class in a tidy drawing's text (Writer._short_classes)
# Writer.finish tidies one part of each skeleton (_skeleton) and fills in the others' values:
# the attributes it takes out (path data, positions and sizes), a path data's token, and the
# placeholder positions and sizes (SENTINEL + j: whole numbers that rounding keeps, found again in the output).
_VALUE = re.compile(rf' (d|{"|".join(sorted(POSITIONS | SIZES))})="([^"]*)"')
_TOKEN = re.compile(r'="@(\d+)@"')
SENTINEL = 1_000_000_000  # a part has fewer than 1000 positions and sizes
# A skeleton's geometry value: a path data's token "@k@" (group 1: k) or a placeholder (group 2: SENTINEL + j).
PLACEHOLDER = rf"@(\d+)@|({str(SENTINEL)[:-3]}\d{{3}})"
_FIELD = re.compile(rf'="(?:{PLACEHOLDER})"')
# A local definition's id ("c0", "c1_") where a tidy drawing's text names it: as an id, in a
# url() reference or a <use>'s href. Writer.finish writes the drawing's own prefix in its place
# (short_id("k", its number); LOCAL while drawings are compared).
_LOCAL_ID = re.compile(r'(id="|url\(#|href="#)c(\d+)')
LOCAL = "c"
SEPARATOR = "\x00"  # between the elements of a run in a template's piece: never in XML text
# Writer.finish tells its progress every this many parts (~0.1 ms each: a report every ~0.1 s).
PROGRESS_PARTS = 1024


@dataclass(frozen=True)
class _Template:
    """A skeleton's tidy drawing as format strings (Writer._template): `form` the whole, `pieces`
    the same cut into its top-level definitions (True) and runs of other elements (False, SEPARATOR
    between them)."""

    form: str
    pieces: tuple[tuple[str, bool], ...]


class RawPart(NamedTuple):
    """A part as face_parts drew it (text: a drawing of every state would not fit in
    memory as lxml trees), with the per-state definitions it references and the `label`
    the Writer's `label_of` gave it. (A named tuple: made 2.5 times as fast as a frozen
    dataclass, for ten thousand parts.)"""

    label: str
    element: str
    definitions: tuple[str, ...]


@dataclass(frozen=True)
class Drawn:
    """The distinct parts one drawing process drew, made ready for Writer.collected by that process
    (drawn_parts): `parts`, distinct, each as (name, text, clips) (elements.Part's fields: plain
    tuples unpickle six times as fast); `done`, all their path data compacted (for a Drawn to be
    sent, done.compact only of the parts holding a member of done.members: see drawn_parts); per
    part its skeleton and values (_skeleton's with done.compact) as `forms` (the number of its
    skeleton in `skeletons`, a few hundred for ten thousand parts, and the values); `holds`: the
    parts holding a first path data of done.firsts (part number -> those path data), which
    Writer.finish checks are collected."""

    parts: list[tuple[str, str, tuple[str, ...]]]
    skeletons: list[str]
    forms: list[tuple[int, list[str]]]
    done: Compacted
    holds: dict[int, tuple[str, ...]]


class Form(NamedTuple):
    """How the parts one drawing function writes from its slots (the texts it fills in: path data,
    numbers) split into a skeleton and values (_skeleton's), known once for all of them (form_of):
    `skeleton` the skeleton of every such part whose path data compact to distinct forms and whose
    sizes are plain numbers; `paths` the slots holding path data, in the order the text first holds
    them; `fields`, per position or size placeholder in order, the slot filling it and whether it is
    a position (rounded to whole pixels), or -1 and the value itself (the same in every part)."""

    skeleton: str
    paths: tuple[int, ...]
    fields: tuple[tuple[int, str, bool], ...]


# A part's Form and its slots' texts, in the order the drawing function takes them.
Formed = tuple[Form, tuple[str, ...]]
# form_of's slot k as the drawing function is given it: a whole number no drawing writes, so it
# passes for a number (rounding keeps it) and, as path data, is compacted to itself.
MARK = 2 * SENTINEL


def form_of(draw: Callable[[list[str]], Part], slots: int) -> Form:
    """The Form of the parts `draw` writes from `slots` texts (its slot k fills path data, or a
    position or a size, wherever the text holds it), found by drawing one with marks (MARK + k)
    for slots. ValueError when a slot fills something else (an attribute a skeleton keeps)."""
    marks = [str(MARK + slot) for slot in range(slots)]
    part = draw(marks)
    where = {mark: slot for slot, mark in enumerate(marks)}
    try:  # the marks as their own compact forms
        skeleton, values = _skeleton((part.text, *part.clips), dict(zip(marks, marks)))
    except KeyError as error:
        raise ValueError(f"path data of {part.name} not from a slot: {error}") from None
    if any(mark in skeleton for mark in marks):
        raise ValueError(f"a slot of {part.name} fills no path data, position or size: {skeleton}")
    names = _PLACED.findall(skeleton)
    paths = tuple(where[d] for d in values[:len(values) - len(names)])
    fields = tuple((where.get(value, -1), "" if value in where else value, name in POSITIONS)
                   for name, value in zip(names, values[len(paths):], strict=True))
    return Form(skeleton, paths, fields)


_PLACED = re.compile(rf' ([^\s=]+)="{str(SENTINEL)[:-3]}\d{{3}}"')  # a position's or size's placeholder


def _formed_values(form: Form, slots: Sequence[tuple[str, ...]], compact: Mapping[str, str]) -> list[list[str] | None]:
    """The values (_skeleton's) of each part the drawing function of `form` wrote from `slots` (its
    slots' texts, a tuple a part), whose skeleton is form.skeleton; None for a part whose skeleton
    it is not (two of its path data compact alike, a size is no plain number): its text is cut then.
    Slot by slot over all the parts (C loops: map, zip), not part by part."""
    columns = {slot: list(map(operator.itemgetter(slot), slots))
               for slot in {*form.paths, *(slot for slot, _, _ in form.fields if slot >= 0)}}
    paths = [list(map(compact.__getitem__, columns[slot])) for slot in form.paths]
    fields = [itertools.repeat(value) if slot < 0 else map(_whole if position else _as_written, columns[slot])
              for slot, value, position in form.fields]
    # per part: its sizes plain numbers, its path data's compact forms distinct
    checks: list[Iterable[bool]] = [map(_plain, columns[slot]) for slot, _, position in form.fields
                                    if slot >= 0 and not position]
    if len(paths) == 2:
        checks.append(map(operator.ne, *paths))
    elif len(paths) > 2:
        checks.append(len(set(row)) == len(row) for row in zip(*paths))
    rows = zip(*paths, *fields) if paths or fields else itertools.repeat(())  # a part a row
    values: list[list[str] | None] = list(map(list, itertools.islice(rows, len(slots))))
    if checks:
        for number in compress(range(len(values)), map(operator.not_, map(all, zip(*checks)))):
            values[number] = None
    return values


@functools.lru_cache(maxsize=1 << 12)
def _plain(value: str) -> bool:
    """Whether a size's text `value` is a plain number (digits, at most one "."), as _skeleton_of takes one."""
    return value.replace(".", "", 1).isdigit()


def drawn_parts(parts: list[Part], tenths: Tenths | None = None, sent: bool = False,
                formed: Mapping[Part, Formed] | None = None) -> Drawn:
    """The Drawn of the distinct `parts` (render/svg.py's face_parts' parts); `tenths`: the
    numbers of some of their path data as written (pathdata.Tenths), not read again. `sent`: the
    Drawn goes to another process, which needs the compact forms only of the parts whose forms
    another process's first path data may change (pathdata.changed_forms: those holding a member
    of a skeleton with a first; Writer.finish makes them again), so done.compact keeps only theirs
    (~a fifth of the bytes sent less; were every part's needed again, Writer.finish compacts them
    from their text). `formed`: the Form and slots of some parts (render/svg.py's all_face_parts'),
    whose path data, skeleton and values are taken from them, not cut out of their text: the parts
    of each Form together (_formed_values)."""
    fields = [(part.name, part.text, part.clips) for part in parts]
    given: list[Formed | None] = [None] * len(parts) if formed is None else list(map(formed.get, parts))
    by_form: dict[Form, tuple[list[int], list[tuple[str, ...]]]] = {}  # each Form's parts and slots (a few dozen)
    cuts: dict[int, list[str]] = {}
    for number, known in enumerate(given):
        if known is None:  # cut at its values once (_VALUE), for its path data and its skeleton; its
            # elements end in ">": a path data in two cannot match
            cuts[number] = _VALUE.split("".join((fields[number][1], *fields[number][2])))
        else:
            numbers, slots = by_form.setdefault(known[0], ([], []))
            numbers.append(number)
            slots.append(known[1])
    # the path data of the parts (and whose each is): of each Form's a column per path slot, of each other part a list
    columns = [(numbers, list(map(operator.itemgetter(slot), slots)))
               for form, (numbers, slots) in by_form.items() for slot in form.paths]
    for number, cut in cuts.items():
        paths = [_text(cut[index + 1]) for index in range(1, len(cut), 3) if cut[index] == "d"]
        columns.append(([number] * len(paths), paths))
    done = compacted(chain.from_iterable(column for _, column in columns), tenths=tenths)
    made: list[tuple[str, list[str]] | None] = [None] * len(parts)
    for form, (numbers, slots) in by_form.items():
        for number, values in zip(numbers, _formed_values(form, slots, done.compact), strict=True):
            if values is not None:
                made[number] = (form.skeleton, values)
    skeletons: dict[str, int] = {}
    forms = []
    for number, skeleton_values in enumerate(made):
        if skeleton_values is None:  # no Form, or not its skeleton: cut
            skeleton_values = (_skeleton_of(cuts.pop(number), done.compact) if number in cuts
                               else _skeleton((fields[number][1], *fields[number][2]), done.compact))
        forms.append((skeletons.setdefault(skeleton_values[0], len(skeletons)), skeleton_values[1]))
    # the parts holding a first path data (few), each's in the order of firsts
    rank = {d: place for place, d in enumerate(done.firsts.values())}
    held: dict[int, set[str]] = {}
    for numbers, column in columns:
        for number, d in compress(zip(numbers, column), map(rank.__contains__, column)):
            held.setdefault(number, set()).add(d)
    holds = {number: tuple(sorted(paths, key=rank.__getitem__)) for number, paths in held.items()}
    if sent:
        members = {d for skeleton_members in done.members.values() for d in skeleton_members}
        sending: set[int] = set()
        for numbers, column in columns:
            sending.update(compress(numbers, map(members.__contains__, column)))
        done = replace(done, compact={d: done.compact[d] for numbers, column in columns
                                      for number, d in zip(numbers, column) if number in sending})
    return Drawn(fields, list(skeletons), forms, done, holds)


class Writer:
    """Collects the drawn states, then writes the distinct part drawings compactly.
    `label_of` names the group a top-level part belongs to by the part's name (kept as RawPart.label)."""

    def __init__(self, label_of: Callable[[str], str]) -> None:
        self.label_of = label_of
        self.raw_ids: dict[tuple[str, tuple[str, ...]], int] = {}
        self.raw: list[RawPart] = []
        self.styles: dict[tuple[tuple[str, str], ...], str] = {}
        self.definitions: list[etree._Element] = []  # shared by several tidy drawings: for the document's <defs>
        self.extents: dict[str, Extent] = {}  # of the compact path data (merge_alike's)
        self._templates: dict[str, _Template] = {}  # by skeleton, and the distinct tidy drawings'
        self._ahead: dict[str, _Template] = {}  # made by prepare, for finish
        self._texts: list[str | None] = []  # prepare's tidy texts of the first raw parts (finish's)
        self._distinct: list[tuple[str, list[str]]] = []  # skeletons and values (finish's, for drawings)
        self._forms: list[tuple[str, list[str]] | None] = []  # per raw part, when a drawing process made them
        self._held: set[str] = set()  # the path data of drawn_parts' Drawn.holds the collected parts hold
        self._sources: list[tuple[Compacted, int, int]] = []  # by collected: each Drawn's path data, its raw parts

    def collect(self, parts: Sequence[Part]) -> tuple[int, ...]:
        """Take one drawing's parts (render/svg.py's face_parts); return the raw part numbers,
        in drawing order."""
        numbers = []
        for part in parts:
            key = (part.text, part.clips)
            number = self.raw_ids.get(key)
            if number is None:  # a new part: finish makes its skeleton
                number = self.raw_ids[key] = len(self.raw)
                self.raw.append(RawPart(self.label_of(part.name), part.text, part.clips))
                self._forms.append(None)
            numbers.append(number)
        return tuple(numbers)

    def collected(self, drawn: Drawn, drawings: Iterable[Sequence[int]]) -> list[tuple[int, ...]]:
        """`collect` of each of `drawings`, whose parts are given by their numbers in `drawn` (a
        drawing process's, drawn_parts), in order: the raw part numbers of each. Each part of
        `drawn` they show is a new raw part (a part that another process's drawings show too is two:
        finish gives them one tidy drawing, numbered at the first). A part keeps its skeleton and
        values from `drawn` (finish makes them again where the path data of all the processes
        compacted together write its path data otherwise)."""
        drawings = list(drawings)
        order = list(dict.fromkeys(chain.from_iterable(drawings)))  # as first shown
        raws = [-1] * len(drawn.parts)
        for raw, number in enumerate(order, len(self.raw)):
            raws[number] = raw
        self._sources.append((drawn.done, len(self.raw), len(self.raw) + len(order)))
        labels = {name: self.label_of(name) for name in {name for name, _, _ in drawn.parts}}  # a few names
        self.raw += [RawPart(labels[name], text, clips) for name, text, clips in map(drawn.parts.__getitem__, order)]
        self._forms += [(drawn.skeletons[skeleton], values) for skeleton, values in map(drawn.forms.__getitem__, order)]
        self._held.update(d for number, held in drawn.holds.items() if raws[number] >= 0 for d in held)
        return [tuple(map(raws.__getitem__, numbers)) for numbers in drawings]  # C loops

    def prepare(self) -> None:
        """Make ahead of finish (in a drawing process's idle time: while the other one's parts
        come) the templates of the skeletons of the parts `collected` since, and their tidy texts,
        which finish takes (a part whose skeleton finish makes again does not)."""
        forms = self._forms[len(self._texts):]
        for skeleton in dict.fromkeys(form[0] for form in forms if form is not None):
            if skeleton not in self._ahead:
                self._ahead[skeleton] = self._template(skeleton)
        self._texts += [None if form is None else self._ahead[form[0]].form.format(*form[1], k=LOCAL) for form in forms]

    def finish(self, progress: Callable[[float], None] | None = None,
               done: Compacted | None = None) -> list[int]:
        """Tidy every raw part; return, per raw part, the number of its distinct tidy drawing
        (`drawings()` then makes them). `progress(fraction)`, when given, is
        told the share 0..1 of the parts tidied every PROGRESS_PARTS parts. `done`: path data
        compacted already (the drawing processes', drawn_parts and pathdata.merged, whose parts
        `collected` took), which may hold more than the parts collected; a part collected keeps
        its skeleton and values unless `done` writes a compact form of them otherwise."""
        forms, self._forms = self._forms, []  # let go when finish returns
        if done is None or not self._held.issuperset(done.firsts.values()):
            # the first path data of a skeleton (whose points are kept in all) came from a drawing
            # not collected (a state whose key an earlier drawing has): compacted again, and every
            # skeleton made here
            done = compacted(part_paths((part.element, *part.definitions) for part in self.raw), done)
            forms = [None] * len(self.raw)
        for own, start, end in self._sources:  # the forms another process's first path data changed: made again
            changed = changed_forms(own, done)
            if changed:
                forms[start:end] = [form if form is None or changed.isdisjoint(form[1]) else None for form in forms[start:end]]
        self._sources = []
        made, self._texts = self._texts, []  # prepare's, of the parts whose forms stand
        made += [None] * (len(self.raw) - len(made))
        compact, self.extents = done.compact, done.extents
        self.raw_ids.clear()
        templates: dict[str, _Template] = {}
        tidy_ids: dict[str, int] = {}
        distinct: list[tuple[str, list[str]]] = []  # skeleton and values of each distinct tidy drawing
        mapping: list[int] = []
        for start in range(0, len(self.raw), PROGRESS_PARTS):
            if progress is not None:
                progress(start / len(self.raw))
            end = start + PROGRESS_PARTS
            chunk = [form or _skeleton((part.element, *part.definitions), compact)
                     for part, form in zip(self.raw[start:end], forms[start:end], strict=True)]
            for skeleton in dict.fromkeys(skeleton for skeleton, _ in chunk):  # made in the order first used
                if skeleton not in templates:
                    templates[skeleton] = self._ahead.pop(skeleton) if skeleton in self._ahead else self._template(skeleton)
            # alike drawings alike, with the local ids; numbered as they first come
            texts = [text if text is not None and form is not None else templates[skeleton].form.format(*values, k=LOCAL)
                     for text, form, (skeleton, values) in zip(made[start:end], forms[start:end], chunk, strict=True)]
            mapping += [tidy_ids.setdefault(text, len(tidy_ids)) for text in texts]
            for form, number in zip(chunk, mapping[start:], strict=True):
                if number == len(distinct):  # its first
                    distinct.append(form)
        self._templates, self._distinct, self._ahead = templates, distinct, {}
        # the style classes in the order the templates made in this order make them (a template
        # makes its new ones in the order its text holds them), those of templates made ahead
        # and not taken left out: the style sheet's order
        style = {label: key for key, label in self.styles.items()}
        self.styles = {style[label]: label
                       for label in dict.fromkeys(label for template in templates.values() for label in _CLASS.findall(template.form))}
        return mapping

    def drawings(self) -> list[list[str]]:
        """The distinct tidy drawings of finish (each a list of its top-level elements' texts, as lxml
        writes them inside the document: no namespace declaration), in their numbers' order.
        A definition that several of them hold alike (an eye's clip path under different gazes) is
        taken out of them into `self.definitions` (ids "v0", "v1", ...: for the document's
        `<defs>`), which they refer to; the style classes are named by use (_short_classes)."""
        templates, distinct = self._templates, self._distinct
        forms = self._short_classes(templates, Counter(skeleton for skeleton, _ in distinct))
        # the local definitions' ids made the drawing's own: "k" and its number; kept as text, which
        # the document is written from (no parse, no serializing again); a definition's key for
        # _hoist made by formatting its piece's _content (no regex per drawing)
        contents = {skeleton: [(piece, _content(piece) if definition else None) for piece, definition in pieces]
                    for skeleton, pieces in forms.items()}
        texts, self.definitions = _hoist([[(piece.format(*values, k=own),
                                            None if content is None else content.format(*values, k=own).encode())
                                           for piece, content in contents[skeleton]]
                                          for (skeleton, values), own in zip(distinct, short_ids("k"))])
        return [SEPARATOR.join(kept).split(SEPARATOR) if kept else [] for kept in texts]

    def _short_classes(self, templates: dict[str, _Template],
                       uses: Counter[str]) -> dict[str, tuple[tuple[str, bool], ...]]:
        """Rename the style classes by how often the distinct tidy drawings use them (`uses`: how
        many are made from each skeleton of `templates`, in the order they come): the most used
        ones get one letter ("a".."z", "A".."Z"). Returns each skeleton's pieces (_Template's) with
        the new names. (The definitions carry no class, so counting on the templates counts what
        the document holds.)"""
        counts: Counter[str] = Counter()
        for skeleton, drawings in uses.items():  # first uses in order: ties keep that order
            for label in _CLASS.findall(templates[skeleton].form):
                counts[label] += drawings
        names = {label: _letters(rank) for rank, (label, _) in enumerate(counts.most_common())}
        self.styles = {key: names[label] for key, label in self.styles.items() if label in names}
        return {skeleton: tuple((_CLASS.sub(lambda m: f' class="{names[m.group(1)]}"', piece), definition)
                                for piece, definition in templates[skeleton].pieces)
                for skeleton in uses}

    def _template(self, skeleton: str) -> _Template:
        """The tidy drawing (_tidy_part) of the part text `skeleton` (_skeleton's: path data "@k@",
        positions SENTINEL + j) as format strings of its values (compact path data, then rounded
        positions) and of the field `k` its local definitions' ids start with (their ids "c0",
        "c1", "c0_" ... become k, k-1, k_ ...). Style classes are made here, so in the order the
        parts come."""
        distinct = len(set(_TOKEN.findall(skeleton)))
        elements = self._tidy_part((skeleton,), {f"@{k}@": f"@{k}@" for k in range(distinct)})
        holder = etree.Element(f"{{{SVG}}}g", nsmap={None: SVG})
        holder.extend(elements)
        pieces: list[tuple[str, bool]] = []
        for node in elements:  # each as it is written inside the holder (no namespace declaration)
            text = etree.tostring(node, encoding="unicode").replace(f' xmlns="{SVG}"', "", 1)
            text = _FIELD.sub(lambda m: f'="{{{m.group(1) or distinct + int(m.group(2)) - SENTINEL}}}"',
                              text.replace("{", "{{").replace("}", "}}"))
            text = _LOCAL_ID.sub(lambda m: m.group(1) + "{k}" + ("" if m.group(2) == "0" else f"-{m.group(2)}"), text)
            definition = node.tag in DEFINITIONS
            if pieces and not definition and not pieces[-1][1]:  # one format for a run (SEPARATOR between)
                pieces[-1] = (pieces[-1][0] + SEPARATOR + text, False)
            else:
                pieces.append((text, definition))
        return _Template("".join(piece for piece, _ in pieces).replace(SEPARATOR, ""), tuple(pieces))

    def _tidy_part(self, texts: tuple[str, ...], compact: dict[str, str]) -> list[etree._Element]:
        """The part drawn by `texts` (the part's element, then its definitions) with compact
        paths, groups that only pass on style dissolved, style as classes: its definitions
        (ids "c0", "c1", ...), then its elements in drawing order."""
        drawn, *definitions = parse_elements(texts)
        tops = (drawn, *definitions)
        paths = [node for top in tops for node in top.iter() if node.get("d")]
        for node in paths:
            node.set("d", compact[node.get("d")])
        renamed = {}
        for number, definition in enumerate(definitions):
            renamed[definition.get("id")] = f"c{number}"
            definition.set("id", f"c{number}")
            for node in definition.iter():
                node.attrib.pop("class", None)
        elements = _dissolve(drawn)
        for top in elements:
            for node in top.iter():
                self._tidy_node(node, renamed)
        _reuse_clip_outlines(definitions, elements)
        return [*definitions, *elements]

    def _tidy_node(self, node: etree._Element, renamed: dict[str, str]) -> None:
        """Round `node`'s position, point its references at hoisted definitions, move its style to a class."""
        attrib = node.attrib
        attrib.pop("class", None)
        style = []
        for name, value in attrib.items():
            if name in POSITIONS:
                attrib[name] = str(round(float(value)))
            elif "url(#" in value and renamed:
                target = value[5:-1] if value.startswith("url(#") and value.endswith(")") else None
                if target in renamed:
                    attrib[name] = f"url(#{renamed[target]})"
                elif target is None:
                    attrib[name] = _REFERENCE.sub(lambda m: f"url(#{renamed.get(m.group(1), m.group(1))})", value)
                elif name not in KEPT:
                    style.append((name, value))
            elif name not in KEPT:
                style.append((name, value))
        for name, _ in style:
            del attrib[name]
        attrib.pop("id", None)
        if style:
            key = tuple(sorted(style))
            label = self.styles.get(key)
            if label is None:
                label = self.styles[key] = f"s{len(self.styles)}"
            attrib["class"] = label

    def classes(self) -> dict[str, dict[str, str]]:
        """The style of every class: its properties by name."""
        return {label: dict(key) for key, label in self.styles.items()}

    def style_sheet(self) -> str:
        """The CSS of the style classes, one rule each."""
        return "".join(f".{label}{{{';'.join(f'{k}:{v}' for k, v in key)}}}" for key, label in self.styles.items())


def part_paths(parts: Iterable[Sequence[str]]) -> Iterator[str]:
    """The path data of `parts` (each the texts of a part's element and its definitions), as values."""
    return (_text(d) for texts in parts for text in texts for d in _PATH_DATA.findall(text))


def _skeleton(texts: tuple[str, ...], compact: dict[str, str]) -> tuple[str, list[str]]:
    """A part's `texts` (its element, then its definitions) with the values that tidying only
    passes on taken out: each path data as "@k@", k numbering its distinct compact forms
    (`compact`, a Compacted's) in order, so paths alike after compacting stay alike (an
    outline and its clip path); each position (POSITIONS) and each size (SIZES, a plain number)
    as SENTINEL + j, j counting them. Returns the text and the values: the distinct compact path
    data, then the positions rounded to whole pixels and the sizes as written, in the order of the
    text. Parts with one skeleton are tidied alike (Writer._template)."""
    return _skeleton_of(_VALUE.split("".join(texts)), compact)


def _skeleton_of(cut: list[str], compact: dict[str, str]) -> tuple[str, list[str]]:
    """_skeleton of the texts `cut` by _VALUE.split (text, then (name, value, text) per value:
    one pass, no callback); `cut` is used up."""
    distinct: dict[str, int] = {}
    positions: list[str] = []
    for index in range(1, len(cut), 3):
        name, value = cut[index], cut[index + 1]
        if name == "d":
            cut[index] = _path_token(distinct.setdefault(compact[_text(value)], len(distinct)))
        elif name in POSITIONS or _plain(value):
            cut[index] = _position_token(name, len(positions))
            positions.append(_whole(value) if name in POSITIONS else _as_written(value))
        else:  # a size that is not a plain number stays in the skeleton
            cut[index] = f' {name}="{value}"'
        cut[index + 1] = ""
    return "".join(cut), [*distinct, *positions]


@functools.cache
def _path_token(number: int) -> str:
    """_skeleton's placeholder of its path data `number` (made once: formatting it per value cost
    a quarter of the drawing processes' skeletons)."""
    return f' d="@{number}@"'


@functools.cache
def _position_token(name: str, number: int) -> str:
    """_skeleton's attribute `name` (POSITIONS, SIZES) holding its placeholder position `number`."""
    return f' {name}="{SENTINEL + number}"'


@functools.lru_cache(maxsize=1 << 16)
def _whole(value: str) -> str:
    """A position's text `value` rounded to whole pixels, as text (the drawings repeat a few
    thousand positions over and over)."""
    return str(round(float(value)))


@functools.lru_cache(maxsize=1 << 12)
def _as_written(value: str) -> str:
    """A size's text `value`, one object for equal texts (sent pickled once per drawing process)."""
    return value


def _reuse_clip_outlines(definitions: list[etree._Element], elements: list[etree._Element]) -> None:
    """Draw a top-level path of `elements` whose outline is that of a clip path's only path in
    `definitions` (the mouth's opening clipping the teeth, an eye's outline clipping the eyeball)
    as a `<use>` of it: the clip path's path gets the id of its clip path plus "_". The `<use>`
    carries the style (class) and the path none, so the shown copy inherits it."""
    outlines: dict[str, etree._Element] = {}
    for definition in definitions:
        if definition.tag == f"{{{SVG}}}clipPath" and len(definition) == 1 and definition[0].get("d"):
            outlines.setdefault(definition[0].get("d"), definition)
    for index, node in enumerate(elements):
        definition = outlines.get(node.get("d")) if node.tag == f"{{{SVG}}}path" else None
        if definition is None or set(node.attrib) - {"d", "class"}:
            continue
        definition[0].set("id", definition.get("id") + "_")
        use = element(None, "use", href=f"#{definition.get('id')}_")
        if node.get("class"):
            use.set("class", node.get("class"))
        elements[index] = use


def _content(definition: str) -> str:
    """The text of a `definition` as lxml serializes it on its own (the namespace declared) and
    without the ids of its nodes: equal for definitions that define alike. Of a template's piece
    (a format string) too: formatting it gives the content of the piece formatted (no value holds an id)."""
    name = _TAG.match(definition)
    assert name is not None, definition
    return _ID.sub("", f'{name.group()} xmlns="{SVG}"{definition[name.end():]}')


def _hoist(drawings: list[list[tuple[str, bytes | None]]]) -> tuple[list[list[str]], list[etree._Element]]:
    """Take the definitions that two or more of the tidy `drawings` (each its top-level definitions'
    texts with their _content as UTF-8 and other elements' texts with None, own ids "k5", "k5_",
    "k5-1", ...) hold alike out of them, pointing their references at one shared copy. Returns each
    drawing's pieces' texts left and the shared copies, ids "v0", "v1", ... (a clip path's only
    path "v0_", for its `<use>`s)."""
    held = [{key for _, key in pieces if key is not None} for pieces in drawings]
    counts = Counter(key for keys in held for key in keys)
    # named and written alike outlines side by side (their path data after its first move), for gzip
    order = sorted((content for content, count in counts.items() if count > 1), key=lambda content: _MOVE.sub(b"", content))
    names = {key: short_id("v", number) for number, key in enumerate(order)}
    shared = [etree.fromstring(key) for key in order]
    for copy, content in zip(shared, order, strict=True):
        copy.set("id", names[content])
        if len(copy) == 1:
            copy[0].set("id", names[content] + "_")
    texts: list[list[str]] = []
    for pieces, keys in zip(drawings, held, strict=True):
        if not keys:  # no definition (most drawings)
            texts.append([text for text, _ in pieces])
            continue
        local: dict[str, str] = {}
        kept = []
        for text, key in pieces:
            if key is None or counts[key] < 2:
                kept.append(text)
                continue
            own = _OWN_ID.match(text)
            assert own is not None, text
            local[own.group(1)] = names[key]
        for old, new in local.items():  # references by url() and a clip path's path's <use>
            kept = [text.replace(f'="url(#{old})"', f'="url(#{new})"').replace(f' href="#{old}_"', f' href="#{new}_"')
                    for text in kept]
        texts.append(kept)
    return texts, shared


def _letters(number: int) -> str:
    """A CSS class name for `number` >= 0 made of letters only: 0 -> "a", 51 -> "Z", 52 -> "aa"."""
    alphabet = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
    name = alphabet[number % 52]
    while number >= 52:
        number = number // 52 - 1
        name = alphabet[number % 52] + name
    return name


def short_id(letter: str, number: int) -> str:
    """An id for drawing `number` (>= 0): `letter` and the number in base 36 ("k", 1295 -> "kzz")."""
    return letter + _base36(number)


_DIGITS = "0123456789abcdefghijklmnopqrstuvwxyz"
_PAIRS = [high + low for high in _DIGITS for low in _DIGITS]  # 00 .. zz: two digits a look-up (ids by the thousand)


def _base36(number: int) -> str:
    """`number` (>= 0) in base 36, no leading zero: 0 -> "0", 1295 -> "zz", 1296 -> "100"."""
    if number < 36:
        return _DIGITS[number]
    if number < 36 * 36:
        return _PAIRS[number]
    high, low = divmod(number, 36 * 36)
    return _base36(high) + _PAIRS[low]


def short_ids(letter: str) -> Iterator[str]:
    """short_id(letter, 0), short_id(letter, 1), ... in order."""
    return (letter + _base36(number) for number in itertools.count())


def _text(value: str) -> str:
    """An attribute value as written in a part's text, back to its value."""
    return html.unescape(value) if "&" in value else value


def _dissolve(top: etree._Element) -> list[etree._Element]:
    """Hand the INHERITED style of every `<g>` in `top` down to its children (each child
    keeps what it sets itself) and replace a `<g>` left with no other attribute by its children,
    a `<g>` left with a clip path only around one shape (SHAPES, not transformed, clipped or
    masked itself) by the shape clipped; returns `top`, or what replaced it if it dissolved. Fewer elements and
    classes for the browser, fewer bytes per frame (a clipped group keeps only its clip)."""
    groups = list(top.iter(f"{{{SVG}}}g"))
    for group in groups:  # outermost first, so handed-down style goes on down
        style = {name: value for name, value in group.attrib.items() if name in INHERITED}
        for child in group:
            for name, value in style.items():
                if name not in child.attrib:
                    child.set(name, value)
        for name in style:
            del group.attrib[name]
    empty = [group for group in groups if all(name == "class" for name in group.attrib)]
    for group in reversed(empty):  # innermost first
        parent = group.getparent()
        if parent is not None:
            index = parent.index(group)
            parent[index : index + 1] = list(group)
    clipped = [group for group in groups if group not in empty and set(group.attrib) == {"clip-path"} and len(group) == 1
               and group[0].tag in SHAPES and not {"transform", "clip-path", "mask"} & set(group[0].attrib)]
    for group in clipped:  # the clip in the shape's user space, the group's own without a transform
        group[0].set("clip-path", group.get("clip-path"))
        parent = group.getparent()
        if parent is not None:
            parent.replace(group, group[0])
    if empty and empty[0] is top:
        return list(top)
    if clipped and clipped[0] is top:
        return [top[0]]
    return [top]


def _extent(d: str) -> Extent | None:
    """The box (x0, y0, x1, y1) holding every point and control point of the path data `d` (which
    holds its curves); None for data it does not read (arcs, a first command not a move)."""
    if _UNREAD.search(d):
        return None
    xs: list[float] = []
    ys: list[float] = []
    x = y = start_x = start_y = 0.0
    for letter, text in _COMMAND.findall(d):
        if not xs and letter not in "Mm" or not text.strip(" ,") and letter not in "Zz":
            return None
        low = letter.lower()
        values = [float(v) for v in _PATH_NUMBER.findall(text)]
        arity = _ARITY[low]
        if low == "z":
            x, y = start_x, start_y
            continue
        if len(values) % arity:
            return None
        for index in range(0, len(values), arity):
            chunk = values[index:index + arity]
            base_x, base_y = (x, y) if letter.islower() else (0.0, 0.0)
            if low == "h":
                x = chunk[0] + (x if letter.islower() else 0.0)
            elif low == "v":
                y = chunk[0] + (y if letter.islower() else 0.0)
            else:
                points = [(base_x + chunk[k], base_y + chunk[k + 1]) for k in range(0, arity, 2)]
                xs.extend(px for px, _ in points[:-1])
                ys.extend(py for _, py in points[:-1])
                x, y = points[-1]
            xs.append(x)
            ys.append(y)
            if low == "m" and index == 0:
                start_x, start_y = x, y
    return (min(xs), min(ys), max(xs), max(ys)) if xs else None


def _absolute_start(d: str) -> str:
    """The path data `d` (starting with a move) with its first move absolute, so that it can follow
    other path data: "m3,4 5,6" -> "M3,4l5,6"."""
    match = _FIRST_MOVE.match(d)
    if match is None:
        return d
    rest = d[match.end():]
    return f"M{match.group(1)},{match.group(2)}" + (f"l{rest}" if rest and rest[0] not in _ARITY_LETTERS else rest)


_ARITY_LETTERS = "".join(letter + letter.upper() for letter in _ARITY)


def start_tag(text: str) -> tuple[str, dict[str, str]]:
    """The tag (no namespace: "path") and attributes (values as written) of the element `text`
    begins with."""
    end = text.index(">")  # a find, not a regex: a regex walks long path data slower; and no copy of it
    name = _TAG.match(text)
    assert name is not None, text
    return name.group()[1:], dict(_ATTRIBUTE.findall(text, 1, end))


def _own_class(text: str) -> str | None:
    """The class of the element `text` begins with (None: none), by two finds (a regex walks the
    path data before it slower)."""
    start = text.find(' class="', 0, text.find(">"))
    return None if start < 0 else text[start + 8:text.index('"', start + 8)]


def with_id(text: str, name: str) -> str:
    """The element `text` (without an id) with the id `name` after its attributes, as lxml's set writes it."""
    end = text.index(">")
    end -= text[end - 1] == "/"
    return f'{text[:end]} id="{name}"{text[end:]}'


def merge_alike(elements: list[str], styles: dict[str, dict[str, str]],
                extents: Mapping[str, Extent] | None = None) -> list[str]:
    """`elements` (a drawing's element texts, in drawing order) with each run of consecutive paths of
    one opaque style (only `d` and a `class` of `styles`, no paint server, no opacity) whose extents
    lie apart (MERGE_GAP beyond half the stroke) written as one path: the same pixels, one element
    (the two brows). A path data's extent is taken from `extents` (Writer.extents: read off its
    numbers) when it is there, else read (_extent)."""
    labels = list(map(_Classes(styles).__getitem__, elements))
    if not any(map(operator.eq, labels, labels[1:])):
        return list(elements)  # only consecutive paths of one class join: none here (most drawings)
    return _joined(elements, labels, styles, extents)


def merge_all_alike(drawings: Sequence[list[str]], styles: dict[str, dict[str, str]],
                    extents: Mapping[str, Extent] | None = None) -> list[list[str]]:
    """merge_alike of each of `drawings` (the same lists where nothing joins): the classes of all their
    elements compared in one pass, the class of a text read once however many drawings show it (a
    shared part's `<use>`); only the drawings with two consecutive elements of one class are read
    further (about one in eight of a book's). A loop over the drawings took twice as long."""
    elements = list(chain.from_iterable(drawings))
    labels = list(map(_Classes(styles).__getitem__, elements))
    ends = list(accumulate(map(len, drawings)))  # of each drawing in `elements`: its first is the next's
    firsts = set(ends)
    alike = {bisect_right(ends, at) for at in compress(range(1, len(elements)), map(operator.eq, labels, labels[1:]))
             if at not in firsts}  # the drawings of the second elements of equal pairs inside one drawing
    merged = list(drawings)
    for number in alike:
        start = ends[number - 1] if number else 0
        merged[number] = _joined(drawings[number], labels[start:ends[number]], styles, extents)
    return merged


class _Classes(dict[str, str]):
    """The class of each element text asked for (_own_class), read from the text the first time, when
    paths of that class can join (_joinable by `styles`); of any other element, the text itself (no
    class is equal to it: it begins with "<"), so that the drawings holding only runs that cannot join
    (the two cheeks, the two ears: filled by gradients; two fifths of a book's runs) are not read further."""

    def __init__(self, styles: dict[str, dict[str, str]]) -> None:
        super().__init__()
        self.joinable = {name: _joinable(style) for name, style in styles.items()}

    def __missing__(self, text: str) -> str:
        own = _own_class(text)
        label = self[text] = text if own is None or not self.joinable.get(own, False) else own
        return label


def _joinable(style: dict[str, str] | None) -> bool:
    """Whether paths of the class whose declarations are `style` (None: no such class) may be joined
    into one: opaque, no paint server."""
    return style is not None and not any("url(" in value or "opacity" in name for name, value in style.items())


def _joined(elements: list[str], labels: list[str], styles: dict[str, dict[str, str]],
            extents: Mapping[str, Extent] | None) -> list[str]:
    """merge_alike of `elements` whose classes are `labels` (_Classes'): each run of one class read
    in full (_joined_run), an element of a class of its own as it is."""
    joined: list[str] = []
    for _, run in groupby(range(len(elements)), labels.__getitem__):
        texts = [elements[index] for index in run]
        joined.extend(_joined_run(texts, styles, extents) if len(texts) > 1 else texts)
    return joined


def _joined_run(elements: list[str], styles: dict[str, dict[str, str]], extents: Mapping[str, Extent] | None) -> list[str]:
    """merge_alike of `elements`, read in full."""
    tags = [start_tag(text) for text in elements]
    known = extents or {}
    merged: list[str] = []
    boxes: list[Extent] = []
    last_class: str | None = None
    for text, (tag, attrs) in zip(elements, tags, strict=True):
        label = attrs.get("class")
        style = styles.get(label or "")
        d = _text(attrs.get("d", ""))
        extent = ((known.get(d) or _extent(d)) if tag == "path" and set(attrs) == {"d", "class"} and _joinable(style)
                  else None)
        if extent is not None and merged and last_class == label and boxes:
            pad = float((style or {}).get("stroke-width", "1")) + MERGE_GAP
            if all(a[2] + pad < extent[0] or extent[2] + pad < a[0] or a[3] + pad < extent[1] or extent[3] + pad < a[1]
                   for a in boxes):
                # the path before holds d and class only (it has an extent): its d extended
                before = _PATH_DATA.search(merged[-1])
                assert before is not None, merged[-1]
                merged[-1] = f"{merged[-1][:before.end(1)]}{_absolute_start(d)}{merged[-1][before.end(1):]}"
                boxes.append(extent)
                continue
        merged.append(text)
        last_class = label
        boxes = [extent] if extent is not None else []
    return merged


def bare(elements: Sequence[str]) -> bool:
    """Whether the drawing `elements` (element texts) is one element that can itself be the target of
    a `<use>` in place of a `<g id>` around it: drawn (not a definition) and without an id of its own."""
    if len(elements) != 1:
        return False
    text = elements[0]
    name = _TAG.match(text)
    assert name is not None, text
    # start_tag's, without reading (or copying) the attributes: an id is ' id="' before the first ">"
    return f"{{{SVG}}}{name.group()[1:]}" not in DEFINITIONS and text.find(' id="', 0, text.index(">")) < 0


def _children(text: str) -> int:
    """How many child elements the element `text` holds."""
    if text.count("<") == 1:  # one empty element (most shared parts): no tag to walk
        return 0
    depth = children = 0
    for match in _ANY_TAG.finditer(text):
        if match.group(1):
            depth -= 1
            continue
        if depth == 1:
            children += 1
        if text[match.end() - 2] != "/":  # not an empty element
            depth += 1
    return children


def _kind(elements: Sequence[str]) -> tuple[str, str, int, int, str]:
    """The order of the parts share puts into `<defs>`: parts of one kind (their first element's tag and
    class, how many elements) together, alike outlines side by side (the first path data's commands and
    numbers after its starting point): gzip finds their repeats within its window (32 KB)."""
    first = elements[0]
    tag, attrs = start_tag(first)
    if tag == "path":  # its own start tag, read already
        path_attrs = attrs
    else:
        path = _FIRST_PATH.search(first)
        path_attrs = start_tag(first[path.start():])[1] if path else {}
    d = _text(path_attrs.get("d", ""))
    return tag, attrs.get("class", ""), len(elements), _children(first), _START.sub("", d, count=1)


def share(drawings: dict[str, list[list[int]]], tidy: list[list[str]],
          moved: Mapping[int, tuple[int, str]] | None = None) -> tuple[dict[str, list[list[str]]], str]:
    """The element texts of every drawing of `drawings` (lists of tidy part numbers by group, as
    Writer.finish numbered them into `tidy`: Writer.drawings'): a part drawn in one drawing only is
    itself; a part in several is put once into the definitions as `<g id="gN">` (a part of one element:
    that element with the id, no `<g>`: bare) and each drawing shows it with `<use>`. A part of `moved`
    (part -> an earlier part and the SVG matrix "a b c d e f" that shows it, render/reuse.py) is a
    `<use transform="matrix(...)">` of that part, put into the definitions as shared. Returns the
    drawings' element texts by group and the definitions' text."""
    shown = moved or {}
    # a moved part counts as a use of its source (which its own drawing uses too: shared)
    shows = list(chain.from_iterable(chain.from_iterable(drawings.values())))  # the parts, as often as shown
    sources = {part: source for part, (source, _) in shown.items()}
    uses = Counter(map(sources.get, shows, shows))  # C loops: each part's source or itself
    names: dict[int, str] = {}
    defs = []
    for part in sorted((part for part, count in uses.items() if count > 1), key=lambda part: _kind(tidy[part])):
        names[part] = short_id("g", len(names))
        defs.append(with_id(tidy[part][0], names[part]) if bare(tidy[part])
                    else markup("g", {"id": names[part]}, "".join(tidy[part])))
    # each part's texts made once, however many drawings show it (ids and matrices need no escaping)
    nodes = {part: [f'<use href="#{names[shown[part][0]]}" transform="matrix({shown[part][1]})"/>'] if part in shown
             else [f'<use href="#{names[part]}"/>'] if part in names else tidy[part] for part in dict.fromkeys(shows)}
    return ({track: [list(chain.from_iterable(map(nodes.__getitem__, drawing))) for drawing in track_drawings]
             for track, track_drawings in drawings.items()}, "".join(defs))
