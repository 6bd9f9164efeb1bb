"""Frames: the timeline sampled at a frame rate, one FaceState per frame (thesis 002, 5.4).

Between two key frames a value moves along an easing curve of u, the share of
the way from one key to the next (0..1):

- ``smoothstep`` 3u^2 - 2u^3 for mouth weights, blink and brow amounts: a shape
  settles into and out of each key frame, so each basic shape is seen
  clearly at its key while the lips never jump;
- ``cosine`` (1 - cos(pi u)) / 2 for head angles: a head accelerates and
  decelerates like a mass.

Values are quantised so identical consecutive frames compare equal and the SVG
writer can merge them: angles to 0.1 degree, amounts and mouth weights to 0.01. An
emotion's intensity and the lips' gamma go from key to key in a few equal steps
(EASE_STEP), along the easing curve: each step redraws the eyes, brows and mouth.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cartoonface.animate.idle import rounded_angles
from cartoonface.animate.timeline import Timeline, Track
from cartoonface.errors import OptionError
from cartoonface.face.emotion import EMOTIONS
from cartoonface.face.mouth import MOUTH_SYMBOLS
from cartoonface.face.state import MAX_ANGLE, MAX_GAZE, FaceState, Pose, trusted_face_state, trusted_pose, trusted_state

FPS_RANGE = (12, 60)  # frames per second allowed (default 30; docs/animation.md)
EASINGS = {
    "smoothstep": lambda u: u * u * (3.0 - 2.0 * u),
    "cosine": lambda u: 0.5 - 0.5 * np.cos(np.pi * u),
}
# An emotion's intensity and the lips' gamma (seed 000 eq. 18) ease from one key to the next in
# equal steps of at most this much (our choice; docs/emotions.md): each distinct value is a new
# drawing of the eyes, brows, nose and mouth, for every pose and mouth shape it meets. An eighth
# of an emotion at full intensity moves no point of the sample faces more than about 3 px
# (surprise's brows and dropped jaw, 22-24 px in all), as far as a full 0.4 s ease
# (behaviour.py EMOTION_EASE) moves them in one frame at its fastest (30 fps): the steps merge
# frames only where the ease is slow.
EASE_STEP = 0.125
# A nod bends the head down: Pose.tilt is the rotation about X and positive
# means the face looks down (face/state.py), so a nod of depth d is tilt +d.
NOD_SIGN = 1.0


def frame_times(timeline: Timeline, fps: int) -> np.ndarray:
    """(n,) seconds of the frames at `fps`: frame i shows time i / fps, and they cover the whole
    timeline, ceil(duration * fps) of them. `fps` an int in 12..60 (OptionError otherwise)."""
    if isinstance(fps, bool) or not isinstance(fps, int | np.integer) or not FPS_RANGE[0] <= fps <= FPS_RANGE[1]:
        low, high = FPS_RANGE
        raise OptionError(f"fps: {fps!r}; expected a whole number of frames per second from {low} to {high}")
    return np.arange(-(-timeline.duration * int(fps) // 1000)) / fps


def sample_frames(timeline: Timeline, fps: int) -> tuple[FaceState, ...]:
    """One FaceState per frame of frame_times(timeline, fps). Identical consecutive states are the
    same object."""
    return states_at(timeline, frame_times(timeline, fps))


def states_at(timeline: Timeline, times: np.ndarray | Sequence[float], sway: np.ndarray | None = None) -> tuple[FaceState, ...]:
    """The face state at each of `times` ((n,) seconds), interpolated between key frames.

    `sway`: (n, 3) degrees (tilt, turn, roll; animate/idle.py) added to the poses, the sums kept
    within +-MAX_ANGLE and rounded to 0.1 degree (idle.rounded_angles). Identical consecutive
    states are the same object.
    """
    t = np.asarray(times, dtype=float) * 1000.0
    mouth = _mouth(timeline.track("mouth"), t)
    blink, brow, smile = (_amount(timeline.track(name), t) for name in ("blink", "brow", "smile"))
    tilt, turn, nod, gaze_h, gaze_v = (_angle(timeline.track(name), t) for name in ("tilt", "turn", "nod", "gaze_h", "gaze_v"))
    pitch = NOD_SIGN * nod + 0.0
    feelings = _emotions(timeline, t)
    lips = _stepped(timeline.track("lips"), t) if any(feelings) else np.ones_like(t)
    # The mouth mixes and emotion names are made in range here; the numbers are checked at once, and
    # only when one is out of range (an edited actions.json) are the states made by FaceState's
    # checks, which name it.
    checked = (_within(MAX_ANGLE, pitch, turn, tilt) and _within(MAX_GAZE, gaze_h, gaze_v)
               and _within(0.5, blink - 0.5, brow - 0.5, smile - 0.5, lips - 0.5)  # each 0..1
               and all(0.0 <= amount <= 1.0 for feeling in feelings for _, amount in feeling))
    if sway is not None:
        if not checked:  # FaceState's checks name the number out of range before the sway clamps it
            states_at(timeline, times)
        pitch, turn, tilt = rounded_angles(np.stack([pitch, turn, tilt], axis=1) + sway).T
    columns = zip(blink.tolist(), brow.tolist(), smile.tolist(), pitch.tolist(), turn.tolist(), tilt.tolist(),
                  gaze_h.tolist(), gaze_v.tolist(), mouth, feelings, lips.tolist(), strict=True)
    state_of, pose_of = (trusted_face_state, trusted_pose) if checked else (FaceState, Pose)
    states: list[FaceState] = []
    previous = None
    for values in columns:
        if values != previous:
            eyes, brows, smiling, down, sideways, lean, look_h, look_v, mix, feeling, gamma = values
            states.append(state_of(pose_of(down, sideways, lean), eyes, smiling, brows, mix, look_h, look_v, feeling,
                                   gamma if feeling else 1.0))
            previous = values
        else:
            states.append(states[-1])
    return tuple(states)


def _within(limit: float, *values: np.ndarray | float) -> bool:
    """Whether every number of `values` (arrays or numbers) is finite with |x| <= `limit`."""
    return all(bool(np.all(np.abs(x) <= limit)) for x in values)


def _emotions(timeline: Timeline, t: np.ndarray) -> list[tuple[tuple[str, float], ...]]:
    """The emotions at times `t` (ms): ((name, intensity), ...) of those above 0, to 0.01 and in
    steps (_stepped), in EMOTIONS order; () where none is felt (or the timeline has no emotion
    tracks)."""
    tracks = {name: _stepped(timeline.track(f"emotion:{name}"), t)
              for name in EMOTIONS if f"emotion:{name}" in timeline.names}
    felt = {name: amounts.tolist() for name, amounts in tracks.items() if np.any(amounts > 0)}  # the others add nothing
    return [tuple((name, a) for name, a in zip(felt, column, strict=True) if a > 0)
            for column in zip(*felt.values(), strict=True)] if felt else [()] * len(t)


# A slow head move is drawn on twos (our choice, as animators do; it lightens the SVG, where every
# new pose redraws every part): a frame whose pose differs from both neighbours' by less than
# HOLD_STEP degrees on every axis keeps the pose of the frame before. 0.6 degree moves a point
# one FAPU d (the eye distance, 100 px on the sample faces) from the axis by about 1 px, for one
# frame: the precision the path data is written with (render/pathdata.py: whole pixels).
HOLD_STEP = 0.6  # degrees per frame (18 degrees per second at 30 fps)


def on_twos(states: Sequence[FaceState]) -> tuple[FaceState, ...]:
    """`states` (one per frame) with every second frame of a slow head move holding the pose of
    the frame before (HOLD_STEP), and every second frame of an emotion's ease holding the
    emotions and the lips' gamma of the frame before (an ease is slow at both ends and steps
    by EASE_STEP: held, the fastest part moves two steps at 15 frames a second, as animators
    draw on twos); fast head moves, the gaze, the mouth and the rest are unchanged."""
    poses = np.array([(s.pose.tilt, s.pose.turn, s.pose.roll) for s in states]).reshape(-1, 3)
    steps = np.append(np.abs(np.diff(poses, axis=0)).max(axis=1, initial=0.0), 0.0)  # (n,): to the next; 0 at the end
    odd = np.arange(1, len(states), 2)  # only odd frames change, and only from the (even) frame before
    slow = (steps[odd - 1] > 0.0) & (steps[odd - 1] < HOLD_STEP) & (steps[odd] < HOLD_STEP)  # > 0: a new pose
    out = list(states)
    for i in odd[slow].tolist():
        out[i] = trusted_state(out[i], pose=out[i - 1].pose)  # fields of checked states
    for i in odd.tolist():
        now, before = out[i], out[i - 1]
        if now is not before and (now.emotion, now.lips) != (before.emotion, before.lips):
            out[i] = trusted_state(now, emotion=before.emotion, lips=before.lips)
    return tuple(out)


def breaths_at(timeline: Timeline, times: np.ndarray | Sequence[float]) -> np.ndarray:
    """(n,) depth of the breath 0..1 (to 0.01) at each of `times` ((n,) seconds): the body's
    track, beside the face's states (animate/body.py)."""
    return _amount(timeline.track("breath"), np.asarray(times, dtype=float) * 1000.0)


def sample_breaths(timeline: Timeline, fps: int) -> np.ndarray:
    """(n,) depth of the breath at each frame of frame_times(timeline, fps)."""
    return breaths_at(timeline, frame_times(timeline, fps))


def _segments(track: Track, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For times `t` (ms): index of the key before, index of the key after, eased share 0..1.

    Before the first key the first key holds, after the last the last holds;
    at a time shared by several keys the last of them counts.
    """
    times = np.array([key.t for key in track.keys], dtype=float)
    before = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 1)
    after = np.minimum(before + 1, len(times) - 1)
    span = times[after] - times[before]
    share = np.clip(np.divide(t - times[before], span, out=np.zeros_like(t), where=span > 0), 0.0, 1.0)
    return before, after, EASINGS[track.easing](share)


def _values(track: Track, t: np.ndarray) -> np.ndarray:
    values = np.array([key.value for key in track.keys], dtype=float)
    before, after, eased = _segments(track, t)
    return values[before] + (values[after] - values[before]) * eased


def _amount(track: Track, t: np.ndarray) -> np.ndarray:
    """A 0..1 amount track at times `t` (ms), to 0.01."""
    return np.clip(np.round(_values(track, t), 2), 0.0, 1.0) + 0.0


def _stepped(track: Track, t: np.ndarray) -> np.ndarray:
    """A 0..1 amount track at times `t` (ms), to 0.01, moving from each key to the next in
    n = ceil(|change| / EASE_STEP) equal steps: the eased share rounded to a multiple of 1 / n,
    so each key is reached exactly and the steps follow the easing curve (short in the middle)."""
    values = np.array([key.value for key in track.keys], dtype=float)
    before, after, eased = _segments(track, t)
    change = values[after] - values[before]
    steps = np.maximum(np.ceil(np.round(np.abs(change) / EASE_STEP, 6)), 1.0)
    stepped = values[before] + change * np.round(eased * steps) / steps
    return np.clip(np.round(stepped, 2), 0.0, 1.0) + 0.0


def _angle(track: Track, t: np.ndarray) -> np.ndarray:
    """An angle track at times `t` (ms), degrees to 0.1 (no negative zero)."""
    return np.round(_values(track, t), 1) + 0.0


def _mouth(track: Track, t: np.ndarray) -> list[tuple[tuple[str, float], ...]]:
    """Mouth mixes at times `t` (ms): ((symbol, weight), ...) in MOUTH_SYMBOLS order, weights to 0.01."""
    shapes = np.array([MOUTH_SYMBOLS.index(key.value) for key in track.keys])
    before, after, eased = _segments(track, t)
    hundredths = np.round(eased * 100).astype(int)
    first, second = shapes[before], shapes[after]
    mixed = (first != second) & (hundredths > 0) & (hundredths < 100)
    # Each frame's mix as one number: a shape alone is its index, a mix of a, b at k hundredths is
    # past those; the few distinct mixes are made once (a 3-minute book: ~5,700 frames, ~1,000 mixes).
    count = len(MOUTH_SYMBOLS)
    codes = np.where(mixed, count + (first * count + second) * 101 + hundredths,
                     np.where(hundredths == 100, second, first))
    distinct, index = np.unique(codes, return_inverse=True)
    table = [_mix(code) for code in distinct.tolist()]
    return [table[i] for i in index.tolist()]


def _mix(code: int) -> tuple[tuple[str, float], ...]:
    """The mouth mix of a _mouth code: the shape of index `code`, or past len(MOUTH_SYMBOLS) shapes
    a and b at k hundredths of the way from a to b, in MOUTH_SYMBOLS order."""
    count = len(MOUTH_SYMBOLS)
    if code < count:
        return ((MOUTH_SYMBOLS[code], 1.0),)
    pair, k = divmod(code - count, 101)
    a, b = divmod(pair, count)
    from_a, to_b = (MOUTH_SYMBOLS[a], (100 - k) / 100), (MOUTH_SYMBOLS[b], k / 100)
    return (from_a, to_b) if a < b else (to_b, from_a)  # a != b
