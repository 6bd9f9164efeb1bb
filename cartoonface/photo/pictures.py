"""Pictures of a photo for people to look at: the overlay of the detected points
(`cartoonface face from-photo --overlay`) and the JPEG the web point editor shows.
"""

from __future__ import annotations

import io

import numpy as np
from PIL import Image, ImageDraw

from cartoonface.photo.model_from_photo import Photo, PhotoFace

# JPEG quality of the editor's picture (Pillow's scale, 1..95).
JPEG_QUALITY = 88
# Overlay colours (RGB): the hair polygon, the named points and their rims.
HAIR_COLOUR = (40, 110, 255)
POINT_COLOUR = (255, 40, 40)
RIM_COLOUR = (255, 255, 255)
# Overlay dot radius: this share of the face width, at least MIN_DOT_RADIUS pixels.
DOT_SHARE = 0.012
MIN_DOT_RADIUS = 1.5


def scaled_image(rgb: np.ndarray, max_side: int) -> tuple[Image.Image, float]:
    """The (H, W, 3) uint8 picture as a PIL image scaled down (never up) to at most
    `max_side` pixels a side; returns (image, its pixels per pixel of `rgb`)."""
    image = Image.fromarray(rgb)
    k = min(1.0, max_side / max(image.size))
    if k < 1.0:
        image = image.resize((max(1, round(image.width * k)), max(1, round(image.height * k))),
                             Image.Resampling.LANCZOS)
    return image, k


def display_jpeg(rgb: np.ndarray, max_side: int) -> tuple[bytes, tuple[int, int], float]:
    """The (H, W, 3) uint8 picture as JPEG bytes at most `max_side` pixels a side; returns
    (bytes, (width, height) of the JPEG, its pixels per pixel of `rgb`)."""
    image, k = scaled_image(rgb, max_side)
    out = io.BytesIO()
    image.save(out, "JPEG", quality=JPEG_QUALITY)
    return out.getvalue(), image.size, k


def overlay_png(photo: Photo, result: PhotoFace, max_side: int = 512) -> bytes:
    """PNG bytes of the photo (scaled to at most `max_side` pixels a side) with the
    detected named points (red dots) and the hair outline (blue closed line and dots) drawn on it."""
    image, k = scaled_image(photo.rgb, max_side)
    draw = ImageDraw.Draw(image)
    r = max(MIN_DOT_RADIUS, DOT_SHARE * float(np.ptp(result.points[:, 0])) * k)
    hair = [(float(x) * k, float(y) * k) for x, y in result.hair]
    draw.line(hair + hair[:1], fill=HAIR_COLOUR, width=max(1, round(r / 2)))
    for x, y in hair:
        draw.ellipse((x - r, y - r, x + r, y + r), fill=HAIR_COLOUR)
    for x, y in result.points * k:
        draw.ellipse((x - r, y - r, x + r, y + r), fill=POINT_COLOUR, outline=RIM_COLOUR)
    out = io.BytesIO()
    image.save(out, "PNG", optimize=True)
    return out.getvalue()
