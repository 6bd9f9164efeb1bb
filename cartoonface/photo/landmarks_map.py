"""The 49 named model points from the 478-point face mesh (docs/photo.md, the mapping table).

Most points are one mesh point; the eyebrow ends are the middle of the brow's upper
and lower edge; the face contour points (temples, hairline beside the middle, cheeks,
jaw corners) are read off the mesh's face oval at a height set by other points; the
ears, which the mesh does not cover, are placed beside the face oval (so they are
placed even when hair hides them). Works on a mesh already levelled (no roll).
"""

from __future__ import annotations

import numpy as np

from cartoonface.face.model import POINT_NAMES

# The iris centres: face-mesh rows of the iris refinement (landmarks.py): the image-left
# iris (the subject's right eye, point 3.6, FAPU r1) and the image-right iris (3.5, r2).
IRIS_LEFT = 468
IRIS_RIGHT = 473
# Named point -> face mesh index (image left = the subject's right).
DIRECT = {
    "2.1": 152, "2.2": 13, "2.3": 14,
    "3.1": 386, "3.2": 159, "3.3": 374, "3.4": 145, "3.5": IRIS_RIGHT, "3.6": IRIS_LEFT,
    "3.7": 263, "3.8": 133, "3.11": 362, "3.12": 33,
    "4.3": 334, "4.4": 105, "4.3a": 293, "4.4a": 63,
    "8.1": 0, "8.2": 17, "8.3": 291, "8.4": 61, "8.9": 37, "8.10": 267,
    "9.1": 327, "9.2": 98, "9.4": 97, "9.5": 326, "9.6": 196, "9.7": 419,
    "9.13": 275, "9.14": 45, "9.15": 94,
    "11.1": 10,
}
# Eyebrow ends: the middle of the upper-edge and lower-edge mesh points.
BROW_ENDS = {"4.1": (336, 285), "4.2": (107, 55), "4.5": (300, 276), "4.6": (70, 46)}
# Eyebrow thickness at the arch and beside it (upper edge, lower edge) per side:
# EyebrowH = 1.3 x thickness (thesis 002, Alg. 2.1: G = 4.4 + EyebrowH / 1.3).
BROW_THICKNESS = {"eyebrow_h": ((105, 52), (334, 282)), "eyebrow_h2": ((63, 53), (293, 283))}
# Iris centre and rim per FAPU (docs/face-model.md: r1 for the image-left eye 3.6, r2 for 3.5).
IRIS_RIM = {"r1": (IRIS_LEFT, (469, 470, 471, 472)), "r2": (IRIS_RIGHT, (474, 475, 476, 477))}
# The face oval from the top of the forehead (10) to the chin (152), per side.
OVAL_LEFT = (10, 109, 67, 103, 54, 21, 162, 127, 234, 93, 132, 58, 172, 136, 150, 149, 176, 148, 152)
OVAL_RIGHT = (10, 338, 297, 332, 284, 251, 389, 356, 454, 323, 361, 288, 397, 365, 379, 378, 400, 377, 152)
# The whole oval as one loop: down the image-left side, up the image-right side.
OVAL = OVAL_LEFT + OVAL_RIGHT[-2:0:-1]
# Contour points on the oval, at a height given as (point a, point b, fraction):
# y = y_a + fraction (y_b - y_a). Ours, from the proportions of the sample faces
# (temple a little above the eyes, cheek level with the nose bottom, jaw corner
# 0.55 of the way from the mouth corners to the chin, hairline points a fifth of
# the way from the hairline middle to the temple).
ON_OVAL = {
    "11.2": ("eyes", "4.4", 0.3), "11.3": ("eyes", "4.3", 0.3),
    "10.10": ("9.15", "9.15", 0.0), "10.9": ("9.15", "9.15", 0.0),
    "2.14": ("8.4", "2.1", 0.55), "2.13": ("8.3", "2.1", 0.55),
}
HAIRLINE_SIDE = {"11.2a": "11.2", "11.3a": "11.3"}
HAIRLINE_FRACTION = 0.2
# Ears in units of d: the top 0.1 d above the eyes and EAR_OUT outside the oval; the
# lobe level with the nose bottom, EAR_LOBE_OUT outside the oval (thesis Table 2.1 puts
# the lobe 10.8 at depth 0, on the face side of the ear).
EAR_RAISE, EAR_OUT, EAR_LOBE_OUT = 0.1, 0.15, 0.03


def eyes(mesh: np.ndarray) -> tuple[np.ndarray, float]:
    """The (3,) midpoint of the two iris centres of a (478, 3) mesh and their distance d
    in the image plane (pixels)."""
    left, right = mesh[IRIS_LEFT], mesh[IRIS_RIGHT]
    return (left + right) / 2, float(np.hypot(*(right[:2] - left[:2])))


def _on_oval(mesh: np.ndarray, oval: tuple[int, ...], y: float) -> np.ndarray:
    """(3,) point of the oval polyline at height y (clamped to its ends), x and z interpolated."""
    line = mesh[list(oval)]
    order = np.argsort(line[:, 1], kind="stable")
    ys = line[order, 1]
    y = float(np.clip(y, ys[0], ys[-1]))
    return np.array([np.interp(y, ys, line[order, 0]), y, np.interp(y, ys, line[order, 2])])


def model_points(mesh: np.ndarray) -> np.ndarray:
    """(49, 3) named points in POINT_NAMES order from a levelled (478, 3) mesh (x, y, z pixels)."""
    out: dict[str, np.ndarray] = {name: mesh[i] for name, i in DIRECT.items()}
    for name, (upper, lower) in BROW_ENDS.items():
        out[name] = (mesh[upper] + mesh[lower]) / 2
    middle, d = eyes(mesh)
    eyes_y = middle[1]
    for name, (a, b, fraction) in ON_OVAL.items():
        ya = eyes_y if a == "eyes" else out[a][1]
        y = ya + fraction * (out[b][1] - ya)
        out[name] = _on_oval(mesh, OVAL_LEFT if name in ("11.2", "10.10", "2.14") else OVAL_RIGHT, y)
    for name, temple in HAIRLINE_SIDE.items():
        y = out["11.1"][1] + HAIRLINE_FRACTION * (out[temple][1] - out["11.1"][1])
        out[name] = _on_oval(mesh, OVAL_LEFT if name == "11.2a" else OVAL_RIGHT, y)
    for top, lobe, oval, side in (("10.2", "10.8", OVAL_LEFT, -1.0), ("10.1", "10.7", OVAL_RIGHT, 1.0)):
        out[top] = _on_oval(mesh, oval, eyes_y - EAR_RAISE * d) + [side * EAR_OUT * d, 0, 0]
        out[lobe] = _on_oval(mesh, oval, out["9.15"][1]) + [side * EAR_LOBE_OUT * d, 0, 0]
    return np.array([out[name] for name in POINT_NAMES], dtype=float)


def free_fapu(mesh: np.ndarray) -> dict[str, float]:
    """The FAPUs the points cannot give (eyebrow_h, eyebrow_h2, r1, r2) from a (478, 3) mesh, pixels."""
    out = {}
    for name, sides in BROW_THICKNESS.items():
        out[name] = 1.3 * float(np.mean([np.hypot(*(mesh[u, :2] - mesh[lo, :2])) for u, lo in sides]))
    for name, (centre_row, rim) in IRIS_RIM.items():
        centre = mesh[centre_row, :2]
        out[name] = float(np.mean(np.hypot(*(mesh[list(rim), :2] - centre).T)))
    return out
