"""Head pose from video: the face mesh's pose against the seed 003 cylinder tracker
(cartoonface/video/headpose.py; docs/video.md "Head pose", docs/BENCHMARKS.md).

Data: the GRID clips beside the repository (../shared/bench/av/grid/*.mpg: 360 x 288,
25 fps, MPEG-1, speaker s1, CC BY 4.0), decoded with the bundled ffmpeg to raw RGB
frames through a pipe. The mesh is MediaPipe's face mesh in video mode on whole frames
(as the driving code runs it), its pose by mesh_pose; the cylinder tracker starts from
the first frame's mesh (mesh_start) and re-initialises from the mesh when lost.

Figures, per clip and over the clips:
- agreement: median and 90th percentile of |cylinder - mesh| per axis, degrees;
- jitter: the median frame-to-frame change per axis (a) over each whole GRID clip (the
  speaker sits still and talks) and (b) on a still clip: the first frame held for
  STILL_FRAMES frames with sensor noise (NOISE gray levels) added to each;
- known motion: each GRID clip warped by a synthetic head motion of AMPLITUDE degrees
  (a sine over PERIOD frames): a roll (an in-plane rotation about the face centre: exact
  up to perspective) and a turn and a tilt (each frame's face mesh rotated in 3D about
  the head's centre and the picture warped triangle by triangle: approximate, see
  `turned`). Error per frame: estimate on the warped clip minus the
  same estimator on the unwarped clip minus the synthetic angle (the speaker's own
  motion cancels), on the moved axis and on the other two (cross-talk);
- speed: frames per second of CPU time (time.process_time) for the mesh (network and
  mesh_pose) and for the cylinder tracker alone (it runs on top of the mesh in the
  driving code), at 360 x 288 and scaled to 900 x 720.

The known-motion figures were tuned on s1_bbaf2n (the tuning half) and are reported
on the other two clips (held out); agreement and jitter on all three.
"""

from __future__ import annotations

import functools
import math
import re
import subprocess
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from cartoonface.photo.landmarks import _quiet
from cartoonface.speech.audio import ffmpeg_exe
from cartoonface.video.headpose import FACE_POINTS, Start, mesh_pose, mesh_start, track_cylinder

# The benchmark data lives beside the repository, not in it (docs/BENCHMARKS.md).
GRID = Path(__file__).resolve().parent.parent.parent / "shared" / "bench" / "av" / "grid"
TUNING = ("s1_bbaf2n",)
AXES = ("tilt", "turn", "roll")
STILL_FRAMES = 50
NOISE = 2.0
AMPLITUDE = 15.0
PERIOD = 50
LARGE = (900, 720)
# The face oval's points at the ears (image left, image right): the head turns about
# their depth.
EARS = (234, 454)


def decode(path: Path, size: tuple[int, int] | None = None) -> np.ndarray:
    """(n, H, W, 3) uint8 RGB frames of the video at `path` (scaled to `size` (W, H))."""
    probe = subprocess.run([ffmpeg_exe(), "-hide_banner", "-i", str(path)], capture_output=True, text=True)
    found = re.search(r"Video:.*?, (\d{2,5})x(\d{2,5})", probe.stderr)
    if found is None:
        raise SystemExit(f"{path}: no video stream")
    width, height = (int(found.group(1)), int(found.group(2))) if size is None else size
    scale = [] if size is None else ["-vf", f"scale={width}:{height}"]
    raw = subprocess.run([ffmpeg_exe(), "-v", "error", "-i", str(path), *scale, "-f", "rawvideo",
                          "-pix_fmt", "rgb24", "-"], capture_output=True, check=True).stdout
    return np.frombuffer(raw, np.uint8).reshape(-1, height, width, 3)


class VideoMesh:
    """MediaPipe's face mesh in video mode (it follows the face between frames)."""

    def __init__(self) -> None:
        with _quiet():
            from mediapipe.python.solutions import face_mesh
            self._mesh = face_mesh.FaceMesh(static_image_mode=False, max_num_faces=1, refine_landmarks=True)

    def points(self, rgb: np.ndarray) -> np.ndarray | None:
        """(478, 3) mesh points in pixels (as photo/landmarks.py's) or None (no face)."""
        height, width = rgb.shape[:2]
        with _quiet():
            found = self._mesh.process(np.ascontiguousarray(rgb)).multi_face_landmarks
        if not found:
            return None
        return np.array([(p.x * width, p.y * height, p.z * width) for p in found[0].landmark])

    def close(self) -> None:
        self._mesh.close()


def mesh_run(frames: np.ndarray) -> tuple[np.ndarray, list[np.ndarray | None], float]:
    """Mesh pose per frame (n, 3) (a frame without a face holds the last), the meshes and
    the CPU seconds taken."""
    mesh = VideoMesh()
    started = time.process_time()
    meshes = [mesh.points(frame) for frame in frames]
    poses, last = [], (0.0, 0.0, 0.0)
    for points in meshes:
        last = last if points is None else mesh_pose(points)
        poses.append(last)
    seconds = time.process_time() - started
    mesh.close()
    return np.array(poses), meshes, seconds


def cylinder_run(frames: np.ndarray, meshes: list[np.ndarray | None]) -> tuple[np.ndarray, float]:
    """Cylinder pose per frame (n, 3) from the first frame's mesh (re-initialised from the
    frame's mesh when lost) and the CPU seconds the tracker took (the meshes are given)."""
    import cv2

    first = next(i for i, points in enumerate(meshes) if points is not None)
    grays = [cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY) for frame in frames[first:]]

    def relocate(index: int, gray: np.ndarray) -> Start | None:
        points = meshes[first + index]
        return None if points is None else mesh_start(points)

    started = time.process_time()
    start = mesh_start(meshes[first])  # type: ignore[arg-type]
    poses = track_cylinder(grays, start, relocate)
    seconds = time.process_time() - started
    return np.concatenate([np.repeat(poses[:1], first, axis=0), poses]), seconds


def synthetic_angles(count: int) -> np.ndarray:
    """(count,) degrees: a sine of AMPLITUDE over PERIOD frames."""
    return AMPLITUDE * np.sin(2 * math.pi * np.arange(count) / PERIOD)


def rolled(frame: np.ndarray, centre: tuple[float, float], angle: float) -> np.ndarray:
    """`frame` turned `angle` degrees about `centre` (x, y): Pose's roll + moves the top of
    the head to the image left, counter-clockwise on screen as getRotationMatrix2D's
    positive angle (y down)."""
    import cv2

    affine = cv2.getRotationMatrix2D(centre, angle, 1.0)
    return cv2.warpAffine(frame, affine, (frame.shape[1], frame.shape[0]), borderMode=cv2.BORDER_REPLICATE)


@functools.lru_cache(maxsize=1)
def _triangles() -> np.ndarray:
    """(T, 3) triangles over the FACE_POINTS of a frontal face mesh: the Delaunay
    triangulation of the mesh of the first GRID clip's first frame."""
    from scipy.spatial import Delaunay

    points = VideoMesh().points(decode(sorted(GRID.glob("*.mpg"))[0])[0])
    if points is None:
        raise SystemExit("no face in the first GRID frame")
    return np.asarray(Delaunay(points[:FACE_POINTS, :2]).simplices)


def turned(frame: np.ndarray, points: np.ndarray, axis: int, angle: float) -> np.ndarray:
    """`frame` with its face (the mesh `points` (478, 3) px) turned `angle` degrees about
    `axis` (0 tilt, 1 turn; Pose's signs): the mesh's own 3D points rotated about the
    head's centre (the depth of the face oval at the ears, 234 and 454), projected
    orthographically, and the picture warped triangle by triangle (far ones drawn
    first); outside the face nothing moves. Approximate: the far side is squeezed, not
    hidden, and the hair and ears stay."""
    import cv2

    face = points[:FACE_POINTS].astype(float)
    pivot = np.array([*face[:, :2].mean(axis=0), face[list(EARS), 2].mean()])
    a = math.radians(angle)
    local = face - pivot  # x right, y down, z away from the camera
    moved = local.copy()
    if axis == 1:  # turn +: a point in front (z < 0) moves to the image right
        moved[:, 0] = local[:, 0] * math.cos(a) - local[:, 2] * math.sin(a)
        moved[:, 2] = local[:, 0] * math.sin(a) + local[:, 2] * math.cos(a)
    else:  # tilt +: the face looks down, a point in front moves down the image
        moved[:, 1] = local[:, 1] * math.cos(a) - local[:, 2] * math.sin(a)
        moved[:, 2] = local[:, 1] * math.sin(a) + local[:, 2] * math.cos(a)
    target = moved[:, :2] + pivot[:2]
    height, width = frame.shape[:2]
    owner = np.full((height, width), -1, dtype=np.int32)
    triangles = _triangles()
    for k in np.argsort(-moved[triangles, 2].mean(axis=1)):  # far first
        cv2.fillConvexPoly(owner, np.round(target[triangles[k]]).astype(np.int32), int(k))
    ys, xs = np.nonzero(owner >= 0)
    tri = triangles[owner[ys, xs]]
    # barycentric coordinates in the target triangle, applied to the source triangle
    t0, t1, t2 = target[tri[:, 0]], target[tri[:, 1]], target[tri[:, 2]]
    v0, v1 = t1 - t0, t2 - t0
    vp = np.column_stack([xs, ys]) - t0
    det = v0[:, 0] * v1[:, 1] - v0[:, 1] * v1[:, 0]
    det = np.where(np.abs(det) < 1e-9, 1e-9, det)
    u = (vp[:, 0] * v1[:, 1] - vp[:, 1] * v1[:, 0]) / det
    v = (v0[:, 0] * vp[:, 1] - v0[:, 1] * vp[:, 0]) / det
    source = face[:, :2]
    s0, s1, s2 = source[tri[:, 0]], source[tri[:, 1]], source[tri[:, 2]]
    where = s0 + u[:, None] * (s1 - s0) + v[:, None] * (s2 - s0)
    map_x = np.tile(np.arange(width, dtype=np.float32), (height, 1))
    map_y = np.tile(np.arange(height, dtype=np.float32)[:, None], (1, width))
    map_x[ys, xs], map_y[ys, xs] = where[:, 0], where[:, 1]
    return cv2.remap(frame, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


def synthetic(frames: np.ndarray, meshes: list[np.ndarray | None], axis: int) -> tuple[np.ndarray, np.ndarray]:
    """The frames with a synthetic head motion about `axis` (0 tilt, 1 turn, 2 roll) from
    each frame's mesh (a frame without one is left as it is). Returns (warped frames,
    (n,) the synthetic angles in degrees, Pose's signs)."""
    angles = synthetic_angles(len(frames))
    warped = frames.copy()
    for i, (frame, points, angle) in enumerate(zip(frames, meshes, angles)):
        if points is None:
            continue
        if axis == 2:
            x, y = points[:FACE_POINTS, :2].mean(axis=0)
            warped[i] = rolled(frame, (float(x), float(y)), float(angle))
        else:
            warped[i] = turned(frame, points, axis, float(angle))
    return warped, angles


def jitter(poses: np.ndarray) -> np.ndarray:
    """(3,) median |frame-to-frame change| per axis, degrees."""
    return np.median(np.abs(np.diff(poses, axis=0)), axis=0)


def spread(diff: np.ndarray) -> str:
    """'median / p90' of |diff| per axis."""
    a = np.abs(diff)
    return "  ".join(f"{name} {np.median(a[:, k]):.2f} / {np.percentile(a[:, k], 90):.2f}"
                     for k, name in enumerate(AXES))


def still_clip(frame: np.ndarray) -> np.ndarray:
    """STILL_FRAMES copies of `frame` with Gaussian sensor noise (seeded)."""
    rng = np.random.default_rng(0)
    noisy = frame[None].astype(float) + rng.normal(0.0, NOISE, (STILL_FRAMES, *frame.shape))
    return np.clip(noisy, 0, 255).astype(np.uint8)


def _both(frames: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, float]:
    mesh, meshes, mesh_seconds = mesh_run(frames)
    cylinder, cylinder_seconds = cylinder_run(frames, meshes)
    return mesh, cylinder, mesh_seconds, cylinder_seconds


def main(report: Callable[[str], None] = print) -> None:
    """Print the figures."""
    clips = sorted(GRID.glob("*.mpg"))
    if not clips:
        raise SystemExit(f"no GRID clips in {GRID}")
    agree, whole, still, rates = [], [], [], []
    known: dict[tuple[str, int], list[np.ndarray]] = {}
    for clip in clips:
        frames = decode(clip)
        mesh, cylinder, mesh_seconds, cylinder_seconds = _both(frames)
        agree.append(cylinder - mesh)
        whole.append((jitter(mesh), jitter(cylinder)))
        rates.append((len(frames) / mesh_seconds, len(frames) / cylinder_seconds))
        report(f"{clip.stem}: {len(frames)} frames; |cylinder - mesh| median / p90: {spread(cylinder - mesh)}")
        report(f"  jitter (median step) mesh {np.round(jitter(mesh), 2)}  cylinder {np.round(jitter(cylinder), 2)}")
        s_mesh, s_cylinder, _, _ = _both(still_clip(frames[0]))
        still.append((jitter(s_mesh), jitter(s_cylinder)))
        report(f"  still clip jitter mesh {np.round(jitter(s_mesh), 3)}  cylinder {np.round(jitter(s_cylinder), 3)}")
        _, meshes, _ = mesh_run(frames)
        half = "tuning" if clip.stem in TUNING else "held-out"
        for axis in (2, 1, 0):
            warped, truth = synthetic(frames, meshes, axis)
            w_mesh, w_cylinder, _, _ = _both(warped)
            for name, base, est in (("mesh", mesh, w_mesh), ("cylinder", cylinder, w_cylinder)):
                error = est - base
                error[:, axis] -= truth
                known.setdefault((name, axis), []).append(error) if half == "held-out" else None
                report(f"  {half} {AXES[axis]} +-{AMPLITUDE:g}: {name:8s} error median / p90: {spread(error)}")
        large = decode(clip, LARGE)
        _, _, l_mesh, l_cylinder = _both(large)
        report(f"  speed {LARGE[0]}x{LARGE[1]}: mesh {len(large) / l_mesh:.0f} fps, "
               f"cylinder {len(large) / l_cylinder:.0f} fps (CPU time)")
    report("== over the clips")
    report(f"agreement |cylinder - mesh| median / p90: {spread(np.concatenate(agree))}")
    report(f"jitter whole clips (median of clips): mesh {np.round(np.median([m for m, _ in whole], axis=0), 2)}"
           f"  cylinder {np.round(np.median([c for _, c in whole], axis=0), 2)}")
    report(f"jitter still clips (median of clips): mesh {np.round(np.median([m for m, _ in still], axis=0), 3)}"
           f"  cylinder {np.round(np.median([c for _, c in still], axis=0), 3)}")
    for (name, axis), errors in sorted(known.items()):
        report(f"held-out {AXES[axis]} +-{AMPLITUDE:g}: {name:8s} error median / p90: {spread(np.concatenate(errors))}")
    report(f"speed 360x288 (median of clips, CPU time): mesh {np.median([m for m, _ in rates]):.0f} fps, "
           f"cylinder {np.median([c for _, c in rates]):.0f} fps")


if __name__ == "__main__":
    main()
