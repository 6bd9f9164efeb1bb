"""The 12 basic Mandarin mouth shapes (thesis 002, 5.2.2) as data, and their use.

A shape moves the mouth control points 8.9 (up), 8.2 (dn), 8.4 (lf), 8.3 (rt)
from the neutral face; every offset is a multiple of one FAPU, so the table
holds for any face size. The other mouth points follow (see shape_displacements)
and the chin 2.1 follows 8.2 (thesis 5.2.2: 2.1 = 8.2 + JawH). Image y is down:
a negative dy moves a point up.
"""

from __future__ import annotations

import functools
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
    """One basic mouth shape as FAPU terms (image y down) and what the drawing shows.

    up: dy of 8.9; dn: dy of 8.2; inward: dx of each corner towards the mouth
    centre (8.4 moves +inward, 8.3 -inward; negative widens); corner_dy: dy of
    both corners, measured from their neutral y, or, when corner_at_mid, from
    the middle of the moved up and dn points (the thesis's (up.y + dn.y)/2).

    Our additions (the thesis's control points stay where it puts them):
    upper_lip / lower_lip: change of the upper / lower lip's thickness
    (positive thicker), made by moving the inner lip points 2.2 / 2.3 against
    8.9 / 8.2: lips stretched wide get thinner, protruded lips thicker. upper_teeth / lower_teeth: how much of each row of teeth shows in
    the opening (0..1 of render/mouth.py's full tooth height); tongue: how far
    the tongue rises (0 lying low, 1 its tip at the upper teeth); bite: the
    upper teeth resting on the lower lip (0..1, f).
    """

    up: Term = ZERO
    dn: Term = ZERO
    inward: Term = ZERO
    corner_dy: Term = ZERO
    corner_at_mid: bool = False
    upper_lip: Term = ZERO
    lower_lip: Term = ZERO
    upper_teeth: float = 0.0
    lower_teeth: float = 0.0
    tongue: float = 0.0
    bite: float = 0.0


# Thesis 002, 5.2.2 (m and f: 5.2.1, which 5.2.2 item 1 keeps): up, dn, inward
# and corner_dy. Choices where the text is garbled or ambiguous, and where we
# depart from it to make each shape read at a glance (docs/mouth.md):
# - 5.2.1's pixel offsets ("- 1", "- 3") are not used: 5.2.2 replaced them by
#   FAPU terms (0.1 x MNS0, UpperLipH/2), which we take as they stand.
# - a: the text says lf.x = 8.4.x + 0.8 x MW0, which would carry each corner
#   past the other; 5.2.1 has MW0/8. We take MW0/24 and open it further
#   (up 0.45, dn 1.5 MNS0 for the thesis's 0.3, 0.8; corners 0.25 MNS0 above
#   the middle for UpperLipH/3): a wide-open mouth with a real jaw drop (the
#   chin follows dn), clearly bigger than o, its upper edge flatter than its
#   lower; 'a' then changes >= 5 % of the figure from 'm' (issue 10, bench/mouth.py).
# - i: dn MNS0/6 -> 0.22 MNS0, so both rows of teeth show; o: inward 0.2 ->
#   0.14 MW0 and dn 0.65 -> 0.6 MNS0, round rather than a tall slot; u: up and
#   dn 0.3 -> 0.35 MNS0 with thicker lips, puckered; h: up -0.25 -> -0.3
#   MNS0, the upper lip raised, so it stays apart from the spread e (issue 10).
# - the lip thicknesses, teeth, tongue and bite are ours (MouthShape).
MOUTH_SHAPES: dict[str, MouthShape] = {
    # m (b p m): the neutral (rest) shape, lips shut
    "m": MouthShape(),
    # f: part of the lower lip hidden by the upper lip; the upper teeth rest on it
    "f": MouthShape(dn=(-0.5, "lower_lip_h"), bite=1.0),
    # h' (d t n l j q x): a narrow opening, the tongue tip near the teeth ridge
    "h'": MouthShape(up=(-0.25, "mns0"), dn=(0.3, "mns0"), corner_dy=(-0.1, "mns0"),
                     upper_teeth=1.0, lower_teeth=0.4, tongue=0.7),
    # h (g k h, e eng er): a medium oval, jaw further down than h', teeth apart
    "h": MouthShape(up=(-0.3, "mns0"), dn=(0.5, "mns0"), inward=(1 / 12, "mw0"), corner_dy=(0.1, "mns0"),
                    upper_teeth=0.5, tongue=0.45),
    # r (zh ch sh r): slightly rounded, protruded lips, teeth close together
    "r": MouthShape(up=(-0.25, "mns0"), dn=(0.25, "mns0"), inward=(0.15, "mw0"),
                    upper_lip=(0.06, "mns0"), lower_lip=(0.04, "mns0"), upper_teeth=1.0, lower_teeth=1.0),
    # z (z c s): teeth almost closed, both rows showing
    "z": MouthShape(up=(-0.15, "mns0"), dn=(0.15, "mns0"), upper_teeth=1.0, lower_teeth=1.0),
    # a: wide open and round, the jaw dropped, teeth and tongue showing
    "a": MouthShape(
        up=(-0.45, "mns0"), dn=(1.5, "mns0"), inward=(1 / 24, "mw0"),
        corner_dy=(-0.25, "mns0"), corner_at_mid=True, upper_teeth=1.0, lower_teeth=0.5,
    ),
    # i: spread lips, thinned, both rows of teeth nearly together
    "i": MouthShape(dn=(0.22, "mns0"), inward=(-1 / 12, "mw0"), corner_dy=(-0.5, "upper_lip_h"),
                    upper_lip=(-0.05, "mns0"), lower_lip=(-0.05, "mns0"), upper_teeth=1.0, lower_teeth=1.0),
    # u: small and puckered: corners well in, lips pushed out (thicker)
    "u": MouthShape(up=(-0.35, "mns0"), dn=(0.35, "mns0"), inward=(0.2, "mw0"),
                    upper_lip=(0.14, "mns0"), lower_lip=(0.14, "mns0")),
    # e: mid-spread, half open, the upper teeth and a low tongue showing
    "e": MouthShape(dn=(0.5, "mns0"), inward=(-1 / 12, "mw0"), corner_dy=(-0.5, "upper_lip_h"),
                    upper_lip=(-0.03, "mns0"), upper_teeth=1.0, lower_teeth=0.6, tongue=0.2),
    # o: round, corners in, lips a little pushed out
    "o": MouthShape(up=(-0.25, "mns0"), dn=(0.6, "mns0"), inward=(0.14, "mw0"), corner_at_mid=True,
                    upper_lip=(0.05, "mns0"), lower_lip=(0.05, "mns0"), upper_teeth=0.3, tongue=0.2),
    # n (en): open, the tongue tip up behind the upper teeth
    "n": MouthShape(up=(-0.3, "mns0"), dn=(0.4, "mns0"), corner_dy=(-1 / 3, "upper_lip_h"),
                    upper_teeth=1.0, lower_teeth=0.3, tongue=1.0),
}

# Our addition to 5.2.2 (the thesis moves only the chin 2.1 with 8.2): a real
# jaw opens by rotating about the ear, so the jaw corners 2.13 / 2.14, about
# half as far from the hinge as the chin, drop by this share of the chin's
# drop (0.6, a little over half, so the jaw contour visibly follows an open
# mouth: issue 10). Without it an open mouth pulls the chin (depth 1.33 d, Table 2.1) down
# alone and, with the head tilted down, the chin turns into a point.
JAW_CORNER_SHARE = 0.6

# Outer mouth contour in drawing order (Alg. 2.2 step 13) and the inner lips.
OUTER_LIP = ("8.4", "8.9", "8.1", "8.10", "8.3", "8.2")
INNER_LIP = ("8.4", "2.2", "8.3", "2.3")


def _px(face: FaceModel, term: Term) -> float:
    coefficient, unit = term
    return coefficient * getattr(face.fapu, unit)


def shape_displacements(face: FaceModel) -> np.ndarray:
    """Image displacement of every model point for each basic shape.

    Returns (len(MOUTH_SYMBOLS), P, 2) pixels in MOUTH_SYMBOLS / POINT_NAMES
    order; row m is all zeros. Besides the four control points: 8.1 rises
    with 8.9, the inner upper lip 2.2 too, less the shape's upper_lip; the peaks 8.9 / 8.10 also move inwards
    with the corners in proportion to their distance from the mouth centre
    (so a narrowing shape never carries a corner past a peak); 8.10 mirrors
    8.9; the chin 2.1 follows 8.2, the jaw corners by JAW_CORNER_SHARE of it; the inner lower lip 2.3 follows 8.2 (less
    lower_lip) but never rises above 2.2 (in f the lower lip tucks under the upper one).
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
        up, dn, inward, corner, upper_lip, lower_lip = (
            _px(face, t) for t in (shape.up, shape.dn, shape.inward, shape.corner_dy, shape.upper_lip,
                                   shape.lower_lip))
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
        d[i["2.2"], 1] = up + upper_lip
        d[i["8.2"], 1] = dn
        d[i["2.1"], 1] = dn
        d[i["2.13"], 1] = JAW_CORNER_SHARE * dn
        d[i["2.14"], 1] = JAW_CORNER_SHARE * dn
        lower = max(p[i["2.3"], 1] + dn - lower_lip, p[i["2.2"], 1] + up + upper_lip)
        d[i["2.3"], 1] = lower - p[i["2.3"], 1]
    return out


# What the drawing shows besides the points, per shape (MouthShape fields), in this order.
SHOWN = ("upper_teeth", "lower_teeth", "tongue", "bite")


@functools.lru_cache(maxsize=1)
def shown_parts() -> np.ndarray:
    """(len(MOUTH_SYMBOLS), len(SHOWN)) the SHOWN amounts of each basic shape (read-only); a mix
    of shapes shows its weights @ this table."""
    table = np.array([[getattr(MOUTH_SHAPES[s], name) for name in SHOWN] for s in MOUTH_SYMBOLS])
    table.flags.writeable = False
    return table


def mouth_weights(mouth: Sequence[tuple[str, float]]) -> np.ndarray:
    """(len(MOUTH_SYMBOLS),) weights from (symbol, weight) pairs (symbols already validated)."""
    weights = np.zeros(len(MOUTH_SYMBOLS))
    for symbol, weight in mouth:
        weights[MOUTH_INDEX[symbol]] += weight
    return weights


def mouth_points(face: FaceModel, mouth: Sequence[tuple[str, float]]) -> np.ndarray:
    """(P, 2) model points with the mouth set to a weighted mix of basic shapes."""
    return face.points + np.tensordot(mouth_weights(mouth), shape_displacements(face), axes=1)
