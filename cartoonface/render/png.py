"""SVG documents as PNG pictures, rasterised with resvg (resvg-py): `face render --png`,
the contact sheet and diagram pictures, the photo preview."""

from __future__ import annotations

import io

import resvg_py
from PIL import Image

# Colours of a palette PNG (the most a PNG palette holds).
PALETTE_COLOURS = 256


def svg_to_png(data: bytes, palette: bool = False) -> bytes:
    """Rasterise SVG bytes at their own size with resvg; returns PNG bytes (RGBA). With
    `palette`, the picture (drawn on an opaque background) is stored with a 256-colour
    palette instead: a third of the size, for large sheets."""
    png = bytes(resvg_py.svg_to_bytes(svg_string=data.decode("utf-8")))
    if not palette:
        return png
    with Image.open(io.BytesIO(png)) as image:
        out = io.BytesIO()
        image.convert("RGB").quantize(PALETTE_COLOURS).save(out, "PNG", optimize=True)
    return out.getvalue()
