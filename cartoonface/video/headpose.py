"""Head pose from a video of a talking person: two estimators (seed 003).

mesh_pose reads the pose off one frame's face mesh (photo/landmarks.py, 478 points):
the head's axes from mirror pairs of rigid points (eye corners, cheeks, nose wings)
and the midline (forehead to nose base); zero is the mesh's own frontal face (its
forehead-to-nose-base line upright: on the GRID clips, speakers facing the camera,
the median tilt is 1-1.3 degrees). Angles are in the project's Pose convention
(face/state.py, face/pose.py rotation_matrix: Rz(roll) Rx(tilt) Ry(turn) in a frame
x right, y up, z towards the viewer): tilt + looks down, turn + moves the nose to the
image right, roll + moves the top of the head to the image left.

track_cylinder is seed 003's section 2: a cylindrical head model started from the mesh
(mesh_start), its surface points tracked frame to frame with pyramidal Lucas-Kanade and
its rigid motion fitted to them, with template update, re-registration to the first
frame against drift and re-initialisation when lost. docs/video.md ("Head pose")
compares the two (bench/video_pose.py); the driving code uses mesh_pose.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass

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


# --- The cylinder tracker (seed 003, section 2) ---
#
# Camera: a pinhole at the image centre with this focal length in image widths (the
# clips' lenses are unknown; 1.0 is a ~53 degree field of view, a webcam's).
FOCAL_WIDTHS = 1.0
# The cylinder's radius in face box widths (mesh_start's box spans the face oval from
# cheek to cheek; the head is a little wider): tuned on s1_bbaf2n's synthetic motions
# (bench/video_pose.py; 0.5 to 0.65 tried).
RADIUS_BOXES = 0.55
# The face mesh's rows before the irises (photo/landmarks.py: 468-477 are the irises).
FACE_POINTS = 468
# Template points are sampled in the face box down to this fraction of its height
# (eyes, brows, nose; not the mouth and jaw, which move with speech) and only where the
# cylinder's surface faces the camera within this angle (degrees): nearer the rim a
# pixel's depth is ill-defined.
TEMPLATE_BOTTOM = 0.72
MAX_SLANT = 60.0
# Shi-Tomasi corners per template: at most this many, this far apart (box widths),
# with this quality relative to the strongest corner.
TEMPLATE_POINTS = 120
POINT_SPACING = 0.04
CORNER_QUALITY = 0.01
# Pyramidal Lucas-Kanade (cv2.calcOpticalFlowPyrLK): window side (px), pyramid levels,
# iterations and step for convergence; a point is kept when tracking it back lands
# within FB_PIXELS of where it started (forward-backward check).
LK_WINDOW = 21
LK_LEVELS = 3
LK_ITERATIONS = 30
LK_EPSILON = 0.01
FB_PIXELS = 1.0
# Pose from the tracked points: RANSAC over the rigid motion of the cylinder
# (cv2.solvePnPRansac) with this reprojection bound (px) and iterations.
INLIER_PIXELS = 2.0
RANSAC_ITERATIONS = 60
# A frame is fitted when at least MIN_INLIERS points and this fraction of the tracked
# ones agree; otherwise it counts as occluded (the seed's template recovery).
MIN_INLIERS = 12
MIN_INLIER_SHARE = 0.5
# A fit beyond this angle on any axis (degrees) is not a head pose but a failure.
LOST_ANGLE = 45.0
# Below this many live points the template is refilled at the current pose.
REFILL_POINTS = 60
# After this many occluded frames in a row the track is lost and re-initialised.
LOST_FRAMES = 5
# Drift control: the key template (the frame the track started from) is registered
# again in every frame; its points join the fit when at least KEY_POINTS come back.
# (Registering only within 5 or 10 degrees of the key's pose, where its patches look
# alike, let the pose drift further on the tuning clip: docs/video.md.)
KEY_POINTS = 12
# CV frame (x right, y down, z away) <-> face/pose.py's local frame (y up, z front).
FLIP = np.diag([1.0, -1.0, -1.0])


@dataclass(frozen=True)
class Start:
    """Where a track starts: the head's pose (tilt, turn, roll degrees, as mesh_pose
    gives) and its face box (x0, y0, x1, y1) image pixels (mesh_start makes both)."""

    pose: tuple[float, float, float]
    box: tuple[float, float, float, float]


def mesh_start(points: np.ndarray) -> Start:
    """A track's Start from one face mesh ((478, 3) as mesh_pose takes): its pose and
    the extent (x0, y0, x1, y1) of the face's FACE_POINTS (forehead to chin, cheek to
    cheek; the irises left out)."""
    face = points[:FACE_POINTS, :2]
    x0, y0 = face.min(axis=0)
    x1, y1 = face.max(axis=0)
    return Start(mesh_pose(points), (float(x0), float(y0), float(x1), float(y1)))


@dataclass(frozen=True)
class _Template:
    """An image and the cylinder points seen in it: gray (H, W) uint8, xy (k, 2) float32
    image pixels, model (k, 3) the same points on the cylinder in the head's frame."""

    gray: np.ndarray
    xy: np.ndarray
    model: np.ndarray


def camera(shape: tuple[int, ...]) -> np.ndarray:
    """(3, 3) pinhole matrix for a frame of `shape` (H, W): FOCAL_WIDTHS, centred."""
    height, width = shape[:2]
    focal = FOCAL_WIDTHS * width
    return np.array([[focal, 0.0, width / 2], [0.0, focal, height / 2], [0.0, 0.0, 1.0]])


def pose_rotation(pose: tuple[float, float, float]) -> np.ndarray:
    """(3, 3) head-to-camera rotation in OpenCV's frame for (tilt, turn, roll) degrees
    (face/pose.py's rotation_matrix, Rz(roll) @ Rx(tilt) @ Ry(turn), without Pose's
    +-15 degree limit: a tracked head may start further turned)."""
    a, b, g = (math.radians(v) for v in pose)
    about_x = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(a), -math.sin(a)], [0.0, math.sin(a), math.cos(a)]])
    about_y = np.array([[math.cos(b), 0.0, math.sin(b)], [0.0, 1.0, 0.0], [-math.sin(b), 0.0, math.cos(b)]])
    about_z = np.array([[math.cos(g), -math.sin(g), 0.0], [math.sin(g), math.cos(g), 0.0], [0.0, 0.0, 1.0]])
    return FLIP @ about_z @ about_x @ about_y @ FLIP


def rotation_pose(rotation: np.ndarray) -> tuple[float, float, float]:
    """(tilt, turn, roll) degrees of a (3, 3) head-to-camera rotation in OpenCV's frame."""
    return angles(FLIP @ rotation @ FLIP)


def towards(point: np.ndarray) -> np.ndarray:
    """(3, 3) the smallest rotation taking the camera's optical axis (0, 0, 1) to the
    line of sight to `point` (3,) (camera coordinates, in front of the camera)."""
    axis = np.array([0.0, 0.0, 1.0])
    sight = point / np.linalg.norm(point)
    across = np.cross(axis, sight)
    sine, cosine = float(np.linalg.norm(across)), float(axis @ sight)
    if sine < 1e-12:
        return np.eye(3)
    k = across / sine
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + sine * cross + (1 - cosine) * cross @ cross


def _relative(rotation: np.ndarray, shift: np.ndarray, radius: float) -> tuple[float, float, float]:
    """(tilt, turn, roll) degrees of the cylinder posed by `rotation` (3, 3) and `shift`
    (3,) relative to the line of sight to the middle of its front (a radius in front of
    its axis)."""
    front = shift - rotation @ np.array([0.0, 0.0, radius])
    return rotation_pose(towards(front).T @ rotation)


def _on_cylinder(xy: np.ndarray, radius: float, rotation: np.ndarray, shift: np.ndarray,
                 matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Back-project image points `xy` (k, 2) onto the cylinder (axis the head's y, of
    `radius`) posed by `rotation` (3, 3) and `shift` (3,) in the camera `matrix`.
    Returns (model (m, 3) points in the head's frame, keep (k,) bool: which points hit
    the cylinder's front within MAX_SLANT)."""
    rays = np.column_stack([xy, np.ones(len(xy))]) @ np.linalg.inv(matrix).T
    origin = -rotation.T @ shift  # the camera centre in the head's frame
    direction = rays @ rotation  # each ray in the head's frame
    dx, dz = direction[:, 0], direction[:, 2]
    a = dx * dx + dz * dz
    b = 2 * (origin[0] * dx + origin[2] * dz)
    c = origin[0] ** 2 + origin[2] ** 2 - radius ** 2
    disc = b * b - 4 * a * c
    hit = disc > 0
    s = (-b - np.sqrt(np.where(hit, disc, 0.0))) / (2 * a)
    model = origin + s[:, None] * direction
    # the front (towards the camera, -z) within MAX_SLANT of facing it
    slant = np.degrees(np.arctan2(np.abs(model[:, 0]), -model[:, 2]))
    keep = hit & (model[:, 2] < 0) & (slant < MAX_SLANT)
    return model[keep], keep


class _Cylinder:
    """The tracker's state over one clip (track_cylinder drives it)."""

    def __init__(self, shape: tuple[int, ...]) -> None:
        self.matrix = camera(shape)
        self.radius = 0.0
        self.rotation = np.eye(3)
        self.shift = np.zeros(3)
        self.box_width = 0.0
        self.half_height = 0.0

    def start(self, gray: np.ndarray, start: Start) -> _Template | None:
        """Fit the cylinder to `start`'s box at its pose and sample the key template."""
        x0, y0, x1, y1 = start.box
        focal = self.matrix[0, 0]
        self.box_width = x1 - x0
        self.half_height = (y1 - y0) / 2
        # 3D units: pixels at the depth of the face's front (distance = focal)
        self.radius = RADIUS_BOXES * self.box_width
        centre = np.array([(x0 + x1) / 2 - self.matrix[0, 2], (y0 + y1) / 2 - self.matrix[1, 2], focal])
        # the mesh's pose is relative to the line of sight to the face
        self.rotation = towards(centre) @ pose_rotation(start.pose)
        # the axis lies a radius behind the face's front along the head's own depth
        self.shift = centre + self.rotation @ np.array([0.0, 0.0, self.radius])
        return self.sample(gray, start.box)

    def pose(self) -> tuple[float, float, float]:
        """(tilt, turn, roll) degrees relative to the line of sight to the head (as the
        mesh gives them: a head off the image centre that faces the camera has 0, 0, 0)."""
        return _relative(self.rotation, self.shift, self.radius)

    def sample(self, gray: np.ndarray, box: tuple[float, float, float, float],
               taken: np.ndarray | None = None) -> _Template | None:
        """A template of `gray`: corners in the upper TEMPLATE_BOTTOM of `box`, away
        from the points `taken` (k, 2) already tracked, put on the cylinder at the
        current pose; None when too few land on it."""
        import cv2

        height, width = gray.shape
        x0, y0, x1, y1 = box
        mask = np.zeros_like(gray)
        mask[max(0, int(y0)):max(0, min(height, int(y0 + (y1 - y0) * TEMPLATE_BOTTOM))),
             max(0, int(x0)):max(0, min(width, int(x1)))] = 255
        spacing = max(1.0, POINT_SPACING * self.box_width)
        for x, y in taken if taken is not None else ():
            cv2.circle(mask, (int(round(x)), int(round(y))), int(round(spacing)), 0, -1)
        corners = cv2.goodFeaturesToTrack(gray, TEMPLATE_POINTS, CORNER_QUALITY, spacing, mask=mask)
        if corners is None:
            return None
        xy = corners.reshape(-1, 2).astype(np.float32)
        model, keep = _on_cylinder(xy, self.radius, self.rotation, self.shift, self.matrix)
        if len(model) < MIN_INLIERS:
            return None
        return _Template(gray, xy[keep], model)

    def box(self) -> tuple[float, float, float, float]:
        """The face box at the current pose, (x0, y0, x1, y1) image pixels: the
        projection of the cylinder's front within MAX_SLANT, as tall as the start box."""
        import cv2

        side = math.sin(math.radians(MAX_SLANT)) * self.radius
        depth = -math.cos(math.radians(MAX_SLANT)) * self.radius
        corners = np.array([[x, y, z] for x, z in ((-side, depth), (0.0, -self.radius), (side, depth))
                            for y in (-self.half_height, self.half_height)])
        xy, _ = cv2.projectPoints(corners, cv2.Rodrigues(self.rotation)[0], self.shift, self.matrix, None)
        xy = xy.reshape(-1, 2)
        return (float(xy[:, 0].min()), float(xy[:, 1].min()), float(xy[:, 0].max()), float(xy[:, 1].max()))

    def project(self, model: np.ndarray) -> np.ndarray:
        """(k, 2) float32 image pixels of head-frame points (k, 3) at the current pose."""
        import cv2

        xy, _ = cv2.projectPoints(model, cv2.Rodrigues(self.rotation)[0], self.shift, self.matrix, None)
        return xy.reshape(-1, 2).astype(np.float32)

    def fit(self, model: np.ndarray, xy: np.ndarray) -> np.ndarray | None:
        """Pose from head-frame points `model` (k, 3) seen at `xy` (k, 2): RANSAC over
        the cylinder's rigid motion from the current pose. Updates the pose and returns
        the inlier mask (k,), or None (pose unchanged) when the fit is not trusted."""
        import cv2

        if len(model) < MIN_INLIERS:
            return None
        guess = np.asarray(cv2.Rodrigues(self.rotation)[0], dtype=float)
        ok, rvec, tvec, inliers = cv2.solvePnPRansac(
            model.astype(np.float64), xy.astype(np.float64), self.matrix, None, guess,
            self.shift.reshape(3, 1).copy(), useExtrinsicGuess=True, iterationsCount=RANSAC_ITERATIONS,
            reprojectionError=INLIER_PIXELS, flags=cv2.SOLVEPNP_ITERATIVE)
        if not ok or inliers is None or len(inliers) < max(MIN_INLIERS, MIN_INLIER_SHARE * len(model)):
            return None
        keep = np.zeros(len(model), dtype=bool)
        keep[np.asarray(inliers).ravel()] = True
        rvec, tvec = cv2.solvePnPRefineLM(model[keep].astype(np.float64), xy[keep].astype(np.float64),
                                          self.matrix, None, rvec, tvec)
        rotation = np.asarray(cv2.Rodrigues(rvec)[0], dtype=float)
        shift = np.asarray(tvec, dtype=float).ravel()
        if max(abs(a) for a in _relative(rotation, shift, self.radius)) > LOST_ANGLE or shift[2] <= self.radius:
            return None
        self.rotation, self.shift = rotation, shift
        return keep


def _flow(before: np.ndarray, after: np.ndarray, xy: np.ndarray,
          guess: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Track points `xy` (k, 2) float32 from gray image `before` to `after` with pyramidal
    Lucas-Kanade (from `guess` (k, 2) when given) and back. Returns (moved (k, 2),
    good (k,) bool: found both ways and back within FB_PIXELS)."""
    import cv2

    window = (LK_WINDOW, LK_WINDOW)
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, LK_ITERATIONS, LK_EPSILON)
    start = xy.copy() if guess is None else guess.astype(np.float32)
    flags = 0 if guess is None else cv2.OPTFLOW_USE_INITIAL_FLOW
    moved, found, _ = cv2.calcOpticalFlowPyrLK(before, after, xy, start, winSize=window, maxLevel=LK_LEVELS,
                                               criteria=criteria, flags=flags)
    back, found_back, _ = cv2.calcOpticalFlowPyrLK(after, before, moved, moved.copy(), winSize=window,
                                                   maxLevel=LK_LEVELS, criteria=criteria)
    good = (found.ravel() == 1) & (found_back.ravel() == 1) & (np.linalg.norm(back - xy, axis=1) < FB_PIXELS)
    return moved, good


def track_cylinder(frames: Iterable[np.ndarray], start: Start,
                   relocate: Callable[[int, np.ndarray], Start | None] | None = None) -> np.ndarray:
    """Head pose per frame by the seed 003 cylindrical head model (section 2).

    frames: gray (H, W) uint8 images; start: the pose and face box on the first frame
    (mesh_start of the frame's face mesh); relocate(index, gray): a new Start for
    a frame when the track is lost (the mesh again), or None (no face: hold the pose).
    Returns (n, 3) float (tilt, turn, roll) degrees, one row per frame.

    A cylinder fitted to the face box carries the template points (corners of the first
    frame, on its surface); each frame they are tracked with pyramidal Lucas-Kanade
    from the template image and the cylinder's rigid motion is fitted to them (RANSAC;
    the seed solves eq. 1-5 densely, we solve the same motion model on sparse points).
    Template update (the seed's last paragraph of section 2): a fitted frame becomes the
    template for the next, points that stop agreeing are dropped and new ones sampled
    on the cylinder at the current pose; a frame that does not fit (occlusion) is
    dropped and the most recent good template kept. Drift control (the seed's reference
    [6], re-registration): the key template of the first frame is tracked into every
    frame from its projection at the current pose and its points join the fit when
    they come back, pulling the pose to the key frame's. After LOST_FRAMES frames
    that do not fit, the track re-initialises from relocate.
    """
    poses: list[tuple[float, float, float]] = []
    tracker: _Cylinder | None = None
    key: _Template | None = None
    template: _Template | None = None
    missed = 0
    for index, gray in enumerate(frames):
        if tracker is None:
            tracker = _Cylinder(gray.shape)
            key = template = tracker.start(gray, start)
        elif template is not None and key is not None:
            template, fitted = _step(tracker, key, template, gray)
            missed = 0 if fitted else missed + 1
        if template is None or key is None or missed >= LOST_FRAMES:
            found = relocate(index, gray) if relocate is not None else None
            if found is not None:
                key = template = tracker.start(gray, found)
                missed = 0
        poses.append(tracker.pose())
    return np.array(poses, dtype=float).reshape(-1, 3)


def _step(tracker: _Cylinder, key: _Template, template: _Template,
          gray: np.ndarray) -> tuple[_Template, bool]:
    """One frame: track, fit, update the template. Returns (the template for the next
    frame, whether this frame was fitted)."""
    moved, good = _flow(template.gray, gray, template.xy)
    model, xy = template.model[good], moved[good]
    # drift control: the key frame's points, tracked from where the pose puts them now
    back, home = _flow(key.gray, gray, key.xy, tracker.project(key.model))
    if home.sum() >= KEY_POINTS:
        model = np.concatenate([model, key.model[home]])
        xy = np.concatenate([xy, back[home]])
    keep = tracker.fit(model, xy)
    if keep is None:
        return template, False  # occluded: recover the most recent template
    live = keep[:int(good.sum())]
    updated = _Template(gray, xy[:len(live)][live], model[:len(live)][live])
    if len(updated.xy) < REFILL_POINTS:
        fresh = tracker.sample(gray, tracker.box(), updated.xy)
        if fresh is not None:
            updated = _Template(gray, np.concatenate([updated.xy, fresh.xy]),
                                np.concatenate([updated.model, fresh.model]))
    return updated, True
