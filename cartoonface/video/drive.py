"""What the tracked face did -> the cartoon's FaceState per frame (issue 15, seed 003's cloning).

`drive(tracking, base, fps, face, combine)` replaces the pose, blink, brow and mouth of `base`
(the states the timeline sampled: emotions, lips and, with a transcript, the aligned mouth) by
what the video shows, frame i of the cartoon at i / fps s:

- pose: mesh_pose less the clip's median (the cartoon faces the viewer when the person faces
  their usual direction; a camera a little off to the side is no turn), clamped to +-MAX_ANGLE,
  in steps of POSE_STEP;
- blink: from the eyes' opening, calibrated per clip: the open level is the OPEN_PERCENTILE of
  the clip's openings; the lids are down by BLINK_START of it and shut at BLINK_FULL;
- brow: the brows' height over its median, BROW_FULL of the person's own brow-to-eye distance
  (the FAPU EyebrowH the cartoon's brow raise moves by) raising the cartoon's brows fully, less
  while the eyes close (the mesh lifts its brow points with the lids);
- mouth: the opening above the lips' rest gap (REST_PERCENTILE) in units of the person's MNS0 (nose to upper lip) and the width change in
  units of their MW0 (mouth width at rest), each times a gain, placed among the cartoon's
  VIDEO_SHAPES (the same measures of each shape on the cartoon, from face/mouth.py's table):
  a blend of the two nearest, in steps of MOUTH_STEP. With a transcript (`combine`) the aligned
  shapes and the video's blend are mixed half and half (ALIGNED_SHARE).

Smoothing is zero-phase (a Butterworth low-pass run forwards and backwards, SciPy's
sosfiltfilt), so it removes the mesh's jitter without any lag: the pose and brows at
SLOW_CUTOFF, the mouth at MOUTH_CUTOFF; the eyes are not smoothed: a blink's closed part lasts
one to three frames at 25 fps, which a median or a low-pass would halve (bench/video.py).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from cartoonface.face.model import FaceModel
from cartoonface.face.mouth import MOUTH_SHAPES, MouthShape, Term
from cartoonface.face.state import MAX_ANGLE, FaceState, Pose
from cartoonface.video.track import Tracking

# Smoothing: low-pass cut-offs (Hz). Head and brow moves of speech are slower than 3 Hz
# (nods and beats: 2-3 per second at most); the jaw moves with the syllables, 3-7 per second.
SLOW_CUTOFF = 3.0
MOUTH_CUTOFF = 8.0
FILTER_ORDER = 2
# Blinks, tuned on GRID s1_bbaf2n (bench/video.py, bench/video_blinks.csv): the open level is
# this percentile of the clip's openings; blink 0 at BLINK_START of it, 1 at BLINK_FULL.
OPEN_PERCENTILE = 90
BLINK_START = 0.75
BLINK_FULL = 0.35
# Brows: a raise of this share of the person's brow-to-eye distance raises the cartoon's fully.
BROW_FULL = 0.12
# Mouth: the cartoon's shapes are drawn larger than people speak (thesis 002 5.2.2, docs/mouth.md):
# the measured opening (MNS0) and width change (MW0) are scaled by these gains first (GRID s1_bbaf2n).
OPEN_GAIN = 2.5
# The lips' gap at rest (the mesh's inner lips rarely meet): this percentile of the clip's openings,
# taken off every opening (a talking clip has its lips shut for more than a tenth of the time).
REST_PERCENTILE = 10
WIDTH_GAIN = 3.0
# How far one MW0 of width change counts against one MNS0 of opening when the nearest shapes are found.
WIDTH_WEIGHT = 2.0
# The shapes a video can tell apart by opening and width (f's bite, r's and n's tongue cannot be seen).
VIDEO_SHAPES = ("m", "z", "h'", "h", "a", "i", "e", "u", "o")
# The pose is drawn in steps of this many degrees: each distinct pose is a drawing in the SVG, and
# 0.5 makes 1.9 MB per minute of the joined GRID clips against 3.1 for 0.1 degrees (bench/video.py).
POSE_STEP = 0.5
MOUTH_STEP = 0.1  # blend weights are multiples of this (fewer distinct drawings in the SVG)
ALIGNED_SHARE = 0.5  # with a transcript: the aligned shapes' share of the mouth, the video's the rest


def low_pass(values: np.ndarray, fps: float, cutoff: float) -> np.ndarray:
    """(n, k) or (n,) `values` sampled at `fps` -> the same, zero-phase low-passed at `cutoff` Hz
    (Butterworth of FILTER_ORDER, forwards and backwards: no lag). Unchanged when the cutoff is at
    or above the Nyquist frequency or there are too few samples to filter."""
    data = np.asarray(values, dtype=float)
    if cutoff >= 0.5 * fps or len(data) < 2:
        return data.copy()
    # imported here: scipy.signal costs ~0.6 s of start-up, and only a video-driven job needs it
    from scipy.signal import butter, sosfiltfilt

    sos = butter(FILTER_ORDER, cutoff, fs=fps, output="sos")
    pad = min(3 * (2 * len(sos) + 1), len(data) - 1)
    return sosfiltfilt(sos, data, axis=0, padlen=pad)


def blink_amounts(opening: np.ndarray) -> np.ndarray:
    """(n,) eye openings (lid distance over eye width) -> (n,) blink 0..1, calibrated on these
    openings (OPEN_PERCENTILE is the open level; BLINK_START, BLINK_FULL of it)."""
    level = float(np.percentile(opening, OPEN_PERCENTILE))
    if level <= 0:
        return np.zeros(len(opening))
    return np.clip((BLINK_START - opening / level) / (BLINK_START - BLINK_FULL), 0.0, 1.0)


def brow_amounts(height: np.ndarray) -> np.ndarray:
    """(n,) brow-to-eye heights -> (n,) brow raise 0..1 over the median (BROW_FULL of it: 1)."""
    rest = float(np.median(height))
    return np.clip((height / rest - 1.0) / BROW_FULL, 0.0, 1.0)


def _px(face: FaceModel, term: Term) -> float:
    """A FAPU term of face/mouth.py's table in the face's pixels."""
    coefficient, unit = term
    return coefficient * float(getattr(face.fapu, unit))


def shape_measures(face: FaceModel) -> np.ndarray:
    """(len(VIDEO_SHAPES), 2) the inner opening (units of the face's MNS0) and the width change
    (units of its MW0) each of VIDEO_SHAPES gives the cartoon `face`, the measures the video gives."""
    rows = []
    for symbol in VIDEO_SHAPES:
        shape: MouthShape = MOUTH_SHAPES[symbol]
        opening = _px(face, shape.dn) - _px(face, shape.up) - _px(face, shape.upper_lip) - _px(face, shape.lower_lip)
        rows.append((opening / face.fapu.mns0, -2 * _px(face, shape.inward) / face.fapu.mw0))
    return np.array(rows)


def mouth_blends(opening: np.ndarray, width: np.ndarray, shapes: np.ndarray) -> list[tuple[tuple[str, float], ...]]:
    """(n,) openings (MNS0) and width changes (MW0) of the cartoon's mouth, and (S, 2)
    `shape_measures` -> per frame the blend of the two nearest VIDEO_SHAPES (weights inverse to
    the distance, multiples of MOUTH_STEP summing to 1; one shape where the other's rounds to 0)."""
    points = np.column_stack([opening, width * WIDTH_WEIGHT])
    targets = shapes * np.array([1.0, WIDTH_WEIGHT])
    distance = np.linalg.norm(points[:, None, :] - targets[None, :, :], axis=2)
    nearest = np.argsort(distance, axis=1)[:, :2]
    blends = []
    steps = round(1 / MOUTH_STEP)
    for row, (a, b) in zip(distance, nearest):
        near, far = row[a], row[b]
        share = far / (near + far) if near + far > 0 else 1.0
        first = round(share * steps)
        pairs = ((VIDEO_SHAPES[a], first / steps), (VIDEO_SHAPES[b], (steps - first) / steps))
        blends.append(tuple(pair for pair in pairs if pair[1] > 0))
    return blends


def mix_mouths(first: tuple[tuple[str, float], ...], second: tuple[tuple[str, float], ...],
               share: float) -> tuple[tuple[str, float], ...]:
    """`share` of mouth blend `first` and 1 - share of `second` -> one blend (weights summing to 1,
    in steps of MOUTH_STEP, each shape once)."""
    weights: dict[str, float] = {}
    for pairs, part in ((first, share), (second, 1.0 - share)):
        for symbol, weight in pairs:
            weights[symbol] = weights.get(symbol, 0.0) + weight * part
    steps = round(1 / MOUTH_STEP)
    counts = {symbol: round(weight * steps) for symbol, weight in weights.items()}
    top = max(weights, key=lambda symbol: weights[symbol])
    counts[top] += steps - sum(counts.values())  # rounding's remainder on the largest
    return tuple((symbol, count / steps) for symbol, count in counts.items() if count > 0)


def video_mouths(tracking: Tracking, times: np.ndarray, face: FaceModel) -> list[tuple[tuple[str, float], ...]]:
    """The mouth blend (mouth_blends) of the cartoon `face` at each of (n,) `times` (s) from the
    tracked opening (above the rest gap, in MNS0, times OPEN_GAIN) and width (change in MW0, times
    WIDTH_GAIN), low-passed at MOUTH_CUTOFF."""
    mouth = low_pass(np.column_stack([tracking.measure("mouth_open"), tracking.measure("mouth_width")]),
                     tracking.fps, MOUTH_CUTOFF)
    clip_times = np.arange(len(mouth)) / tracking.fps
    mns0 = float(np.median(tracking.measure("nose_mouth")))
    mw0 = float(np.median(mouth[:, 1]))
    shut = float(np.percentile(mouth[:, 0], REST_PERCENTILE))
    opening = np.maximum(mouth[:, 0] - shut, 0) / mns0 * OPEN_GAIN
    width = (mouth[:, 1] / mw0 - 1) * WIDTH_GAIN
    return mouth_blends(np.interp(times, clip_times, opening), np.interp(times, clip_times, width),
                        shape_measures(face))


def drive(tracking: Tracking, base: Sequence[FaceState], fps: int, face: FaceModel,
          combine: bool = False) -> tuple[FaceState, ...]:
    """The cartoon's states at `fps` (frame i at i / fps s, one per state of `base`) with pose,
    blink, brow and mouth from `tracking`; `combine`: mix the mouth of `base` (the aligned
    shapes) with the video's (ALIGNED_SHARE), else the video's alone. See the module docstring."""
    rate = tracking.fps
    clip_times = np.arange(len(tracking.pose)) / rate
    times = np.arange(len(base)) / fps

    def at_frames(values: np.ndarray) -> np.ndarray:
        return np.interp(times, clip_times, values)

    pose = low_pass(tracking.pose, rate, SLOW_CUTOFF)
    pose = np.clip(pose - np.median(pose, axis=0), -MAX_ANGLE, MAX_ANGLE)
    opening = (tracking.measure("eye_left") + tracking.measure("eye_right")) / 2
    blink = at_frames(blink_amounts(opening))
    brow = at_frames(brow_amounts(low_pass((tracking.measure("brow_left") + tracking.measure("brow_right")) / 2,
                                           rate, SLOW_CUTOFF)))
    brow *= 1 - blink  # the mesh lifts its brow points as the lids close: no raise while blinking
    blends = video_mouths(tracking, times, face)
    angles = np.round(np.column_stack([at_frames(pose[:, k]) for k in range(3)]) / POSE_STEP) * POSE_STEP
    states = []
    for i, state in enumerate(base):
        mix = mix_mouths(state.mouth, blends[i], ALIGNED_SHARE) if combine else blends[i]
        states.append(replace(state, pose=Pose(*(float(a) for a in angles[i])), blink=round(float(blink[i]), 2),
                              brow=round(float(brow[i]), 2), mouth=mix))
    return tuple(states)
