"""Reused drawings shown in the page by moving their source (render/moved.py): the page shows, at every
key time of every track, the drawing the written animation shows, under the same transform."""

from __future__ import annotations

import bisect
import math

import numpy as np
from lxml import etree

from cartoonface.render.animation import animation_svg
from cartoonface.render.moved import KINDS, affine_steps
from cartoonface.render.pages import inline_svg
from tests.test_reuse import face, nodding  # noqa: F401 (face: the module fixture)

S = "{http://www.w3.org/2000/svg}"
FPS = 30


def step_matrix(kind: str, value: str) -> np.ndarray:
    """SVG's `kind`(value) transform as a (3, 3) matrix."""
    numbers = [float(v) for v in value.split(",")]
    if kind == "translate":
        return np.array([[1, 0, numbers[0]], [0, 1, numbers[1] if len(numbers) > 1 else 0], [0, 0, 1]])
    if kind == "scale":
        return np.diag([numbers[0], numbers[-1], 1.0])
    angle = math.radians(numbers[0])
    if kind == "skewX":
        return np.array([[1, math.tan(angle), 0], [0, 1, 0], [0, 0, 1]])
    return np.array([[math.cos(angle), -math.sin(angle), 0], [math.sin(angle), math.cos(angle), 0], [0, 0, 1]])


def matrix_of(text: str) -> np.ndarray:
    """matrix(a b c d e f)'s numbers (text) as a (3, 3) matrix."""
    a, b, c, d, e, f = (float(v) for v in text.split())
    return np.array([[a, c, e], [b, d, f], [0, 0, 1]])


def test_the_steps_compose_to_the_matrix():
    rng = np.random.default_rng(5)
    for _ in range(200):
        linear = np.eye(2) + rng.normal(0, 0.05, (2, 2)) if _ % 2 else rng.normal(0, 1, (2, 2))
        if np.linalg.det(linear) <= 0:
            linear[:, 0] *= -1
        shift = rng.normal(0, 30, 2)
        text = " ".join(f"{v:.4f}" for v in (*linear[:, 0], *linear[:, 1], *shift))
        product = np.eye(3)
        for kind, value in zip(KINDS, affine_steps(text), strict=True):
            product = product @ step_matrix(kind, value)
        # a point 400 px out lands within 0.01 px
        assert np.abs(product - matrix_of(text)).max() * 400 < 0.01, text


def shown(track: etree._Element) -> list[tuple[str, str | None, np.ndarray]]:
    """(drawing id, its data-shape, transform) the track's `<use>` shows at each of its key times,
    the drawing resolved through a reused drawing (`<use href transform>`) of its `<defs>`."""
    defs = {node.get("id"): node for node in track.find(f"{S}defs")}
    use = track.find(f"{S}use")
    animate = use.find(f"{S}animate")
    moves = use.findall(f"{S}animateTransform")
    rows = []
    times = [float(time) for time in animate.get("keyTimes").split(";")]
    for time, value in zip(times, animate.get("values").split(";"), strict=True):
        matrix = np.eye(3)
        for move in moves:
            # discrete: the value of the last key time at or before `time`
            at = bisect.bisect_right([float(t) for t in move.get("keyTimes").split(";")], time) - 1
            matrix = matrix @ step_matrix(move.get("type"), move.get("values").split(";")[at])
        drawing = defs[value[1:]]
        shape = drawing.get("data-shape")
        if drawing.tag == f"{S}use":
            matrix = matrix @ matrix_of(drawing.get("transform")[7:-1])
            drawing = defs[drawing.get("href")[1:]]
        rows.append((drawing.get("id"), shape or drawing.get("data-shape"), matrix))
    return rows


def test_the_page_shows_the_written_drawings_moved_alike(face):  # noqa: F811
    written = animation_svg(face, nodding(3 * FPS), FPS)
    page = etree.fromstring(str(inline_svg(written)).encode("utf-8"))
    tracks = {t.get("data-part"): t for t in etree.fromstring(written).iter(f"{S}g")
              if t.get("data-part") and t.find(f"{S}defs") is not None}
    reused = sum(1 for t in tracks.values() for node in t.find(f"{S}defs") if node.tag == f"{S}use")
    assert reused > 10, "the input should have reused drawings"
    left = 0
    for track in page.iter(f"{S}g"):
        if track.get("data-part") not in tracks:
            continue
        before, after = shown(tracks[track.get("data-part")]), shown(track)
        assert len(before) == len(after)
        for (name, shape, matrix), (name_now, shape_now, matrix_now) in zip(before, after, strict=True):
            assert (name_now, shape_now) == (name, shape)
            assert np.abs(matrix_now - matrix).max() * 400 < 0.01
        left += sum(1 for node in track.find(f"{S}defs") if node.tag == f"{S}use" and node.get("id"))
    # only reused mouths of another basic shape than their source's stay as written
    assert left < reused / 5
