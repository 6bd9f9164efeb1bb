"""The point editor's logic: the points the user sent, checked, and the face model they give
(docs/web.md, "Face from a photo"; the routes are photo_views.py, the drafts draft_store.py).

Moving a point by (dx, dy) photo pixels moves the model point by MAP @ (dx, dy), where MAP
is the draft's `to_model`, the linear part of the least-squares affine map from the
detected photo points to the detected model points (draft_store.linear_map): the
normalisation photo/model_from_photo.py applies (levelling, turning to the camera,
closing the mouth) stays, and the user's correction is added to it.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np

from cartoonface.errors import FaceModelError, InputError
from cartoonface.face.model import POINT_INDEX, POINT_NAMES, FaceModel, face_from_dict, face_to_dict
from cartoonface.face.state import FaceState
from cartoonface.render.elements import svg_bytes
from cartoonface.render.svg import face_svg
from cartoonface.web.draft_store import Draft, model_points, named_points
from cartoonface.web.point_labels import POINT_LABELS

# A dragged point may leave the photo by this share of its size (a chin at the edge).
EDGE_MARGIN = 0.25
# The edited points arrive as JSON text of at most this many characters
# (49 names and pairs of numbers take about 2 kB).
MAX_POINTS_CHARS = 16384


def parse_points(text: str, size: tuple[int, int]) -> np.ndarray:
    """The edited points sent by the editor: JSON text of an object with every point name
    and no other, each [x, y] of finite numbers in photo.jpg pixels of `size` (width,
    height), at most EDGE_MARGIN of the photo outside it. Returns (49, 2) in POINT_NAMES
    order; InputError naming the point and what was expected."""
    if len(text) > MAX_POINTS_CHARS:
        raise InputError(f"points: {len(text)} characters; expected at most {MAX_POINTS_CHARS}")
    try:
        obj = json.loads(text)
    except (ValueError, RecursionError) as exc:  # not JSON, nested too deeply, an integer of 4300+ digits
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
    moved = model_points(draft.base) + (points - draft.detected) @ draft.to_model.T
    obj = {**draft.base, "points": named_points(moved)}
    try:
        face = face_from_dict(obj, "the cartoon")
    except FaceModelError as exc:
        named = re.search(r"points\['([^']+)'\]", str(exc))
        where = f"point {named.group(1)} ({POINT_LABELS[named.group(1)]})" if named else "these points"
        raise InputError(f"points: {where} cannot make a cartoon face; move it back towards the face "
                         f"(the model says: {exc})") from None
    return face, face_to_dict(face)


def preview_svg(face: FaceModel) -> bytes:
    """The cartoon face, neutral and still, as SVG bytes (render/svg.py face_svg)."""
    return svg_bytes(face_svg(face, FaceState()))
