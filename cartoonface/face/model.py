"""The 2D cartoon face model: named feature points, hair contour, FAPUs, palette.

Thesis 002, 2.2 (the 72-point model of Chen and Tsai, Fig. 2.2, missing from the
text) rebuilt from every point the thesis names; docs/face-model.md lists them.
Coordinates are image pixels, x right, y down. A face is loaded from / saved to
JSON (format "cartoonface-face", version 1) and validated on load: every problem
raises FaceModelError naming the file and field.
"""

from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass, fields, replace
from pathlib import Path

import numpy as np

from cartoonface.errors import FaceModelError
from cartoonface.files import read_user_text, write_text_atomic

FORMAT = "cartoonface-face"
VERSION = 1

# Thesis 002, 2.2 / 2.3.2 / 2.4.1 / 5.2: every point the text names, MPEG-4
# style. "Left" in the thesis is the image left: the image-left eye is drawn
# with 3.12, 3.2, 3.8, 3.4 (Alg. 2.2 step 9), so even numbers are on the image
# left, odd ones on the image right. 3.5 / 3.6 are the eyeball (iris) centres of
# the image-right / image-left eye, as MPEG-4 numbers them (subject's left = odd).
# 8.5 is not a point: the thesis names it only in S = 8.5 (Alg. 2.1), which
# Table 2.1 pairs with 8.3 and Alg. 2.2 step 13 uses as the right mouth corner;
# we read it as 8.3. 47 points + 2 eyeball centres + 23 hair points = 72.
POINT_NAMES: tuple[str, ...] = (
    # chin, inner lips, jaw corners
    "2.1", "2.2", "2.3", "2.13", "2.14",
    # eyes: upper lids, lower lids, eyeball centres, corners
    "3.1", "3.2", "3.3", "3.4", "3.5", "3.6", "3.7", "3.8", "3.11", "3.12",
    # eyebrows
    "4.1", "4.2", "4.3", "4.4", "4.5", "4.6", "4.3a", "4.4a",
    # outer lips
    "8.1", "8.2", "8.3", "8.4", "8.9", "8.10",
    # nose
    "9.1", "9.2", "9.4", "9.5", "9.6", "9.7", "9.13", "9.14", "9.15",
    # ears and cheeks
    "10.1", "10.2", "10.7", "10.8", "10.9", "10.10",
    # forehead / temples
    "11.1", "11.2", "11.3", "11.2a", "11.3a",
)
POINT_INDEX: dict[str, int] = {name: i for i, name in enumerate(POINT_NAMES)}

# Thesis 002, Alg. 2.2 step 2: the hair is a polygon of 23 points. Faces from
# other sources may use more or fewer; at least a triangle is required.
HAIR_POINTS = 23
MIN_HAIR_POINTS = 3
# At most this many hair points: 17 x the thesis's 23, room for a finely traced outline
# (2.7 px apart on the sample's outline). Drawing one state is now linear in H
# (render/geometry.py: a banded (8 H, H) corner-cutting matrix; 30,000 points peak at
# 39 MiB), but `generate` keeps every distinct frame's drawing while it compacts the
# animation (render/compact.py), about 110 bytes per hair point per frame. Extrapolated
# from a 25 s recording at 12-60 fps, a 30-minute recording at 30 fps then takes about
# 2 GB with 400 points and 12 GB with 2,000, over a web job's 6 GiB
# (docs/BENCHMARKS.md "Face drawing").
MAX_HAIR_POINTS = 400

# Every point and hair point lies on the canvas or within this share of its size
# outside it (hair may reach past the edge of the picture).
CANVAS_MARGIN = 0.5
# A free FAPU (eyebrow thickness, iris radius) is at most this many eye distances d
# (the samples: 0.10 .. 0.15 d): a larger one is a wrong number, and would draw a shape
# far larger than the face.
MAX_FREE_FAPU_D = 1.0
# A JSON number with more digits than this is refused before it is read (Python refuses
# integers of over 4300 digits with a ValueError; a coordinate needs a dozen).
MAX_NUMBER_DIGITS = 100

# Half-size of the face box in median deviations of the model points from
# their median (about 2.4 d across and 3.6 d down for the samples): room for
# long hair and ears; a point beyond it is a typo or a wrong coordinate system.
FACE_BOX_SPREADS = 8.0
MAX_CANVAS = 10000.0

# FAPUs the file must give (not computable from the points).
FREE_FAPU = ("eyebrow_h", "eyebrow_h2", "r1", "r2")
# FAPUs computed from the points; a value in the file is ignored (the points win).
COMPUTED_FAPU = ("d", "left_eye_h", "right_eye_h", "upper_lip_h", "lower_lip_h", "mns0", "mw0", "jaw_h")


@dataclass(frozen=True)
class Fapu:
    """Facial animation parameter units in pixels (thesis 002, 2.2, Fig. 2.2b).

    d: distance between the eyeball centres 3.5 and 3.6 (the length unit of 2.3.2).
    eyebrow_h / eyebrow_h2: 1.3 x the eyebrow thickness at 4.4/4.3 and at
        4.4a/4.3a (Alg. 2.1: G = 4.4 + EyebrowH/1.3, F = 4.4a + EyebrowH2/1.3).
    left_eye_h / right_eye_h: eye opening 3.4 - 3.2 (image left) / 3.3 - 3.1.
    upper_lip_h: 2.2.y - 8.1.y; lower_lip_h: 8.2.y - 2.3.y.
    mns0: mouth-nose separation 2.2.y - 9.15.y; mw0: mouth width 8.3.x - 8.4.x.
    jaw_h: 2.1.y - 8.2.y (thesis 5.2.2: 2.1 = 8.2 + JawH).
    r1 / r2: iris radius of the image-left (3.6) / image-right (3.5) eye.
    """

    d: float
    eyebrow_h: float
    eyebrow_h2: float
    left_eye_h: float
    right_eye_h: float
    upper_lip_h: float
    lower_lip_h: float
    mns0: float
    mw0: float
    jaw_h: float
    r1: float
    r2: float


@dataclass(frozen=True)
class Palette:
    """Named fill/stroke colours of a face as '#rrggbb' strings."""

    skin: str
    skin_shadow: str
    hair: str
    brow: str
    eye_white: str
    iris: str
    pupil: str
    lip: str
    mouth: str
    cheek: str
    outline: str


PALETTE_NAMES = tuple(f.name for f in fields(Palette))
FAPU_NAMES = tuple(f.name for f in fields(Fapu))
_COLOUR = re.compile(r"^#(?:[0-9a-fA-F]{3}|[0-9a-fA-F]{6})$")


@dataclass(frozen=True, eq=False)
class FaceModel:
    """A frontal neutral cartoon face.

    points: (P, 2) float, P = len(POINT_NAMES), image pixels in POINT_NAMES order.
    hair: (H, 2) float, the hair contour polygon in drawing order.
    width, height: canvas size in pixels.
    """

    name: str
    points: np.ndarray
    hair: np.ndarray
    fapu: Fapu
    palette: Palette
    width: float
    height: float

    def point(self, name: str) -> np.ndarray:
        """The (2,) position of the named model point (KeyError for an unknown name)."""
        return self.points[POINT_INDEX[name]]


def _frozen(array: np.ndarray) -> np.ndarray:
    out = np.array(array, dtype=float)
    out.flags.writeable = False
    return out


def computed_fapu(points: np.ndarray) -> dict[str, float]:
    """The FAPUs that follow from the (P, 2) points, by name (pixels, see Fapu)."""

    def p(name: str) -> np.ndarray:
        return points[POINT_INDEX[name]]

    return {
        "d": float(np.hypot(*(p("3.5") - p("3.6")))),
        "left_eye_h": float(p("3.4")[1] - p("3.2")[1]),
        "right_eye_h": float(p("3.3")[1] - p("3.1")[1]),
        "upper_lip_h": float(p("2.2")[1] - p("8.1")[1]),
        "lower_lip_h": float(p("8.2")[1] - p("2.3")[1]),
        "mns0": float(p("2.2")[1] - p("9.15")[1]),
        "mw0": float(p("8.3")[0] - p("8.4")[0]),
        "jaw_h": float(p("2.1")[1] - p("8.2")[1]),
    }


# What each computed FAPU needs from the points, for error messages.
_COMPUTED_RULE = {
    "d": "the eyeball centres 3.5 and 3.6 must be apart",
    "left_eye_h": "the lower eyelid 3.4 must be below the upper eyelid 3.2",
    "right_eye_h": "the lower eyelid 3.3 must be below the upper eyelid 3.1",
    "upper_lip_h": "the inner upper lip 2.2 must not be above the outer upper lip 8.1",
    "lower_lip_h": "the outer lower lip 8.2 must not be above the inner lower lip 2.3",
    "mns0": "the inner upper lip 2.2 must be below the nose tip 9.15",
    "mw0": "the mouth corner 8.3 must be right of the corner 8.4",
    "jaw_h": "the chin 2.1 must be below the lower lip 8.2",
}
# Computed FAPUs that may be zero (a lower lip drawn as a line); the others must be > 0.
_MAY_BE_ZERO = ("lower_lip_h",)


def _number(value: object, where: str, source: str) -> float:
    if isinstance(value, LongNumber):
        raise FaceModelError(f"{source}: {where} is {value!r}; expected a number of at most "
                             f"{MAX_NUMBER_DIGITS} characters")
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise FaceModelError(f"{source}: {where} is {value!r}; expected a number")
    if not math.isfinite(value):
        raise FaceModelError(f"{source}: {where} is {value!r}; expected a finite number")
    return float(value)


def _xy(value: object, where: str, source: str) -> tuple[float, float]:
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise FaceModelError(f"{source}: {where} is {value!r}; expected [x, y]")
    return _number(value[0], f"{where}[0]", source), _number(value[1], f"{where}[1]", source)


def _obj(value: object, where: str, source: str) -> dict:
    if not isinstance(value, dict):
        raise FaceModelError(f"{source}: {where} is {type(value).__name__}; expected an object")
    return value


def _check_keys(given: dict, expected: tuple[str, ...], where: str, source: str, required: tuple[str, ...]) -> None:
    unknown = [k for k in given if k not in expected]
    if unknown:
        raise FaceModelError(
            f"{source}: {where}: unknown {where} entry {unknown[0]!r}; expected one of {', '.join(expected)}"
        )
    missing = [k for k in required if k not in given]
    if missing:
        raise FaceModelError(f"{source}: {where}: missing {where} entry {missing[0]!r}")


def face_from_dict(obj: object, source: str) -> FaceModel:
    """Validate a parsed face JSON object and build the FaceModel.

    source names the file (or other origin) in error messages. Raises
    FaceModelError naming the first offending field.
    """
    top = _obj(obj, "the face file", source)
    if top.get("format") != FORMAT:
        raise FaceModelError(f"{source}: format is {top.get('format')!r}; expected {FORMAT!r}")
    if "version" not in top:
        raise FaceModelError(f"{source}: version is missing; expected {VERSION}")
    if isinstance(top["version"], bool) or top["version"] != VERSION:
        raise FaceModelError(f"{source}: version is {top['version']!r}; this program reads version {VERSION}")
    known = ("format", "version", "name", "canvas", "points", "hair", "fapu", "palette")
    _check_keys(top, known, "top-level", source, known)

    name = top["name"]
    if not isinstance(name, str) or isinstance(name, LongNumber) or not name.strip():
        raise FaceModelError(f"{source}: name is {name!r}; expected a non-empty string")

    canvas = top["canvas"]
    width, height = _xy(canvas, "canvas", source)
    for label, size in (("canvas width", width), ("canvas height", height)):
        if not 0 < size <= MAX_CANVAS:
            raise FaceModelError(f"{source}: {label} is {size:g}; expected 0 < size <= {MAX_CANVAS:g} pixels")

    given_points = _obj(top["points"], "points", source)
    _check_keys(given_points, POINT_NAMES, "points", source, POINT_NAMES)
    points = np.array([_xy(given_points[n], f"points[{n!r}]", source) for n in POINT_NAMES])

    hair_list = top["hair"]
    if not isinstance(hair_list, list) or len(hair_list) < MIN_HAIR_POINTS:
        raise FaceModelError(f"{source}: hair must be a list of at least {MIN_HAIR_POINTS} [x, y] points")
    if len(hair_list) > MAX_HAIR_POINTS:
        raise FaceModelError(f"{source}: hair has {len(hair_list)} points; expected at most {MAX_HAIR_POINTS}")
    hair = np.array([_xy(p, f"hair[{i}]", source) for i, p in enumerate(hair_list)])
    _check_canvas(points, hair, width, height, source)

    given_fapu = _obj(top["fapu"], "fapu", source)
    _check_keys(given_fapu, FAPU_NAMES, "fapu", source, FREE_FAPU)
    values = {}
    for key, value in given_fapu.items():
        number = _number(value, f"fapu.{key}", source)
        if number < 0:
            raise FaceModelError(f"{source}: fapu.{key} is {number:g}; a FAPU is a length, expected >= 0")
        values[key] = number
    for key in ("r1", "r2"):
        if values[key] <= 0:
            raise FaceModelError(f"{source}: fapu.{key} is {values[key]:g}; an iris radius must be > 0")
    _check_box(points, hair, source)
    for key, value in computed_fapu(points).items():
        if value < 0 or (value == 0 and key not in _MAY_BE_ZERO):
            raise FaceModelError(
                f"{source}: fapu.{key} computed from the points is {value:g}: {_COMPUTED_RULE[key]}"
            )
        values[key] = value
    for key in FREE_FAPU:
        if values[key] > MAX_FREE_FAPU_D * values["d"]:
            raise FaceModelError(f"{source}: fapu.{key} is {values[key]:g}; expected at most "
                                 f"{MAX_FREE_FAPU_D:g} x the eye distance d = {values['d']:g} pixels")

    given_palette = _obj(top["palette"], "palette", source)
    _check_keys(given_palette, PALETTE_NAMES, "palette", source, PALETTE_NAMES)
    for key, value in given_palette.items():
        if not isinstance(value, str) or not _COLOUR.match(value):
            raise FaceModelError(f"{source}: palette.{key} is {value!r}; expected a colour like '#a0522d'")

    return FaceModel(
        name=name.strip(),
        points=_frozen(points),
        hair=_frozen(hair),
        fapu=Fapu(**{k: values[k] for k in FAPU_NAMES}),
        palette=Palette(**{k: given_palette[k].lower() for k in PALETTE_NAMES}),
        width=width,
        height=height,
    )


def _check_canvas(points: np.ndarray, hair: np.ndarray, width: float, height: float, source: str) -> None:
    """Every point ((P, 2) and hair (H, 2), pixels) lies on the `width` x `height` canvas
    or within CANVAS_MARGIN of its size outside it; FaceModelError naming the first that does not."""
    low = -CANVAS_MARGIN * np.array([width, height])
    high = (1 + CANVAS_MARGIN) * np.array([width, height])
    area = f"[{low[0]:g}..{high[0]:g}] x [{low[1]:g}..{high[1]:g}]"
    outside = _first_outside(points, hair, low, high)
    if outside:
        where, x, y = outside
        raise FaceModelError(f"{source}: {where} = [{x:g}, {y:g}] is off the {width:g} x {height:g} canvas; "
                             f"expected within {area}")


def _first_outside(points: np.ndarray, hair: np.ndarray, low: np.ndarray,
                   high: np.ndarray) -> tuple[str, float, float] | None:
    """The first of `points` (P, 2) then `hair` (H, 2) outside the box `low`..`high` (2,) pixels,
    as (its field name, x, y), or None when all lie inside."""
    for label, array in (("points", points), ("hair", hair)):
        outside = np.nonzero(np.any((array < low) | (array > high), axis=1))[0]
        if outside.size:
            i = int(outside[0])
            where = f"points[{POINT_NAMES[i]!r}]" if label == "points" else f"hair[{i}]"
            return where, float(array[i][0]), float(array[i][1])
    return None


def _check_box(points: np.ndarray, hair: np.ndarray, source: str) -> None:
    """Every point and hair point lies in the face box.

    The face box is centred on the per-axis median of the model points and
    reaches FACE_BOX_SPREADS median deviations each way: robust, so one wild
    point cannot stretch the box that is meant to catch it.
    """
    centre = np.median(points, axis=0)
    spread = np.maximum(np.median(np.abs(points - centre), axis=0), 1.0)
    low, high = centre - FACE_BOX_SPREADS * spread, centre + FACE_BOX_SPREADS * spread
    box = f"[{low[0]:.0f}..{high[0]:.0f}] x [{low[1]:.0f}..{high[1]:.0f}]"
    outside = _first_outside(points, hair, low, high)
    if outside:
        where, x, y = outside
        raise FaceModelError(f"{source}: {where} = [{x:g}, {y:g}] is far outside the face box; expected within {box}")


def load_face(path: str | os.PathLike[str]) -> FaceModel:
    """Read and validate a face JSON file; FaceModelError names the file and field."""
    source = str(path)
    text = read_user_text(path, FaceModelError, "face file")
    return face_from_dict(parse_face_json(text, source), source)


class LongNumber(str):
    """The text of a JSON number of more than MAX_NUMBER_DIGITS characters, kept unread."""

    def __repr__(self) -> str:
        return f"a number of {len(self)} characters"


def _int_or_long(text: str) -> int | LongNumber:
    return LongNumber(text) if len(text) > MAX_NUMBER_DIGITS else int(text)


def _float_or_long(text: str) -> float | LongNumber:
    return LongNumber(text) if len(text) > MAX_NUMBER_DIGITS else float(text)


def json_with_long_numbers(text: str) -> object:
    """json.loads(`text`), except that a number of more than MAX_NUMBER_DIGITS characters
    becomes a LongNumber (which face_from_dict refuses naming its field) instead of being
    read. Raises what json.loads raises (ValueError, RecursionError)."""
    return json.loads(text, parse_int=_int_or_long, parse_float=_float_or_long)


def parse_face_json(text: str, source: str) -> object:
    """The JSON value of a face file's `text` (json_with_long_numbers); FaceModelError
    naming `source` when the text is not JSON or nests too deeply."""
    try:
        return json_with_long_numbers(text)
    except json.JSONDecodeError as exc:
        raise FaceModelError(
            f"{source}: not valid JSON at line {exc.lineno} column {exc.colno}: {exc.msg}"
        ) from None
    except (ValueError, RecursionError) as exc:  # deep nesting, or a number Python will not read
        raise FaceModelError(f"{source}: not a face model this program reads ({exc})") from None


def _round(value: float) -> float:
    return round(float(value), 2)


def face_to_dict(face: FaceModel) -> dict:
    """The JSON object for a face (all FAPUs listed; computed ones for reference)."""
    return {
        "format": FORMAT,
        "version": VERSION,
        "name": face.name,
        "canvas": [_round(face.width), _round(face.height)],
        "points": {n: [_round(x), _round(y)] for n, (x, y) in zip(POINT_NAMES, face.points)},
        "hair": [[_round(x), _round(y)] for x, y in face.hair],
        "fapu": {k: _round(getattr(face.fapu, k)) for k in FAPU_NAMES},
        "palette": {k: getattr(face.palette, k) for k in PALETTE_NAMES},
    }


# A JSON [x, y] pair that json.dumps(indent=...) spread over three lines.
_PAIR = re.compile(r"\[\s+(-?[0-9.e+-]+),\s+(-?[0-9.e+-]+)\s+\]")


def save_face(face: FaceModel, path: str | os.PathLike[str]) -> Path:
    """Write the face as JSON, one point per line (atomically); return the path."""
    text = _PAIR.sub(r"[\1, \2]", json.dumps(face_to_dict(face), indent=1))
    return write_text_atomic(path, text + "\n")


def scale_face(face: FaceModel, d: float) -> FaceModel:
    """The face scaled so its FAPU d becomes `d` pixels (thesis 002, 2.3.2).

    Every point, hair point, FAPU and the canvas are multiplied by d / face.fapu.d
    about the image origin (0, 0). FaceModelError if d is not a positive number.
    """
    if isinstance(d, bool) or not isinstance(d, (int, float)) or not math.isfinite(d) or d <= 0:
        raise FaceModelError(f"scale: d is {d!r}; expected a positive number of pixels")
    k = d / face.fapu.d
    fapu = Fapu(**{n: getattr(face.fapu, n) * k for n in FAPU_NAMES})
    return replace(
        face,
        points=_frozen(face.points * k),
        hair=_frozen(face.hair * k),
        fapu=fapu,
        width=face.width * k,
        height=face.height * k,
    )
