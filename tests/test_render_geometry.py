"""Curve maths of the drawing: Bezier arcs, contours, corner cutting, number text."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import Delaunay

from cartoonface.render.geometry import arc, chaikin, chaikin_closed_operator, contour
from cartoonface.render.numbers import fill, number_text, number_texts, rounded_tenths, template_frame


def bezier(start: np.ndarray, pieces: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Sample Bezier pieces (k, 3, 2) starting at `start` at parameters t: returns (k, len(t), 2)."""
    p0 = np.concatenate([start[None], pieces[:-1, 2]])[:, None]
    c1, c2, p3 = (pieces[:, i][:, None] for i in range(3))
    t = t[None, :, None]
    return (1 - t) ** 3 * p0 + 3 * (1 - t) ** 2 * t * c1 + 3 * (1 - t) * t**2 * c2 + t**3 * p3


# Drawing a 5,000-point hair outline (compiling the map, the number strings and the path
# text included) peaks under this: 9 MiB measured; the old dense map took 1.5 GiB.
LONG_HAIR_PEAK_BYTES = 32 * 2**20


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(7)


@pytest.mark.parametrize("n", [2, 3, 5, 8])
def test_arc_passes_through_every_point(rng: np.random.Generator, n: int) -> None:
    points = rng.uniform(0, 100, (n, 2))
    pieces = arc(points)
    assert pieces.shape == (n - 1, 3, 2)
    ends = bezier(points[0], pieces, np.array([0.0, 1.0]))
    np.testing.assert_allclose(ends[:, 0], points[:-1])
    np.testing.assert_allclose(ends[:, 1], points[1:])


def test_arc_is_smooth_at_inner_points(rng: np.random.Generator) -> None:
    points = rng.uniform(0, 100, (6, 2))
    pieces = arc(points)
    incoming = pieces[:-1, 2] - pieces[:-1, 1]
    outgoing = pieces[1:, 0] - pieces[:-1, 2]
    np.testing.assert_allclose(incoming, outgoing)


def test_arc_of_collinear_points_stays_on_the_line() -> None:
    points = np.array([[0.0, 0.0], [1.0, 2.0], [3.0, 6.0], [4.0, 8.0]])
    samples = bezier(points[0], arc(points), np.linspace(0, 1, 9)).reshape(-1, 2)
    np.testing.assert_allclose(samples[:, 1], 2 * samples[:, 0], atol=1e-9)


def test_arc_reversed_is_the_same_curve(rng: np.random.Generator) -> None:
    points = rng.uniform(0, 100, (5, 2))
    forward = bezier(points[0], arc(points), np.linspace(0, 1, 7))
    backward = bezier(points[-1], arc(points[::-1]), np.linspace(1, 0, 7))[::-1]
    np.testing.assert_allclose(forward, backward, atol=1e-9)


def test_smooth_contour_has_no_corner_at_joins(rng: np.random.Generator) -> None:
    pts = rng.uniform(0, 100, (6, 2))
    arcs = [pts[[0, 1, 2]], pts[[2, 3, 4]], pts[[4, 5, 0]]]
    for smooth in (True, False):
        pieces = contour(arcs, smooth)
        assert pieces.shape == (6, 3, 2)
        np.testing.assert_allclose(pieces[-1, 2], pts[0])
        joint = pieces[1, 2]  # point 2, where arcs 0 and 1 meet
        incoming, outgoing = joint - pieces[1, 1], pieces[2, 0] - joint
        cross = incoming[0] * outgoing[1] - incoming[1] * outgoing[0]
        assert (abs(cross) < 1e-9) == smooth


def test_arc_is_linear_in_its_points(rng: np.random.Generator) -> None:
    a, b = rng.uniform(0, 100, (2, 4, 2))
    np.testing.assert_allclose(arc(2 * a - b), 2 * arc(a) - arc(b), atol=1e-9)


@pytest.mark.parametrize("closed", [False, True])
@pytest.mark.parametrize("rounds", [1, 3])
def test_chaikin_stays_inside_the_control_hull(rng: np.random.Generator, closed: bool, rounds: int) -> None:
    polygon = rng.uniform(0, 100, (7, 2))
    refined = chaikin(polygon, rounds, closed=closed)
    assert len(refined) == len(polygon) * 2**rounds
    assert (Delaunay(polygon).find_simplex(refined, tol=1e-9) >= 0).all()


def test_open_chaikin_keeps_its_end_points(rng: np.random.Generator) -> None:
    polygon = rng.uniform(0, 100, (4, 2))
    refined = chaikin(polygon, 3)
    np.testing.assert_allclose(refined[[0, -1]], polygon[[0, -1]])


def test_chaikin_cuts_corners_and_shortens_the_polygon(rng: np.random.Generator) -> None:
    polygon = rng.uniform(0, 100, (6, 2))

    def perimeter(p: np.ndarray) -> float:
        return float(np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1).sum())

    lengths = [perimeter(chaikin(polygon, r, closed=True)) for r in range(4)]
    assert all(a > b for a, b in zip(lengths, lengths[1:]))


@pytest.mark.parametrize("count", [3, 4, 23, 101])
@pytest.mark.parametrize("rounds", [1, 2, 3])
def test_closed_chaikin_operator_is_the_corner_cutting(rng: np.random.Generator, count: int, rounds: int) -> None:
    points = rng.uniform(-50, 50, (count, 2))
    operator = chaikin_closed_operator(count, rounds)
    np.testing.assert_allclose(operator @ points, chaikin(points, rounds, closed=True), rtol=0, atol=1e-12)
    # banded: each cut point mixes at most three neighbouring points, so the size is linear in count
    assert operator.columns.shape == operator.weights.shape
    assert operator.columns.shape[1] <= 3


@pytest.mark.parametrize("value", [0.0, 3.0, -3.0, 0.04, 0.26, -0.5, 12.349, -1234.56, 9999.9, -4000.25])
def test_number_text_rounds_to_a_tenth_with_fewest_characters(value: float) -> None:
    text = number_text(value)
    assert abs(float(text) - value) <= 0.05 + 1e-9
    assert not text.endswith(".0") and not text.startswith(("0.", "-0."))
    assert number_texts(np.array([value])) == (text,)


def test_number_texts_writes_each_value_as_number_text(rng: np.random.Generator) -> None:
    # the drawing writes a state's numbers in one call (face_shapes, the mouth, the eyes and cheeks)
    values = np.concatenate([rng.uniform(-400, 400, 500), np.arange(-30, 31) / 20, [4000.25, -5000.05]])
    assert number_texts(values) == tuple(number_text(v) for v in values.tolist())


def test_number_texts_of_every_tenth_the_table_holds_are_number_text() -> None:
    # number_texts reads a table of every tenth in +-3276.8 px, built apart from number_text
    tenths = np.arange(-(1 << 15), 1 << 15)
    texts = number_texts(tenths / 10)
    assert texts == tuple(number_text(v / 10) for v in tenths.tolist())
    assert all(round(float(text) * 10) == v for text, v in zip(texts, tenths.tolist(), strict=True))


@pytest.mark.parametrize("template", ["%s", "M%s %sZ", "%s|%s", "M%s %sC%s %s %s %s %s %s|%s|", "x"])
def test_a_filled_frame_is_the_percent_format(rng: np.random.Generator, template: str) -> None:
    texts = number_texts(rng.uniform(-99, 99, template.count("%s")))
    assert fill(template_frame(template), texts) == template % texts
    with pytest.raises(ValueError):  # a number too many: an error, as the %-format gives
        fill(template_frame(template), (*texts, "1"))


@pytest.fixture(scope="module")
def posed_sample():
    from cartoonface.face.lift import lift
    from cartoonface.face.model import load_face
    from cartoonface.face.pose import pose_face
    from cartoonface.face.state import FaceState, Pose
    from tests.conftest import ROOT

    lifted = lift(load_face(ROOT / "samples" / "faces" / "female.json"))
    return {turn: pose_face(lifted, FaceState(pose=Pose(4, turn, -3), smile=0.3).with_mouth("o")) for turn in (-12, 12)}


def anchors(d: str) -> np.ndarray:
    """The on-curve points of an absolute M/C path: (n, 2)."""
    import re

    points: list[np.ndarray] = []
    for command, args in re.findall(r"([MCLZ])([^MCLZ]*)", d):
        values = np.array([float(v) for v in re.findall(r"-?(?:\d+\.?\d*|\.\d+)", args)]).reshape(-1, 2)
        points.extend(values[2::3] if command == "C" else values)
    return np.array(points)


def test_face_shapes_draw_every_part_through_its_points(posed_sample) -> None:
    from cartoonface.render.geometry import FACE_CONTOUR, PARTS, face_shapes

    posed = posed_sample[12]
    shapes = face_shapes(posed)
    assert set(shapes) == {"hair"} | {name for name, _, _ in PARTS}
    assert all(shapes.values())
    contour = [name for arc_ in FACE_CONTOUR for name in arc_[:-1]]
    expected = np.array([posed.p(name) for name in contour + contour[:1]])
    np.testing.assert_allclose(anchors(shapes["face"]), expected, atol=0.051)


def test_nose_bridge_is_drawn_on_the_side_the_pose_shows(posed_sample) -> None:
    from cartoonface.render.geometry import face_shapes

    for posed in posed_sample.values():
        start = anchors(face_shapes(posed)["nose"])[0]
        bridge = "9.7" if posed.nose_side == 1 else "9.6"
        np.testing.assert_allclose(start, posed.p(bridge), atol=0.051)
    assert {p.nose_side for p in posed_sample.values()} == {-1, 1}


@pytest.mark.parametrize("count", [3, 23, 40])
def test_hair_of_any_size_is_corner_cut(posed_sample, count: int) -> None:
    import dataclasses

    from cartoonface.render.geometry import CHAIKIN_ROUNDS, face_shapes

    angles = np.linspace(0, 2 * np.pi, count, endpoint=False)
    hair = np.column_stack([200 + 120 * np.cos(angles), 200 + 150 * np.sin(angles)])
    posed = dataclasses.replace(posed_sample[12], hair=hair)
    outline = anchors(face_shapes(posed)["hair"])
    assert len(outline) == count * 2**CHAIKIN_ROUNDS
    assert (Delaunay(hair).find_simplex(outline, tol=0.06) >= 0).all()


def test_long_hair_outline_is_drawn_in_memory_linear_in_its_points(posed_sample) -> None:
    import dataclasses
    import tracemalloc

    from cartoonface.render.geometry import CHAIKIN_ROUNDS, _plan, face_shapes

    count = 5000  # a dense map over all points would hold 8 * 5000 x 5049 numbers: 1.5 GiB
    angles = np.linspace(0, 2 * np.pi, count, endpoint=False)
    hair = np.column_stack([200 + 120 * np.cos(angles), 200 + 150 * np.sin(angles)])
    posed = dataclasses.replace(posed_sample[12], hair=hair)
    _plan.cache_clear()  # measure compiling the drawing too, not only using it
    tracemalloc.start()
    try:
        shapes = face_shapes(posed)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    outline = anchors(shapes["hair"])
    assert len(outline) == count * 2**CHAIKIN_ROUNDS
    assert peak < LONG_HAIR_PEAK_BYTES


def test_neutral_pose_draws_the_model_points() -> None:
    from cartoonface.face.lift import lift
    from cartoonface.face.model import load_face
    from cartoonface.face.pose import pose_face
    from cartoonface.face.state import FaceState
    from cartoonface.render.geometry import face_shapes
    from tests.conftest import ROOT

    face = load_face(ROOT / "samples" / "faces" / "male.json")
    shapes = face_shapes(pose_face(lift(face), FaceState()))
    # the mouth: tests/test_mouth_drawing.py
    for part, names in (("eye_l", ("3.12", "3.2", "3.8", "3.4", "3.12")), ("eye_r", ("3.7", "3.1", "3.11", "3.3", "3.7"))):
        np.testing.assert_allclose(anchors(shapes[part]), [face.point(n) for n in names], atol=0.051)


def test_rounded_tenths_are_narrow_where_they_fit_and_exact_beyond() -> None:
    # a drawing's tenths are int32 (half the bytes to compare); a number beyond int32 keeps int64
    assert rounded_tenths(np.array([[12.34, -0.05], [400.0, 3276.8]])).dtype == np.int32
    wide = rounded_tenths(np.array([3e8, -1.25]))
    assert wide.dtype == np.int64 and wide.tolist() == [3_000_000_000, -12]
