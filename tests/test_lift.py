"""3D lift (thesis 002, Alg. 2.1, Table 2.1): origin, additional points, depths."""

from __future__ import annotations

import numpy as np
import pytest

from cartoonface.face.lift import (
    ADDITIONAL_NAMES,
    DEPTH,
    FRONT_NAMES,
    HAIR_DEPTH,
    HAIR_FADE,
    LIFTED_INDEX,
    ON_SURFACE,
    SILHOUETTES,
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
    """Every depth is Table 2.1's, except the outer eye corners and eyebrow ends, which
    are set back onto the rounder head (never forward, and still in front of the temples)."""
    lifted = lift(face)
    d = face.fapu.d
    for name in LIFTED_NAMES:
        z = lifted.local[LIFTED_INDEX[name], 2]
        if name in ON_SURFACE:
            assert DEPTH[ON_SURFACE[name]] * d < z <= DEPTH[name] * d
        else:
            assert z == pytest.approx(DEPTH[name] * d)
    # the hair: beside the temples at and above the eyes, in Table 2.1's hair plane lower down
    eyes = lifted.local[LIFTED_INDEX["3.5"], 1]
    z, y = lifted.hair[:, 2], lifted.hair[:, 1]
    assert np.allclose(z[y >= eyes], DEPTH["11.2"] * d)
    assert np.allclose(z[y <= eyes - HAIR_FADE * d], HAIR_DEPTH * d)
    assert np.all((HAIR_DEPTH * d - 1e-9 <= z) & (z <= DEPTH["11.2"] * d + 1e-9))
    assert np.any(y >= eyes)
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
    assert np.allclose(b.front, a.front * k)
    assert np.allclose(b.origin, a.origin * k)


def test_outer_features_lie_on_the_temples_cross_section(face):
    """An outer eye corner or eyebrow end is no further forward than the front half of its
    temple's cross-section at its distance from the face's middle: turned away, it stays
    inside the far silhouette."""
    lifted = lift(face)
    names = tuple(SILHOUETTES)
    middle = (lifted.local[LIFTED_INDEX["11.2"], 0] + lifted.local[LIFTED_INDEX["11.3"], 0]) / 2
    for name, temple in ON_SURFACE.items():
        x, _, z = lifted.local[LIFTED_INDEX[name]]
        k = names.index(temple)
        reach, front = lifted.silhouette.reach[k], lifted.silhouette.front[k]
        base = lifted.local[LIFTED_INDEX[temple], 2]
        out = abs(x - middle) / reach
        assert out < 1
        assert (z - base) / front <= np.sqrt(1 - out**2) + 1e-9


def test_front_layer_is_the_hair_top_and_a_hairline_over_the_forehead(face):
    """The crown runs left to right along the top of the hair outline, above the temples;
    the hairline lies just below the forehead contour, at its depths."""
    lifted = lift(face)
    crown = lifted.front[[FRONT_NAMES.index(n) for n in FRONT_NAMES if n.startswith("crown")]]
    hairline = lifted.front[[FRONT_NAMES.index(n) for n in FRONT_NAMES if n.startswith("hairline")]]
    temples = max(lifted.local[LIFTED_INDEX["11.2"], 1], lifted.local[LIFTED_INDEX["11.3"], 1])
    assert np.all(np.diff(crown[:, 0]) > 0) and np.all(crown[:, 1] > temples)
    assert crown[:, 1].max() == pytest.approx(lifted.hair[:, 1].max())
    outline = lifted.hair[:, :2]
    for point in crown[:, :2]:  # on the outline: within a hair's breadth of one of its edges
        a, b = outline, np.roll(outline, -1, axis=0)
        t = np.clip(np.einsum("ij,ij->i", point - a, b - a) / np.einsum("ij,ij->i", b - a, b - a), 0, 1)
        assert np.min(np.linalg.norm(a + t[:, None] * (b - a) - point, axis=1)) < 1e-6 * face.fapu.d
    top = lifted.local[LIFTED_INDEX["11.1"]]
    assert hairline[1, 0] == pytest.approx(top[0]) and hairline[1, 2] == pytest.approx(top[2])
    assert 0 < top[1] - hairline[1, 1] < top[1] - lifted.local[LIFTED_INDEX["4.1"], 1]


def test_hair_that_does_not_reach_over_the_forehead_has_no_front_layer(face):
    """A hair outline lying wholly below the top of the forehead (a model drawn so) gets a
    front layer with next to no area (under 5 % of the sample's): its crown lies along the
    hairline, so no hair is drawn over the face."""
    import dataclasses

    def area(lifted):
        crown = lifted.front[[FRONT_NAMES.index(n) for n in FRONT_NAMES if n.startswith("crown")]]
        hairline = lifted.front[[FRONT_NAMES.index(n) for n in FRONT_NAMES if n.startswith("hairline")]]
        temples = lifted.local[[LIFTED_INDEX["11.3"], LIFTED_INDEX["11.2"]]]
        polygon = np.vstack([crown, temples[:1], hairline, temples[1:]])
        x, y = polygon[:, 0], polygon[:, 1]
        return abs(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)) / 2

    low = lift(dataclasses.replace(face, hair=face.hair + [0.0, 3 * face.fapu.d]))
    assert area(low) < 0.05 * area(lift(face))
    crown = low.front[[FRONT_NAMES.index(n) for n in FRONT_NAMES if n.startswith("crown")]]
    assert np.all(crown[:, 1] <= low.local[LIFTED_INDEX["11.1"], 1] + 1e-9)


def test_front_layer_does_not_depend_on_the_hair_outline_direction(face):
    """A hair outline listed the other way round (a photo may give it so) makes the same
    front layer and the same cross-sections."""
    import dataclasses

    a, b = lift(face), lift(dataclasses.replace(face, hair=face.hair[::-1].copy()))
    assert np.allclose(a.front, b.front)
    h = len(face.hair)
    n = len(a.local)
    rows_a = {int(r) if r < n or r >= n + h else n + h - 1 - (int(r) - n): k for k, r in enumerate(a.silhouette.rows)}
    rows_b = {int(r): k for k, r in enumerate(b.silhouette.rows)}
    assert set(rows_a) == set(rows_b)
    for row, k in rows_a.items():
        j = rows_b[row]
        assert np.allclose(a.silhouette.normals[k], b.silhouette.normals[j])
        assert a.silhouette.reach[k] == pytest.approx(b.silhouette.reach[j])
