"""Geometry checks shared by the drawing tests: points along Bezier paths, polygon area and
self-crossings, the corners of polygon path data."""

from __future__ import annotations

import re

import numpy as np

SAMPLES = 10  # points sampled on each Bezier piece
NUMBER = re.compile(r"-?(?:\d+\.?\d*|\.\d+)")


def sample(path: np.ndarray) -> np.ndarray:
    """(pieces * SAMPLES, 2) points along a path of render/mouth.py (start, then pieces), end excluded."""
    t = np.linspace(0, 1, SAMPLES, endpoint=False)[:, None, None]
    starts = path[0:-1:3]
    c1, c2, ends = path[1::3], path[2::3], path[3::3]
    curve = (1 - t) ** 3 * starts + 3 * (1 - t) ** 2 * t * c1 + 3 * (1 - t) * t**2 * c2 + t**3 * ends
    return curve.transpose(1, 0, 2).reshape(-1, 2)


def area(polygon: np.ndarray) -> float:
    """Signed area of a closed polygon (n, 2); positive when it runs clockwise on screen (y down)."""
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def crossings(polygon: np.ndarray) -> int:
    """Number of pairs of non-adjacent edges of the closed polygon that properly cross."""
    a, b = polygon, np.roll(polygon, -1, axis=0)

    def side(p, q, r):
        return np.sign((q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0]))

    p1, p2, q1, q2 = a[:, None], b[:, None], a[None, :], b[None, :]
    cross = (side(p1, p2, q1) * side(p1, p2, q2) < 0) & (side(q1, q2, p1) * side(q1, q2, p2) < 0)
    n = len(polygon)
    i, j = np.indices((n, n))
    adjacent = (abs(i - j) <= 1) | (abs(i - j) == n - 1)
    return int((cross & ~adjacent).sum()) // 2


def polygon(d: str) -> np.ndarray:
    """The corners (n, 2) of an absolute M/L/Z polygon's path data."""
    return np.array([float(v) for v in NUMBER.findall(d)]).reshape(-1, 2)
