"""Turned faces (thesis 002, 2.4.3, Alg. 2.3): the posed 2D points of one FaceState.

pose_face applies the expressions and the mouth to the model points, moves
the additional points with them (Alg. 2.1), moves every outline point (face
contour and hair) to where the view grazes its cross-section (face/lift.py's
Silhouette: our continuous form of the hair depth shift and the contour
replacement of Alg. 2.3 steps 1-2 and 5-6), rotates (2.4.3.1),
projects to the image, picks the nose side (step 8) and turns the
eyeballs to the fixed focus (2.4.3.2), moved by the state's gaze. Everything per call is a handful of
numpy operations on arrays precomputed once per lifted face (the Rig).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cartoonface.face.emotion import emotion_basis, emotion_coefficients
from cartoonface.face.expression import EXPRESSIONS, LOWER_LIDS, UPPER_LIDS, expression_displacements
from cartoonface.face.lift import LIFTED_INDEX, LIFTED_NAMES, LiftedFace
from cartoonface.face.model import POINT_NAMES
from cartoonface.face.mouth import MOUTH_INDEX, MOUTH_SYMBOLS, shape_displacements
from cartoonface.face.state import FaceState, Pose

# Thesis 002, 2.4.3.2: eyeball radius 0.3 d; focus at (EyeMid.x, EyeMid.y, 15 d).
EYEBALL_RADIUS = 0.3
FOCUS_DEPTH = 15.0
# Eyes in PosedFace.pupils order: image-left eye (3.6, radius r1), image-right (3.5, r2).
EYEBALLS = ("3.6", "3.5")
# Upper and lower lid of each eye, same order.
EYE_LIDS = (("3.2", "3.4"), ("3.1", "3.3"))
# Our addition to 2.4.3.2: the thesis's gaze keeps the eyes on the viewer, so at
# tilt +15 an iris slides up under its lid. After the gaze, each iris centre is
# kept at least IRIS_KEEP x its radius inside the lids, measured along the line
# from the upper to the lower lid point (never past the middle of the opening):
# then at least about half of an open eye's iris shows at every pose.
IRIS_KEEP = 0.35


@dataclass(frozen=True, eq=False)
class PosedFace:
    """The 2D drawing points of one face state.

    xy: (N, 2) image pixels in LIFTED_NAMES order, the outline points (temples,
        cheeks, jaw corners) on their silhouettes, rows 3.6 / 3.5 the gazing pupils.
    hair: (H, 2) image pixels: the hair's back layer.
    front: (F, 2) image pixels: the hair's front layer (face/lift.py FRONT_NAMES).
    pupils: (2, 2) iris centres of the image-left eye (3.6) and image-right
        eye (3.5); the drawing clips each iris circle by its eye outline
        (3.12, 3.2, 3.8, 3.4 / 3.7, 3.1, 3.11, 3.3).
    iris_r: (2,) iris radii r1, r2 in pixels, same order.
    nose_side: +1 draw the nose bridge through 9.7, C, 9.13 (turn > 0, step 8),
        -1 through 9.6, C, 9.14.
    mouth: (len(MOUTH_SYMBOLS),) weights of the basic mouth shapes (the drawing
        shows their teeth, tongue and bite: face/mouth.py shown_parts).
    """

    xy: np.ndarray
    hair: np.ndarray
    front: np.ndarray
    pupils: np.ndarray
    iris_r: np.ndarray
    nose_side: int
    mouth: np.ndarray

    def p(self, name: str) -> np.ndarray:
        """(2,) image position of a lifted point by name."""
        return self.xy[LIFTED_INDEX[name]]


def rotation_matrix(pose: Pose) -> np.ndarray:
    """(3, 3) rotation in the local frame (x right, y up, z front), thesis 2.4.3.1.

    First about Y by turn (beta), then about X by tilt (alpha), then about Z by
    roll (gamma); positive angles counter-clockwise. The thesis's
    z2 = y1 sin(a) - z1 cos(a) is a sign slip (it would mirror depth); we use
    z2 = y1 sin(a) + z1 cos(a), which projects to the same image. rotation_matrices of the one pose.
    """
    return rotation_matrices([pose])[0]


def rotation_matrices(poses: Sequence[Pose]) -> np.ndarray:
    """(S, 3, 3): rotation_matrix of each of `poses`, its sines and cosines by `math` (as one pose's
    were), the products multiplied out over all S at once (the same numbers)."""
    a, b, g = (np.array([math.radians(getattr(pose, name)) for pose in poses], dtype=float)
               for name in ("tilt", "turn", "roll"))
    ca, sa, cb, sb, cg, sg = (np.array(list(map(function, angle.tolist())), dtype=float)
                              for angle in (a, b, g) for function in (math.cos, math.sin))
    # Rz(g) @ Rx(a) @ Ry(b), multiplied out
    return np.stack([
        cg * cb - sg * sa * sb, -sg * ca, cg * sb + sg * sa * cb,
        sg * cb + cg * sa * sb, cg * ca, sg * sb - cg * sa * cb,
        -ca * sb, sa, ca * cb,
    ], axis=1).reshape(-1, 3, 3)


def rotate(points: np.ndarray, pose: Pose) -> np.ndarray:
    """(M, 3) local points rotated by the pose (Alg. 2.3 step 3, before projection)."""
    return points @ rotation_matrix(pose).T


@dataclass(frozen=True, eq=False)
class Rig:
    """Per-face arrays for pose_face, in image orientation (x right, y down, z front)
    relative to the rotation origin. Built once per LiftedFace by rig()."""

    neutral: np.ndarray  # (N*2,) lifted image points minus origin, flattened
    basis: np.ndarray  # (12 + 3 + 14, N*2) mouth shapes, expressions, emotions (D_i, D_l), flattened
    template: np.ndarray  # (N + H + F, 3) column 2 filled: depths, hair and front layer points
    outline: tuple[np.ndarray, ...]  # silhouette rows of the template, normals (k, 2), reach, front, back (k,)
    centres: np.ndarray  # (2, 3) eyeball centres
    focus: np.ndarray  # (3,)
    radius: float  # eyeball radius, pixels
    origin: np.ndarray  # (2,)
    iris_r: np.ndarray  # (2,)
    lids: tuple[np.ndarray, np.ndarray]  # flat indices of upper / lower lid y
    pupil_rows: np.ndarray  # rows of 3.6, 3.5 in xy
    lid_rows: tuple[np.ndarray, np.ndarray]  # rows of the upper / lower lid of each eye in xy


def _rows(names: tuple[str, ...]) -> np.ndarray:
    return np.array([LIFTED_INDEX[n] for n in names])


@functools.lru_cache(maxsize=16)
def rig(lifted: LiftedFace) -> Rig:
    """The precomputed arrays of pose_face for one lifted face (cached by identity)."""
    face = lifted.face
    n, p = len(LIFTED_NAMES), len(POINT_NAMES)
    flip = np.array([1.0, -1.0, 1.0])
    image_rel = lifted.local[:, :2] * flip[:2]  # local -> image orientation, origin-relative
    model_moves = np.concatenate([shape_displacements(face), expression_displacements(face), emotion_basis(face)])
    basis = (model_moves.reshape(len(model_moves), 2 * p) @ lifted.depends.T)
    h = len(lifted.hair)
    template = np.zeros((n + h + len(lifted.front), 3))
    template[:n, 2] = lifted.local[:, 2]
    template[n:n + h] = lifted.hair * flip
    template[n + h:] = lifted.front * flip
    outline = lifted.silhouette
    d = face.fapu.d
    eyes = _rows(EYEBALLS)
    pupils = lifted.local[eyes]
    eye_mid = pupils.mean(axis=0)
    focus_local = np.array([eye_mid[0], eye_mid[1], FOCUS_DEPTH * d])
    toward = focus_local - pupils
    centres_local = pupils - EYEBALL_RADIUS * d * toward / np.linalg.norm(toward, axis=1, keepdims=True)
    upper = np.array([2 * LIFTED_INDEX[POINT_NAMES[i]] + 1 for i in UPPER_LIDS])
    lower = np.array([2 * LIFTED_INDEX[POINT_NAMES[i]] + 1 for i in LOWER_LIDS])
    iris_r = np.array([face.fapu.r1, face.fapu.r2])
    iris_r.flags.writeable = False
    return Rig(
        neutral=image_rel.ravel().copy(),
        basis=basis,
        template=template,
        centres=centres_local * flip,
        focus=focus_local * flip,
        radius=EYEBALL_RADIUS * d,
        origin=np.asarray(lifted.origin, dtype=float),
        iris_r=iris_r,
        lids=(upper, lower),
        pupil_rows=eyes,
        lid_rows=(_rows(tuple(u for u, _ in EYE_LIDS)), _rows(tuple(lo for _, lo in EYE_LIDS))),
        outline=(outline.rows, outline.normals * flip[:2], outline.reach, outline.front, outline.back),
    )


def _keep_in_lids(pupils: np.ndarray, upper: np.ndarray, lower: np.ndarray, iris_r: np.ndarray) -> np.ndarray:
    """(S, 2, 2) iris centres moved along the upper-to-lower lid line (all (S, 2, 2) image
    pixels) so that each lies at least IRIS_KEEP x its radius (iris_r (2,)) inside
    the lids, or in the middle of an opening narrower than that."""
    axis = lower - upper
    length2 = np.maximum((axis * axis).sum(axis=-1), 1e-12)
    t = ((pupils - upper) * axis).sum(axis=-1) / length2
    margin = np.minimum(0.5, IRIS_KEEP * iris_r / np.sqrt(length2))
    return pupils + (np.clip(t, margin, 1.0 - margin) - t)[..., None] * axis


def _graze(q: np.ndarray, outline: tuple[np.ndarray, ...], view: np.ndarray) -> None:
    """Move the outline points of `q` (S, M, 3, image orientation, before the rotation) in place
    to the points of their cross-sections (face/lift.py's Silhouette) that the view grazes.

    `outline`: the rig's rows (k,), normals (k, 2) in image orientation, reach, front and
    back depths (k,) in pixels; `view` (S, 3): the direction to the viewer in the same frame
    (the third row of each rotation). A cross-section is a half ellipse from the point
    inwards, semi-axes reach (along -normal) and front (forwards), and one backwards
    (depth `back`); the view grazes it where the ellipse's normal is perpendicular to the
    view: at angle t from the front with tan t = reach * view_z / (depth * -(normal . view)).
    Seen from the front (normal . view = 0) every point stays where it is."""
    rows, normals, reach, front, back = outline
    along = (normals @ view[:, :2, None])[..., 0]  # (S, k); < 0: the point's side turns away (the far side)
    depth = np.where(along < 0, front, back)
    sine, cosine = reach * view[:, 2:], depth * along  # cosine with its sign turned: -depth * along
    scale = 1.0 / np.sqrt(sine * sine + cosine * cosine)
    move = np.empty((len(view), len(rows), 3))
    move[..., :2] = normals * (reach * (sine * scale - 1.0))[..., None]
    move[..., 2] = depth * cosine * -scale
    q[:, rows] += move


_N_MOUTH = len(MOUTH_SYMBOLS)
_N_COEF = _N_MOUTH + len(EXPRESSIONS)


@dataclass(frozen=True, eq=False)
class PosedFaces:
    """S posed faces at once: PosedFace's fields with a leading axis of S (xy (S, N, 2),
    hair (S, H, 2), front (S, F, 2), pupils (S, 2, 2), nose_side (S,) int, mouth (S, 12)),
    the iris radii (2,) shared. `faces[i]` is the PosedFace of state i (views, no copies)."""

    xy: np.ndarray
    hair: np.ndarray
    front: np.ndarray
    pupils: np.ndarray
    iris_r: np.ndarray
    nose_side: np.ndarray
    mouth: np.ndarray

    def __len__(self) -> int:
        return len(self.xy)

    def __getitem__(self, index: int) -> PosedFace:
        return PosedFace(xy=self.xy[index], hair=self.hair[index], front=self.front[index],
                         pupils=self.pupils[index], iris_r=self.iris_r, nose_side=int(self.nose_side[index]),
                         mouth=self.mouth[index])

    @classmethod
    def stack(cls, faces: Sequence[PosedFace]) -> PosedFaces:
        """The posed `faces` (one face model's) as one PosedFaces."""
        xy, hair, front, pupils, mouth = (np.stack([getattr(face, name) for face in faces])
                                          for name in ("xy", "hair", "front", "pupils", "mouth"))
        return cls(xy=xy, hair=hair, front=front, pupils=pupils, iris_r=faces[0].iris_r,
                   nose_side=np.array([face.nose_side for face in faces]), mouth=mouth)


def _coefficients(states: Sequence[FaceState]) -> np.ndarray:
    """(S, 12 + 3) weights of the rig's mouth and expression rows for each of `states`."""
    rows = []
    for state in states:
        row = [0.0] * _N_COEF
        for symbol, weight in state.mouth:
            row[MOUTH_INDEX[symbol]] += weight
        row[_N_MOUTH:] = (state.blink, state.smile, state.brow)
        rows.append(row)
    return np.array(rows, dtype=float).reshape(len(states), _N_COEF)


def pose_faces(lifted: LiftedFace, states: Sequence[FaceState]) -> PosedFaces:
    """pose_face of each of `states` at once, as array operations over the S states: the rig's
    rows mixed by (S, 1, k) @ (k, 2N) products, the (S, M, 3) points rotated by (S, 3, 2)
    stacked products (each slice the product pose_face made for one state, so the numbers are
    the same to the last bit)."""
    r = rig(lifted)
    n, count = len(LIFTED_NAMES), len(states)
    coef = _coefficients(states)
    flat = r.neutral + (coef[:, None, :] @ r.basis[:_N_COEF])[:, 0]
    moved = [index for index, state in enumerate(states) if state.emotion]
    if moved:
        weights = np.array([emotion_coefficients(states[index].emotion, states[index].lips) for index in moved])
        flat[moved] += (weights[:, None, :] @ r.basis[_N_COEF:])[:, 0]
    upper, lower = r.lids
    flat[:, lower] = np.maximum(flat[:, lower], flat[:, upper])  # expression.close_lids on the flat rows

    q = np.repeat(r.template[None], count, axis=0)
    q[:, :n, :2] = flat.reshape(count, n, 2)
    h = len(lifted.hair)
    # Rotations of the local frame seen in image orientation (y flipped both ways).
    m = rotation_matrices([state.pose for state in states])
    m[:, 1, :] = -m[:, 1, :]
    m[:, :, 1] = -m[:, :, 1]
    _graze(q, r.outline, m[:, 2])
    out = q @ m[:, :2].transpose(0, 2, 1) + r.origin

    centres = r.centres @ m.transpose(0, 2, 1)
    # The gaze (our addition to 2.4.3.2) moves the focus across the viewer's
    # plane, FOCUS_DEPTH d in front: the eyes turn by about gaze_h, gaze_v degrees.
    gaze = np.array([[math.tan(math.radians(state.gaze_h)), math.tan(math.radians(state.gaze_v)), 0.0]
                     for state in states]).reshape(count, 3)
    focus = r.focus + r.focus[2] * gaze
    toward = focus[:, None, :] - centres
    pupils = centres[..., :2] + (r.radius / np.sqrt((toward * toward).sum(axis=2)))[..., None] * toward[..., :2]
    pupils += r.origin
    xy = out[:, :n]
    pupils = _keep_in_lids(pupils, xy[:, r.lid_rows[0]], xy[:, r.lid_rows[1]], r.iris_r)
    xy[:, r.pupil_rows] = pupils
    sides = np.array([1 if state.pose.turn > 0 else -1 for state in states], dtype=int)
    return PosedFaces(xy=xy, hair=out[:, n:n + h], front=out[:, n + h:], pupils=pupils, iris_r=r.iris_r,
                      nose_side=sides, mouth=coef[:, :_N_MOUTH])


def pose_face(lifted: LiftedFace, state: FaceState) -> PosedFace:
    """The posed face: expressions + mouth + hair shift + rotation + projection + gaze.

    Returns a PosedFace in image pixels (pose_faces of the one state). With Pose(0, 0, 0)
    and a neutral state the model points come back unchanged.
    """
    return pose_faces(lifted, (state,))[0]


def unrolled(state: FaceState) -> FaceState:
    """`state` with no roll (the state render/animation.py draws, turning the roll as a layer)."""
    if not state.pose.roll:
        return state
    return dataclasses.replace(state, pose=dataclasses.replace(state.pose, roll=0.0))


def unroll_faces(posed: PosedFaces, rolls: Sequence[float], origin: np.ndarray) -> PosedFaces:
    """`posed` (S faces, each posed with its roll of `rolls`, degrees) turned back by their rolls
    about the rig's `origin` (2,) pixels. pose_face rolls last, in the image plane about that
    origin (rotation_matrix: Rz @ Rx @ Ry, y flipped: x' = cos x + sin y, y' = -sin x + cos y),
    so this is each face posed without roll, except the pupils, which keep gazing at the fixed
    focus (up to 0.05 px per degree of roll apart); drawn and turned by `rotate(-roll)` (SVG
    angles turn clockwise on screen) it is the posed face exactly. Faces without roll are
    left as they are (the same numbers)."""
    rolled = [index for index, roll in enumerate(rolls) if roll]
    if not rolled:
        return posed
    angles = [math.radians(rolls[index]) for index in rolled]
    # row vectors: (x', y') @ back = (c x' - s y', s x' + c y')
    back = np.array([[[math.cos(a), math.sin(a)], [-math.sin(a), math.cos(a)]] for a in angles])

    def turn(points: np.ndarray) -> np.ndarray:
        turned = points.copy()
        turned[rolled] = (points[rolled] - origin) @ back + origin
        return turned

    return dataclasses.replace(posed, xy=turn(posed.xy), hair=turn(posed.hair), front=turn(posed.front),
                               pupils=turn(posed.pupils))


def unroll(posed: PosedFace, roll: float, origin: np.ndarray) -> PosedFace:
    """`posed` (a face posed with `roll` degrees) turned back by the roll about `origin` (2,)
    pixels: unroll_faces of the one face."""
    if not roll:
        return posed
    return unroll_faces(PosedFaces.stack([posed]), [roll], origin)[0]
