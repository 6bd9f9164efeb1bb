"""Turns that look like turns (docs/pose.md): properties of the posed face over a grid of
head poses within +-15 degrees, corners and combinations included, on both sample faces."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from cartoonface.face.lift import FRONT_NAMES, lift
from cartoonface.face.model import load_face
from cartoonface.face.pose import PosedFace, pose_face, unroll
from cartoonface.face.state import FaceState, Pose
from cartoonface.render.geometry import FACE_CONTOUR, contour, inside
from cartoonface.render.svg import OUTLINE
from tests.mirror import SWAP, mirrored

ANGLES = (-15.0, -7.5, 0.0, 10.0, 15.0)
POSES = [Pose(*angles) for angles in itertools.product(ANGLES, repeat=3)]
MOUTHS = ("m", "a", "o")
SAMPLES_PER_PIECE = 12
# Looking up, the chin stays below each jaw corner by at least this share of its frontal
# drop below it (the jaw line flattens a little; before the jaw's floor, tilt -15 left a
# fifth of it: a flat-bottomed box).
CHIN_DROP_KEPT = 0.5
# The drawn outline turns across a jaw corner at most this many degrees more than at the
# frontal view (pure turns reach 6; before the jaw's floor, tilt -15 reached 22).
CORNER_SLACK = 12.0


@pytest.fixture(params=("female", "male"), scope="module")
def posed_grid(request):
    """(face, [(pose, mouth, PosedFace)]) over POSES x MOUTHS."""
    from tests.conftest import ROOT

    face = load_face(ROOT / "samples" / "faces" / f"{request.param}.json")
    lifted = lift(face)
    return face, [(pose, mouth, pose_face(lifted, FaceState(pose=pose).with_mouth(mouth)))
                  for pose in POSES for mouth in MOUTHS]


def _axes(posed: PosedFace) -> tuple[np.ndarray, np.ndarray, float]:
    """The face's own up axis (from the mouth corners to the eyebrows), a unit vector to its
    image right, and the mouth-to-brow distance in pixels."""
    brow = np.mean([posed.p(n) for n in ("4.1", "4.2", "4.3", "4.4", "4.5", "4.6")], axis=0)
    mouth = (posed.p("8.3") + posed.p("8.4")) / 2
    span = float(np.linalg.norm(brow - mouth))
    up = (brow - mouth) / span
    return up, np.array([-up[1], up[0]]), span


def _height(posed: PosedFace, point: np.ndarray) -> float:
    """Height of `point` along the face's up axis: 0 at the mouth corners, 1 at the eyebrows."""
    up, _, span = _axes(posed)
    return float((point - (posed.p("8.3") + posed.p("8.4")) / 2) @ up / span)


def _bezier_samples(pieces: np.ndarray, start: np.ndarray) -> np.ndarray:
    """(k, 2) points along cubic Bezier pieces (n, 3, 2) that start at `start` (2,)."""
    t = np.linspace(0, 1, SAMPLES_PER_PIECE, endpoint=False)[:, None]
    out, here = [], start
    for c1, c2, end in pieces:
        out.append((1 - t) ** 3 * here + 3 * (1 - t) ** 2 * t * c1 + 3 * (1 - t) * t**2 * c2 + t**3 * end)
        here = end
    out.append(here[None])
    return np.concatenate(out)


def _face_outline(posed: PosedFace) -> list[np.ndarray]:
    """The drawn face contour (render/geometry.py's FACE_CONTOUR, smooth joins) sampled, one
    (k, 2) array per arc."""
    arcs = [np.array([posed.p(n) for n in names]) for names in FACE_CONTOUR]
    pieces = contour(arcs, smooth=True)
    out, first = [], 0
    for points in arcs:
        count = len(points) - 1
        out.append(_bezier_samples(pieces[first:first + count], points[0]))
        first += count
    return out


def test_jaw_is_a_smooth_convex_curve(posed_grid):
    """From the right temple down round the chin to the left temple the drawn contour lies
    on its convex hull, within the width of the outline drawn over it (no dent a viewer can
    see, no cheek bulging out and back), and never turns sharply (no corner at the chin)."""
    face, grid = posed_grid
    for pose, mouth, posed in grid:
        arcs = _face_outline(posed)[1:]
        lower = np.concatenate([arc[:-1] for arc in arcs] + [arcs[-1][-1:]])
        hull = ConvexHull(lower)
        dent = -np.max(lower @ hull.equations[:, :2].T + hull.equations[:, 2], axis=1)
        assert dent.max() < OUTLINE * face.fapu.d, (pose, mouth, dent.max())
        steps = np.diff(lower, axis=0)
        turning = np.degrees(np.arctan2(steps[:-1, 0] * steps[1:, 1] - steps[:-1, 1] * steps[1:, 0],
                                        np.einsum("ij,ij->i", steps[:-1], steps[1:])))
        assert np.abs(turning).max() < 30, (pose, mouth, turning)


def test_ears_stay_between_brow_and_mouth(posed_grid):
    """Each ear's middle stays between the mouth corners' and the eyebrows' heights,
    measured along the face's own up axis, at every pose."""
    _, grid = posed_grid
    for pose, _mouth, posed in grid:
        for loop in (("10.2", "10.8", "A"), ("10.1", "10.7", "B")):
            middle = np.mean([posed.p(n) for n in loop], axis=0)
            assert 0.1 < _height(posed, middle) < 1.0, (pose, loop)


def test_far_ear_goes_behind_the_cheek(posed_grid):
    """Turned 15 degrees, the far ear's top and lobe lie inside the face's outline: the
    cheek hides it, whatever the tilt and roll."""
    _, grid = posed_grid
    for pose, _mouth, posed in grid:
        if abs(pose.turn) < 15:
            continue
        outline = np.concatenate([arc[:-1] for arc in _face_outline(posed)])
        for name in ("10.1", "10.7") if pose.turn > 0 else ("10.2", "10.8"):
            assert inside(posed.p(name), outline), (pose, name)


def test_far_half_of_the_face_is_narrower(posed_grid):
    """Turned 10 degrees or more, the nose tip is nearer the far cheek than the near one
    (measured across the face), and the far cheek stays beyond the nose."""
    _, grid = posed_grid
    for pose, _mouth, posed in grid:
        if abs(pose.turn) < 10:
            continue
        _, right, _ = _axes(posed)
        far, near = ("10.9", "10.10") if pose.turn > 0 else ("10.10", "10.9")
        side = np.sign(pose.turn)
        nose = posed.p("9.15") @ right
        assert 0 < side * (posed.p(far) @ right - nose) < side * (nose - posed.p(near) @ right), pose


def test_nose_stays_between_the_eyes_and_above_the_mouth(posed_grid):
    """The nose tip lies across the face between the pupils, below the eyes and above the
    mouth corners, and inside the face outline, at every pose."""
    _, grid = posed_grid
    for pose, _mouth, posed in grid:
        _, right, _ = _axes(posed)
        tip = posed.p("9.15")
        left_eye, right_eye = sorted(posed.pupils @ right)
        assert left_eye < tip @ right < right_eye, pose
        eyes = _height(posed, posed.pupils.mean(axis=0))
        assert 0 < _height(posed, tip) < eyes, pose
        assert inside(tip, np.concatenate([arc[:-1] for arc in _face_outline(posed)])), pose


def test_hair_covers_the_top_of_the_head(posed_grid):
    """The hair's front layer covers the top of the forehead contour (11.2a, 11.1, 11.3a)
    and rises above it by at least a tenth of d at every pose: no bald crown, no strip of
    hair when the head tilts back."""
    face, grid = posed_grid
    crown = [FRONT_NAMES.index(n) for n in FRONT_NAMES if n.startswith("crown")]
    hairline = [FRONT_NAMES.index(n) for n in FRONT_NAMES if n.startswith("hairline")]
    for pose, _mouth, posed in grid:
        polygon = np.vstack([posed.front[crown], posed.p("11.3")[None], posed.front[hairline], posed.p("11.2")[None]])
        for name in ("11.2a", "11.1", "11.3a"):
            assert inside(posed.p(name), polygon), (pose, name)
        up, _, _ = _axes(posed)
        above = np.max((np.vstack([posed.hair, posed.front]) - posed.p("11.1")) @ up)
        assert above > 0.1 * face.fapu.d, pose


def test_back_layer_stays_behind_the_crown(posed_grid):
    """The hair's back layer never shows a second outline above the front layer's crown:
    along the face's up axis its top is within a twentieth of d of the crown's."""
    face, grid = posed_grid
    for pose, _mouth, posed in grid:
        up, _, _ = _axes(posed)
        assert np.max(posed.hair @ up) - np.max(posed.front @ up) < 0.05 * face.fapu.d, pose


def _unrolled(face, pose: Pose, posed: PosedFace) -> PosedFace:
    """`posed` turned back by its roll about the rotation origin: its image y is the head's
    own down axis."""
    return unroll(posed, pose.roll, lift(face).origin)


def _corner_turns(posed: PosedFace) -> tuple[float, float]:
    """Degrees the drawn face contour turns across the jaw corners 2.13 and 2.14: between its
    directions in the middle of the piece before each corner and of the piece after it."""
    arcs = _face_outline(posed)
    middle = SAMPLES_PER_PIECE // 2
    turns = []
    for before, after in ((arcs[1], arcs[2]), (arcs[2], arcs[3])):
        a = before[-middle] - before[-middle - 2]
        b = after[middle + 1] - after[middle - 1]
        turns.append(float(np.degrees(np.arctan2(a[0] * b[1] - a[1] * b[0], a @ b))))
    return turns[0], turns[1]


def test_chin_stays_the_lowest_point_looking_up(posed_grid):
    """With the face level or looking up (tilt <= 0), along the head's own down axis no
    point of the drawn contour lies lower than the chin 2.1 (within half the outline's
    width) and the chin stays below each jaw corner by at least CHIN_DROP_KEPT of its drop
    below it at the frontal view: a U/V jaw, not a flat-bottomed box."""
    face, grid = posed_grid
    frontal = {mouth: posed for pose, mouth, posed in grid if pose == Pose()}
    for pose, mouth, posed in grid:
        if pose.tilt > 0:
            continue
        level = _unrolled(face, pose, posed)
        chin = level.p("2.1")[1]
        lowest = max(arc[:, 1].max() for arc in _face_outline(level))
        assert lowest - chin < OUTLINE / 2 * face.fapu.d, (pose, mouth, lowest - chin)
        for corner in ("2.13", "2.14"):
            drop = frontal[mouth].p("2.1")[1] - frontal[mouth].p(corner)[1]
            assert chin - level.p(corner)[1] > CHIN_DROP_KEPT * drop, (pose, mouth, corner)


def test_jaw_corners_no_sharper_than_frontal(posed_grid):
    """The drawn contour turns across each jaw corner at most CORNER_SLACK degrees more
    than at the frontal view with the same mouth, at every pose (no box corner)."""
    _, grid = posed_grid
    frontal = {mouth: _corner_turns(posed) for pose, mouth, posed in grid if pose == Pose()}
    for pose, mouth, posed in grid:
        for turned, level in zip(_corner_turns(posed), frontal[mouth]):
            assert turned < level + CORNER_SLACK, (pose, mouth, turned, level)


def test_mirrored_poses_mirror_the_face(posed_grid):
    """The sample face's mirror image posed with the turn and roll reversed is the mirror
    image of the posed face (points, hair, front layer), at every pose of the grid."""
    face, grid = posed_grid
    _, mirror = mirrored(face)
    lifted = lift(mirror)
    for pose, mouth, posed in grid:
        flipped = pose_face(lifted, FaceState(pose=Pose(pose.tilt, -pose.turn, -pose.roll)).with_mouth(mouth))
        assert np.allclose(face.width - flipped.xy[SWAP, 0], posed.xy[:, 0], atol=1e-6), pose
        assert np.allclose(flipped.xy[SWAP, 1], posed.xy[:, 1], atol=1e-6), pose
        assert np.allclose(face.width - flipped.hair[:, 0], posed.hair[:, 0], atol=1e-6), pose
