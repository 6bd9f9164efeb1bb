"""Blink, smile (with squint) and eyebrow raise (thesis 002, 2.4.2) as data.

Each expression is a continuous amount 0..1 that moves some model points by
multiples of FAPUs (image y down: negative dy is up); the displacement is
linear in the amount, so expressions blend and interpolate. The thesis names
which points move and by which FAPU; the coefficients are ours (the figures
2.11-2.13 that showed them are missing) and docs/face-model.md lists them.
"""

from __future__ import annotations

import numpy as np

from cartoonface.face.model import POINT_INDEX, POINT_NAMES, FaceModel

EXPRESSIONS: tuple[str, ...] = ("blink", "smile", "brow")

Move = tuple[str, float, str, float, str]  # (point, dx coefficient, dx FAPU, dy coefficient, dy FAPU)

# Thesis 002, 2.4.2: blinking sets 3.2, 3.4, 3.1, 3.3 from LeftEyeH / RightEyeH.
# (lid, other lid, share): at blink 1 each lid has moved this share of the way
# to the other along the line between them (vertically: 0.8 LeftEyeH down for
# the upper lid, 0.2 up for the lower), so the lids meet, the eye outline
# collapses and the clipped eyeball is hidden.
UPPER_LID_SHARE = 0.8
BLINK: tuple[tuple[str, str, float], ...] = (
    ("3.2", "3.4", UPPER_LID_SHARE),
    ("3.4", "3.2", 1.0 - UPPER_LID_SHARE),
    ("3.1", "3.3", UPPER_LID_SHARE),
    ("3.3", "3.1", 1.0 - UPPER_LID_SHARE),
)
# Thesis 002, 2.4.2: smiling moves the mouth corners 8.4, 8.3 by UpperLipH and
# squints by moving the lower lids 3.4, 3.3 by LeftEyeH / RightEyeH.
SMILE: tuple[Move, ...] = (
    ("8.4", -1.0, "upper_lip_h", -1.5, "upper_lip_h"),
    ("8.3", 1.0, "upper_lip_h", -1.5, "upper_lip_h"),
    ("3.4", 0.0, "d", -0.3, "left_eye_h"),
    ("3.3", 0.0, "d", -0.3, "right_eye_h"),
)
# Thesis 002, 2.4.2: raising moves the 8 eyebrow points (the 4 additional
# eyebrow points F, G, H, I follow through Alg. 2.1) by EyebrowH; the inner
# and middle points rise most, the outer ends less, keeping the arch.
BROW: tuple[Move, ...] = (
    ("4.2", 0.0, "d", -1.0, "eyebrow_h"),
    ("4.1", 0.0, "d", -1.0, "eyebrow_h"),
    ("4.4", 0.0, "d", -1.0, "eyebrow_h"),
    ("4.3", 0.0, "d", -1.0, "eyebrow_h"),
    ("4.4a", 0.0, "d", -0.85, "eyebrow_h"),
    ("4.3a", 0.0, "d", -0.85, "eyebrow_h"),
    ("4.6", 0.0, "d", -0.6, "eyebrow_h"),
    ("4.5", 0.0, "d", -0.6, "eyebrow_h"),
)

# Upper / lower lid point indices, image-left eye then image-right eye.
UPPER_LIDS = np.array([POINT_INDEX["3.2"], POINT_INDEX["3.1"]])
LOWER_LIDS = np.array([POINT_INDEX["3.4"], POINT_INDEX["3.3"]])


def expression_displacements(face: FaceModel) -> np.ndarray:
    """(len(EXPRESSIONS), P, 2) image displacement of each model point at amount 1."""
    out = np.zeros((len(EXPRESSIONS), len(POINT_NAMES), 2))
    for lid, other, share in BLINK:
        out[0, POINT_INDEX[lid]] = share * (face.point(other) - face.point(lid))
    for k, table in ((1, SMILE), (2, BROW)):
        for point, dx, dx_unit, dy, dy_unit in table:
            out[k, POINT_INDEX[point]] = (dx * getattr(face.fapu, dx_unit), dy * getattr(face.fapu, dy_unit))
    return out


def close_lids(points: np.ndarray) -> None:
    """Stop each lower lid at its upper lid, in place, on (..., P, 2) image points.

    Blink and squint together would carry the lower lid past the upper one;
    the lids then meet where the upper lid is.
    """
    points[..., LOWER_LIDS, 1] = np.maximum(points[..., LOWER_LIDS, 1], points[..., UPPER_LIDS, 1])


def expression_points(face: FaceModel, blink: float = 0.0, smile: float = 0.0, brow: float = 0.0) -> np.ndarray:
    """(P, 2) model points with the given expression amounts (each 0..1) applied."""
    amounts = np.array([blink, smile, brow])
    points = face.points + np.tensordot(amounts, expression_displacements(face), axes=1)
    close_lids(points)
    return points
