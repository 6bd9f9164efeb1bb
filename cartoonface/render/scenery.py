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
from cartoonface.render.numbers import TENTHS, decimal_text, fill, rounded_tenths, template_frame, tenths_texts

BACKGROUNDS = ("studio", "newsroom", "classroom", "plain")
CLOTHES = ("suit", "shirt", "sweater", "none")

# Everything below is our own drawing (the thesis's figures are lost), tuned by eye.
# Vertical gradients by id: (offset 0..1, colour) stops, top to bottom.
GRADIENTS: dict[str, tuple[tuple[float, str], ...]] = {
    "bg-news": ((0, "#0b1a33"), (0.6, "#10305a"), (1, "#07101f")),  # the newsroom's wall, cool blue
    "bg-screen": ((0, "#1d4ed8"), (1, "#0e7490")),  # a screen of its video wall
    "bg-desk-top": ((0, "#f1f5f9"), (1, "#94a3b8")),  # the news desk's lit top edge
    "bg-desk": ((0, "#1e293b"), (1, "#0b1220")),  # its front
    "bg-news-floor": ((0, "#2b4775"), (1, "#172641")),  # the lit set wall behind the anchor's shoulders
    "bg-studio": ((0, "#d5dbe2"), (1, "#97a3b0")),  # the studio's paper backdrop
    "bg-sweep": ((0, "#8e99a6"), (1, "#66717e")),  # where the backdrop sweeps into the floor
    "bg-board": ((0, "#2f5d3a"), (1, "#1f3d27")),  # chalkboard
    "bg-wood": ((0, "#9a6a3a"), (1, "#6f4622")),  # the classroom's wainscot and the board's tray
    "cl-shirt-front": ((0, "#ffffff"), (1, "#dfe5ec")),  # the suit's shirt, shaded down the chest
}
# Horizontal gradients of the garments, (offset, colour) left to right: darker at the sides,
# where the body turns away from the light, lightest in the middle of the chest.
SHADED: dict[str, tuple[tuple[float, str], ...]] = {
    "cl-suit": ((0, "#0c1220"), (0.3, "#1c2740"), (0.5, "#27365a"), (0.7, "#1c2740"), (1, "#0c1220")),
    "cl-shirt": ((0, "#6f98cc"), (0.3, "#9fc1ea"), (0.5, "#bcd5f3"), (0.7, "#9fc1ea"), (1, "#6f98cc")),
    "cl-sweater": ((0, "#0f4424"), (0.3, "#17753a"), (0.5, "#1f8f48"), (0.7, "#17753a"), (1, "#0f4424")),
    "cl-tie": ((0, "#7f1d1d"), (0.5, "#c62828"), (1, "#7f1d1d")),
}
# Radial glows: (colour, opacity at the centre), fading to nothing at the edge.
GLOWS = {"bg-news-glow": ("#60a5fa", 0.35), "bg-spot": ("#ffffff", 0.6), "bg-softbox": ("#ffffff", 1.0),
         "cl-neck-shadow": ("#000000", 0.22)}
# Flat colours by what they paint.
COLOURS = {"wall": "#f3efe6", "classroom wall": "#efe6d2", "board frame": "#8b5a2b", "chalk": "#e5e7eb",
           "floor": "#c8b48c", "eraser": "#374151", "news frame": "#0a1428", "news line": "#1e3a5f",
           "news light": "#7dd3fc", "band": "#b91c1c", "band text": "#ffffff",
           "desk accent": "#38bdf8", "softbox": "#1f2937", "softbox face": "#f8fafc", "stand": "#374151",
           "jaw shadow": "#000", "collar": "#ffffff", "collar line": "#b6c2cf", "lapel": "#151d31",
           "lapel edge": "#3d4d70", "suit seam": "#070b14", "button": "#0b0f1a", "shirt collar": "#dbeafe",
           "shirt collar line": "#7ea6d8", "placket": "#6f98cc", "shirt button": "#f8fafc", "rib": "#27a85c",
           "rib line": "#157a3c"}

# Backgrounds, in fractions of the picture's width w and height h.
CORNER = 0.01  # corner radius of panels, screens and frames
# Newsroom: a video wall of SCREENS (columns, rows) in a frame, a glow behind the anchor, light
# columns at the sides, a red band with a logo and a line of "text" under the wall, a dark floor.
NEWS_WALL = (0.06, 0.08, 0.88, 0.48)  # x, y, width, height of the video wall's frame
SCREENS = (4, 2)
SCREEN_GAP = 0.006  # between screens and around them, of w
SCREEN_OPACITY = "0.85"
NEWS_GLOW = (0.5, 0.42, 0.45, 0.5)  # centre x, y and radii of the glow, of w and h
NEWS_LIGHTS = (0.015, 0.965)  # left edges of the light columns
NEWS_LIGHT_WIDTH, NEWS_LIGHT_TOP, NEWS_LIGHT_BOTTOM, NEWS_LIGHT_OPACITY = 0.02, 0.08, 0.7, "0.45"
BAND = (0.6, 0.05)  # top and height of the red band
BAND_LOGO = (0.08, 0.12)  # left edge and width of the logo block on it
BAND_TEXT = ((0.24, 0.1), (0.37, 0.16), (0.56, 0.08), (0.67, 0.14), (0.84, 0.08))  # "words": left, width
BAND_TEXT_HEIGHT, BAND_TEXT_OPACITY = 0.3, "0.75"  # of the band's height
NEWS_FLOOR = 0.7  # top of the floor
GLOBE = (0.5, 0.5, 0.3)  # on the first screen: centre and radius, of the screen's width and height / its height
GLOBE_LINE, GLOBE_OPACITY = 0.003, "0.6"  # of w
CHART = (0.2, 0.45, 0.7, 0.35, 0.55)  # bar heights on the last screen, of the screen's height
CHART_OPACITY = "0.6"
# The news desk, in front of the anchor: its top DESK_DROP fw below the shoulder line (above the
# announcer page's caption, which then sits on the desk's front), the top edge DESK_EDGE h
# thick, DESK_SPAN of w wide; an accent line on its front.
DESK_DROP, DESK_EDGE, DESK_SPAN = 0.4, 0.03, (0.06, 0.94)
DESK_ACCENT, DESK_ACCENT_LINE = 0.03, 0.004  # below the top edge, of h
# Studio: a paper backdrop lit behind the head, sweeping into the floor, a softbox on a stand
# at each side.
SPOT = (0.35, 0.55)  # radii of the light on the backdrop, of w and h, centred above the chin
SWEEP_TOP, SWEEP_BOW = 0.78, 0.04  # the floor's edge at the sides and how much lower in the middle
SOFTBOXES = (0.1, 0.9)  # centres x
SOFTBOX = (0.08, 0.2, 0.12)  # width of w, height and top of h
SOFTBOX_DEPTH = 0.15  # the housing behind the diffuser, of the softbox's width on each side
STAND_LINE, STAND_FOOT, STAND_SPREAD = 0.004, 0.86, 0.03  # of w; the foot's height of h; legs' spread of w
# Classroom: a chalkboard in a wooden frame with a chalk tray, chalk writing and a diagram,
# a wooden wainscot and the floor.
FRAME = (0.05, 0.06, 0.9, 0.55)  # the board's wooden frame: x, y, width, height
BOARD = (0.07, 0.085, 0.86, 0.5)  # the board inside it
TRAY = 0.018  # the chalk tray under the frame, of h
CHALK_STICKS = ((0.2, 0.03), (0.25, 0.02))  # on the tray: left, length, of w
ERASER = (0.72, 0.06, 0.022)  # on the tray: left and width of w, height of h
CHALK_LINE, CHALK_OPACITY = 0.003, "0.75"
# Chalk "writing": rows of characters, each a few strokes in a cell; (left, top) of the first
# cell, cell size and pitch of w, characters per row. A triangle and a circle as a diagram.
WRITING_ROWS = ((0.1, 0.14, 5), (0.1, 0.26, 7), (0.1, 0.38, 4))
CELL, CELL_PITCH = 0.03, 0.042
STROKES = (((0.1, 0.2), (0.9, 0.2)), ((0.5, 0.0), (0.5, 1.0)), ((0.2, 0.5), (0.8, 0.5)),
           ((0.1, 1.0), (0.5, 0.6)), ((0.9, 1.0), (0.5, 0.6)), ((0.2, 0.8), (0.8, 0.8)))  # in a unit cell
STROKES_PER_CHARACTER = 3
DIAGRAM = ((0.72, 0.42), (0.86, 0.42), (0.72, 0.18))  # a right triangle's corners, of w and h
DIAGRAM_CIRCLE = (0.8, 0.3, 0.05)  # centre of w and h, radius of h
WAINSCOT = (0.72, 0.08)  # top and height, of h
FLOOR_TOP, FLOOR_HEIGHT = 0.8, 0.2

# The body, in fractions of the face width fw (Figure.face_width); render/sheet.py's neck
# uses NECK too, so the sheet's heads sit on the same neck.
NECK = 0.22  # half the neck's width
NECK_TOP = 0.3  # the neck starts this far above the chin, so the jaw covers it while the head moves
NECK_FOOT = 0.1  # ... and ends this far below the shoulder line
SHOULDER_DROP = 0.35  # the shoulder line below the chin
# The garments' shapes: points (u, v) with u in half neck widths (NECK fw) from the middle,
# negative to the image left, and v in fw below the shoulder line; None for v is the bottom
# of the picture. Each shape is given for the image-left side and mirrored (_symmetric /
# _both_sides). Path pieces: ("L", point) or ("C", control, control, point).
# The torso's outline from the back of the neck out over a rounded shoulder and down the arm.
TORSO = ((0.0, -0.04), ("L", (-1.2, -0.04)), ("C", (-2.3, -0.02), (-3.8, 0.03), (-4.8, 0.1)),
         ("C", (-5.5, 0.15), (-5.8, 0.3), (-5.85, 0.5)), ("L", (-6.0, None)))
# The suit: the shirt's V between the lapels, its collar, the tie, the notched lapels, a
# button where the lapels meet, a breast pocket with a folded square, the seams of the sleeves.
SHIRT_FRONT = ((0.0, -0.04), ("L", (-1.5, -0.04)), ("L", (0.0, 0.8)))
SUIT_COLLAR = ((-1.25, -0.07), (-0.1, 0.02), (-0.75, 0.2), (-1.55, 0.06))
TIE = ((0.0, 0.11), ("L", (-0.28, 0.11)), ("L", (-0.55, 0.62)), ("L", (0.0, 0.72)))
TIE_KNOT = ((0.0, 0.01), ("L", (-0.42, 0.01)), ("L", (-0.3, 0.13)), ("L", (0.0, 0.13)))
LAPEL = ((-1.3, -0.06), (-0.05, 0.82), (-1.7, 0.52), (-3.0, 0.22), (-2.55, 0.14), (-2.9, 0.06), (-2.1, -0.07))
BUTTON = (0.0, 0.88, 0.02)  # centre (u, v), radius in fw
POCKET = ((2.6, 0.62), (3.9, 0.58))  # the welt of the breast pocket on the image right: from, to
POCKET_SQUARE = ((2.8, 0.6), (3.1, 0.5), (3.4, 0.54), (3.7, 0.59))
SLEEVE_SEAM = ((-4.9, 0.14), ("C", (-4.5, 0.4), (-4.5, 0.7), (-4.7, None)))
SEAM_OPACITY = "0.5"
# The shirt: an open collar over the skin, a placket with buttons, a breast pocket.
OPEN_NECK = ((0.0, -0.04), ("L", (-1.0, -0.04)), ("L", (0.0, 0.3)))
SHIRT_COLLAR = ((-1.25, -0.09), (-0.95, -0.02), (-0.15, 0.29), (-2.4, 0.14))
SHIRT_BUTTONS = (0.45, 0.7, 0.95)  # v of each button
SHIRT_POCKET = (1.9, 0.5, 1.3, 0.3)  # u, v, width (half neck widths), height (fw)
# The sweater: a ribbed round neck with a shirt collar over it, raglan seams.
RIB = ((-1.4, -0.01), (0.0, 0.17), (1.4, -0.01))  # quadratic: from, control, to
RIB_WIDTH, RIB_DASH = 0.05, 0.012  # the rib band's width and its ribs' pitch, of fw
SWEATER_COLLAR = ((-1.15, -0.02), (-0.08, 0.09), (-0.65, 0.2), (-1.45, 0.08))
RAGLAN = ((-1.7, 0.04), ("L", (-5.4, 0.62)))
NECK_SHADOW = (1.5, 0.09)  # the neck's soft shadow on the chest: radii, in half neck widths and fw
LINE = 0.006  # outlines of collars and lapels, of fw
JAW_SHADOW, JAW_SHADOW_OPACITY = 0.07, "0.12"  # the jaw's shadow on the neck: vertical radius
SHADOW_WIDTH = 0.85  # the shadow's horizontal radius / half the neck's width: room for the chin to move
SHADOW_POINTS = 16  # corners of the jaw's shadow cut at a side of the neck (an ellipse, within 1 px at our sizes)
_SHADOW_ANGLES = np.linspace(0, 2 * np.pi, SHADOW_POINTS, endpoint=False)  # the corners' angles about the chin
_SHADOW_COS, _SHADOW_SIN = np.cos(_SHADOW_ANGLES), np.sin(_SHADOW_ANGLES)
# The cut shadow's path data with its corners' x, y %-formatted to DECIMALS (1) decimal (_num, then _short_tenths).
_SHADOW_TEMPLATE = "M" + "L".join(["%.1f,%.1f"] * SHADOW_POINTS) + "Z"
# The same with the numbers written from whole tenths by numbers.tenths_texts (chin_shadows: the
# same text where the tenths are what %.1f rounds to and the number has a whole part).
_SHADOW_FRAME = template_frame(_SHADOW_TEMPLATE.replace("%.1f", "%s"))
LEAN_DECIMALS = 1  # the neck's lean is written to 0.1 degree: 0.1 px at the chin for a lever of 60 px
# The torso's motion (animate/body.py), our choices tuned by eye: a full breath lifts the
# shoulders by BREATH_RISE fw (about 4 px on the sample faces) and the neck by NECK_BREATH of
# that; the torso turns about a vertical axis TORSO_DEPTH fw behind its front (its front moves
# sideways by sin(turn) of that) and leans about a point TORSO_PIVOT fw below the shoulder line.
BREATH_RISE = 0.02
NECK_BREATH = 0.3
TORSO_DEPTH = 0.5
TORSO_PIVOT = 1.2


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


def _short_tenths(data: str) -> str:
    """Polygon path data whose numbers were %-formatted with DECIMALS (1) decimal, each followed
    by "," "L" or "Z", with every ".0" dropped: each number as `_num` writes it ("12", "-0")."""
    return data.replace(".0,", ",").replace(".0L", "L").replace(".0Z", "Z")


def _gradient(defs: etree._Element, gid: str) -> str:
    """Add the linear gradient `gid` to `defs` (GRADIENTS: top to bottom; SHADED: left to
    right) unless it is there; return its url()."""
    if defs.find(f"*[@id='{gid}']") is None:
        vertical = gid in GRADIENTS
        grad = element(defs, "linearGradient", id=gid, x1="0", y1="0", x2="0" if vertical else "1",
                       y2="1" if vertical else "0")
        for offset, colour in (GRADIENTS if vertical else SHADED)[gid]:
            element(grad, "stop", offset=f"{offset:g}", stop_color=colour)
    return f"url(#{gid})"


def _glow(defs: etree._Element, gid: str) -> str:
    """Add the radial gradient GLOWS[`gid`] (its colour fading out to the edge) to `defs` unless it is there; return its url()."""
    if defs.find(f"*[@id='{gid}']") is None:
        colour, opacity = GLOWS[gid]
        grad = element(defs, "radialGradient", id=gid)
        element(grad, "stop", offset="0", stop_color=colour, stop_opacity=f"{opacity:g}")
        element(grad, "stop", offset="1", stop_color=colour, stop_opacity="0")
    return f"url(#{gid})"


def background_layer(name: str, figure: Figure, defs: etree._Element) -> etree._Element:
    """The background `name` (one of BACKGROUNDS) as a `<g>` filling `figure.box`; gradients go into `defs`.
    Drawn once: a newsroom set (video wall, logo band, cool light), a photo studio (lit
    backdrop, softboxes), a classroom (chalkboard), or a plain wall. The news desk is in front
    of the body: desk_layer."""
    if name not in BACKGROUNDS:
        raise OptionError(f"background {name!r}: expected one of {', '.join(BACKGROUNDS)}")
    x, y, w, h = figure.box
    layer = element(None, "g", id="background")
    if name == "plain":
        element(layer, "rect", x=x, y=y, width=w, height=h, fill=COLOURS["wall"])
    elif name == "newsroom":
        _newsroom(layer, figure.box, defs)
    elif name == "studio":
        _studio(layer, figure, defs)
    else:
        _classroom(layer, figure.box, defs)
    return layer


def _newsroom(layer: etree._Element, box: tuple[float, float, float, float], defs: etree._Element) -> None:
    """A news studio set into `layer` over `box`: the wall, a glow, the video wall, light columns, the red band, the floor."""
    x, y, w, h = box
    element(layer, "rect", x=x, y=y, width=w, height=h, fill=_gradient(defs, "bg-news"))
    gx, gy, grx, gry = NEWS_GLOW
    element(layer, "ellipse", cx=x + w * gx, cy=y + h * gy, rx=w * grx, ry=h * gry, fill=_glow(defs, "bg-news-glow"))
    left, top, width, height = NEWS_WALL
    element(layer, "rect", x=x + w * left, y=y + h * top, width=w * width, height=h * height, rx=w * CORNER,
            fill=COLOURS["news frame"], stroke=COLOURS["news line"], stroke_width=w * SCREEN_GAP / 2)
    columns, rows = SCREENS
    gap = w * SCREEN_GAP
    cell_w = (w * width - gap * (columns + 1)) / columns
    cell_h = (h * height - gap * (rows + 1)) / rows
    screen = _gradient(defs, "bg-screen")
    for row in range(rows):
        for column in range(columns):
            sx = x + w * left + gap + column * (cell_w + gap)
            sy = y + h * top + gap + row * (cell_h + gap)
            element(layer, "rect", x=sx, y=sy, width=cell_w, height=cell_h, fill=screen, opacity=SCREEN_OPACITY)
            if column == 0 and row == 0:  # a globe
                cx, cy, r = sx + cell_w * GLOBE[0], sy + cell_h * GLOBE[1], cell_h * GLOBE[2]
                globe = element(layer, "g", fill="none", stroke=COLOURS["news light"], stroke_width=w * GLOBE_LINE,
                                opacity=GLOBE_OPACITY)
                element(globe, "circle", cx=cx, cy=cy, r=r)
                element(globe, "ellipse", cx=cx, cy=cy, rx=r / 2, ry=r)
                element(globe, "path", d=f"M{_num(cx - r)},{_num(cy)}H{_num(cx + r)}M{_num(cx)},{_num(cy - r)}V{_num(cy + r)}")
            if column == columns - 1 and row == 0:  # a bar chart
                bar = cell_w / (2 * len(CHART) + 1)
                for k, tall in enumerate(CHART):
                    element(layer, "rect", x=sx + bar * (2 * k + 1), y=sy + cell_h * (1 - tall) - gap, width=bar,
                            height=cell_h * tall, fill=COLOURS["news light"], opacity=CHART_OPACITY)
    for lx in NEWS_LIGHTS:
        element(layer, "rect", x=x + w * lx, y=y + h * NEWS_LIGHT_TOP, width=w * NEWS_LIGHT_WIDTH,
                height=h * (NEWS_LIGHT_BOTTOM - NEWS_LIGHT_TOP), rx=w * NEWS_LIGHT_WIDTH / 2,
                fill=COLOURS["news light"], opacity=NEWS_LIGHT_OPACITY)
    band_top, band_height = BAND
    element(layer, "rect", x=x, y=y + h * band_top, width=w, height=h * band_height, fill=COLOURS["band"])
    element(layer, "rect", x=x + w * BAND_LOGO[0], y=y + h * band_top, width=w * BAND_LOGO[1], height=h * band_height,
            fill=COLOURS["band text"])
    text_y = y + h * (band_top + band_height * (1 - BAND_TEXT_HEIGHT) / 2)
    for left_edge, length in BAND_TEXT:
        element(layer, "rect", x=x + w * left_edge, y=text_y, width=w * length, height=h * band_height * BAND_TEXT_HEIGHT,
                fill=COLOURS["band text"], opacity=BAND_TEXT_OPACITY)
    element(layer, "rect", x=x, y=y + h * NEWS_FLOOR, width=w, height=h * (1 - NEWS_FLOOR),
            fill=_gradient(defs, "bg-news-floor"))


def _studio(layer: etree._Element, figure: Figure, defs: etree._Element) -> None:
    """A photo studio into `layer`: the paper backdrop lit behind the head, its sweep into the
    floor, a softbox on a stand at each side."""
    x, y, w, h = figure.box
    element(layer, "rect", x=x, y=y, width=w, height=h, fill=_gradient(defs, "bg-studio"))
    element(layer, "ellipse", cx=figure.chin_x, cy=figure.chin_y, rx=w * SPOT[0], ry=h * SPOT[1],
            fill=_glow(defs, "bg-spot"))
    edge, middle = y + h * SWEEP_TOP, y + h * (SWEEP_TOP + SWEEP_BOW)
    element(layer, "path", d=f"M{_num(x)},{_num(edge)}Q{_num(x + w / 2)},{_num(2 * middle - edge)} {_num(x + w)},{_num(edge)}"
            f"V{_num(y + h)}H{_num(x)}Z", fill=_gradient(defs, "bg-sweep"))
    width, height, top = SOFTBOX
    for centre in SOFTBOXES:
        cx, box_w, box_top = x + w * centre, w * width, y + h * top
        foot = y + h * STAND_FOOT
        stand = element(layer, "path", d=f"M{_num(cx)},{_num(box_top + h * height)}V{_num(foot)}"
                        f"M{_num(cx - w * STAND_SPREAD)},{_num(y + h)}L{_num(cx)},{_num(foot)}L{_num(cx + w * STAND_SPREAD)},{_num(y + h)}",
                        fill="none", stroke=COLOURS["stand"], stroke_width=w * STAND_LINE)
        stand.set("stroke-linecap", "round")
        depth = box_w * SOFTBOX_DEPTH
        element(layer, "path", d=_points((cx - box_w / 2 - depth, box_top - depth), (cx + box_w / 2 + depth, box_top - depth),
                                         (cx + box_w / 2, box_top + h * height), (cx - box_w / 2, box_top + h * height)),
                fill=COLOURS["softbox"])
        element(layer, "rect", x=cx - box_w / 2, y=box_top, width=box_w, height=h * height, rx=w * CORNER,
                fill=COLOURS["softbox face"])
        element(layer, "rect", x=cx - box_w / 2, y=box_top, width=box_w, height=h * height, rx=w * CORNER,
                fill=_glow(defs, "bg-softbox"))


def _classroom(layer: etree._Element, box: tuple[float, float, float, float], defs: etree._Element) -> None:
    """A classroom into `layer` over `box`: a chalkboard with writing and a diagram in a wooden
    frame with its chalk tray, on a cream wall over a wooden wainscot and the floor."""
    x, y, w, h = box
    element(layer, "rect", x=x, y=y, width=w, height=h, fill=COLOURS["classroom wall"])
    wood = _gradient(defs, "bg-wood")
    element(layer, "rect", x=x, y=y + h * WAINSCOT[0], width=w, height=h * WAINSCOT[1], fill=wood)
    element(layer, "rect", x=x + w * FRAME[0], y=y + h * FRAME[1], width=w * FRAME[2], height=h * FRAME[3],
            rx=w * CORNER, fill=COLOURS["board frame"])
    element(layer, "rect", x=x + w * BOARD[0], y=y + h * BOARD[1], width=w * BOARD[2], height=h * BOARD[3],
            fill=_gradient(defs, "bg-board"))
    tray_y = y + h * (FRAME[1] + FRAME[3])
    element(layer, "rect", x=x + w * FRAME[0], y=tray_y, width=w * FRAME[2], height=h * TRAY, fill=wood)
    for left, length in CHALK_STICKS:
        element(layer, "rect", x=x + w * left, y=tray_y - h * TRAY / 2, width=w * length, height=h * TRAY / 2,
                fill=COLOURS["chalk"])
    element(layer, "rect", x=x + w * ERASER[0], y=tray_y - h * ERASER[2], width=w * ERASER[1], height=h * ERASER[2],
            fill=COLOURS["eraser"])
    strokes = []
    for row, (left, top, count) in enumerate(WRITING_ROWS):
        for k in range(count):
            cx, cy, size = x + w * (left + k * CELL_PITCH), y + h * top, w * CELL
            for j in range(STROKES_PER_CHARACTER):  # a different choice of strokes in each cell
                (u0, v0), (u1, v1) = STROKES[(row * 5 + k * 2 + j * 3) % len(STROKES)]
                strokes.append(f"M{_num(cx + size * u0)},{_num(cy + size * v0)}L{_num(cx + size * u1)},{_num(cy + size * v1)}")
    (ax, ay), (bx, by), (tx, ty) = DIAGRAM
    strokes.append(_points((x + w * ax, y + h * ay), (x + w * bx, y + h * by), (x + w * tx, y + h * ty)))
    chalk = element(layer, "g", fill="none", stroke=COLOURS["chalk"], stroke_width=w * CHALK_LINE, opacity=CHALK_OPACITY)
    chalk.set("stroke-linecap", "round")
    element(chalk, "path", d="".join(strokes))
    cx, cy, r = DIAGRAM_CIRCLE
    element(chalk, "circle", cx=x + w * cx, cy=y + h * cy, r=h * r)
    element(layer, "rect", x=x, y=y + h * FLOOR_TOP, width=w, height=h * FLOOR_HEIGHT, fill=COLOURS["floor"])


def desk_layer(background: str, figure: Figure, defs: etree._Element) -> etree._Element | None:
    """The news desk in front of the body as a `<g id="desk">` for the "newsroom" background
    (None for the others): a lit top edge DESK_DROP fw below the shoulder line across
    DESK_SPAN of the picture, its front with an accent line; None when that is below the
    picture."""
    x, y, w, h = figure.box
    top = neck_pivot(figure) + figure.face_width * DESK_DROP
    if background != "newsroom" or top >= y + h:  # none, or below the picture (a portrait's)
        return None
    left, right = x + w * DESK_SPAN[0], x + w * DESK_SPAN[1]
    layer = element(None, "g", id="desk")
    element(layer, "rect", x=left, y=top + h * DESK_EDGE, width=right - left, height=y + h - top,
            fill=_gradient(defs, "bg-desk"))
    element(layer, "rect", x=left, y=top, width=right - left, height=h * DESK_EDGE, rx=h * DESK_EDGE / 2,
            fill=_gradient(defs, "bg-desk-top"))
    element(layer, "rect", x=left, y=top + h * (DESK_EDGE + DESK_ACCENT), width=right - left, height=h * DESK_ACCENT_LINE,
            fill=COLOURS["desk accent"])
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


def neck_middle(figure: Figure, degrees: float, height: float | np.ndarray) -> float | np.ndarray:
    """The x (pixels) of the middle of the neck leaned by `degrees` (lean) at `height` pixels
    (a float, or an array of heights: an array of the same shape)."""
    return figure.chin_x + math.tan(math.radians(degrees)) * (height - neck_pivot(figure))


def lean_transform(figure: Figure, degrees: float) -> str:
    """An SVG transform leaning the neck by `degrees` (lean) about neck_pivot."""
    pivot = _num(neck_pivot(figure))
    return f"translate(0 {pivot}) skewX({decimal_text(degrees, LEAN_DECIMALS)}) translate(0 -{pivot})"


def torso_pivot(figure: Figure) -> tuple[float, float]:
    """The point (x, y) pixels the torso leans about: under the chin, TORSO_PIVOT fw below the shoulder line."""
    return figure.chin_x, neck_pivot(figure) + figure.face_width * TORSO_PIVOT


def torso_shift(figure: Figure, turn: np.ndarray, breath: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pixels the torso moves for its `turn` ((n,) degrees, animate/body.py) and the `breath`
    ((n,) depth 0..1): (dx, dy) of the torso, dy of the neck (y down: a breath is negative)."""
    fw = figure.face_width
    dx = fw * TORSO_DEPTH * np.sin(np.radians(np.asarray(turn, dtype=float)))
    dy = -fw * BREATH_RISE * np.asarray(breath, dtype=float)
    return dx, dy, NECK_BREATH * dy


def chin_shadows(figure: Figure, chins: np.ndarray, middles: np.ndarray, paint: str = "",
                 tenths: dict[str, np.ndarray] | None = None) -> list[str]:
    """The jaw's shadow on the neck for each posed chin 2.1 of `chins` (S, 2) pixels, the
    text of one SVG element (no namespace declaration) with the attribute text `paint` (' fill="..."',
    class, opacity) after its outline's: an ellipse centred on the chin, SHADOW_WIDTH of the
    neck wide and JAW_SHADOW fw high (the face drawn over it hides its top half). Where it would
    pass a side of the neck (whose middle at the chin's height is in `middles` (S,), neck_middle), a
    polygon of SHADOW_POINTS corners cut at that side instead; corner SHADOW_POINTS // 4 is its
    lowest point, right under the chin while the chin is over the neck. Numbers are written as
    `_num` writes them; the corners of all cut ones are computed together and written by
    _shadow_data (the hot path of an animation), which hands `tenths` on."""
    half = figure.face_width * NECK
    lefts, rights = middles - half, middles + half
    rx, ry = half * SHADOW_WIDTH, figure.face_width * JAW_SHADOW
    inside = ((lefts <= chins[:, 0] - rx) & (chins[:, 0] + rx <= rights)).tolist()
    cx = np.clip(chins[:, 0], lefts, rights)  # a chin beyond a side of the neck: on that side
    # clamping x cuts an upright ellipse exactly at the sides: beyond a side it is no taller than there
    corners = np.empty((len(chins), SHADOW_POINTS, 2))
    corners[:, :, 0] = np.clip(cx[:, None] + rx * _SHADOW_COS, lefts[:, None], rights[:, None])
    corners[:, :, 1] = chins[:, 1, None] + ry * _SHADOW_SIN
    cut = [index for index, whole in enumerate(inside) if not whole]
    written = iter(_shadow_data(corners[cut].reshape(len(cut), 2 * SHADOW_POINTS), tenths))
    return [f'<ellipse cx="{_num(x)}" cy="{_num(y)}" rx="{_num(rx)}" ry="{_num(ry)}"{paint}/>' if whole
            else f'<path d="{next(written)}"{paint}/>' for (x, y), whole in zip(chins.tolist(), inside, strict=True)]


def _shadow_data(numbers: np.ndarray, tenths: dict[str, np.ndarray] | None = None) -> list[str]:
    """The path data of cut shadows (`numbers` (n, 2 SHADOW_POINTS): each one's corners x, y pixels) as
    _short_tenths(_SHADOW_TEMPLATE % row) writes them: from whole tenths by one numbers.tenths_texts,
    but a row with a number under 1 px ("0.5" is ".5" there) or a tenth rounded from a half by the
    %-format (which rounds the exact binary value: the product rounded_tenths rounds lies on the same
    side of every half but where it is one). `tenths` gets the rows written from tenths (pathdata.Tenths)."""
    rounded = rounded_tenths(numbers)
    scaled = numbers * TENTHS
    plain = ~np.any(scaled - np.floor(scaled) == 0.5, axis=1) & np.all(np.abs(rounded) >= TENTHS, axis=1)
    texts, width = tenths_texts(rounded[plain]), numbers.shape[1]
    written = iter([fill(_SHADOW_FRAME, texts[start:start + width]) for start in range(0, len(texts), width)])
    data = []
    for row, alike in zip(numbers.tolist(), plain.tolist(), strict=True):
        data.append(next(written) if alike else _short_tenths(_SHADOW_TEMPLATE % tuple(row)))
    if tenths is not None:
        tenths.update(zip([d for d, alike in zip(data, plain.tolist(), strict=True) if alike], rounded[plain],
                          strict=True))
    return data


Point = tuple[float, float | None]


def _at(figure: Figure, point: Point, mirror: bool = False) -> tuple[float, float]:
    """Pixels of a garment point (u, v) (see TORSO), mirrored to the other side if `mirror`."""
    u, v = point
    _, y, _, h = figure.box
    fw = figure.face_width
    bottom = y + h + fw  # past the bottom edge: the body leaves the picture
    return figure.chin_x + (-u if mirror else u) * fw * NECK, bottom if v is None else neck_pivot(figure) + fw * v


def _xy(figure: Figure, point: Point, mirror: bool = False) -> str:
    """A garment point as path data "x,y"."""
    px, py = _at(figure, point, mirror)
    return f"{_num(px)},{_num(py)}"


def _symmetric(figure: Figure, shape: tuple) -> str:
    """Closed path data of a shape symmetric about the middle, from its image-left half
    `shape` = (start, pieces...) (see TORSO): that half, then the other side back to the start."""
    start, pieces = shape[0], shape[1:]
    ends = [start] + [piece[-1] for piece in pieces]
    d = "M" + _xy(figure, start) + "".join(piece[0] + " ".join(_xy(figure, p) for p in piece[1:]) for piece in pieces)
    for index in range(len(pieces) - 1, -1, -1):  # the mirror image, walked backwards
        piece, before = pieces[index], ends[index]
        if index == len(pieces) - 1:
            d += "L" + _xy(figure, piece[-1], True)
        if piece[0] == "C":
            d += "C" + " ".join(_xy(figure, p, True) for p in (piece[2], piece[1], before))
        else:
            d += "L" + _xy(figure, before, True)
    return d + "Z"


def _open(figure: Figure, shape: tuple, mirror: bool = False) -> str:
    """Path data of an open line `shape` = (start, pieces...) (see TORSO), mirrored if `mirror`."""
    start, pieces = shape[0], shape[1:]
    return "M" + _xy(figure, start, mirror) + "".join(
        piece[0] + " ".join(_xy(figure, p, mirror) for p in piece[1:]) for piece in pieces)


def _polygon(figure: Figure, points: tuple, mirror: bool = False) -> str:
    """Closed path data through garment `points`, mirrored if `mirror`."""
    return _points(*(_at(figure, point, mirror) for point in points))


def clothes_layer(name: str, figure: Figure, defs: etree._Element) -> etree._Element:
    """The clothes `name` (one of CLOTHES) with neck and shoulders under the chin as a `<g id="clothes">`;
    "none" is the neck alone, down past the picture's bottom, so the head never floats. The neck
    is the layer's first child, an upright path of class "neck" that the caller leans with the
    head (lean, lean_transform); the rest is the torso (render/animation.py moves it with the
    breath and the head, animate/body.py). The jaw's shadow is the face's (render/svg.py,
    chin_shadow): it moves with the chin. Sizes are fractions of the face width fw (the body
    constants above, and the garments' tables)."""
    if name not in CLOTHES:
        raise OptionError(f"clothes {name!r}: expected one of {', '.join(CLOTHES)}")
    x, y, w, h = figure.box
    cx, chin, fw = figure.chin_x, figure.chin_y, figure.face_width
    bottom = y + h + fw  # past the bottom edge: the body leaves the picture
    neck = fw * NECK
    layer = element(None, "g", id="clothes")
    foot = bottom if name == "none" else neck_pivot(figure) + fw * NECK_FOOT
    element(layer, "path", {"class": "neck"}, d=_points((cx - neck, chin - fw * NECK_TOP), (cx + neck, chin - fw * NECK_TOP),
                                                        (cx + neck, foot), (cx - neck, foot)),
            fill=figure.skin)
    if name == "none":
        return layer
    element(layer, "path", d=_symmetric(figure, TORSO), fill=_gradient(defs, f"cl-{name}"))
    seam = SLEEVE_SEAM if name != "sweater" else RAGLAN
    seams = element(layer, "path", d=_open(figure, seam) + _open(figure, seam, True), fill="none",
                    stroke=COLOURS["suit seam"], stroke_width=fw * LINE, opacity=SEAM_OPACITY)
    seams.set("stroke-linecap", "round")
    line = {"stroke-width": _num(fw * LINE), "stroke-linejoin": "round"}
    shadow_x, shadow_y = _at(figure, (0.0, 0.0))
    shadow: dict[str, str | float] = {"cx": shadow_x, "cy": shadow_y, "rx": neck * NECK_SHADOW[0], "ry": fw * NECK_SHADOW[1],
              "fill": _glow(defs, "cl-neck-shadow")}
    if name == "suit":
        element(layer, "path", d=_symmetric(figure, SHIRT_FRONT), fill=_gradient(defs, "cl-shirt-front"))
        element(layer, "ellipse", **shadow)
        element(layer, "path", d=_symmetric(figure, TIE), fill=_gradient(defs, "cl-tie"))
        element(layer, "path", d=_symmetric(figure, TIE_KNOT), fill=_gradient(defs, "cl-tie"))
        for mirror in (False, True):
            element(layer, "path", {**line}, d=_polygon(figure, SUIT_COLLAR, mirror), fill=COLOURS["collar"],
                    stroke=COLOURS["collar line"])
        for mirror in (False, True):
            element(layer, "path", {**line}, d=_polygon(figure, LAPEL, mirror), fill=COLOURS["lapel"],
                    stroke=COLOURS["lapel edge"])
        bx, by = _at(figure, BUTTON[:2])
        element(layer, "circle", cx=bx, cy=by, r=fw * BUTTON[2], fill=COLOURS["button"])
        element(layer, "path", d=_polygon(figure, POCKET_SQUARE), fill=COLOURS["collar"])
        element(layer, "path", d="M" + _xy(figure, POCKET[0]) + "L" + _xy(figure, POCKET[1]), fill="none",
                stroke=COLOURS["suit seam"], stroke_width=fw * LINE * 2)
    elif name == "shirt":
        element(layer, "ellipse", **shadow)
        element(layer, "path", d=_symmetric(figure, OPEN_NECK), fill=figure.skin)
        px, py = _at(figure, OPEN_NECK[-1][-1])
        element(layer, "path", d=f"M{_num(px)},{_num(py)}V{_num(bottom)}", fill="none", stroke=COLOURS["placket"],
                stroke_width=fw * LINE * 2)
        for v in SHIRT_BUTTONS:
            bx, by = _at(figure, (0.0, v))
            element(layer, "circle", cx=bx, cy=by, r=fw * BUTTON[2] * 0.7, fill=COLOURS["shirt button"],
                    stroke=COLOURS["placket"], stroke_width=fw * LINE / 2)
        u, v, width, height = SHIRT_POCKET
        px, py = _at(figure, (u, v))
        element(layer, "rect", x=px, y=py, width=width * neck, height=fw * height, fill="none",
                stroke=COLOURS["placket"], stroke_width=fw * LINE)
        for mirror in (False, True):
            element(layer, "path", {**line}, d=_polygon(figure, SHIRT_COLLAR, mirror), fill=COLOURS["shirt collar"],
                    stroke=COLOURS["shirt collar line"])
    else:  # sweater: a ribbed round neck with a shirt collar over it
        element(layer, "ellipse", **shadow)
        (ax, ay), (qx, qy), (bx, by) = (_at(figure, point) for point in RIB)
        rib = f"M{_num(ax)},{_num(ay)}Q{_num(qx)},{_num(qy)} {_num(bx)},{_num(by)}"
        element(layer, "path", d=rib, fill="none", stroke=COLOURS["rib"], stroke_width=fw * RIB_WIDTH,
                stroke_linecap="round")
        element(layer, "path", d=rib, fill="none", stroke=COLOURS["rib line"], stroke_width=fw * RIB_WIDTH * 0.8,
                stroke_dasharray=f"{_num(fw * RIB_DASH / 3)} {_num(fw * RIB_DASH * 2 / 3)}")
        for mirror in (False, True):
            element(layer, "path", {**line}, d=_polygon(figure, SWEATER_COLLAR, mirror), fill=COLOURS["collar"],
                    stroke=COLOURS["collar line"])
    return layer
