"""The generated page in real Chromium (Playwright, Debian's chromium): the face stays on the voice.

One short page is generated per session from speech made here with espeak-ng.
"""

from __future__ import annotations

import math
import re
import shutil
from io import BytesIO
from pathlib import Path

import pytest
from PIL import Image, ImageChops

from cartoonface.pipeline import Options, generate
from tests.conftest import speak

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not Path("/usr/bin/chromium").exists() or not shutil.which("espeak-ng"),
                       reason="needs Debian's chromium and espeak-ng"),
]

ROOT = Path(__file__).resolve().parent.parent
# Two drawings the same: at most this share of pixels differs by more than EDGE_NOISE grey levels.
SAME_PIXELS = 2e-4
EDGE_NOISE = 8
FPS = 30
TEXT = "小猫在花园里玩。它看见了一只蝴蝶。"
# What the page is asked, in one evaluation so both clocks are read at the same moment.
CLOCKS = """() => ({audio: document.getElementById('cf-audio').currentTime,
                    svg: document.getElementById('cf-face').getCurrentTime()})"""
# The same, read in an animation frame callback (after the page script's own, which was
# registered first), so a slow machine's long frames do not count as drift.
CLOCKS_IN_FRAME = """() => new Promise(done => requestAnimationFrame(() => done({
    audio: document.getElementById('cf-audio').currentTime,
    svg: document.getElementById('cf-face').getCurrentTime()})))"""
# The mouth shapes shown: the drawings (with data-shape) the tracks' <use>s point at now.
VISIBLE_MOUTH = """() => [...document.querySelectorAll('#cf-face g[data-part] > use')]
    .map(use => document.getElementById(use.href.animVal.slice(1))).filter(g => g && g.dataset.shape)
    .map(g => g.dataset.shape)"""


@pytest.fixture(scope="session")
def site(tmp_path_factory) -> Path:
    """A generated audio-book folder for ~5 s of espeak-ng Mandarin."""
    folder = tmp_path_factory.mktemp("browser")
    speech = folder / "speech.wav"
    speak(TEXT, speech, speed=150)
    generate(ROOT / "samples" / "faces" / "female.json", speech, TEXT, folder / "site",
             Options(title="小猫 <test>", fps=FPS, seed=3))
    return folder / "site"


@pytest.fixture
def page(browser, site):
    """The generated index.html opened from file://, its script errors collected in page.errors."""
    opened = browser.new_page(viewport={"width": 900, "height": 700})
    errors: list[str] = []
    opened.on("pageerror", lambda error: errors.append(str(error)))
    opened.goto((site / "index.html").as_uri(), wait_until="load")
    opened.wait_for_function("document.getElementById('cf-audio').readyState >= 1")
    yield opened
    assert errors == []
    opened.close()


def seek(page, seconds: float) -> None:
    """Seek the audio element and wait until the page has handled it."""
    page.evaluate("""t => new Promise(done => { const a = document.getElementById('cf-audio');
        a.addEventListener('seeked', () => requestAnimationFrame(() => done()), {once: true}); a.currentTime = t; })""",
                  seconds)


def mouth_shape_intervals(textgrid: str) -> list[tuple[float, float, str]]:
    """(start, end, symbol) of the labelled intervals of the 'mouth shapes' tier of a long-format TextGrid."""
    tier = textgrid.split('name = "mouth shapes"', 1)[1]
    found = re.findall(r'xmin = ([\d.]+)\s+xmax = ([\d.]+)\s+text = "([^"]*)"', tier)
    return [(float(a), float(b), text) for a, b, text in found if text]


def test_svg_time_follows_audio_while_playing(page):
    page.evaluate("document.getElementById('cf-audio').play()")
    page.wait_for_timeout(2000)
    clocks = page.evaluate(CLOCKS_IN_FRAME)
    assert clocks["audio"] > 1.0, "the audio did not play"
    assert abs(clocks["svg"] - clocks["audio"]) <= 1 / FPS


def test_seek_to_middle_shows_the_aligned_mouth_shape(page, site):
    intervals = mouth_shape_intervals((site / "alignment.TextGrid").read_text(encoding="utf-8"))
    duration = page.evaluate("document.getElementById('cf-audio').duration")
    # A shape shown for at least 4 frames, nearest the middle: at its first frame it dominates the mix.
    long_enough = [i for i in intervals if i[1] - i[0] >= 4 / FPS]
    start, _, symbol = min(long_enough, key=lambda i: abs(i[0] - duration / 2))
    frame = math.ceil(start * FPS - 1e-6)
    seek(page, frame / FPS + 0.002)
    clocks = page.evaluate(CLOCKS)
    assert abs(clocks["svg"] - clocks["audio"]) < 0.5 / FPS
    assert page.evaluate(VISIBLE_MOUTH) == [symbol]


def test_pause_stops_the_face(page):
    page.evaluate("document.getElementById('cf-audio').play()")
    page.wait_for_timeout(800)
    page.evaluate("document.getElementById('cf-audio').pause()")
    page.wait_for_timeout(100)
    before = page.evaluate(CLOCKS)
    page.wait_for_timeout(600)
    after = page.evaluate(CLOCKS)
    assert before["audio"] > 0.3
    assert after["svg"] == pytest.approx(before["svg"], abs=1e-3)
    assert abs(after["svg"] - after["audio"]) <= 0.5 / FPS


def test_space_toggles_play_and_sentence_is_highlighted(page):
    seek(page, 0.0)
    page.keyboard.press("Space")
    page.wait_for_timeout(1500)
    assert page.evaluate("!document.getElementById('cf-audio').paused")
    assert page.evaluate("document.querySelectorAll('.cf-speaking').length") == 1
    page.keyboard.press("Space")
    assert page.evaluate("document.getElementById('cf-audio').paused")


def test_faster_playback_keeps_the_face_on_the_audio(page):
    page.evaluate("const a = document.getElementById('cf-audio'); a.playbackRate = 1.5; a.play()")
    page.wait_for_timeout(1500)
    clocks = page.evaluate(CLOCKS_IN_FRAME)
    assert clocks["audio"] > 1.5
    assert abs(clocks["svg"] - clocks["audio"]) <= 1 / FPS


def test_screenshot_is_not_blank(page):
    shot = page.locator("#cf-face").screenshot()
    pixels = Image.open(BytesIO(shot)).convert("RGB")
    colours = pixels.getcolors(maxcolors=1 << 20)
    assert colours is not None and len(colours) > 20, "the face drew (almost) nothing"
    assert max(count for count, _ in colours) < 0.9 * pixels.width * pixels.height


def test_phone_layout_fits_the_screen(browser, site):
    phone = browser.new_page(viewport={"width": 375, "height": 740}, device_scale_factor=2)
    phone.goto((site / "index.html").as_uri(), wait_until="load")
    widths = phone.evaluate("""() => ({page: document.documentElement.scrollWidth,
        face: document.getElementById('cf-face').getBoundingClientRect().width})""")
    phone.close()
    assert widths["page"] <= 375
    assert 250 <= widths["face"] <= 375


def test_tab_switch_pauses_the_face_and_catches_up(page):
    page.evaluate("document.getElementById('cf-audio').play()")
    page.wait_for_timeout(500)
    hide = """hidden => { Object.defineProperty(document, 'hidden', {configurable: true, get: () => hidden});
                          document.dispatchEvent(new Event('visibilitychange')); }"""
    page.evaluate(hide, True)
    hidden_at = page.evaluate(CLOCKS)
    page.wait_for_timeout(700)
    assert page.evaluate("document.getElementById('cf-face').animationsPaused()"), "a hidden page runs no animation"
    assert page.evaluate(CLOCKS)["audio"] > hidden_at["audio"] + 0.4, "the audio plays on"
    page.evaluate(hide, False)
    assert not page.evaluate("document.getElementById('cf-face').animationsPaused()")
    back = page.evaluate(CLOCKS_IN_FRAME)  # in a frame, after the page script's catch-up (a loaded machine's
    assert abs(back["svg"] - back["audio"]) <= 0.5 / FPS  # read between the two drifted 19 ms once)


def test_standalone_animation_plays_on_its_own(browser, site):
    alone = browser.new_page()
    alone.goto((site / "animation.svg").as_uri(), wait_until="load")
    alone.wait_for_timeout(1200)
    shown = alone.evaluate(f"""() => ({{time: document.documentElement.getCurrentTime(),
        visible: ({VISIBLE_MOUTH})().length}})""")
    alone.close()
    assert shown["time"] > 1.0
    assert shown["visible"] == 1


def test_page_face_draws_as_the_svg_written(browser, site, tmp_path):
    """The page's inline SVG (track drawings undisplayed, clip paths hoisted: render/pages.py) shows the
    same pixels as animation.svg put in the page as written, at times across the recording."""
    copy = tmp_path / "site"
    shutil.copytree(site, copy)
    html = (copy / "index.html").read_text(encoding="utf-8")
    written = (copy / "animation.svg").read_text(encoding="utf-8")
    written = written[written.index("<svg"):]
    inline = re.search(r"<svg\b.*</svg>", html, re.S)
    assert inline is not None and inline.group(0) != written, "the page inlines the SVG unchanged"
    (copy / "written.html").write_text(html[: inline.start()] + written + html[inline.end():], encoding="utf-8")
    opened = []
    for name in ("index.html", "written.html"):
        tab = browser.new_page(viewport={"width": 900, "height": 700})
        tab.goto((copy / name).as_uri(), wait_until="load")
        tab.wait_for_function("document.getElementById('cf-audio').readyState >= 1")
        opened.append(tab)
    duration = opened[0].evaluate("document.getElementById('cf-audio').duration")
    for fraction in (0.05, 0.2, 0.35, 0.5, 0.65, 0.8, 0.95):
        shots = []
        for tab in opened:
            seek(tab, duration * fraction)
            tab.evaluate("() => new Promise(done => requestAnimationFrame(() => requestAnimationFrame(done)))")
            shots.append(Image.open(BytesIO(tab.locator("#cf-face").screenshot())).convert("RGB"))
        assert shots[0].size == shots[1].size
        # Chromium's raster differs now and then by a few edge pixels of the scenery between two tabs.
        differing = sum(count for count, level in ImageChops.difference(*shots).convert("L").getcolors(256)
                        if level > EDGE_NOISE)
        assert differing <= SAME_PIXELS * shots[0].width * shots[0].height, \
            f"the page's face differs at {duration * fraction:.2f} s in {differing} pixels"
    for tab in opened:
        tab.close()


def test_clicking_a_sentence_seeks_to_it_and_highlights_it(page):
    sentences = page.locator(".cf-sentence")
    assert sentences.count() >= 2
    start = float(sentences.nth(1).get_attribute("data-start"))
    page.evaluate("""() => new Promise(done => { const a = document.getElementById('cf-audio');
        a.addEventListener('seeked', () => requestAnimationFrame(() => done()), {once: true});
        document.querySelectorAll('.cf-sentence')[1].click(); })""")
    assert page.evaluate("document.getElementById('cf-audio').currentTime") == pytest.approx(start, abs=0.01)
    assert page.evaluate("document.querySelector('.cf-speaking') === document.querySelectorAll('.cf-sentence')[1]")
