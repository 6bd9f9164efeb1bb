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
- speed: frames per second of CPU time (time.process_time, all threads) and of wall
  time for the mesh (network and mesh_pose) and for the cylinder tracker alone (it runs on top of the mesh in the
  driving code), at 360 x 288 and scaled to 900 x 720.

`python bench/video_pose.py OUT.png` draws docs/video.md's picture; `python
bench/video_pose.py --clip OUT.mp4` writes a clip with larger head movement (write_clip).

The known-motion figures were tuned on s1_bbaf2n (the tuning half) and are reported
on the other two clips (held out); agreement and jitter on all three.
"""

from __future__ import annotations

import functools
import math
import re
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from cartoonface.speech.audio import ffmpeg_exe
from cartoonface.video.track import mesh_points, video_mesh
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
# (CPU, wall) seconds.
Seconds = tuple[float, float]


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


def mesh_run(frames: np.ndarray) -> tuple[np.ndarray, list[np.ndarray | None], Seconds]:
    """Mesh pose per frame (n, 3) (a frame without a face holds the last), the meshes and
    the (CPU, wall) seconds taken."""
    mesh = video_mesh()
    started = time.process_time(), time.perf_counter()
    meshes = [mesh_points(mesh, frame) for frame in frames]
    poses, last = [], (0.0, 0.0, 0.0)
    for points in meshes:
        last = last if points is None else mesh_pose(points)
        poses.append(last)
    seconds = time.process_time() - started[0], time.perf_counter() - started[1]
    mesh.close()  # type: ignore[attr-defined]
    return np.array(poses), meshes, seconds


def cylinder_run(frames: np.ndarray, meshes: list[np.ndarray | None]) -> tuple[np.ndarray, Seconds]:
    """Cylinder pose per frame (n, 3) from the first frame's mesh (re-initialised from the
    frame's mesh when lost) and the (CPU, wall) seconds the tracker took (the meshes are
    given)."""
    import cv2

    first = next(i for i, points in enumerate(meshes) if points is not None)
    grays = [cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY) for frame in frames[first:]]

    def relocate(index: int, gray: np.ndarray) -> Start | None:
        points = meshes[first + index]
        return None if points is None else mesh_start(points)

    started = time.process_time(), time.perf_counter()
    start = mesh_start(meshes[first])  # type: ignore[arg-type]
    poses = track_cylinder(grays, start, relocate)
    seconds = time.process_time() - started[0], time.perf_counter() - started[1]
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

    points = mesh_points(video_mesh(), decode(sorted(GRID.glob("*.mpg"))[0])[0])
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


def rate(frames: int, seconds: Seconds) -> str:
    """'cpu / wall' frames per second."""
    return f"{frames / seconds[0]:.0f} / {frames / seconds[1]:.0f}"


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


def _both(frames: np.ndarray) -> tuple[np.ndarray, np.ndarray, Seconds, Seconds]:
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
        rates.append((len(frames) / np.array(mesh_seconds), len(frames) / np.array(cylinder_seconds)))
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
        report(f"  speed {LARGE[0]}x{LARGE[1]} fps (CPU, wall): mesh {rate(len(large), l_mesh)}, "
               f"cylinder {rate(len(large), l_cylinder)}")
    report("== over the clips")
    report(f"agreement |cylinder - mesh| median / p90: {spread(np.concatenate(agree))}")
    report(f"jitter whole clips (median of clips): mesh {np.round(np.median([m for m, _ in whole], axis=0), 2)}"
           f"  cylinder {np.round(np.median([c for _, c in whole], axis=0), 2)}")
    report(f"jitter still clips (median of clips): mesh {np.round(np.median([m for m, _ in still], axis=0), 3)}"
           f"  cylinder {np.round(np.median([c for _, c in still], axis=0), 3)}")
    for (name, axis), errors in sorted(known.items()):
        report(f"held-out {AXES[axis]} +-{AMPLITUDE:g}: {name:8s} error median / p90: {spread(np.concatenate(errors))}")
    report("speed 360x288 fps (CPU, wall; median of clips): "
           f"mesh {np.round(np.median([m for m, _ in rates], axis=0))}, "
           f"cylinder {np.round(np.median([c for _, c in rates], axis=0))}")


def figure(path: Path, clip: str = "s1_lbak3a") -> None:
    """Write docs/video.md's picture to `path` (PNG, 256 colours): a held-out GRID clip
    (CC BY 4.0) at the synthetic poses (top) and each estimator's response to the
    synthetic motions against the truth (bottom)."""
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from PIL import Image

    frames = decode(GRID / f"{clip}.mpg")
    mesh, meshes, _ = mesh_run(frames)
    cylinder, _ = cylinder_run(frames, meshes)
    fig = plt.figure(figsize=(12, 6.4))
    picks = ((1, -AMPLITUDE), (1, AMPLITUDE), (0, -AMPLITUDE), (0, AMPLITUDE), (2, -AMPLITUDE), (2, AMPLITUDE))
    points = meshes[0]
    assert points is not None
    x, y = points[:FACE_POINTS, :2].mean(axis=0)
    for k, (axis, angle) in enumerate(picks):
        shown = rolled(frames[0], (float(x), float(y)), angle) if axis == 2 else turned(frames[0], points, axis, angle)
        ax = fig.add_subplot(2, 6, k + 1)
        ax.imshow(shown[20:270, 40:320])
        ax.set_title(f"{AXES[axis]} {angle:+g}", fontsize=9)
        ax.axis("off")
    for k, axis in enumerate((1, 0, 2)):
        warped, truth = synthetic(frames, meshes, axis)
        w_mesh, w_cylinder, _, _ = _both(warped)
        ax = fig.add_subplot(2, 3, 4 + k)
        ax.plot(truth, "k--", label="synthetic")
        ax.plot(w_mesh[:, axis] - mesh[:, axis], label="mesh")
        ax.plot(w_cylinder[:, axis] - cylinder[:, axis], label="cylinder")
        ax.set_title(f"{AXES[axis]}: response to the synthetic motion", fontsize=9)
        ax.set_xlabel("frame (25 fps)", fontsize=8)
        ax.set_ylabel("degrees", fontsize=8)
        if k == 0:
            ax.legend(fontsize=8)
    fig.suptitle(f"GRID {clip} (CC BY 4.0), held out: synthetic poses and the estimators' response", fontsize=10)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=72)
    Image.open(buffer).convert("RGB").quantize(256).save(path, optimize=True)


def write_clip(path: Path) -> None:
    """Write a clip with larger head movement (CC BY 4.0, from GRID) to `path` (MP4,
    H.264 + AAC) and its known motion to `path` with suffix .csv: the three GRID clips
    joined, each warped by one synthetic sine of AMPLITUDE over its whole length (turn,
    tilt, roll in clip order), with their own sound. Columns: frame, then the synthetic
    tilt, turn, roll in degrees (Pose's signs), added to the speaker's own pose."""
    clips = sorted(GRID.glob("*.mpg"))
    parts, truth = [], []
    for clip, axis in zip(clips, (1, 0, 2)):
        frames = decode(clip)
        _, meshes, _ = mesh_run(frames)
        count = len(frames)
        angles = AMPLITUDE * np.sin(2 * math.pi * np.arange(count) / count)
        warped = frames.copy()
        for i, (points, angle) in enumerate(zip(meshes, angles)):
            if points is None:
                continue
            x, y = points[:FACE_POINTS, :2].mean(axis=0)
            warped[i] = (rolled(frames[i], (float(x), float(y)), float(angle)) if axis == 2
                         else turned(frames[i], points, axis, float(angle)))
        parts.append(warped)
        rows = np.zeros((count, 3))
        rows[:, axis] = angles
        truth.append(rows)
    video = np.concatenate(parts)
    height, width = video.shape[1:3]
    sounds = [str(clip.with_suffix(".wav")) for clip in clips]
    inputs = [arg for sound in sounds for arg in ("-i", sound)]
    joined = "".join(f"[{k + 1}:a]" for k in range(len(sounds))) + f"concat=n={len(sounds)}:v=0:a=1[a]"
    subprocess.run([ffmpeg_exe(), "-v", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24",
                    "-s", f"{width}x{height}", "-r", "25", "-i", "-", *inputs, "-filter_complex", joined,
                    "-map", "0:v", "-map", "[a]", "-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "20",
                    "-c:a", "aac", "-shortest", str(path)], input=video.tobytes(), check=True)
    table = np.column_stack([np.arange(len(video)), np.concatenate(truth)])
    np.savetxt(path.with_suffix(".csv"), table, fmt=["%d", "%.3f", "%.3f", "%.3f"], delimiter=",",
               header="frame,tilt,turn,roll", comments="")


if __name__ == "__main__":
    if len(sys.argv) > 2 and sys.argv[1] == "--clip":
        write_clip(Path(sys.argv[2]))
    elif len(sys.argv) > 1:
        figure(Path(sys.argv[1]))
    else:
        main()
