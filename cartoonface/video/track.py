"""The face in every frame of a clip: MediaPipe's face mesh in video mode, and what it shows.

`track(clip)` runs the 478-point face mesh (the model photo/landmarks.py uses, shipped in the
mediapipe wheel) on each decoded frame in video mode (the mesh follows the face from frame to
frame and looks for it again only when it is lost), and measures per frame:

- the head pose (video/headpose.py's mesh_pose: tilt, turn, roll degrees, unclamped);
- each eye's opening: the lids' distance over the eye's width (an eye aspect ratio);
- each brow's height: brow to eye over the eye distance;
- the mouth: the inner lips' opening and the corners' distance over the eye distance, and the
  nose-to-upper-lip distance (the person's own MNS0, the unit drive.py gives the opening in).

Distances are taken in 3D (the mesh's x, y, z in pixels), so a turned head does not shrink them.
Frames without a face hold the last measures for HOLD seconds, then ease to the clip's median
over EASE seconds (`fill_lost`); frames before the first face show the median.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from cartoonface.photo.landmarks import MESH_POINTS, PhotoExtraMissing, quiet
from cartoonface.video.clip import Clip, VideoError, frames
from cartoonface.video.headpose import mesh_pose

# Columns of Tracking.measures, in this order.
MEASURES = ("eye_left", "eye_right", "brow_left", "brow_right", "mouth_open", "mouth_width", "nose_mouth")
# Face mesh indices (MediaPipe's canonical face; "left" is the image left, the person's right).
EYE_CORNERS = ((33, 133), (362, 263))  # (outer, inner) image-left eye, (inner, outer) image-right eye
EYE_LIDS = (((160, 144), (159, 145), (158, 153)), ((385, 380), (386, 374), (387, 373)))  # (upper, lower) pairs
BROWS = ((105, 66, 107), (334, 296, 336))  # the middle and inner part of each brow
INNER_LIPS = (13, 14)  # upper and lower inner lip on the midline
MOUTH_CORNERS = (61, 291)
NOSE_BOTTOM = 2  # below the nose tip, on the midline
# A lost face: its last measures are held this long, then eased to the median over EASE (s).
HOLD = 0.3
EASE = 0.5
# Share of the frames that must show a face (below it the clip is refused: a video of something else).
MIN_FOUND = 0.2
# The mesh's video mode: the face is searched for (detector) and followed (tracker) at these confidences.
DETECTION_CONFIDENCE = 0.5
TRACKING_CONFIDENCE = 0.5


@dataclass(frozen=True, eq=False)
class Tracking:
    """What the face did in a clip, one row per decoded frame (frame i at i / fps s).

    pose: (n, 3) tilt, turn, roll degrees (mesh_pose, unclamped); measures: (n, len(MEASURES))
    as MEASURES; found: (n,) bool, the mesh found the face (other rows filled by fill_lost).
    """

    fps: float
    pose: np.ndarray
    measures: np.ndarray
    found: np.ndarray

    def measure(self, name: str) -> np.ndarray:
        """(n,) the column of MEASURES called `name`."""
        return self.measures[:, MEASURES.index(name)]


def measure(points: np.ndarray) -> np.ndarray:
    """(len(MEASURES),) of one face mesh `points` ((478, 3) pixels): eye openings (lid distance
    over eye width), brow heights, mouth opening and width and nose-to-lip distance (over the eye
    distance), as MEASURES."""
    eyes = [points[list(corners)].mean(axis=0) for corners in EYE_CORNERS]
    span = float(np.linalg.norm(eyes[1] - eyes[0]))

    def dist(a: np.ndarray, b: np.ndarray) -> float:
        return float(np.linalg.norm(a - b))

    openings = [np.mean([dist(points[up], points[down]) for up, down in lids]) / dist(*points[list(corners)])
                for lids, corners in zip(EYE_LIDS, EYE_CORNERS)]
    brows = [dist(points[list(brow)].mean(axis=0), eye) / span for brow, eye in zip(BROWS, eyes)]
    upper, lower = points[INNER_LIPS[0]], points[INNER_LIPS[1]]
    mouth = [dist(upper, lower) / span, dist(*points[list(MOUTH_CORNERS)]) / span,
             dist(points[NOSE_BOTTOM], upper) / span]
    return np.array(openings + brows + mouth)


def fill_lost(values: np.ndarray, found: np.ndarray, fps: float) -> np.ndarray:
    """(n, k) `values` per frame at `fps`, valid where (n,) `found`: a copy with every lost frame
    filled: the last found row held HOLD s, then eased (cosine) to the found rows' median over
    EASE s; lost frames before the first found one take the median. At least one row found."""
    out = np.array(values, dtype=float)
    median = np.median(out[found], axis=0)
    last, since = median, None
    for i in range(len(out)):
        if found[i]:
            last, since = out[i], None
            continue
        since = 0 if since is None else since + 1
        if i < int(np.argmax(found)):
            out[i] = median
            continue
        share = np.clip((since / fps - HOLD) / EASE, 0.0, 1.0)
        ease = (1 - np.cos(np.pi * share)) / 2
        out[i] = last + (median - last) * ease
    return out


def video_mesh() -> object:
    """A MediaPipe face mesh in video mode (one face, the iris points refined); `close()` it after use."""
    os.environ.setdefault("GLOG_minloglevel", "2")
    try:
        with quiet():
            from mediapipe.python.solutions import face_mesh
    except ImportError as exc:
        raise PhotoExtraMissing(f"a video needs the photo extra ({exc.name or exc}): "
                                "pip install 'cartoonface[photo]' and see scripts/setup.sh") from None
    with quiet():
        return face_mesh.FaceMesh(static_image_mode=False, max_num_faces=1, refine_landmarks=True,
                                  min_detection_confidence=DETECTION_CONFIDENCE,
                                  min_tracking_confidence=TRACKING_CONFIDENCE)


def mesh_points(mesh: object, rgb: np.ndarray) -> np.ndarray | None:
    """(MESH_POINTS, 3) face mesh points in pixels (x, y, and z on x's scale) of the frame `rgb`
    (H, W, 3) uint8 read by `mesh` (video_mesh()), or None when no face is found."""
    height, width = rgb.shape[:2]
    with quiet():
        result = mesh.process(np.ascontiguousarray(rgb)).multi_face_landmarks  # type: ignore[attr-defined]
    if not result:
        return None
    scale = np.array([width, height, width], dtype=float)
    return np.array([(p.x, p.y, p.z) for p in result[0].landmark], dtype=float)[:MESH_POINTS] * scale


def track(clip: Clip, progress: Callable[[float], None] | None = None) -> Tracking:
    """Follow the face through every frame of `clip`; `progress(fraction)` told every second of video.

    Raises VideoError naming the clip when the face is found in fewer than MIN_FOUND of the frames."""
    mesh = video_mesh()
    poses, rows, found = [], [], []
    step = max(1, round(clip.fps))
    for i, rgb in enumerate(frames(clip)):
        points = mesh_points(mesh, rgb)
        if points is not None:
            poses.append(mesh_pose(points))
            rows.append(measure(points))
        else:
            poses.append((np.nan,) * 3)
            rows.append(np.full(len(MEASURES), np.nan))
        found.append(points is not None)
        if progress is not None and i % step == 0:
            progress(min(1.0, i / clip.frame_count))
    with quiet():
        mesh.close()  # type: ignore[attr-defined]
    seen = np.array(found, dtype=bool)
    if seen.mean() < MIN_FOUND:
        raise VideoError(f"{clip.path}: a face was found in {int(seen.sum())} of {len(seen)} frames; "
                         f"expected a video of a person facing the camera (a face in at least "
                         f"{MIN_FOUND:.0%} of the frames)")
    return Tracking(fps=clip.fps, pose=fill_lost(np.array(poses), seen, clip.fps),
                    measures=fill_lost(np.array(rows), seen, clip.fps), found=seen)
