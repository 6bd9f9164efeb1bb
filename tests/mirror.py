"""Mirror images of faces for the symmetry tests: the left-right partner of every lifted point
and a face model reflected about its canvas's middle."""

from __future__ import annotations

import numpy as np

from cartoonface.face.lift import LIFTED_INDEX, LIFTED_NAMES
from cartoonface.face.model import face_from_dict, face_to_dict

# Left-right partner of every lifted point (docs/face-model.md); unlisted points lie on the midline.
PAIRS = [
    ("2.13", "2.14"), ("3.1", "3.2"), ("3.3", "3.4"), ("3.5", "3.6"), ("3.7", "3.12"), ("3.8", "3.11"),
    ("4.1", "4.2"), ("4.3", "4.4"), ("4.3a", "4.4a"), ("4.5", "4.6"), ("8.3", "8.4"), ("8.9", "8.10"),
    ("9.1", "9.2"), ("9.4", "9.5"), ("9.6", "9.7"), ("9.13", "9.14"), ("10.1", "10.2"), ("10.7", "10.8"),
    ("10.9", "10.10"), ("11.2", "11.3"), ("11.2a", "11.3a"),
    ("A", "B"), ("D", "E"), ("F", "I"), ("G", "H"), ("J", "K"), ("L", "M"), ("N", "Q"), ("R", "S"),
]
PARTNER = {n: n for n in LIFTED_NAMES} | {a: b for a, b in PAIRS} | {b: a for a, b in PAIRS}
SWAP = np.array([LIFTED_INDEX[PARTNER[n]] for n in LIFTED_NAMES])


def mirrored(face, skew=0.0):
    """The face reflected left-right about x = width / 2, names swapped; `skew`
    first moves some image-left points so the face is not symmetric."""
    obj = face_to_dict(face)
    points = {n: list(p) for n, p in obj["points"].items()}
    if skew:
        for name in ("3.12", "4.6", "8.4", "11.2a", "10.10"):
            points[name] = [points[name][0] - skew, points[name][1] + skew / 2]
        obj["points"] = points
        face = face_from_dict(obj, "skewed")
        obj = face_to_dict(face)
        points = obj["points"]
    w = obj["canvas"][0]
    flipped = dict(obj)
    flipped["points"] = {PARTNER[n]: [w - x, y] for n, (x, y) in points.items()}
    flipped["hair"] = [[w - x, y] for x, y in obj["hair"]]
    flipped["fapu"] = dict(obj["fapu"], r1=obj["fapu"]["r2"], r2=obj["fapu"]["r1"])
    return face, face_from_dict(flipped, "mirrored")
