"""Background and clothes layers of the virtual announcer (thesis 002, 6.3.1 and 7.2).

The thesis draws four layers, background, hair, clothes and face (its Figs. 6.7,
6.8, 7.2 and 7.3 show a studio backdrop and a suit; the figures themselves are
lost in the text). These are our own drawings: three backgrounds and three
clothes, plus "plain" and "none", each a few SVG shapes with gradients. The body
stays still while the head tilts, turns and nods; the neck (drawn with every clothes
option, "none" included) leans about the collar to stay under the chin.

Geometry comes from a `Figure`: where the chin is and how wide the face is, so
the neck and shoulders fit any face model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from lxml import etree

from cartoonface.errors import OptionError
from cartoonface.face.model import FaceModel
from cartoonface.render.elements import DECIMALS, element
from cartoonface.render.numbers import decimal_text

BACKGROUNDS = ("studio", "newsroom", "classroom", "plain")
CLOTHES = ("suit", "shirt", "sweater", "none")

# Everything below is our own drawing (the thesis's figures are lost), tuned by eye.
# Gradients by id: (offset 0..1, colour) stops, top to bottom.
GRADIENTS: dict[str, tuple[tuple[float, str], ...]] = {
    "bg-studio": ((0, "#1e3a8a"), (0.7, "#0f172a"), (1, "#020617")),  # dark blue backdrop
    "bg-desk": ((0, "#475569"), (1, "#1e293b")),
    "bg-dusk": ((0, "#fb923c"), (0.55, "#7c3aed"), (1, "#1e1b4b")),  # the newsroom's evening sky
    "bg-board": ((0, "#2f5d3a"), (1, "#1f3d27")),  # chalkboard
    "cl-suit": ((0, "#334155"), (1, "#0f172a")),
    "cl-shirt": ((0, "#bfdbfe"), (1, "#60a5fa")),
    "cl-sweater": ((0, "#16a34a"), (1, "#14532d")),
}
# Flat colours by what they paint.
COLOURS = {"wall": "#f3efe6", "panel": "#3b82f6", "skyline": "#1e1b4b", "window": "#fde68a",
           "classroom wall": "#efe6d2", "board frame": "#8b5a2b", "chalk": "#e5e7eb", "floor": "#c8b48c",
           "jaw shadow": "#000", "shirt front": "#f8fafc", "tie": "#b91c1c", "lapel": "#1e293b",
           "collar": "#eff6ff", "collar line": "#93c5fd", "placket": "#3b82f6", "rib": "#166534"}

# Backgrounds, in fractions of the picture's width w and height h.
STUDIO_PANELS = 5  # light panels behind the announcer: left edges at w * (PANEL_LEFT + PANEL_PITCH k)
PANEL_LEFT, PANEL_PITCH, PANEL_TOP, PANEL_WIDTH, PANEL_HEIGHT = 0.04, 0.2, 0.08, 0.12, 0.5
PANEL_OPACITY = "0.18"
DESK_TOP, DESK_HEIGHT = 0.78, 0.22
CORNER = 0.01  # corner radius of the panels and the board frame
SKYLINE = (0.35, 0.55, 0.42, 0.7, 0.5, 0.62, 0.38, 0.58, 0.45, 0.66)  # building heights, left to right
BUILDING_WIDTH, BUILDING_OPACITY = 0.92, "0.85"  # of the building's slot w / len(SKYLINE)
# Lit windows: a row per tenth of the building's height, WINDOW_FIRST below its top then every
# WINDOW_PITCH (of h); WINDOW_LEFT, WINDOW_WIDTH of the slot.
WINDOW_ROWS_PER_HEIGHT = 10
WINDOW_LEFT, WINDOW_WIDTH, WINDOW_FIRST, WINDOW_PITCH, WINDOW_HEIGHT = 0.2, 0.5, 0.05, 0.08, 0.02
WINDOW_OPACITY = "0.5"
FRAME = (0.05, 0.06, 0.9, 0.55)  # the board's wooden frame: x, y, width, height
BOARD = (0.07, 0.085, 0.86, 0.5)  # the board inside it
CHALK_MARKS = ((0.12, 0.2), (0.7, 0.3), (0.15, 0.45))  # left ends; mark k rises 0.02 k over its length
CHALK_LENGTH, CHALK_RISE, CHALK_LINE, CHALK_OPACITY = 0.15, 0.02, 0.004, "0.7"
FLOOR_TOP, FLOOR_HEIGHT = 0.8, 0.2

# The body, in fractions of the face width fw (Figure.face_width); render/sheet.py's neck
# uses NECK too, so the sheet's heads sit on the same neck.
NECK = 0.22  # half the neck's width
NECK_TOP = 0.3  # the neck starts this far above the chin, so the jaw covers it while the head moves
NECK_FOOT = 0.1  # ... and ends this far below the shoulder line
SHOULDER_DROP = 0.35  # the shoulder line below the chin
SHOULDER = 1.25  # half the shoulders' width
SHOULDER_SLOPE = 0.25  # the arms' top below the shoulder line
SHOULDER_START = 2.2  # where the shoulders leave the collar, in half neck widths
JAW_SHADOW, JAW_SHADOW_OPACITY = 0.07, "0.12"  # the jaw's shadow on the neck: vertical radius
SHADOW_WIDTH = 0.85  # the shadow's horizontal radius / half the neck's width: room for the chin to move
SHADOW_POINTS = 16  # corners of the jaw's shadow cut at a side of the neck (an ellipse, within 1 px at our sizes)
LEAN_DECIMALS = 1  # the neck's lean is written to 0.1 degree: 0.1 px at the chin for a lever of 60 px


@dataclass(frozen=True)
class Figure:
    """Where the body goes: `box` (x, y, width, height) of the picture in pixels,
    the chin at (`chin_x`, `chin_y`), the face `face_width` in pixels, `skin` a hex colour."""

    box: tuple[float, float, float, float]
    chin_x: float
    chin_y: float
    face_width: float
    skin: str


def figure_of(face: FaceModel, box: tuple[float, float, float, float]) -> Figure:
    """Where the neck and shoulders go for `face` inside the picture `box` (x, y, width,
    height in pixels): under its chin 2.1, the face as wide as its widest feature points
    (the contour). The one place a Figure is made, so stills and animations match."""
    chin = face.point("2.1")
    return Figure(box=box, chin_x=float(chin[0]), chin_y=float(chin[1]),
                  face_width=float(np.ptp(face.points[:, 0])), skin=face.palette.skin)


def _num(value: float) -> str:
    """A coordinate of path data, written like element's numbers (to 0.1 px, "0.5", "12")."""
    return decimal_text(value, DECIMALS)


def _points(*pairs: tuple[float, float]) -> str:
    """Path data of a closed polygon through `pairs`."""
    return "M" + "L".join(f"{_num(x)},{_num(y)}" for x, y in pairs) + "Z"


def _gradient(defs: etree._Element, gid: str) -> str:
    """Add the vertical linear gradient GRADIENTS[`gid`] to `defs`; return its url()."""
    grad = element(defs, "linearGradient", id=gid, x1="0", y1="0", x2="0", y2="1")
    for offset, colour in GRADIENTS[gid]:
        element(grad, "stop", offset=f"{offset:g}", stop_color=colour)
    return f"url(#{gid})"


def background_layer(name: str, figure: Figure, defs: etree._Element) -> etree._Element:
    """The background `name` (one of BACKGROUNDS) as a `<g>` filling `figure.box`; gradients go into `defs`."""
    if name not in BACKGROUNDS:
        raise OptionError(f"background {name!r}: expected one of {', '.join(BACKGROUNDS)}")
    x, y, w, h = figure.box
    layer = element(None, "g", id="background")
    if name == "plain":
        element(layer, "rect", x=x, y=y, width=w, height=h, fill=COLOURS["wall"])
    elif name == "studio":
        element(layer, "rect", x=x, y=y, width=w, height=h, fill=_gradient(defs, "bg-studio"))
        for k in range(STUDIO_PANELS):
            px = x + w * (PANEL_LEFT + PANEL_PITCH * k)
            element(layer, "rect", x=px, y=y + h * PANEL_TOP, width=w * PANEL_WIDTH, height=h * PANEL_HEIGHT,
                    rx=w * CORNER, fill=COLOURS["panel"], opacity=PANEL_OPACITY)
        element(layer, "rect", x=x, y=y + h * DESK_TOP, width=w, height=h * DESK_HEIGHT,
                fill=_gradient(defs, "bg-desk"))
    elif name == "newsroom":
        element(layer, "rect", x=x, y=y, width=w, height=h, fill=_gradient(defs, "bg-dusk"))
        step = w / len(SKYLINE)
        for k, tall in enumerate(SKYLINE):  # a city skyline
            element(layer, "rect", x=x + k * step, y=y + h * (1 - tall), width=step * BUILDING_WIDTH,
                    height=h * tall, fill=COLOURS["skyline"], opacity=BUILDING_OPACITY)
            for row in range(int(tall * WINDOW_ROWS_PER_HEIGHT)):
                element(layer, "rect", x=x + k * step + step * WINDOW_LEFT,
                        y=y + h * (1 - tall + WINDOW_FIRST + row * WINDOW_PITCH),
                        width=step * WINDOW_WIDTH, height=h * WINDOW_HEIGHT, fill=COLOURS["window"],
                        opacity=WINDOW_OPACITY)
    else:  # classroom: a chalkboard in a wooden frame on a cream wall
        element(layer, "rect", x=x, y=y, width=w, height=h, fill=COLOURS["classroom wall"])
        element(layer, "rect", x=x + w * FRAME[0], y=y + h * FRAME[1], width=w * FRAME[2], height=h * FRAME[3],
                rx=w * CORNER, fill=COLOURS["board frame"])
        element(layer, "rect", x=x + w * BOARD[0], y=y + h * BOARD[1], width=w * BOARD[2], height=h * BOARD[3],
                fill=_gradient(defs, "bg-board"))
        for k, (u, v) in enumerate(CHALK_MARKS):
            element(layer, "path", d=_points((x + w * u, y + h * v),
                                             (x + w * (u + CHALK_LENGTH), y + h * (v - CHALK_RISE * k))),
                    stroke=COLOURS["chalk"], stroke_width=w * CHALK_LINE, fill="none", opacity=CHALK_OPACITY)
        element(layer, "rect", x=x, y=y + h * FLOOR_TOP, width=w, height=h * FLOOR_HEIGHT, fill=COLOURS["floor"])
    return layer


def neck_pivot(figure: Figure) -> float:
    """The height (pixels) about which the neck leans: the shoulder line, where it leaves the collar."""
    return figure.chin_y + figure.face_width * SHOULDER_DROP


def lean(figure: Figure, origin: np.ndarray, roll: float) -> float:
    """Degrees of skewX about neck_pivot that lean the neck with the head's `roll` (degrees,
    positive leans the head's top to the image left) about the rotation `origin` (2,) pixels:
    the neck's middle passes through the rolled chin while its foot stays in the collar. The
    head's tilt and turn move the chin over the neck, not the neck. Positive leans the neck's
    top to the image left (SVG skewX)."""
    angle = math.radians(roll)
    x, y = figure.chin_x - float(origin[0]), figure.chin_y - float(origin[1])
    rolled_x = float(origin[0]) + x * math.cos(angle) + y * math.sin(angle)
    rolled_y = float(origin[1]) - x * math.sin(angle) + y * math.cos(angle)
    return math.degrees(math.atan((rolled_x - figure.chin_x) / (rolled_y - neck_pivot(figure))))


def neck_middle(figure: Figure, degrees: float, height: float) -> float:
    """The x (pixels) of the middle of the neck leaned by `degrees` (lean) at `height` pixels."""
    return figure.chin_x + math.tan(math.radians(degrees)) * (height - neck_pivot(figure))


def lean_transform(figure: Figure, degrees: float) -> str:
    """An SVG transform leaning the neck by `degrees` (lean) about neck_pivot."""
    pivot = _num(neck_pivot(figure))
    return f"translate(0 {pivot}) skewX({decimal_text(degrees, LEAN_DECIMALS)}) translate(0 -{pivot})"


def chin_shadow(figure: Figure, chin: np.ndarray, middle: float) -> etree._Element:
    """The jaw's shadow on the neck for a posed chin 2.1 at `chin` (2,) pixels, without class or
    paint: an ellipse centred on the chin, SHADOW_WIDTH of the neck wide and JAW_SHADOW fw high
    (the face drawn over it hides its top half). Where it would pass a side of the neck (whose
    middle at the chin's height is `middle`, neck_middle), a polygon of SHADOW_POINTS corners
    cut at that side instead; corner SHADOW_POINTS // 4 is its lowest point, right under the
    chin while the chin is over the neck."""
    half = figure.face_width * NECK
    left, right = middle - half, middle + half
    cx, cy = float(chin[0]), float(chin[1])
    rx, ry = half * SHADOW_WIDTH, figure.face_width * JAW_SHADOW
    if left <= cx - rx and cx + rx <= right:
        return element(None, "ellipse", cx=cx, cy=cy, rx=rx, ry=ry)
    cx = float(np.clip(cx, left, right))  # a chin beyond a side of the neck: on that side
    angles = np.linspace(0, 2 * np.pi, SHADOW_POINTS, endpoint=False)
    # clamping x cuts an upright ellipse exactly at the sides: beyond a side it is no taller than there
    xs = np.clip(cx + rx * np.cos(angles), left, right)
    return element(None, "path", d=_points(*zip(xs.tolist(), (cy + ry * np.sin(angles)).tolist(), strict=True)))


def clothes_layer(name: str, figure: Figure, defs: etree._Element) -> etree._Element:
    """The clothes `name` (one of CLOTHES) with neck and shoulders under the chin as a `<g id="clothes">`;
    "none" is the neck alone, down past the picture's bottom, so the head never floats. The neck
    is the layer's first child, an upright path of class "neck" that the caller leans with the
    head (lean, lean_transform). The jaw's shadow is the face's (render/svg.py, chin_shadow):
    it moves with the chin. Sizes are fractions of the face
    width fw (the body constants above, and the clothes' own)."""
    if name not in CLOTHES:
        raise OptionError(f"clothes {name!r}: expected one of {', '.join(CLOTHES)}")
    x, y, w, h = figure.box
    cx, chin, fw = figure.chin_x, figure.chin_y, figure.face_width
    bottom = y + h + fw  # past the bottom edge: the body leaves the picture
    neck = fw * NECK
    shoulder_y = chin + fw * SHOULDER_DROP
    spread = fw * SHOULDER
    layer = element(None, "g", id="clothes")
    foot = bottom if name == "none" else shoulder_y + fw * NECK_FOOT
    element(layer, "path", {"class": "neck"}, d=_points((cx - neck, chin - fw * NECK_TOP), (cx + neck, chin - fw * NECK_TOP),
                                                        (cx + neck, foot), (cx - neck, foot)),
            fill=figure.skin)
    if name == "none":
        return layer
    arms = shoulder_y + fw * SHOULDER_SLOPE
    body = ((cx - spread, bottom), (cx - spread, arms), (cx - neck * SHOULDER_START, shoulder_y),
            (cx + neck * SHOULDER_START, shoulder_y), (cx + spread, arms), (cx + spread, bottom))
    element(layer, "path", d=_points(*body), fill=_gradient(defs, f"cl-{name}"))
    # Below: each garment's own shapes, points as (x in half neck widths from cx, y in fw from shoulder_y).
    if name == "suit":
        element(layer, "path", d=_points((cx - neck * 1.6, shoulder_y - fw * 0.02), (cx + neck * 1.6, shoulder_y - fw * 0.02),
                                         (cx, shoulder_y + fw * 0.7)), fill=COLOURS["shirt front"])
        element(layer, "path", d=_points((cx - neck * 0.35, shoulder_y + fw * 0.06), (cx + neck * 0.35, shoulder_y + fw * 0.06),
                                         (cx + neck * 0.5, shoulder_y + fw * 0.55), (cx, shoulder_y + fw * 0.68),
                                         (cx - neck * 0.5, shoulder_y + fw * 0.55)), fill=COLOURS["tie"])
        for side in (-1, 1):  # lapels
            element(layer, "path", d=_points((cx + side * neck * 1.6, shoulder_y - fw * 0.02),
                                             (cx + side * neck * 0.2, shoulder_y + fw * 0.75),
                                             (cx + side * neck * 2.6, shoulder_y + fw * 0.3)), fill=COLOURS["lapel"])
    elif name == "shirt":
        element(layer, "path", d=_points((cx - neck, shoulder_y - fw * 0.02), (cx + neck, shoulder_y - fw * 0.02),
                                         (cx, shoulder_y + fw * 0.3)), fill=figure.skin)  # open collar
        for side in (-1, 1):
            element(layer, "path", d=_points((cx + side * neck * 1.1, shoulder_y - fw * 0.08), (cx, shoulder_y + fw * 0.3),
                                             (cx + side * neck * 2.4, shoulder_y + fw * 0.12)),
                    fill=COLOURS["collar"], stroke=COLOURS["collar line"], stroke_width=fw * 0.01)
        element(layer, "path", d=f"M{_num(cx)},{_num(shoulder_y + fw * 0.3)}V{_num(bottom)}",
                stroke=COLOURS["placket"], stroke_width=fw * 0.012, fill="none")
    else:  # sweater: round neck, ribbed collar
        left, right, dip = cx - neck * 1.3, cx + neck * 1.3, shoulder_y + fw * 0.12
        element(layer, "path", d=f"M{_num(left)},{_num(shoulder_y)}Q{_num(cx)},{_num(dip)} {_num(right)},{_num(shoulder_y)}",
                fill="none", stroke=COLOURS["rib"], stroke_width=fw * 0.05, stroke_linecap="round")
    return layer
