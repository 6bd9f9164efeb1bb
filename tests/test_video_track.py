"""video/track.py: the face mesh followed through a real GRID clip; a lost face held and eased back."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from cartoonface.data import SAMPLE_FACES
from cartoonface.face.model import load_face
from cartoonface.face.state import MAX_ANGLE, FaceState
from cartoonface.video.clip import VideoError, probe
from cartoonface.video.drive import drive
from cartoonface.video.track import EASE, HOLD, MEASURES, fill_lost, track
from tests.clips import GRID, LABELS, make_clip

FACE = SAMPLE_FACES / "female.json"


@pytest.fixture(scope="module")
def tracking():
    return track(probe(GRID))


def test_the_face_is_found_in_every_frame(tracking):
    assert tracking.found.all() and tracking.measures.shape == (len(tracking.found), len(MEASURES))
    assert np.isfinite(tracking.pose).all() and np.isfinite(tracking.measures).all()
    # the speaker faces the camera: small angles
    assert np.all(np.abs(np.median(tracking.pose, axis=0)) < 15)


def test_the_eyes_measure_closed_on_the_hand_labelled_blinks(tracking):
    with LABELS.open(encoding="utf-8") as handle:
        closed = [range(int(r["first"]), int(r["last"]) + 1) for r in csv.DictReader(handle) if r["clip"] == GRID.stem]
    opening = (tracking.measure("eye_left") + tracking.measure("eye_right")) / 2
    shut = np.zeros(len(opening), dtype=bool)
    for run in closed:
        shut[list(run)] = True
    assert closed and opening[shut].max() < 0.6 * np.median(opening[~shut])


def test_the_mouth_opens_in_the_words_and_rests_in_the_silences(tracking):
    words = [line.split() for line in GRID.with_suffix(".align").read_text().splitlines()]
    times = np.arange(len(tracking.found)) / tracking.fps
    speaking = np.zeros(len(times), dtype=bool)
    for start, end, word in words:
        if word not in ("sil", "sp"):
            speaking |= (times >= int(start) / 25000) & (times < int(end) / 25000)
    opening = tracking.measure("mouth_open")
    assert np.percentile(opening[speaking], 75) > 3 * np.median(opening[~speaking])


def test_a_lost_face_holds_then_eases_to_the_median():
    fps = 20.0
    values = np.column_stack([np.linspace(0, 1, 100), np.full(100, 2.0)])
    found = np.ones(100, dtype=bool)
    found[:5] = False
    found[40:80] = False
    filled = fill_lost(values, found, fps)
    median = np.median(values[found], axis=0)
    assert np.array_equal(filled[found], values[found])
    assert np.allclose(filled[:5], median)
    held = round(HOLD * fps)
    assert np.allclose(filled[40:40 + held], values[39])
    back = 40 + round((HOLD + EASE) * fps)
    assert np.allclose(filled[back:80], median)
    steps = np.diff(filled[40:back, 0])
    assert np.all(steps * np.sign(median[0] - values[39, 0]) >= 0)  # eased monotonically towards the median


def test_a_video_without_a_face_is_refused(tmp_path):
    clip = probe(make_clip(tmp_path / "pattern.mp4", "-f", "lavfi", "-i", "testsrc=size=320x240:rate=10",
                           "-t", "1", "-c:v", "libx264", "-preset", "ultrafast"))
    with pytest.raises(VideoError, match="face was found in 0 of 10 frames"):
        track(clip)


def test_a_face_hidden_for_a_while_is_held_then_eased_back(tmp_path):
    hidden = make_clip(tmp_path / "hidden.mp4", "-i", str(GRID), "-vf",
                       "drawbox=x=0:y=0:w=iw:h=ih:color=gray:t=fill:enable='between(t,1,2.2)'",
                       "-c:v", "libx264", "-preset", "ultrafast")
    tracking = track(probe(hidden))
    times = np.arange(len(tracking.found)) / tracking.fps
    lost = ~tracking.found
    assert lost[(times > 1.05) & (times < 2.15)].all() and tracking.found[times < 0.95].all()
    first = int(np.argmax(lost))
    held = tracking.measures[first:first + int(HOLD * tracking.fps)]
    assert np.allclose(held, tracking.measures[first - 1])
    eased = first + int((HOLD + EASE) * tracking.fps) + 1
    assert np.allclose(tracking.measures[eased:eased + 3], np.median(tracking.measures[tracking.found], axis=0))


def test_a_rolling_head_rolls_the_cartoon_within_the_range(tmp_path):
    # the picture turned clockwise by up to 0.35 rad (20 degrees): the head's top to the image right
    rolled = make_clip(tmp_path / "roll.mp4", "-i", str(GRID), "-vf", "rotate=0.35*sin(2*PI*t/1.5):fillcolor=gray",
                       "-c:v", "libx264", "-preset", "ultrafast")
    tracking = track(probe(rolled))
    times = np.arange(len(tracking.found)) / tracking.fps
    truth = -np.degrees(0.35 * np.sin(2 * np.pi * times / 1.5))  # Pose: + is the top to the image left
    states = drive(tracking, (FaceState(),) * len(times), round(tracking.fps), load_face(FACE))
    roll = np.array([s.pose.roll for s in states])
    inside = np.abs(truth) < MAX_ANGLE - 3
    assert np.corrcoef(truth[inside], roll[inside])[0, 1] > 0.98
    assert np.median(np.abs(roll[inside] - truth[inside])) < 1.5
    assert np.abs(roll).max() == MAX_ANGLE
