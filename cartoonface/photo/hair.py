"""The hair region, its outline and the hair and clothes colours from a photo.

MediaPipe's selfie segmentation (landmarks.py, `Landmarker.person`) finds the person
(hair, face and body) in a window around the face. Hair is the person minus the face
oval of the face mesh, minus skin-coloured pixels (ears, neck), minus the neck and
shoulders below the chin except hair of the crown's colour that hangs down (long hair),
kept where it hangs together with the hair on the crown; inside the face oval, hair of
that colour above the brows is a fringe. The hair colour is the median, in Lab, of the
pixels the segmentation is sure of.

The outline (thesis 002, Alg. 2.2 step 2: HAIR_POINTS points, drawn behind the face)
is the hair's own outline, read along rays from the middle of the face oval and turned with
the head's roll: the outer edge (the hair's silhouette) over the stretch of rays that
find hair round the crown, and back along the inner edge (the face oval on the sides,
the hairline or the fringe's edge over the forehead, taken a little under the drawn
face), so it stays off the face below the brows. docs/photo.md, "Hair".
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from cartoonface.face.model import HAIR_POINTS
from cartoonface.photo.landmarks_map import OVAL, eyes
from cartoonface.photo.palette import polygon_mask

# The window around the face box (its width w, height h): sideways, up, down.
WINDOW_SIDE, WINDOW_UP, WINDOW_DOWN = 0.9, 0.8, 0.7
# The window is segmented scaled to at most this many pixels a side (the selfie model
# itself looks at 256 x 256), at least MIN_SEGMENT_SIDE.
SEGMENT_SIDE = 256
MIN_SEGMENT_SIDE = 8
# Selfie segmentation confidence: a pixel over PERSON belongs to the person; over
# CONFIDENT it is sure enough to sample the hair colour from.
PERSON = 0.5
CONFIDENT = 0.8
# The head ellipse in face widths / heights: its centre this far above the middle of
# the face box, its half-axes. Above the mouth corners (mesh points 61 and 291) everything
# of the person inside it that is not skin is hair (the colour is sampled above the eyes);
# outside it only pixels of the hair's colour are (not a neighbour, not the clothes).
HEAD_RAISE = 0.15
HEAD_HALF_WIDTH, HEAD_HALF_HEIGHT = 0.8, 0.75
MOUTH_CORNERS = (61, 291)
# Holes in the hair (highlights of the skin's colour) up to this many pixels across are closed.
CLOSE_SIDE = 5
# Clothes are looked for from this many face heights below the chin.
CLOTHES_BELOW_CHIN = 0.1
# Lab distance (OpenCV 8-bit Lab) under which a pixel counts as skin / as the hair colour.
SKIN_DISTANCE = 22.0
HAIR_DISTANCE = 28.0
# Beside the face (in the head ellipse, between the eyes and the mouth corners) hair may
# differ from the crown's colour (in shadow) within this many face widths of the oval.
SIDE_REACH = 0.2
# Hair below the chin is followed down to this many face heights (long hair).
HAIR_BELOW_CHIN = 0.6
# A fringe stops this many d (eye distance) above the line through the brow arch tops
# (mesh points 105 and 334): the outline never reaches the brows.
BROW_TOPS = (105, 334)
BROW_CLEAR = 0.12
# Fewer hair pixels than this (in the window) are no hair: too few for a median.
MIN_HAIR_PIXELS = 30
# The outline is read off RAYS rays round the face, sampled every RAY_STEP pixels of the window.
RAYS = 72
RAY_STEP = 0.5
# A gap of this fraction of the face width ends a ray's run through the hair.
RAY_GAP = 0.05
# A ray finds hair when the hair reaches this many face widths beyond the face oval;
# it reaches at most MAX_HAIR face widths beyond it (a busy background or a neighbour's
# hair must not pull the outline away).
HAIR_BEYOND = 0.02
MAX_HAIR = 0.6
# Below the middle of the face hair must be this many face widths thick to count (a
# shadow along the jaw is not a lock of hair).
LOW_HAIR_BEYOND = 0.07
# Below the middle of the face, hair reaches beyond the face at most SYMMETRY times as
# far as at the mirrored ray: long hair hangs on both sides, a dark collar or background
# on one side only is not hair. On a head turned less than FRONTAL degrees the same holds
# above the middle, with SYMMETRY_SLACK face widths more (a neighbour's shoulder beside
# the crown is cut back; a parting's extra volume is kept in part).
SYMMETRY = 1.5
FRONTAL = 15.0
SYMMETRY_SLACK = 0.1
# The outline's points (HAIR_POINTS in all): INNER_SIDE on the inner edge each side of
# the top, the rest on the outer edge; the inner points sit at these shares of the way
# from the top of the head to the end of the hair on their side.
INNER_SIDE = 4
INNER_SHARES = (0.125, 0.375, 0.625, 0.875)
OUTER = HAIR_POINTS - 2 * INNER_SIDE
# The inner edge is pulled INSET face widths into the face, but never into the bare
# face (the oval below the line BROW_CLEAR above the brows): over the forehead the hair
# then reaches under the drawn face, so a head that turns or nods, moving the face over
# the hair, shows no gap between them. Where the bare face stops it (the sides), the
# inner points lie outside the oval by the sag of the chords between them (1 / cos of
# half their spacing), so the straight edges do not cut into the face.
INSET = 0.1
# The outline has a fringe where its inner edge comes this many face widths below the oval.
FRINGE_DIP = 0.06
# Where no hair is found round the crown (a bald head, hair of the background's colour),
# the outline is a cap this many degrees each side of the top, from INSIDE_FACE of the
# way to the face oval to the oval: hidden behind the drawn face.
CAP_HALF_ANGLE = 60.0
INSIDE_FACE = 0.9
# Angle of the ray straight up (degrees from straight down, through the image left).
TOP = 180.0


@dataclass(frozen=True)
class Head:
    """What the segmentation found, in photo pixels.

    polygon: (HAIR_POINTS, 2) the hair outline, drawing order (docs/photo.md, "Hair").
    hair: (3,) median RGB of the hair, None when no hair was found (bald or hidden).
    clothes: (3,) median RGB of the clothes below the chin, None when none is visible.
    fringe: whether hair covers the forehead FRINGE_DIP face widths or more below the
        top of the face oval.
    """

    polygon: np.ndarray
    hair: np.ndarray | None
    clothes: np.ndarray | None
    fringe: bool


def _lab(rgb: np.ndarray) -> np.ndarray:
    import cv2

    return cv2.cvtColor(np.ascontiguousarray(rgb, dtype=np.uint8), cv2.COLOR_RGB2LAB).astype(float)


def _rgb(lab: np.ndarray) -> np.ndarray:
    """(3,) RGB of a (3,) OpenCV 8-bit Lab colour."""
    import cv2

    pixel = np.clip(np.round(lab), 0, 255).astype(np.uint8).reshape(1, 1, 3)
    return cv2.cvtColor(pixel, cv2.COLOR_LAB2RGB)[0, 0].astype(float)


def _distance(lab: np.ndarray, colour: np.ndarray) -> np.ndarray:
    """Lab distance of every pixel of `lab` (..., 3) to the Lab `colour` (3,)."""
    return np.linalg.norm(lab - colour, axis=-1)


def segment_head(rgb: np.ndarray, mesh: np.ndarray, skin: np.ndarray, roll: float, turn: float,
                 person_of: Callable[[np.ndarray], np.ndarray]) -> Head:
    """The head of the face whose (478, 3) mesh is given, in the photo `rgb` (H, W, 3);
    `skin` the face's (3,) RGB skin colour; `roll` the head's lean in degrees (positive
    clockwise on screen), so the rays keep their places on the head; `turn` its turn
    in degrees (a frontal head's hair is taken to be symmetric-ish); `person_of` the
    segmentation: (h, w, 3) uint8 -> (h, w) confidence 0..1 of the person."""
    import cv2

    height, width = rgb.shape[:2]
    (x0, y0), (x1, y1) = mesh[:, :2].min(axis=0), mesh[:, :2].max(axis=0)
    w, h = x1 - x0, y1 - y0
    left, right = int(max(0, x0 - WINDOW_SIDE * w)), int(min(width, x1 + WINDOW_SIDE * w))
    top, bottom = int(max(0, y0 - WINDOW_UP * h)), int(min(height, y1 + WINDOW_DOWN * h))
    scale = min(1.0, SEGMENT_SIDE / max(right - left, bottom - top))
    size = (max(MIN_SEGMENT_SIDE, int(round((right - left) * scale))),
            max(MIN_SEGMENT_SIDE, int(round((bottom - top) * scale))))
    image = cv2.resize(np.ascontiguousarray(rgb[top:bottom, left:right]), size, interpolation=cv2.INTER_AREA)
    sw, sh = size
    to_window = np.array([left, top], float)
    window_mesh = (mesh[:, :2] - to_window) * scale
    face = polygon_mask((sh, sw), window_mesh[list(OVAL)])
    chin_y = (y1 - top) * scale
    ws, hs = w * scale, h * scale
    middle, d = eyes(mesh)
    eyes_y = (middle[1] - top) * scale
    rows, cols = np.mgrid[0:sh, 0:sw]
    (xa, ya), (xb, yb) = window_mesh[list(BROW_TOPS)]
    # in profile the brow tops can be one above the other: then the higher one, level
    slope, level = ((yb - ya) / (xb - xa), ya) if abs(xb - xa) >= 1.0 else (0.0, min(ya, yb))
    brow_line = level + (cols - xa) * slope - BROW_CLEAR * d * scale

    confidence = person_of(image)
    person = confidence > PERSON
    lab = _lab(image)
    skinlike = _distance(lab, _lab(np.asarray(skin).reshape(1, 1, 3))[0, 0]) < SKIN_DISTANCE
    head = np.zeros((sh, sw), np.uint8)
    cx, cy = ((x0 + x1) / 2 - left) * scale, ((y0 + y1) / 2 - top) * scale
    cv2.ellipse(head, (int(cx), int(cy - HEAD_RAISE * hs)), (int(HEAD_HALF_WIDTH * ws), int(HEAD_HALF_HEIGHT * hs)),
                0, 0, 360, 1, -1)  # not turned, the whole way round, value 1, filled
    candidates = person & ~face & ~skinlike
    mouth_y = window_mesh[list(MOUTH_CORNERS), 1].mean()
    sides = candidates & (rows < mouth_y) & head.astype(bool)
    crown = sides & (rows < eyes_y)
    hair_mask = np.zeros_like(face)
    hair = None
    hairlike = np.zeros_like(face)
    if crown.sum() >= MIN_HAIR_PIXELS:
        hairlike = _distance(lab, np.median(lab[crown], axis=0)) < HAIR_DISTANCE
        beside = cv2.distanceTransform((~face).astype(np.uint8), cv2.DIST_L2, 3) < SIDE_REACH * ws
        sides &= (rows < eyes_y) | beside | hairlike
        fringe_px = person & face & hairlike & ~skinlike & (rows < brow_line)
        hair_mask = sides | (candidates & hairlike & (rows < chin_y + HAIR_BELOW_CHIN * hs)) | fringe_px
        # keep the hair that hangs together with the hair on the crown
        _, labels = cv2.connectedComponents(hair_mask.astype(np.uint8), connectivity=8)
        keep = np.unique(labels[crown])
        hair_mask = np.isin(labels, keep[keep > 0])
        sure = hair_mask & (confidence > CONFIDENT)
        if sure.sum() >= MIN_HAIR_PIXELS:
            hair = _rgb(np.median(lab[sure], axis=0))
        else:
            hair_mask = np.zeros_like(face)
    clothes_px = person & ~skinlike & ~hairlike & ~face & (rows > chin_y + CLOTHES_BELOW_CHIN * hs)
    clothes = np.median(image[clothes_px], axis=0) if clothes_px.sum() >= MIN_HAIR_PIXELS else None

    closed = cv2.morphologyEx(hair_mask.astype(np.uint8), cv2.MORPH_CLOSE, np.ones((CLOSE_SIDE, CLOSE_SIDE), np.uint8))
    bare = face & (rows >= brow_line)
    hair_mask = closed.astype(bool) & ~bare
    # the skin of the head beyond the oval (a high forehead, the ears) joins face and hair
    _, labels = cv2.connectedComponents((face | (person & skinlike & (rows < chin_y))).astype(np.uint8))
    head_skin = np.isin(labels, np.unique(labels[face]))
    # the rays start at the middle of the face oval (not at the nose: on a turned head
    # the nose tip can lie outside the oval)
    centre = np.array([cols[face].mean(), rows[face].mean()])
    polygon, fringe = _outline(hair_mask, face, head_skin, bare, centre, roll, ws, abs(turn) < FRONTAL)
    return Head(polygon=polygon / scale + to_window, hair=hair, clothes=clothes, fringe=fringe)


def _outline(hair: np.ndarray, face: np.ndarray, skin: np.ndarray, bare: np.ndarray, centre: np.ndarray,
             roll: float, face_width: float, frontal: bool = True) -> tuple[np.ndarray, bool]:
    """The (HAIR_POINTS, 2) hair outline in window pixels from the (H, W) bool masks of the
    `hair`, the `face` oval, the head's `skin` (the oval and the skin joined to it) and the
    `bare` face the outline keeps off (below the brows; it holds `centre`), rays from
    `centre` (2,) turned by `roll` degrees; and whether a fringe covers the
    forehead (the inner edge dips below the oval's top). `frontal`: the head faces the
    camera, so its hair is held symmetric-ish above the middle of the face too."""
    angles = np.linspace(0.0, 360.0, RAYS, endpoint=False) + 180.0 / RAYS
    directions = _directions(angles, roll)
    gap = RAY_GAP * face_width
    face_reach = _runs(face, centre, directions, gap)[1]
    bare_reach = _runs(bare, centre, directions, gap)[1]
    start, end = _runs(hair, centre, directions, gap)
    silhouette = _runs(hair | skin, centre, directions, gap)[1]
    beyond = _median3(np.clip(silhouette - face_reach, 0.0, MAX_HAIR * face_width))
    mirrored = np.interp(360.0 - angles, angles, beyond, period=360.0)
    low = np.abs(angles - TOP) > 90.0  # rays pointing below the middle of the face
    beyond = np.where(low, np.minimum(beyond, SYMMETRY * mirrored), beyond)
    if frontal:
        beyond = np.minimum(beyond, SYMMETRY * mirrored + SYMMETRY_SLACK * face_width)
    outer = face_reach + beyond
    inner = _median3(np.minimum(np.where(end > 0, start, np.inf), face_reach))
    least = np.where(low, LOW_HAIR_BEYOND, HAIR_BEYOND) * face_width
    hair_out = (end > face_reach + least) & (beyond > least)
    found = _median3((hair_out | (inner < face_reach)).astype(float)) > 0
    top = int(np.argmin(np.abs(angles - TOP)))
    seeds = [ray for ray in (top, top + 1) if found[ray]]
    if seeds:
        lo = hi = seeds[0]
        while lo > 0 and found[lo - 1]:
            lo -= 1
        while hi < RAYS - 1 and found[hi + 1]:
            hi += 1
        first, last = angles[lo], angles[hi]
        fringe = bool(np.any(inner[lo:hi + 1] < face_reach[lo:hi + 1] - FRINGE_DIP * face_width))
    else:
        first, last = TOP - CAP_HALF_ANGLE, TOP + CAP_HALF_ANGLE
        outer, inner, fringe = face_reach, INSIDE_FACE * face_reach, False
    shares = np.array(INNER_SHARES)
    inner_left = TOP - (TOP - first) * shares
    inner_right = (TOP + (last - TOP) * shares)[::-1]
    outer_angles = np.linspace(first, last, OUTER)
    spacing = np.diff(shares[:2])[0]

    def inner_radii(at: np.ndarray, spread: float) -> np.ndarray:
        reach = np.maximum(np.interp(at, angles, bare_reach), np.interp(at, angles, inner) - INSET * face_width)
        stopped = reach >= np.interp(at, angles, face_reach) - RAY_STEP
        return np.where(stopped, reach / np.cos(np.radians(spread * spacing / 2)), reach)

    radii = np.concatenate([inner_radii(inner_left, TOP - first), np.interp(outer_angles, angles, outer),
                            inner_radii(inner_right, last - TOP)])
    points = np.concatenate([inner_left, outer_angles, inner_right])
    return centre + radii[:, None] * _directions(points, roll), fringe


def _median3(values: np.ndarray) -> np.ndarray:
    """(R,) each value replaced by the median of it and its two neighbours on the ray
    circle (no ray may spike past both of its neighbours)."""
    return np.median(np.stack([np.roll(values, 1), values, np.roll(values, -1)]), axis=0)


def _directions(angles: np.ndarray, roll: float) -> np.ndarray:
    """(R, 2) unit ray directions at `angles` (R,) degrees from straight down, turning
    through the image left, over the top, to the image right (the drawing order of the
    sample faces' hair), turned by `roll` degrees (positive clockwise on screen)."""
    radians = np.radians(np.asarray(angles, float) + roll)
    return np.column_stack([-np.sin(radians), np.cos(radians)])


def _runs(mask: np.ndarray, centre: np.ndarray, directions: np.ndarray, gap: float) -> tuple[np.ndarray, np.ndarray]:
    """((R,), (R,)) where each ray from `centre` along `directions` (R, 2) first meets the
    mask and where its run through the mask ends: its last mask pixel before the first
    stretch of more than `gap` pixels outside the mask (pixels; both 0 when the ray
    never meets the mask)."""
    sh, sw = mask.shape
    steps = np.arange(0.0, float(np.hypot(sh, sw)), RAY_STEP)
    xy = centre + steps[None, :, None] * directions[:, None, :]
    inside = (xy[..., 0] >= 0) & (xy[..., 0] <= sw - 1) & (xy[..., 1] >= 0) & (xy[..., 1] <= sh - 1)
    px = np.clip(np.round(xy).astype(int), 0, [sw - 1, sh - 1])
    hits = mask[px[..., 1], px[..., 0]] & inside
    starts, ends = np.zeros(len(directions)), np.zeros(len(directions))
    for ray, row in enumerate(hits):
        index = np.nonzero(row)[0]
        if not len(index):
            continue
        breaks = np.nonzero(np.diff(index) * RAY_STEP > gap)[0]
        starts[ray] = steps[index[0]]
        ends[ray] = steps[index[breaks[0]] if len(breaks) else index[-1]]
    return starts, ends
