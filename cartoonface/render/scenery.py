"""Background and clothes layers of the virtual announcer (thesis 002, 6.3.1 and 7.2).

The thesis draws four layers, background, hair, clothes and face (its Figs. 6.7,
6.8, 7.2 and 7.3 show a studio backdrop and a suit; the figures themselves are
lost in the text). These are our own drawings: three backgrounds and three
clothes, plus "plain" and "none", each a few SVG shapes with gradients. They do
not move: the body stays still while the head tilts, turns and nods.

Geometry comes from a `Figure`: where the chin is and how wide the face is, so
the neck and shoulders fit any face model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from lxml import etree

from cartoonface.errors import OptionError
from cartoonface.face.model import FaceModel
from cartoonface.render.elements import DECIMALS, element
from cartoonface.render.numbers import decimal_text

BACKGROUNDS = ("studio", "newsroom", "classroom", "plain")
CLOTHES = ("suit", "shirt", "sweater", "none")


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


def _gradient(defs: etree._Element, gid: str, stops: tuple[tuple[float, str], ...], vertical: bool = True) -> str:
    """Add a linear gradient `gid` with (offset 0..1, colour) `stops` to `defs`; return its url()."""
    grad = element(defs, "linearGradient", id=gid, x1="0", y1="0", x2="0" if vertical else "1", y2="1" if vertical else "0")
    for offset, colour in stops:
        element(grad, "stop", offset=f"{offset:g}", stop_color=colour)
    return f"url(#{gid})"


def background_layer(name: str, figure: Figure, defs: etree._Element) -> etree._Element:
    """The background `name` (one of BACKGROUNDS) as a `<g>` filling `figure.box`; gradients go into `defs`."""
    if name not in BACKGROUNDS:
        raise OptionError(f"background {name!r}: expected one of {', '.join(BACKGROUNDS)}")
    x, y, w, h = figure.box
    layer = element(None, "g", id="background")
    if name == "plain":
        element(layer, "rect", x=x, y=y, width=w, height=h, fill="#f3efe6")
    elif name == "studio":
        element(layer, "rect", x=x, y=y, width=w, height=h,
            fill=_gradient(defs, "bg-studio", ((0, "#1e3a8a"), (0.7, "#0f172a"), (1, "#020617"))))
        for k in range(5):  # light panels behind the announcer
            px = x + w * (0.04 + 0.2 * k)
            element(layer, "rect", x=px, y=y + h * 0.08, width=w * 0.12, height=h * 0.5, rx=w * 0.01,
                fill="#3b82f6", opacity="0.18")
        element(layer, "rect", x=x, y=y + h * 0.78, width=w, height=h * 0.22,
            fill=_gradient(defs, "bg-desk", ((0, "#475569"), (1, "#1e293b"))))
    elif name == "newsroom":
        element(layer, "rect", x=x, y=y, width=w, height=h,
            fill=_gradient(defs, "bg-dusk", ((0, "#fb923c"), (0.55, "#7c3aed"), (1, "#1e1b4b"))))
        heights = (0.35, 0.55, 0.42, 0.7, 0.5, 0.62, 0.38, 0.58, 0.45, 0.66)
        step = w / len(heights)
        for k, tall in enumerate(heights):  # a city skyline
            element(layer, "rect", x=x + k * step, y=y + h * (1 - tall), width=step * 0.92, height=h * tall, fill="#1e1b4b",
                opacity="0.85")
            for row in range(int(tall * 10)):
                element(layer, "rect", x=x + k * step + step * 0.2, y=y + h * (1 - tall + 0.05 + row * 0.08),
                    width=step * 0.5, height=h * 0.02, fill="#fde68a", opacity="0.5")
    else:  # classroom: a chalkboard in a wooden frame on a cream wall
        element(layer, "rect", x=x, y=y, width=w, height=h, fill="#efe6d2")
        element(layer, "rect", x=x + w * 0.05, y=y + h * 0.06, width=w * 0.9, height=h * 0.55, rx=w * 0.01, fill="#8b5a2b")
        element(layer, "rect", x=x + w * 0.07, y=y + h * 0.085, width=w * 0.86, height=h * 0.5,
            fill=_gradient(defs, "bg-board", ((0, "#2f5d3a"), (1, "#1f3d27"))))
        for k, (u, v) in enumerate(((0.12, 0.2), (0.7, 0.3), (0.15, 0.45))):  # chalk marks
            element(layer, "path", d=_points((x + w * u, y + h * v), (x + w * (u + 0.15), y + h * (v - 0.02 * k))),
                stroke="#e5e7eb", stroke_width=w * 0.004, fill="none", opacity="0.7")
        element(layer, "rect", x=x, y=y + h * 0.8, width=w, height=h * 0.2, fill="#c8b48c")
    return layer


def clothes_layer(name: str, figure: Figure, defs: etree._Element) -> etree._Element | None:
    """The clothes `name` (one of CLOTHES) with neck and shoulders under the chin as a `<g>`, or None for "none"."""
    if name not in CLOTHES:
        raise OptionError(f"clothes {name!r}: expected one of {', '.join(CLOTHES)}")
    if name == "none":
        return None
    x, y, w, h = figure.box
    cx, chin, fw = figure.chin_x, figure.chin_y, figure.face_width
    bottom = y + h + fw  # past the bottom edge: the body leaves the picture
    neck = fw * 0.22  # half the neck's width
    shoulder_y = chin + fw * 0.35
    spread = fw * 1.25  # half the shoulders' width
    layer = element(None, "g", id="clothes")
    # The neck starts well above the chin so the jaw covers its top while the head moves.
    element(layer, "path", d=_points((cx - neck, chin - fw * 0.3), (cx + neck, chin - fw * 0.3),
                                 (cx + neck, shoulder_y + fw * 0.1), (cx - neck, shoulder_y + fw * 0.1)),
        fill=figure.skin)
    # The jaw's shadow on the neck: the face covers the top half of this ellipse.
    element(layer, "ellipse", cx=cx, cy=chin, rx=neck, ry=fw * 0.07, fill="#000", opacity="0.12")
    body = ((cx - spread, bottom), (cx - spread, shoulder_y + fw * 0.25), (cx - neck * 2.2, shoulder_y),
            (cx + neck * 2.2, shoulder_y), (cx + spread, shoulder_y + fw * 0.25), (cx + spread, bottom))
    if name == "suit":
        element(layer, "path", d=_points(*body), fill=_gradient(defs, "cl-suit", ((0, "#334155"), (1, "#0f172a"))))
        element(layer, "path", d=_points((cx - neck * 1.6, shoulder_y - fw * 0.02), (cx + neck * 1.6, shoulder_y - fw * 0.02),
                                     (cx, shoulder_y + fw * 0.7)), fill="#f8fafc")  # shirt front
        element(layer, "path", d=_points((cx - neck * 0.35, shoulder_y + fw * 0.06), (cx + neck * 0.35, shoulder_y + fw * 0.06),
                                     (cx + neck * 0.5, shoulder_y + fw * 0.55), (cx, shoulder_y + fw * 0.68),
                                     (cx - neck * 0.5, shoulder_y + fw * 0.55)), fill="#b91c1c")  # tie
        for side in (-1, 1):  # lapels
            element(layer, "path", d=_points((cx + side * neck * 1.6, shoulder_y - fw * 0.02),
                                         (cx + side * neck * 0.2, shoulder_y + fw * 0.75),
                                         (cx + side * neck * 2.6, shoulder_y + fw * 0.3)), fill="#1e293b")
    elif name == "shirt":
        element(layer, "path", d=_points(*body), fill=_gradient(defs, "cl-shirt", ((0, "#bfdbfe"), (1, "#60a5fa"))))
        element(layer, "path", d=_points((cx - neck, shoulder_y - fw * 0.02), (cx + neck, shoulder_y - fw * 0.02),
                                     (cx, shoulder_y + fw * 0.3)), fill=figure.skin)  # open collar
        for side in (-1, 1):
            element(layer, "path", d=_points((cx + side * neck * 1.1, shoulder_y - fw * 0.08), (cx, shoulder_y + fw * 0.3),
                                         (cx + side * neck * 2.4, shoulder_y + fw * 0.12)),
                fill="#eff6ff", stroke="#93c5fd", stroke_width=fw * 0.01)
        element(layer, "path", d=f"M{_num(cx)},{_num(shoulder_y + fw * 0.3)}V{_num(bottom)}",
            stroke="#3b82f6", stroke_width=fw * 0.012, fill="none")
    else:  # sweater: round neck, ribbed collar
        element(layer, "path", d=_points(*body), fill=_gradient(defs, "cl-sweater", ((0, "#16a34a"), (1, "#14532d"))))
        left, right, dip = cx - neck * 1.3, cx + neck * 1.3, shoulder_y + fw * 0.12
        element(layer, "path", d=f"M{_num(left)},{_num(shoulder_y)}Q{_num(cx)},{_num(dip)} {_num(right)},{_num(shoulder_y)}",
            fill="none", stroke="#166534", stroke_width=fw * 0.05, stroke_linecap="round")  # ribbed collar
    return layer
