"""The drawn mouth (render/mouth.py) over every shape, blend and pose: properties of its outlines."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from lxml import etree

from cartoonface.face.lift import lift
from cartoonface.face.model import load_face
from cartoonface.face.mouth import MOUTH_SYMBOLS, shown_parts
from cartoonface.face.pose import pose_face
from cartoonface.face.state import FaceState, Pose
from cartoonface.render.mouth import ROWS, MouthOutlines, mouth_outlines, mouth_texts
from cartoonface.render.svg import face_group
from tests.shapes import area, crossings, sample

SVG = "{http://www.w3.org/2000/svg}"
# Poses: the front and the eight corners of the +-15 degree cube (tilt, turn, roll).
POSES = (Pose(),) + tuple(Pose(*corner) for corner in itertools.product((-15, 15), repeat=3))
WEIGHTS = (0.25, 0.5, 0.75)  # blends between two shapes, besides the pure shapes
MIXES = tuple(((s, 1.0),) for s in MOUTH_SYMBOLS) + tuple(
    ((s, 1.0 - w), (t, w)) for s, t in itertools.combinations(MOUTH_SYMBOLS, 2) for w in WEIGHTS)


@pytest.fixture(params=("female", "male", "slanted"), scope="module")
def face(request):
    """The sample faces, and the female one with a slanted mouth as faces from photos have: one
    corner lower, the shut lips' 2.3 beside 2.2, the lower lip's bottom 8.2 barely below the
    corners."""
    from cartoonface.face.model import face_from_dict, face_to_dict
    from tests.conftest import ROOT

    if request.param != "slanted":
        return load_face(ROOT / "samples" / "faces" / f"{request.param}.json")
    obj = face_to_dict(load_face(ROOT / "samples" / "faces" / "female.json"))
    points = obj["points"]
    points["8.3"] = [points["8.3"][0], points["8.3"][1] + 6]
    points["2.3"] = [points["2.3"][0] - 2, points["2.3"][1]]
    points["8.2"] = [points["8.2"][0], points["8.3"][1] + 1]
    return face_from_dict(obj, "slanted")


def drawn(face, state: FaceState) -> MouthOutlines:
    posed = pose_face(lift(face), state)
    return mouth_outlines(posed.xy[ROWS], posed.mouth @ shown_parts(), face.fapu.d)


def inside(points: np.ndarray, polygon: np.ndarray, tolerance: float) -> np.ndarray:
    """(m,) whether each point lies inside the closed polygon or within `tolerance` px of its edges."""
    a, b = polygon, np.roll(polygon, -1, axis=0)
    x, y = points[:, None, 0], points[:, None, 1]
    straddle = (a[None, :, 1] > y) != (b[None, :, 1] > y)
    at_x = a[None, :, 0] + (y - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) / np.where(
        b[None, :, 1] == a[None, :, 1], 1e-12, b[None, :, 1] - a[None, :, 1])
    odd = (straddle & (x < at_x)).sum(axis=1) % 2 == 1
    ab = b - a
    u = np.clip(((points[:, None] - a[None]) * ab[None]).sum(-1) / np.maximum((ab**2).sum(-1), 1e-12)[None], 0, 1)
    near = np.hypot(*(points[:, None] - (a[None] + u[..., None] * ab[None])).transpose(2, 0, 1)).min(axis=1)
    return odd | (near <= tolerance)


def down(outlines: MouthOutlines) -> np.ndarray:
    """(2,) unit vector down the face in the mouth's frame: perpendicular to corner-to-corner."""
    left, right = outlines.lips[0], outlines.lips[12]
    along = (right - left) / np.hypot(*(right - left))
    return np.array([-along[1], along[0]])


def test_every_shape_blend_and_pose_draws_a_sound_mouth(face):
    """Lips and opening never cross themselves, the opening lies inside the lips, the upper row of
    teeth above the lower one; 210 mixes x 9 poses."""
    tolerance = 0.02 * face.fapu.d
    for mix, pose in itertools.product(MIXES, POSES):
        out = drawn(face, FaceState(pose=pose, mouth=mix))
        lips, opening = sample(out.lips), sample(out.opening)
        where = f"{mix} at {pose}"
        assert area(lips) > 0 and crossings(lips) == 0, where
        assert area(opening) >= -1e-6 * face.fapu.d**2, where
        if area(opening) > 1e-3 * face.fapu.d**2:
            assert crossings(opening) == 0, where
        assert inside(opening, lips, tolerance).all(), where
        # the rows' middles: the upper row's lower edge not below the lower row's upper edge
        middle = np.array([1, 3, 3, 1]) / 8
        upper_edge = middle @ out.upper_teeth + down(out) * out.upper_width / 2
        lower_edge = middle @ out.lower_teeth - down(out) * out.lower_width / 2
        assert (lower_edge - upper_edge) @ down(out) >= -1e-9, where


def test_the_teeth_and_tongue_are_clipped_by_the_opening(face):
    """In the SVG, the tongue and both rows of teeth are inside a group clipped by a path whose
    outline is the opening's, drawn just before it; a shut mouth has none."""
    lifted = lift(face)
    for symbol, pose in itertools.product(MOUTH_SYMBOLS, (Pose(), Pose(15, -15, 15))):
        posed = pose_face(lifted, FaceState(pose=pose).with_mouth(symbol))
        group = face_group(face, posed, "t")
        mouth = group.find(f"{SVG}g[@class='mouth']")
        opening = mouth_texts(mouth_outlines(posed.xy[ROWS], posed.mouth @ shown_parts(), face.fapu.d))["opening"]
        clipped = mouth.find(f"{SVG}g[@clip-path='url(#cf-mouth-t)']")
        if symbol in ("m", "f"):
            assert clipped is None
            continue
        clip = group.find(f".//{SVG}clipPath[@id='{clipped.get('clip-path')[5:-1]}']")
        assert [node.get("d") for node in clip] == [opening]
        assert clipped.getprevious().get("d") == opening
        tags = [etree.QName(node).localname for node in clipped]
        assert tags[0] == "ellipse"  # the tongue, behind the teeth
        shown = dict(zip(("upper_teeth", "lower_teeth"), shown_parts()[MOUTH_SYMBOLS.index(symbol), :2]))
        assert len(tags) == 1 + sum(1 for amount in shown.values() if amount > 0), symbol


def test_the_teeth_on_the_lower_lip_are_clipped_by_the_lips(face):
    """f: the upper teeth over the lower lip are drawn in a group clipped by the lips' outline."""
    lifted = lift(face)
    for pose in (Pose(), Pose(15, -15, 15), Pose(-15, 15, -15)):
        posed = pose_face(lifted, FaceState(pose=pose, smile=1.0).with_mouth("f"))
        group = face_group(face, posed, "t")
        texts = mouth_texts(mouth_outlines(posed.xy[ROWS], posed.mouth @ shown_parts(), face.fapu.d))
        clipped = group.find(f"{SVG}g[@class='mouth']/{SVG}g[@clip-path='url(#cf-lips-t)']")
        assert [node.get("d") for node in group.find(f".//{SVG}clipPath[@id='cf-lips-t']")] == [texts["lips"]]
        assert [node.get("d") for node in clipped] == [texts["bite"]]


def test_the_lips_pass_through_the_thesis_points(face):
    """Alg. 2.2 step 13: the lips run through 8.4, 8.9, 8.1, 8.10, 8.3 and 8.2, the opening
    through 2.2 and 2.3, at every pose."""
    lifted = lift(face)
    for symbol, pose in itertools.product(MOUTH_SYMBOLS, POSES[:3]):
        posed = pose_face(lifted, FaceState(pose=pose).with_mouth(symbol))
        out = mouth_outlines(posed.xy[ROWS], posed.mouth @ shown_parts(), face.fapu.d)
        anchors = out.lips[::3]
        np.testing.assert_allclose(anchors, [posed.p(n) for n in ("8.4", "8.9", "8.1", "8.10", "8.3", "8.2", "8.4")],
                                   atol=1e-9)
        shut = out.tongue[3] == 0
        np.testing.assert_allclose(out.opening[[3, 9]], [posed.p("2.2"), posed.p("2.2" if shut else "2.3")],
                                   atol=1e-9)


def opening_areas(face, pose: Pose) -> dict[str, float]:
    return {s: area(sample(drawn(face, FaceState(pose=pose).with_mouth(s)).opening)) for s in MOUTH_SYMBOLS}


@pytest.mark.parametrize("pose", [Pose(), Pose(-15, 15, -15), Pose(15, -15, 15)])
def test_opening_areas_follow_the_shapes(face, pose):
    """m and f are shut; a opens most, then o, then u; spread i less than e; h' less than h."""
    areas = opening_areas(face, pose)
    small = 1e-6 * face.fapu.d**2
    assert abs(areas["m"]) < small and abs(areas["f"]) < small
    assert max(areas, key=areas.get) == "a"
    assert areas["a"] > areas["o"] > areas["u"] > small
    assert areas["i"] < areas["e"] and areas["h'"] < areas["h"]


def test_only_f_bites_and_the_shut_mouth_shows_no_teeth(face):
    for symbol in MOUTH_SYMBOLS:
        out = drawn(face, FaceState().with_mouth(symbol))
        assert (out.bite_width > 0) == (symbol == "f"), symbol
        if symbol in ("m", "f"):
            assert out.upper_width == 0 and out.lower_width == 0


def test_the_tongue_rises_for_n(face):
    """n: the tongue's top reaches the upper edge of the opening (2.2); a: it lies low. Measured
    down the mouth (perpendicular to the line between its corners)."""
    for symbol, raised in (("n", True), ("a", False)):
        out = drawn(face, FaceState().with_mouth(symbol))
        cx, cy, rx, ry = out.tongue
        top = np.array([cx, cy]) @ down(out) - ry
        upper, lower = out.opening[[3, 9]] @ down(out)
        assert (abs(top - upper) < 1e-6) == raised, symbol
        assert upper - 1e-6 <= top < lower


def test_full_opening_is_much_bigger_than_the_rest_mouth(face):
    """The lips of a, drawn, cover at least 1.5 times the area of the shut mouth's."""
    rest = area(sample(drawn(face, FaceState()).lips))
    wide = area(sample(drawn(face, FaceState().with_mouth("a")).lips))
    assert wide > 1.5 * rest


def test_drawing_follows_the_head_roll(face):
    """Rolling the head turns the drawn mouth with it: same outlines, rotated about the roll origin."""
    from cartoonface.face.pose import rig

    straight = drawn(face, FaceState(mouth=(("a", 0.6), ("i", 0.4))))
    rolled = drawn(face, FaceState(pose=Pose(0, 0, 10), mouth=(("a", 0.6), ("i", 0.4))))
    origin = rig(lift(face)).origin
    angle = np.radians(-10)  # positive roll turns the image counter-clockwise on screen (y down)
    turn = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    np.testing.assert_allclose((straight.lips - origin) @ turn.T + origin, rolled.lips, atol=1e-6)
