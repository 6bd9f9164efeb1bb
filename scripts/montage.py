"""Screenshot montages of generated pages, seen in headless Debian chromium (Playwright).

    .venv/bin/python scripts/montage.py sentence WAV TRANSCRIPT OUT.png [--shapes N] [--start SECONDS]
    .venv/bin/python scripts/montage.py frames SITE_FOLDER OUT.png LABEL T1 T2 ...

`sentence`: generates an audio-book page for each sample face from the recording and its
transcript, seeks the page's audio to the middle of each of the first N mouth-shape intervals
of the alignment (from `--start` seconds on) and lays the face shots out one row per face, each
labelled with the time, the syllable and the shape (docs/sentence-montage.png, in the README).

`frames`: SITE_FOLDER is a `cartoonface generate` output (audio book or announcer page); its animation.svg is paused at each
time Ti (seconds) and the head cropped, in rows under LABEL (docs/performer-*.png were made with
the times 0.5 2 5.2 7 9.8 12 14 16.5 18 20 21.5 24 on samples/speech/story.wav).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from io import BytesIO
from pathlib import Path
from typing import TYPE_CHECKING

from lxml import etree
from PIL import Image, ImageDraw, ImageFont

from cartoonface.data import SAMPLE_FACES
from cartoonface.pipeline import Options, generate
from cartoonface.speech.textgrid import read_tiers

if TYPE_CHECKING:
    from playwright.sync_api import Page

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--mute-audio", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run"]
TILE = 190  # px: width and height of one face tile in the montage
LABEL = 24  # px: label band above each tile (and the title band above a frames montage)
FONT = "/usr/share/fonts/opentype/noto/NotoSansCJK-Regular.ttc"  # fonts-noto-cjk (scripts/setup.sh)
FONT_SIZE = 15  # px
FACE_CROP = (0.18, 0.22, 0.82, 0.86)  # share of the page's face element (left, top, right, bottom) kept
HEAD = (60, 60, 340, 400)  # crop box of the head on that canvas, pixels
COLUMNS = 6  # tiles per row of a frames montage
SETTLE_MS = 60  # wait after setting the SVG clock before the screenshot
COLOURS = 256  # palette size of the saved PNG (keeps the docs' pictures small)
SEEK = """t => new Promise(done => { const a = document.getElementById('cf-audio');
    a.addEventListener('seeked', () => requestAnimationFrame(() => requestAnimationFrame(() => done())),
                       {once: true}); a.currentTime = t; })"""
SET_SVG_TIME = "t => { const s = document.documentElement; s.pauseAnimations(); s.setCurrentTime(t); }"


@contextmanager
def opened(url: str, size: tuple[int, int], scale: float) -> Iterator[Page]:
    """A headless chromium page of `size` (w, h) CSS px at device scale `scale`, loaded from `url`."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as play:
        browser = play.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
        page = browser.new_page(viewport={"width": size[0], "height": size[1]}, device_scale_factor=scale)
        page.goto(url, wait_until="load")
        yield page
        browser.close()


def shots(page: Page, times: list[float], seek: Callable[[Page, float], bytes],
          crop: tuple[float, float, float, float]) -> list[Image.Image]:
    """One screenshot per time (seconds) taken by `seek`, cropped to the shares `crop` of the image."""
    images = []
    for seconds in times:
        image = Image.open(BytesIO(seek(page, seconds))).convert("RGB")
        w, h = image.size
        images.append(image.crop((int(crop[0] * w), int(crop[1] * h), int(crop[2] * w), int(crop[3] * h))))
    return images


def grid(tiles: list[Image.Image], labels: list[str], columns: int, title: str = "") -> Image.Image:
    """`tiles` as TILE-square cells, `columns` a row, each under its label; `title` on top when given."""
    font = ImageFont.truetype(FONT, FONT_SIZE)
    rows = -(-len(tiles) // columns)
    top = LABEL if title else 0
    sheet = Image.new("RGB", (columns * TILE, top + rows * (TILE + LABEL)), "white")
    draw = ImageDraw.Draw(sheet)
    if title:
        draw.text((4, 2), title, fill="black", font=font)
    for i, (tile, label) in enumerate(zip(tiles, labels, strict=True)):
        x, y = (i % columns) * TILE, top + (i // columns) * (TILE + LABEL)
        sheet.paste(tile.resize((TILE, TILE), Image.Resampling.LANCZOS), (x, y + LABEL))
        draw.text((x + 4, y + 2), label, fill="black", font=font)
    return sheet


def shape_times(textgrid: str, count: int, start: float) -> list[tuple[float, str, str]]:
    """(middle seconds, syllable, shape) of the first `count` shape intervals starting at or after `start`."""
    _, tiers = read_tiers(textgrid, "alignment.TextGrid")
    syllables = [item for item in tiers.get("syllables", tiers.get("phones", [])) if item.text]  # phones: English
    chosen = []
    for item in tiers["mouth shapes"]:
        if not item.text or item.start < start:
            continue
        middle = (item.start + item.end) / 2
        syllable = next((s.text for s in syllables if s.start <= middle < s.end), "")
        chosen.append((middle, syllable, item.text))
        if len(chosen) == count:
            break
    return chosen


def seek_page(page: Page, seconds: float) -> bytes:
    """Seek a generated page's audio to `seconds`; the face element's screenshot."""
    page.evaluate(SEEK, seconds)
    return page.locator("#cf-face").screenshot()


def seek_svg(page: Page, seconds: float) -> bytes:
    """Pause an opened animation.svg at `seconds`; the screenshot."""
    page.evaluate(SET_SVG_TIME, seconds)
    page.wait_for_timeout(SETTLE_MS)
    return page.screenshot()


def sentence(wav: Path, transcript: Path, count: int, start: float) -> Image.Image:
    """The montage of the `sentence` mode: one row per sample face."""
    tiles: list[Image.Image] = []
    labels: list[str] = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in ("female", "male"):
            site = Path(tmp) / name
            generate(SAMPLE_FACES / f"{name}.json", wav, transcript, site, Options(seed=1))
            chosen = shape_times((site / "alignment.TextGrid").read_text(encoding="utf-8"), count, start)
            with opened((site / "index.html").as_uri(), (900, 900), 2) as page:
                page.wait_for_function("document.getElementById('cf-audio').readyState >= 1")
                tiles += shots(page, [t for t, _, _ in chosen], seek_page, FACE_CROP)
            labels += [f"{name[0].upper()} {t:.2f}s {syllable} [{shape}]" for t, syllable, shape in chosen]
    return grid(tiles, labels, count)


def head_crop(svg: Path) -> tuple[tuple[int, int], tuple[float, float, float, float]]:
    """The viewport (px) of animation.svg `svg` and the shares of it its HEAD box covers: the
    audio book's portrait canvas is the face model's, the announcer's 16:9 stage lies around it."""
    root = etree.parse(str(svg), etree.XMLParser(huge_tree=True)).getroot()
    x, y, width, height = (float(v) for v in root.get("viewBox", "").split())
    return ((round(float(root.get("width", width))), round(float(root.get("height", height)))),
            ((HEAD[0] - x) / width, (HEAD[1] - y) / height, (HEAD[2] - x) / width, (HEAD[3] - y) / height))


def frames(site: Path, label: str, times: list[float]) -> Image.Image:
    """The montage of the `frames` mode: animation.svg of `site` at `times`, under `label`."""
    size, crop = head_crop(site / "animation.svg")
    with opened((site / "animation.svg").as_uri(), size, 1) as page:
        tiles = shots(page, times, seek_svg, crop)
    return grid(tiles, [f"{t:.2f} s" for t in times], COLUMNS, label)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    modes = parser.add_subparsers(dest="mode", required=True)
    one = modes.add_parser("sentence", help="a real sentence at its mouth shapes, both sample faces")
    one.add_argument("wav", type=Path)
    one.add_argument("transcript", type=Path)
    one.add_argument("out", type=Path)
    one.add_argument("--shapes", type=int, default=8, help="how many mouth shapes (columns)")
    one.add_argument("--start", type=float, default=0.0, help="first shape at or after this time (s)")
    many = modes.add_parser("frames", help="a generated folder's animation.svg at given times")
    many.add_argument("site", type=Path)
    many.add_argument("out", type=Path)
    many.add_argument("label")
    many.add_argument("times", type=float, nargs="+")
    args = parser.parse_args(argv)
    if args.mode == "sentence":
        picture = sentence(args.wav, args.transcript, args.shapes, args.start)
    else:
        picture = frames(args.site, args.label, args.times)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    partial = args.out.with_suffix(".part.png")
    picture.quantize(colors=COLOURS, method=Image.Quantize.MEDIANCUT).save(partial, optimize=True)
    partial.replace(args.out)
    print(args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
