"""The 2D face lifted to 3D (thesis 002, 2.3.2, Alg. 2.1 and Table 2.1).

The rotation origin O (the centre of the neck) lies 1.3 d below EyeMid; 17
additional points A..S help drawing turned faces; every point gets a depth
from Table 2.1 as a multiple of d. Local coordinates: x right, y up, z towards
the viewer, origin O, in pixels.

The thesis writes the local transform as x = x_o - x (Alg. 2.1 step 5) but the
way back as x = x + x_o (2.4.1, Alg. 2.3 step 4); these are not inverses. We
use x_local = x - x_o, the inverse of the way back: the frame is then
right-handed, and a positive turn (Alg. 2.3 step 5) hides the image-right
contour points 11.3, 10.9, 2.13, as the thesis's replacement rule requires.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cartoonface.face.model import POINT_INDEX, POINT_NAMES, FaceModel

# Thesis 002, Alg. 2.1 step 3: y_o = EyeMid.y + 1.3 d (image y down).
ORIGIN_BELOW_EYES = 1.3

ADDITIONAL_NAMES: tuple[str, ...] = ("A", "B", "C", "D", "E", "F", "G", "H", "I", "J", "K", "L", "M", "N", "Q", "R", "S")
LIFTED_NAMES: tuple[str, ...] = POINT_NAMES + ADDITIONAL_NAMES
LIFTED_INDEX: dict[str, int] = {name: i for i, name in enumerate(LIFTED_NAMES)}

_EYEMID = (("3.5", 0.5), ("3.6", 0.5))
# Thesis 002, Alg. 2.1 step 4, in image coordinates (y down), as data:
# name -> (x terms, y terms, x offset, y offset). A term list is a weighted
# sum of model points (weights add up to 1); an offset is (coefficient,
# quantity) with quantity "w_ear" (W_ear, step 1) or a FAPU field name.
# S: the text says S = 8.5, but Table 2.1 pairs R, S with 8.4, 8.3 and Alg. 2.2
# step 13 closes the inner mouth with arc(R, 2.2, S): S is the corner 8.3.
ADDITIONAL: dict[str, tuple] = {
    "A": (_EYEMID, (("10.2", 0.8), ("10.8", 0.2)), (-1.0, "w_ear"), None),
    "B": (_EYEMID, (("10.1", 0.8), ("10.7", 0.2)), (1.0, "w_ear"), None),
    "C": ((("9.13", 0.5), ("9.14", 0.5)), (("9.14", 0.5), ("3.5", 0.25), ("3.6", 0.25)), None, None),
    "D": ((("9.4", 5 / 6), ("9.5", 1 / 6)), (("9.4", 2 / 3), ("9.14", 1 / 3)), None, None),
    "E": ((("9.5", 5 / 6), ("9.4", 1 / 6)), (("9.5", 2 / 3), ("9.13", 1 / 3)), None, None),
    "F": ((("4.4a", 1.0),), (("4.4a", 1.0),), None, (1 / 1.3, "eyebrow_h2")),
    "G": ((("4.4", 1.0),), (("4.4", 1.0),), None, (1 / 1.3, "eyebrow_h")),
    "H": ((("4.3", 1.0),), (("4.3", 1.0),), None, (1 / 1.3, "eyebrow_h")),
    "I": ((("4.3a", 1.0),), (("4.3a", 1.0),), None, (1 / 1.3, "eyebrow_h2")),
    "J": ((("2.14", 5 / 6), ("2.1", 1 / 6)), (("2.14", 1.0),), None, None),
    "K": ((("2.13", 5 / 6), ("2.1", 1 / 6)), (("2.13", 1.0),), None, None),
    "L": ((("3.12", 0.5), ("10.10", 0.5)), (("10.10", 1.0),), None, None),
    "M": ((("3.7", 0.5), ("10.9", 0.5)), (("10.9", 1.0),), None, None),
    "N": ((("11.2", 1.0),), (("11.2", 1.0),), None, None),
    "Q": ((("11.3", 1.0),), (("11.3", 1.0),), None, None),
    "R": ((("8.4", 1.0),), (("8.4", 1.0),), None, None),
    "S": ((("8.3", 1.0),), (("8.3", 1.0),), None, None),
}

# Thesis 002, Table 2.1: depth (z) of each point as a multiple of d.
HAIR_DEPTH = -0.58
DEPTH: dict[str, float] = {
    "3.1": 1.33, "3.2": 1.33, "3.3": 1.33, "3.4": 1.33, "3.5": 1.33, "3.6": 1.33,
    "3.7": 1.19, "3.12": 1.19, "3.8": 1.25, "3.11": 1.25,
    "4.5": 1.17, "4.6": 1.17, "4.3a": 1.30, "4.4a": 1.30, "F": 1.30, "I": 1.30,
    "4.3": 1.44, "4.4": 1.44, "G": 1.44, "H": 1.44, "4.1": 1.49, "4.2": 1.49,
    "2.2": 1.55, "2.3": 1.55, "8.3": 1.40, "8.4": 1.40, "R": 1.40, "S": 1.40,
    "8.1": 1.60, "8.9": 1.60, "8.10": 1.60, "8.2": 1.56,
    "2.13": 0.36, "2.14": 0.36, "2.1": 1.33, "J": 1.18, "K": 1.18,
    "11.1": 1.37, "11.2a": 0.90, "11.3a": 0.90, "11.2": 0.42, "11.3": 0.42, "N": 0.85, "Q": 0.85,
    "10.1": -0.37, "10.2": -0.37, "10.7": 0.0, "10.8": 0.0, "A": 0.04, "B": 0.04,
    "9.1": 1.39, "9.2": 1.39, "9.6": 1.39, "9.7": 1.39, "9.13": 1.40, "9.14": 1.40,
    "9.4": 1.44, "9.5": 1.44, "9.15": 1.65, "C": 1.51, "D": 1.53, "E": 1.53,
    "10.9": 0.27, "10.10": 0.27, "L": 1.11, "M": 1.11,
}


@dataclass(frozen=True, eq=False)
class LiftedFace:
    """A face model in 3D (Alg. 2.1).

    origin: (2,) rotation origin O in image pixels.
    local: (N, 3) pixels, N = len(LIFTED_NAMES), local frame (x right, y up, z front).
    hair: (H, 3) hair points in the local frame (z = HAIR_DEPTH d).
    depends, offsets: (2N, 2P) and (N, 2), Alg. 2.1 step 4 as an affine map
        (additional_map): the additional points follow any displacement of the
        model points (expressions, mouth); see lifted_image_points.
    """

    face: FaceModel
    origin: np.ndarray
    local: np.ndarray
    hair: np.ndarray
    depends: np.ndarray
    offsets: np.ndarray


def eye_mid(face: FaceModel) -> np.ndarray:
    """EyeMid: (2,) image midpoint of the eyeball centres 3.5 and 3.6 (2.3.2)."""
    return (face.point("3.5") + face.point("3.6")) / 2


def ear_width(face: FaceModel) -> float:
    """W_ear (Alg. 2.1 step 1) in pixels: the mean horizontal distance from EyeMid
    to where the ears meet the face at the bottom (10.8, 10.7), so A and B sit
    on the face side of the ears, where arc(10.8, 10.2, A) closes each ear."""
    mid = eye_mid(face)[0]
    return float((abs(face.point("10.8")[0] - mid) + abs(face.point("10.7")[0] - mid)) / 2)


def additional_map(face: FaceModel) -> tuple[np.ndarray, np.ndarray]:
    """Alg. 2.1 step 4 as an affine map: (depends (2N, 2P), offsets (N, 2)).

    For model points (P, 2), the image positions of LIFTED_NAMES are
    (depends @ points.ravel()).reshape(N, 2) + offsets; the model rows are
    the identity with zero offsets.
    """
    quantities = {"w_ear": ear_width(face), "eyebrow_h": face.fapu.eyebrow_h, "eyebrow_h2": face.fapu.eyebrow_h2}
    n, p = len(LIFTED_NAMES), len(POINT_NAMES)
    depends = np.zeros((n, 2, p, 2))
    offsets = np.zeros((n, 2))
    for axis in (0, 1):
        depends[np.arange(p), axis, np.arange(p), axis] = 1.0
    for row, name in enumerate(ADDITIONAL_NAMES, start=p):
        x_terms, y_terms, x_offset, y_offset = ADDITIONAL[name]
        for axis, terms, offset in ((0, x_terms, x_offset), (1, y_terms, y_offset)):
            for point, weight in terms:
                depends[row, axis, POINT_INDEX[point], axis] += weight
            if offset is not None:
                offsets[row, axis] = offset[0] * quantities[offset[1]]
    return depends.reshape(2 * n, 2 * p), offsets


def lifted_image_points(lifted: LiftedFace, points: np.ndarray) -> np.ndarray:
    """(N, 2) image positions of all lifted points for (P, 2) (displaced) model points."""
    return (lifted.depends @ points.ravel()).reshape(-1, 2) + lifted.offsets


def lift(face: FaceModel) -> LiftedFace:
    """Alg. 2.1: rotation origin, additional points, local 3D coordinates (Table 2.1)."""
    d = face.fapu.d
    mid = eye_mid(face)
    origin = np.array([mid[0], mid[1] + ORIGIN_BELOW_EYES * d])
    depends, offsets = additional_map(face)
    image = (depends @ face.points.ravel()).reshape(-1, 2) + offsets
    local = np.column_stack([
        image[:, 0] - origin[0],
        origin[1] - image[:, 1],
        np.array([DEPTH[name] for name in LIFTED_NAMES]) * d,
    ])
    hair = np.column_stack([
        face.hair[:, 0] - origin[0],
        origin[1] - face.hair[:, 1],
        np.full(len(face.hair), HAIR_DEPTH * d),
    ])
    return LiftedFace(face=face, origin=origin, local=local, hair=hair, depends=depends, offsets=offsets)
