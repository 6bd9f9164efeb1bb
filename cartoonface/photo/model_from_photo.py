"""A cartoon face model from a portrait photo (thesis 002, 2.1-2.2, with a landmark model).

`load_photo(path)` reads and checks the picture; `face_from_photo(photo)` finds the
largest face (face mesh, landmarks.py), maps the mesh to the named points
(landmarks_map.py), segments the hair (hair.py), samples the colours
(palette.py), warns when the face is not neutral and normalises it (levels the
roll, turns it to face the camera, closes the mouth, drops a smile), and places it on
the canvas of the sample faces (d = 100 px). docs/photo.md.
"""

from __future__ import annotations

import math
import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image, ImageOps

from cartoonface.errors import FaceModelError, InputError
from cartoonface.photo.landmarks import Landmarks, landmarker
from cartoonface.photo.landmarks_map import IRIS_LEFT, IRIS_RIGHT, eyes, free_fapu, model_points
from cartoonface.face.model import FORMAT, POINT_INDEX, VERSION, FaceModel, face_from_dict
from cartoonface.photo.hair import Head, segment_head
from cartoonface.photo.palette import BLACK, face_colours, hex_colour, mix, palette_values

# A face narrower than this (in the photo's own pixels) is refused: too few pixels
# for the eyes and mouth to be placed.
MIN_FACE_PX = 64
# A file declaring more pixels than this is refused before decoding (a decompression bomb).
MAX_PIXELS = 100_000_000
# Larger photos are scaled down so their long side is at most this (faces stay big enough).
WORK_SIDE = 2048
# The model's canvas, eye distance and eye midpoint: those of samples/faces/*.json.
CANVAS = (400.0, 480.0)
MODEL_D = 100.0
EYES_AT = np.array([200.0, 200.0])
# Neutrality thresholds (ours): turn / roll beyond 15 degrees (the pose range of
# thesis 002, 2.4.3), a lip gap over 8 % of the mouth width, corners raised over 6 %.
MAX_TURN = 15.0
MAX_ROLL = 15.0
OPEN_MOUTH = 0.08
SMILE_LIFT = 0.06
# A smile moves the corners out by 1.0 UpperLipH and up by 1.5 (the smile expression,
# docs/face-model.md section 9): undoing a lift moves each corner in by 1/1.5 of it.
SMILE_SIDEWAYS = 1.0 / 1.5
# Symmetric mesh points (image left, image right) whose depth difference gives the turn.
TURN_PAIRS = ((33, 263), (133, 362), (234, 454), (93, 323), (61, 291), (129, 358))
# Smallest eye opening kept, in d (closed eyes are opened this far).
MIN_EYE_OPENING = 0.08
# Stand-ins for colours a photo does not show (RGB).
BROWN_IRIS = np.array([91.0, 58.0, 41.0])
LIP_RED = np.array([200.0, 80.0, 90.0])


@dataclass(frozen=True, eq=False)
class Photo:
    """A decoded photo: rgb (H, W, 3) uint8, upright (EXIF applied), alpha flattened on
    white; `scale` = its pixels per pixel of the file (< 1 when it was scaled down)."""

    rgb: np.ndarray
    source: str
    scale: float = 1.0


@dataclass(frozen=True, eq=False)
class PhotoFace:
    """The result of `face_from_photo`.

    face: the normalised cartoon face model.
    points: (49, 2) the named points as detected, in `photo.rgb` pixels (POINT_NAMES order).
    hair: (23, 2) the hair polygon in photo pixels.
    turn, roll: the head pose found, degrees (turn > 0: nose to the image right;
        roll > 0: the head leans with its top to the image left).
    clothes: '#rrggbb' clothes colour below the chin, or None.
    warnings: what was not neutral or was guessed, for the user.
    fringe: whether the hair outline comes down over the forehead (a fringe).
    """

    face: FaceModel
    points: np.ndarray
    hair: np.ndarray
    turn: float
    roll: float
    clothes: str | None
    warnings: tuple[str, ...]
    fringe: bool


def photo_from_image(image: Image.Image, source: str) -> Photo:
    """A Photo from a PIL image: grey, palette and alpha images become RGB (alpha over
    white); photos larger than WORK_SIDE are scaled down."""
    if image.mode in ("RGBA", "LA", "PA") or (image.mode == "P" and "transparency" in image.info):
        rgba = image.convert("RGBA")
        flat = Image.new("RGBA", rgba.size, (255, 255, 255, 255))
        flat.alpha_composite(rgba)
        image = flat
    rgb = image.convert("RGB")
    scale = min(1.0, WORK_SIDE / max(rgb.size))
    if scale < 1.0:
        rgb = rgb.resize((max(1, round(rgb.width * scale)), max(1, round(rgb.height * scale))),
                         Image.Resampling.LANCZOS)
    return Photo(rgb=np.asarray(rgb, dtype=np.uint8), source=source, scale=scale)


def load_photo(path: str | os.PathLike[str]) -> Photo:
    """Read a photo file (JPEG, PNG, WebP, ... anything Pillow decodes); InputError naming
    the file when it is missing, not an image, truncated or too large to decode safely."""
    source = str(path)
    if not Path(path).is_file():
        raise InputError(f"{source}: no such photo file")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            with Image.open(path) as image:
                if image.width * image.height > MAX_PIXELS:
                    raise InputError(f"{source}: the image declares {image.width} x {image.height} pixels; "
                                     f"expected at most {MAX_PIXELS // 1_000_000} megapixels")
                full = max(image.size)
                # JPEG can decode straight to a smaller size (much faster for huge photos).
                image.draft("RGB", (WORK_SIDE, WORK_SIDE))
                image.load()
                upright = ImageOps.exif_transpose(image)
                photo = photo_from_image(upright, source)
    except (Image.DecompressionBombError, Image.DecompressionBombWarning):
        raise InputError(f"{source}: the image is too large to decode safely (a decompression bomb?); "
                         f"expected at most {MAX_PIXELS // 1_000_000} megapixels") from None
    except Image.UnidentifiedImageError:
        raise InputError(f"{source}: not an image; expected a photo (JPEG, PNG, WebP, ...)") from None
    except (OSError, SyntaxError, ValueError) as exc:
        raise InputError(f"{source}: the image is truncated or damaged ({exc}); expected a complete photo") from None
    # The decoder may have scaled a JPEG down already: scale is relative to the file's size.
    return Photo(rgb=photo.rgb, source=source, scale=max(photo.rgb.shape[:2]) / full)


def _rotate2d(xy: np.ndarray, centre: np.ndarray, degrees: float) -> np.ndarray:
    """(N, 2) points turned `degrees` about `centre` in the image plane (positive: clockwise
    on screen, as y points down)."""
    a = math.radians(degrees)
    c, s = math.cos(a), math.sin(a)
    rel = xy - centre
    return np.column_stack([c * rel[:, 0] - s * rel[:, 1], s * rel[:, 0] + c * rel[:, 1]]) + centre


def _unturn(xyz: np.ndarray, centre: np.ndarray, degrees: float) -> np.ndarray:
    """(N, 2) image x, y of (N, 3) points turned back by `degrees` about the vertical axis
    through `centre` (3,), so a head turned by `degrees` faces the camera."""
    a = math.radians(degrees)
    rel = xyz - centre
    x = rel[:, 0] * math.cos(a) + rel[:, 2] * math.sin(a)
    return np.column_stack([x + centre[0], xyz[:, 1]])


def _neutral_mouth(points: np.ndarray, d: float) -> tuple[np.ndarray, list[str]]:
    """Close an open mouth and lower raised mouth corners on frontal (49, 2) points.
    Returns the new points and the warnings for the user."""
    p = points.copy()
    notes = []

    def at(name: str) -> np.ndarray:
        return p[POINT_INDEX[name]]

    width = at("8.3")[0] - at("8.4")[0]
    gap = at("2.3")[1] - at("2.2")[1]
    if gap > OPEN_MOUTH * width:
        notes.append(f"the mouth is open ({gap / width:.0%} of its width); the model closes it")
        for name, share in (("2.3", 1.0), ("8.2", 1.0), ("2.1", 1.0), ("2.13", 0.5), ("2.14", 0.5)):
            p[POINT_INDEX[name], 1] -= share * gap
    elif gap > 0:
        p[POINT_INDEX["2.3"], 1] = at("2.2")[1]
    line = (at("2.2")[1] + at("2.3")[1]) / 2
    lift = line - (at("8.3")[1] + at("8.4")[1]) / 2
    if lift > SMILE_LIFT * width:
        notes.append(f"the face smiles (mouth corners {lift / d:.2f} d above the lips); the model lowers them")
        inward = SMILE_SIDEWAYS * lift
        p[POINT_INDEX["8.3"]] += [-inward, line - at("8.3")[1]]
        p[POINT_INDEX["8.4"]] += [inward, line - at("8.4")[1]]
    for upper, lower in (("3.2", "3.4"), ("3.1", "3.3")):
        opening = at(lower)[1] - at(upper)[1]
        if opening < MIN_EYE_OPENING * d:
            notes.append(f"the eye at {upper} looks closed; the model opens it")
            middle = (at(lower)[1] + at(upper)[1]) / 2
            p[POINT_INDEX[upper], 1] = middle - MIN_EYE_OPENING * d / 2
            p[POINT_INDEX[lower], 1] = middle + MIN_EYE_OPENING * d / 2
    return p, notes


def _palette(colours: dict[str, np.ndarray | None], head: Head, skin: np.ndarray) -> tuple[dict[str, str], list[str]]:
    """The face's palette (hex colours by name) from the sampled face colours and the head
    segmentation, with a stand-in (and a warning) for what could not be sampled: when no
    hair is found the hair takes the eyebrow colour."""
    notes = []
    brow = colours["brow"] if colours["brow"] is not None else mix(skin, BLACK, 0.6)
    hair = head.hair
    if hair is None:
        notes.append("no hair found around the face; the hair takes the eyebrow colour")
    iris = colours["iris"]
    if iris is None:
        notes.append("the irises are hidden; the model uses a brown iris")
        iris = BROWN_IRIS
    lip = colours["lip"] if colours["lip"] is not None else mix(skin, LIP_RED, 0.5)
    return palette_values(skin, brow if hair is None else hair, brow, iris, lip), notes


def face_from_photo(photo: Photo, name: str = "photo") -> PhotoFace:
    """The cartoon face of the largest face in `photo`.

    InputError naming the photo when no face is found or the face is narrower than
    MIN_FACE_PX pixels of the file; PhotoExtraMissing without the photo extra.
    """
    found = landmarker().find(photo.rgb)
    if found is None:
        raise InputError(f"{photo.source}: no face found in the photo; expected a frontal portrait")
    return face_from_landmarks(photo, found, name)


def face_from_landmarks(photo: Photo, found: Landmarks, name: str = "photo") -> PhotoFace:
    """The cartoon face of the face whose landmarks `found` were read from `photo`
    (face_from_photo without the detection step)."""
    source = photo.source
    mesh = found.points
    face_width = float(np.ptp(mesh[:, 0])) / photo.scale
    if face_width < MIN_FACE_PX:
        raise InputError(f"{source}: photo too small: the face is {face_width:.0f} px wide; "
                         f"expected at least {MIN_FACE_PX} px")
    notes = []
    if found.faces > 1:
        notes.append(f"{found.faces} faces in the photo; using the largest")

    middle, _d = eyes(mesh)
    across = mesh[IRIS_RIGHT] - mesh[IRIS_LEFT]
    roll = math.degrees(math.atan2(across[1], across[0]))
    level = mesh.copy()
    level[:, :2] = _rotate2d(mesh[:, :2], middle[:2], -roll)
    turn = float(np.degrees(np.median([math.atan2(level[b, 2] - level[a, 2], level[b, 0] - level[a, 0])
                                       for a, b in TURN_PAIRS])))
    if abs(turn) > MAX_TURN:
        notes.append(f"the head is turned {abs(turn):.0f} degrees (more than {MAX_TURN:g}); the model is "
                     "turned to face the camera and its far side is a guess")
    if abs(roll) > MAX_ROLL:
        notes.append(f"the head leans {abs(roll):.0f} degrees sideways; the model is levelled")

    named = model_points(level)
    photo_points = _rotate2d(named[:, :2], middle[:2], roll)

    colours = face_colours(photo.rgb, mesh)
    skin = colours["skin"]
    if skin is None:
        raise InputError(f"{source}: the face shows too little skin to sample its colour; expected a clear portrait")
    head = segment_head(photo.rgb, mesh, skin, roll, turn, landmarker().person)
    hair_level = _rotate2d(head.polygon, middle[:2], -roll)
    hair_depth = float(np.mean(level[[234, 454], 2]))
    hair_xyz = np.column_stack([hair_level, np.full(len(hair_level), hair_depth)])

    axis, _d = eyes(level)
    frontal = _unturn(named, axis, turn)
    hair_frontal = _unturn(hair_xyz, axis, turn)
    d = float(np.hypot(*(frontal[POINT_INDEX["3.5"]] - frontal[POINT_INDEX["3.6"]])))
    frontal, mouth_notes = _neutral_mouth(frontal, d)
    notes.extend(mouth_notes)

    k = MODEL_D / d
    centre = (frontal[POINT_INDEX["3.5"]] + frontal[POINT_INDEX["3.6"]]) / 2
    points = (frontal - centre) * k + EYES_AT
    hair = (hair_frontal - centre) * k + EYES_AT
    hair = np.clip(hair, [0, 0], [CANVAS[0], CANVAS[1]])

    palette, colour_notes = _palette(colours, head, skin)
    notes.extend(colour_notes)

    fapu = {key: value * k for key, value in free_fapu(level).items()}
    obj = {
        "format": FORMAT, "version": VERSION, "name": name, "canvas": list(CANVAS),
        "points": {n: [float(x), float(y)] for n, (x, y) in zip(POINT_INDEX, points)},
        "hair": [[float(x), float(y)] for x, y in hair],
        "fapu": fapu,
        "palette": palette,
    }
    try:
        face = face_from_dict(obj, source)
    except FaceModelError as exc:
        raise InputError(f"{source}: the face found could not be made into a model ({exc})") from None
    return PhotoFace(face=face, points=photo_points, hair=head.polygon, turn=turn, roll=roll,
                     clothes=hex_colour(head.clothes) if head.clothes is not None else None,
                     warnings=tuple(notes), fringe=head.fringe)
