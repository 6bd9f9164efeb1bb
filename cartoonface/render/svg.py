"""A posed cartoon face as SVG, built with lxml (thesis 002, 6.3.1).

Layers, back to front (thesis 002, 6.3.1, Figs. 6.7/6.8): background, hair, clothes,
face. The hair layer is the hair's back layer, one corner-cut polygon behind the body;
the face layer holds, in order, the ears, the face, the hair's front layer (the crown
and a fringe over the forehead, face/lift.py), the cheeks, the nose, the eyebrows, the
eyes and the mouth.

Each eye is its white, then the iris (radial gradient), pupil and highlight clipped by
the eye outline (thesis 002, 6.3.1, Fig. 6.5: "during eye blinks, the eyeball will be
hidden, an effect of clipping paths is utilized"): when the lids meet the clip path has
no area left and nothing of the eyeball shows. Then the outline and a bolder upper lid.

`face_defs(face)` gives the gradients once per document (ids "cf-..."); `face_group`
gives one state's drawing as a `<g>` whose children are the parts, each with a class
naming it ("hair", "ear-l", "face", "eye-l", "mouth", ...), and whose own clip paths carry
the caller's `uid` so many states can share one document (render/animation.py). Colours
are written as hex (#rrggbb), the form `_mix` reads and every renderer paints alike
(docs/drawing.md). The contact sheet, the point diagram and PNG output are in
render/sheet.py, render/diagram.py and render/png.py.
"""

from __future__ import annotations

import functools
import operator
import re
from collections.abc import Callable, Hashable, Sequence
from typing import TypeVar

import numpy as np
from lxml import etree

from cartoonface.face.lift import LIFTED_INDEX, lift
from cartoonface.face.model import FaceModel
from cartoonface.face.pose import PosedFace, PosedFaces, pose_face
from cartoonface.face.state import FaceState
from cartoonface.face.mouth import shown_parts
from cartoonface.render.compact import Form, Formed, form_of
from cartoonface.render.elements import SVG, Part, attributes_text, element, svg_root
from cartoonface.render.geometry import all_face_shape_columns, hypots
from cartoonface.render.mouth import ROWS as MOUTH_ROWS
from cartoonface.render.mouth import TEXTS as MOUTH_TEXTS
from cartoonface.render.mouth import drawn_mouth_texts
from cartoonface.render.numbers import fill, number_text, number_texts
from cartoonface.render.scenery import (COLOURS, JAW_SHADOW_OPACITY, background_layer, chin_shadows, clothes_layer,
                                        Figure, desk_layer, figure_of, lean, lean_transform, neck_middle)


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
BROW_LINE = 0.006  # the eyebrow's outline, which rounds its corner-cut polygon
EYE_LINE = 0.8    # the eye outline's width / OUTLINE
# Shades and opacities, our own choice like the widths.
HAIR_LINE_SHADE = 0.35   # the hair's outline: its colour this far towards black
LID_SHADOW_OPACITY = "0.18"
# The blush (_cheeks), in d: an eye this wide (corner to corner) seen
# frontally gives the full CHEEK[0] width; a wider-looking eye widens it up to CHEEK_STRETCH times.
CHEEK_EYE_WIDTH = 0.46
CHEEK_STRETCH = 1.2
# the blush centre's x: these weights of the outer and the inner eye corner
CHEEK_OUTER, CHEEK_INNER = 0.55, 0.45
CHEEK_LIFT = 0.08   # the blush centre above the midpoint of the lower lid and the mouth corner
# The highlight on the iris: its centre left and up of the iris centre by these fractions
# of the iris radius (the light comes from the upper left), and its opacity.
GLINT_LEFT = 0.3
GLINT_UP = 0.34
GLINT_OPACITY = "0.9"

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


def _gradient(kind: str, gid: str, stops: tuple[tuple[float, str, float], ...], **attrs: str) -> etree._Element:
    """A linear/radial gradient `gid` with (offset, colour, opacity) stops."""
    grad = element(None, f"{kind}Gradient", {"id": gid, **attrs})
    for offset, colour, opacity in stops:
        stop = element(grad, "stop", {"offset": f"{offset:g}", "stop-color": colour})
        if opacity < 1:
            stop.set("stop-opacity", f"{opacity:g}")
    return grad


def face_defs(face: FaceModel) -> tuple[etree._Element, ...]:
    """The gradients every drawing of `face` uses, once per document: skin "cf-skin", hair
    "cf-hair", the hair's front layer "cf-fringe", iris "cf-iris", lips "cf-lip", blush "cf-cheek", nose line "cf-nose" (each in the element's own
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
        # the hair's front layer: the same sheen on the crown, the plain hair colour towards its
        # edges, which is the back layer's colour where they meet, so no seam shows
        _gradient("radial", "cf-fringe", ((0, _mix(p.hair, "#ffffff", 0.22), 1), (0.55, p.hair, 1), (1, p.hair, 1)),
                  cx=".5", cy=".1", r=".95", fy=".02"),
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
        "hair": {"fill": "url(#cf-hair)", "stroke": _mix(p.hair, "#000000", HAIR_LINE_SHADE),
                 "stroke-width": number_text(HAIR_LINE * d), "stroke-linejoin": "round"},
        # unstroked: its crown lies on the back layer's outline, its sides inside the hair
        "fringe": {"fill": "url(#cf-fringe)"},
        "skin": skin,
        "nose": {**line, "stroke": "url(#cf-nose)", "stroke-width": number_text(FEATURE * d)},
        "brow": {"fill": p.brow, "stroke": p.brow, "stroke-width": number_text(BROW_LINE * d),
                 "stroke-linejoin": "round"},
        "cheek_ry": {"ry": number_text(CHEEK[1] * d)},
        "white": {"fill": p.eye_white},
        "eye_line": {**line, "stroke-width": number_text(OUTLINE * d * EYE_LINE)},
        "lid": {**line, "stroke-width": number_text(LID * d)},
        # the upper lid's shadow on the eyeball, inside the eye clip
        "lid_shadow": {"fill": "none", "stroke": p.outline, "stroke-opacity": LID_SHADOW_OPACITY,
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


@functools.lru_cache(maxsize=16)
def _style_texts(face: FaceModel) -> dict[str, str]:
    """_styles(face) as attribute texts (elements.attributes_text), and the pupil's fill."""
    texts = {part: attributes_text(attrs) for part, attrs in _styles(face).items()}
    texts["pupil"] = attributes_text({"fill": face.palette.pupil})
    return texts


@functools.lru_cache(maxsize=16)
def _canvas_figure(face: FaceModel) -> Figure:
    """render/scenery.py's Figure of `face` on its own canvas (0, 0, width, height): the body
    face_parts' chin shadow sits on, made once per face instead of once per state."""
    return figure_of(face, (0.0, 0.0, float(face.width), float(face.height)))


# Rows of posed.xy read by the cheeks and the eyes: the eye outlines of "l" and "r", the mouth
# corners 8.4 and 8.3.
_ROWS = [LIFTED_INDEX[n] for n in EYES["l"] + EYES["r"] + ("8.4", "8.3")]
# The chin shadow's paint, after the outline render/scenery.py's chin_shadow gives.
# Numbers face_parts writes per state for the cheeks (_cheek_numbers) and for each eye (_eye_numbers).
_CHEEK_COUNT, _EYE_COUNT = 6, 7
_Key = TypeVar("_Key", bound=Hashable)  # what _once draws a part from
_CHIN_SHADOW = attributes_text({"class": "chin-shadow", "fill": COLOURS["jaw shadow"], "opacity": JAW_SHADOW_OPACITY})


def face_parts(face: FaceModel, posed: PosedFace, uid: str, neck_lean: float = 0.0) -> tuple[Part, ...]:
    """One state's drawing of `face` posed as `posed`, over a neck leaned by `neck_lean` degrees
    (render/scenery.py's lean; 0 for an upright one), as the texts of its parts (elements.Part),
    in drawing order: "hair" (the back layer), "ear-l", "ear-r", "chin-shadow" (the jaw's shadow
    on the neck, under the posed chin: render/scenery.py's chin_shadow), "face", "fringe" (the
    hair's front layer, over the forehead), "cheeks", "nose", "brow-l", "brow-r", "eye-l",
    "eye-r", "mouth". Their clip paths' ids end in "-{uid}" (`uid`: letters, digits, "-").
    Fills use face_defs' gradients. all_face_parts of the one state.
    """
    return all_face_parts(face, PosedFaces.stack([posed]), uid, neck_lean)[0]


def all_face_parts(face: FaceModel, posed: PosedFaces, uid: str, neck_lean: float = 0.0,
                   tenths: dict[str, np.ndarray] | None = None,
                   forms: dict[Part, Formed] | None = None) -> list[tuple[Part, ...]]:
    """face_parts of S states at once (`posed`: face/pose.py's PosedFaces): the path data of all
    of them by geometry's all_face_shape_columns, the cheeks' and eyes' numbers of all of them as
    arrays written by one number_texts, the mouths by render/mouth.py's drawn_mouth_texts; each
    part drawn once per batch (_once, _drawn_once), part by part, and the states' drawings
    zipped from those columns. Written as text: the hot path of render/animation.py. `tenths`,
    when given, gets the numbers of the path data of geometry's shapes, the mouths and the chin shadows as written (render/pathdata.py's
    Tenths: what compacting them would read again). `forms`, when given, gets the Form and slots
    (render/compact.py's Formed) of each part drawn but the uncut chin shadows: its path data, positions and
    sizes, for compacting without cutting its text apart again (compact.drawn_parts)."""
    style, made = _style_texts(face), _forms(face, uid)
    shapes = all_face_shape_columns(posed)
    figure, chins = _canvas_figure(face), posed.xy[:, LIFTED_INDEX["2.1"]]
    points = posed.xy[:, _ROWS]
    eyes = _eyeballs(posed.pupils, posed.iris_r, points)
    texts = number_texts(np.concatenate([_cheek_numbers(points, face.fapu.d), _eye_numbers(eyes)], axis=1))
    per_state = _CHEEK_COUNT + 2 * _EYE_COUNT
    # each mouth's mix of shapes @ the table of what they show, (S, 1, 12) @ (12, 4) as one state's
    shown = (posed.mouth[:, None, :] @ shown_parts())[:, 0]
    mouths, mouth_of = drawn_mouth_texts(posed.xy[:, MOUTH_ROWS], shown, face.fapu.d, tenths)
    shadows = chin_shadows(figure, chins, np.asarray(neck_middle(figure, neck_lean, chins[:, 1])), _CHIN_SHADOW, tenths)
    paths = {name: _drawn_once([_formed(_path_part(name, d, style[kind]), made[name], (d,), forms) for d in shapes[shape][0]],
                               shapes[shape][2])
             for name, (shape, kind) in _PATHS.items()}
    if tenths is not None:
        for written, rows, _ in shapes.values():
            tenths.update(zip(written, rows, strict=True))
    # each state's numbers (CHEEK_COUNT, then EYE_COUNT per eye) as columns: number j of every state
    numbers = [texts[j::per_state] for j in range(per_state)]
    eye_parts = []
    for side, first in (("l", _CHEEK_COUNT), ("r", _CHEEK_COUNT + _EYE_COUNT)):
        (outlines, _, outline_of), (lids, _, lid_of) = shapes[f"eye_{side}"], shapes[f"lid_{side}"]
        keys = zip([side] * len(outline_of), [outlines[number] for number in outline_of],
                   [lids[number] for number in lid_of], *numbers[first:first + _EYE_COUNT], strict=True)
        eye_parts.append(_once(list(keys), lambda key: _formed(_eye(key[0], key[1], key[2], key[3:], uid, style),
                                                               made[f"eye-{key[0]}"], key[1:], forms)))
    cheeks = _once(list(zip(*numbers[:_CHEEK_COUNT], strict=True)),
                   lambda key: _formed(Part("cheeks", _cheeks(key, style)), made["cheeks"], key, forms))
    return list(zip(paths["hair"], paths["ear-l"], paths["ear-r"],
                    _once(shadows, lambda text: _chin_shadow(text, made["chin-shadow"], forms)),
                    paths["face"], paths["fringe"], cheeks, paths["nose"], paths["brow-l"], paths["brow-r"],
                    *eye_parts, _drawn_once([_mouth_part(face, uid, mouth, forms) for mouth in mouths], mouth_of),
                    strict=True))


# The parts drawn as one path of geometry's face_shapes: their class, by the face_shapes name,
# and their style (_styles).
_PATHS = {"hair": ("hair", "hair"), "ear-l": ("ear_l", "skin"), "ear-r": ("ear_r", "skin"), "face": ("face", "skin"),
          "fringe": ("fringe", "fringe"), "nose": ("nose", "nose"), "brow-l": ("brow_l", "brow"),
          "brow-r": ("brow_r", "brow")}


def _path_part(name: str, d: str, style: str) -> Part:
    """The part `name` (one of _PATHS): the path data `d` with the `style` text."""
    return Part(name, f'<path class="{name}" d="{d}"{style}/>')


@functools.lru_cache(maxsize=16)
def _forms(face: FaceModel, uid: str) -> dict[str, Form]:
    """The Form (render/compact.py's form_of) of each part all_face_parts draws of `face` with
    clip ids ending in `uid`, by name, but the mouth's (_mouth_kind): the path parts (_PATHS, slot:
    the path data), the eyes (_eye's outline, lid and texts), the cheeks (_cheeks' texts) and a cut
    chin shadow (_chin_shadow: its path data)."""
    style = _style_texts(face)
    forms = {name: form_of(functools.partial(_slot_path_part, name, style[kind]), 1) for name, (_, kind) in _PATHS.items()}
    for side in EYES:
        forms[f"eye-{side}"] = form_of(functools.partial(_slot_eye, side, uid, style), 2 + _EYE_COUNT)
    forms["cheeks"] = form_of(lambda slots: Part("cheeks", _cheeks(slots, style)), _CHEEK_COUNT)
    forms["chin-shadow"] = form_of(lambda slots: Part("chin-shadow", _SHADOW_HEAD + slots[0] + _SHADOW_TAIL), 1)
    return forms


# A cut chin shadow's text as render/scenery.py's chin_shadows writes it with the paint _CHIN_SHADOW:
# its path data between these two.
_SHADOW_HEAD, _SHADOW_TAIL = '<path d="', f'"{_CHIN_SHADOW}/>'


def _chin_shadow(text: str, form: Form, forms: dict[Part, Formed] | None) -> Part:
    """The chin shadow `text` (render/scenery.py's chin_shadows') as a part; a cut one (a path) put
    into `forms` (when given) with its `form` and its path data, read off between the two ends its
    text always has (an ellipse's text is cut by compact.drawn_parts)."""
    part = Part("chin-shadow", text)
    if text.startswith(_SHADOW_HEAD) and text.endswith(_SHADOW_TAIL):
        d = text[len(_SHADOW_HEAD):-len(_SHADOW_TAIL)]
        if '"' not in d:  # the path data alone
            _formed(part, form, (d,), forms)
    return part


def _slot_path_part(name: str, style: str, slots: Sequence[str]) -> Part:
    """_path_part from its slot (form_of's)."""
    return _path_part(name, slots[0], style)


def _slot_eye(side: str, uid: str, style: dict[str, str], slots: Sequence[str]) -> Part:
    """_eye from its slots (form_of's): the outline, the lid, then _eye's texts."""
    return _eye(side, slots[0], slots[1], slots[2:], uid, style)


# The mouth's texts that _mouth writes into what its skeleton keeps (render/compact.py: stroke widths)
# or reads (whether a piece is drawn): its Forms and templates differ by them. Their places in MOUTH_TEXTS.
_KEPT = tuple(MOUTH_TEXTS.index(name) for name in ("tongue_ry", "lower_width", "upper_width", "bite_width"))


def _mouth_part(face: FaceModel, uid: str, texts: tuple[str, ...], forms: dict[Part, Formed] | None) -> Part:
    """_mouth's part of the mouth `texts` (render/mouth.py's, in its TEXTS order), filled into the
    templates of its kind (_mouth_kind), put into `forms` (when given) with its Form and the texts."""
    form, text, clips = _mouth_kind(face, uid, texts[_KEPT[0]] == "0", _KEPT_WIDTHS(texts))
    return _formed(Part("mouth", text(texts), tuple(clip(texts) for clip in clips)), form, texts, forms)


_KEPT_WIDTHS = operator.itemgetter(*_KEPT[1:])
_Filled = Callable[[Sequence[str]], str]  # a text written from a mouth's texts (_filled)


@functools.lru_cache(maxsize=1024)
def _mouth_kind(face: FaceModel, uid: str, shut: bool, widths: tuple[str, ...]) -> tuple[Form, _Filled, tuple[_Filled, ...]]:
    """The mouths with no tongue drawn (`shut`) or one and the `widths` of _KEPT[1:] (whole pixels: a
    few dozen kinds), which _mouth draws alike from their other texts: their Form (render/compact.py's
    form_of; slots: the texts in MOUTH_TEXTS order), and _mouth's text and clips as functions of the
    texts (_filled: one join a text instead of _mouth's pieces), made once."""
    fixed = dict(zip(_KEPT[1:], widths, strict=True))
    if shut:
        fixed[_KEPT[0]] = "0"
    style = _style_texts(face)

    def draw(slots: Sequence[str]) -> Part:
        return _mouth(dict(zip(MOUTH_TEXTS, [fixed.get(place, slot) for place, slot in enumerate(slots)], strict=True)),
                      uid, style)

    part = draw([f"{_MARK}{place}{_MARK}" for place in range(len(MOUTH_TEXTS))])
    return form_of(draw, len(MOUTH_TEXTS)), _filled(part.text), tuple(map(_filled, part.clips))


_MARK = "\x00"  # around a text's place where _mouth_kind draws a mouth: in no text _mouth writes
_MARKED = re.compile(f"{_MARK}(\\d+){_MARK}")


def _filled(marked: str) -> _Filled:
    """The text `marked` (_mouth_kind's: the places of the texts marked) as a function of the
    texts: its pieces between the marks joined with the texts they mark (numbers.fill)."""
    cut = _MARKED.split(marked)
    frame = tuple(text if index % 2 == 0 else "" for index, text in enumerate(cut))
    places = [int(place) for place in cut[1::2]]
    if len(places) == 1:  # itemgetter of one place gives the text, not a tuple
        return lambda texts: fill(frame, (texts[places[0]],))
    taken = operator.itemgetter(*places)
    return lambda texts: fill(frame, taken(texts))


def _formed(part: Part, form: Form, slots: tuple[str, ...], forms: dict[Part, Formed] | None) -> Part:
    """`part`, put into `forms` (when given) with its `form` and the `slots` it was drawn from."""
    if forms is not None:
        forms[part] = (form, slots)
    return part


def _drawn_once(made: list[Part], which: list[int]) -> list[Part]:
    """The part of each state, `made` holding the distinct ones drawn once and `which` (per state)
    the number of its own among them (a part drawn again is the same object)."""
    return [made[number] for number in which]


def _once(keys: Sequence[_Key], draw: Callable[[_Key], Part]) -> list[Part]:
    """The part `draw(key)` of each of `keys` (hashable: the texts it is drawn from), each
    distinct key drawn once (a part drawn again is the same object, its text written once)."""
    made: dict[_Key, Part] = {}
    return [made.get(key) or made.setdefault(key, draw(key)) for key in keys]


def face_group(face: FaceModel, posed: PosedFace, uid: str, neck_lean: float = 0.0) -> etree._Element:
    """One state's drawing of `face` posed as `posed`, as a `<g class="cf-face">`, over a neck
    leaned by `neck_lean` degrees (render/scenery.py's lean; 0 for an upright one).

    Children, in drawing order: a `<defs>` with this state's clip paths (ids end in
    "-{uid}"), then the parts of face_parts (by class: "hair", "ear-l", "ear-r",
    "chin-shadow", "face", "fringe", "cheeks", "nose", "brow-l", "brow-r", "eye-l", "eye-r",
    "mouth").
    """
    parts = face_parts(face, posed, uid, neck_lean)
    clips = "".join(clip for part in parts for clip in part.clips)
    group = etree.fromstring(f'<g xmlns="{SVG}" class="cf-face"><defs>{clips}</defs>'
                             + "".join(part.text for part in parts) + "</g>")
    return group


def _cheek_numbers(points: np.ndarray, d: float) -> np.ndarray:
    """Blush under each eye, between the eye's lower lid and the mouth corner on its side: the
    centre x, y and the horizontal radius of the left's ellipse and the right's, (S, 6) pixels.
    `points`: (S, 10, 2) the posed rows _ROWS of S states; `d` the FAPU d in pixels."""
    eyes = points[:, :8].reshape(-1, 2, 4, 2)  # (S, eye, outline point, xy)
    (ox, oy), (ix, iy), lower_y = eyes[:, :, 0].transpose(2, 0, 1), eyes[:, :, 2].transpose(2, 0, 1), eyes[:, :, 3, 1]
    width = hypots(ox - ix, oy - iy) / (CHEEK_EYE_WIDTH * d)  # foreshortening: narrower when turned away
    cy = 0.5 * lower_y + 0.5 * points[:, 8:, 1] - CHEEK_LIFT * d
    return np.stack([CHEEK_OUTER * ox + CHEEK_INNER * ix, cy, CHEEK[0] * d * np.minimum(width, CHEEK_STRETCH)],
                    axis=2).reshape(-1, 6)


def _cheeks(texts: Sequence[str], style: dict[str, str]) -> str:
    """The text of the cheeks' `<g class="cheeks">` from the number `texts` of _cheek_numbers."""
    ellipses = "".join(f'<ellipse cx="{cx}" cy="{cy}" rx="{rx}"{style["cheek_ry"]}/>'
                       for cx, cy, rx in (texts[:3], texts[3:6]))
    return f'<g class="cheeks" fill="url(#cf-cheek)">{ellipses}</g>'


def _eyeballs(pupils: np.ndarray, radii: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(S, 2, 3): (x, y, iris radius) for the eye drawn "l" and "r" of S states, each pupil of
    `pupils` (S, 2, 2: PosedFaces.pupils, iris radii `radii` (2,)) paired with the eye whose
    outline centre (from `points` (S, 10, 2), the rows _ROWS) is nearest: PosedFace has its own order."""
    left = points[:, :4]
    cx = (left[:, 0, 0] + left[:, 1, 0] + left[:, 2, 0] + left[:, 3, 0]) / 4
    cy = (left[:, 0, 1] + left[:, 1, 1] + left[:, 2, 1] + left[:, 3, 1]) / 4
    near = hypots(pupils[:, :, 0] - cx[:, None], pupils[:, :, 1] - cy[:, None])
    eyeballs = np.concatenate([pupils, np.broadcast_to(np.asarray(radii, dtype=float)[:, None], pupils[..., :1].shape)],
                              axis=2)
    return np.where((near[:, 0] <= near[:, 1])[:, None, None], eyeballs, eyeballs[:, ::-1])


def _eye_numbers(eyeballs: np.ndarray) -> np.ndarray:
    """The eyeballs' (S, 2, 3) (x, y, iris radius) pixels and what _eye draws of them: pupil radius,
    the highlight's centre x, y and radius; (S, 14) pixels, 7 an eye."""
    x, y, r = eyeballs.transpose(2, 0, 1)
    return np.stack([x, y, r, PUPIL * r, x - GLINT_LEFT * r, y - GLINT_UP * r, GLINT * r], axis=2).reshape(-1, 14)


def _eye(side: str, outline: str, lid: str, texts: Sequence[str], uid: str, style: dict[str, str]) -> Part:
    """Eye `side`: white, clipped iris + pupil + the lid's shadow + highlight, outline, upper
    lid; its clip path the eye `outline` (path data, as the `lid`'s). `texts`: the numbers of
    _eye_numbers as text."""
    clip_id = f"cf-eye-{side}-{uid}"
    cx, cy, r, pupil, glint_x, glint_y, glint = texts
    text = (f'<g class="eye-{side}"><path d="{outline}"{style["white"]}/><g clip-path="url(#{clip_id})">'
            f'<circle cx="{cx}" cy="{cy}" r="{r}" fill="url(#cf-iris)"/>'
            f'<circle cx="{cx}" cy="{cy}" r="{pupil}"{style["pupil"]}/>'
            f'<path d="{lid}"{style["lid_shadow"]}/>'
            f'<circle cx="{glint_x}" cy="{glint_y}" r="{glint}" fill="#ffffff" opacity="{GLINT_OPACITY}"/></g>'
            f'<path d="{outline}"{style["eye_line"]}/><path d="{lid}"{style["lid"]}/></g>')
    return Part(f"eye-{side}", text, (f'<clipPath id="{clip_id}"><path d="{outline}"/></clipPath>',))


def _mouth(text: dict[str, str], uid: str, style: dict[str, str]) -> Part:
    """The mouth (render/mouth.py's texts `text`): lips; the opening, its outline the line where the
    lips meet; the tongue and the lower and upper teeth clipped to it (when it is open by a
    pixel or more; each row when it shows a pixel or more); the upper teeth on the lower lip
    (f, clipped by the lips); a gloss on the lower lip."""
    pieces = ['<g class="mouth" stroke-linejoin="round" stroke-linecap="round">',
              f'<path d="{text["lips"]}"{style["lips"]}/>', f'<path d="{text["opening"]}"{style["opening"]}/>']
    clips = []
    if text["tongue_ry"] != "0":  # open by a pixel or more (sizes are whole pixels)
        clip_id = f"cf-mouth-{uid}"
        clips.append(f'<clipPath id="{clip_id}"><path d="{text["opening"]}"/></clipPath>')
        pieces += [f'<g clip-path="url(#{clip_id})">',
                   f'<ellipse cx="{text["tongue_cx"]}" cy="{text["tongue_cy"]}" rx="{text["tongue_rx"]}" '
                   f'ry="{text["tongue_ry"]}"{style["tongue"]}/>']
        pieces += [f'<path d="{text[f"{row}_teeth"]}"{style[f"{row}_teeth"]} stroke-width="{text[f"{row}_width"]}"/>'
                   for row in ("lower", "upper") if text[f"{row}_width"] != "0"]
        pieces.append("</g>")
    if text["bite_width"] != "0":
        lips_id = f"cf-lips-{uid}"
        clips.append(f'<clipPath id="{lips_id}"><path d="{text["lips"]}"/></clipPath>')
        pieces.append(f'<g clip-path="url(#{lips_id})"><path d="{text["bite"]}"{style["upper_teeth"]} '
                      f'stroke-width="{text["bite_width"]}"/></g>')
    pieces += [f'<ellipse cx="{text["gloss_cx"]}" cy="{text["gloss_cy"]}" rx="{text["gloss_rx"]}" '
               f'ry="{text["gloss_ry"]}"{style["gloss"]}/>', "</g>"]
    return Part("mouth", "".join(pieces), tuple(clips))


def face_svg(face: FaceModel, state: FaceState, background: str = "plain", clothes: str = "shirt") -> etree._Element:
    """`face` in `state` as a whole SVG document root, canvas-sized, with the layers
    `<g id="background">`, `<g id="hair">`, `<g id="clothes">`, `<g id="desk">` (newsroom only) and
    `<g id="face">` in that order; the clothes layer's neck leans to stay under the posed chin (render/scenery.py's lean).

    `background` / `clothes` name the scenery of render/scenery.py (OptionError if unknown).
    """
    width, height = float(face.width), float(face.height)
    root = svg_root({"width": f"{width:g}", "height": f"{height:g}", "viewBox": f"0 0 {width:g} {height:g}"})
    defs = element(root, "defs", {})
    defs.extend(face_defs(face))
    figure = figure_of(face, (0.0, 0.0, width, height))
    root.append(background_layer(background, figure, defs))
    lifted = lift(face)
    leaning = lean(figure, lifted.origin, state.pose.roll)
    group = face_group(face, pose_face(lifted, state), "0", leaning)
    hair = element(root, "g", {"id": "hair"})
    hair.extend(group.findall(f"{{{SVG}}}path[@class='hair']"))
    dressed = clothes_layer(clothes, figure, defs)
    dressed[0].set("transform", lean_transform(figure, leaning))  # the neck leans with the head
    root.append(dressed)
    desk = desk_layer(background, figure, defs)  # the newsroom's desk, in front of the body
    if desk is not None:
        root.append(desk)
    group.set("id", "face")
    root.append(group)
    return root
