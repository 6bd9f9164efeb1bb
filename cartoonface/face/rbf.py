"""Scattered-data deformation by Gaussian RBFs with a width per cluster (seed 003, eq. 8-12).

Given the displacement of some points of a face (the centres), `interpolate`
moves any other point by f(x) = sum_j A_j Phi_j(x) (eq. 8 without the
polynomial term, as eq. 11 solves it), the weights A from Phi A = D at the
centres (eq. 11). The kernel of centre j is a Gaussian of the Mahalanobis
distance in the cluster c(j) the centre belongs to (seed 003: "the width
parameters of each cluster are determined by use of the mahalanobis distance";
an elliptic Gaussian, as seed 000, 5.1, argues for):

    Phi_j(x) = exp(-m_c(x - x_j)^2 / sigma_c^2),  m_c(v) = sqrt(v' S_c^-1 v),

S_c the covariance of the cluster's points and sigma_c eq. 12: the largest
Mahalanobis distance from the cluster's major point to a point of its cluster.
(Eq. 10 divides r^2 by sigma; we divide by sigma^2 so that sigma is a distance
in the same units as r.) Clusters: every point joins the nearest of the 12
major feature points (seed 003, Fig. 3: 12 major points as the centres of the
local areas; one k-means assignment step from those centres).

`Widths` names the width rule, for the comparison in docs/emotions.md:
"cluster" (eq. 12, the default), "global" (one Euclidean width for all: the
largest cluster radius) and "nearest" (each centre's Euclidean width the
distance to its nearest other centre, a common rule seed 003 compares against).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cartoonface.face.model import POINT_INDEX

# Seed 003, 3.2 / Fig. 3: 12 major feature points, here the brows' inner and outer
# ends, the upper and lower lids, the mouth corners and the middle of each lip.
MAJOR_POINTS: tuple[str, ...] = ("4.2", "4.1", "4.6", "4.5", "3.2", "3.1", "3.4", "3.3", "8.4", "8.3", "8.1", "8.2")
WIDTHS: tuple[str, ...] = ("cluster", "global", "nearest")
# Ridge added to the diagonal of Phi (relative to 1, the kernel at distance 0): close
# centres with wide kernels make eq. 11 ill-conditioned, and the exact solution swings
# the points between and beyond them (a jaw corner 46 px for a 12 px brow move on the
# sample female). 0.1 trades exactness at the centres (which `deform` sets exactly
# anyway) for a smooth field: no free point of the sample faces then moves more than
# its largest neighbouring centre (bench/emotion.py).
RIDGE = 0.1
# Regularisation of each cluster's covariance, as a share of its trace: a cluster of
# points on a line would otherwise have a singular S.
COVARIANCE_FLOOR = 0.05


@dataclass(frozen=True, eq=False)
class Clusters:
    """The clusters of a face's points: `label` (M,) cluster index of each point,
    `inverse` (12, 2, 2) the inverse covariance S_c^-1 of each cluster, `sigma` (12,) eq. 12."""

    label: np.ndarray
    inverse: np.ndarray
    sigma: np.ndarray


def clusters(points: np.ndarray) -> Clusters:
    """The clusters of the model points `points` ((P, 2) in POINT_NAMES order, pixels)."""
    major = points[[POINT_INDEX[name] for name in MAJOR_POINTS]]
    label = np.argmin(((points[:, None, :] - major[None]) ** 2).sum(axis=2), axis=1)
    inverse = np.zeros((len(major), 2, 2))
    sigma = np.zeros(len(major))
    for c, centre in enumerate(major):
        members = points[label == c]
        offsets = members - members.mean(axis=0)
        s = offsets.T @ offsets / max(len(members), 1)
        s += COVARIANCE_FLOOR * max(np.trace(s), 1.0) * np.eye(2)
        inverse[c] = np.linalg.inv(s)
        reach = members - centre
        sigma[c] = max(float(np.sqrt(np.max(np.einsum("ni,ij,nj->n", reach, inverse[c], reach)))), 1.0)
    return Clusters(label=label, inverse=inverse, sigma=sigma)


def kernels(centres: np.ndarray, groups: np.ndarray, targets: np.ndarray, shape: Clusters | None,
            widths: str = "cluster") -> np.ndarray:
    """(T, C) kernel values Phi_j(target) of the centres ((C, 2) pixels, `groups` (C,)
    their cluster index) at `targets` (T, 2), with the width rule `widths` (WIDTHS)."""
    offsets = targets[:, None, :] - centres[None, :, :]
    if widths == "cluster":
        if shape is None:
            raise ValueError("the 'cluster' widths need the face's clusters")
        m2 = np.einsum("tci,cij,tcj->tc", offsets, shape.inverse[groups], offsets)
        return np.exp(-m2 / shape.sigma[groups] ** 2)
    r2 = (offsets ** 2).sum(axis=2)
    if widths == "global":
        if shape is None:
            raise ValueError("the 'global' width needs the face's clusters")
        return np.exp(-r2 / _global_width(centres, groups, shape) ** 2)
    if widths == "nearest":
        between = ((centres[:, None] - centres[None]) ** 2).sum(axis=2)
        np.fill_diagonal(between, np.inf)
        return np.exp(-r2 / np.maximum(between.min(axis=1), 1.0))
    raise ValueError(f"width rule {widths!r}; expected one of {', '.join(WIDTHS)}")


def _global_width(centres: np.ndarray, groups: np.ndarray, shape: Clusters) -> float:
    """One Euclidean width: the largest distance from a centre to another of its cluster."""
    reach = 1.0
    for c in np.unique(groups):
        members = centres[groups == c]
        reach = max(reach, float(np.max(np.linalg.norm(members[:, None] - members[None], axis=2))))
    return reach


def interpolate(centres: np.ndarray, values: np.ndarray, groups: np.ndarray, targets: np.ndarray,
                shape: Clusters | None, widths: str = "cluster") -> np.ndarray:
    """(T, 2) displacement at `targets` (T, 2) interpolating `values` (C, 2) given at
    `centres` (C, 2), pixels (eq. 8 and 11); `groups` (C,) the centres' clusters."""
    phi = kernels(centres, groups, centres, shape, widths)
    weights = np.linalg.solve(phi + RIDGE * np.eye(len(centres)), values)
    return kernels(centres, groups, targets, shape, widths) @ weights


def deform(points: np.ndarray, names: tuple[str, ...], values: np.ndarray, widths: str = "cluster") -> np.ndarray:
    """(P, 2) displacement of every model point (`points` (P, 2) in POINT_NAMES order):
    the points `names` move by `values` ((len(names), 2) pixels) exactly, every other
    point by the RBF interpolation of those moves."""
    shape = clusters(points)
    rows = np.array([POINT_INDEX[name] for name in names])
    out = interpolate(points[rows], values, shape.label[rows], points, shape, widths)
    out[rows] = values
    return out


def leave_one_out(points: np.ndarray, names: tuple[str, ...], values: np.ndarray,
                  widths: str = "cluster") -> np.ndarray:
    """(len(names),) error in pixels of the RBF at each named point when that point is left
    out of the centres and predicted from the others (`points`, `values` as in `deform`)."""
    errors = np.zeros(len(names))
    for i, name in enumerate(names):
        keep = [j for j in range(len(names)) if j != i]
        moved = deform(points, tuple(names[j] for j in keep), values[keep], widths)
        errors[i] = float(np.linalg.norm(moved[POINT_INDEX[name]] - values[i]))
    return errors
