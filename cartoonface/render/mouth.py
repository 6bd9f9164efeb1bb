"""The drawn mouth: outlines of the lips, the opening, the teeth and the tongue from posed points.

Thesis 002, Alg. 2.2 step 13 draws the lips as arc(8.1, 8.9, 8.4), arc(8.4, 8.2, 8.3),
arc(8.3, 8.10, 8.1) and the opening as arc(R, 2.2, S), arc(S, 2.3, R), with R, S the mouth
corners. Drawn that way an open mouth is a diamond with beak points at the corners. We keep
the points (every outline passes through the thesis's points) but shape the curves between
them as a cartoonist would (docs/mouth.md):

- A frame along the mouth: x from the corner 8.4 to 8.3, y perpendicular (down the face).
  All curves are cubic Bezier pieces built in that frame, so a turned or rolled head draws
  the same mouth, turned.
- Opening: its corners sit inside the lip corners (by INSET of its height, at most
  INSET_MAX d), so the lips wrap round them. From each corner the upper edge runs to the
  inner upper lip 2.2 and on to the other corner, the lower edge through 2.3, each with a
  level tangent at 2.2 / 2.3. The tangent at a corner turns from the chord (a slit, pointed
  ends) towards the perpendicular (an ellipse) as the opening gets taller for its width:
  `roundness` = height / (ROUND x width), clipped to 0..1. A quarter ellipse has arms of
  KAPPA times its half axes.
- Lips: 8.4 -> 8.9 -> 8.1 -> 8.10 -> 8.3 along the top, 8.3 -> 8.2 -> 8.4 along the
  bottom; level tangents at the peaks 8.9 / 8.10, the Cupid's bow 8.1 and 8.2; at the
  corners the same turn towards the perpendicular, never below LIP_ROUND, so the corners are
  round, not pointed.
- Teeth: the upper row a band of height up to TEETH d along the middle of the upper edge of
  the opening, the lower row (up to LOWER_TEETH d) along the lower edge, each at most
  TEETH_OF_OPENING of the opening's height and scaled by the shape's upper_teeth /
  lower_teeth; drawn as strokes clipped by the opening, so only the inside shows.
- Tongue: an ellipse at the bottom of the opening, raised with the shape's `tongue` until
  its top reaches the upper edge, taller and narrower (n: tongue tip behind the upper teeth).
- Bite (f): the upper teeth as a band of height up to BITE d under the line where the lips
  meet, over the lower lip (clipped by the lips' outline).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cartoonface.face.lift import LIFTED_INDEX
from cartoonface.render.geometry import number_texts

# The posed points the mouth is drawn from, in this order (thesis 002, Alg. 2.2 step 13).
MOUTH_POINTS = ("8.4", "8.3", "8.9", "8.10", "8.1", "2.2", "2.3", "8.2")
ROWS = [LIFTED_INDEX[name] for name in MOUTH_POINTS]

KAPPA = 4 * (math.sqrt(2) - 1) / 3  # Bezier arm of a quarter circle of radius 1 (0.5523)
ROUND = 0.55       # an opening this tall for its width has fully round (elliptic) corners
INSET = 0.1        # the opening's corners inside the lip corners, share of its height ...
INSET_MAX = 0.03   # ... at most this share of the FAPU d
LIP_ROUND = 0.5    # the lips' corners are at least this round (0: pointed, 1: a half circle) ...
LIP_FOLLOWS = 0.8  # ... and as round as this share of the opening's roundness
BOW = 0.4          # Bezier arm between a peak 8.9 / 8.10 and the Cupid's bow 8.1, share of their distance
TEETH = 0.075      # full height of the upper teeth showing, share of d
LOWER_TEETH = 0.055  # ... of the lower teeth
TEETH_OF_OPENING = 0.46  # a row of teeth at most this share of the opening's height
TEETH_SPAN = 0.9  # the rows of teeth span this share of the opening's width
TEETH_SAG = 0.3   # the rows curve down in the middle (the dental arch) by this share of their height
LOWER_FOLLOW = 0.3  # the lower row follows the rise of the corners this much less than the upper
TONGUE_WIDTH = 0.34  # tongue half-width, share of the opening's width
TONGUE_HEIGHT = 0.32  # tongue half-height, share of the opening's height, doubled when raised
TONGUE_TIP = 0.35  # a raised tongue is this much narrower (its tip)
BITE = 0.05        # height of the upper teeth resting on the lower lip (f), share of d
BITE_OF_LIP = 0.5  # ... at most this share of the lower lip's thickness
BITE_SPAN = 0.6    # ... across this share of the teeth's span
GLOSS = 0.14       # half-width of the gloss on the lower lip, share of the opening's width


@dataclass(frozen=True)
class MouthOutlines:
    """A drawn mouth in image pixels. A path is (1 + 3k, 2): its start point, then k cubic
    Bezier pieces (first control, second control, end).

    lips: closed outer outline from 8.4 over the top and back under the bottom (6 pieces).
    opening: closed, from the left inner corner along the upper edge and back along the
        lower edge (4 pieces); it clips the teeth and the tongue; its upper edge (the first
        2 pieces) is where the lips meet.
    upper_teeth, lower_teeth: centre lines (1 piece) of the rows, with their stroke widths
        (twice the height that shows inside the opening); width 0 when a row is hidden.
    tongue: (cx, cy, rx, ry): an ellipse, level in the image (it shows through the opening
        only, where a turn of the head's small angles does not show); ry 0 when shut.
    bite: centre line (1 piece) and width of the teeth on the lower lip (0 when none).
    gloss: (cx, cy, rx, ry) the highlight on the lower lip.
    """

    lips: np.ndarray
    opening: np.ndarray
    upper_teeth: np.ndarray
    upper_width: float
    lower_teeth: np.ndarray
    lower_width: float
    tongue: tuple[float, float, float, float]
    bite: np.ndarray
    bite_width: float
    gloss: tuple[float, float, float, float]


def _row(middle: np.ndarray, half_width: float, sag: float, follow: float) -> np.ndarray:
    """(4, 2) the centre line of a row of teeth through `middle` (local (2,)), from
    `half_width` left of it to as far right, `sag` pixels lower at the middle than at the
    ends. Where the mouth's corners (at local y 0) lie above `middle`, the ends rise by
    `follow` x that height x (half_width / the opening's half width)**2, as the edge of a
    smiling opening does (`follow` already includes the square)."""
    x, y = middle
    end = y + follow * min(-y, 0.0)
    dip = 4 * (sag + y - end) / 3  # a cubic's middle is 3/4 of the way to control points set this low
    return np.array([[x - half_width, end], [x - half_width / 3, end + dip], [x + half_width / 3, end + dip],
                     [x + half_width, end]])


def _corner_arm(corner: np.ndarray, towards: np.ndarray, rise: float, roundness: float) -> np.ndarray:
    """First control point leaving a corner (local (2,)) for a piece to `towards`: between the
    third of the chord (roundness 0) and an ellipse arm of KAPPA x `rise` straight up or down
    the y axis (roundness 1)."""
    return corner + (1 - roundness) * (towards - corner) / 3 + roundness * np.array([0.0, KAPPA * rise])


def _level_arm(point: np.ndarray, other: np.ndarray, roundness: float) -> np.ndarray:
    """Control point next to `point` (local (2,)), on a level tangent towards `other`'s x:
    KAPPA of the x distance for an ellipse, a third of it for a slit."""
    arm = (roundness * KAPPA + (1 - roundness) / 3) * (other[0] - point[0])
    return point + np.array([arm, 0.0])


def _half(corner: np.ndarray, middle: np.ndarray, rise: float, roundness: float) -> np.ndarray:
    """(4, 2) one cubic from `corner` to `middle` (level there), turning at the corner by
    `roundness` (see _corner_arm)."""
    return np.array([corner, _corner_arm(corner, middle, rise, roundness), _level_arm(middle, corner, roundness),
                     middle])


def _edge(left: np.ndarray, middle: np.ndarray, right: np.ndarray, roundness: float) -> np.ndarray:
    """(2, 4, 2) the two cubics left -> middle -> right of an edge through `middle`, which lies
    `middle[1] - corner y` below (or, negative, above) the corners."""
    first = _half(left, middle, middle[1] - left[1], roundness)
    second = _half(right, middle, middle[1] - right[1], roundness)[::-1]
    return np.array([first, second])


def _path(cubics: np.ndarray) -> np.ndarray:
    """(1 + 3k, 2) path rows from (k, 4, 2) joined cubics."""
    return np.concatenate([cubics[0, :1], cubics[:, 1:].reshape(-1, 2)])


def mouth_outlines(points: np.ndarray, shown: np.ndarray, d: float) -> MouthOutlines:
    """The drawn mouth from posed points.

    Takes `points` (8, 2) image pixels of MOUTH_POINTS, `shown` (4,) the amounts of
    face/mouth.py SHOWN (upper_teeth, lower_teeth, tongue, bite) of the mouth's mix of
    shapes, and `d` the FAPU d in pixels. Returns the MouthOutlines in image pixels.
    """
    upper_teeth, lower_teeth, tongue, bite = (float(v) for v in shown)
    left, right = points[0], points[1]
    width = max(float(np.hypot(*(right - left))), 1e-9)
    ex, ey = (right - left) / width
    axes = np.array([[ex, ey], [-ey, ex]])  # rows: x along the mouth, y down the face
    centre = (left + right) / 2
    local = (points - centre) @ axes.T
    corner_l, corner_r, peak_l, peak_r, bow, inner_up, inner_dn, bottom = local

    height = max(float(inner_dn[1] - inner_up[1]), 0.0)
    inset = min(INSET * height, INSET_MAX * d, 0.25 * width)
    open_l, open_r = corner_l + (inset, 0.0), corner_r - (inset, 0.0)
    inner_width = open_r[0] - open_l[0]
    roundness = min(height / (ROUND * inner_width), 1.0)
    upper = _edge(open_l, inner_up, open_r, roundness)
    lower = _edge(open_r, inner_dn, open_l, roundness)
    opening = np.concatenate([upper, lower])

    lip_round = max(LIP_ROUND, LIP_FOLLOWS * roundness)
    upper_lip = np.array([
        _half(corner_l, peak_l, peak_l[1], lip_round),
        [peak_l, peak_l + (BOW * (bow[0] - peak_l[0]), 0.0), bow - (BOW * (bow[0] - peak_l[0]), 0.0), bow],
        [bow, bow + (BOW * (peak_r[0] - bow[0]), 0.0), peak_r - (BOW * (peak_r[0] - bow[0]), 0.0), peak_r],
        _half(corner_r, peak_r, peak_r[1], lip_round)[::-1],
    ])
    lips = np.concatenate([upper_lip, _edge(corner_r, bottom, corner_l, lip_round)])

    row = TEETH_OF_OPENING * height
    upper_h = upper_teeth * min(TEETH * d, row)
    lower_h = lower_teeth * min(LOWER_TEETH * d, row)
    span = TEETH_SPAN * inner_width / 2
    follow = TEETH_SPAN**2
    teeth_up = _row(inner_up, span, TEETH_SAG * upper_h, follow)
    teeth_dn = _row(inner_dn, span, TEETH_SAG * lower_h, LOWER_FOLLOW * follow)
    bite_h = bite * min(BITE * d, BITE_OF_LIP * float(bottom[1] - inner_dn[1]))
    bite_line = _row(inner_up + (0.0, bite_h / 2), span * BITE_SPAN, TEETH_SAG * bite_h, follow * BITE_SPAN**2)

    tongue_rx = TONGUE_WIDTH * inner_width * (1 - TONGUE_TIP * tongue)
    tongue_ry = TONGUE_HEIGHT * height * (1 + tongue)
    # at rest the tongue's top is a third of the way up the opening; raised, at its upper edge
    top = (1 - tongue) * (inner_dn[1] - height / 3) + tongue * inner_up[1]
    tongue_c = np.array([inner_dn[0], top + tongue_ry])

    gloss_c = 0.45 * inner_dn + 0.55 * bottom

    def image(rows: np.ndarray) -> np.ndarray:
        return centre + rows @ axes

    tongue_xy = image(tongue_c)
    gloss_xy = image(gloss_c)
    return MouthOutlines(
        lips=image(_path(lips)),
        opening=image(_path(opening)),
        upper_teeth=image(teeth_up),
        upper_width=2 * upper_h,
        lower_teeth=image(teeth_dn),
        lower_width=2 * lower_h,
        tongue=(float(tongue_xy[0]), float(tongue_xy[1]), float(tongue_rx), float(tongue_ry)),
        bite=image(bite_line),
        bite_width=bite_h,
        gloss=(float(gloss_xy[0]), float(gloss_xy[1]), GLOSS * inner_width,
               0.22 * float(bottom[1] - inner_dn[1])),
    )


# Path templates: a start point, then cubic pieces.
_CUBICS = {k: "M%s %s" + "C%s %s %s %s %s %s" * k for k in (1, 2, 4, 6)}


def _text(template: str, rows: np.ndarray) -> str:
    """`template` filled with `rows` (n, 2) pixels as SVG numbers (0.1 px)."""
    return (template % number_texts(rows)).replace(" -", "-")


def mouth_paths(outlines: MouthOutlines) -> dict[str, str]:
    """SVG path data of `outlines`: {"lips", "opening", "upper_teeth", "lower_teeth", "bite"};
    closed outlines end in Z."""
    return {
        "lips": _text(_CUBICS[6], outlines.lips) + "Z",
        "opening": _text(_CUBICS[4], outlines.opening) + "Z",
        "upper_teeth": _text(_CUBICS[1], outlines.upper_teeth),
        "lower_teeth": _text(_CUBICS[1], outlines.lower_teeth),
        "bite": _text(_CUBICS[1], outlines.bite),
    }
