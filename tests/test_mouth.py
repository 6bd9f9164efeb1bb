"""The 12 basic mouth shapes (thesis 002, 5.2.2): valid contours and the opening order."""

from __future__ import annotations

import numpy as np
import pytest

from cartoonface.errors import OptionError
from cartoonface.face.lift import lift
from cartoonface.face.model import POINT_INDEX, load_face, scale_face
from cartoonface.face.mouth import INNER_LIP, MOUTH_SHAPES, MOUTH_SYMBOLS, OUTER_LIP, mouth_points, shape_displacements
from cartoonface.face.pose import pose_face
from cartoonface.face.state import FaceState, Pose


@pytest.fixture(params=("female", "male"), scope="module")
def face(request):
    from tests.conftest import ROOT

    return load_face(ROOT / "samples" / "faces" / f"{request.param}.json")


def _crosses(p1, p2, q1, q2):
    def side(a, b, c):
        return np.sign((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))

    return side(p1, p2, q1) * side(p1, p2, q2) < 0 and side(q1, q2, p1) * side(q1, q2, p2) < 0


def _is_simple(polygon):
    n = len(polygon)
    edges = [(polygon[i], polygon[(i + 1) % n]) for i in range(n)]
    return not any(
        _crosses(*edges[i], *edges[j]) for i in range(n) for j in range(i + 2, n) if not (i == 0 and j == n - 1)
    )


def _area(polygon):
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * (np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _opening(points):
    return points[POINT_INDEX["2.3"], 1] - points[POINT_INDEX["2.2"], 1]


def test_table_covers_every_symbol():
    assert tuple(MOUTH_SHAPES) == MOUTH_SYMBOLS


def test_neutral_m_is_the_rest_shape(face):
    assert np.array_equal(mouth_points(face, (("m", 1.0),)), face.points)
    assert not shape_displacements(face)[MOUTH_SYMBOLS.index("m")].any()


@pytest.mark.parametrize("symbol", MOUTH_SYMBOLS)
@pytest.mark.parametrize("smile", [0.0, 1.0])
@pytest.mark.parametrize("pose", [Pose(), Pose(10, -15, 8)])
def test_every_shape_keeps_the_mouth_a_simple_closed_contour(face, symbol, smile, pose):
    posed = pose_face(lift(face), FaceState(pose=pose, smile=smile).with_mouth(symbol))
    outer = np.array([posed.p(n) for n in OUTER_LIP])
    inner = np.array([posed.p(n) for n in ("R", "2.2", "S", "2.3")])
    assert _is_simple(outer)
    assert _area(outer) > 0.02 * face.fapu.d**2
    assert _is_simple(inner)
    # the lips never turn inside out: inner lower lip not above the inner upper lip,
    # outer lips outside the inner ones
    down = np.array([np.sin(np.radians(pose.roll)), np.cos(np.radians(pose.roll))])
    assert (posed.p("2.3") - posed.p("2.2")) @ down >= -1e-9
    assert (posed.p("2.2") - posed.p("8.1")) @ down > 0
    assert (posed.p("8.2") - posed.p("2.3")) @ down >= -1e-9
    assert (posed.p("2.1") - posed.p("8.2")) @ down > 0


def test_openings_follow_the_thesis_order(face):
    opening = {s: _opening(mouth_points(face, ((s, 1.0),))) for s in MOUTH_SYMBOLS}
    assert opening["m"] == pytest.approx(0) and opening["f"] == pytest.approx(0)
    assert max(opening, key=opening.get) == "a"
    for symbol in set(MOUTH_SYMBOLS) - {"m", "f", "a"}:
        assert 0 < opening[symbol] < opening["a"]
    # thesis 5.2.2: h' is the narrower posture of h; i opens least of the finals
    assert opening["h'"] < opening["h"]
    assert opening["i"] == min(opening[s] for s in ("a", "i", "u", "e", "o", "n"))


def test_f_tucks_the_lower_lip_under_the_upper(face):
    points = mouth_points(face, (("f", 1.0),))
    lower_lip = points[POINT_INDEX["8.2"], 1] - points[POINT_INDEX["2.3"], 1]
    assert 0 <= lower_lip < face.fapu.lower_lip_h


def test_width_changes_follow_the_thesis(face):
    width = {}
    for s in MOUTH_SYMBOLS:
        points = mouth_points(face, ((s, 1.0),))
        width[s] = points[POINT_INDEX["8.3"], 0] - points[POINT_INDEX["8.4"], 0]
    assert width["i"] > width["m"] and width["e"] > width["m"]  # spread lips
    assert width["u"] < width["a"] < width["m"] and width["o"] < width["m"]  # rounded lips
    assert width["u"] == pytest.approx(width["m"] * 0.6)  # 0.2 MW0 in from each corner


@pytest.mark.parametrize("symbol", MOUTH_SYMBOLS)
def test_jaw_follows_the_lower_lip(face, symbol):
    points = mouth_points(face, ((symbol, 1.0),))
    assert points[POINT_INDEX["2.1"], 1] - points[POINT_INDEX["8.2"], 1] == pytest.approx(face.fapu.jaw_h)
    assert points[POINT_INDEX["2.1"], 0] == face.point("2.1")[0]


def test_weights_blend_linearly(face):
    half = mouth_points(face, (("a", 0.5), ("m", 0.5)))
    full = mouth_points(face, (("a", 1.0),))
    assert np.allclose(half, (full + face.points) / 2)
    mix = pose_face(lift(face), FaceState(mouth=(("o", 0.25), ("i", 0.75))))
    assert np.allclose(mix.xy[: len(face.points)], mouth_points(face, (("o", 0.25), ("i", 0.75))))


def test_shapes_are_in_fapu_units(face):
    big = scale_face(face, face.fapu.d * 1.5)
    assert np.allclose(shape_displacements(big), 1.5 * shape_displacements(face))


@pytest.mark.parametrize(
    ("mouth", "expected"),
    [((("x", 1.0),), "mouth symbol 'x'"), ((("a", 0.5),), "sum to 0.5"), ((("a", -1.0), ("o", 2.0)), "weight of 'a'"), ((), "empty")],
)
def test_bad_mouth_is_refused(mouth, expected):
    with pytest.raises(OptionError, match=expected):
        FaceState(mouth=mouth)


def test_with_mouth_refuses_unknown_symbol():
    with pytest.raises(OptionError, match="mouth symbol 'q'"):
        FaceState().with_mouth("q")
    assert FaceState().with_mouth("o").mouth == (("o", 1.0),)


def test_inner_lip_names_are_model_points():
    assert all(n in POINT_INDEX for n in INNER_LIP + OUTER_LIP)


@pytest.mark.parametrize("symbol", MOUTH_SYMBOLS)
def test_jaw_corners_follow_the_opening_less_than_the_chin(face, symbol):
    """The jaw hinges at the ear: when a shape drops the chin 2.1, the jaw corners
    2.13 / 2.14 drop too, by less than the chin, and the face stays symmetric."""
    moved = mouth_points(face, ((symbol, 1.0),)) - face.points
    chin = moved[POINT_INDEX["2.1"], 1]
    for corner in ("2.13", "2.14"):
        dy = moved[POINT_INDEX[corner], 1]
        if chin > 0:
            assert 0 < dy < chin
        else:
            assert chin <= dy <= 0
    assert moved[POINT_INDEX["2.13"], 1] == pytest.approx(moved[POINT_INDEX["2.14"], 1])
