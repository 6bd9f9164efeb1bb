"""Blink, smile with squint, eyebrow raise (thesis 002, 2.4.2)."""

from __future__ import annotations

import numpy as np
import pytest

from cartoonface.errors import OptionError
from cartoonface.face.expression import expression_points
from cartoonface.face.lift import lift
from cartoonface.face.model import POINT_INDEX, load_face
from cartoonface.face.pose import pose_face
from cartoonface.face.state import FaceState, Pose

EYES = (("3.12", "3.2", "3.8", "3.4"), ("3.7", "3.1", "3.11", "3.3"))
BROWS = ("4.1", "4.2", "4.3", "4.4", "4.3a", "4.4a", "4.5", "4.6")


@pytest.fixture(params=("female", "male"), scope="module")
def face(request):
    from tests.conftest import ROOT

    return load_face(ROOT / "samples" / "faces" / f"{request.param}.json")


def _area(polygon):
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _opening(points, eye):
    corner_a, upper, corner_b, lower = (points[POINT_INDEX[n]] for n in eye)
    return lower[1] - upper[1]


@pytest.mark.parametrize("pose", [Pose(), Pose(9, -14, 6), Pose(-15, 15, -15)])
@pytest.mark.parametrize("smile", [0.0, 1.0])
def test_blink_closes_the_eyes_and_hides_the_eyeballs(face, pose, smile):
    posed = pose_face(lift(face), FaceState(pose=pose, blink=1.0, smile=smile))
    for eye in EYES:
        outline = np.array([posed.p(n) for n in eye])
        assert np.allclose(posed.p(eye[1]), posed.p(eye[3]), atol=1e-9)  # the lids meet
        assert _area(outline) < 1e-6  # the clip region of the eyeball is empty
    opened = pose_face(lift(face), FaceState(pose=pose, smile=smile))
    for eye in EYES:
        assert _area(np.array([opened.p(n) for n in eye])) > 0.01 * face.fapu.d**2


def test_blink_is_continuous_and_monotone(face):
    amounts = np.linspace(0, 1, 21)
    for eye in EYES:
        openings = np.array([_opening(expression_points(face, blink=b), eye) for b in amounts])
        assert np.all(np.diff(openings) < 0)
        assert openings[0] == pytest.approx(_opening(face.points, eye))
        assert openings[-1] == pytest.approx(0, abs=1e-9)
        # linear in the amount: half a blink closes half the eye
        assert openings[10] == pytest.approx(openings[0] / 2)


def test_blink_moves_only_eyelids(face):
    moved = np.nonzero(np.any(expression_points(face, blink=1) != face.points, axis=1))[0]
    assert {name for name, i in POINT_INDEX.items() if i in moved} == {"3.1", "3.2", "3.3", "3.4"}


def test_smile_lifts_and_widens_the_mouth_corners_and_squints(face):
    smiling = expression_points(face, smile=1)
    p = lambda points, n: points[POINT_INDEX[n]]  # noqa: E731
    for corner in ("8.4", "8.3"):
        assert p(smiling, corner)[1] < p(face.points, corner)[1]
    assert p(smiling, "8.3")[0] - p(smiling, "8.4")[0] > face.fapu.mw0
    for eye in EYES:
        assert 0 < _opening(smiling, eye) < _opening(face.points, eye)
    for name in ("8.1", "8.2", "2.2", "2.3", "3.5", "3.6"):
        assert np.array_equal(p(smiling, name), p(face.points, name))


def test_brow_raise_lifts_eyebrows_and_their_lower_edge(face):
    lifted = lift(face)
    front = pose_face(lifted, FaceState())
    raised = pose_face(lifted, FaceState(brow=1))
    for name in BROWS:
        assert raised.p(name)[1] < front.p(name)[1] - 0.5 * face.fapu.eyebrow_h
    for edge, top in (("F", "4.4a"), ("G", "4.4"), ("H", "4.3"), ("I", "4.3a")):
        assert raised.p(edge) - front.p(edge) == pytest.approx(raised.p(top) - front.p(top))
    for name in ("3.1", "3.2", "3.3", "3.4", "8.4", "9.15"):
        assert np.array_equal(raised.p(name), front.p(name))


def test_expressions_scale_with_the_face(face):
    from cartoonface.face.model import scale_face

    big = scale_face(face, face.fapu.d * 2)
    moves = expression_points(face, 0.4, 0.7, 0.9) - face.points
    assert np.allclose(expression_points(big, 0.4, 0.7, 0.9) - big.points, 2 * moves)


@pytest.mark.parametrize(("field", "value"), [("blink", 1.5), ("smile", -0.1), ("brow", float("inf")), ("blink", "x")])
def test_out_of_range_amounts_are_refused(field, value):
    with pytest.raises(OptionError, match=field):
        FaceState(**{field: value})
