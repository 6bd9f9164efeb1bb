"""Face from a photo: detection rate, landmark error, speed (docs/BENCHMARKS.md, docs/photo.md).

Data: dlib's example photos (9 PASCAL VOC photos, 43 faces annotated with the 68 iBUG
points, themselves predicted by dlib's model), beside the repository as docs/BENCHMARKS.md
("Face from a photo") says. The faces are 37-109 px wide,
mostly under the 64 px the photo reader accepts, so each face is cut out with context
(a square CROP_CONTEXT times its box) and scaled up so its box is BOX_PX wide, as a user
would crop a group photo; the points are scaled back to the photo to be compared.

Figures: the share of faces found (the largest face in the crop lies on the annotated
box; and, for the detector alone, among all faces of the whole photos scaled up twice), the normalised mean error (NME: mean point distance / distance between the outer
eye corners 36 and 45) of (a) the named model points that have a 68-point counterpart
and (b) all 68 points read off the face mesh (landmarks.IBUG68), medians over faces;
the time per photo after the model is loaded; the model load time.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from lxml import etree
from PIL import Image

# The benchmark data lives beside the repository, not in it (docs/BENCHMARKS.md).
DATA = Path(__file__).resolve().parent.parent.parent / "shared" / "bench" / "faces" / "dlib_examples"
CROP_CONTEXT = 2.0
BOX_PX = 160
# Named model point -> iBUG 68 indices whose mean is its counterpart (jaw corners,
# cheeks, temples, ears and the nose side points have no counterpart of the same
# definition and are left out).
COUNTERPARTS = {
    "2.1": (8,), "2.2": (62,), "2.3": (66,),
    "3.12": (36,), "3.8": (39,), "3.11": (42,), "3.7": (45,),
    "3.2": (37, 38), "3.4": (40, 41), "3.1": (43, 44), "3.3": (46, 47),
    "4.6": (17,), "4.4": (19,), "4.2": (21,), "4.1": (22,), "4.3": (24,), "4.5": (26,),
    "8.4": (48,), "8.9": (50,), "8.1": (51,), "8.10": (52,), "8.3": (54,), "8.2": (57,),
    "9.15": (33,),
}
LOAD_RUNS = 3
# Whole photos are also given to the detector alone, scaled up this many times.
WHOLE_UPSCALE = 2


def annotated_faces() -> list[tuple[Path, np.ndarray, np.ndarray]]:
    """(photo, box (4,) x0 y0 x1 y1, points (68, 2)) for every annotated face."""
    faces = []
    for xml in ("training_with_face_landmarks.xml", "testing_with_face_landmarks.xml"):
        for image in etree.parse(str(DATA / xml)).getroot().iter("image"):
            for box in image.iter("box"):
                left, top = float(box.get("left")), float(box.get("top"))
                x0y0x1y1 = np.array([left, top, left + float(box.get("width")), top + float(box.get("height"))])
                parts = sorted(box.iter("part"), key=lambda p: int(p.get("name")))
                points = np.array([[float(p.get("x")), float(p.get("y"))] for p in parts])
                faces.append((DATA / image.get("file"), x0y0x1y1, points))
    return faces


def crop(photo: Image.Image, box: np.ndarray) -> tuple[Image.Image, np.ndarray, float]:
    """The face cut out with context and scaled so the box is BOX_PX wide:
    (image, origin (2,) in photo pixels, scale crop px per photo px)."""
    centre = (box[:2] + box[2:]) / 2
    side = CROP_CONTEXT * max(box[2] - box[0], box[3] - box[1])
    origin = centre - side / 2
    scale = BOX_PX / (box[2] - box[0])
    x0, y0 = origin
    area = (round(x0), round(y0), round(x0 + side), round(y0 + side))
    size = int(round(side * scale))
    return photo.crop(area).resize((size, size), Image.Resampling.BICUBIC), np.round(origin), scale


def load_seconds() -> list[float]:
    """Model load times (import + detector + face mesh) in fresh processes."""
    code = ("import time; t = time.perf_counter(); from cartoonface.photo.landmarks import landmarker; "
            "landmarker(); print(time.perf_counter() - t)")
    return [float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                 check=True).stdout.strip()) for _ in range(LOAD_RUNS)]


def main() -> None:
    """Print the figures."""
    from cartoonface.errors import InputError
    from cartoonface.face.model import POINT_INDEX
    from cartoonface.photo.landmarks import IBUG68, landmarker
    from cartoonface.photo.model_from_photo import face_from_photo, photo_from_image

    loads = load_seconds()
    print(f"model load (import + detector + mesh, fresh process): median {statistics.median(loads):.2f} s "
          f"over {LOAD_RUNS} runs")
    marker = landmarker()
    faces = annotated_faces()
    found, nme_named, nme_68, seconds, widths = 0, [], [], [], []
    for path, box, truth in faces:
        with Image.open(path) as image:
            photo = image.convert("RGB")
        widths.append(box[2] - box[0])
        picture, origin, scale = crop(photo, box)
        started = time.perf_counter()
        try:
            result = face_from_photo(photo_from_image(picture, path.name))
        except InputError:
            seconds.append(time.perf_counter() - started)
            continue
        seconds.append(time.perf_counter() - started)
        named = result.points / scale + origin
        centre = named[POINT_INDEX["9.15"]]
        if not (box[0] <= centre[0] <= box[2] and box[1] <= centre[1] <= box[3]):
            continue
        found += 1
        iod = float(np.hypot(*(truth[45] - truth[36])))
        errors = [np.hypot(*(named[POINT_INDEX[n]] - truth[list(idx)].mean(axis=0))) for n, idx in COUNTERPARTS.items()]
        nme_named.append(float(np.mean(errors)) / iod)
        mesh = marker.find(np.asarray(picture))
        if mesh is not None:
            ibug = mesh.points[list(IBUG68), :2] / scale + origin
            nme_68.append(float(np.mean(np.hypot(*(ibug - truth).T))) / iod)
    n = len(faces)
    whole_found, extra = 0, 0
    for path in sorted({f[0] for f in faces}):
        with Image.open(path) as image:
            big = image.convert("RGB").resize((image.width * WHOLE_UPSCALE, image.height * WHOLE_UPSCALE),
                                              Image.Resampling.BICUBIC)
        boxes = np.array(marker.boxes(np.asarray(big))).reshape(-1, 4) / WHOLE_UPSCALE
        centres = (boxes[:, :2] + boxes[:, 2:]) / 2
        matched = np.zeros(len(boxes), bool)
        for _, box, _ in (f for f in faces if f[0] == path):
            inside = np.all((centres >= box[:2]) & (centres <= box[2:]), axis=1)
            whole_found += bool(inside.any())
            matched |= inside
        extra += int((~matched).sum())
    print(f"faces: {n} in {len({f[0] for f in faces})} photos, box {min(widths):.0f}-{max(widths):.0f} px wide, "
          f"each cropped x{CROP_CONTEXT:g} and scaled to a {BOX_PX} px box")
    print(f"detection rate, one crop per face: {found}/{n} = {found / n:.1%}")
    print(f"detection rate, whole photos scaled x{WHOLE_UPSCALE}: {whole_found}/{n} = {whole_found / n:.1%} "
          f"(a detector box centred inside the annotated box), {extra} boxes on no annotated face")
    print(f"NME named points with a 68-point counterpart ({len(COUNTERPARTS)}): median {statistics.median(nme_named):.3f}, "
          f"mean {statistics.mean(nme_named):.3f}, worst {max(nme_named):.3f}")
    print(f"NME all 68 points from the mesh: median {statistics.median(nme_68):.3f}, "
          f"mean {statistics.mean(nme_68):.3f}, worst {max(nme_68):.3f}")
    print(f"time per photo after load (face_from_photo, {BOX_PX * CROP_CONTEXT:.0f} px crops): "
          f"median {statistics.median(seconds) * 1000:.0f} ms, max {max(seconds) * 1000:.0f} ms")
    from skimage import data

    portrait = photo_from_image(Image.fromarray(data.astronaut()), "astronaut")
    runs = []
    for _ in range(10):
        started = time.perf_counter()
        face_from_photo(portrait)
        runs.append(time.perf_counter() - started)
    print(f"time per photo after load (astronaut 512 x 512): median {statistics.median(runs) * 1000:.0f} ms")
