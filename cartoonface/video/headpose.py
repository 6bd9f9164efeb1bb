"""Head pose from a video of a talking person: two estimators (seed 003).

mesh_pose reads the pose off one frame's face mesh (photo/landmarks.py, 478 points):
the head's axes from mirror pairs of rigid points (eye corners, cheeks, nose wings)
and the midline (forehead to nose base); zero is the mesh's own frontal face (its
forehead-to-nose-base line upright: on the GRID clips, speakers facing the camera,
the median tilt is 1-1.3 degrees). Angles are in the project's Pose convention
(face/state.py, face/pose.py rotation_matrix: Rz(roll) Rx(tilt) Ry(turn) in a frame
x right, y up, z towards the viewer): tilt + looks down, turn + moves the nose to the
image right, roll + moves the top of the head to the image left.
"""

from __future__ import annotations

import math

import numpy as np

# Face mesh indices (photo/landmarks.py's IBUG68 choice plus the forehead midline),
# rigid under speech and expression: (image-left, image-right) of a frontal face.
MIRROR_PAIRS = (
    (33, 263), (133, 362),  # eye corners, outer and inner
    (127, 356), (234, 454), (93, 323),  # face oval at the temples and cheeks
    (98, 327), (97, 326),  # nose wings
)
# The midline from the forehead (top) to the nose base (bottom).
FOREHEAD = (10, 151, 9)
NOSE_BASE = (2, 98, 327)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def mesh_axes(points: np.ndarray) -> np.ndarray:
    """(3, 3) rotation whose columns are the head's right, up and front axes in the
    local frame (x right, y up, z towards the viewer) from `points` ((478, 3) face
    mesh: x, y image pixels with y down, z depth in pixels, smaller nearer)."""
    local = points[:, :3] * np.array([1.0, -1.0, -1.0])
    left = local[[a for a, _ in MIRROR_PAIRS]]
    right = local[[b for _, b in MIRROR_PAIRS]]
    across = _unit((right - left).sum(axis=0))
    up = local[list(FOREHEAD)].mean(axis=0) - local[list(NOSE_BASE)].mean(axis=0)
    up = _unit(up - across * (up @ across))
    return np.column_stack([across, up, np.cross(across, up)])


def angles(rotation: np.ndarray) -> tuple[float, float, float]:
    """(tilt, turn, roll) degrees of a (3, 3) rotation in face/pose.py's frame and
    order (rotation = Rz(roll) @ Rx(tilt) @ Ry(turn))."""
    tilt = math.asin(float(np.clip(rotation[2, 1], -1.0, 1.0)))
    turn = math.atan2(-rotation[2, 0], rotation[2, 2])
    roll = math.atan2(-rotation[0, 1], rotation[1, 1])
    return math.degrees(tilt), math.degrees(turn), math.degrees(roll)


def mesh_pose(points: np.ndarray) -> tuple[float, float, float]:
    """(tilt, turn, roll) degrees of the head whose face mesh is `points` ((478, 3)
    as photo/landmarks.py's Landmarks.points: image pixels, y down, z depth in
    pixels). Not clamped: the caller clamps to Pose's range."""
    return angles(mesh_axes(points))
