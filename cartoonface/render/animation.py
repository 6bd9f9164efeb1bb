"""The talking-face animation as one SVG document (thesis 002, ch. 6).

Spatial domain (6.3.1): four layers, background, hair, clothes and face, drawn
in that order; the face's gradients live once in `<defs>`. A part's clip path
(the eye outline clipping the eyeball, the mouth opening clipping the teeth)
is written just before the part, inside the same frame: its children inherit
the frame's visibility, so the clip is whole exactly while the part is shown,
and gzip finds the clip's outline next to the same outline drawn by the part.

Temporal domain (6.3.2): the thesis shows each frame as
`<g visibility="hidden"><set attributeName="visibility" to="visible" begin=".." dur=".."/>...</g>`.
We keep that form and make it small:

- the face of render/svg.py is split into part tracks (TRACK_OF): hair, ears,
  face (outline, cheeks and mouth, which follow the jaw), features (nose and
  brows), eyes. Each track has its own frames, so a moving mouth does not
  repeat the eyes, and a still head does not repeat the hair;
- a part drawing that looks the same in consecutive frames is one longer
  `<set>`; a drawing that comes back later (the rest mouth, open eyes) is
  written once, its earlier runs in one `<set>` with a begin list (and one
  `dur`, or an end list), its last run in a `<set>` of its own;
- a track whose drawing never changes is written once, outside any frame;
- every frame's state is drawn (no pose held over frames); the head's roll is
  not drawn into the parts but is a rotation of the hair and face layers (one
  discrete `<animateTransform>` each), so a sideways lean redraws nothing;
- coordinates are whole pixels in relative path commands (render/pathdata.py);
- a part shown in several drawings of its track (the face outline under
  different mouths) is defined once and drawn with `<use>`; a path with the
  outline of its part's clip path (the mouth's opening, an eye's white and
  outline) is a `<use>` of the clip path's outline;
- repeated presentation attributes become CSS classes, the most used ones
  named by one letter; ids are short (base 36).

Frame i shows time i / fps. Times are written in whole milliseconds, each
`begin`/`dur`/`end` derived from the frame boundaries round(i * 1000 / fps), so the
`<set>`s of one track tile the timeline with no gap and no overlap. The last
drawing of each track is frozen (`fill="freeze"`) so the face stays after the
end. SMIL starts at 0 when the document loads: animation.svg opened on its
own plays silently; the pages drive its clock from the audio (static/cartoonface.js).
"""

from __future__ import annotations

import html
import re
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from lxml import etree

from cartoonface.face.lift import lift
from cartoonface.face.model import FaceModel
from cartoonface.face.pose import pose_face, rig, unroll, unrolled
from cartoonface.face.state import FaceState
from cartoonface.render.elements import SVG, element, svg_root
from cartoonface.render.numbers import decimal_text
from cartoonface.render.pathdata import compact_paths
from cartoonface.render.scenery import Figure, background_layer, clothes_layer
from cartoonface.render.svg import face_defs, face_group

# The track of each part of render/svg.py's face_group (by its class), in drawing order.
# Parts that change together share a track; a part of another class gets a track of its own.
# The mouth moves with the jaw, so it shares the track of the face outline: it is then drawn
# before the nose, brows and eyes rather than after them, which changes nothing on screen
# (they never overlap; where a nodding nose tip comes near the upper lip, the nose in front is right).
TRACK_OF = {"hair": "hair", "ear-l": "ears", "ear-r": "ears", "face": "face", "cheeks": "face",
            "nose": "features", "brow-l": "features", "brow-r": "features", "eye-l": "eyes", "eye-r": "eyes",
            "mouth": "face"}
MOUTH_TRACK = TRACK_OF["mouth"]  # its frames carry data-shape
HAIR_TRACKS = ("hair",)  # drawn in the hair layer, behind the clothes; every other track in the face layer
# Elements that only define something referenced by id: a part's own ones (per state, from
# face_group) go with the part, renamed so each distinct part drawing has its own.
DEFINITIONS = tuple(f"{{{SVG}}}{tag}" for tag in ("clipPath", "linearGradient", "radialGradient", "mask",
                                                  "pattern", "filter", "marker", "symbol"))
# Attributes that place an element (rounded to whole pixels, kept on it). Every other
# attribute but KEPT ones and references to per-state definitions is style: a CSS class.
POSITIONS = frozenset(("cx", "cy", "x", "y", "x1", "y1", "x2", "y2"))
KEPT = frozenset(("d", "r", "rx", "ry", "width", "height", "points", "clip-path", "mask", "transform", "href",
                  "offset", "id"))
# Properties a <g> passes on to its children by inheritance (SVG 1.1, property index): a group
# with no other attribute can be dissolved into its children. Not opacity, which applies to
# the group as a whole.
INHERITED = frozenset(("fill", "fill-opacity", "fill-rule", "stroke", "stroke-width", "stroke-linecap",
                       "stroke-linejoin", "stroke-opacity", "stroke-miterlimit", "stroke-dasharray",
                       "stroke-dashoffset", "color"))
UID = "u"  # the one uid every state is drawn with; definitions are then renamed by content
WIDE = 16 / 9  # the announcer's stage: a 16:9 picture with the face in the middle,
STAGE_DEPTH = 1.3  # reaching this many canvas heights down, so the shoulders show under the chin
# The head's roll (Pose.roll, a sideways lean) is drawn as a rotation of the hair and face
# layers, in steps of this many decimals of a degree: 0.01 degree moves a point 250 px from
# the centre by 0.04 px.
ROLL_DECIMALS = 2
_REFERENCE = re.compile(r"url\(#([^)]+)\)")
_PATH_DATA = re.compile(rb' d="([^"]*)"')


@dataclass(frozen=True)
class Run:
    """Frames `first` .. `first + count - 1` of a track show its drawing number `drawing`."""

    drawing: int
    first: int
    count: int


def frame_ms(index: int, fps: int) -> int:
    """Start of frame `index` at `fps` frames per second, in whole milliseconds."""
    return round(index * 1000 / fps)


def clock(ms: int) -> str:
    """A SMIL clock value (seconds, no unit) for `ms` milliseconds: 1234 -> '1.234', 500 -> '0.5', 0 -> '0'."""
    return decimal_text(ms / 1000, 3)  # exact: ms / 1000 is the double nearest a 3-decimal number


def runs(keys: Sequence[int]) -> tuple[Run, ...]:
    """Merge consecutive equal drawing numbers `keys` (one per frame) into Runs, in time order."""
    merged: list[Run] = []
    for index, key in enumerate(keys):
        if merged and merged[-1].drawing == key:
            merged[-1] = Run(key, merged[-1].first, merged[-1].count + 1)
        else:
            merged.append(Run(key, index, 1))
    return tuple(merged)


def figure_of(face: FaceModel, box: tuple[float, float, float, float]) -> Figure:
    """Where the neck and shoulders go for `face` inside the picture `box` (the face is as wide as
    its widest feature points, the contour)."""
    chin = face.point("2.1")
    return Figure(box=box, chin_x=float(chin[0]), chin_y=float(chin[1]),
                  face_width=float(np.ptp(face.points[:, 0])), skin=face.palette.skin)


def track_of(part: etree._Element) -> str:
    """The track a top-level part of a face group belongs to (TRACK_OF by its class)."""
    name = (part.get("class") or "").split()
    return TRACK_OF.get(name[0], name[0]) if name else "face"


@dataclass(frozen=True)
class _RawPart:
    """A part as face_group drew it (serialized: a drawing of every state would not fit in
    memory as lxml trees), with the per-state definitions it references."""

    track: str
    element: bytes
    definitions: tuple[bytes, ...]


class _Writer:
    """Collects the drawn states, then writes the distinct part drawings compactly."""

    def __init__(self, defs: etree._Element) -> None:
        self.defs = defs
        self.raw_ids: dict[bytes, int] = {}
        self.raw: list[_RawPart] = []
        self.styles: dict[tuple[tuple[str, str], ...], str] = {}

    def collect(self, group: etree._Element) -> tuple[int, ...]:
        """Take one face_group drawing; return the raw part numbers, in drawing order."""
        definitions = {node.get("id"): node for node in group.iter(*DEFINITIONS) if node.get("id")}
        numbers = []
        for part in group:
            if not isinstance(part.tag, str) or part.tag == f"{{{SVG}}}defs":
                continue
            raw = etree.tostring(part)
            used = tuple(etree.tostring(node) for name, node in definitions.items() if f"#{name})".encode() in raw)
            key = raw + b"".join(used)
            number = self.raw_ids.get(key)
            if number is None:
                number = self.raw_ids[key] = len(self.raw)
                self.raw.append(_RawPart(track_of(part), raw, used))
            numbers.append(number)
        return tuple(numbers)

    def finish(self) -> tuple[list[int], list[list[etree._Element]]]:
        """Tidy every raw part; return, per raw part, the number of its distinct tidy drawing,
        and the tidy drawings (each a list of elements)."""
        compact = compact_paths(_text(d) for part in self.raw
                                for raw in (part.element, *part.definitions) for d in _PATH_DATA.findall(raw))
        self.raw_ids.clear()
        tidy_ids: dict[bytes, int] = {}
        tidy: list[list[etree._Element]] = []
        mapping = []
        for part in self.raw:
            elements = self._tidy_part(part, compact)
            key = b"".join(etree.tostring(element) for element in elements)
            number = tidy_ids.get(key)
            if number is None:
                number = tidy_ids[key] = len(tidy)
                tidy.append(_own_ids(elements, short_id("k", number)))
            mapping.append(number)
        self._short_classes(tidy)
        return mapping, tidy

    def _short_classes(self, tidy: list[list[etree._Element]]) -> None:
        """Rename the style classes of the `tidy` drawings (each written once in the document) by
        how often they are used: the most used ones get one letter ("a".."z", "A".."Z")."""
        nodes = [node for elements in tidy for top in elements for node in top.iter() if node.get("class")]
        counts = Counter(node.get("class") for node in nodes)
        names = {label: _letters(rank) for rank, (label, _) in enumerate(counts.most_common())}
        for node in nodes:
            node.set("class", names[node.get("class")])
        self.styles = {key: names[label] for key, label in self.styles.items() if label in names}

    def _tidy_part(self, part: _RawPart, compact: dict[str, str]) -> list[etree._Element]:
        """The part with compact paths, groups that only pass on style dissolved, style as
        classes: its definitions (ids "c0", "c1", ...), then its elements in drawing order."""
        element = etree.fromstring(part.element)
        definitions = [etree.fromstring(raw) for raw in part.definitions]
        tops = (element, *definitions)
        paths = [node for top in tops for node in top.iter() if node.get("d")]
        for node in paths:
            node.set("d", compact[node.get("d")])
        renamed = {}
        for number, definition in enumerate(definitions):
            renamed[definition.get("id")] = f"c{number}"
            definition.set("id", f"c{number}")
            for node in definition.iter():
                node.attrib.pop("class", None)
        elements = _dissolve(element)
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

    def style_sheet(self) -> str:
        """The CSS of the style classes, one rule each."""
        return "".join(f".{label}{{{';'.join(f'{k}:{v}' for k, v in key)}}}" for key, label in self.styles.items())


def _reuse_clip_outlines(definitions: list[etree._Element], elements: list[etree._Element]) -> None:
    """Draw a top-level path of `elements` whose outline is that of a clip path's only path in
    `definitions` (the mouth's opening clipping the teeth, an eye's outline clipping the eyeball)
    as a `<use>` of it: the clip path's path gets the id of its clip path plus "_". The `<use>`
    carries the style (class) and the path none, so the shown copy inherits it."""
    outlines = {}
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
    digits = ""
    while True:
        number, digit = divmod(number, 36)
        digits = "0123456789abcdefghijklmnopqrstuvwxyz"[digit] + digits
        if not number:
            return letter + digits


def _own_ids(elements: list[etree._Element], prefix: str) -> list[etree._Element]:
    """`elements` with their local definition ids ("c0", "c1", ...) made unique: `prefix`,
    `prefix`-1, ..., and the references to them."""
    def own(local: str) -> str:  # "c0" -> prefix, "c0_" -> prefix + "_", "c1" -> prefix + "-1"
        number, rest = re.fullmatch(r"c(\d+)(\D*)", local).groups()
        return prefix + ("" if number == "0" else f"-{number}") + rest

    for top in elements:
        for node in top.iter():
            for name, value in node.attrib.items():
                if name == "id":
                    node.set(name, own(value))
                elif value.startswith("url(#c"):
                    node.set(name, f"url(#{own(value[5:-1])})")
                elif name == "href" and value.startswith("#c"):
                    node.set(name, f"#{own(value[1:])}")
    return elements


def _text(value: bytes) -> str:
    """An attribute value as serialized by lxml, back to its text."""
    text = value.decode()
    return html.unescape(text) if "&" in text else text


@dataclass
class _Track:
    """One track being filled: its distinct drawings (tidy part numbers), the drawing number of
    every frame, and the dominant mouth symbol of each drawing (mouth track only)."""

    drawings: list[list[int]] = field(default_factory=list)
    keys: list[int] = field(default_factory=list)
    shapes: list[str] = field(default_factory=list)


def _tracks(frames: Sequence[tuple[FaceState, tuple[int, ...]]], raw_tracks: Sequence[str],
            mapping: Sequence[int]) -> dict[str, _Track]:
    """Group each frame's raw parts (track names `raw_tracks`, tidy numbers `mapping`) into
    tracks, in drawing order; equal drawings of a track get one number."""
    tracks: dict[str, _Track] = {}
    numbers: dict[str, dict[tuple[int, ...], int]] = {}
    for state, parts in frames:
        by_track: dict[str, list[int]] = {}
        for raw in parts:
            by_track.setdefault(raw_tracks[raw], []).append(mapping[raw])
        for name, tidy_parts in by_track.items():
            track = tracks.setdefault(name, _Track())
            known = numbers.setdefault(name, {})
            number = known.get(tuple(tidy_parts))
            if number is None:
                number = known[tuple(tidy_parts)] = len(track.drawings)
                track.drawings.append(tidy_parts)
                if name == MOUTH_TRACK:
                    track.shapes.append(max(state.mouth, key=lambda pair: pair[1])[0])
            track.keys.append(number)
    return tracks


def _dissolve(element: etree._Element) -> list[etree._Element]:
    """Hand the INHERITED style of every `<g>` in `element` down to its children (each child
    keeps what it sets itself) and replace a `<g>` left with no other attribute by its children;
    returns `element`, or its children if `element` itself dissolved. Fewer elements and
    classes for the browser, fewer bytes per frame (a clipped group keeps only its clip)."""
    groups = list(element.iter(f"{{{SVG}}}g"))
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
    if empty and empty[0] is element:
        return list(element)
    return [element]


def _show(frame: etree._Element, spans: Sequence[tuple[int, int]]) -> etree._Element:
    """Add to `frame` the `<set>` making it visible during `spans` ((begin, end) ms, in time
    order): one begin list, with one `dur` if all spans are as long, else with the list of
    their ends (SMIL: each interval ends at the first end after its begin). Returns the set."""
    begins = ";".join(clock(begin) for begin, _ in spans)
    lengths = {end - begin for begin, end in spans}
    timing = ({"dur": clock(lengths.pop())} if len(lengths) == 1
              else {"end": ";".join(clock(end) for _, end in spans)})
    return element(frame, "set", attributeName="visibility", to="visible", begin=begins, **timing)


def _track_group(parent: etree._Element, track: str, drawings: list[list[etree._Element]],
                 keys: Sequence[int], fps: int, shapes: Sequence[str]) -> None:
    """Write one track into `parent`: its drawing as is if it never changes, else one
    `<g visibility="hidden">` per distinct drawing, shown by `<set>`s (_show) over the runs of
    frames showing it."""
    holder = element(parent, "g", data_part=track)
    if len(drawings) == 1:
        holder.extend(drawings[0])
        return
    frames = [element(holder, "g", visibility="hidden") for _ in drawings]
    all_runs = runs(keys)
    shown: list[list[tuple[int, int]]] = [[] for _ in drawings]  # (begin, end) ms of each drawing's runs
    for run in all_runs[:-1]:
        shown[run.drawing].append((frame_ms(run.first, fps), frame_ms(run.first + run.count, fps)))
    for frame, spans in zip(frames, shown, strict=True):
        if spans:
            _show(frame, spans)
    last = all_runs[-1]
    _show(frames[last.drawing], [(frame_ms(last.first, fps), frame_ms(last.first + last.count, fps))]).set(
        "fill", "freeze")
    for number, frame in enumerate(frames):
        if track == MOUTH_TRACK:
            frame.set("data-shape", shapes[number])
        frame.extend(drawings[number])


def _share(drawings: dict[str, list[list[int]]], tidy: list[list[etree._Element]],
           defs: etree._Element) -> dict[str, list[list[etree._Element]]]:
    """The elements of every drawing: a part drawn in one drawing only is itself; a part in
    several is put once into `defs` as `<g id="gN">` and each drawing shows it with `<use>`."""
    uses = Counter(part for track in drawings.values() for drawing in track for part in drawing)
    names: dict[int, str] = {}
    for part, count in uses.items():
        if count > 1:
            names[part] = short_id("g", len(names))
            element(defs, "g", id=names[part]).extend(tidy[part])
    return {track: [[node for part in drawing
                     for node in ([element(None, "use", href=f"#{names[part]}")] if part in names
                                  else tidy[part])]
                     for drawing in track_drawings]
            for track, track_drawings in drawings.items()}


def _roll(layers: Sequence[etree._Element], rolls: Sequence[int], fps: int, centre: str) -> None:
    """Turn each of `layers` by the head's roll: `rolls` (one per frame, hundredths of a degree,
    positive counter-clockwise) as one discrete `<animateTransform>` whose key times are the
    frame boundaries of the runs of equal rolls; `centre` "x y" is the rotation origin.
    Nothing is added when the head never rolls."""
    if not any(rolls):
        return
    all_runs = runs(rolls)
    total = frame_ms(len(rolls), fps)
    values = ";".join(f"{-rolls[run.first] / 10 ** ROLL_DECIMALS:g} {centre}" for run in all_runs)
    # fractions of the whole, 9 decimals (never an exponent): within 0.01 ms for up to 10^4 s
    times = ";".join(decimal_text(frame_ms(run.first, fps) / total, 9) for run in all_runs)
    for layer in layers:
        layer.insert(0, element(None, "animateTransform", {
            "attributeName": "transform", "type": "rotate", "calcMode": "discrete", "values": values,
            "keyTimes": times, "dur": clock(total), "fill": "freeze"}))


def animation_svg(face: FaceModel, states: Sequence[FaceState], fps: int, *, background: str = "plain",
                  clothes: str = "none", wide: bool = False, title: str = "") -> bytes:
    """The animation of `states` (frame i shows time i / fps s) as a standalone SVG document (UTF-8 bytes).

    `background` and `clothes` name the scenery layers (render/scenery.py);
    `wide` makes the picture a 16:9 stage around the face, deep enough for the shoulders
    (the announcer's);
    `title` becomes the document's <title> (escaped like every text by lxml).
    The root is `<svg id="cf-face">`; each track is a `<g data-part="...">`;
    mouth frames carry `data-shape`, the dominant basic mouth shape they show.
    """
    width, height = float(face.width), float(face.height)
    box_height = height * STAGE_DEPTH if wide else height
    box_width = max(width, box_height * WIDE) if wide else width
    box = ((width - box_width) / 2, 0.0, box_width, box_height)
    root = svg_root({"id": "cf-face", "width": f"{box_width:g}", "height": f"{box_height:g}",
                     "viewBox": " ".join(f"{v:g}" for v in box), "data-fps": str(fps)})
    if title:
        element(root, "title").text = title
    style = element(root, "style")
    defs = element(root, "defs")
    defs.extend(face_defs(face))
    figure = figure_of(face, box)
    root.append(background_layer(background, figure, defs))
    writer = _Writer(defs)
    lifted = lift(face)
    origin = rig(lifted).origin
    by_state: dict[FaceState, tuple[int, ...]] = {}
    drawn: dict[tuple[FaceState, tuple[float, ...]], tuple[int, ...]] = {}
    frames = []
    rolls = [round(state.pose.roll * 10 ** ROLL_DECIMALS) for state in states]
    for state, roll in zip(states, rolls, strict=True):
        parts = by_state.get(state)
        if parts is None:
            # turned back by the roll as written (the two turns cancel exactly)
            posed = unroll(pose_face(lifted, state), roll / 10 ** ROLL_DECIMALS, origin)
            # the drawing depends on the state without roll and on the pupils (written to 0.1 px);
            # states that share it differ by a turn of under 0.005 degrees (the roll's rounding),
            # which moves no point by more than 0.02 px
            key = (unrolled(state), tuple(np.round(posed.pupils, 1).ravel().tolist()))
            parts = drawn.get(key)
            if parts is None:
                parts = drawn[key] = writer.collect(face_group(face, posed, UID))
            by_state[state] = parts
        frames.append((state, parts))
    mapping, tidy = writer.finish()
    tracks = _tracks(frames, [part.track for part in writer.raw], mapping)
    elements = _share({name: track.drawings for name, track in tracks.items()}, tidy, defs)
    style.text = writer.style_sheet()
    hair = element(root, "g", id="hair")
    dressed = clothes_layer(clothes, figure, defs)
    if dressed is not None:
        root.append(dressed)
    layer = element(root, "g", id="face")
    for name, track in tracks.items():
        _track_group(hair if name in HAIR_TRACKS else layer, name, elements[name], track.keys, fps, track.shapes)
    _roll((hair, layer), rolls, fps,
          f"{origin[0]:.6g} {origin[1]:.6g}")
    return etree.tostring(root, xml_declaration=True, encoding="utf-8")
