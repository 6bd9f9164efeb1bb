"""The point editor's logic: the points the user sent, checked, and the face model they give
(docs/web.md, "Face from a photo"; the routes are photo_views.py, the drafts draft_store.py).

Moving a point by (dx, dy) photo pixels moves the model point by MAP @ (dx, dy), where MAP
is the draft's `to_model`, the linear part of the least-squares affine map from the
detected photo points to the detected model points (draft_store.linear_map): the
normalisation photo/model_from_photo.py applies (levelling, turning to the camera,
closing the mouth) stays, and the user's correction is added to it.

`implausible` finds points that landed where no face has them (an eye below the mouth, a
mouth corner outside the face outline, a left point on the right): the editor warns next to
the point and asks again before such points are used.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass

import numpy as np

from cartoonface.errors import FaceModelError, InputError
from cartoonface.face.model import POINT_INDEX, POINT_NAMES, FaceModel, face_from_dict, face_to_dict
from cartoonface.face.state import FaceState
from cartoonface.render.geometry import inside
from cartoonface.render.elements import svg_bytes
from cartoonface.render.svg import face_svg
from cartoonface.web.draft_store import Draft, model_points, named_points
from cartoonface.web.point_labels import PAIRS, POINT_LABELS

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


# Groups of points for the plausibility checks (docs/face-model.md, section 2).
EYES = ("3.1", "3.2", "3.3", "3.4", "3.5", "3.6", "3.7", "3.8", "3.11", "3.12")
BROWS = ("4.1", "4.2", "4.3", "4.4", "4.3a", "4.4a", "4.5", "4.6")
NOSE_TIP = ("9.15",)
MOUTH = ("8.1", "8.2", "8.3", "8.4", "8.9", "8.10", "2.2", "2.3")
CHIN = ("2.1",)
# The face outline (hairline, temples, cheeks, jaw, chin): inner points must stay inside it.
OUTLINE = ("11.1", "11.2a", "11.2", "10.10", "2.14", "2.1", "2.13", "10.9", "11.3", "11.3a")
INSIDE = EYES + NOSE_TIP + MOUTH
# (upper group, its name, lower group, its name): every point of the upper group is above
# every point of the lower one, measured along the face's own up-down direction.
ABOVE = ((EYES, "the eyes", MOUTH, "the mouth"), (EYES, "the eyes", NOSE_TIP, "the nose tip"),
         (BROWS, "the eyebrows", EYES, "the eyes"), (NOSE_TIP, "the nose tip", MOUTH, "the mouth"),
         (MOUTH, "the mouth", CHIN, "the chin"))
# A point must cross a line by more than this share of the eye distance to break a rule (so
# that points found close together, like the two top ends of the nose bridge, may touch).
CROSS_SHARE = 0.05


@dataclass(frozen=True)
class PointWarning:
    """A point that landed somewhere impossible: its name and what is wrong, in words."""

    point: str
    message: str


def _frame(detected: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """The face's own axes from the detected points ((49, 2) pixels): (origin between the
    iris centres, 2x2 rows across and down the face, the eye distance in pixels)."""
    right, left = detected[POINT_INDEX["3.5"]], detected[POINT_INDEX["3.6"]]
    origin = (right + left) / 2
    across = (right - left) / max(float(np.linalg.norm(right - left)), 1e-9)
    down = np.array([-across[1], across[0]])
    if down @ (detected[POINT_INDEX["2.1"]] - origin) < 0:
        down = -down
    return origin, np.stack([across, down]), float(np.linalg.norm(right - left))


def _outline_order(face: np.ndarray) -> np.ndarray:
    """The OUTLINE points' indices sorted by angle around their centre in `face` ((49, 2))."""
    indices = np.array([POINT_INDEX[name] for name in OUTLINE])
    offsets = face[indices] - face[indices].mean(axis=0)
    return indices[np.argsort(np.arctan2(offsets[:, 1], offsets[:, 0]))]


def _broken(points: np.ndarray, detected: np.ndarray) -> list[tuple[tuple[str, ...], dict[str, str]]]:
    """Every rule the `points` ((49, 2)) break, judged in the face's own axes of the `detected`
    points: (the rule and the points involved, as a key; point name -> what is wrong, with
    {name} for the point, for each point that may be blamed), outline rules first."""
    origin, axes, eye_distance = _frame(detected)
    face = (points - origin) @ axes.T  # (across, down) in the face's own axes
    where = (detected - origin) @ axes.T
    margin = CROSS_SHARE * eye_distance
    broken: list[tuple[tuple[str, ...], dict[str, str]]] = []
    ring = points[_outline_order(detected)]
    for name in INSIDE:
        if not inside(points[POINT_INDEX[name]], ring):
            pulled = f"{{name}} leaves point {name} ({POINT_LABELS[name]}) outside the face outline"
            broken.append((("outline", name), {name: "{name} is outside the face outline",
                                               **{edge: pulled for edge in OUTLINE}}))
    for (right, left), what in PAIRS.items():
        i, j = POINT_INDEX[right], POINT_INDEX[left]
        side = np.sign(where[i, 0] - where[j, 0])
        if side * (face[i, 0] - face[j, 0]) < -margin:
            told = f"{{name}} has crossed its partner: the two {what} points are swapped left for right"
            broken.append((("pair", right, left), {right: told, left: told}))
        for name, k in ((right, i), (left, j)):
            if abs(where[k, 0]) > margin and np.sign(where[k, 0]) * face[k, 0] < -margin:
                broken.append((("half", name), {name: "{name} is on the other half of the face"}))
    for upper, upper_name, lower, lower_name in ABOVE:
        for high in upper:
            for low in lower:
                if face[POINT_INDEX[high], 1] - face[POINT_INDEX[low], 1] > margin:
                    broken.append((("above", high, low), {
                        high: f"{{name}} is below {lower_name}; it belongs above {lower_name}",
                        low: f"{{name}} is above {upper_name}; it belongs below {upper_name}"}))
    return broken


def implausible(points: np.ndarray, detected: np.ndarray) -> tuple[PointWarning, ...]:
    """Warnings for the edited `points` ((49, 2) photo pixels) that are where no face has them,
    judged against the `detected` points ((49, 2)): an eye below the mouth or the nose tip, a
    brow below an eye, the mouth below the chin; the two points of a pair swapped left for right
    or one on the other half of the face; an eye, the nose tip or the mouth outside the face
    outline; a point must cross by more than CROSS_SHARE of the eye distance. A rule the
    detected points already break is not told. Each warning blames the point of the rule that
    was moved furthest from where it was found; at most one per point (the first rule it
    breaks), in POINT_NAMES order."""
    already = {key for key, _ in _broken(detected, detected)}
    moved = np.linalg.norm(points - detected, axis=1)
    told: dict[str, str] = {}
    for key, texts in _broken(points, detected):
        if key in already:
            continue
        blamed = max(texts, key=lambda name: moved[POINT_INDEX[name]])
        told.setdefault(blamed, texts[blamed].format(name=f"point {blamed} ({POINT_LABELS[blamed]})"))
    return tuple(PointWarning(name, told[name]) for name in POINT_NAMES if name in told)
