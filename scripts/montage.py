"""A screenshot montage of a real sentence: the generated page in Chromium, paused at each mouth shape.

Usage: .venv/bin/python scripts/montage.py WAV TRANSCRIPT OUT.png [--shapes N] [--start SECONDS]

Generates an audio-book page for each sample face from the recording and its transcript, opens it
in headless Debian chromium (Playwright), seeks the page's audio to the middle of each of the first
N mouth-shape intervals of the alignment (from `--start` seconds on), screenshots the face, and lays
the shots out as a grid: one row per face, one column per time, labelled with the time, the
syllable and the shape. Used for the README's montage (docs/sentence-montage.png).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from io import BytesIO
from pathlib import Path

from PIL import Image, ImageDraw, ImageFont

from cartoonface.data import SAMPLE_FACES
from cartoonface.pipeline import Options, generate
from cartoonface.speech.textgrid import read_tiers

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--mute-audio", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run"]
TILE = 190  # px: width and height of one face tile in the montage
LABEL = 24  # px: label band above each tile
FONT = "/usr/share/fonts/opentype/noto/NotoSansCJK-Regular.ttc"  # fonts-noto-cjk (scripts/setup.sh)
FONT_SIZE = 15  # px
FACE_CROP = (0.18, 0.22, 0.82, 0.86)  # share of the face element (left, top, right, bottom) kept in a tile
SEEK = """t => new Promise(done => { const a = document.getElementById('cf-audio');
    a.addEventListener('seeked', () => requestAnimationFrame(() => requestAnimationFrame(() => done())),
                       {once: true}); a.currentTime = t; })"""


def shape_times(textgrid: str, count: int, start: float) -> list[tuple[float, str, str]]:
    """(middle seconds, syllable, shape) of the first `count` shape intervals starting at or after `start`."""
    _, tiers = read_tiers(textgrid, "alignment.TextGrid")
    syllables = [item for item in tiers["syllables"] if item.text]
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


def shots(site: Path, times: list[float]) -> list[Image.Image]:
    """Screenshots of the page's face at each time (seconds), cropped to the head."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as play:
        browser = play.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
        page = browser.new_page(viewport={"width": 900, "height": 900}, device_scale_factor=2)
        page.goto((site / "index.html").as_uri(), wait_until="load")
        page.wait_for_function("document.getElementById('cf-audio').readyState >= 1")
        face = page.locator("#cf-face")
        images = []
        for seconds in times:
            page.evaluate(SEEK, seconds)
            image = Image.open(BytesIO(face.screenshot())).convert("RGB")
            w, h = image.size
            left, top, right, bottom = FACE_CROP
            images.append(image.crop((int(left * w), int(top * h), int(right * w), int(bottom * h))))
        browser.close()
    return images


def montage(rows: list[tuple[str, list[Image.Image], list[str]]]) -> Image.Image:
    """A grid image: per row a name and its tiles with one label each."""
    columns = max(len(tiles) for _, tiles, _ in rows)
    sheet = Image.new("RGB", (columns * TILE, len(rows) * (TILE + LABEL)), "white")
    draw = ImageDraw.Draw(sheet)
    font = ImageFont.truetype(FONT, FONT_SIZE)
    for r, (name, tiles, labels) in enumerate(rows):
        y = r * (TILE + LABEL)
        for c, (tile, label) in enumerate(zip(tiles, labels)):
            sheet.paste(tile.resize((TILE, TILE), Image.Resampling.LANCZOS), (c * TILE, y + LABEL))
            draw.text((c * TILE + 4, y + 2), f"{name} {label}", fill="black", font=font)
    return sheet


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("wav", type=Path)
    parser.add_argument("transcript", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--shapes", type=int, default=8, help="how many mouth shapes (columns)")
    parser.add_argument("--start", type=float, default=0.0, help="first shape at or after this time (s)")
    args = parser.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in ("female", "male"):
            site = Path(tmp) / name
            generate(SAMPLE_FACES / f"{name}.json", args.wav, args.transcript, site, Options(seed=1))
            chosen = shape_times((site / "alignment.TextGrid").read_text(encoding="utf-8"), args.shapes, args.start)
            labels = [f"{t:.2f}s {syllable} [{shape}]" for t, syllable, shape in chosen]
            rows.append((name[0].upper(), shots(site, [t for t, _, _ in chosen]), labels))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    partial = args.out.with_suffix(".part.png")
    montage(rows).save(partial)
    partial.replace(args.out)
    print(args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
