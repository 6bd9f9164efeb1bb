"""The talking-face animation as one SVG document (thesis 002, ch. 6).

Spatial domain (6.3.1): four layers, background, hair, clothes and face, drawn
in that order; gradients and clip paths live once in `<defs>`.

Temporal domain (6.3.2): the thesis shows each frame as
`<g visibility="hidden"><set attributeName="visibility" to="visible" begin=".." dur=".."/>...</g>`.
We keep that form and make it small:

- the face is split into part tracks (hair, head, brows, eyes, mouth); each
  track has its own frames, so a moving mouth does not repeat the eyes;
- a part drawing that looks the same in consecutive frames is one longer
  `<set>`; a drawing that comes back later (the rest mouth, open eyes) is
  written once with one `<set>` per time it is shown;
- a track whose drawing never changes is written once, outside any frame;
- coordinates are the 0.1 px of render.geometry.

Frame i shows time i / fps. Times are written in whole milliseconds, each
`begin`/`dur` derived from the frame boundaries round(i * 1000 / fps), so the
intervals of one track tile the timeline with no gap and no overlap. The last
drawing of each track is frozen (`fill="freeze"`) so the face stays after the
end. SMIL starts at 0 when the document loads: animation.svg opened on its
own plays silently; the pages drive its clock from the audio (static/cartoonface.js).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from lxml import etree

from cartoonface.face.lift import lift
from cartoonface.face.model import CONTOUR_NAMES, FaceModel
from cartoonface.face.pose import pose_face
from cartoonface.face.state import FaceState
from cartoonface.render.scenery import Figure, background_layer, clothes_layer
from cartoonface.render.svg import face_defs, face_group

SVG = "http://www.w3.org/2000/svg"
XLINK = "http://www.w3.org/1999/xlink"
NSMAP = {None: SVG, "xlink": XLINK}
# Part tracks in drawing order; "hair" goes to the hair layer, the rest to the face layer.
TRACKS = ("hair", "head", "brows", "eyes", "mouth")
# Which track a drawn part belongs to, by the start of its name (class or id, see _part_name).
PART_PREFIXES = (("hair", "hair"), ("brow", "brows"), ("eye", "eyes"), ("lid", "eyes"), ("pupil", "eyes"),
                 ("iris", "eyes"), ("lash", "eyes"), ("mouth", "mouth"), ("lip", "mouth"), ("teeth", "mouth"),
                 ("tongue", "mouth"))
# Elements that only define something referenced by id: hoisted out of the frames into <defs>
# (inside a hidden frame a clip path's children would inherit visibility="hidden" and clip everything).
DEFINITIONS = frozenset(f"{{{SVG}}}{tag}" for tag in ("clipPath", "linearGradient", "radialGradient", "mask",
                                                       "pattern", "filter", "marker", "symbol"))
UID = "u"  # the one uid every state is drawn with; ids are then renamed by content
WIDE = 16 / 9  # the announcer's stage: a 16:9 picture with the face in the middle
_REFERENCE = re.compile(r"url\(#([^)]+)\)")


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
    """A SMIL clock value for `ms` milliseconds: 1234 -> '1.234s', 500 -> '0.5s', 0 -> '0s'."""
    seconds = f"{ms // 1000}.{ms % 1000:03d}".rstrip("0").rstrip(".")
    return f"{seconds}s"


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
    """Where the neck and shoulders go for `face` inside the picture `box`."""
    contour = np.array([face.point(name) for name in CONTOUR_NAMES])
    chin = face.point("2.1")
    return Figure(box=box, chin_x=float(chin[0]), chin_y=float(chin[1]),
                  face_width=float(np.ptp(contour[:, 0])), skin=face.palette.skin)


def _el(parent: etree._Element, tag: str, **attrs: str) -> etree._Element:
    """Append the SVG element `tag` with attributes `attrs` to `parent`."""
    return etree.SubElement(parent, f"{{{SVG}}}{tag}", {k.replace("_", "-"): v for k, v in attrs.items()})


def _part_name(element: etree._Element) -> str:
    """A drawn part's name: its class, else its id without the uid suffix, else ''."""
    name = element.get("class") or element.get("id") or ""
    return name.split()[0].removesuffix(f"-{UID}").removesuffix(f"_{UID}").removesuffix(UID) if name else ""


def track_of(element: etree._Element) -> str:
    """The track (one of TRACKS) a top-level part of a face group belongs to."""
    name = _part_name(element).lower()
    for prefix, track in PART_PREFIXES:
        if name.startswith(prefix):
            return track
    return "head"


class _Drawings:
    """Distinct part drawings of every track and the hoisted definitions they share."""

    def __init__(self, defs: etree._Element) -> None:
        self.defs = defs
        self.definition_ids: dict[bytes, str] = {}
        self.keys: dict[str, dict[bytes, int]] = {track: {} for track in TRACKS}
        self.parts: dict[str, list[list[etree._Element]]] = {track: [] for track in TRACKS}
        self.shapes: list[str] = []  # dominant mouth symbol of each mouth drawing

    def _hoist(self, definition: etree._Element) -> str:
        """Move `definition` to <defs> under an id named by its content (shared if seen before)."""
        definition.attrib.pop("id", None)
        content = etree.tostring(definition)
        new_id = self.definition_ids.get(content)
        if new_id is None:
            new_id = f"k{len(self.definition_ids)}"
            self.definition_ids[content] = new_id
            definition.set("id", new_id)
            self.defs.append(definition)
        return new_id

    def add(self, group: etree._Element, state: FaceState) -> dict[str, int]:
        """Split one drawn face `group` into tracks; return {track: drawing number}."""
        renamed: dict[str, str] = {}
        for definition in [e for e in group.iter() if e.tag in DEFINITIONS and e.get("id")]:
            old = definition.get("id")
            definition.getparent().remove(definition)
            renamed[old] = self._hoist(definition)
        by_track: dict[str, list[etree._Element]] = {track: [] for track in TRACKS}
        for part in group:
            if not isinstance(part.tag, str) or (part.tag == f"{{{SVG}}}defs" and len(part) == 0):
                continue
            for node in part.iter():
                node.attrib.pop("id", None)
                for name, value in node.attrib.items():
                    if "url(#" in value:
                        node.set(name, _REFERENCE.sub(lambda m: f"url(#{renamed.get(m.group(1), m.group(1))})", value))
                    elif name in ("href", f"{{{XLINK}}}href") and value[1:] in renamed:
                        node.set(name, f"#{renamed[value[1:]]}")
            by_track[track_of(part)].append(part)
        numbers = {}
        for track, parts in by_track.items():
            key = b"".join(etree.tostring(part) for part in parts)
            known = self.keys[track]
            if key not in known:
                known[key] = len(known)
                self.parts[track].append(parts)
                if track == "mouth":
                    self.shapes.append(max(state.mouth, key=lambda pair: pair[1])[0])
            numbers[track] = known[key]
        return numbers


def _track_group(parent: etree._Element, track: str, drawings: list[list[etree._Element]],
                 keys: Sequence[int], fps: int, shapes: Sequence[str]) -> None:
    """Write one track into `parent`: its drawing as is if it never changes, else one
    `<g visibility="hidden">` per distinct drawing with a `<set>` per run of frames showing it."""
    holder = _el(parent, "g", **{"data-part": track})
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
    defs = _el(root, "defs")
    for definition in face_defs(face):
        defs.append(definition)
    figure = figure_of(face, box)
    root.append(background_layer(background, figure, defs))
    drawings = _Drawings(defs)
    lifted = lift(face)
    seen: dict[FaceState, dict[str, int]] = {}
    keys: dict[str, list[int]] = {track: [] for track in TRACKS}
    for state in states:
        numbers = seen.get(state)
        if numbers is None:
            numbers = seen[state] = drawings.add(face_group(face, pose_face(lifted, state), UID), state)
        for track, number in numbers.items():
            keys[track].append(number)
    hair = _el(root, "g", id="hair")
    _track_group(hair, "hair", drawings.parts["hair"], keys["hair"], fps, drawings.shapes)
    dressed = clothes_layer(clothes, figure, defs)
    if dressed is not None:
        root.append(dressed)
    layer = _el(root, "g", id="face")
    for track in TRACKS[1:]:
        _track_group(layer, track, drawings.parts[track], keys[track], fps, drawings.shapes)
    return etree.tostring(root, xml_declaration=True, encoding="utf-8")
