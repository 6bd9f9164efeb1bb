"""3D lift (thesis 002, Alg. 2.1, Table 2.1): origin, additional points, depths."""

from __future__ import annotations

import numpy as np
import pytest

from cartoonface.face.lift import (
    ADDITIONAL_NAMES,
    DEPTH,
    HAIR_DEPTH,
    LIFTED_INDEX,
    LIFTED_NAMES,
    lift,
    lifted_image_points,
)
from cartoonface.face.model import POINT_NAMES, load_face, scale_face


@pytest.fixture(params=("female", "male"))
def face(request, root):
    return load_face(root / "samples" / "faces" / f"{request.param}.json")


def _image(lifted):
    """Local coordinates back to image pixels (thesis 2.4.1: x + x_o, y_o - y)."""
    return np.column_stack([lifted.local[:, 0] + lifted.origin[0], lifted.origin[1] - lifted.local[:, 1]])


def test_names_are_the_model_points_and_17_additional():
    assert LIFTED_NAMES[: len(POINT_NAMES)] == POINT_NAMES
    assert len(ADDITIONAL_NAMES) == 17 == len(set(ADDITIONAL_NAMES))
    assert set(DEPTH) == set(LIFTED_NAMES)


def test_origin_is_below_eyemid(face):
    lifted = lift(face)
    mid = (face.point("3.5") + face.point("3.6")) / 2
    assert lifted.origin[0] == pytest.approx(mid[0])
    assert lifted.origin[1] - mid[1] == pytest.approx(1.3 * face.fapu.d)


def test_local_frame_round_trips_to_the_model_points(face):
    lifted = lift(face)
    back = _image(lifted)
    assert np.allclose(back[: len(POINT_NAMES)], face.points)
    assert np.allclose(back, lifted_image_points(lifted, face.points))
    # local y points up: the forehead is above (greater y than) the chin
    assert lifted.local[LIFTED_INDEX["11.1"], 1] > lifted.local[LIFTED_INDEX["2.1"], 1]


def test_depths_follow_table_2_1(face):
    lifted = lift(face)
    d = face.fapu.d
    for name in LIFTED_NAMES:
        assert lifted.local[LIFTED_INDEX[name], 2] == pytest.approx(DEPTH[name] * d)
    assert np.allclose(lifted.hair[:, 2], HAIR_DEPTH * d)
    # the nose tip is the frontmost point, the ear tops the furthest back
    z = lifted.local[:, 2]
    assert LIFTED_NAMES[int(np.argmax(z))] == "9.15"
    assert LIFTED_NAMES[int(np.argmin(z))] in ("10.1", "10.2")


def test_additional_points_sit_where_alg_2_1_puts_them(face):
    image = lifted_image_points(lift(face), face.points)
    at = {name: image[LIFTED_INDEX[name]] for name in LIFTED_NAMES}
    fapu = face.fapu
    assert np.allclose(at["R"], face.point("8.4")) and np.allclose(at["S"], face.point("8.3"))
    assert np.allclose(at["N"], face.point("11.2")) and np.allclose(at["Q"], face.point("11.3"))
    # eyebrow lower edge: below its upper point by EyebrowH / 1.3
    assert at["G"][1] - face.point("4.4")[1] == pytest.approx(fapu.eyebrow_h / 1.3)
    assert at["F"][1] - face.point("4.4a")[1] == pytest.approx(fapu.eyebrow_h2 / 1.3)
    # C halfway between the nostril tops in x, D and E between them vertically
    assert at["C"][0] == pytest.approx((face.point("9.13")[0] + face.point("9.14")[0]) / 2)
    for name, low, high in (("D", "9.14", "9.4"), ("E", "9.13", "9.5"), ("A", "10.2", "10.8")):
        assert face.point(low)[1] < at[name][1] < face.point(high)[1]
    # J and K lie between the jaw corners and the chin, at corner height
    assert face.point("2.14")[0] < at["J"][0] < face.point("2.1")[0] < at["K"][0] < face.point("2.13")[0]
    # A and B equally far from EyeMid, on either side
    mid = (face.point("3.5") + face.point("3.6")) / 2
    assert mid[0] - at["A"][0] == pytest.approx(at["B"][0] - mid[0])
    assert at["A"][0] < mid[0]


def test_additional_points_follow_moved_model_points(face):
    lifted = lift(face)
    moved = face.points.copy()
    moved[POINT_NAMES.index("4.4")] += (3.0, -7.0)
    moved[POINT_NAMES.index("8.3")] += (2.0, 5.0)
    before = lifted_image_points(lifted, face.points)
    after = lifted_image_points(lifted, moved)
    assert np.allclose(after[LIFTED_INDEX["G"]] - before[LIFTED_INDEX["G"]], (3.0, -7.0))
    assert np.allclose(after[LIFTED_INDEX["S"]] - before[LIFTED_INDEX["S"]], (2.0, 5.0))
    assert np.allclose(after[LIFTED_INDEX["C"]], before[LIFTED_INDEX["C"]])


def test_lift_scales_with_d(face):
    k = 1.8
    a, b = lift(face), lift(scale_face(face, face.fapu.d * k))
    assert np.allclose(b.local, a.local * k)
    assert np.allclose(b.hair, a.hair * k)
    assert np.allclose(b.origin, a.origin * k)
