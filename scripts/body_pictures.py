"""Pictures of the body and the scenery for the docs (issue 11).

    .venv/bin/python scripts/body_pictures.py sheet OUT.png
    .venv/bin/python scripts/body_pictures.py breath SITE_FOLDER OUT.png

`sheet`: every background (rows) with every clothes option (columns) on the announcer's 16:9
stage, for both sample faces (female rows first), rasterised with resvg; run with another
checkout first on PYTHONPATH to picture that version (docs/body-before.png).

`breath`: SITE_FOLDER is a `cartoonface generate --page announcer` output; its animation.svg,
opened in headless Debian chromium (Playwright) and paused at times through the deepest breath
of its actions.json (before, halfway in, top, then each of the first seconds of the exhalation),
cropped to the neck and a shoulder with a red line where the shoulders are at rest.
"""

from __future__ import annotations

import argparse
import io
import json
import sys
from pathlib import Path

from PIL import Image, ImageDraw, ImageFont

from cartoonface.data import SAMPLE_FACES
from cartoonface.face.model import load_face
from cartoonface.face.state import FaceState
from cartoonface.render.animation import STAGE_DEPTH, WIDE, animation_svg
from cartoonface.render.png import svg_to_png
from cartoonface.render.scenery import BACKGROUNDS, CLOTHES

SCALE = 0.2  # of the stage's size: one tile of the sheet
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--mute-audio", "--no-first-run"]
ZOOM = 2  # device scale factor of the breathing screenshots
CROP = (1.35, 0.15, 0.3, 0.2)  # the breathing tiles (the image-left shoulder and the neck): left and right of
# the chin, above and below the shoulder's top, of the face width
STEPS = 3  # seconds of the exhalation shown, one tile a second
FONT = "/usr/share/fonts/opentype/noto/NotoSansCJK-Regular.ttc"  # fonts-noto-cjk (scripts/setup.sh)
LABEL, FONT_SIZE = 24, 15  # px
COLOURS = 256  # palette size of the saved PNG


def sheet() -> Image.Image:
    """The backgrounds x clothes contact sheet of both sample faces."""
    rows = []
    for name in ("female", "male"):
        face = load_face(SAMPLE_FACES / f"{name}.json")
        for background in BACKGROUNDS:
            row = []
            for clothes in CLOTHES:
                svg = animation_svg(face, [FaceState()], 30, background=background, clothes=clothes, wide=True)
                image = Image.open(io.BytesIO(svg_to_png(svg))).convert("RGB")
                row.append(image.resize((round(image.width * SCALE), round(image.height * SCALE)), Image.Resampling.LANCZOS))
            rows.append(row)
    width, height = rows[0][0].size
    picture = Image.new("RGB", (width * len(CLOTHES), height * len(rows)), "white")
    for r, row in enumerate(rows):
        for c, tile in enumerate(row):
            picture.paste(tile, (c * width, r * height))
    return picture


def breath(site: Path) -> Image.Image:
    """The breathing strip of a generated announcer page (see the module's docstring)."""
    from playwright.sync_api import sync_playwright

    from cartoonface.render.scenery import TORSO, figure_of, neck_pivot  # here: `sheet` runs on older checkouts too

    shoulder = TORSO[2][-1]  # (u, v) of the shoulder's top in the torso's outline

    actions = json.loads((site / "actions.json").read_text(encoding="utf-8"))["actions"]
    deepest = max((a for a in actions if a["kind"] == "breath"), key=lambda a: a["amplitude"])
    top = deepest["start"] + deepest["attack"]
    times = [deepest["start"] - 0.1, deepest["start"] + deepest["attack"] / 2, top]
    times += [top + k for k in range(1, min(int(deepest["release"]), STEPS) + 1)]
    face = load_face(SAMPLE_FACES / "female.json")
    height = face.height * STAGE_DEPTH
    width = max(face.width, height * WIDE)
    left = (face.width - width) / 2
    figure = figure_of(face, (left, 0.0, width, height))
    fw = figure.face_width
    shoulder_y = neck_pivot(figure) + fw * shoulder[1]
    box = [(figure.chin_x - fw * CROP[0] - left) * ZOOM, (shoulder_y - fw * CROP[2]) * ZOOM,
           (figure.chin_x + fw * CROP[1] - left) * ZOOM, (shoulder_y + fw * CROP[3]) * ZOOM]
    tiles: list[Image.Image] = []
    with sync_playwright() as play:
        browser = play.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
        page = browser.new_page(viewport={"width": round(width), "height": round(height)}, device_scale_factor=ZOOM)
        page.goto((site / "animation.svg").as_uri(), wait_until="load")
        for seconds in times:
            page.evaluate("t => { const s = document.documentElement; s.pauseAnimations(); s.setCurrentTime(t); }",
                          seconds)
            page.wait_for_timeout(60)
            shot = Image.open(io.BytesIO(page.screenshot())).convert("RGB").crop((box[0], box[1], box[2], box[3]))
            tiles.append(shot.resize((shot.width // ZOOM, shot.height // ZOOM), Image.Resampling.LANCZOS))
        browser.close()
    font = ImageFont.truetype(FONT, FONT_SIZE)
    tile_w, tile_h = tiles[0].size
    picture = Image.new("RGB", (tile_w * len(tiles), tile_h + LABEL), "white")
    draw = ImageDraw.Draw(picture)
    rest = shoulder_y - box[1] / ZOOM
    for k, (tile, seconds) in enumerate(zip(tiles, times, strict=True)):
        picture.paste(tile, (k * tile_w, LABEL))
        draw.line([(k * tile_w, LABEL + rest), ((k + 1) * tile_w, LABEL + rest)], fill="red", width=1)
        draw.text((k * tile_w + 4, 2), f"{seconds:.2f} s", fill="black", font=font)
    return picture


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    modes = parser.add_subparsers(dest="mode", required=True)
    one = modes.add_parser("sheet", help="backgrounds x clothes, both sample faces")
    one.add_argument("out", type=Path)
    two = modes.add_parser("breath", help="the shoulders through a breath of a generated announcer page")
    two.add_argument("site", type=Path)
    two.add_argument("out", type=Path)
    args = parser.parse_args(argv)
    picture = sheet() if args.mode == "sheet" else breath(args.site)
    picture.quantize(colors=COLOURS, method=Image.Quantize.MEDIANCUT).save(args.out, optimize=True)
    print(args.out, args.out.stat().st_size)
    return 0


if __name__ == "__main__":
    sys.exit(main())
