"""video/drive.py: smoothing without lag, calibrated blinks, brows, the mouth among the 12 shapes."""

from __future__ import annotations

import numpy as np
import pytest

from cartoonface.data import SAMPLE_FACES
from cartoonface.face.model import load_face
from cartoonface.face.state import MAX_ANGLE, FaceState
from cartoonface.video.drive import (ALIGNED_SHARE, BLINK_FULL, MOUTH_STEP, OPEN_PERCENTILE, VIDEO_SHAPES,
                                     blink_amounts, brow_amounts, drive, low_pass, mix_mouths, mouth_blends,
                                     shape_measures)
from cartoonface.video.track import MEASURES, Tracking

FPS = 25.0
FACE = load_face(SAMPLE_FACES / "female.json")


def lag_of(raw: np.ndarray, smooth: np.ndarray) -> int:
    """Frames by which `smooth` follows `raw` best (cross-correlation peak)."""
    a, b = raw - raw.mean(), smooth - smooth.mean()
    full = np.correlate(b, a, mode="full")
    return int(np.argmax(full)) - (len(a) - 1)


def test_low_pass_removes_jitter_without_lag():
    rng = np.random.default_rng(3)
    t = np.arange(200) / FPS
    motion = 5 * np.sin(2 * np.pi * 0.7 * t)
    raw = motion + rng.normal(0, 0.8, len(t))
    smooth = low_pass(raw, FPS, 3.0)
    assert lag_of(motion, smooth) == 0
    assert np.std(smooth - motion) < 0.5 * np.std(raw - motion)
    # a cut-off past the Nyquist frequency leaves the values alone; short series too
    assert np.array_equal(low_pass(raw, FPS, 20.0), raw)
    assert low_pass(raw[:1], FPS, 3.0).tolist() == raw[:1].tolist()


def test_blinks_are_calibrated_on_the_clip_own_open_level():
    for scale in (0.2, 0.35):  # narrow and wide eyes
        opening = np.full(100, scale)
        opening[40:44] = scale * BLINK_FULL * 0.5
        blink = blink_amounts(opening)
        assert np.all(blink[40:44] > 0.9) and np.all(blink[:38] == 0) and np.all(blink[46:] == 0)
    # more closed never gives less blink
    ramp = np.linspace(0.35, 0.0, 60)
    padded = np.concatenate([np.full(200, 0.35), ramp])
    assert np.all(np.diff(blink_amounts(padded)[200:]) >= 0)
    assert np.percentile(padded, OPEN_PERCENTILE) == pytest.approx(0.35)


def test_brows_rise_only_above_their_median():
    height = np.full(50, 0.5)
    height[10:20] = 0.56
    height[30:35] = 0.45
    brow = brow_amounts(height)
    assert np.all(brow[10:20] > 0.5) and np.all(brow[30:35] == 0) and brow[0] == 0


def test_each_shape_own_measures_give_that_shape():
    shapes = shape_measures(FACE)
    blends = mouth_blends(shapes[:, 0], shapes[:, 1], shapes)
    for symbol, blend in zip(VIDEO_SHAPES, blends):
        assert blend == ((symbol, 1.0),)


def test_mouth_blends_are_whole_steps_of_the_nearest_shapes():
    shapes = shape_measures(FACE)
    rng = np.random.default_rng(5)
    opening, width = rng.uniform(0, 2, 300), rng.uniform(-0.4, 0.3, 300)
    for blend in mouth_blends(opening, width, shapes):
        assert 1 <= len(blend) <= 2 and sum(w for _, w in blend) == pytest.approx(1)
        assert all(abs(w / MOUTH_STEP - round(w / MOUTH_STEP)) < 1e-9 for _, w in blend)
    # wider opening, more of the open shapes
    closed, half, wide = mouth_blends(np.array([0.0, 0.4, 1.9]), np.zeros(3), shapes)
    assert closed == (("m", 1.0),) and dict(wide).get("a", 0) > 0.5 and "m" not in dict(wide) and half != closed


def test_mixed_mouths_keep_each_shape_once_and_sum_to_one():
    mixed = mix_mouths((("a", 0.7), ("o", 0.3)), (("a", 0.5), ("m", 0.5)), ALIGNED_SHARE)
    weights = dict(mixed)
    assert len(weights) == len(mixed) and sum(weights.values()) == pytest.approx(1)
    assert weights["a"] > weights["m"] > 0 and weights["o"] > 0


def tracking_of(count: int, pose: np.ndarray | None = None, eyes: np.ndarray | None = None,
                mouth: np.ndarray | None = None) -> Tracking:
    """A Tracking of `count` frames at FPS with plausible rest measures, overridden where given."""
    rest = {"eye_left": 0.3, "eye_right": 0.3, "brow_left": 0.5, "brow_right": 0.5,
            "mouth_open": 0.01, "mouth_width": 0.85, "nose_mouth": 0.42}
    measures = np.tile([rest[name] for name in MEASURES], (count, 1))
    if eyes is not None:
        measures[:, 0] = measures[:, 1] = eyes
    if mouth is not None:
        measures[:, MEASURES.index("mouth_open")] = mouth
    return Tracking(fps=FPS, pose=np.zeros((count, 3)) if pose is None else pose, measures=measures,
                    found=np.ones(count, dtype=bool))


def test_drive_clamps_the_pose_and_follows_eyes_and_mouth():
    count = 100
    pose = np.zeros((count, 3))
    pose[30:70, 1] = 40.0  # a turn far past the range
    eyes = np.full(count, 0.3)
    eyes[80:84] = 0.02
    mouth = np.full(count, 0.01)
    mouth[10:25] = 0.25
    base = (FaceState(),) * (count * 30 // 25)
    states = drive(tracking_of(count, pose, eyes, mouth), base, 30, FACE)
    assert len(states) == len(base)
    turns = np.array([s.pose.turn for s in states])
    assert turns.max() == pytest.approx(MAX_ANGLE) and np.all(np.abs(turns) <= MAX_ANGLE)
    blinks = np.array([s.blink for s in states])
    assert blinks[round(81.5 * 30 / 25)] > 0.9 and blinks[: 70 * 30 // 25].max() == 0
    assert dict(states[round(17 * 30 / 25)].mouth).get("m", 0) < 0.5 and states[round(50 * 30 / 25)].mouth == (("m", 1.0),)
    # no brow raise while the eyes are shut, whatever the brow points do
    assert all(s.brow == 0 for s in states if s.blink == 1)


def test_drive_combines_the_aligned_mouth_with_the_video():
    count = 50
    base = (FaceState(mouth=(("o", 1.0),)),) * count
    states = drive(tracking_of(count), base, 25, FACE, combine=True)
    assert all(dict(s.mouth) == {"o": ALIGNED_SHARE, "m": 1 - ALIGNED_SHARE} for s in states)
