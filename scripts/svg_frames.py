"""Frames of a generated page's animation.svg at chosen times, seen in Chromium, as one PNG.

    .venv/bin/python scripts/svg_frames.py SITE_FOLDER OUT.png LABEL T1 T2 ...

SITE_FOLDER is a `cartoonface generate` output; each Ti (seconds) is one cell: the SVG's
SMIL clock is paused and set to Ti, the head is cropped and scaled, the time written
under it. docs/performer-*.png were made with the times
0.5 2 5.2 7 9.8 12 14 16.5 18 20 21.5 24 on samples/speech/story.wav (docs/animation.md).
"""

from __future__ import annotations

import io
import sys
from pathlib import Path

from PIL import Image, ImageDraw
from playwright.sync_api import ViewportSize, sync_playwright

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--disable-gpu", "--mute-audio", "--disable-background-networking",
        "--disable-component-update", "--disable-sync", "--no-first-run"]
VIEWPORT: ViewportSize = {"width": 400, "height": 480}  # the face model's canvas
HEAD = (60, 60, 340, 400)  # crop box of the head on that canvas, pixels
SCALE = 0.75  # cell size / cropped size
COLUMNS = 6
CAPTION = 18  # pixels under each cell for its time
TITLE = 22  # pixels above the cells for the label
SETTLE_MS = 60  # wait after seeking before the screenshot
COLOURS = 128  # palette size of the saved PNG


def main(argv: list[str]) -> int:
    """Write the montage; 2 with a usage line when the arguments are missing."""
    if len(argv) < 4:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    site, out, label, times = Path(argv[0]), Path(argv[1]), argv[2], [float(t) for t in argv[3:]]
    shots = []
    with sync_playwright() as play:
        browser = play.chromium.launch(executable_path=CHROMIUM, headless=True, args=ARGS)
        page = browser.new_page(viewport=VIEWPORT)
        page.goto((site / "animation.svg").as_uri(), wait_until="load")
        for t in times:
            page.evaluate("t => { const s = document.documentElement; s.pauseAnimations(); s.setCurrentTime(t); }", t)
            page.wait_for_timeout(SETTLE_MS)
            shots.append(Image.open(io.BytesIO(page.screenshot())).convert("RGB"))
        browser.close()
    size = (round((HEAD[2] - HEAD[0]) * SCALE), round((HEAD[3] - HEAD[1]) * SCALE))
    cells = [shot.crop(HEAD).resize(size) for shot in shots]
    rows = -(-len(cells) // COLUMNS)
    sheet = Image.new("RGB", (COLUMNS * size[0], rows * (size[1] + CAPTION) + TITLE), "white")
    draw = ImageDraw.Draw(sheet)
    draw.text((6, 4), label, fill="black")
    for i, (cell, t) in enumerate(zip(cells, times, strict=True)):
        x, y = (i % COLUMNS) * size[0], TITLE + (i // COLUMNS) * (size[1] + CAPTION)
        sheet.paste(cell, (x, y))
        draw.text((x + 6, y + size[1] + 3), f"{t:.2f} s", fill="black")
    sheet.quantize(colors=COLOURS, method=Image.Quantize.MEDIANCUT).save(out, optimize=True)
    print(out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
