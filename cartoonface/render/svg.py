"""A posed cartoon face as SVG, built with lxml (thesis 002, 6.3.1).

Layers, back to front (thesis 002, 6.3.1, Figs. 6.7/6.8): background, hair, clothes,
face. The hair is one corner-cut polygon behind the body; the face layer holds, in
order, the ears, the face, the cheeks, the nose, the eyebrows, the eyes and the mouth.

Each eye is its white, then the iris (radial gradient), pupil and highlight clipped by
the eye outline (thesis 002, 6.3.1, Fig. 6.5: "during eye blinks, the eyeball will be
hidden, an effect of clipping paths is utilized"): when the lids meet the clip path has
no area left and nothing of the eyeball shows. Then the outline and a bolder upper lid.

`face_defs(face)` gives the gradients once per document (ids "cf-..."); `face_group`
gives one state's drawing as a `<g>` whose children are the parts, each with a class
naming it ("hair", "ear-l", "face", "eye-l", "mouth", ...), and whose own clip paths carry
the caller's `uid` so many states can share one document (render/animation.py). Colours
are written as hex: cairosvg paints hsl() black (shared DEPENDENCIES.md).
"""

from __future__ import annotations

import functools
import io
import math

import numpy as np
import resvg_py
from lxml import etree
from PIL import Image

from cartoonface.face.lift import LIFTED_INDEX, lift
from cartoonface.face.model import FaceModel
from cartoonface.face.pose import PosedFace, pose_face
from cartoonface.face.state import FaceState
from cartoonface.face.mouth import shown_parts
from cartoonface.render.geometry import face_shapes, number_text
from cartoonface.render.mouth import ROWS as MOUTH_ROWS
from cartoonface.render.mouth import mouth_outlines, mouth_texts
from cartoonface.render.scenery import Figure, background_layer, clothes_layer

SVG = "http://www.w3.org/2000/svg"
NSMAP = {None: SVG}

# Line widths as fractions of the FAPU d (the distance between the eyeball centres), so a
# face of any size is drawn alike. Our own choice, tuned by eye on the sample faces.
OUTLINE = 0.022   # face, ears, eye outline
LID = 0.045       # upper lid (lash line)
LID_SHADOW = 0.09  # width of the lid's shadow on the eyeball (half of it falls inside the eye)
FEATURE = 0.02    # nose, the line between the lips
HAIR_LINE = 0.018
LOWER_TEETH_COLOUR = "#ece6e1"  # the lower teeth, in the upper ones' shade: a touch darker than white
PUPIL = 0.48      # pupil radius / iris radius
GLINT = 0.26      # highlight radius / iris radius
CHEEK = (0.2, 0.12)  # blush ellipse radii / d

# Eye outline points (thesis 002, Alg. 2.2 steps 9-10) by drawn eye.
EYES = {"l": ("3.12", "3.2", "3.8", "3.4"), "r": ("3.7", "3.1", "3.11", "3.3")}


def _mix(colour: str, other: str, t: float) -> str:
    """The hex colour `t` (0..1) of the way from `colour` to `other` (both '#rgb' or '#rrggbb')."""

    def rgb(hex_: str) -> np.ndarray:
        h = hex_.lstrip("#")
        h = "".join(c * 2 for c in h) if len(h) == 3 else h
        return np.array([int(h[i:i + 2], 16) for i in (0, 2, 4)], dtype=float)

    mixed = np.rint(rgb(colour) * (1 - t) + rgb(other) * t).astype(int)
    return "#" + "".join(f"{v:02x}" for v in mixed)


def _el(parent: etree._Element, tag: str, attrs: dict[str, str]) -> etree._Element:
    """Append SVG element `tag` with string attributes `attrs` to `parent`; return it."""
    return etree.SubElement(parent, f"{{{SVG}}}{tag}", attrs)


def _gradient(kind: str, gid: str, stops: tuple[tuple[float, str, float], ...], **attrs: str) -> etree._Element:
    """A linear/radial gradient `gid` with (offset, colour, opacity) stops."""
    grad = etree.Element(f"{{{SVG}}}{kind}Gradient", {"id": gid, **attrs})
    for offset, colour, opacity in stops:
        stop = _el(grad, "stop", {"offset": f"{offset:g}", "stop-color": colour})
        if opacity < 1:
            stop.set("stop-opacity", f"{opacity:g}")
    return grad


def face_defs(face: FaceModel) -> tuple[etree._Element, ...]:
    """The gradients every drawing of `face` uses, once per document: skin "cf-skin", hair
    "cf-hair", iris "cf-iris", lips "cf-lip", blush "cf-cheek", nose line "cf-nose" (each in the element's own
    bounding box, so they fit any pose). Returns the elements, to go into `<defs>`."""
    p = face.palette
    nose = _mix(p.skin_shadow, p.outline, 0.4)
    return (
        _gradient("radial", "cf-skin", ((0, _mix(p.skin, "#ffffff", 0.1), 1), (0.62, p.skin, 1),
                                        (1, _mix(p.skin, p.skin_shadow, 0.7), 1)),
                  cx=".5", cy=".42", r=".62", fy=".36"),
        # hair: a sheen on the crown, darker towards the ends
        _gradient("radial", "cf-hair", ((0, _mix(p.hair, "#ffffff", 0.22), 1), (0.4, p.hair, 1),
                                        (1, _mix(p.hair, "#000000", 0.3), 1)),
                  cx=".5", cy=".12", r=".9", fy=".04"),
        _gradient("radial", "cf-iris", ((0, _mix(p.iris, "#ffffff", 0.3), 1), (0.6, p.iris, 1),
                                        (1, _mix(p.iris, "#000000", 0.45), 1)), fy=".62"),
        _gradient("linear", "cf-lip", ((0, _mix(p.lip, "#000000", 0.08), 1), (0.45, p.lip, 1),
                                       (1, _mix(p.lip, "#ffffff", 0.12), 1)), x2="0", y2="1"),
        _gradient("radial", "cf-cheek", ((0, p.cheek, 0.55), (1, p.cheek, 0))),
        # The nose bridge fades out towards the eyes; the nostrils and tip are drawn fully.
        _gradient("linear", "cf-nose", ((0, nose, 0), (0.55, nose, 0.45), (0.8, nose, 1)), x2="0", y2="1"),
    )


@functools.lru_cache(maxsize=16)
def _styles(face: FaceModel) -> dict[str, dict[str, str]]:
    """The attributes every drawing of `face` repeats, by part (computed once per face)."""
    p, d = face.palette, face.fapu.d
    round_ = {"stroke-linecap": "round", "stroke-linejoin": "round"}
    line = {"fill": "none", "stroke": p.outline, **round_}
    skin = {**line, "fill": "url(#cf-skin)", "stroke-width": number_text(OUTLINE * d)}
    return {
        "hair": {"fill": "url(#cf-hair)", "stroke": _mix(p.hair, "#000000", 0.35),
                 "stroke-width": number_text(HAIR_LINE * d), "stroke-linejoin": "round"},
        "skin": skin,
        "nose": {**line, "stroke": "url(#cf-nose)", "stroke-width": number_text(FEATURE * d)},
        "brow": {"fill": p.brow, "stroke": p.brow, "stroke-width": number_text(0.006 * d), "stroke-linejoin": "round"},
        "cheek_ry": {"ry": number_text(CHEEK[1] * d)},
        "white": {"fill": p.eye_white},
        "eye_line": {**line, "stroke-width": number_text(OUTLINE * d * 0.8)},
        "lid": {**line, "stroke-width": number_text(LID * d)},
        # the upper lid's shadow on the eyeball, inside the eye clip
        "lid_shadow": {"fill": "none", "stroke": p.outline, "stroke-opacity": "0.18",
                       "stroke-width": number_text(LID_SHADOW * d)},
        "lips": {"fill": "url(#cf-lip)", "stroke": _mix(p.lip, p.outline, 0.4), "stroke-width": number_text(0.012 * d)},
        # the opening, outlined: the line where the lips meet when it is shut
        "opening": {"fill": p.mouth, "stroke": _mix(p.mouth, p.lip, 0.25),
                    "stroke-width": number_text(FEATURE * d * 0.8)},
        "gloss": {"fill": "#ffffff", "opacity": "0.22", "stroke": "none"},
        "tongue": {"fill": _mix(p.lip, p.mouth, 0.3)},
        "upper_teeth": {"fill": "none", "stroke": "#ffffff"},
        "lower_teeth": {"fill": "none", "stroke": LOWER_TEETH_COLOUR},
    }


# Rows of posed.xy read by the cheeks and the eyes: the eye outlines of "l" and "r", the mouth
# corners 8.4 and 8.3.
_ROWS = [LIFTED_INDEX[n] for n in EYES["l"] + EYES["r"] + ("8.4", "8.3")]


def face_group(face: FaceModel, posed: PosedFace, uid: str) -> etree._Element:
    """One state's drawing of `face` posed as `posed`, as a `<g class="cf-face">`.

    Children, in drawing order: a `<defs>` with this state's clip paths (ids end in
    "-{uid}"), then the parts "hair", "ear-l", "ear-r", "face", "cheeks", "nose",
    "brow-l", "brow-r", "eye-l", "eye-r", "mouth". Fills use face_defs' gradients.
    """
    style = _styles(face)
    shapes = face_shapes(posed)
    points = posed.xy[_ROWS].tolist()
    group = etree.Element(f"{{{SVG}}}g", {"class": "cf-face"})
    defs = _el(group, "defs", {})
    _el(group, "path", {"class": "hair", "d": shapes["hair"], **style["hair"]})
    for side in "lr":
        _el(group, "path", {"class": f"ear-{side}", "d": shapes[f"ear_{side}"], **style["skin"]})
    _el(group, "path", {"class": "face", "d": shapes["face"], **style["skin"]})
    _cheeks(group, points, face.fapu.d, style)
    _el(group, "path", {"class": "nose", "d": shapes["nose"], **style["nose"]})
    for side in "lr":
        _el(group, "path", {"class": f"brow-{side}", "d": shapes[f"brow_{side}"], **style["brow"]})
    for side, eyeball in zip("lr", _eyeballs(posed, points)):
        _eye(group, defs, shapes, side, eyeball, face, uid, style)
    _mouth(group, defs, posed, uid, style, face.fapu.d)
    return group


def _cheeks(group: etree._Element, points: list[list[float]], d: float, style: dict[str, dict[str, str]]) -> None:
    """Blush under each eye, between the eye's lower lid and the mouth corner on its side.
    `points`: the posed rows _ROWS as [x, y] lists."""
    cheeks = _el(group, "g", {"class": "cheeks", "fill": "url(#cf-cheek)"})
    for first, mouth_corner in ((0, points[8]), (4, points[9])):
        (ox, oy), _, (ix, iy), (_, lower_y) = points[first:first + 4]
        width = math.hypot(ox - ix, oy - iy) / (0.46 * d)  # foreshortening: narrower when turned away
        cy = 0.5 * lower_y + 0.5 * mouth_corner[1] - 0.08 * d
        _el(cheeks, "ellipse", {"cx": number_text(0.55 * ox + 0.45 * ix), "cy": number_text(cy),
                                "rx": number_text(CHEEK[0] * d * min(width, 1.2)), **style["cheek_ry"]})


def _eyeballs(posed: PosedFace, points: list[list[float]]) -> tuple[tuple[float, float, float], ...]:
    """(x, y, iris radius) for the eye drawn "l" and "r", each pupil paired with the eye whose
    outline centre (from `points`, the rows _ROWS) is nearest: PosedFace has its own order."""
    (x0, y0), (x1, y1) = posed.pupils.tolist()
    cx = sum(p[0] for p in points[:4]) / 4
    cy = sum(p[1] for p in points[:4]) / 4
    r0, r1 = (float(r) for r in posed.iris_r)
    if math.hypot(x0 - cx, y0 - cy) <= math.hypot(x1 - cx, y1 - cy):
        return (x0, y0, r0), (x1, y1, r1)
    return (x1, y1, r1), (x0, y0, r0)


def _eye(group: etree._Element, defs: etree._Element, shapes: dict[str, str], side: str,
         eyeball: tuple[float, float, float], face: FaceModel, uid: str, style: dict[str, dict[str, str]]) -> None:
    """Append eye `side`: white, clipped iris + pupil + the lid's shadow + highlight, outline,
    upper lid."""
    outline = shapes[f"eye_{side}"]
    clip_id = f"cf-eye-{side}-{uid}"
    _el(_el(defs, "clipPath", {"id": clip_id}), "path", {"d": outline})
    eye = _el(group, "g", {"class": f"eye-{side}"})
    _el(eye, "path", {"d": outline, **style["white"]})
    ball = _el(eye, "g", {"clip-path": f"url(#{clip_id})"})
    x, y, r = eyeball
    cx, cy = number_text(x), number_text(y)
    _el(ball, "circle", {"cx": cx, "cy": cy, "r": number_text(r), "fill": "url(#cf-iris)"})
    _el(ball, "circle", {"cx": cx, "cy": cy, "r": number_text(PUPIL * r), "fill": face.palette.pupil})
    _el(ball, "path", {"d": shapes[f"lid_{side}"], **style["lid_shadow"]})
    _el(ball, "circle", {"cx": number_text(x - 0.3 * r), "cy": number_text(y - 0.34 * r),
                         "r": number_text(GLINT * r), "fill": "#ffffff", "opacity": "0.9"})
    _el(eye, "path", {"d": outline, **style["eye_line"]})
    _el(eye, "path", {"d": shapes[f"lid_{side}"], **style["lid"]})


def _mouth(group: etree._Element, defs: etree._Element, posed: PosedFace, uid: str,
           style: dict[str, dict[str, str]], d: float) -> None:
    """Append the mouth (render/mouth.py): lips; the opening, its outline the line where the
    lips meet; the tongue and the lower and upper teeth clipped to it (when it is open by a
    pixel or more; each row when it shows a pixel or more); the upper teeth on the lower lip
    (f, clipped by the lips); a gloss on the lower lip. `d` is the FAPU d in pixels."""
    outlines = mouth_outlines(posed.xy[MOUTH_ROWS], posed.mouth @ shown_parts(), d)
    text = mouth_texts(outlines)
    mouth = _el(group, "g", {"class": "mouth", "stroke-linejoin": "round", "stroke-linecap": "round"})
    _el(mouth, "path", {"d": text["lips"], **style["lips"]})
    _el(mouth, "path", {"d": text["opening"], **style["opening"]})
    if text["tongue_ry"] != "0":  # open by a pixel or more (sizes are whole pixels)
        clip_id = f"cf-mouth-{uid}"
        _el(_el(defs, "clipPath", {"id": clip_id}), "path", {"d": text["opening"]})
        inside = _el(mouth, "g", {"clip-path": f"url(#{clip_id})"})
        _el(inside, "ellipse", {"cx": text["tongue_cx"], "cy": text["tongue_cy"], "rx": text["tongue_rx"],
                                "ry": text["tongue_ry"], **style["tongue"]})
        for row in ("lower", "upper"):
            if text[f"{row}_width"] != "0":
                _el(inside, "path", {"d": text[f"{row}_teeth"], **style[f"{row}_teeth"],
                                     "stroke-width": text[f"{row}_width"]})
    if text["bite_width"] != "0":
        lips_id = f"cf-lips-{uid}"
        _el(_el(defs, "clipPath", {"id": lips_id}), "path", {"d": text["lips"]})
        _el(_el(mouth, "g", {"clip-path": f"url(#{lips_id})"}), "path",
            {"d": text["bite"], **style["upper_teeth"], "stroke-width": text["bite_width"]})
    _el(mouth, "ellipse", {"cx": text["gloss_cx"], "cy": text["gloss_cy"], "rx": text["gloss_rx"],
                           "ry": text["gloss_ry"], **style["gloss"]})


def face_svg(face: FaceModel, state: FaceState, background: str = "plain", clothes: str = "shirt") -> etree._Element:
    """`face` in `state` as a whole SVG document root, canvas-sized, with the layers
    `<g id="background">`, `<g id="hair">`, `<g id="clothes">` and `<g id="face">` in that order.

    `background` / `clothes` name the scenery of render/scenery.py (OptionError if unknown).
    """
    width, height = float(face.width), float(face.height)
    root = etree.Element(f"{{{SVG}}}svg", {"width": f"{width:g}", "height": f"{height:g}",
                                            "viewBox": f"0 0 {width:g} {height:g}"}, nsmap=NSMAP)
    defs = _el(root, "defs", {})
    defs.extend(face_defs(face))
    chin = face.point("2.1")
    # the face width as render/animation.py measures it, so stills and animations match
    figure = Figure(box=(0.0, 0.0, width, height), chin_x=float(chin[0]), chin_y=float(chin[1]),
                    face_width=float(np.ptp(face.points[:, 0])), skin=face.palette.skin)
    root.append(background_layer(background, figure, defs))
    group = face_group(face, pose_face(lift(face), state), "0")
    hair = _el(root, "g", {"id": "hair"})
    hair.extend(group.findall(f"{{{SVG}}}path[@class='hair']"))
    dressed = clothes_layer(clothes, figure, defs)
    root.append(dressed if dressed is not None else etree.Element(f"{{{SVG}}}g", {"id": "clothes"}))
    group.set("id", "face")
    root.append(group)
    return root


def svg_bytes(root: etree._Element) -> bytes:
    """The document `root` as UTF-8 SVG bytes with an XML declaration."""
    return etree.tostring(root, xml_declaration=True, encoding="utf-8")


def svg_to_png(data: bytes, palette: bool = False) -> bytes:
    """Rasterise SVG bytes at their own size with resvg; returns PNG bytes (RGBA). With
    `palette`, the picture (drawn on an opaque background) is stored with a 256-colour
    palette instead: a third of the size, for large sheets."""
    png = bytes(resvg_py.svg_to_bytes(svg_string=data.decode("utf-8")))
    if not palette:
        return png
    with Image.open(io.BytesIO(png)) as image:
        out = io.BytesIO()
        image.convert("RGB").quantize(256).save(out, "PNG", optimize=True)
    return out.getvalue()


def _head_box(face: FaceModel) -> tuple[float, float, float, float]:
    """(x, y, width, height) around the hair and the head of `face`, with room for a head
    turned, tilted or rolled by 15 degrees."""
    points = np.concatenate([face.points, face.hair])
    low, high = points.min(axis=0), points.max(axis=0)
    margin = 0.55 * face.fapu.d
    return low[0] - margin, low[1] - margin, high[0] - low[0] + 2 * margin, high[1] - low[1] + 2 * margin


def _neck(face: FaceModel, bottom: float) -> etree._Element:
    """A plain neck under the chin down to `bottom` (the sheet's heads have no body): the
    width of render/scenery.py's neck, its top hidden behind the jaw in every pose."""
    chin = face.point("2.1")
    half = 0.22 * float(np.ptp(face.points[:, 0]))
    top = float(chin[1]) - 0.6 * face.fapu.d
    corners = ((chin[0] - half, bottom), (chin[0] - half, top), (chin[0] + half, top), (chin[0] + half, bottom))
    d = "M" + "L".join(f"{number_text(x)} {number_text(y)}" for x, y in corners)  # open: no line at the bottom
    return etree.Element(f"{{{SVG}}}path", {"class": "neck", "d": d, "fill": face.palette.skin,
                                             "stroke": face.palette.outline,
                                             "stroke-width": number_text(OUTLINE * face.fapu.d)})


def sheet_svg(face: FaceModel, rows: list[tuple[str, list[FaceState]]], columns: list[str],
              cell_width: float) -> etree._Element:
    """A contact sheet: a grid of heads (hair and face layers), one row per (label, states)
    of `rows` (a label may hold several lines, split at "\n"), each column headed by its label
    in `columns`, cells `cell_width` pixels wide. Returns the SVG root."""
    x0, y0, w, h = _head_box(face)
    scale = cell_width / w
    cell_height = h * scale
    font = max(11.0, cell_width * 0.12)
    gap = cell_width * 0.05
    longest = max(len(line) for label, _ in rows for line in label.split("\n"))
    left_margin, top_margin = font * (0.62 * longest + 1), font * 2
    pitch_x, pitch_y = cell_width + gap, cell_height + gap
    width = left_margin + len(columns) * pitch_x + gap
    height = top_margin + len(rows) * pitch_y + gap
    root = etree.Element(f"{{{SVG}}}svg", {"width": number_text(width), "height": number_text(height),
                                            "viewBox": f"0 0 {number_text(width)} {number_text(height)}"}, nsmap=NSMAP)
    _el(root, "defs", {}).extend(face_defs(face))
    _el(root, "rect", {"width": "100%", "height": "100%", "fill": "#ffffff"})
    text_style = {"font-family": "DejaVu Sans, sans-serif", "font-size": number_text(font), "fill": "#333333"}
    for j, label in enumerate(columns):
        _el(root, "text", {"x": number_text(left_margin + j * pitch_x + cell_width / 2),
                           "y": number_text(font * 1.4), "text-anchor": "middle", **text_style}).text = label
    lifted = lift(face)
    neck = _neck(face, y0 + h)
    for i, (label, states) in enumerate(rows):
        top = top_margin + i * pitch_y
        lines = label.split("\n")
        caption = _el(root, "text", {"text-anchor": "end", **text_style})
        for k, line in enumerate(lines):
            _el(caption, "tspan", {"x": number_text(left_margin - gap * 2),
                                   "y": number_text(top + cell_height / 2 + font * (1.25 * k - 0.6 * len(lines) + 1))
                                   }).text = line
        for j, state in enumerate(states):
            left = left_margin + j * pitch_x
            _el(root, "rect", {"x": number_text(left), "y": number_text(top), "width": number_text(cell_width),
                               "height": number_text(cell_height), "rx": number_text(cell_width * 0.04),
                               "fill": "#f1ede6"})
            head = face_group(face, pose_face(lifted, state), f"s{i}-{j}")
            head.insert(2, etree.fromstring(etree.tostring(neck)))  # after the <defs> and the hair
            head.set("transform", f"translate({number_text(left - x0 * scale)} {number_text(top - y0 * scale)}) "
                                  f"scale({scale:.5g})")
            root.append(head)
    return root


def diagram_svg(face: FaceModel, scale: float = 3.0) -> etree._Element:
    """The labelled point diagram of `face` (docs/face-model.md): the frontal drawing faded,
    every model point (black), additional point A..S (red, thesis 002 Alg. 2.1) and hair
    point (blue, numbered from 0) with its name; points at the same place share a label.
    Labels are placed greedily where they overlap no other label or point, with a leader
    line when pushed away. The picture shows the head `scale` times its model size.
    Returns the SVG root."""
    from cartoonface.face.lift import LIFTED_NAMES
    from cartoonface.face.model import POINT_NAMES

    posed = pose_face(lift(face), FaceState())
    font, dot = 0.042 * face.fapu.d, 0.011 * face.fapu.d
    groups: dict[tuple[float, float], list[str]] = {}
    colour: dict[tuple[float, float], str] = {}
    named = [(n, xy, "#000000" if n in POINT_NAMES else "#c62828") for n, xy in zip(LIFTED_NAMES, posed.xy)]
    named += [(str(i), xy, "#1565c0") for i, xy in enumerate(posed.hair)]
    for name, xy, ink in named:
        key = (round(float(xy[0]), 1), round(float(xy[1]), 1))
        groups.setdefault(key, []).append(name)
        colour.setdefault(key, ink)
    x0, y0, w, h = _head_box(face)
    x0, y0, w, h = x0 - 4 * font, y0 - 2 * font, w + 8 * font, h + 4 * font
    root = etree.Element(f"{{{SVG}}}svg", {"width": number_text(w * scale), "height": number_text(h * scale),
                                            "viewBox": " ".join(number_text(v) for v in (x0, y0, w, h))},
                         nsmap=NSMAP)
    _el(root, "defs", {}).extend(face_defs(face))
    _el(root, "rect", {"x": number_text(x0), "y": number_text(y0), "width": "100%", "height": "100%",
                       "fill": "#ffffff"})
    drawing = face_group(face, posed, "d")
    drawing.set("opacity", "0.35")
    root.append(drawing)
    marks = _el(root, "g", {"font-family": "DejaVu Sans, sans-serif", "font-size": number_text(font)})
    taken = [(x - dot, y - dot, x + dot, y + dot) for x, y in groups]
    centre = posed.xy.mean(axis=0)
    for (x, y), names in groups.items():
        text = "/".join(names)
        box, anchor, (tx, ty) = _place_label(text, np.array([x, y]), centre, font, taken)
        taken.append(box)
        if np.hypot(tx - x, ty + 0.35 * font - y) > 1.6 * font:
            _el(marks, "line", {"x1": number_text(x), "y1": number_text(y), "x2": number_text(tx),
                                "y2": number_text(ty - 0.35 * font), "stroke": colour[(x, y)],
                                "stroke-width": number_text(dot * 0.25), "opacity": "0.6"})
        _el(marks, "circle", {"cx": number_text(x), "cy": number_text(y), "r": number_text(dot),
                              "fill": colour[(x, y)]})
        _el(marks, "text", {"x": number_text(tx), "y": number_text(ty), "text-anchor": anchor,
                            "fill": colour[(x, y)]}).text = text
    return root


def _place_label(text: str, at: np.ndarray, centre: np.ndarray, font: float,
                 taken: list[tuple[float, float, float, float]]) -> tuple[tuple[float, float, float, float], str,
                                                                          tuple[float, float]]:
    """Where the label `text` of the point `at` goes: the first candidate position (directions
    starting away from `centre`, growing distances) whose box overlaps none of `taken`.
    Returns (box (x1, y1, x2, y2), text-anchor, baseline position)."""
    width, height = 0.62 * font * len(text), font
    away = np.degrees(np.arctan2(*(at - centre)[::-1]))
    for distance in (1.0, 1.8, 2.8, 4.0, 5.5, 7.5):
        for turn in (0, 30, -30, 60, -60, 90, -90, 135, -135, 180):
            angle = np.radians(away + turn)
            ux, uy = np.cos(angle), np.sin(angle)
            cx, cy = at[0] + ux * distance * font, at[1] + uy * distance * font
            left = cx if ux > 0.3 else cx - width if ux < -0.3 else cx - width / 2
            box = (left, cy - height / 2, left + width, cy + height / 2)
            if not any(box[0] < b[2] and b[0] < box[2] and box[1] < b[3] and b[1] < box[3] for b in taken):
                anchor = "start" if ux > 0.3 else "end" if ux < -0.3 else "middle"
                return box, anchor, (cx, cy + 0.35 * font)
    return box, anchor, (cx, cy + 0.35 * font)
