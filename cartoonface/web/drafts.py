"""Photo drafts: a face model made from an uploaded photo, with its points checked and
corrected by the user before a job uses it (docs/web.md, "Face from a photo").

A draft is a folder `<instance>/photos/<id>/` (ids as for jobs, store.py) written
atomically when the photo is read: `photo.jpg` (the head's part of the upright photo,
at most DISPLAY_SIDE pixels a side: the picture the points are drawn on), `draft.json` (the user's file name,
the warnings, the detected points and hair in photo.jpg pixels, the detected model and
the linear map from photo to model pixels) and `edit.json` (the points as the user left
them and the model they give, rewritten atomically on every change).

Moving a point by (dx, dy) photo pixels moves the model point by MAP @ (dx, dy), where MAP
is the linear part of the least-squares affine map from the detected photo points to the
detected model points: the normalisation face/photo.py applies (levelling, turning to
the camera, closing the mouth) stays, and the user's correction is added to it.
"""

from __future__ import annotations

import io
import json
import math
import re
import shutil
import tempfile
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image

from cartoonface.errors import FaceModelError, InputError
from cartoonface.face.model import POINT_INDEX, POINT_NAMES, FaceModel, face_from_dict, face_to_dict
from cartoonface.face.photo import PhotoFace, face_from_photo, load_photo
from cartoonface.face.state import FaceState
from cartoonface.files import atomic_directory, write_text_atomic
from cartoonface.render.elements import svg_bytes
from cartoonface.render.svg import face_svg
from cartoonface.web.store import delete_job, valid_id

# The picture the points are shown and edited on: long side in pixels, JPEG quality.
DISPLAY_SIDE = 1024
JPEG_QUALITY = 88
# The editor shows the box of the points and hair widened by this share of its size each way.
HEAD_MARGIN = 0.3
# A dragged point may leave the photo by this share of its size (a chin at the edge).
EDGE_MARGIN = 0.25
# The edited points arrive as JSON text of at most this many characters
# (49 names and pairs of numbers take about 2 kB).
MAX_POINTS_CHARS = 16384
# Drafts not used for this long are deleted, and the oldest beyond this count.
DRAFT_SECONDS = 24 * 3600.0
MAX_DRAFTS = 200

PHOTO_FILE = "photo.jpg"
DRAFT_FILE = "draft.json"
EDIT_FILE = "edit.json"

# What each point is, shown when it is hovered or selected (docs/face-model.md, section 2;
# "right" and "left" are the person's own, so their right is on the image left).
_PAIRS = {
    ("2.13", "2.14"): "jaw corner",
    ("3.1", "3.2"): "upper eyelid, middle",
    ("3.3", "3.4"): "lower eyelid, middle",
    ("3.5", "3.6"): "iris centre",
    ("3.7", "3.12"): "outer eye corner",
    ("3.11", "3.8"): "inner eye corner",
    ("4.1", "4.2"): "eyebrow, inner end",
    ("4.3", "4.4"): "eyebrow, top of the arch",
    ("4.3a", "4.4a"): "eyebrow, between arch and outer end",
    ("4.5", "4.6"): "eyebrow, outer end",
    ("8.3", "8.4"): "mouth corner",
    ("8.10", "8.9"): "upper lip peak",
    ("9.1", "9.2"): "outer edge of the nostril wing",
    ("9.5", "9.4"): "bottom of the nose beside the tip",
    ("9.7", "9.6"): "top of the nose bridge",
    ("9.13", "9.14"): "top of the nostril wing",
    ("10.1", "10.2"): "top of the ear",
    ("10.7", "10.8"): "ear lobe",
    ("10.9", "10.10"): "cheek on the face contour",
    ("11.3a", "11.2a"): "hairline between middle and temple",
    ("11.3", "11.2"): "temple",
}
POINT_LABELS: dict[str, str] = {
    "2.1": "chin", "2.2": "inner upper lip, middle", "2.3": "inner lower lip, middle",
    "8.1": "outer upper lip, middle", "8.2": "outer lower lip, middle", "9.15": "nose tip",
    "11.1": "hairline, middle",
    **{right: f"{what} (their right)" for (right, _left), what in _PAIRS.items()},
    **{left: f"{what} (their left)" for (_right, left), what in _PAIRS.items()},
}


@dataclass(frozen=True)
class Draft:
    """A stored photo draft.

    id, folder: where it is. label: the user's file name (for display only).
    warnings: what the photo step said about the photo. size: (width, height) of photo.jpg.
    detected: (49, 2) the detected points in photo.jpg pixels (POINT_NAMES order).
    points: (49, 2) the points as last edited, same pixels. hair: (N, 2) hair polygon, same pixels.
    base: the detected face model (JSON object). face: the model of the edited points (JSON object).
    to_model: (2, 2) photo.jpg pixels -> model pixels (the linear part, see the module docstring).
    """

    id: str
    folder: Path
    label: str
    warnings: tuple[str, ...]
    size: tuple[int, int]
    detected: np.ndarray
    points: np.ndarray
    hair: np.ndarray
    base: Mapping[str, object]
    face: Mapping[str, object]
    to_model: np.ndarray


def drafts_root(instance: Path) -> Path:
    """The folder holding every draft folder."""
    return instance / "photos"


def linear_map(photo: np.ndarray, model: np.ndarray) -> np.ndarray:
    """The (2, 2) linear part of the least-squares affine map taking (N, 2) `photo`
    points to (N, 2) `model` points (model ~ photo @ A.T + b); returns A."""
    design = np.column_stack([photo, np.ones(len(photo))])
    solution, *_ = np.linalg.lstsq(design, model, rcond=None)
    return solution[:2].T


def head_box(found: PhotoFace, shape: tuple[int, ...]) -> tuple[int, int, int, int]:
    """The part of the photo shown in the editor, (x0, y0, x1, y1) pixels of an image of
    `shape` (H, W, ...): the box of the points and the hair, widened by HEAD_MARGIN of its
    size each way and cut to the photo, so the face fills the editor."""
    both = np.vstack([found.points, found.hair])
    low, high = both.min(axis=0), both.max(axis=0)
    pad = HEAD_MARGIN * (high - low)
    height, width = shape[:2]
    x0, y0 = np.floor(np.maximum(low - pad, 0)).astype(int)
    x1, y1 = np.ceil(np.minimum(high + pad, [width, height])).astype(int)
    return int(x0), int(y0), max(int(x1), int(x0) + 1), max(int(y1), int(y0) + 1)


def display_jpeg(rgb: np.ndarray) -> tuple[bytes, tuple[int, int], float]:
    """The (H, W, 3) uint8 picture as JPEG bytes at most DISPLAY_SIDE a side; returns
    (bytes, (width, height) of the JPEG, its pixels per pixel of `rgb`)."""
    image = Image.fromarray(rgb)
    k = min(1.0, DISPLAY_SIDE / max(image.size))
    if k < 1.0:
        image = image.resize((max(1, round(image.width * k)), max(1, round(image.height * k))),
                             Image.Resampling.LANCZOS)
    out = io.BytesIO()
    image.save(out, "JPEG", quality=JPEG_QUALITY)
    return out.getvalue(), image.size, k


def detect(data: bytes, ext: str, label: str) -> tuple[bytes, tuple[int, int], np.ndarray, float, PhotoFace]:
    """Read the photo bytes (format `ext`, decided by the caller from the content) and find
    the face. Returns (photo.jpg bytes: the head's part of the photo, its (width, height),
    the (2,) photo.rgb pixel of its corner, its pixels per photo.rgb pixel, the PhotoFace).
    InputError naming `label` (never a server path) when the photo cannot be read or holds
    no usable face."""
    with tempfile.TemporaryDirectory(prefix="cartoonface-photo-") as tmp:
        path = Path(tmp) / f"photo.{ext}"
        path.write_bytes(data)
        try:
            photo = load_photo(path)
            found = face_from_photo(photo, "photo")
        except InputError as exc:
            raise InputError(str(exc).replace(str(path), label)) from None
    x0, y0, x1, y1 = head_box(found, photo.rgb.shape)
    jpeg, size, k = display_jpeg(photo.rgb[y0:y1, x0:x1])
    return jpeg, size, np.array([x0, y0], dtype=float), k, found


def _pairs(array: np.ndarray) -> list[list[float]]:
    return [[round(float(x), 2), round(float(y), 2)] for x, y in array]


def _named(array: np.ndarray) -> dict[str, list[float]]:
    return dict(zip(POINT_NAMES, _pairs(array)))


def create_draft(instance: Path, data: bytes, ext: str, label: str, draft_id: str) -> Draft:
    """Detect the face in the photo bytes and store the draft `draft_id` (a new_id());
    return it. InputError as detect()."""
    jpeg, size, corner, k, found = detect(data, ext, label)
    detected = (found.points - corner) * k
    base = face_to_dict(found.face)
    model = np.array([base["points"][name] for name in POINT_NAMES], dtype=float)
    record = {
        "label": label,
        "warnings": list(found.warnings),
        "size": list(size),
        "detected": _named(detected),
        "hair": _pairs((found.hair - corner) * k),
        "base": base,
        "to_model": linear_map(detected, model).tolist(),
    }
    edit = {"points": record["detected"], "face": base}
    with atomic_directory(drafts_root(instance) / draft_id) as tmp:
        (tmp / PHOTO_FILE).write_bytes(jpeg)
        (tmp / DRAFT_FILE).write_text(json.dumps(record, ensure_ascii=False), encoding="utf-8")
        (tmp / EDIT_FILE).write_text(json.dumps(edit, ensure_ascii=False), encoding="utf-8")
    return load_draft(instance, draft_id)


def load_draft(instance: Path, draft_id: str) -> Draft | None:
    """The stored draft `draft_id`, or None when the id is malformed or no such draft is readable."""
    if not valid_id(draft_id):
        return None
    folder = drafts_root(instance) / draft_id
    try:
        record = json.loads((folder / DRAFT_FILE).read_text(encoding="utf-8"))
        edit = json.loads((folder / EDIT_FILE).read_text(encoding="utf-8"))
        return Draft(
            id=draft_id, folder=folder, label=str(record["label"]),
            warnings=tuple(str(w) for w in record["warnings"]),
            size=(int(record["size"][0]), int(record["size"][1])),
            detected=np.array([record["detected"][n] for n in POINT_NAMES], dtype=float),
            points=np.array([edit["points"][n] for n in POINT_NAMES], dtype=float),
            hair=np.array(record["hair"], dtype=float).reshape(-1, 2),
            base=record["base"], face=edit["face"],
            to_model=np.array(record["to_model"], dtype=float).reshape(2, 2),
        )
    except (OSError, ValueError, KeyError, TypeError, IndexError):  # gone, or not a draft this app wrote
        return None


def parse_points(text: str, size: tuple[int, int]) -> np.ndarray:
    """The edited points sent by the editor: JSON text of an object with every point name
    and no other, each [x, y] of finite numbers in photo.jpg pixels of `size` (width,
    height), at most EDGE_MARGIN of the photo outside it. Returns (49, 2) in POINT_NAMES
    order; InputError naming the point and what was expected."""
    if len(text) > MAX_POINTS_CHARS:
        raise InputError(f"points: {len(text)} characters; expected at most {MAX_POINTS_CHARS}")
    try:
        obj = json.loads(text)
    except (json.JSONDecodeError, RecursionError) as exc:
        raise InputError(f"points: not JSON ({exc}); expected an object of point name -> [x, y]") from None
    if not isinstance(obj, dict):
        raise InputError(f"points: a JSON {type(obj).__name__}; expected an object of point name -> [x, y]")
    unknown = [name for name in obj if name not in POINT_INDEX]
    if unknown:
        raise InputError(f"points: unknown point {unknown[0][:40]!r}; expected the face model's point names "
                         "(2.1 ... 11.3a)")
    missing = [name for name in POINT_NAMES if name not in obj]
    if missing:
        raise InputError(f"points: point {missing[0]!r} is missing; expected all {len(POINT_NAMES)} points")
    width, height = size
    low = (-EDGE_MARGIN * width, -EDGE_MARGIN * height)
    high = ((1 + EDGE_MARGIN) * width, (1 + EDGE_MARGIN) * height)
    out = np.zeros((len(POINT_NAMES), 2))
    for i, name in enumerate(POINT_NAMES):
        value = obj[name]
        if (not isinstance(value, list) or len(value) != 2
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)):
            raise InputError(f"points: point {name} is {str(value)[:40]}; expected [x, y] numbers")
        x, y = (float(v) for v in value)
        if not (math.isfinite(x) and math.isfinite(y)):
            raise InputError(f"points: point {name} is [{x}, {y}]; expected finite numbers")
        if not (low[0] <= x <= high[0] and low[1] <= y <= high[1]):
            raise InputError(f"points: point {name} = [{x:g}, {y:g}] is outside the photo "
                             f"({width} x {height} px); expected a point on it")
        out[i] = (x, y)
    return out


def edited_face(draft: Draft, points: np.ndarray) -> tuple[FaceModel, dict[str, object]]:
    """The face model of the draft with its photo points moved to `points` ((49, 2)
    photo.jpg pixels): (the FaceModel, its JSON object). InputError (from face_from_dict)
    naming the point when the result is not a valid face, e.g. a point dragged far away."""
    base = np.array([draft.base["points"][name] for name in POINT_NAMES], dtype=float)  # type: ignore[index]
    moved = base + (points - draft.detected) @ draft.to_model.T
    obj = {**draft.base, "points": _named(moved)}
    try:
        face = face_from_dict(obj, "the cartoon")
    except FaceModelError as exc:
        named = re.search(r"points\['([^']+)'\]", str(exc))
        where = f"point {named.group(1)} ({POINT_LABELS[named.group(1)]})" if named else "these points"
        raise InputError(f"points: {where} cannot make a cartoon face; move it back towards the face "
                         f"(the model says: {exc})") from None
    return face, face_to_dict(face)


def save_edit(draft: Draft, points: np.ndarray, face: Mapping[str, object]) -> None:
    """Store the edited points and their model (edit.json, atomically)."""
    write_text_atomic(draft.folder / EDIT_FILE,
                      json.dumps({"points": _named(points), "face": face}, ensure_ascii=False))


def preview_svg(face: FaceModel) -> bytes:
    """The cartoon face, neutral and still, as SVG bytes (render/svg.py face_svg)."""
    return svg_bytes(face_svg(face, FaceState()))


def draft_choice(instance: Path, draft_id: str) -> tuple[bytes, str, tuple[str, ...]] | None:
    """The draft's current model as a job's face: (face JSON bytes, label, the photo's
    warnings prefixed with the file name), or None when there is no such draft."""
    draft = load_draft(instance, draft_id)
    if draft is None:
        return None
    return (json.dumps(draft.face, ensure_ascii=False).encode("utf-8"), f"{draft.label} (points checked)",
            tuple(f"{draft.label}: {warning}" for warning in draft.warnings))


def sweep_drafts(instance: Path, now: float | None = None) -> list[str]:
    """Delete drafts last changed more than DRAFT_SECONDS ago, then the oldest while
    more than MAX_DRAFTS are left, and leftovers of unfinished writes. Returns the deleted ids."""
    root = drafts_root(instance)
    if not root.is_dir():
        return []
    now = time.time() if now is None else now
    aged = []
    for entry in root.iterdir():
        if not valid_id(entry.name):
            if entry.name.startswith(".deleted-") and entry.is_dir():
                shutil.rmtree(entry, ignore_errors=True)
            continue
        try:
            aged.append((max(p.stat().st_mtime for p in entry.iterdir()), entry))
        except (OSError, ValueError):  # removed meanwhile, or empty
            continue
    aged.sort()
    deleted = []
    for i, (changed, folder) in enumerate(aged):
        if now - changed > DRAFT_SECONDS or len(aged) - i > MAX_DRAFTS:
            delete_job(folder)
            deleted.append(folder.name)
    return deleted
