"""The 2D face lifted to 3D (thesis 002, 2.3.2, Alg. 2.1 and Table 2.1).

The rotation origin O (the centre of the neck) lies 1.3 d below EyeMid; 17
additional points A..S help drawing turned faces; every point gets a depth
from Table 2.1 as a multiple of d. Local coordinates: x right, y up, z towards
the viewer, origin O, in pixels.

The thesis writes the local transform as x = x_o - x (Alg. 2.1 step 5) but the
way back as x = x + x_o (2.4.1, Alg. 2.3 step 4); these are not inverses. We
use x_local = x - x_o, the inverse of the way back: the frame is then
right-handed, and a positive turn (Alg. 2.3 step 5) hides the image-right
contour points 11.3, 10.9, 2.13, as the thesis's replacement rule requires.

Our additions, for turns that look like turns (docs/pose.md):

- silhouettes: Alg. 2.3 steps 5-6 swap the far contour points for points further
  forward (Q, M, K) beyond 10 degrees; those points sit almost as wide as the contour
  but 0.8 d further forward, so a turned far cheek bulges out. Instead each contour
  point that is a silhouette at the frontal view (temples, cheeks, jaw corners) gets a
  cross-section through the head: a half ellipse from the point (its Table 2.1 depth)
  inwards along its outward normal to the face's front, and one backwards. pose.py
  draws, at every pose, the point of that cross-section the view grazes: on the far
  side it moves forward round the cheek, on the near side back, continuously;
- the hair: its 23-point outline is the silhouette of the hair's volume at the frontal
  view (in the Table 2.1 hair plane), so its points get cross-sections too (down to
  EyeMid, fading out below it, where long hair hangs); this replaces the hair depth
  shift of Alg. 2.3 steps 1-2. That outline is the back layer, drawn behind the head;
  the front layer is its top above the temples (the crown, resampled) closed by a
  hairline a little below the forehead contour: drawn over the forehead, it turns and
  tilts with the skull.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cartoonface.face.model import POINT_INDEX, POINT_NAMES, FaceModel

# Thesis 002, Alg. 2.1 step 3: y_o = EyeMid.y + 1.3 d (image y down).
ORIGIN_BELOW_EYES = 1.3

ADDITIONAL_NAMES: tuple[str, ...] = ("A", "B", "C", "D", "E", "F", "G", "H", "I", "J", "K", "L", "M", "N", "Q", "R", "S")
LIFTED_NAMES: tuple[str, ...] = POINT_NAMES + ADDITIONAL_NAMES
LIFTED_INDEX: dict[str, int] = {name: i for i, name in enumerate(LIFTED_NAMES)}

_EYEMID = (("3.5", 0.5), ("3.6", 0.5))
# Thesis 002, Alg. 2.1 step 4, in image coordinates (y down), as data:
# name -> (x terms, y terms, x offset, y offset). A term list is a weighted
# sum of model points (weights add up to 1); an offset is (coefficient,
# quantity) with quantity "w_ear" (W_ear, step 1) or a FAPU field name.
# S: the text says S = 8.5, but Table 2.1 pairs R, S with 8.4, 8.3 and Alg. 2.2
# step 13 closes the inner mouth with arc(R, 2.2, S): S is the corner 8.3.
ADDITIONAL: dict[str, tuple] = {
    "A": (_EYEMID, (("10.2", 0.8), ("10.8", 0.2)), (-1.0, "w_ear"), None),
    "B": (_EYEMID, (("10.1", 0.8), ("10.7", 0.2)), (1.0, "w_ear"), None),
    "C": ((("9.13", 0.5), ("9.14", 0.5)), (("9.14", 0.5), ("3.5", 0.25), ("3.6", 0.25)), None, None),
    "D": ((("9.4", 5 / 6), ("9.5", 1 / 6)), (("9.4", 2 / 3), ("9.14", 1 / 3)), None, None),
    "E": ((("9.5", 5 / 6), ("9.4", 1 / 6)), (("9.5", 2 / 3), ("9.13", 1 / 3)), None, None),
    "F": ((("4.4a", 1.0),), (("4.4a", 1.0),), None, (1 / 1.3, "eyebrow_h2")),
    "G": ((("4.4", 1.0),), (("4.4", 1.0),), None, (1 / 1.3, "eyebrow_h")),
    "H": ((("4.3", 1.0),), (("4.3", 1.0),), None, (1 / 1.3, "eyebrow_h")),
    "I": ((("4.3a", 1.0),), (("4.3a", 1.0),), None, (1 / 1.3, "eyebrow_h2")),
    "J": ((("2.14", 5 / 6), ("2.1", 1 / 6)), (("2.14", 1.0),), None, None),
    "K": ((("2.13", 5 / 6), ("2.1", 1 / 6)), (("2.13", 1.0),), None, None),
    "L": ((("3.12", 0.5), ("10.10", 0.5)), (("10.10", 1.0),), None, None),
    "M": ((("3.7", 0.5), ("10.9", 0.5)), (("10.9", 1.0),), None, None),
    "N": ((("11.2", 1.0),), (("11.2", 1.0),), None, None),
    "Q": ((("11.3", 1.0),), (("11.3", 1.0),), None, None),
    "R": ((("8.4", 1.0),), (("8.4", 1.0),), None, None),
    "S": ((("8.3", 1.0),), (("8.3", 1.0),), None, None),
}

# Thesis 002, Table 2.1: depth (z) of each point as a multiple of d.
HAIR_DEPTH = -0.58
DEPTH: dict[str, float] = {
    "3.1": 1.33, "3.2": 1.33, "3.3": 1.33, "3.4": 1.33, "3.5": 1.33, "3.6": 1.33,
    "3.7": 1.19, "3.12": 1.19, "3.8": 1.25, "3.11": 1.25,
    "4.5": 1.17, "4.6": 1.17, "4.3a": 1.30, "4.4a": 1.30, "F": 1.30, "I": 1.30,
    "4.3": 1.44, "4.4": 1.44, "G": 1.44, "H": 1.44, "4.1": 1.49, "4.2": 1.49,
    "2.2": 1.55, "2.3": 1.55, "8.3": 1.40, "8.4": 1.40, "R": 1.40, "S": 1.40,
    "8.1": 1.60, "8.9": 1.60, "8.10": 1.60, "8.2": 1.56,
    "2.13": 0.36, "2.14": 0.36, "2.1": 1.33, "J": 1.18, "K": 1.18,
    "11.1": 1.37, "11.2a": 0.90, "11.3a": 0.90, "11.2": 0.42, "11.3": 0.42, "N": 0.85, "Q": 0.85,
    "10.1": -0.37, "10.2": -0.37, "10.7": 0.0, "10.8": 0.0, "A": 0.04, "B": 0.04,
    "9.1": 1.39, "9.2": 1.39, "9.6": 1.39, "9.7": 1.39, "9.13": 1.40, "9.14": 1.40,
    "9.4": 1.44, "9.5": 1.44, "9.15": 1.65, "C": 1.51, "D": 1.53, "E": 1.53,
    "10.9": 0.27, "10.10": 0.27, "L": 1.11, "M": 1.11,
}


# Silhouettes (our addition, see the module text). Contour point -> the Table 2.1 point
# whose depth is the face's front at its height (the front half of its cross-section
# reaches that depth: the forehead, the nose's sides, the lips), and how deep the back
# half is: None for as deep as the front (temples and cheeks: the round side of the
# skull), 0.0 d for flat (the jaw corners: the jaw's angle is the widest point of the lower
# face, the neck behind it), or a point name: back to that point's Table 2.1 depth. The
# chin's front is itself; seen from below, the underside of the jaw forms its outline, a
# floor from the chin back to the jaw corners' depth (about 1 d: a shallower one, 0.6 d,
# let the chin rise nearly to the corners' height at tilt -15, a flat-bottomed box).
SILHOUETTES: dict[str, tuple[str, float | str | None]] = {
    "11.2": ("11.1", None), "11.3": ("11.1", None),
    "10.10": ("9.14", None), "10.9": ("9.13", None),
    "2.14": ("8.1", 0.0), "2.13": ("8.1", 0.0),
    "2.1": ("2.1", "2.13"),
}
# A rounder head (our addition): Table 2.1 puts the outer eye corners and eyebrow ends
# (1.19 d, 1.17 d) nearly as far forward as the pupils although they lie close to the
# temples, in front of the temples' cross-section; turned away, they would then poke out
# of the far silhouette. Each of these points is set no further forward than the front
# half of the cross-section of the silhouette point beside it at its distance from the
# face's middle.
ON_SURFACE: dict[str, str] = {"3.7": "11.3", "3.12": "11.2", "4.5": "11.3", "4.6": "11.2"}
# The hair's front layer: the crown is the hair outline above the height CROWN_CUT of
# the way from the temples (11.2, 11.3) up to 11.2a / 11.3a, resampled to CROWN_POINTS
# points evenly along it; the hairline is the forehead contour 11.3a, 11.1, 11.2a moved
# down towards the eyebrows by FRINGE_DROP d (a fringe over the forehead that keeps the
# forehead's arch: dropping the middle further made a straight, helmet-like edge; a lower
# hairline, 0.16 d, hid the raised brows of surprise and fear under the fringe).
CROWN_CUT = 0.5
CROWN_POINTS = 9
HAIRLINE = ("11.3a", "11.1", "11.2a")  # image right to left, as drawn
FRINGE_DROP = 0.05
FRONT_NAMES: tuple[str, ...] = (tuple(f"crown{i}" for i in range(CROWN_POINTS))
                                + tuple(f"hairline{i}" for i in range(len(HAIRLINE))))
# The hair's volume: at and above EyeMid its frontal outline lies beside the temples, at
# their depth (Table 2.1, 11.2 / 11.3), so that it wraps round the head as the face does;
# its cross-section reaches the forehead (11.1's depth) forwards and the back of the head,
# HEAD_BACK d, backwards (our estimate: a head is about 3 d from brow to back). Below
# EyeMid the hair fades to the Table 2.1 hair plane (HAIR_DEPTH) and to no cross-section
# over HAIR_FADE d: long hair hangs behind the neck and does not wrap round the head.
HEAD_BACK = -1.6
HAIR_FADE = 1.0
# No cross-section is narrower than MIN_REACH d (a point whose normal passes near the
# centre of the head would otherwise turn on the spot), except the chin's: its reach is
# the radius of the edge between the chin's front and the jaw's floor, CHIN_ROUND d (our
# estimate: a nearly sharp edge; with 0.2 d the rounded edge kept the outline near the chin's
# front, which rose nearly to the jaw corners' height at tilt -15).
MIN_REACH = 0.2
CHIN_ROUND = 0.05


@dataclass(frozen=True, eq=False)
class Silhouette:
    """Cross-sections of the points that form the outline at the frontal view.

    rows: (k,) rows in the stacked local points [LiftedFace.local; .hair; .front].
    normals: (k, 2) outward unit normals in the local x-y plane (y up).
    reach: (k,) pixels from the point inwards, along -normal, to the axis of its
        cross-section (the half width of the head there).
    front, back: (k,) pixels of depth the cross-section reaches in front of / behind
        the point (the half ellipses' other semi-axes).
    """

    rows: np.ndarray
    normals: np.ndarray
    reach: np.ndarray
    front: np.ndarray
    back: np.ndarray


@dataclass(frozen=True, eq=False)
class LiftedFace:
    """A face model in 3D (Alg. 2.1).

    origin: (2,) rotation origin O in image pixels.
    local: (N, 3) pixels, N = len(LIFTED_NAMES), local frame (x right, y up, z front).
    hair: (H, 3) hair points in the local frame: the back layer (z: the temples' depth
        at and above EyeMid, HAIR_DEPTH d from HAIR_FADE d below it).
    front: (F, 3) the hair's front layer, FRONT_NAMES: the crown (left to right) then
        the hairline (right to left); drawn with 11.3 and 11.2 between them.
    silhouette: the cross-sections of the outline points (contour and crown).
    depends, offsets: (2N, 2P) and (N, 2), Alg. 2.1 step 4 as an affine map
        (additional_map): the additional points follow any displacement of the
        model points (expressions, mouth); see lifted_image_points.
    """

    face: FaceModel
    origin: np.ndarray
    local: np.ndarray
    hair: np.ndarray
    depends: np.ndarray
    offsets: np.ndarray
    front: np.ndarray
    silhouette: Silhouette


def eye_mid(face: FaceModel) -> np.ndarray:
    """EyeMid: (2,) image midpoint of the eyeball centres 3.5 and 3.6 (2.3.2)."""
    return (face.point("3.5") + face.point("3.6")) / 2


def ear_width(face: FaceModel) -> float:
    """W_ear (Alg. 2.1 step 1) in pixels: the mean horizontal distance from EyeMid
    to where the ears meet the face at the bottom (10.8, 10.7), so A and B sit
    on the face side of the ears, where arc(10.8, 10.2, A) closes each ear."""
    mid = eye_mid(face)[0]
    return float((abs(face.point("10.8")[0] - mid) + abs(face.point("10.7")[0] - mid)) / 2)


def additional_map(face: FaceModel) -> tuple[np.ndarray, np.ndarray]:
    """Alg. 2.1 step 4 as an affine map: (depends (2N, 2P), offsets (N, 2)).

    For model points (P, 2), the image positions of LIFTED_NAMES are
    (depends @ points.ravel()).reshape(N, 2) + offsets; the model rows are
    the identity with zero offsets.
    """
    quantities = {"w_ear": ear_width(face), "eyebrow_h": face.fapu.eyebrow_h, "eyebrow_h2": face.fapu.eyebrow_h2}
    n, p = len(LIFTED_NAMES), len(POINT_NAMES)
    depends = np.zeros((n, 2, p, 2))
    offsets = np.zeros((n, 2))
    for axis in (0, 1):
        depends[np.arange(p), axis, np.arange(p), axis] = 1.0
    for row, name in enumerate(ADDITIONAL_NAMES, start=p):
        x_terms, y_terms, x_offset, y_offset = ADDITIONAL[name]
        for axis, terms, offset in ((0, x_terms, x_offset), (1, y_terms, y_offset)):
            for point, weight in terms:
                depends[row, axis, POINT_INDEX[point], axis] += weight
            if offset is not None:
                offsets[row, axis] = offset[0] * quantities[offset[1]]
    return depends.reshape(2 * n, 2 * p), offsets


def lifted_image_points(lifted: LiftedFace, points: np.ndarray) -> np.ndarray:
    """(N, 2) image positions of all lifted points for (P, 2) (displaced) model points."""
    return (lifted.depends @ points.ravel()).reshape(-1, 2) + lifted.offsets


def lift(face: FaceModel) -> LiftedFace:
    """Alg. 2.1: rotation origin, additional points, local 3D coordinates (Table 2.1)."""
    d = face.fapu.d
    mid = eye_mid(face)
    origin = np.array([mid[0], mid[1] + ORIGIN_BELOW_EYES * d])
    depends, offsets = additional_map(face)
    image = (depends @ face.points.ravel()).reshape(-1, 2) + offsets
    local = np.column_stack([
        image[:, 0] - origin[0],
        origin[1] - image[:, 1],
        np.array([DEPTH[name] for name in LIFTED_NAMES]) * d,
    ])
    hair_y = origin[1] - face.hair[:, 1]
    fade = np.clip((hair_y - ORIGIN_BELOW_EYES * d) / (HAIR_FADE * d) + 1.0, 0.0, 1.0)  # EyeMid at 1.3 d
    temples = DEPTH["11.2"]
    hair = np.column_stack([face.hair[:, 0] - origin[0], hair_y, (HAIR_DEPTH + fade * (temples - HAIR_DEPTH)) * d])
    front, silhouette = _front_and_silhouette(local, hair, fade, d)
    _round_off(local, silhouette)
    return LiftedFace(face=face, origin=origin, local=local, hair=hair, depends=depends, offsets=offsets,
                      front=front, silhouette=silhouette)


def _round_off(local: np.ndarray, silhouette: Silhouette) -> None:
    """Move the ON_SURFACE points of `local` (N, 3) back in place to the front half of the
    cross-section of their silhouette point (`silhouette`'s first rows are SILHOUETTES'
    points, in order) where they are not already behind it."""
    names = tuple(SILHOUETTES)
    middle_x = (local[LIFTED_INDEX["11.2"], 0] + local[LIFTED_INDEX["11.3"], 0]) / 2
    for name, beside in ON_SURFACE.items():
        k = names.index(beside)
        row, side = LIFTED_INDEX[name], LIFTED_INDEX[beside]
        out = min(abs(local[row, 0] - middle_x) / silhouette.reach[k], 1.0)
        surface = local[side, 2] + silhouette.front[k] * math.sqrt(1.0 - out * out)
        local[row, 2] = min(local[row, 2], surface)


def _crown(hair: np.ndarray, cut: float) -> np.ndarray:
    """(CROWN_POINTS, 2) the run of the closed local hair outline `hair` (H, 2) above the
    height `cut` that holds its top point, from its crossings of that height (or its ends),
    resampled evenly by length and ordered left to right (x increasing)."""
    count = len(hair)
    top = int(np.argmax(hair[:, 1]))
    start = top
    while hair[(start - 1) % count, 1] > cut and (start - 1) % count != top:
        start = (start - 1) % count
    stop = top
    while hair[(stop + 1) % count, 1] > cut and (stop + 1) % count != start:
        stop = (stop + 1) % count
    run = [hair[(start + i) % count] for i in range((stop - start) % count + 1)]
    before, after = hair[(start - 1) % count], hair[(stop + 1) % count]
    if before[1] <= cut < hair[start, 1]:
        run.insert(0, hair[start] + (cut - hair[start, 1]) / (before[1] - hair[start, 1]) * (before - hair[start]))
    if after[1] <= cut < hair[stop, 1]:
        run.append(hair[stop] + (cut - hair[stop, 1]) / (after[1] - hair[stop, 1]) * (after - hair[stop]))
    path = np.array(run)
    if len(path) < 2:
        path = np.array([path[0], path[0]])
    length = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
    at = np.linspace(0.0, length[-1], CROWN_POINTS)
    crown = np.column_stack([np.interp(at, length, path[:, 0]), np.interp(at, length, path[:, 1])])
    return crown if crown[0, 0] <= crown[-1, 0] else crown[::-1]


def _normals(points: np.ndarray, closed: bool) -> np.ndarray:
    """(n, 2) unit normals of the polyline `points` (n, 2), perpendicular to the chord of
    each point's neighbours (one-sided at the ends of an open one), turned to the left
    of the direction of travel (outward for a clockwise outline, y up)."""
    after = np.roll(points, -1, axis=0) if closed else np.concatenate([points[1:], points[-1:]])
    before = np.roll(points, 1, axis=0) if closed else np.concatenate([points[:1], points[:-1]])
    chord = after - before
    normals = np.column_stack([-chord[:, 1], chord[:, 0]])
    return normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)


def _front_and_silhouette(local: np.ndarray, hair: np.ndarray, fade: np.ndarray,
                          d: float) -> tuple[np.ndarray, Silhouette]:
    """The hair's front layer (F, 3) and the cross-sections of the outline points, from
    the local points `local` (N, 3), the local hair outline `hair` (H, 3), how much each
    hair point wraps round the head `fade` (H,) 0..1, and the FAPU d."""
    at = {name: local[LIFTED_INDEX[name]] for name in LIFTED_NAMES}
    temple_y = (at["11.2"][1] + at["11.3"][1]) / 2
    upper_y = (at["11.2a"][1] + at["11.3a"][1]) / 2
    hairline = np.array([at[name] - np.array([0.0, FRINGE_DROP * d, 0.0]) for name in HAIRLINE])
    bare = hair[:, 1].max() <= at["11.1"][1]  # hair that does not reach over the forehead: no front layer
    if bare:  # the crown laid on the hairline, left to right: the front layer has no area
        path = np.vstack([at["11.2"], hairline[::-1], at["11.3"]])
        length = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path[:, :2], axis=0), axis=1))])
        along = np.linspace(0.0, length[-1], CROWN_POINTS)
        crown_3d = np.column_stack([np.interp(along, length, path[:, axis]) for axis in range(3)])
    else:
        crown = _crown(hair[:, :2], temple_y + CROWN_CUT * (upper_y - temple_y))
        crown_3d = np.column_stack([crown, np.full(len(crown), at["11.2"][2])])
    crown = crown_3d[:, :2] if not bare else crown_3d[:0, :2]  # the crown points with cross-sections
    front = np.vstack([crown_3d, hairline])

    # the face contour clockwise (y up): forehead left to right, down the right, the jaw, up the left
    ring = ("11.2", "11.2a", "11.1", "11.3a", "11.3", "10.9", "2.13", "2.1", "2.14", "10.10")
    ring_normals = dict(zip(ring, _normals(np.array([at[n][:2] for n in ring]), closed=True)))
    middle_x = (at["11.2"][0] + at["11.3"][0]) / 2
    names = tuple(SILHOUETTES)
    normals = np.array([ring_normals[n] for n in names])
    reach = np.array([CHIN_ROUND * d if n == "2.1" else max((at[n][0] - middle_x) * normal[0], MIN_REACH * d)
                      for n, normal in zip(names, normals)])
    front_depth = np.array([at[SILHOUETTES[n][0]][2] - at[n][2] for n in names])
    backs = [SILHOUETTES[n][1] for n in names]
    back_depth = np.array([depth if back is None else at[n][2] - at[back][2] if isinstance(back, str) else back * d
                           for n, back, depth in zip(names, backs, front_depth)])

    centre = np.array([middle_x, (at["3.5"][1] + at["3.6"][1]) / 2])  # EyeMid, local
    outline = hair[:, :2]
    area = np.sum(outline[:, 0] * np.roll(outline[:, 1], -1) - np.roll(outline[:, 0], -1) * outline[:, 1])
    hair_normals = _normals(outline, closed=True) * (1.0 if area < 0 else -1.0)  # outward either way round
    kept = fade > 0
    crown_normals = _normals(crown, closed=False)  # left to right over the top: clockwise
    volume = np.vstack([outline[kept], crown])  # the hair points that wrap round the head
    weight = np.concatenate([fade[kept], np.ones(len(crown))])
    volume_normals = np.vstack([hair_normals[kept], crown_normals])
    volume_reach = np.maximum(np.einsum("ij,ij->i", volume - centre, volume_normals), MIN_REACH * d)
    rows = np.concatenate([[LIFTED_INDEX[n] for n in names], len(local) + np.flatnonzero(kept),
                           len(local) + len(hair) + np.arange(len(crown))])
    return front, Silhouette(
        rows=rows,
        normals=np.vstack([normals, volume_normals]),
        reach=np.concatenate([reach, weight * volume_reach]),
        front=np.concatenate([np.maximum(front_depth, 0.0), weight * (at["11.1"][2] - at["11.2"][2])]),
        back=np.concatenate([back_depth, weight * (at["11.2"][2] - HEAD_BACK * d)]),
    )
