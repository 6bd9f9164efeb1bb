"""point_editor.implausible: warnings for points dragged where no face has them, tested by
properties on the sample faces' points standing in for the points found on a photo."""

from __future__ import annotations

import json

import numpy as np
import pytest

from cartoonface.face.model import POINT_INDEX, POINT_NAMES
from cartoonface.web.point_editor import CROSS_SHARE, implausible
from tests.conftest import ROOT

FACES = sorted((ROOT / "samples" / "faces").glob("*.json"))


def points_of(path) -> np.ndarray:
    named = json.loads(path.read_text(encoding="utf-8"))["points"]
    return np.array([named[name] for name in POINT_NAMES], dtype=float)


def at(points: np.ndarray, name: str) -> np.ndarray:
    return points[POINT_INDEX[name]]


def moved(points: np.ndarray, **to: np.ndarray) -> np.ndarray:
    """A copy of `points` with the named points (dots written as underscores) at new places."""
    out = points.copy()
    for key, value in to.items():
        out[POINT_INDEX[key.replace("_", ".")]] = value
    return out


def turned(points: np.ndarray, degrees: float, scale: float = 1.0) -> np.ndarray:
    """`points` turned about their mean by `degrees` and scaled (a tilted, nearer photo)."""
    angle = np.radians(degrees)
    matrix = scale * np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    centre = points.mean(axis=0)
    return (points - centre) @ matrix.T + centre + (40.0, -25.0)


def eye_distance(points: np.ndarray) -> float:
    return float(np.linalg.norm(at(points, "3.5") - at(points, "3.6")))


@pytest.fixture(params=FACES, ids=lambda path: path.stem)
def face(request) -> np.ndarray:
    return points_of(request.param)


def test_the_points_as_found_and_small_moves_are_fine(face):
    assert implausible(face, face) == ()
    rng = np.random.default_rng(7)
    small = CROSS_SHARE * eye_distance(face) / 4
    for _ in range(50):
        assert implausible(face + rng.uniform(-small, small, face.shape), face) == ()


@pytest.mark.parametrize("degrees", [0.0, 25.0, -40.0])
def test_an_eye_below_the_mouth_is_named(face, degrees):
    photo = turned(face, degrees, 1.7)
    chin, mouth = at(photo, "2.1"), at(photo, "8.2")
    edited = moved(photo, **{"3_6": (chin + mouth) / 2})
    warnings = implausible(edited, photo)
    assert [w.point for w in warnings] == ["3.6"]
    assert "3.6" in warnings[0].message and "below the mouth" in warnings[0].message


@pytest.mark.parametrize("degrees", [0.0, 30.0])
def test_a_mouth_corner_outside_the_face_outline_is_named(face, degrees):
    photo = turned(face, degrees)
    cheek, corner = at(photo, "10.9"), at(photo, "8.3")
    edited = moved(photo, **{"8_3": cheek + 0.5 * (cheek - corner)})  # beyond the cheek
    warnings = implausible(edited, photo)
    assert [w.point for w in warnings] == ["8.3"]
    assert "outside the face outline" in warnings[0].message


def test_swapped_mouth_corners_are_told(face):
    edited = moved(face, **{"8_3": at(face, "8.4"), "8_4": at(face, "8.3")})
    warnings = implausible(edited, face)
    assert {w.point for w in warnings} <= {"8.3", "8.4"} and warnings
    assert any("swapped" in w.message or "other half" in w.message for w in warnings)


def test_a_rule_the_photo_already_breaks_is_not_told(face):
    # a face found with a brow end lower than the eye corner: moving the brow a little is no news
    found = moved(face, **{"4_5": at(face, "3.7") + (0.0, 0.3 * eye_distance(face))})
    assert implausible(found, found) == ()
    assert implausible(moved(found, **{"4_5": at(found, "4.5") + (1.0, 1.0)}), found) == ()


def test_the_point_moved_furthest_is_blamed(face):
    nose = at(face, "9.15")
    lifted = moved(face, **{"8_1": nose - (0.0, 0.3 * eye_distance(face))})  # the upper lip above the nose tip
    assert [w.point for w in implausible(lifted, face)] == ["8.1"]
