"""What a face shows at one moment: head pose, expression amounts, mouth mix."""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, replace

from cartoonface.errors import OptionError
from cartoonface.face.emotion import check_emotion, check_intensity
from cartoonface.face.mouth import MOUTH_SYMBOLS

# Thesis 002, 2.3.1 / 2.4.3: the generic depth model holds for slight head
# rotations; the system draws poses within +-15 degrees about each axis.
MAX_ANGLE = 15.0
# Gaze: how far the eyes turn from looking at the viewer, degrees, each axis.
# Bahill, Adler and Stark (1975), "Most naturally occurring human saccades have
# magnitudes of 15 degrees or less": larger gaze shifts are made with the head.
MAX_GAZE = 15.0
# Mouth weights must sum to 1 within this tolerance.
WEIGHT_TOLERANCE = 1e-6


def _finite(value: object, name: str) -> float:
    """value as a float; OptionError unless it is a finite real number (numpy ones too)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise OptionError(f"{name} is {value!r}; expected a number")
    return float(value)


@dataclass(frozen=True)
class Pose:
    """Head rotation in degrees (thesis 002, 2.4.3.1; positive = counter-clockwise).

    tilt: about X (positive: the face looks down); turn: about Y (positive: the
    nose moves to the image right); roll: about Z (positive: the top of the head
    moves to the image left). Each within +-MAX_ANGLE, else OptionError.
    """

    tilt: float = 0.0
    turn: float = 0.0
    roll: float = 0.0

    def __post_init__(self) -> None:
        for name in ("tilt", "turn", "roll"):
            value = _finite(getattr(self, name), name)
            if abs(value) > MAX_ANGLE:
                raise OptionError(f"{name} {value:g} degrees is out of range; expected -15 to 15")
            object.__setattr__(self, name, value)


@dataclass(frozen=True)
class FaceState:
    """Pose, expression amounts blink / smile / brow in 0..1, the mouth and the gaze.

    mouth: (symbol, weight) pairs, symbols from MOUTH_SYMBOLS, weights >= 0
    summing to 1, so key frames interpolate by blending weights.
    gaze_h, gaze_v: the eyes' turn away from the viewer in degrees (gaze_h
    positive: towards the image right; gaze_v positive: down), each within
    +-MAX_GAZE; 0, 0 looks at the viewer.
    emotion: (name, intensity) pairs, names from face/emotion.py EMOTIONS, each
    once, intensities 0..1 (several blend, e.g. while one fades into another);
    () is neutral. lips: gamma of seed 000 eq. 18, the share 0..1 of the
    emotions' lip displacement shown (1 at rest, less while talking).
    OptionError for anything out of range.
    """

    pose: Pose = Pose()
    blink: float = 0.0
    smile: float = 0.0
    brow: float = 0.0
    mouth: tuple[tuple[str, float], ...] = (("m", 1.0),)
    gaze_h: float = 0.0
    gaze_v: float = 0.0
    emotion: tuple[tuple[str, float], ...] = ()
    lips: float = 1.0

    def __post_init__(self) -> None:
        if not isinstance(self.pose, Pose):
            raise OptionError(f"pose is {self.pose!r}; expected a Pose")
        for name in ("blink", "smile", "brow", "lips"):
            value = _finite(getattr(self, name), name)
            if not 0.0 <= value <= 1.0:
                raise OptionError(f"{name} {value:g} is out of range; expected 0 to 1")
            object.__setattr__(self, name, value)
        for name in ("gaze_h", "gaze_v"):
            value = _finite(getattr(self, name), name)
            if abs(value) > MAX_GAZE:
                raise OptionError(f"{name} {value:g} degrees is out of range; expected -{MAX_GAZE:g} to {MAX_GAZE:g}")
            object.__setattr__(self, name, value)
        seen = set()
        for pair in self.emotion:
            if not isinstance(pair, tuple) or len(pair) != 2:
                raise OptionError(f"emotion entry {pair!r}; expected a (name, intensity) pair")
            name = check_emotion(pair[0], "emotion")
            if name in seen:
                raise OptionError(f"emotion {name!r} is given twice; expected each emotion once")
            seen.add(name)
            check_intensity(pair[1], f"intensity of {name}")
        if not self.mouth:
            raise OptionError("mouth is empty; expected (symbol, weight) pairs")
        total = 0.0
        for pair in self.mouth:
            if not isinstance(pair, tuple) or len(pair) != 2:
                raise OptionError(f"mouth entry {pair!r}; expected a (symbol, weight) pair")
            symbol, weight = pair
            if symbol not in MOUTH_SYMBOLS:
                raise OptionError(f"mouth symbol {symbol!r} is unknown; expected one of {' '.join(MOUTH_SYMBOLS)}")
            weight = _finite(weight, f"mouth weight of {symbol!r}")
            if weight < 0:
                raise OptionError(f"mouth weight of {symbol!r} is {weight:g}; expected >= 0")
            total += weight
        if abs(total - 1.0) > WEIGHT_TOLERANCE:
            raise OptionError(f"mouth weights sum to {total:g}; expected 1")

    def with_mouth(self, symbol: str) -> FaceState:
        """This state with the mouth set to one basic shape (OptionError if unknown)."""
        return replace(self, mouth=((symbol, 1.0),))


def trusted_pose(tilt: float, turn: float, roll: float) -> Pose:
    """A Pose of angles the program has already made finite floats within +-MAX_ANGLE (clamped and
    rounded, or taken from checked poses), made without Pose's checks: the frame loops make
    thousands (issue 16). Anything from a user goes through Pose itself."""
    pose = object.__new__(Pose)
    pose.__dict__.update(tilt=tilt, turn=turn, roll=roll)
    return pose


def trusted_state(state: FaceState, **changes: object) -> FaceState:
    """`dataclasses.replace(state, **changes)` without FaceState's checks, for a checked `state`
    and changes the program made in range (a trusted_pose, or fields of other checked states)."""
    new = object.__new__(FaceState)
    new.__dict__.update(state.__dict__, **changes)
    return new


def trusted_face_state(pose: Pose, blink: float, smile: float, brow: float, mouth: tuple[tuple[str, float], ...],
                       gaze_h: float, gaze_v: float, emotion: tuple[tuple[str, float], ...], lips: float) -> FaceState:
    """`FaceState(pose, blink, ...)` of every field without its checks, for fields the program made in
    range (a trusted_pose, numbers checked at once with numpy): frames.states_at makes one a frame."""
    new = object.__new__(FaceState)
    new.__dict__.update(pose=pose, blink=blink, smile=smile, brow=brow, mouth=mouth, gaze_h=gaze_h, gaze_v=gaze_v,
                        emotion=emotion, lips=lips)
    return new
