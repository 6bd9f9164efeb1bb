"""Emotions (seed 000, 5.6 "moving templates D"): happy, sad, angry, fear, surprise,
disgust and wink as displacements of the model points in FAPU units.

Each emotion is defined once, on the reference face (samples/faces/female.json),
as the displacement of the points it names at intensity 1, every coordinate a
multiple of one FAPU (image y down: negative dy is up). Face/rbf.py carries a
template to any face: the named points move by the template times that face's
FAPUs, and the points no template names (cheeks, contour, forehead) follow by
RBF interpolation (seed 003, eq. 8-12). The displacement is linear in the
intensity 0..1, so emotions blend with each other, with the mouth shapes and
with blink / smile / brow, and interpolate between key frames.

Seed 000, eq. 18: FE = P(N + sum_i D_i + gamma D_l + (1 - gamma) L). The
emotion's displacement splits into D_i (brows, eyes, nose, mouth corners:
every point but the lips) and D_l (LIP_POINTS); `lip_split` returns the two
parts, and face/pose.py weighs D_l by the state's `lips` (gamma: 1 at rest, 0
while talking, animate/timeline.py). L, the mouth shape, is kept whole rather
than weighed by 1 - gamma: the shapes are made for a face at rest, and while
gamma is 1 the mouth is at rest (L = 0), so the two readings agree there. The coefficients are ours, chosen by looking at
the sample faces against the descriptions of the six basic expressions
(Ekman and Friesen's FACS action units: e.g. happy AU6+12, sad AU1+4+15,
surprise AU1+2+5+26); docs/emotions.md shows them.
"""

from __future__ import annotations

import math
import numbers
import numpy as np

from cartoonface.errors import OptionError
from cartoonface.face.model import POINT_INDEX, POINT_NAMES, FaceModel, Fapu
from cartoonface.face.mouth import JAW_CORNER_SHARE
from cartoonface.face.rbf import deform

EMOTIONS: tuple[str, ...] = ("happy", "sad", "angry", "fear", "surprise", "disgust", "wink")
EMOTION_INDEX: dict[str, int] = {name: i for i, name in enumerate(EMOTIONS)}

# The lips of seed 000 eq. 18 (D_l): the points that open and shape the mouth, and the chin
# and jaw corners that follow them. The mouth corners 8.3 / 8.4 are not among them: they
# carry the emotion (a smile, a frown) through speech as the brows do, while the opening
# belongs to the syllables (a surprised 'm' still closes the lips).
LIP_POINTS: tuple[str, ...] = ("8.1", "8.2", "8.9", "8.10", "2.2", "2.3", "2.1", "2.13", "2.14")

# Image-left / image-right pairs; a symmetric entry names the image-left point
# and its dx, the image-right point gets -dx (the face's mirror image).
MIRROR: dict[str, str] = {
    "4.2": "4.1", "4.4": "4.3", "4.4a": "4.3a", "4.6": "4.5",
    "3.2": "3.1", "3.4": "3.3", "3.12": "3.7", "3.8": "3.11",
    "8.4": "8.3", "8.9": "8.10", "9.2": "9.1", "9.4": "9.5", "9.14": "9.13", "9.6": "9.7",
}
# Points every template holds (zero where not named): the features the renderer
# draws from them, the eyeball centres (the gaze places the pupils), the jaw
# corners (they follow the chin, as in face/mouth.py) and the ears. The points
# left (cheeks 10.7-10.10, forehead and temples 11.x) move only through the RBF
# (face/rbf.py) or not at all (plain FAPU scaling).
FEATURE_POINTS: tuple[str, ...] = (
    "4.1", "4.2", "4.3", "4.4", "4.5", "4.6", "4.3a", "4.4a",
    "3.1", "3.2", "3.3", "3.4", "3.7", "3.8", "3.11", "3.12",
    "8.1", "8.2", "8.3", "8.4", "8.9", "8.10", "2.2", "2.3", "2.1",
    "9.1", "9.2", "9.4", "9.5", "9.6", "9.7", "9.13", "9.14", "9.15",
    "3.5", "3.6", "2.13", "2.14", "10.1", "10.2",
)

# Points the RBF would move that every emotion holds still (our choice; docs/emotions.md): the
# ears' attachments 10.7 / 10.8 (an ear does not move with the face's muscles; moved, its lobe
# rose with a smile and every emotion redrew the ears) and, where the hair's front layer covers
# it, the forehead's contour 11.1, 11.2a, 11.3a (face/lift.py: the fringe does not move with
# emotions; the contour's moves were hidden under it, but where it dipped, in a wink, the skin's
# top flattened the hairline). Held, their drawings are shared across emotions in an animation.
EARS = ("10.7", "10.8")
FOREHEAD = ("11.1", "11.2a", "11.3a")
# The face's contour, a closed ring (face/lift.py's ring of silhouette points): a point of it
# that no template names moves only across the contour, along its normal (the chord of its
# neighbours turned a quarter), and not at all where that move stays under ACROSS_MIN d at
# intensity 1 (a pixel on the samples, d = 100). The RBF moves the cheeks 10.9 / 10.10 and the temples 11.2 / 11.3 mostly along
# the contour (up to 5 px at intensity 1 on the samples; across it, the cheeks up to 1.5 px,
# puffed out by a smile, the temples under 0.7 px): a slide along the outline changes none of
# its pixels, and the animation's path data are whole pixels (render/pathdata.py), so a move
# under one pixel only changes which drawings are alike.
ACROSS_MIN = 0.01
CONTOUR = ("11.2", "11.2a", "11.1", "11.3a", "11.3", "10.9", "2.13", "2.1", "2.14", "10.10")

Move = tuple[str, float, str, float, str]  # (point, dx coefficient, dx FAPU, dy coefficient, dy FAPU)


def _both(point: str, dx: float, dx_unit: str, dy: float, dy_unit: str) -> tuple[Move, Move]:
    """A move of an image-left point and its mirror image on the image right."""
    return (point, dx, dx_unit, dy, dy_unit), (MIRROR[point], -dx, dx_unit, dy, dy_unit)


def _brows(inner: float, top: float, arch: float, outer: float, inward: float = 0.0) -> tuple[Move, ...]:
    """Both eyebrows: dy of the inner point 4.2, top 4.4, 4.4a and outer end 4.6 in EyebrowH,
    the inner points pulled `inward` d towards the nose (positive: together)."""
    return (*_both("4.2", inward, "d", inner, "eyebrow_h"), *_both("4.4", 0.5 * inward, "d", top, "eyebrow_h"),
            *_both("4.4a", 0.0, "d", arch, "eyebrow_h"), *_both("4.6", 0.0, "d", outer, "eyebrow_h"))


def _lids(upper: float, lower: float) -> tuple[Move, ...]:
    """Both eyes: dy of the upper lid 3.2 / 3.1 and the lower lid 3.4 / 3.3 in LeftEyeH / RightEyeH."""
    return (("3.2", 0.0, "d", upper, "left_eye_h"), ("3.1", 0.0, "d", upper, "right_eye_h"),
            ("3.4", 0.0, "d", lower, "left_eye_h"), ("3.3", 0.0, "d", lower, "right_eye_h"))


def _corners(out: float, dy: float) -> tuple[Move, ...]:
    """Both mouth corners 8.4 / 8.3: `out` MW0 away from the centre, dy in MNS0."""
    return _both("8.4", -out, "mw0", dy, "mns0")


def _jaw(drop: float) -> tuple[Move, ...]:
    """The chin 2.1 down by `drop` MNS0 and the jaw corners by face/mouth.py's JAW_CORNER_SHARE of it."""
    return (("2.1", 0.0, "d", drop, "mns0"), ("2.13", 0.0, "d", JAW_CORNER_SHARE * drop, "mns0"),
            ("2.14", 0.0, "d", JAW_CORNER_SHARE * drop, "mns0"))


# Our coefficients (see the module docstring), at intensity 1 on any face.
TEMPLATES: dict[str, tuple[Move, ...]] = {
    # AU6 cheek raiser (lower lids up), AU12 lip corner puller; brows lifted a little
    "happy": (
        *_brows(-0.25, -0.35, -0.3, -0.15), *_lids(0.06, -0.3), *_corners(0.12, -0.5),
        *_both("8.9", -0.04, "mw0", -0.12, "mns0"), ("8.1", 0.0, "d", -0.1, "mns0"),
        ("2.2", 0.0, "d", -0.06, "mns0"), ("8.2", 0.0, "d", 0.04, "mns0"),
        *_both("9.2", -0.02, "d", -0.02, "d"),
    ),
    # AU1 inner brow raiser + AU4 brow lowerer (oblique brows), drooping lids, AU15 corners down
    "sad": (
        *_brows(-0.9, -0.1, 0.25, 0.45, inward=0.03), *_lids(0.22, -0.04), *_corners(-0.03, 0.45),
        *_both("8.9", 0.0, "mw0", 0.08, "mns0"), ("8.1", 0.0, "d", 0.06, "mns0"),
        ("8.2", 0.0, "d", -0.1, "mns0"), ("2.3", 0.0, "d", -0.02, "mns0"),
    ),
    # AU4 brows down and together, AU5 upper lid raised + AU7 lower lid tightened, AU24 lips pressed
    "angry": (
        *_brows(1.0, 0.5, 0.1, -0.3, inward=0.05), *_lids(-0.05, -0.25), *_corners(-0.08, 0.15),
        *_both("8.9", 0.02, "mw0", 0.08, "mns0"), ("8.1", 0.0, "d", 0.06, "mns0"),
        ("8.2", 0.0, "d", -0.16, "mns0"), ("2.2", 0.0, "d", 0.02, "mns0"),
        *_both("9.2", -0.03, "d", -0.015, "d"),
    ),
    # AU1+2+4 brows up and drawn together, AU5 lids wide, AU20 lips stretched, AU25 parted
    "fear": (
        *_brows(-1.0, -0.6, -0.4, -0.1, inward=0.04), *_lids(-0.25, -0.1), *_corners(0.12, 0.2),
        ("8.2", 0.0, "d", 0.3, "mns0"), ("2.3", 0.0, "d", 0.3, "mns0"), *_jaw(0.3),
        *_both("8.9", -0.03, "mw0", -0.02, "mns0"),
    ),
    # AU1+2 brows high and round, AU5 lids wide, AU26 jaw drop: a round open mouth
    "surprise": (
        *_brows(-1.2, -1.4, -1.2, -0.7), *_lids(-0.3, 0.08), *_corners(-0.08, 0.3),
        ("8.1", 0.0, "d", -0.1, "mns0"), *_both("8.9", 0.02, "mw0", -0.1, "mns0"), ("2.2", 0.0, "d", -0.08, "mns0"),
        ("8.2", 0.0, "d", 0.9, "mns0"), ("2.3", 0.0, "d", 0.85, "mns0"), *_jaw(0.9),
    ),
    # AU9 nose wrinkler, AU10 upper lip raiser (stronger on the image right), brows lowered
    "disgust": (
        *_brows(0.6, 0.35, 0.3, 0.1), *_lids(0.1, -0.3),
        ("8.4", 0.0, "mw0", 0.2, "mns0"), ("8.3", 0.02, "mw0", -0.05, "mns0"),
        ("8.9", 0.0, "mw0", -0.12, "mns0"), ("8.10", 0.0, "mw0", -0.3, "mns0"),
        ("8.1", 0.0, "d", -0.22, "mns0"), ("2.2", 0.0, "d", -0.18, "mns0"),
        ("8.2", 0.0, "d", 0.08, "mns0"), ("2.3", 0.0, "d", 0.02, "mns0"),
        *_both("9.2", -0.02, "d", -0.04, "d"), *_both("9.4", 0.0, "d", -0.03, "d"), ("9.15", 0.0, "d", -0.02, "d"),
    ),
    # The image-left eye shut (as a blink, face/expression.py), its brow down, that mouth corner up
    "wink": (
        ("3.2", 0.0, "d", 0.8, "left_eye_h"), ("3.4", 0.0, "d", -0.2, "left_eye_h"),
        ("3.1", 0.0, "d", 0.05, "right_eye_h"), ("3.3", 0.0, "d", -0.1, "right_eye_h"),
        ("4.2", 0.0, "d", 0.35, "eyebrow_h"), ("4.4", 0.0, "d", 0.45, "eyebrow_h"),
        ("4.4a", 0.0, "d", 0.45, "eyebrow_h"), ("4.6", 0.0, "d", 0.3, "eyebrow_h"),
        ("4.1", 0.0, "d", -0.2, "eyebrow_h"), ("4.3", 0.0, "d", -0.25, "eyebrow_h"),
        ("8.4", -0.08, "mw0", -0.45, "mns0"), ("8.3", 0.03, "mw0", -0.1, "mns0"),
        ("8.9", -0.02, "mw0", -0.12, "mns0"),
    ),
}


def template_points(name: str) -> tuple[str, ...]:
    """The points a template holds: FEATURE_POINTS and any other point it names."""
    named = [move[0] for move in TEMPLATES[name]]
    return FEATURE_POINTS + tuple(dict.fromkeys(p for p in named if p not in FEATURE_POINTS))


def template_fapu(name: str, fapu: Fapu) -> np.ndarray:
    """(len(template_points(name)), 2) pixel displacement of the template's points at
    intensity 1, each coefficient times `fapu`'s (a face's Fapu) unit: plain FAPU scaling."""
    points = template_points(name)
    where = {p: i for i, p in enumerate(points)}
    out = np.zeros((len(points), 2))
    for point, dx, dx_unit, dy, dy_unit in TEMPLATES[name]:
        out[where[point]] += (dx * getattr(fapu, dx_unit), dy * getattr(fapu, dy_unit))
    return out


def scaled_displacements(face: FaceModel) -> np.ndarray:
    """(len(EMOTIONS), P, 2) image displacement of every model point at intensity 1 by plain
    FAPU scaling: the points a template names move, no other point does."""
    out = np.zeros((len(EMOTIONS), len(POINT_NAMES), 2))
    for k, name in enumerate(EMOTIONS):
        rows = [POINT_INDEX[p] for p in template_points(name)]
        out[k, rows] = template_fapu(name, face.fapu)
    return out


LIP_ROWS = np.array([POINT_INDEX[p] for p in LIP_POINTS])


def lip_split(displacements: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(..., P, 2) displacements split into (D_i, D_l) of seed 000 eq. 18: every point but
    LIP_POINTS, and LIP_POINTS only; the two sum to the input."""
    lips = np.zeros_like(displacements)
    lips[..., LIP_ROWS, :] = displacements[..., LIP_ROWS, :]
    return displacements - lips, lips


def check_emotion(name: object, what: str) -> str:
    """`name` if it is one of EMOTIONS, else OptionError naming `what` and the choices."""
    if name not in EMOTIONS:
        raise OptionError(f"{what} {name!r} is unknown; expected one of {', '.join(EMOTIONS)}")
    return str(name)


def check_intensity(value: object, what: str) -> float:
    """`value` as a float in 0..1, else OptionError naming `what`."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise OptionError(f"{what} is {value!r}; expected a number from 0 to 1")
    if not 0.0 <= float(value) <= 1.0:
        raise OptionError(f"{what} {float(value):g} is out of range; expected 0 to 1")
    return float(value)


def emotion_displacements(face: FaceModel, widths: str | None = "cluster") -> np.ndarray:
    """(len(EMOTIONS), P, 2) image displacement of every model point of `face` at intensity 1.

    The template's points move by their FAPU terms on this face; `widths` a face/rbf.py
    width rule moves every other point by the RBF (seed 003, eq. 8-12), as the animation
    draws it (`drawn_moves`: the contour only across itself, the ears and a covered forehead
    still); None keeps them still (plain FAPU scaling, `scaled_displacements`).
    """
    if widths is None:
        return scaled_displacements(face)
    out = np.zeros((len(EMOTIONS), len(POINT_NAMES), 2))
    for k, name in enumerate(EMOTIONS):
        out[k] = deform(face.points, template_points(name), template_fapu(name, face.fapu), widths)
    return drawn_moves(face, out)


def drawn_moves(face: FaceModel, moves: np.ndarray) -> np.ndarray:
    """`moves` ((E, P, 2) pixel displacements of `face`'s points, one row per emotion at
    intensity 1) as the animation draws them: each CONTOUR point no template names moved only
    across the contour, by nothing where that is under ACROSS_MIN d; held_points(face) still."""
    out = moves.copy()
    ring = np.array([POINT_INDEX[p] for p in CONTOUR])
    chords = face.points[np.roll(ring, -1)] - face.points[np.roll(ring, 1)]
    normals = np.column_stack([-chords[:, 1], chords[:, 0]])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
    free = np.array([k for k, p in enumerate(CONTOUR) if p not in FEATURE_POINTS])
    across = np.einsum("epi,pi->ep", out[:, ring[free]], normals[free])
    across[np.abs(across) < ACROSS_MIN * face.fapu.d] = 0.0
    out[:, ring[free]] = across[:, :, None] * normals[free][None]
    out[:, [POINT_INDEX[p] for p in held_points(face)]] = 0.0
    return out


def held_points(face: FaceModel) -> tuple[str, ...]:
    """The points the emotions of `face` hold still although the RBF would move them: EARS, and
    FOREHEAD when the hair reaches above the forehead's top 11.1, where the front layer covers it
    (face/lift.py builds no front layer over a bare forehead)."""
    covered = len(face.hair) > 0 and float(face.hair[:, 1].min()) < float(face.point("11.1")[1])
    return EARS + FOREHEAD if covered else EARS


def emotion_basis(face: FaceModel) -> np.ndarray:
    """(2 len(EMOTIONS), P, 2) the emotions' D_i (rows 0..6) then D_l (rows 7..13) of seed
    000 eq. 18 at intensity 1 on `face` (RBF transfer): face/pose.py's rig rows."""
    rest, lips = lip_split(emotion_displacements(face))
    return np.concatenate([rest, lips])


def emotion_coefficients(emotion: tuple[tuple[str, float], ...], lips: float) -> np.ndarray:
    """(2 len(EMOTIONS),) weights of emotion_basis's rows for a FaceState's `emotion`
    ((name, intensity) pairs) and `lips` (gamma of eq. 18)."""
    coef = np.zeros(2 * len(EMOTIONS))
    for name, intensity in emotion:
        coef[EMOTION_INDEX[name]] += intensity
        coef[len(EMOTIONS) + EMOTION_INDEX[name]] += intensity * lips
    return coef
