"""The neck under every head and the jaw's shadow that follows the chin (issue 11)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from lxml import etree

from cartoonface.face.lift import lift
from cartoonface.face.model import load_face
from cartoonface.face.pose import pose_face
from cartoonface.face.state import FaceState, Pose
from cartoonface.render.animation import animation_svg
from cartoonface.render.scenery import CLOTHES, NECK, _points, _shadow_data, _short_tenths, chin_shadows, figure_of
from cartoonface.render.svg import face_svg
from tests.conftest import ROOT
from tests.shapes import NUMBER, polygon

SVG = "{http://www.w3.org/2000/svg}"
ANGLES = (-15.0, 0.0, 15.0)
POSES = [Pose(tilt, turn, roll) for tilt, turn, roll in itertools.product(ANGLES, ANGLES, ANGLES)]
NEAR = 0.05  # of the FAPU d: how far the shadow's centre may lie from the posed chin


@pytest.fixture(params=("female", "male"), scope="module")
def face(request):
    return load_face(ROOT / "samples" / "faces" / f"{request.param}.json")


def shadow_outline(group) -> np.ndarray:
    """Points (n, 2) around the face group's jaw shadow: an ellipse's, or a cut polygon's corners."""
    shadow = group.find(f"{SVG}*[@class='chin-shadow']")
    if shadow.tag == f"{SVG}ellipse":
        cx, cy, rx, ry = (float(shadow.get(name)) for name in ("cx", "cy", "rx", "ry"))
        angles = np.linspace(0, 2 * np.pi, 64, endpoint=False)
        return np.column_stack([cx + rx * np.cos(angles), cy + ry * np.sin(angles)])
    return polygon(shadow.get("d"))


def _layer(root, name):
    return root.find(f"{SVG}g[@id='{name}']")


@pytest.mark.parametrize("clothes", CLOTHES)
def test_every_clothes_option_has_a_neck_under_the_chin(face, clothes):
    root = face_svg(face, FaceState(pose=Pose(-15, 0, 0)), clothes=clothes)
    necks = _layer(root, "clothes").findall(f"{SVG}path[@class='neck']")
    assert len(necks) == 1
    corners = polygon(necks[0].get("d"))
    chin = face.point("2.1")
    low, high = corners.min(axis=0), corners.max(axis=0)
    assert low[0] < chin[0] < high[0]
    assert low[1] < chin[1] < high[1]  # its top behind the jaw, its foot below the chin
    assert necks[0].get("fill") == face.palette.skin
    if clothes == "none":  # nothing else to stand on: down past the picture's bottom
        assert high[1] >= face.height


def test_the_animation_with_no_clothes_has_the_neck(face):
    states = [FaceState(pose=Pose(0, 0, roll)) for roll in (-10.0, 0.0, 10.0)]
    root = etree.fromstring(animation_svg(face, states, 24, clothes="none", wide=True))
    neck = _layer(root, "clothes").find(f".//{SVG}path[@class='neck']")
    assert neck is not None
    skews = neck.getparent().find(f"{SVG}animateTransform[@type='skewX']").get("values").split(";")
    assert len(set(skews)) == 3 and float(skews[1]) == 0  # a lean for each roll, upright without roll
    assert float(skews[0]) * float(skews[2]) < 0  # leaning to either side


def test_the_jaw_shadow_follows_the_posed_chin(face):
    lifted = lift(face)
    d = face.fapu.d
    chins, centres = [], []
    for pose in POSES:
        state = FaceState(pose=pose)
        group = _layer(face_svg(face, state), "face")
        parts = [part.get("class") for part in group]
        assert parts.index("chin-shadow") < parts.index("face")  # the face hides the shadow's top half
        shadow = shadow_outline(group)
        lowest = shadow[np.argmax(shadow[:, 1])]
        centres.append((lowest[0], (shadow[:, 1].min() + shadow[:, 1].max()) / 2))  # right under the chin
        chins.append(pose_face(lifted, state).p("2.1"))
    chins_a, centres_a = np.array(chins), np.array(centres)
    # the poses move the chin far more than the tolerance, so a shadow fixed on the neck fails
    assert np.ptp(chins_a, axis=0).max() > 5 * NEAR * d
    assert np.linalg.norm(centres_a - chins_a, axis=1).max() < NEAR * d


def _leaned(root):
    """The neck's corners (4, 2) as drawn: its path under its lean transform (scenery's lean_transform)."""
    neck = _layer(root, "clothes").find(f"{SVG}path[@class='neck']")
    _, pivot, skew, _, _ = (float(v) for v in NUMBER.findall(neck.get("transform")))  # translate skewX translate
    corners = polygon(neck.get("d"))
    corners[:, 0] += np.tan(np.radians(skew)) * (corners[:, 1] - pivot)
    return corners


def _side_x(corners, side, y):
    """x of the neck's left (side 0) or right (side 1) edge at height y; corners go TL, TR, BR, BL."""
    top, foot = (corners[0], corners[3]) if side == 0 else (corners[1], corners[2])
    return top[0] + (foot[0] - top[0]) * (y - top[1]) / (foot[1] - top[1])


def test_the_jaw_shadow_stays_on_the_leaning_neck(face):
    for pose in POSES:
        root = face_svg(face, FaceState(pose=pose), clothes="none")
        neck = _leaned(root)
        shadow = shadow_outline(_layer(root, "face"))
        for x, y in shadow:  # cut upright at the chin's height: the leaning sides slant by under 1 px over it
            assert _side_x(neck, 0, y) - 1 <= x <= _side_x(neck, 1, y) + 1, (pose, x, y)


def test_the_neck_leans_with_the_roll_to_stay_under_the_chin(face):
    lifted = lift(face)
    for roll in (-15.0, -7.0, 7.0, 15.0):
        state = FaceState(pose=Pose(0, 0, roll))
        neck = _leaned(face_svg(face, state))
        chin = pose_face(lifted, state).p("2.1")
        middle = (_side_x(neck, 0, chin[1]) + _side_x(neck, 1, chin[1])) / 2
        upright = face.point("2.1")[0]
        assert abs(middle - chin[0]) < 0.1 * abs(upright - chin[0])  # far nearer than an upright neck


def test_the_cut_shadow_writes_its_numbers_as_the_scenery_does():
    # the polygon's bulk %-format gives the text of the per-number writer, ties, whole numbers and -0 included
    rng = np.random.default_rng(7)
    values = np.concatenate([rng.uniform(-500, 500, 200), np.arange(-40, 41) / 20, [-0.04, 0.04, -0.0, 0.0]])
    for chunk in range(0, len(values) - 1, 32):
        corners = values[chunk:chunk + 32]
        corners = corners[:len(corners) // 2 * 2].reshape(-1, 2)
        template = "M" + "L".join(["%.1f,%.1f"] * len(corners)) + "Z"
        assert _short_tenths(template % tuple(corners.ravel().tolist())) == _points(*corners.tolist())


def test_cut_shadows_written_from_tenths_are_written_as_the_scenery_writes_them():
    # rows of plain numbers, of binary halves of a tenth (12.25), of decimal ones (1.45: a product
    # that may land on a half), of numbers under a pixel and -0: each row's text is the per-number writer's
    rng = np.random.default_rng(8)
    rows = np.concatenate([rng.uniform(20, 900, (40, 32)), np.round(rng.uniform(20, 900, (40, 32)), 2),
                           rng.integers(200, 9000, (40, 32)) / 10 + 0.05, rng.integers(-400, 400, (20, 32)) / 8,
                           rng.uniform(-2, 2, (10, 32)), np.full((1, 32), -0.0)])
    tenths: dict[str, np.ndarray] = {}
    written = _shadow_data(rows, tenths)
    assert written == [_points(*row.reshape(-1, 2).tolist()) for row in rows]
    assert 40 < len(tenths) < len(rows)  # many written from tenths, not all
    for data, numbers in tenths.items():  # what compacting reads of the text
        assert [float(v) for v in data[1:-1].replace("L", ",").split(",")] == (numbers / 10).tolist()


def test_the_shadow_beyond_a_side_is_the_polygon_and_within_the_ellipse(face):
    figure = figure_of(face, (0.0, 0.0, float(face.width), float(face.height)))
    chin = face.point("2.1")
    chins = np.array([chin, chin + [figure.face_width, 0]], dtype=float)
    inside, outside = chin_shadows(figure, chins, np.full(2, float(chin[0])), ' class="s"')
    assert inside.startswith("<ellipse") and outside.startswith("<path")
    for text in (inside, outside):
        node = etree.fromstring(text)
        assert node.get("class") == "s"
    corners = polygon(etree.fromstring(outside).get("d"))
    assert corners[:, 0].max() <= chin[0] + figure.face_width * NECK + 0.05  # cut at the neck's right side
