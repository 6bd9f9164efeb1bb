"""The talking-face animation as one SVG document (thesis 002, ch. 6).

Spatial domain (6.3.1): four layers, background, hair, clothes and face, drawn
in that order; gradients and clip paths live once in `<defs>`.

Temporal domain (6.3.2): the thesis shows each frame as
`<g visibility="hidden"><set attributeName="visibility" to="visible" begin=".." dur=".."/>...</g>`.
We keep that form and make it small:

- the face of render/svg.py is split into part tracks (TRACK_OF): hair, ears,
  face (outline and cheeks, which follow the jaw), features (nose and brows),
  eyes, mouth. Each track has its own frames, so a moving mouth does not
  repeat the eyes, and a still head does not repeat the hair;
- a part drawing that looks the same in consecutive frames is one longer
  `<set>`; a drawing that comes back later (the rest mouth, open eyes) is
  written once with one `<set>` per time it is shown;
- a track whose drawing never changes is written once, outside any frame;
- coordinates are rounded to whole pixels of the face canvas and written as
  relative path commands; runs of straight segments (the corner-cut hair and
  brows) drop points within half a pixel of the line through their
  neighbours (Douglas-Peucker): below what a screen shows, at a third of the
  bytes;
- repeated presentation attributes become a handful of CSS classes.

Frame i shows time i / fps. Times are written in whole milliseconds, each
`begin`/`dur` derived from the frame boundaries round(i * 1000 / fps), so the
`<set>`s of one track tile the timeline with no gap and no overlap. The last
drawing of each track is frozen (`fill="freeze"`) so the face stays after the
end. SMIL starts at 0 when the document loads: animation.svg opened on its
own plays silently; the pages drive its clock from the audio (static/cartoonface.js).
"""

from __future__ import annotations

import functools
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from lxml import etree

from cartoonface.face.lift import lift
from cartoonface.face.model import FaceModel
from cartoonface.face.pose import pose_face
from cartoonface.face.state import FaceState
from cartoonface.render.scenery import Figure, background_layer, clothes_layer
from cartoonface.render.svg import face_defs, face_group

SVG = "http://www.w3.org/2000/svg"
NSMAP = {None: SVG}
# The track of each part of render/svg.py's face_group (by its class), in drawing order.
# Parts that change together share a track; a part of another class gets a track of its own.
TRACK_OF = {"hair": "hair", "ear-l": "ears", "ear-r": "ears", "face": "face", "cheeks": "face",
            "nose": "features", "brow-l": "features", "brow-r": "features", "eye-l": "eyes", "eye-r": "eyes",
            "mouth": "mouth"}
HAIR_TRACKS = ("hair",)  # drawn in the hair layer, behind the clothes; every other track in the face layer
# Elements that only define something referenced by id: hoisted out of the frames into <defs>
# (inside a hidden frame a clip path's children would inherit visibility="hidden" and clip everything).
DEFINITIONS = frozenset(f"{{{SVG}}}{tag}" for tag in ("clipPath", "linearGradient", "radialGradient", "mask",
                                                       "pattern", "filter", "marker", "symbol"))
# Attributes that place an element (rounded, kept on it); every other attribute but these
# and the references below is style, moved into a CSS class.
POSITIONS = frozenset(("cx", "cy", "x", "y", "x1", "y1", "x2", "y2"))
KEPT = frozenset(("d", "r", "rx", "ry", "width", "height", "points", "clip-path", "mask", "transform", "id",
                  "offset"))
UID = "u"  # the one uid every state is drawn with; definitions are then renamed by content
WIDE = 16 / 9  # the announcer's stage: a 16:9 picture with the face in the middle
TOLERANCE = 0.5  # pixels: straight runs lose points closer than this to the simplified line
_TOKEN = re.compile(r"[A-Za-z]|[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
_REFERENCE = re.compile(r"url\(#([^)]+)\)")
_ARITY = {"M": 2, "L": 2, "C": 6, "Q": 4, "S": 4, "T": 2, "H": 1, "V": 1, "Z": 0}


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
    return f"{ms // 1000}.{ms % 1000:03d}".rstrip("0").rstrip(".")


def runs(keys: Sequence[int]) -> tuple[Run, ...]:
    """Merge consecutive equal drawing numbers `keys` (one per frame) into Runs, in time order."""
    merged: list[Run] = []
    for index, key in enumerate(keys):
        if merged and merged[-1].drawing == key:
            merged[-1] = Run(key, merged[-1].first, merged[-1].count + 1)
        else:
            merged.append(Run(key, index, 1))
    return tuple(merged)


def _simplify(points: list[tuple[int, int]]) -> list[tuple[int, int]]:
    """Douglas-Peucker: the points of a polyline (first and last kept) whose dropping would move
    the line by more than TOLERANCE pixels."""
    if len(points) < 3:
        return points
    xy = np.array(points, dtype=float)
    keep = np.zeros(len(xy), dtype=bool)
    keep[[0, -1]] = True
    stack = [(0, len(xy) - 1)]
    while stack:
        first, last = stack.pop()
        if last - first < 2:
            continue
        chord = xy[last] - xy[first]
        offsets = xy[first + 1 : last] - xy[first]
        length = float(np.hypot(*chord))
        if length == 0:
            distance = np.hypot(offsets[:, 0], offsets[:, 1])
        else:
            distance = np.abs(chord[0] * offsets[:, 1] - chord[1] * offsets[:, 0]) / length
        worst = int(np.argmax(distance))
        if distance[worst] > TOLERANCE:
            middle = first + 1 + worst
            keep[middle] = True
            stack += [(first, middle), (middle, last)]
    return [point for point, kept in zip(points, keep.tolist(), strict=True) if kept]


def _numbers(values: Sequence[int]) -> str:
    """Integers joined the SVG way: a comma only where the next one has no minus sign."""
    text = ""
    for value in values:
        text += f"{value}" if not text or value < 0 else f",{value}"
    return text


@functools.lru_cache(maxsize=1 << 16)
def compact_path(d: str) -> str:
    """Path data `d` (absolute M/L/C/Q/S/T/H/V/Z commands) rounded to whole pixels, straight runs
    simplified (TOLERANCE), written with relative commands; `d` unchanged if it holds anything else."""
    tokens = _TOKEN.findall(d)
    commands: list[tuple[str, list[int]]] = []
    x = y = start_x = start_y = 0
    index, command = 0, ""
    while index < len(tokens):
        if tokens[index].isalpha():
            command = tokens[index]
            index += 1
        if command not in _ARITY:
            return d
        if command == "Z":
            commands.append(("z", []))
            x, y = start_x, start_y
            continue
        arity = _ARITY[command]
        try:
            values = [round(float(v)) for v in tokens[index : index + arity]]
        except ValueError:
            return d
        if len(values) < arity:
            return d
        index += arity
        if command == "H":
            command, values = "L", [values[0], y]
        elif command == "V":
            command, values = "L", [x, values[0]]
        commands.append((command, values))
        x, y = values[-2], values[-1]
        if command == "M":
            start_x, start_y = x, y
            command = "L"  # numbers after a moveto are linetos
    return _relative(_straightened(commands))


def _straightened(commands: list[tuple[str, list[int]]]) -> list[tuple[str, list[int]]]:
    """The commands with each run of linetos simplified (`_simplify`) and zero-length linetos dropped."""
    out: list[tuple[str, list[int]]] = []
    current = run_start = (0, 0)
    run: list[tuple[int, int]] = []
    for command, values in [*commands, ("end", [])]:
        if command == "L":
            if not run:
                run_start = current
            run.append((values[0], values[1]))
        else:
            if run:
                kept = _simplify([run_start, *run])[1:]
                out += [("L", [px, py]) for (px, py), (qx, qy) in zip(kept, [run_start, *kept]) if (px, py) != (qx, qy)]
                run = []
            if command != "end":
                out.append((command, values))
        if values:
            current = (values[-2], values[-1])
        elif command == "z":
            current = _subpath_start(out)
    return out


def _subpath_start(commands: list[tuple[str, list[int]]]) -> tuple[int, int]:
    """Where the last subpath of `commands` began (its moveto), (0, 0) if none."""
    for command, values in reversed(commands):
        if command == "M":
            return values[0], values[1]
    return 0, 0


def _relative(commands: list[tuple[str, list[int]]]) -> str:
    """Absolute integer commands as relative path text (z returns to the subpath start)."""
    text, previous = "", ""
    x = y = start_x = start_y = 0
    for command, values in commands:
        if command == "z":
            text += "z"
            x, y, previous = start_x, start_y, "z"
            continue
        relative = [v - (y if i % 2 else x) for i, v in enumerate(values)]
        letter = command.lower()
        numbers = _numbers(relative)
        if letter == previous and letter != "m":
            text += numbers if numbers.startswith("-") else "," + numbers
        else:
            text += letter + numbers
        x, y = values[-2], values[-1]
        if command == "M":
            start_x, start_y = x, y
        previous = letter
    return text


def figure_of(face: FaceModel, box: tuple[float, float, float, float]) -> Figure:
    """Where the neck and shoulders go for `face` inside the picture `box` (the face is as wide as
    its widest feature points, the contour)."""
    chin = face.point("2.1")
    return Figure(box=box, chin_x=float(chin[0]), chin_y=float(chin[1]),
                  face_width=float(np.ptp(face.points[:, 0])), skin=face.palette.skin)


def _el(parent: etree._Element, tag: str, **attrs: str) -> etree._Element:
    """Append the SVG element `tag` with attributes `attrs` (underscores become hyphens) to `parent`."""
    return etree.SubElement(parent, f"{{{SVG}}}{tag}", {k.replace("_", "-"): v for k, v in attrs.items()})


def track_of(part: etree._Element) -> str:
    """The track a top-level part of a face group belongs to (TRACK_OF by its class)."""
    name = (part.get("class") or "").split()
    return TRACK_OF.get(name[0], name[0]) if name else "face"


class _Drawings:
    """Distinct part drawings of every track, the definitions they share and their style classes."""

    def __init__(self, defs: etree._Element) -> None:
        self.defs = defs
        self.definition_ids: dict[bytes, str] = {}
        self.styles: dict[tuple[tuple[str, str], ...], str] = {}
        self.order: list[str] = []  # tracks in drawing order
        self.keys: dict[str, dict[bytes, int]] = {}
        self.parts: dict[str, list[list[etree._Element]]] = {}
        self.shapes: list[str] = []  # dominant mouth symbol of each mouth drawing

    def _hoist(self, definition: etree._Element) -> str:
        """Move `definition` to <defs> under an id named by its content (shared if seen before)."""
        definition.attrib.pop("id", None)
        for node in definition.iter():
            self._tidy(node, style=False)
        content = etree.tostring(definition)
        new_id = self.definition_ids.get(content)
        if new_id is None:
            new_id = f"k{len(self.definition_ids)}"
            self.definition_ids[content] = new_id
            definition.set("id", new_id)
            self.defs.append(definition)
        return new_id

    def _tidy(self, node: etree._Element, style: bool, renamed: dict[str, str] | None = None) -> None:
        """Round `node`'s coordinates, point references at renamed definitions and, if `style`,
        move its presentation attributes into a CSS class."""
        attrib = node.attrib
        if "d" in attrib:
            attrib["d"] = compact_path(attrib["d"])
        attrib.pop("class", None)
        moved = []
        for name, value in list(attrib.items()):
            if name in POSITIONS:
                attrib[name] = str(round(float(value)))
            elif renamed and "url(#" in value:
                value = attrib[name] = _REFERENCE.sub(lambda m: f"url(#{renamed.get(m.group(1), m.group(1))})", value)
            if style and name not in POSITIONS and name not in KEPT and "url(#k" not in value:
                moved.append((name, attrib.pop(name)))
        if moved:
            key = tuple(sorted(moved))
            label = self.styles.get(key)
            if label is None:
                label = self.styles[key] = f"s{len(self.styles)}"
            attrib["class"] = label

    def add(self, group: etree._Element, state: FaceState) -> dict[str, int]:
        """Split one drawn face `group` into tracks; return {track: drawing number}."""
        renamed: dict[str, str] = {}
        for definition in [e for e in group.iter() if e.tag in DEFINITIONS and e.get("id")]:
            old = definition.get("id")
            definition.getparent().remove(definition)
            renamed[old] = self._hoist(definition)
        by_track: dict[str, list[etree._Element]] = {}
        for part in group:
            if not isinstance(part.tag, str) or part.tag == f"{{{SVG}}}defs":
                continue
            track = track_of(part)
            for node in part.iter():
                node.attrib.pop("id", None)
                self._tidy(node, style=True, renamed=renamed)
            by_track.setdefault(track, []).append(part)
        numbers = {}
        for track, parts in by_track.items():
            if track not in self.keys:
                self.order.append(track)
                self.keys[track], self.parts[track] = {}, []
            key = b"".join(etree.tostring(part) for part in parts)
            known = self.keys[track]
            if key not in known:
                known[key] = len(known)
                self.parts[track].append(parts)
                if track == "mouth":
                    self.shapes.append(max(state.mouth, key=lambda pair: pair[1])[0])
            numbers[track] = known[key]
        return numbers

    def style_sheet(self) -> str:
        """The CSS of the style classes, one rule each."""
        return "".join(f".{label}{{{';'.join(f'{k}:{v}' for k, v in key)}}}" for key, label in self.styles.items())


def _track_group(parent: etree._Element, track: str, drawings: list[list[etree._Element]],
                 keys: Sequence[int], fps: int, shapes: Sequence[str]) -> None:
    """Write one track into `parent`: its drawing as is if it never changes, else one
    `<g visibility="hidden">` per distinct drawing with a `<set>` per run of frames showing it."""
    holder = _el(parent, "g", data_part=track)
    if len(drawings) == 1:
        holder.extend(drawings[0])
        return
    frames = [_el(holder, "g", visibility="hidden") for _ in drawings]
    all_runs = runs(keys)
    for run in all_runs:
        begin, end = frame_ms(run.first, fps), frame_ms(run.first + run.count, fps)
        show = _el(frames[run.drawing], "set", attributeName="visibility", to="visible", begin=clock(begin),
                   dur=clock(end - begin))
        if run is all_runs[-1]:
            show.set("fill", "freeze")
    for number, (frame, parts) in enumerate(zip(frames, drawings, strict=True)):
        if track == "mouth":
            frame.set("data-shape", shapes[number])
        frame.extend(parts)


def animation_svg(face: FaceModel, states: Sequence[FaceState], fps: int, *, background: str = "plain",
                  clothes: str = "none", wide: bool = False, title: str = "") -> bytes:
    """The animation of `states` (frame i shows time i / fps s) as a standalone SVG document (UTF-8 bytes).

    `background` and `clothes` name the scenery layers (render/scenery.py);
    `wide` widens the picture to 16:9 around the face (the announcer's stage);
    `title` becomes the document's <title> (escaped like every text by lxml).
    The root is `<svg id="cf-face">`; each track is a `<g data-part="...">`;
    mouth frames carry `data-shape`, the dominant basic mouth shape they show.
    """
    width, height = float(face.width), float(face.height)
    box_width = max(width, height * WIDE) if wide else width
    box = ((width - box_width) / 2, 0.0, box_width, height)
    root = etree.Element(f"{{{SVG}}}svg", nsmap=NSMAP)
    for name, value in (("id", "cf-face"), ("width", f"{box_width:g}"), ("height", f"{height:g}"),
                        ("viewBox", " ".join(f"{v:g}" for v in box)), ("data-fps", str(fps))):
        root.set(name, value)
    if title:
        _el(root, "title").text = title
    style = _el(root, "style")
    defs = _el(root, "defs")
    defs.extend(face_defs(face))
    figure = figure_of(face, box)
    root.append(background_layer(background, figure, defs))
    drawings = _Drawings(defs)
    lifted = lift(face)
    seen: dict[FaceState, dict[str, int]] = {}
    keys: dict[str, list[int]] = {}
    for state in states:
        numbers = seen.get(state)
        if numbers is None:
            numbers = seen[state] = drawings.add(face_group(face, pose_face(lifted, state), UID), state)
        for track, number in numbers.items():
            keys.setdefault(track, []).append(number)
    style.text = drawings.style_sheet()
    hair = _el(root, "g", id="hair")
    dressed = clothes_layer(clothes, figure, defs)
    if dressed is not None:
        root.append(dressed)
    layer = _el(root, "g", id="face")
    for track in drawings.order:
        _track_group(hair if track in HAIR_TRACKS else layer, track, drawings.parts[track], keys[track], fps,
                     drawings.shapes)
    return etree.tostring(root, xml_declaration=True, encoding="utf-8")
