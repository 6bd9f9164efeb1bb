"""The labelled point diagram of a face model (`cartoonface face diagram`, docs/face-model.md)."""

from __future__ import annotations

import numpy as np
from lxml import etree

from cartoonface.face.lift import LIFTED_NAMES, lift
from cartoonface.face.model import POINT_NAMES, FaceModel
from cartoonface.face.pose import pose_face
from cartoonface.face.state import FaceState
from cartoonface.render.elements import element, svg_root
from cartoonface.render.numbers import number_text
from cartoonface.render.sheet import head_box
from cartoonface.render.svg import face_defs, face_group


def diagram_svg(face: FaceModel, scale: float = 3.0) -> etree._Element:
    """The labelled point diagram of `face` (docs/face-model.md): the frontal drawing faded,
    every model point (black), additional point A..S (red, thesis 002 Alg. 2.1) and hair
    point (blue, numbered from 0) with its name; points at the same place share a label.
    Labels are placed greedily where they overlap no other label or point, with a leader
    line when pushed away. The picture shows the head `scale` times its model size.
    Returns the SVG root."""
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
    x0, y0, w, h = head_box(face)
    x0, y0, w, h = x0 - 4 * font, y0 - 2 * font, w + 8 * font, h + 4 * font
    root = svg_root({"width": number_text(w * scale), "height": number_text(h * scale),
                     "viewBox": " ".join(number_text(v) for v in (x0, y0, w, h))})
    element(root, "defs", {}).extend(face_defs(face))
    element(root, "rect", {"x": number_text(x0), "y": number_text(y0), "width": "100%", "height": "100%",
                           "fill": "#ffffff"})
    drawing = face_group(face, posed, "d")
    drawing.set("opacity", "0.35")
    root.append(drawing)
    marks = element(root, "g", {"font-family": "DejaVu Sans, sans-serif", "font-size": number_text(font)})
    taken = [(x - dot, y - dot, x + dot, y + dot) for x, y in groups]
    centre = posed.xy.mean(axis=0)
    for (x, y), names in groups.items():
        text = "/".join(names)
        box, anchor, (tx, ty) = _place_label(text, np.array([x, y]), centre, font, taken)
        taken.append(box)
        if np.hypot(tx - x, ty + 0.35 * font - y) > 1.6 * font:
            element(marks, "line", {"x1": number_text(x), "y1": number_text(y), "x2": number_text(tx),
                                    "y2": number_text(ty - 0.35 * font), "stroke": colour[(x, y)],
                                    "stroke-width": number_text(dot * 0.25), "opacity": "0.6"})
        element(marks, "circle", {"cx": number_text(x), "cy": number_text(y), "r": number_text(dot),
                                  "fill": colour[(x, y)]})
        element(marks, "text", {"x": number_text(tx), "y": number_text(ty), "text-anchor": anchor,
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
