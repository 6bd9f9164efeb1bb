"""Face landmarks and the person's outline from a photo: MediaPipe's face detector,
478-point face mesh and selfie segmentation.

The models ship inside the pinned `mediapipe` wheel (the optional `photo` extra,
docs/photo.md); nothing is downloaded. The full-range detector finds every face (the
short-range one is asked when it finds none);
the largest one is cropped, scaled to MESH_SIDE pixels and given to the face mesh
(with iris refinement), and its points are mapped back to the photo. The selfie
segmentation (the general 256 x 256 model) gives each pixel's confidence of being
part of a person (hair, face, body) rather than the background.
"""

from __future__ import annotations

import contextlib
import functools
import os
import threading
import warnings
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from cartoonface.errors import InputError

MESH_POINTS = 478
# The crop given to the face mesh: the detector's box widened this many times,
# scaled to this many pixels a side (the mesh model itself looks at 192 x 192).
CROP_MARGIN = 1.9
MESH_SIDE = 384

# iBUG 68-point order (as dlib's annotations) -> face mesh index: ours, chosen on
# the mesh's topology (face oval, eyelids, brows, lips); docs/photo.md.
IBUG68 = (
    # jaw 0-16, image left to image right
    127, 234, 93, 132, 58, 172, 136, 149, 152, 378, 365, 397, 288, 361, 323, 454, 356,
    # brows 17-21 (image left, outer to inner), 22-26 (image right, inner to outer)
    70, 63, 105, 66, 107, 336, 296, 334, 293, 300,
    # nose bridge 27-30, lower nose 31-35
    168, 197, 5, 4, 98, 97, 2, 326, 327,
    # eyes 36-41 (image left), 42-47 (image right), from the outer / inner corner
    33, 160, 158, 133, 153, 144, 362, 385, 387, 263, 373, 380,
    # outer lips 48-59, inner lips 60-67
    61, 39, 37, 0, 267, 269, 291, 405, 314, 17, 84, 181,
    78, 82, 13, 312, 308, 317, 14, 87,
)


@dataclass(frozen=True)
class Landmarks:
    """The face mesh of the largest face in a photo.

    points: (478, 3) float, x, y in photo pixels (y down) and z depth in the same
        pixel scale (smaller is nearer the camera); rows 468-477 are the irises
        (468 centre of the image-left iris, 469-472 its rim; 473, 474-477 the other).
    box: (x0, y0, x1, y1) the detector's face box in photo pixels.
    faces: how many faces the detector found.
    """

    points: np.ndarray
    box: tuple[float, float, float, float]
    faces: int


class PhotoExtraMissing(InputError):
    """The `photo` extra (mediapipe, OpenCV) is not installed."""


@contextlib.contextmanager
def quiet() -> Iterator[None]:
    """Silence MediaPipe's C++ log lines on stderr and protobuf's deprecation warning
    (third-party noise a user cannot act on) for the duration of the block."""
    saved = os.dup(2)
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 2)
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message=r".*GetPrototype\(\) is deprecated", category=UserWarning)
            yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


class Landmarker:
    """The loaded detector and face mesh (use `landmarker()`, which caches one).

    Not thread-safe by itself: `find` holds a lock, as MediaPipe graphs are stateful.
    """

    def __init__(self) -> None:
        os.environ.setdefault("GLOG_minloglevel", "2")
        try:
            with quiet():
                import cv2  # noqa: F401  (the crops and masks need it too)
                from mediapipe.python.solutions import face_detection, face_mesh, selfie_segmentation
        except ImportError as exc:
            raise PhotoExtraMissing(
                f"reading a photo needs the photo extra ({exc.name or exc}): "
                "pip install 'cartoonface[photo]' and see scripts/setup.sh") from None
        with quiet():
            # full range first (small faces in a wide photo), then short range (close-ups
            # it misses): both models ship in the wheel
            self._detectors = (face_detection.FaceDetection(model_selection=1, min_detection_confidence=0.5),
                               face_detection.FaceDetection(model_selection=0, min_detection_confidence=0.5))
            self._mesh = face_mesh.FaceMesh(static_image_mode=True, max_num_faces=1, refine_landmarks=True,
                                            min_detection_confidence=0.3)
            # the general model (0); the landscape one (1) is for wide video frames
            self._selfie = selfie_segmentation.SelfieSegmentation(model_selection=0)
        self._lock = threading.Lock()

    def boxes(self, rgb: np.ndarray) -> list[tuple[float, float, float, float]]:
        """Every face box (x0, y0, x1, y1) in `rgb` ((H, W, 3) uint8) photo pixels: the
        full-range detector's, or the short-range detector's when the first finds none."""
        height, width = rgb.shape[:2]
        with self._lock, quiet():
            for detector in self._detectors:
                found = detector.process(np.ascontiguousarray(rgb)).detections or []
                if found:
                    break
        boxes = []
        for detection in found:
            rel = detection.location_data.relative_bounding_box
            boxes.append((rel.xmin * width, rel.ymin * height,
                          (rel.xmin + rel.width) * width, (rel.ymin + rel.height) * height))
        return boxes

    def person(self, rgb: np.ndarray) -> np.ndarray:
        """(H, W) float confidence, 0..1, that each pixel of `rgb` ((H, W, 3) uint8) shows a
        person rather than the background (MediaPipe selfie segmentation)."""
        with self._lock, quiet():
            mask = self._selfie.process(np.ascontiguousarray(rgb)).segmentation_mask
        return np.clip(np.asarray(mask, dtype=float), 0.0, 1.0)

    def find(self, rgb: np.ndarray) -> Landmarks | None:
        """Landmarks of the largest face in `rgb` ((H, W, 3) uint8), or None when there is none."""
        boxes = self.boxes(rgb)
        if not boxes:
            return None
        box = max(boxes, key=lambda b: (b[2] - b[0]) * (b[3] - b[1]))
        crop, origin, scale = _crop(rgb, box)
        with self._lock, quiet():
            result = self._mesh.process(crop).multi_face_landmarks
        if not result:
            return None
        side = crop.shape[0]
        mesh = np.array([(p.x * side, p.y * side, p.z * side) for p in result[0].landmark], dtype=float)
        points = np.column_stack([mesh[:, :2] / scale + origin, mesh[:, 2] / scale])
        x0, y0, x1, y1 = box
        return Landmarks(points=points, box=(float(x0), float(y0), float(x1), float(y1)), faces=len(boxes))


def _crop(rgb: np.ndarray, box: tuple[float, float, float, float]) -> tuple[np.ndarray, np.ndarray, float]:
    """A square crop CROP_MARGIN times the box around its centre, padded with edge pixels
    where it leaves the photo, resized to MESH_SIDE. Returns (crop (S, S, 3) uint8,
    origin (2,) photo pixel of the crop's corner, scale crop pixels per photo pixel)."""
    import cv2

    x0, y0, x1, y1 = box
    side = max(x1 - x0, y1 - y0) * CROP_MARGIN
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    left, top = int(round(cx - side / 2)), int(round(cy - side / 2))
    n = int(round(side))
    height, width = rgb.shape[:2]
    pad = ((max(0, -top), max(0, top + n - height)), (max(0, -left), max(0, left + n - width)), (0, 0))
    window = rgb[max(0, top):top + n, max(0, left):left + n]
    window = np.pad(window, pad, mode="edge")
    scale = MESH_SIDE / n
    crop = cv2.resize(window, (MESH_SIDE, MESH_SIDE),
                      interpolation=cv2.INTER_AREA if scale < 1 else cv2.INTER_CUBIC)
    return np.ascontiguousarray(crop), np.array([left, top], dtype=float), scale


@functools.lru_cache(maxsize=1)
def landmarker() -> Landmarker:
    """The process-wide Landmarker, loaded on first use (PhotoExtraMissing without the extra)."""
    return Landmarker()
