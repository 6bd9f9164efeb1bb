"""The 12 basic Mandarin mouth shapes (thesis 002, 5.2.2) as data, and their use.

A shape moves the mouth control points 8.9 (up), 8.2 (dn), 8.4 (lf), 8.3 (rt)
from the neutral face; every offset is a multiple of one FAPU, so the table
holds for any face size. The other mouth points follow (see shape_displacements)
and the chin 2.1 follows 8.2 (thesis 5.2.2: 2.1 = 8.2 + JawH). Image y is down:
a negative dy moves a point up.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cartoonface.face.model import POINT_INDEX, POINT_NAMES, FaceModel

# Thesis 002, Table 5.5 / 5.6 and 5.2.2: initials m f h' h r z, finals a i u e o n.
MOUTH_SYMBOLS: tuple[str, ...] = ("m", "f", "h'", "h", "r", "z", "a", "i", "u", "e", "o", "n")
MOUTH_INDEX: dict[str, int] = {s: i for i, s in enumerate(MOUTH_SYMBOLS)}

Term = tuple[float, str]  # (coefficient, FAPU field name): coefficient x that FAPU in pixels
ZERO: Term = (0.0, "mns0")


@dataclass(frozen=True)
class MouthShape:
    """One basic mouth shape as FAPU terms (image y down).

    up: dy of 8.9; dn: dy of 8.2; inward: dx of each corner towards the mouth
    centre (8.4 moves +inward, 8.3 -inward; negative widens); corner_dy: dy of
    both corners, measured from their neutral y, or, when corner_at_mid, from
    the middle of the moved up and dn points (the thesis's (up.y + dn.y)/2).
    """

    up: Term = ZERO
    dn: Term = ZERO
    inward: Term = ZERO
    corner_dy: Term = ZERO
    corner_at_mid: bool = False


# Thesis 002, 5.2.2 (m and f: 5.2.1, which 5.2.2 item 1 keeps). Choices where
# the text is garbled or ambiguous (docs/face-model.md, "Mouth shapes"):
# - a: the text says lf.x = 8.4.x + 0.8 x MW0, which would carry each corner
#   past the other; we use MW0/8, the value of the same shape in 5.2.1, whose
#   up/dn terms 5.2.2 repeats unchanged.
# - 5.2.1's pixel offsets ("- 1", "- 3") are not used: 5.2.2 replaced them by
#   FAPU terms (0.1 x MNS0, UpperLipH/2), which we take as they stand.
MOUTH_SHAPES: dict[str, MouthShape] = {
    # m: the neutral (rest) shape
    "m": MouthShape(),
    # f: part of the lower lip hidden by the upper lip
    "f": MouthShape(dn=(-0.5, "lower_lip_h")),
    "h'": MouthShape(up=(-0.25, "mns0"), dn=(0.3, "mns0"), corner_dy=(-0.1, "mns0")),
    "h": MouthShape(up=(-0.25, "mns0"), dn=(0.5, "mns0"), inward=(1 / 12, "mw0"), corner_dy=(0.1, "mns0")),
    "r": MouthShape(up=(-0.25, "mns0"), dn=(0.25, "mns0"), inward=(0.15, "mw0")),
    "z": MouthShape(up=(-0.15, "mns0"), dn=(0.15, "mns0")),
    "a": MouthShape(
        up=(-0.3, "mns0"), dn=(0.8, "mns0"), inward=(1 / 8, "mw0"),
        corner_dy=(-1 / 3, "upper_lip_h"), corner_at_mid=True,
    ),
    "i": MouthShape(dn=(1 / 6, "mns0"), inward=(-1 / 12, "mw0"), corner_dy=(-0.5, "upper_lip_h")),
    "u": MouthShape(up=(-0.3, "mns0"), dn=(0.3, "mns0"), inward=(0.2, "mw0")),
    "e": MouthShape(dn=(0.5, "mns0"), inward=(-1 / 12, "mw0"), corner_dy=(-0.5, "upper_lip_h")),
    "o": MouthShape(up=(-0.25, "mns0"), dn=(0.65, "mns0"), inward=(0.2, "mw0"), corner_at_mid=True),
    "n": MouthShape(up=(-0.3, "mns0"), dn=(0.4, "mns0"), corner_dy=(-1 / 3, "upper_lip_h")),
}

# Our addition to 5.2.2 (the thesis moves only the chin 2.1 with 8.2): a real
# jaw opens by rotating about the ear, so the jaw corners 2.13 / 2.14, about
# half as far from the hinge as the chin, drop by this share of the chin's
# drop. Without it an open mouth pulls the chin (depth 1.33 d, Table 2.1) down
# alone and, with the head tilted down, the chin turns into a point.
JAW_CORNER_SHARE = 0.5

# Outer mouth contour in drawing order (Alg. 2.2 step 13) and the inner lips.
OUTER_LIP = ("8.4", "8.9", "8.1", "8.10", "8.3", "8.2")
INNER_LIP = ("8.4", "2.2", "8.3", "2.3")


def _px(face: FaceModel, term: Term) -> float:
    coefficient, unit = term
    return coefficient * getattr(face.fapu, unit)


def shape_displacements(face: FaceModel) -> np.ndarray:
    """Image displacement of every model point for each basic shape.

    Returns (len(MOUTH_SYMBOLS), P, 2) pixels in MOUTH_SYMBOLS / POINT_NAMES
    order; row m is all zeros. Besides the four control points: 8.1 and the
    inner upper lip 2.2 rise with 8.9; the peaks 8.9 / 8.10 also move inwards
    with the corners in proportion to their distance from the mouth centre
    (so a narrowing shape never carries a corner past a peak); 8.10 mirrors
    8.9; the chin 2.1 follows 8.2, the jaw corners by JAW_CORNER_SHARE of it; the inner lower lip 2.3 follows 8.2 but
    never rises above 2.2 (in f the lower lip tucks under the upper one).
    """
    i = POINT_INDEX
    p = face.points
    centre = (p[i["8.4"], 0] + p[i["8.3"], 0]) / 2
    half = (p[i["8.3"], 0] - p[i["8.4"], 0]) / 2
    frac_89 = float(np.clip((centre - p[i["8.9"], 0]) / half, 0, 1))
    frac_810 = float(np.clip((p[i["8.10"], 0] - centre) / half, 0, 1))
    out = np.zeros((len(MOUTH_SYMBOLS), len(POINT_NAMES), 2))
    for k, symbol in enumerate(MOUTH_SYMBOLS):
        shape = MOUTH_SHAPES[symbol]
        up, dn, inward, corner = (_px(face, t) for t in (shape.up, shape.dn, shape.inward, shape.corner_dy))
        d = out[k]
        if shape.corner_at_mid:
            mid = (p[i["8.9"], 1] + up + p[i["8.2"], 1] + dn) / 2 + corner
            d[i["8.4"]] = (inward, mid - p[i["8.4"], 1])
            d[i["8.3"]] = (-inward, mid - p[i["8.3"], 1])
        else:
            d[i["8.4"]] = (inward, corner)
            d[i["8.3"]] = (-inward, corner)
        d[i["8.9"]] = (inward * frac_89, up)
        d[i["8.10"]] = (-inward * frac_810, up)
        d[i["8.1"], 1] = up
        d[i["2.2"], 1] = up
        d[i["8.2"], 1] = dn
        d[i["2.1"], 1] = dn
        d[i["2.13"], 1] = JAW_CORNER_SHARE * dn
        d[i["2.14"], 1] = JAW_CORNER_SHARE * dn
        lower = max(p[i["2.3"], 1] + dn, p[i["2.2"], 1] + up)
        d[i["2.3"], 1] = lower - p[i["2.3"], 1]
    return out


def mouth_weights(mouth: Sequence[tuple[str, float]]) -> np.ndarray:
    """(len(MOUTH_SYMBOLS),) weights from (symbol, weight) pairs (symbols already validated)."""
    weights = np.zeros(len(MOUTH_SYMBOLS))
    for symbol, weight in mouth:
        weights[MOUTH_INDEX[symbol]] += weight
    return weights


def mouth_points(face: FaceModel, mouth: Sequence[tuple[str, float]]) -> np.ndarray:
    """(P, 2) model points with the mouth set to a weighted mix of basic shapes."""
    return face.points + np.tensordot(mouth_weights(mouth), shape_displacements(face), axes=1)
