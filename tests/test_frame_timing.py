"""The frames' timing in real Chromium (Playwright, Debian's chromium): at a frame's start and in its
middle, the animation seeked by `setCurrentTime` looks as that frame drawn still (tests/stills.py
`frozen`: each track's `<use>` pointed at the frame's drawing), in every track, the head's roll included."""

from __future__ import annotations

from io import BytesIO
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from cartoonface.face.model import load_face
from cartoonface.face.state import FaceState, Pose
from cartoonface.render.animation import animation_svg, frame_ms
from tests.stills import frozen

pytestmark = pytest.mark.browser

ROOT = Path(__file__).resolve().parent.parent
FPS = 30
FRAMES = 24
# A pixel differs when a channel differs by more than this (of 255); a frame matches when under
# this share of its pixels differ (edges antialiased alike in both documents: none in practice).
CHANNEL = 24
SHARE = 1e-3
# Frames (index into the states) checked: both ends, a run of changes, and frames whose start
# is a multiple of 100 ms (30 fps: 3, 6, 9, ...: whole milliseconds hit exactly).
CHECKED = (0, 1, 2, 3, 6, 7, 12, 18, 21, 23)


def changing() -> list[FaceState]:
    """States changing every frame in every track: the head turns, nods and rolls, the eyes blink
    and look about, the mouth cycles through shapes."""
    shapes = "aoeium"
    return [FaceState(pose=Pose(turn=(i % 7) - 3.0, tilt=(i % 5) - 2.0, roll=(i % 4) - 1.5),
                      blink=(i % 3) / 2, gaze_h=2.0 * (i % 5) - 4, mouth=((shapes[i % 6], 1.0),))
              for i in range(FRAMES)]


def shot(page, document: Path, at: float | None) -> np.ndarray:
    """Chromium's picture of `document` (RGB, int16), its animations paused at `at` s (None: still)."""
    page.goto(document.as_uri(), wait_until="load")
    if at is not None:
        page.evaluate(f"document.documentElement.pauseAnimations(); document.documentElement.setCurrentTime({at!r})")
    page.evaluate("new Promise(done => requestAnimationFrame(() => requestAnimationFrame(done)))")
    with Image.open(BytesIO(page.screenshot())) as image:
        return np.asarray(image.convert("RGB"), dtype=np.int16)


def test_every_frame_shows_at_its_start_and_middle(browser, tmp_path):
    face = load_face(ROOT / "samples" / "faces" / "female.json")
    data = animation_svg(face, changing(), FPS)
    animated = tmp_path / "animated.svg"
    animated.write_bytes(data)
    page = browser.new_page(viewport={"width": int(face.width), "height": int(face.height)})
    stills = []
    for frame in CHECKED:
        still = tmp_path / f"still{frame}.svg"
        still.write_bytes(frozen(data, frame, FPS))
        stills.append(shot(page, still, None))
    assert not all((stills[0] == other).all() for other in stills[1:]), "the frames differ"
    for frame, expected in zip(CHECKED, stills, strict=True):
        start = frame_ms(frame, FPS) / 1000
        middle = (frame_ms(frame, FPS) + frame_ms(frame + 1, FPS)) / 2000
        for at in (start, middle):
            differ = np.abs(shot(page, animated, at) - expected).max(axis=2) > CHANNEL
            assert differ.mean() < SHARE, f"frame {frame} at {at} s: {differ.sum()} pixels differ from the frame"
    page.close()
