"""The hair polygon and the hair and clothes colours from a photo: GrabCut on the head.

GrabCut (OpenCV) separates the person from the background in a window around the
face, seeded by the face mesh (sure foreground), a head-shaped ellipse and the body
below the chin (probable foreground) and the window's edges (sure background). Hair
is the foreground that is not skin-coloured; below the eyes only pixels of the hair's
own colour count (down to below the chin, for long hair), so collars and clothes are
left out. The hair polygon is the outer
silhouette of hair and face, read along HAIR_POINTS rays from the middle of the face
(thesis 002, Alg. 2.2 step 2: a polygon of 23 points drawn behind the face).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cartoonface.face.model import HAIR_POINTS
from cartoonface.photo.landmarks_map import OVAL, eyes
from cartoonface.photo.palette import WHITE, polygon_mask

# The window around the face box (its width w, height h): sideways, up, down.
WINDOW_SIDE, WINDOW_UP, WINDOW_DOWN = 0.9, 0.8, 0.7
# GrabCut runs on the window scaled to at most this many pixels a side (at least
# MIN_SEGMENT_SIDE), for this many iterations.
SEGMENT_SIDE = 200
MIN_SEGMENT_SIDE = 8
GRABCUT_ITERATIONS = 4
# GrabCut's colour model arrays: OpenCV's fixed size (5 Gaussians x 13 values).
GMM_VALUES = 65
# GrabCut's rectangle, unused when it starts from a mask.
NO_RECT = (0, 0, 0, 0)
# The head ellipse (probable foreground) in face widths / heights: its centre this far
# above the middle of the face box, its half-axes.
HEAD_RAISE = 0.15
HEAD_HALF_WIDTH, HEAD_HALF_HEIGHT = 0.8, 0.75
# The body below the chin (probable foreground): this many face widths each side of the middle.
BODY_HALF_WIDTH = 0.7
# The sure-background band along the window's edges: the window width over EDGE_BAND_PARTS,
# at least MIN_EDGE_BAND pixels.
EDGE_BAND_PARTS = 50
MIN_EDGE_BAND = 2
# Kernel sides (pixels): the face mask is eroded by FACE_ERODE (sure foreground stays
# inside the oval); hair and face are closed by CLOSE_SIDE (fills small holes).
FACE_ERODE = 3
CLOSE_SIDE = 5
# Clothes are looked for from this many face heights below the chin.
CLOTHES_BELOW_CHIN = 0.1
# Lab distance (OpenCV 8-bit Lab) under which a pixel counts as skin / as the hair colour.
SKIN_DISTANCE = 22.0
HAIR_DISTANCE = 28.0
# Hair below the chin is followed down to this many face heights (long hair).
HAIR_BELOW_CHIN = 0.6
# The rays start at the middle of these face-mesh points (between the eyes, nose tip).
RAY_CENTRE = (168, 4)
# Ray sampling step, pixels of the window.
RAY_STEP = 0.5
# The rays: angles from straight down, turning through the image left, over the top,
# to the image right (the drawing order of the sample faces' hair polygons).
RAY_FIRST = 15.0
# A gap of this fraction of the face width ends a ray's run through the mask.
RAY_GAP = 0.05
MIN_HAIR_PIXELS = 30
# A ray finds hair when it reaches this many face widths beyond the face; where it finds
# none, its point goes INSIDE_FACE of the way out to the face contour.
HAIR_BEYOND = 0.02
INSIDE_FACE = 0.8
# Hair reaches at most this many face widths beyond the face oval along a ray.
MAX_HAIR = 0.6


@dataclass(frozen=True)
class Head:
    """What the segmentation found, in photo pixels.

    polygon: (HAIR_POINTS, 2) the hair polygon, drawing order.
    hair: (3,) median RGB of the hair, None when no hair was found (bald or hidden).
    clothes: (3,) median RGB of the clothes below the chin, None when none is visible.
    background: (3,) median RGB of the window's background.
    """

    polygon: np.ndarray
    hair: np.ndarray | None
    clothes: np.ndarray | None
    background: np.ndarray


def _lab(rgb: np.ndarray) -> np.ndarray:
    import cv2

    return cv2.cvtColor(np.ascontiguousarray(rgb, dtype=np.uint8), cv2.COLOR_RGB2LAB).astype(float)


def _distance(lab: np.ndarray, colour: np.ndarray) -> np.ndarray:
    """Lab distance of every pixel of `lab` (..., 3) to the RGB `colour` (3,)."""
    ref = _lab(np.asarray(colour, dtype=np.uint8).reshape(1, 1, 3))[0, 0]
    return np.linalg.norm(lab - ref, axis=-1)


def segment_head(rgb: np.ndarray, mesh: np.ndarray, skin: np.ndarray, roll: float) -> Head:
    """The head of the face whose (478, 3) mesh is given, in the photo `rgb` (H, W, 3);
    `skin` the face's (3,) RGB skin colour; `roll` the head's lean in degrees (positive
    clockwise on screen), so the rays keep their places on the head."""
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
    oval = (mesh[list(OVAL), :2] - to_window) * scale
    face = polygon_mask((sh, sw), oval)
    chin_y = (y1 - top) * scale
    cx, cy = ((x0 + x1) / 2 - left) * scale, ((y0 + y1) / 2 - top) * scale
    ws, hs = w * scale, h * scale

    mask = np.full((sh, sw), cv2.GC_PR_BGD, np.uint8)
    head = np.zeros((sh, sw), np.uint8)
    cv2.ellipse(head, (int(cx), int(cy - HEAD_RAISE * hs)), (int(HEAD_HALF_WIDTH * ws), int(HEAD_HALF_HEIGHT * hs)),
                0, 0, 360, 1, -1)  # not turned, the whole way round, value 1, filled
    mask[head.astype(bool)] = cv2.GC_PR_FGD
    body = np.zeros((sh, sw), bool)
    body[int(chin_y):, max(0, int(cx - BODY_HALF_WIDTH * ws)):int(cx + BODY_HALF_WIDTH * ws)] = True
    mask[body] = cv2.GC_PR_FGD
    inner = cv2.erode(face.astype(np.uint8), np.ones((FACE_ERODE, FACE_ERODE), np.uint8)).astype(bool)
    mask[inner] = cv2.GC_FGD
    band = max(MIN_EDGE_BAND, sw // EDGE_BAND_PARTS)
    above_chin = slice(0, int(chin_y))
    if top > 0:
        mask[:band] = cv2.GC_BGD
    if left > 0:
        mask[above_chin, :band] = cv2.GC_BGD
    if right < width:
        mask[above_chin, -band:] = cv2.GC_BGD
    bgd, fgd = np.zeros((1, GMM_VALUES), np.float64), np.zeros((1, GMM_VALUES), np.float64)
    cv2.grabCut(image, mask, NO_RECT, bgd, fgd, GRABCUT_ITERATIONS, cv2.GC_INIT_WITH_MASK)
    person = (mask == cv2.GC_FGD) | (mask == cv2.GC_PR_FGD)

    lab = _lab(image)
    skinlike = _distance(lab, skin) < SKIN_DISTANCE
    rows = np.arange(sh)[:, None]
    candidates = person & ~face & ~skinlike
    eyes_y = (eyes(mesh)[0][1] - top) * scale
    crown = candidates & (rows < eyes_y)
    hair = np.median(image[crown], axis=0) if crown.sum() >= MIN_HAIR_PIXELS else None
    if hair is not None:
        hairlike = _distance(lab, hair) < HAIR_DISTANCE
        hair_mask = candidates & ((rows < eyes_y) | (hairlike & (rows < chin_y + HAIR_BELOW_CHIN * hs)))
        # keep the hair that hangs together with the hair on the crown
        _, labels = cv2.connectedComponents(hair_mask.astype(np.uint8), connectivity=8)
        keep = np.unique(labels[crown & hair_mask])
        hair_mask = np.isin(labels, keep[keep > 0])
        clothes_px = person & ~skinlike & ~hairlike & ~face & (rows > chin_y + CLOTHES_BELOW_CHIN * hs)
    else:
        hair_mask = np.zeros_like(face)
        clothes_px = person & ~skinlike & ~face & (rows > chin_y + CLOTHES_BELOW_CHIN * hs)
    clothes = np.median(image[clothes_px], axis=0) if clothes_px.sum() >= MIN_HAIR_PIXELS else None
    outside = ~person
    background = np.median(image[outside], axis=0) if outside.any() else WHITE

    silhouette = cv2.morphologyEx((hair_mask | face).astype(np.uint8), cv2.MORPH_CLOSE,
                                  np.ones((CLOSE_SIDE, CLOSE_SIDE), np.uint8)).astype(bool) | face
    centre = (mesh[list(RAY_CENTRE), :2].mean(axis=0) - to_window) * scale
    directions = _directions(roll)
    face_reach = _reach(face, centre, directions, RAY_GAP * ws)
    reach = _reach(silhouette, centre, directions, RAY_GAP * ws)
    # Hair reaches at most MAX_HAIR face widths beyond the face (a busy background or a
    # neighbour's hair must not pull it away), and one ray may not spike past both of
    # its neighbours. A ray that finds no hair beyond the face ends inside the face, so
    # the polygon stays hidden behind the drawn contour (smoother than the photo's).
    reach = np.minimum(reach, face_reach + MAX_HAIR * ws)
    padded = np.concatenate([reach[:1], reach, reach[-1:]])
    reach = np.median(np.stack([padded[:-2], padded[1:-1], padded[2:]]), axis=0)
    reach = np.where(reach > face_reach + HAIR_BEYOND * ws, reach, INSIDE_FACE * face_reach)
    polygon = (centre + reach[:, None] * directions) / scale + to_window
    return Head(polygon=polygon, hair=hair, clothes=clothes, background=background)


def _directions(roll: float) -> np.ndarray:
    """(HAIR_POINTS, 2) unit ray directions in drawing order, turned by `roll` degrees
    (positive clockwise on screen) with the head."""
    angles = np.radians(np.linspace(RAY_FIRST, 360.0 - RAY_FIRST, HAIR_POINTS) + roll)
    return np.column_stack([-np.sin(angles), np.cos(angles)])


def _reach(mask: np.ndarray, centre: np.ndarray, directions: np.ndarray, gap: float) -> np.ndarray:
    """(R,) how far each ray from `centre` along `directions` (R, 2) runs through the
    mask: to its last mask pixel before the first run of more than `gap` pixels outside
    it, or the edge of the mask (pixels)."""
    sh, sw = mask.shape
    steps = np.arange(0.0, float(np.hypot(sh, sw)), RAY_STEP)
    out = []
    for direction in directions:
        xy = centre + steps[:, None] * direction
        inside = (xy[:, 0] >= 0) & (xy[:, 0] <= sw - 1) & (xy[:, 1] >= 0) & (xy[:, 1] <= sh - 1)
        xy = xy[inside]
        hit = np.nonzero(mask[np.round(xy[:, 1]).astype(int), np.round(xy[:, 0]).astype(int)])[0]
        last = 0
        for i in hit:
            if last > 0 and (i - last) * RAY_STEP > gap:
                break
            last = int(i)
        out.append(steps[last])
    return np.array(out)
