"""Head pose from video frames (cartoonface.video.headpose, seed 003).

The frames are skimage.data.astronaut() (a 512 x 512 portrait shipped by scikit-image)
and pictures made from it: rolled by a known angle, mirrored, repeated as a still clip.
Needs the photo extra (mediapipe, OpenCV, scikit-image); without it the module is skipped.
"""

from __future__ import annotations

import functools
from importlib.util import find_spec

import numpy as np
import pytest

MISSING = [name for name in ("mediapipe", "cv2", "skimage") if find_spec(name) is None]
pytestmark = pytest.mark.skipif(
    bool(MISSING), reason=f"the photo extra is not installed (missing {', '.join(MISSING)}): "
                          "scripts/setup.sh installs it")

if not MISSING:
    import cv2
    from skimage import data

    from cartoonface.face.pose import rotation_matrix
    from cartoonface.face.state import Pose
    from cartoonface.photo.landmarks import landmarker
    from cartoonface.video.headpose import (FLIP, Start, angles, mesh_axes, mesh_pose, mesh_start, pose_rotation,
                                             rotation_pose, towards, track_cylinder)

# How close the mesh's roll follows an exact in-plane rotation of the picture, degrees.
ROLL_BOUND = 1.5
# How far a mirrored picture's turn / roll may be from the negated original's (and its tilt
# from the original's), degrees: the mesh network itself is not exactly mirror-symmetric
# (on the astronaut the two differ by up to 1.4 degrees).
MIRROR_BOUND = 2.0
# The cylinder tracker: a still clip (sensor noise only) moves less than STILL_BOUND on
# any axis; a roll of the picture comes back within TRACK_ROLL_BOUND, and the other axes
# stay within TRACK_OTHER_BOUND (an image rotation about a point off the optical axis is
# not exactly a head roll under perspective).
STILL_BOUND = 0.2
TRACK_ROLL_BOUND = 1.0
TRACK_OTHER_BOUND = 3.0
# How far a face partly covered for a few frames may move the pose, degrees.
OCCLUDED_BOUND = 0.5
# Sensor noise added to each frame of the still clip (gray levels, standard deviation).
NOISE = 2.0


@functools.lru_cache(maxsize=1)
def photo() -> np.ndarray:
    return np.ascontiguousarray(data.astronaut())


def rolled(rgb: np.ndarray, degrees: float, centre: tuple[float, float]) -> np.ndarray:
    """`rgb` turned `degrees` counter-clockwise on screen about `centre` (the top of the
    head moves to the image left for a positive angle)."""
    matrix = cv2.getRotationMatrix2D(centre, degrees, 1.0)
    return cv2.warpAffine(rgb, matrix, (rgb.shape[1], rgb.shape[0]), borderMode=cv2.BORDER_REPLICATE)


def points(rgb: np.ndarray) -> np.ndarray:
    found = landmarker().find(rgb)
    assert found is not None
    return found.points


def face_centre(rgb: np.ndarray) -> tuple[float, float]:
    x, y = points(rgb)[:, :2].mean(axis=0)
    return float(x), float(y)


@pytest.mark.parametrize("degrees", [-12.0, 8.0])
def test_a_rolled_picture_gives_its_roll_back(degrees: float) -> None:
    still = photo()
    base = mesh_pose(points(still))
    turned = mesh_pose(points(rolled(still, degrees, face_centre(still))))
    assert abs((turned[2] - base[2]) - degrees) < ROLL_BOUND
    # an in-plane rotation leaves tilt and turn as they were
    assert abs(turned[0] - base[0]) < ROLL_BOUND and abs(turned[1] - base[1]) < ROLL_BOUND


def test_a_mirrored_picture_gives_the_mirrored_turn_and_roll() -> None:
    still = photo()
    tilt, turn, roll = mesh_pose(points(still))
    m_tilt, m_turn, m_roll = mesh_pose(points(np.ascontiguousarray(still[:, ::-1])))
    assert abs(m_turn + turn) < MIRROR_BOUND and abs(m_roll + roll) < MIRROR_BOUND
    assert abs(m_tilt - tilt) < MIRROR_BOUND


@pytest.mark.parametrize("pose", [(10.0, 0.0, 0.0), (0.0, -12.0, 0.0), (0.0, 0.0, 7.0), (-8.0, 11.0, -5.0)])
def test_a_rigidly_rotated_mesh_gives_face_pose_convention_angles(pose: tuple[float, float, float]) -> None:
    # the astronaut's mesh turned frontal, then by face/pose.py's rotation_matrix: the
    # angles come back in the project's Pose convention (signs and order)
    mesh = points(photo())
    flip = np.array([1.0, -1.0, -1.0])  # image (y down, z away) <-> local (y up, z front)
    local = mesh * flip
    centre = local.mean(axis=0)
    frontal = (local - centre) @ mesh_axes(mesh)
    posed = frontal @ rotation_matrix(Pose(*pose)).T + centre
    assert np.allclose(mesh_pose(posed * flip), pose, atol=1e-6)
    assert np.allclose(angles(rotation_matrix(Pose(*pose))), pose, atol=1e-9)
    # the tracker's OpenCV-frame rotation is the same rotation, and goes back to the pose
    assert np.allclose(FLIP @ pose_rotation(pose) @ FLIP, rotation_matrix(Pose(*pose)), atol=1e-12)
    assert np.allclose(rotation_pose(pose_rotation(pose)), pose, atol=1e-9)


def gray(rgb: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)


def start_of(rgb: np.ndarray) -> Start:
    return mesh_start(points(rgb))


def relocate(index: int, frame: np.ndarray) -> Start | None:
    """The mesh on a gray frame: the Start the tracker re-initialises from, or None."""
    found = landmarker().find(np.ascontiguousarray(np.repeat(frame[:, :, None], 3, axis=2)))
    return None if found is None else mesh_start(found.points)


def moved(frame: np.ndarray, dx: float, dy: float) -> np.ndarray:
    matrix = np.array([[1.0, 0.0, dx], [0.0, 1.0, dy]])
    return cv2.warpAffine(frame, matrix, (frame.shape[1], frame.shape[0]), borderMode=cv2.BORDER_REPLICATE)


def test_a_still_clip_gives_a_still_pose() -> None:
    rng = np.random.default_rng(3)
    still = gray(photo()).astype(float)
    frames = [np.clip(still + rng.normal(0.0, NOISE, still.shape), 0, 255).astype(np.uint8) for _ in range(15)]
    start = start_of(photo())
    poses = track_cylinder(frames, start)
    assert poses.shape == (15, 3)
    assert np.allclose(poses[0], start.pose, atol=1e-6)
    assert np.ptp(poses, axis=0).max() < STILL_BOUND


def test_the_tracker_follows_a_rolling_picture() -> None:
    still = photo()
    centre = face_centre(still)
    frames = [gray(rolled(still, 10.0 * i / 14, centre)) for i in range(15)]
    poses = track_cylinder(frames, start_of(still))
    change = poses[-1] - poses[0]
    assert abs(change[2] - 10.0) < TRACK_ROLL_BOUND
    assert np.abs(change[:2]).max() < TRACK_OTHER_BOUND
    # it rolls steadily: every step the same way
    assert (np.diff(poses[:, 2]) > 0).all()


def test_a_lost_track_holds_its_pose_then_re_initialises_from_the_mesh() -> None:
    # the face, a blank stretch (nothing to track), then the face rolled 8 degrees and
    # moved far from where the track left it
    still = photo()
    face = gray(still)
    blank = np.full_like(face, 128)
    back = moved(gray(rolled(still, 8.0, face_centre(still))), 120, 150)
    frames = [face] * 4 + [blank] * 8 + [back] * 4
    start = start_of(still)
    calls: list[int] = []

    def counted(index: int, frame: np.ndarray) -> Start | None:
        calls.append(index)
        return relocate(index, frame)

    poses = track_cylinder(frames, start, counted)
    assert np.allclose(poses[:12], poses[0], atol=1e-6)  # held through the blank
    assert calls and calls[-1] == 12 and all(i >= 4 for i in calls)
    again = relocate(0, back)
    assert again is not None
    assert np.allclose(poses[12:], again.pose, atol=STILL_BOUND)
    # without a way to re-initialise, it keeps holding the last pose
    assert np.allclose(track_cylinder(frames, start), poses[0], atol=1e-6)


def test_a_partly_covered_face_keeps_its_pose_and_the_track_goes_on() -> None:
    # the seed's occlusion case: a hand-sized block over part of the face for a few
    # frames, then the face rolls; the track neither jumps nor loses the roll
    still = photo()
    face = gray(still)
    x0, y0, x1, y1 = start_of(still).box
    covered = face.copy()
    covered[int((y0 + y1) / 2):int(y1), int(x0):int((x0 + x1) / 2)] = 90
    centre = face_centre(still)
    frames = [face] * 3 + [covered] * 4 + [face] * 2 + [gray(rolled(still, 6.0 * i / 5, centre)) for i in range(1, 6)]
    poses = track_cylinder(frames, start_of(still))
    assert np.abs(poses[:9] - poses[0]).max() < OCCLUDED_BOUND
    assert abs((poses[-1, 2] - poses[0, 2]) - 6.0) < TRACK_ROLL_BOUND


@pytest.mark.parametrize("point", [(0.0, 0.0, 5.0), (30.0, -40.0, 300.0), (-200.0, 90.0, 100.0)])
def test_towards_turns_the_optical_axis_onto_the_line_of_sight(point: tuple[float, float, float]) -> None:
    rotation = towards(np.array(point))
    sight = np.array(point) / np.linalg.norm(point)
    assert np.allclose(rotation @ np.array([0.0, 0.0, 1.0]), sight, atol=1e-12)
    assert np.allclose(rotation.T @ rotation, np.eye(3), atol=1e-12) and np.isclose(np.linalg.det(rotation), 1.0)
    # the smallest such rotation: what is square to both axes stays put
    normal = np.cross([0.0, 0.0, 1.0], sight)
    assert np.allclose(rotation @ normal, normal, atol=1e-12)
