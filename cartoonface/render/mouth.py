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
- Teeth: two rows, bands drawn as strokes clipped by the opening, so only the inside shows:
  the upper one hangs from the level of 2.2 (up to TEETH d), the lower one stands on 2.3 (up
  to LOWER_TEETH d); each at most TEETH_OF_OPENING of the opening's height (a dark gap stays
  between them) and scaled by the shape's upper_teeth / lower_teeth; they span TEETH_SPAN of
  the opening's width, curve down in the middle (TEETH_SAG, the dental arch) and, where the
  corners lie above them (a spread or smiling mouth), rise towards the ends with them.
- Tongue: an ellipse at the bottom of the opening, raised with the shape's `tongue` until
  its top reaches the upper edge, taller and narrower (n: tongue tip behind the upper teeth).
- Bite (f): the upper teeth as a band of height up to BITE d under the line where the lips
  meet, over the lower lip (clipped by the lips' outline).
- The line where the lips meet is the opening's outline, stroked (render/svg.py).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cartoonface.face.lift import LIFTED_INDEX
from cartoonface.render.geometry import hypots
from cartoonface.render.numbers import distinct_rows, fill, rounded_tenths, template_frame, tenths_texts

# The posed points the mouth is drawn from, in this order (thesis 002, Alg. 2.2 step 13).
MOUTH_POINTS = ("8.4", "8.3", "8.9", "8.10", "8.1", "2.2", "2.3", "8.2")
ROWS = np.array([LIFTED_INDEX[name] for name in MOUTH_POINTS])

KAPPA = 4 * (math.sqrt(2) - 1) / 3  # Bezier arm of a quarter circle of radius 1 (0.5523)
SHUT = 0.005       # an opening less tall than this share of d is shut (a slanted mouth's 2.2 and 2.3
                   # of a shut model, side by side, lie a fraction of a pixel apart across it)
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
TONGUE_TIP = 0.5   # a raised tongue is this much narrower (its tip)
BITE = 0.05        # height of the upper teeth resting on the lower lip (f), share of d
BITE_OF_LIP = 0.8  # ... at most this share of the lower lip's thickness
BITE_SPAN = 0.7    # ... across this share of the teeth's span
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
    rows: (44, 2) the paths' rows in one array: lips, opening, upper and lower teeth, bite.
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
    rows: np.ndarray


Point = tuple[np.ndarray, np.ndarray]  # one point of each of S mouths in its frame: (S,) x and (S,) y pixels


def _row(middle: Point, half_width: np.ndarray, sag: np.ndarray, follow: float) -> list[Point]:
    """The 4 control points of the centre line of a row of teeth through `middle`, from
    `half_width` left of it to as far right, `sag` pixels lower at the middle than at the
    ends. Where the mouth's corners (at y 0) lie above `middle`, the ends rise by `follow`
    x that height, as the edge of a smiling opening does (`follow` includes the square of
    half_width / the opening's half width). Arrays (S,) of S mouths."""
    x, y = middle
    end = y + follow * np.minimum(-y, 0.0)
    dip = end + 4 * (sag + y - end) / 3  # a cubic's middle is 3/4 of the way to control points this low
    return [(x - half_width, end), (x - half_width / 3, dip), (x + half_width / 3, dip), (x + half_width, end)]


def _half(corner: Point, middle: Point, roundness: np.ndarray) -> list[Point]:
    """The 4 control points of a cubic from `corner` to `middle`, level at `middle`. At the
    corner it leaves between along the chord (roundness 0: a third of it) and straight up or
    down to `middle`'s height (roundness 1: an ellipse arm of KAPPA x the height); at
    `middle` its arm is KAPPA (ellipse) to a third (chord) of the x distance. Arrays (S,)."""
    (cx, cy), (mx, my) = corner, middle
    level = (roundness * KAPPA + (1 - roundness) / 3) * (cx - mx)
    first = (cx + (1 - roundness) * (mx - cx) / 3, cy + (1 - roundness) * (my - cy) / 3 + roundness * KAPPA * (my - cy))
    return [corner, first, (mx + level, my), middle]


def _edge(left: Point, middle: Point, right: Point, roundness: np.ndarray) -> list[Point]:
    """The 7 path rows (start, then 2 cubics) of an edge left -> middle -> right."""
    return _half(left, middle, roundness) + _half(right, middle, roundness)[2::-1]


def mouth_outlines(points: np.ndarray, shown: np.ndarray, d: float) -> MouthOutlines:
    """The drawn mouth from posed points.

    Takes `points` (8, 2) image pixels of MOUTH_POINTS, `shown` (4,) the amounts of
    face/mouth.py SHOWN (upper_teeth, lower_teeth, tongue, bite) of the mouth's mix of
    shapes, and `d` the FAPU d in pixels. Returns the MouthOutlines in image pixels
    (all_mouth_outlines of the one mouth).
    """
    return all_mouth_outlines(np.asarray(points, dtype=float)[None], np.asarray(shown, dtype=float)[None], d)[0]


def all_mouth_outlines(points: np.ndarray, shown: np.ndarray, d: float) -> list[MouthOutlines]:
    """mouth_outlines of S mouths (`points` (S, 8, 2), `shown` (S, 4)), from _drawn's arrays."""
    images, sizes = _drawn(points, shown, d)
    outlines = []
    for image, (upper_width, lower_width, bite_width, tongue_rx, tongue_ry, gloss_rx, gloss_ry) in zip(
            images, sizes.tolist(), strict=True):
        (tx, ty), (gx, gy) = image[-2:].tolist()
        outlines.append(MouthOutlines(
            lips=image[:19], opening=image[19:32],
            upper_teeth=image[32:36], upper_width=upper_width,
            lower_teeth=image[36:40], lower_width=lower_width,
            bite=image[40:44], bite_width=bite_width,
            tongue=(tx, ty, tongue_rx, tongue_ry),
            gloss=(gx, gy, gloss_rx, gloss_ry),
            rows=image[:44],
        ))
    return outlines


def _drawn(points: np.ndarray, shown: np.ndarray, d: float) -> tuple[np.ndarray, np.ndarray]:
    """S mouths (`points` (S, 8, 2) image pixels of MOUTH_POINTS, `shown` (S, 4) the SHOWN
    amounts, `d` the FAPU d) in image pixels: (S, 46, 2) the rows of MouthOutlines.rows, then
    the tongue's and the gloss's centres; (S, 7) the sizes (the rows' and the bite's widths,
    the tongue's and the gloss's radii). Each mouth built in its frame (_local), all turned into
    the image by one stacked product (each slice the product of one mouth)."""
    points, shown = np.asarray(points, dtype=float), np.asarray(shown, dtype=float)
    (lx, ly), (rx, ry) = points[:, 0].T, points[:, 1].T
    width = np.maximum(hypots(rx - lx, ry - ly), 1e-9)
    ex, ey = (rx - lx) / width, (ry - ly) / width  # x along the mouth; y = (-ey, ex), down the face
    ox, oy = (lx + rx) / 2, (ly + ry) / 2
    # the other points in the frame, (S, 6) x and y
    x, y = points[:, 2:, 0] - ox[:, None], points[:, 2:, 1] - oy[:, None]
    local, sizes = _local(x * ex[:, None] + y * ey[:, None], y * ex[:, None] - x * ey[:, None], width / 2,
                          shown.T, d)
    turns = np.stack([ex, ey, -ey, ex], axis=1).reshape(-1, 2, 2)
    return local @ turns + np.stack([ox, oy], axis=1)[:, None], sizes


def _local(x: np.ndarray, y: np.ndarray, half: np.ndarray, shown: np.ndarray,
           d: float) -> tuple[np.ndarray, np.ndarray]:
    """_drawn's S mouths in their frames (x from the corner 8.4 to 8.3, y down the face), from
    `x`, `y` (S, 6) of the points MOUTH_POINTS[2:] in the frame, `half` (S,) half the corners'
    distance, `shown` (4, S) the SHOWN amounts and the FAPU `d`: (S, 46, 2) the rows of the
    paths and the tongue's and gloss's centres, (S, 7) the sizes (as _drawn's)."""
    upper_teeth, lower_teeth, tongue, bite = shown
    zero = np.zeros_like(half)
    corner_l, corner_r = (-half, zero), (half, zero)
    peak_l, peak_r, bow, inner_up, inner_dn, bottom = zip(x.T, y.T, strict=True)

    height = inner_dn[1] - inner_up[1]
    # 2.3 on 2.2 (or above it) in the model: shut, whatever the mouth's slant
    shut = height < SHUT * d
    inner_dn = (np.where(shut, inner_up[0], inner_dn[0]), np.where(shut, inner_up[1], inner_dn[1]))
    height = np.where(shut, 0.0, height)
    inset = np.minimum(np.minimum(INSET * height, INSET_MAX * d), 0.5 * half)
    open_l, open_r = (inset - half, zero), (half - inset, zero)
    inner_half = half - inset
    roundness = np.minimum(height / (ROUND * 2 * inner_half), 1.0)
    opening = _edge(open_l, inner_up, open_r, roundness) + _edge(open_r, inner_dn, open_l, roundness)[1:]

    lip_round = np.maximum(LIP_ROUND, LIP_FOLLOWS * roundness)
    (px, py), (bx, by), (qx, qy) = peak_l, bow, peak_r
    left_bow, right_bow = BOW * (bx - px), BOW * (qx - bx)
    lips = (_half(corner_l, peak_l, lip_round) + [(px + left_bow, py), (bx - left_bow, by), bow,
                                                  (bx + right_bow, by), (qx - right_bow, qy)]
            + _half(corner_r, peak_r, lip_round)[::-1] + _edge(corner_r, bottom, corner_l, lip_round)[1:])

    row = TEETH_OF_OPENING * height
    upper_h = upper_teeth * np.minimum(TEETH * d, row)
    lower_h = lower_teeth * np.minimum(LOWER_TEETH * d, row)
    span = TEETH_SPAN * inner_half
    follow = TEETH_SPAN**2
    lower_lip = bottom[1] - inner_dn[1]
    bite_h = bite * np.minimum(BITE * d, BITE_OF_LIP * lower_lip)
    teeth = (_row(inner_up, span, TEETH_SAG * upper_h, follow)
             + _row(inner_dn, span, TEETH_SAG * lower_h, LOWER_FOLLOW * follow)
             + _row((inner_up[0], inner_up[1] + bite_h / 2), span * BITE_SPAN, TEETH_SAG * bite_h,
                    follow * BITE_SPAN**2))

    tongue_rx = TONGUE_WIDTH * 2 * inner_half * (1 - TONGUE_TIP * tongue)
    tongue_ry = TONGUE_HEIGHT * height * (1 + tongue)
    # at rest the tongue's top is a third of the way up the opening; raised, at its upper edge
    top = (1 - tongue) * (inner_dn[1] - height / 3) + tongue * inner_up[1]
    centres = [(inner_dn[0], top + tongue_ry), (0.45 * inner_dn[0] + 0.55 * bottom[0], 0.45 * inner_dn[1] + 0.55 * bottom[1])]

    rows = lips + opening + teeth + centres
    return (np.stack([coordinate for row in rows for coordinate in row], axis=1).reshape(len(half), -1, 2),
            np.stack([2 * upper_h, 2 * lower_h, bite_h, tongue_rx, tongue_ry, GLOSS * 2 * inner_half, 0.22 * lower_lip],
                     axis=1))


# The SVG texts of a drawn mouth, "|" between them, in TEXTS order: the path data of the
# lips and the opening (closed), the rows of teeth and the bite (one cubic each), in
# MouthOutlines.rows order, then single numbers.
TEXTS = ("lips", "opening", "upper_teeth", "lower_teeth", "bite", "upper_width", "lower_width", "bite_width",
         "tongue_cx", "tongue_cy", "tongue_rx", "tongue_ry", "gloss_cx", "gloss_cy", "gloss_rx", "gloss_ry")
_PATHS = ((6, "Z"), (4, "Z"), (1, ""), (1, ""), (1, ""))  # the path data's cubic pieces and close
_TEMPLATE = template_frame("|".join(["M%s %s" + "C%s %s %s %s %s %s" * pieces + close for pieces, close in _PATHS]
                                    + ["%s"] * 11))
# where each path data's numbers lie among a mouth's numbers (_texts: Tenths): its place in TEXTS, its slice
_PATH_ENDS = np.cumsum([2 + 6 * pieces for pieces, _ in _PATHS]).tolist()
_PATH_SLICES = tuple(zip(range(len(_PATHS)), [0, *_PATH_ENDS[:-1]], _PATH_ENDS))


def mouth_texts(outlines: MouthOutlines) -> dict[str, str]:
    """The SVG texts of `outlines` by the names in TEXTS: path data and positions to 0.1 px; the
    sizes (stroke widths, radii) in whole pixels, as the animation writer draws the paths: then
    mouths that differ by less than a pixel are written once, not once per tenth."""
    return all_mouth_texts([outlines])[0]


def all_mouth_texts(outlines: Sequence[MouthOutlines]) -> list[dict[str, str]]:
    """mouth_texts of each of `outlines`, every number written by one numbers.tenths_texts."""
    places = np.array([[*o.tongue[:2], *o.gloss[:2]] for o in outlines], dtype=float).reshape(-1, 2, 2)
    rows = np.array([o.rows for o in outlines], dtype=float).reshape(len(outlines), -1, 2)
    sizes = np.array([[o.upper_width, o.lower_width, o.bite_width, *o.tongue[2:], *o.gloss[2:]] for o in outlines],
                     dtype=float).reshape(-1, 7)
    texts, which = _texts(np.concatenate([rows, places], axis=1), sizes)
    return [dict(zip(TEXTS, texts[number], strict=True)) for number in which]


def drawn_mouth_texts(points: np.ndarray, shown: np.ndarray, d: float,
                      tenths: dict[str, np.ndarray] | None = None) -> tuple[list[tuple[str, ...]], list[int]]:
    """all_mouth_texts(all_mouth_outlines(points, shown, d)) without the MouthOutlines between,
    each distinct mouth written once: the texts of the distinct mouths among S (`points` (S, 8, 2),
    `shown` (S, 4)) straight from _drawn's arrays, each in TEXTS order (what render/svg.py draws a
    mouth from), in the order first seen, and each mouth's number among them (S). `tenths`: as _texts'."""
    return _texts(*_drawn(points, shown, d), tenths)


def _texts(images: np.ndarray, sizes: np.ndarray,
           tenths: dict[str, np.ndarray] | None = None) -> tuple[list[tuple[str, ...]], list[int]]:
    """The mouth_texts of the distinct mouths among S from _drawn's `images` (S, 46, 2) and `sizes`
    (S, 7) pixels, each in TEXTS order, those whose numbers written differ (a pose shown many times:
    ~a third fewer), in the order first seen, and each mouth's number among them (S). `tenths`, when
    given, gets the numbers of their path data as written (render/pathdata.py's Tenths)."""
    sizes = np.rint(sizes)
    places = images[:, 44:].reshape(-1, 4)
    numbers = np.concatenate([images[:, :44].reshape(len(images), -1), sizes[:, :3], places[:, :2], sizes[:, 3:5],
                              places[:, 2:], sizes[:, 5:]], axis=1)
    rounded, which = distinct_rows(rounded_tenths(numbers))
    texts = tenths_texts(rounded)
    count = numbers.shape[1]
    drawn = [tuple(fill(_TEMPLATE, texts[index * count:(index + 1) * count]).replace(" -", "-").split("|"))
             for index in range(len(rounded))]
    if tenths is not None:
        for place, start, end in _PATH_SLICES:
            tenths.update(zip([mouth[place] for mouth in drawn], rounded[:, start:end], strict=True))
    return drawn, which
