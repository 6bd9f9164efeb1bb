"""Face colours sampled from a photo: robust medians inside regions the face mesh outlines.

Every sample comes from inside the face (skin, lips, iris, eyebrows), never from the
background; hair and clothes come from the head segmentation (hair.py). The
derived colours (shadow, mouth, cheek, outline, pupil) are mixes of the sampled ones.
"""

from __future__ import annotations

import numpy as np

from cartoonface.photo.landmarks_map import IRIS_RIM, OVAL, eyes

# Face-mesh loops (image left = the subject's right); the mesh's topology.
LIPS_OUTER = (61, 185, 40, 39, 37, 0, 267, 269, 270, 409, 291, 375, 321, 405, 314, 17, 84, 181, 91, 146)
LIPS_INNER = (78, 191, 80, 81, 82, 13, 312, 311, 310, 415, 308, 324, 318, 402, 317, 14, 87, 178, 88, 95)
EYE_LEFT = (33, 246, 161, 160, 159, 158, 157, 173, 133, 155, 154, 153, 145, 144, 163, 7)
EYE_RIGHT = (263, 466, 388, 387, 386, 385, 384, 398, 362, 382, 381, 380, 374, 373, 390, 249)
BROW_LEFT = (70, 63, 105, 66, 107, 55, 65, 52, 53, 46)
BROW_RIGHT = (300, 293, 334, 296, 336, 285, 295, 282, 283, 276)
NOSE_LOWER = (129, 98, 97, 2, 326, 327, 358, 344, 4, 115)
# Skin is sampled below this many d under the eyes (the forehead is often under a fringe).
SKIN_BELOW_EYES = 0.25
# Too few pixels to trust a median.
MIN_PIXELS = 12
# The iris is sampled on the ring between these shares of its radius (inside: the pupil
# and its highlight; outside: the rim's shadow).
IRIS_RING = (0.4, 0.85)
# The face mesh's box is widened by this many pixels before cutting it out (the masks'
# rounding stays inside the cut).
BOX_PAD = 2
# Luma percentile bands (low, high) of each median: skin without shadows and shine, lips,
# the iris without the pupil's dark and the highlight, the darkest part of the brows.
SKIN_BAND, LIP_BAND, IRIS_BAND, BROW_BAND = (20, 90), (15, 85), (10, 75), (0, 40)
# Rec. 601 luma weights of R, G, B.
LUMA = (0.299, 0.587, 0.114)
# Derived colours: how far each mixes towards black (or skin towards lip for the cheek).
SHADOW_DARK, PUPIL_DARK, MOUTH_DARK, OUTLINE_DARK = 0.12, 0.75, 0.55, 0.55
CHEEK_BLUSH = 0.4


def polygon_mask(shape: tuple[int, int], polygon: np.ndarray) -> np.ndarray:
    """(H, W) bool mask of the filled polygon ((N, 2) pixel x, y) on an image of `shape` (H, W)."""
    import cv2

    mask = np.zeros(shape, dtype=np.uint8)
    cv2.fillPoly(mask, [np.round(polygon).astype(np.int32)], 1)
    return mask.astype(bool)


def _loop(mesh: np.ndarray, loop: tuple[int, ...]) -> np.ndarray:
    return mesh[list(loop), :2]


def luminance(pixels: np.ndarray) -> np.ndarray:
    """(n,) Rec. 601 luma of (n, 3) RGB pixels."""
    return pixels @ np.array(LUMA)


def band_median(pixels: np.ndarray, low: float, high: float) -> np.ndarray | None:
    """(3,) median RGB of the pixels whose luma lies between the `low` and `high`
    percentiles (drops shadows, highlights and stray pixels); None if too few."""
    if len(pixels) < MIN_PIXELS:
        return None
    luma = luminance(pixels.astype(float))
    lo, hi = np.percentile(luma, [low, high])
    kept = pixels[(luma >= lo) & (luma <= hi)]
    return np.median(kept if len(kept) >= MIN_PIXELS else pixels, axis=0)


def face_colours(rgb: np.ndarray, mesh: np.ndarray) -> dict[str, np.ndarray | None]:
    """Median RGB (3,) floats of skin, lip, iris and brow from the photo `rgb` (H, W, 3)
    and the face mesh (478, 3) in its pixels; a value is None when too few pixels show it."""
    low = np.maximum(np.floor(mesh[:, :2].min(axis=0)).astype(int) - BOX_PAD, 0)
    high = np.minimum(np.ceil(mesh[:, :2].max(axis=0)).astype(int) + BOX_PAD + 1, [rgb.shape[1], rgb.shape[0]])
    rgb = rgb[low[1]:high[1], low[0]:high[0]]
    mesh = mesh - [low[0], low[1], 0]
    shape = rgb.shape[:2]
    middle, d = eyes(mesh)
    eyes_y = middle[1]
    rows = np.arange(shape[0])[:, None]

    skin = polygon_mask(shape, _loop(mesh, OVAL)) & (rows > eyes_y + SKIN_BELOW_EYES * d)
    for loop in (LIPS_OUTER, NOSE_LOWER):
        skin &= ~polygon_mask(shape, _loop(mesh, loop))
    lips = polygon_mask(shape, _loop(mesh, LIPS_OUTER)) & ~polygon_mask(shape, _loop(mesh, LIPS_INNER))
    brows = polygon_mask(shape, _loop(mesh, BROW_LEFT)) | polygon_mask(shape, _loop(mesh, BROW_RIGHT))

    cols = np.arange(shape[1])[None, :]
    iris = np.zeros(shape, dtype=bool)
    for (centre, rim), eye in ((IRIS_RIM["r1"], EYE_LEFT), (IRIS_RIM["r2"], EYE_RIGHT)):
        cx, cy = mesh[centre, :2]
        r = float(np.mean(np.hypot(*(mesh[list(rim), :2] - mesh[centre, :2]).T)))
        dist = np.hypot(cols - cx, rows - cy)
        # the ring between pupil and rim, inside the open eye
        iris |= (dist <= IRIS_RING[1] * r) & (dist >= IRIS_RING[0] * r) & polygon_mask(shape, _loop(mesh, eye))

    return {
        "skin": band_median(rgb[skin], *SKIN_BAND),
        "lip": band_median(rgb[lips], *LIP_BAND),
        "iris": band_median(rgb[iris], *IRIS_BAND),
        "brow": band_median(rgb[brows], *BROW_BAND),
    }


def mix(a: np.ndarray, b: np.ndarray, t: float) -> np.ndarray:
    """(3,) colour a moved the fraction t towards b."""
    return (1 - t) * np.asarray(a, float) + t * np.asarray(b, float)


def hex_colour(rgb: np.ndarray) -> str:
    """'#rrggbb' of a (3,) RGB colour in 0..255."""
    r, g, b = (int(round(float(np.clip(v, 0, 255)))) for v in rgb)
    return f"#{r:02x}{g:02x}{b:02x}"


BLACK = np.zeros(3)
WHITE = np.full(3, 255.0)


def palette_values(skin: np.ndarray, hair: np.ndarray, brow: np.ndarray, iris: np.ndarray,
                   lip: np.ndarray) -> dict[str, str]:
    """The eleven Palette colours (hex) from the five sampled ones ((3,) RGB each).

    The sclera stays white (a photo's is shaded grey, which reads as dirty in a
    cartoon); the rest mixes the samples: shadow and outline are darker skin, the
    mouth inside darker lip, the cheek blush skin towards lip, the pupil darker iris."""
    return {
        "skin": hex_colour(skin),
        "skin_shadow": hex_colour(mix(skin, BLACK, SHADOW_DARK)),
        "hair": hex_colour(hair),
        "brow": hex_colour(brow),
        "eye_white": hex_colour(WHITE),
        "iris": hex_colour(iris),
        "pupil": hex_colour(mix(iris, BLACK, PUPIL_DARK)),
        "lip": hex_colour(lip),
        "mouth": hex_colour(mix(lip, BLACK, MOUTH_DARK)),
        "cheek": hex_colour(mix(skin, lip, CHEEK_BLUSH)),
        "outline": hex_colour(mix(skin, BLACK, OUTLINE_DARK)),
    }
