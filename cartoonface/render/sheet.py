"""The contact sheet (`cartoonface face sheet`): a grid of heads, poses and expressions
by rows, the basic mouth shapes by columns (docs/drawing.md)."""

from __future__ import annotations

import numpy as np
from lxml import etree

from cartoonface.face.lift import lift
from cartoonface.face.model import FaceModel
from cartoonface.face.pose import pose_face
from cartoonface.face.state import FaceState
from cartoonface.render.elements import element, svg_root
from cartoonface.render.numbers import number_text
from cartoonface.render.scenery import LEAN_DECIMALS, NECK, figure_of, lean, lean_transform
from cartoonface.render.svg import OUTLINE, face_defs, face_group


def head_box(face: FaceModel) -> tuple[float, float, float, float]:
    """(x, y, width, height) around the hair and the head of `face`, with room for a head
    turned, tilted or rolled by 15 degrees."""
    points = np.concatenate([face.points, face.hair])
    low, high = points.min(axis=0), points.max(axis=0)
    margin = 0.55 * face.fapu.d
    return low[0] - margin, low[1] - margin, high[0] - low[0] + 2 * margin, high[1] - low[1] + 2 * margin


def _neck(face: FaceModel, bottom: float) -> etree._Element:
    """A plain neck under the chin down to `bottom` (the sheet's heads have no body): the
    width of render/scenery.py's neck, its top hidden behind the jaw in every pose; each head
    leans it to stay under its chin (scenery's lean)."""
    chin = face.point("2.1")
    half = NECK * float(np.ptp(face.points[:, 0]))
    top = float(chin[1]) - 0.6 * face.fapu.d
    corners = ((chin[0] - half, bottom), (chin[0] - half, top), (chin[0] + half, top), (chin[0] + half, bottom))
    d = "M" + "L".join(f"{number_text(x)} {number_text(y)}" for x, y in corners)  # open: no line at the bottom
    return element(None, "path", {"class": "neck", "d": d, "fill": face.palette.skin, "stroke": face.palette.outline,
                                  "stroke-width": number_text(OUTLINE * face.fapu.d)})


def sheet_svg(face: FaceModel, rows: list[tuple[str, list[FaceState]]], columns: list[str],
              cell_width: float) -> etree._Element:
    """A contact sheet: a grid of heads (hair and face layers), one row per (label, states)
    of `rows` (a label may hold several lines, split at "\n"), each column headed by its label
    in `columns`, cells `cell_width` pixels wide. Returns the SVG root."""
    x0, y0, w, h = head_box(face)
    scale = cell_width / w
    cell_height = h * scale
    font = max(11.0, cell_width * 0.12)
    gap = cell_width * 0.05
    longest = max(len(line) for label, _ in rows for line in label.split("\n"))
    left_margin, top_margin = font * (0.62 * longest + 1), font * 2
    pitch_x, pitch_y = cell_width + gap, cell_height + gap
    width = left_margin + len(columns) * pitch_x + gap
    height = top_margin + len(rows) * pitch_y + gap
    root = svg_root({"width": number_text(width), "height": number_text(height),
                     "viewBox": f"0 0 {number_text(width)} {number_text(height)}"})
    element(root, "defs", {}).extend(face_defs(face))
    element(root, "rect", {"width": "100%", "height": "100%", "fill": "#ffffff"})
    text_style = {"font-family": "DejaVu Sans, sans-serif", "font-size": number_text(font), "fill": "#333333"}
    for j, label in enumerate(columns):
        element(root, "text", {"x": number_text(left_margin + j * pitch_x + cell_width / 2),
                               "y": number_text(font * 1.4), "text-anchor": "middle", **text_style}).text = label
    lifted = lift(face)
    neck = _neck(face, y0 + h)
    figure = figure_of(face, (x0, y0, w, h))
    for i, (label, states) in enumerate(rows):
        top = top_margin + i * pitch_y
        lines = label.split("\n")
        caption = element(root, "text", {"text-anchor": "end", **text_style})
        for k, line in enumerate(lines):
            element(caption, "tspan", {"x": number_text(left_margin - gap * 2),
                                       "y": number_text(top + cell_height / 2 + font * (1.25 * k - 0.6 * len(lines) + 1))
                                       }).text = line
        for j, state in enumerate(states):
            left = left_margin + j * pitch_x
            element(root, "rect", {"x": number_text(left), "y": number_text(top), "width": number_text(cell_width),
                                   "height": number_text(cell_height), "rx": number_text(cell_width * 0.04),
                                   "fill": "#f1ede6"})
            leaning = round(lean(figure, lifted.origin, state.pose.roll), LEAN_DECIMALS)
            head = face_group(face, pose_face(lifted, state), f"s{i}-{j}", leaning)
            leaned = etree.fromstring(etree.tostring(neck))
            leaned.set("transform", lean_transform(figure, leaning))
            head.insert(2, leaned)  # after the <defs> and the hair
            head.set("transform", f"translate({number_text(left - x0 * scale)} {number_text(top - y0 * scale)}) "
                                  f"scale({scale:.5g})")
            root.append(head)
    return root
