"""Turned faces (thesis 002, 2.4.3, Alg. 2.3): frontal identity, mirror symmetry,
rigid rotation, sign conventions, silhouettes, nose side, gaze (poses on a grid:
test_pose_turns.py)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from cartoonface.errors import OptionError
from cartoonface.face.lift import FRONT_NAMES, LIFTED_INDEX, lift
from cartoonface.face.model import POINT_NAMES, load_face
from cartoonface.face.pose import pose_face, rotate, rotation_matrices, rotation_matrix
from cartoonface.face.state import FaceState, Pose
from cartoonface.render.geometry import inside
from tests.mirror import SWAP, mirrored

# The front layer mirrored: the crown runs left to right and the hairline right to left,
# so a mirror image reverses each.
_CROWN = [i for i, n in enumerate(FRONT_NAMES) if n.startswith("crown")]
_HAIRLINE = [i for i, n in enumerate(FRONT_NAMES) if n.startswith("hairline")]
_FRONT_MIRROR = np.array(_CROWN[::-1] + _HAIRLINE[::-1])


@pytest.fixture(params=("female", "male"), scope="module")
def face(request):
    from tests.conftest import ROOT

    return load_face(ROOT / "samples" / "faces" / f"{request.param}.json")


def test_neutral_frontal_pose_reproduces_the_model(face):
    posed = pose_face(lift(face), FaceState())
    assert np.allclose(posed.xy[: len(POINT_NAMES)], face.points)
    assert np.allclose(posed.hair, face.hair)
    assert np.allclose(posed.pupils, [face.point("3.6"), face.point("3.5")])
    assert np.allclose(posed.iris_r, [face.fapu.r1, face.fapu.r2])
    assert posed.p("9.15") == pytest.approx(face.point("9.15"))


@pytest.mark.parametrize(("tilt", "turn", "roll"), [(0, 6, 0), (0, 15, 0), (0, 11, 0), (7, 13, -9), (-15, 9.5, 15),
                                                   (15, 15, 15), (-15, 15, -15), (15, 15, -15)])
def test_mirrored_face_at_plus_turn_mirrors_face_at_minus_turn(face, tilt, turn, roll):
    original, mirror = mirrored(face, skew=4.0)
    state = FaceState(blink=0.3, smile=0.6, brow=0.4, mouth=(("a", 0.7), ("u", 0.3)))
    a = pose_face(lift(original), FaceState(**{**state.__dict__, "pose": Pose(tilt, -turn, -roll)}))
    b = pose_face(lift(mirror), FaceState(**{**state.__dict__, "pose": Pose(tilt, turn, roll)}))
    w = face.width
    assert np.allclose(w - b.xy[SWAP, 0], a.xy[:, 0], atol=1e-6)
    assert np.allclose(b.xy[SWAP, 1], a.xy[:, 1], atol=1e-6)
    assert np.allclose(w - b.hair[:, 0], a.hair[:, 0], atol=1e-6)
    assert np.allclose(b.hair[:, 1], a.hair[:, 1], atol=1e-6)
    assert np.allclose(w - b.front[:, 0], a.front[::1, 0][_FRONT_MIRROR], atol=1e-6)
    assert np.allclose(b.front[:, 1], a.front[_FRONT_MIRROR, 1], atol=1e-6)
    assert np.allclose(w - b.pupils[::-1, 0], a.pupils[:, 0], atol=1e-6)
    assert a.nose_side == -b.nose_side


def test_rotation_keeps_3d_distances(face):
    local = np.vstack([lift(face).local, lift(face).hair])
    before = np.linalg.norm(local[:, None] - local[None], axis=2)
    for angles in itertools.product((-15, -4, 0, 9, 15), repeat=3):
        pose = Pose(*angles)
        after = rotate(local, pose)
        assert np.allclose(np.linalg.norm(after[:, None] - after[None], axis=2), before)
        m = rotation_matrix(pose)
        assert np.allclose(m @ m.T, np.eye(3)) and np.linalg.det(m) == pytest.approx(1.0)


def test_rotation_order_is_turn_then_tilt_then_roll():
    pose = Pose(tilt=12, turn=-9, roll=5)
    p = np.array([[10.0, 20.0, 30.0]])
    one_at_a_time = rotate(rotate(rotate(p, Pose(turn=-9)), Pose(tilt=12)), Pose(roll=5))
    assert np.allclose(rotate(p, pose), one_at_a_time)
    assert not np.allclose(rotate(rotate(rotate(p, Pose(roll=5)), Pose(tilt=12)), Pose(turn=-9)), one_at_a_time)


def test_rotations_of_many_poses_are_each_pose_s_alone():
    # each slice as the pose's rotation alone, to the last bit, whatever the other poses and their order
    rng = np.random.default_rng(5)
    poses = [Pose(*angles) for angles in rng.uniform(-15, 15, (40, 3)).tolist()] + [Pose(), Pose(3, 0, 0)]
    together = rotation_matrices(poses)
    backwards = rotation_matrices(poses[::-1])
    assert together.shape == (len(poses), 3, 3)
    for index, pose in enumerate(poses):
        alone = rotation_matrix(pose)
        assert np.array_equal(together[index], alone) and np.array_equal(backwards[-1 - index], alone)
        assert np.allclose(alone @ alone.T, np.eye(3))
    assert rotation_matrices([]).shape == (0, 3, 3)


def test_sign_conventions(face):
    lifted = lift(face)
    front = pose_face(lifted, FaceState())
    nose = LIFTED_INDEX["9.15"]
    right = pose_face(lifted, FaceState(pose=Pose(turn=10)))
    assert right.xy[nose, 0] > front.xy[nose, 0]  # positive turn: nose to the image right
    down = pose_face(lifted, FaceState(pose=Pose(tilt=10)))
    assert down.xy[nose, 1] > front.xy[nose, 1]  # positive tilt: the face looks down
    rolled = pose_face(lifted, FaceState(pose=Pose(roll=10)))
    top = LIFTED_INDEX["11.1"]
    assert rolled.xy[top, 0] < front.xy[top, 0]  # positive roll: counter-clockwise on screen


# The outline point and the outermost point of its cross-section agree within this many d: exactly
# for a turn alone; with tilt too, the view no longer lies in the plane of a cross-section.
TOLERANCE = 0.03


def _cross_section(lifted, k, count=721):
    """(count, 3) local points of silhouette k's cross-section (face/lift.py Silhouette):
    the front half ellipse and the back one, from the point inwards."""
    outline = lifted.silhouette
    row = outline.rows[k]
    stacked = np.vstack([lifted.local, lifted.hair, lifted.front])
    point, normal, reach = stacked[row], outline.normals[k], outline.reach[k]
    t = np.linspace(0, np.pi, count)
    depth = np.where(t < np.pi / 2, outline.front[k], outline.back[k])
    across = point[:2] + (reach * (np.sin(t) - 1))[:, None] * normal
    return np.column_stack([across, point[2] + depth * np.cos(t)]), normal


@pytest.mark.parametrize("angles", [(0, 15, 0), (0, -15, 0), (0, 10, 0), (12, -7, 5), (-15, 15, -15), (15, 15, 15)])
def test_outline_points_are_where_the_view_grazes_the_head(face, angles):
    """Each outline point (temples, cheeks, jaw corners, hair) is drawn at the outermost
    point of its cross-section as the posed head shows it, measured along its normal
    turned with the head: the outline of a round head, not a point turned rigidly."""
    lifted = lift(face)
    pose = Pose(*angles)
    posed = pose_face(lifted, FaceState(pose=pose))
    drawn = np.vstack([posed.xy, posed.hair, posed.front])
    m = rotation_matrix(pose)
    for k, row in enumerate(lifted.silhouette.rows):
        section, normal = _cross_section(lifted, k)
        seen = rotate(section, pose)[:, :2] * [1, -1] + lifted.origin  # local y up -> image y down
        outward = (m[:2, :2] @ normal) * [1, -1]
        best = seen[np.argmax(seen @ outward)]
        assert np.linalg.norm(drawn[row] - best) < TOLERANCE * face.fapu.d, (k, np.linalg.norm(drawn[row] - best))


def test_far_contour_is_nearer_the_nose_than_the_near_one(face):
    """Turned 10 to 15 degrees, the far half of the face (nose tip to far cheek) is
    narrower than the near half, and narrower than Alg. 2.3's replacement point M / L
    (as wide as the cheek, 1.11 d forward) would draw it: the far cheek recedes."""
    lifted = lift(face)
    for turn in (10, 12.5, 15, -10, -15):
        posed = pose_face(lifted, FaceState(pose=Pose(turn=turn)))
        far, near, swap = ("10.9", "10.10", "M") if turn > 0 else ("10.10", "10.9", "L")
        nose = posed.p("9.15")[0]
        assert 0 < (posed.p(far)[0] - nose) * np.sign(turn) < (nose - posed.p(near)[0]) * np.sign(turn)
        assert abs(posed.p(far)[0] - nose) < abs(posed.p(swap)[0] - nose)


def test_contour_swap_moves_continuously(face):
    lifted = lift(face)
    turns = np.linspace(0, 15, 301)
    xs = np.array([pose_face(lifted, FaceState(pose=Pose(turn=t))).p("10.9") for t in turns])
    steps = np.linalg.norm(np.diff(xs, axis=0), axis=1)
    assert steps.max() < 0.02 * face.fapu.d


def test_nose_is_drawn_from_the_turned_side(face):
    lifted = lift(face)
    assert pose_face(lifted, FaceState(pose=Pose(turn=3))).nose_side == 1
    assert pose_face(lifted, FaceState(pose=Pose(turn=-3))).nose_side == -1
    assert pose_face(lifted, FaceState()).nose_side == -1


def test_far_side_hair_stays_outside_the_face(face):
    """The hair's outline turns round the head like the face's: on the far side its
    outermost point at or above the eyes stays outside the far temple at every turn."""
    lifted = lift(face)
    above = lifted.hair[:, 1] >= lifted.local[LIFTED_INDEX["3.5"], 1]
    for turn in (5, 10, 15, -5, -10, -15):
        posed = pose_face(lifted, FaceState(pose=Pose(turn=turn)))
        side = np.sign(turn)
        outer = np.max(np.where(above, side * posed.hair[:, 0], -np.inf))
        temple = posed.p("11.3" if turn > 0 else "11.2")[0]
        assert outer > side * temple


def test_eyes_keep_gazing_at_the_focus(face):
    lifted = lift(face)
    front = pose_face(lifted, FaceState())

    def offset(posed):
        corners = (posed.p("3.12") + posed.p("3.8")) / 2, (posed.p("3.7") + posed.p("3.11")) / 2
        return posed.pupils[:, 0] - np.array([corners[0][0], corners[1][0]])

    base = offset(front)
    turned = offset(pose_face(lifted, FaceState(pose=Pose(turn=15))))
    assert np.all(turned < base)  # head turns right, the eyes turn back left in their sockets
    turned = offset(pose_face(lifted, FaceState(pose=Pose(turn=-15))))
    assert np.all(turned > base)


def _distance_to_outline(point, polygon):
    a, b = polygon, np.roll(polygon, -1, axis=0)
    t = np.clip(np.einsum("ij,ij->i", point - a, b - a) / np.einsum("ij,ij->i", b - a, b - a), 0, 1)
    return float(np.min(np.linalg.norm(a + t[:, None] * (b - a) - point, axis=1)))


@pytest.mark.parametrize("angles", list(itertools.product((-15, 0, 15), repeat=3)))
def test_irises_show_in_the_open_eyes(face, angles):
    """Turned eyes roll in their sockets (a face tilted down looks up), so a pupil may
    pass under a lid, but some of each iris always shows and it never leaves the eye's width."""
    posed = pose_face(lift(face), FaceState(pose=Pose(*angles)))
    eyes = (("3.12", "3.2", "3.8", "3.4"), ("3.7", "3.1", "3.11", "3.3"))
    for pupil, radius, names in zip(posed.pupils, posed.iris_r, eyes):
        outline = np.array([posed.p(n) for n in names])
        assert inside(pupil, outline) or _distance_to_outline(pupil, outline) < radius
        corners = outline[[0, 2]]
        along = (pupil - corners[0]) @ (corners[1] - corners[0]) / np.sum((corners[1] - corners[0]) ** 2)
        assert 0.2 < along < 0.8


def test_frontal_pupils_are_inside_the_eyes(face):
    posed = pose_face(lift(face), FaceState())
    assert inside(posed.pupils[0], np.array([posed.p(n) for n in ("3.12", "3.2", "3.8", "3.4")]))
    assert inside(posed.pupils[1], np.array([posed.p(n) for n in ("3.7", "3.1", "3.11", "3.3")]))


def test_each_call_returns_fresh_arrays(face):
    lifted = lift(face)
    a = pose_face(lifted, FaceState(pose=Pose(turn=12)))
    copy = a.xy.copy()
    b = pose_face(lifted, FaceState(pose=Pose(turn=-12)))
    b.xy[:] = 0
    assert np.array_equal(a.xy, copy)


@pytest.mark.parametrize(("field", "value"), [("turn", 40), ("tilt", -15.5), ("roll", float("nan")), ("turn", "left")])
def test_out_of_range_angle_is_refused(field, value):
    with pytest.raises(OptionError, match=field):
        Pose(**{field: value})


def test_rotation_follows_the_thesis_equations():
    """Thesis 2.4.3.1 step by step: about Y, then X, then Z (x, y as printed)."""
    rng = np.random.default_rng(3)
    for _ in range(20):
        a, b, g = rng.uniform(-15, 15, 3)
        x, y, z = rng.uniform(-100, 100, 3)
        ra, rb, rg = np.radians([a, b, g])
        x1, y1, z1 = x * np.cos(rb) + z * np.sin(rb), y, -x * np.sin(rb) + z * np.cos(rb)
        x2, y2 = x1, y1 * np.cos(ra) - z1 * np.sin(ra)
        x3, y3 = x2 * np.cos(rg) - y2 * np.sin(rg), x2 * np.sin(rg) + y2 * np.cos(rg)
        assert rotate(np.array([[x, y, z]]), Pose(a, b, g))[0, :2] == pytest.approx([x3, y3])


def test_numpy_numbers_are_accepted_as_plain_floats():
    pose = Pose(np.float32(3.5), np.int64(-7), np.float64(0.25))
    assert pose == Pose(3.5, -7.0, 0.25)
    assert type(pose.turn) is float
    state = FaceState(pose=pose, blink=np.float32(0.5), mouth=(("a", np.float64(1.0)),))
    assert type(state.blink) is float and state.blink == 0.5


@pytest.mark.parametrize("angles", list(itertools.product((-15, 0, 15), repeat=3)))
def test_iris_centre_stays_inside_the_lids(face, angles):
    """The gaze may roll an eye up, but each iris centre stays a share of its radius
    below the upper lid and above the lower lid (pose.IRIS_KEEP), so the iris never
    vanishes under a lid of an open eye."""
    posed = pose_face(lift(face), FaceState(pose=Pose(*angles)))
    for pupil, radius, (upper, lower) in zip(posed.pupils, posed.iris_r, (("3.2", "3.4"), ("3.1", "3.3"))):
        u, lo = posed.p(upper), posed.p(lower)
        axis = lo - u
        t = (pupil - u) @ axis / (axis @ axis)
        margin = 0.3 * radius / np.linalg.norm(axis)
        assert margin <= t <= 1 - margin


def _turn_angle(a, b, c):
    """Degrees the path a -> b -> c turns at b (0 = straight on)."""
    u, v = b - a, c - b
    return float(np.degrees(np.arccos(np.clip(u @ v / np.linalg.norm(u) / np.linalg.norm(v), -1, 1))))


@pytest.mark.parametrize("mouth", ("m", "a", "o"))
@pytest.mark.parametrize("angles", list(itertools.product((-15, 0, 15), repeat=3)))
def test_chin_stays_below_the_mouth_and_round(face, angles, mouth):
    """At every pose the chin 2.1 is below the lower lip 8.2 (along the face's own
    vertical) and the jaw polyline 2.14 -> 2.1 -> 2.13 turns by less than 100 degrees
    at the chin (no spike)."""
    posed = pose_face(lift(face), FaceState(pose=Pose(*angles)).with_mouth(mouth))
    down = posed.p("2.1") - (posed.p("3.5") + posed.p("3.6")) / 2
    assert (posed.p("2.1") - posed.p("8.2")) @ down > 0
    assert _turn_angle(posed.p("2.14"), posed.p("2.1"), posed.p("2.13")) < 100
