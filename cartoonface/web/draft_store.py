"""Photo drafts on disk: a face model made from an uploaded photo, kept while the user
checks and corrects its points (point_editor.py) before a job uses it (docs/web.md,
"Face from a photo").

A draft is a folder `<instance>/photos/<id>/` (ids as for jobs, store.py) written
atomically when the photo is read: `photo.jpg` (the head's part of the upright photo,
at most DISPLAY_SIDE pixels a side: the picture the points are drawn on), `draft.json`
(the user's file name, the warnings, the detected points and hair in photo.jpg pixels, the detected model and
the linear map from photo to model pixels) and `edit.json` (the points as the user left
them and the model they give, rewritten atomically on every change).
"""

from __future__ import annotations

import json
import shutil
import tempfile
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import cast

import numpy as np

from cartoonface.errors import InputError
from cartoonface.face.model import POINT_NAMES, face_to_dict
from cartoonface.files import TRASH_PREFIX, atomic_directory, remove_folder, write_text_atomic
from cartoonface.photo.model_from_photo import PhotoFace, face_from_photo, load_photo
from cartoonface.photo.pictures import display_jpeg
from cartoonface.web.store import valid_id

# The picture the points are shown and edited on: long side in pixels.
DISPLAY_SIDE = 1024
# The editor shows the box of the points and hair widened by this share of its size each way.
HEAD_MARGIN = 0.3
# Drafts not used for this long are deleted, and the oldest beyond this count.
DRAFT_SECONDS = 24 * 3600.0
MAX_DRAFTS = 200

PHOTO_FILE = "photo.jpg"
DRAFT_FILE = "draft.json"
EDIT_FILE = "edit.json"
# A draft folder being deleted is first renamed to this prefix + its id.


@dataclass(frozen=True)
class Draft:
    """A stored photo draft.

    id, folder: where it is. label: the user's file name (for display only).
    warnings: what the photo step said about the photo. size: (width, height) of photo.jpg.
    detected: (49, 2) the detected points in photo.jpg pixels (POINT_NAMES order).
    points: (49, 2) the points as last edited, same pixels. hair: (N, 2) hair polygon, same pixels.
    base: the detected face model (JSON object). face: the model of the edited points (JSON object).
    to_model: (2, 2) photo.jpg pixels -> model pixels (linear_map; how the editor uses it: point_editor.py).
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
    jpeg, size, k = display_jpeg(photo.rgb[y0:y1, x0:x1], DISPLAY_SIDE)
    return jpeg, size, np.array([x0, y0], dtype=float), k, found


def _pairs(array: np.ndarray) -> list[list[float]]:
    return [[round(float(x), 2), round(float(y), 2)] for x, y in array]


def model_points(face: Mapping[str, object]) -> np.ndarray:
    """(49, 2) the points of a face model's JSON object (face_to_dict) in POINT_NAMES order."""
    points = cast(Mapping[str, Sequence[float]], face["points"])
    return np.array([points[name] for name in POINT_NAMES], dtype=float)


def named_points(array: np.ndarray) -> dict[str, list[float]]:
    """(49, 2) points in POINT_NAMES order as JSON: point name -> [x, y] rounded to 0.01."""
    return dict(zip(POINT_NAMES, _pairs(array)))


def create_draft(instance: Path, data: bytes, ext: str, label: str, draft_id: str) -> Draft:
    """Detect the face in the photo bytes and store the draft `draft_id` (a new_id());
    return it. InputError as detect(), or when the draft is gone before it is read back."""
    jpeg, size, corner, k, found = detect(data, ext, label)
    detected = (found.points - corner) * k
    base = face_to_dict(found.face)
    model = model_points(base)
    record = {
        "label": label,
        "warnings": list(found.warnings),
        "size": list(size),
        "detected": named_points(detected),
        "hair": _pairs((found.hair - corner) * k),
        "base": base,
        "to_model": linear_map(detected, model).tolist(),
    }
    edit = {"points": record["detected"], "face": base}
    with atomic_directory(drafts_root(instance) / draft_id) as tmp:
        (tmp / PHOTO_FILE).write_bytes(jpeg)
        (tmp / DRAFT_FILE).write_text(json.dumps(record, ensure_ascii=False), encoding="utf-8")
        (tmp / EDIT_FILE).write_text(json.dumps(edit, ensure_ascii=False), encoding="utf-8")
    draft = load_draft(instance, draft_id)
    if draft is None:  # swept away by another request between the write and this read
        raise InputError(f"{label}: the photo was removed before it could be shown; please upload it again")
    return draft


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


def save_edit(draft: Draft, points: np.ndarray, face: Mapping[str, object]) -> None:
    """Store the edited points and their model (edit.json, atomically)."""
    write_text_atomic(draft.folder / EDIT_FILE,
                      json.dumps({"points": named_points(points), "face": face}, ensure_ascii=False))


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
            if entry.name.startswith(TRASH_PREFIX) and entry.is_dir():
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
            remove_folder(folder)
            deleted.append(folder.name)
    return deleted
