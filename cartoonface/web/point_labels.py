"""What each face-model point is, in words, for the point editor (shown when a point is
hovered or selected): docs/face-model.md, section 2. "Right" and "left" are the
person's own, so their right is on the image left.
"""

from __future__ import annotations

# Points that come in pairs: (their right, their left) -> what both are.
PAIRS = {
    ("2.13", "2.14"): "jaw corner",
    ("3.1", "3.2"): "upper eyelid, middle",
    ("3.3", "3.4"): "lower eyelid, middle",
    ("3.5", "3.6"): "iris centre",
    ("3.7", "3.12"): "outer eye corner",
    ("3.11", "3.8"): "inner eye corner",
    ("4.1", "4.2"): "eyebrow, inner end",
    ("4.3", "4.4"): "eyebrow, top of the arch",
    ("4.3a", "4.4a"): "eyebrow, between arch and outer end",
    ("4.5", "4.6"): "eyebrow, outer end",
    ("8.3", "8.4"): "mouth corner",
    ("8.10", "8.9"): "upper lip peak",
    ("9.1", "9.2"): "outer edge of the nostril wing",
    ("9.5", "9.4"): "bottom of the nose beside the tip",
    ("9.7", "9.6"): "top of the nose bridge",
    ("9.13", "9.14"): "top of the nostril wing",
    ("10.1", "10.2"): "top of the ear",
    ("10.7", "10.8"): "ear lobe",
    ("10.9", "10.10"): "cheek on the face contour",
    ("11.3a", "11.2a"): "hairline between middle and temple",
    ("11.3", "11.2"): "temple",
}
# Points on the middle line of the face.
MIDDLE = {
    "2.1": "chin", "2.2": "inner upper lip, middle", "2.3": "inner lower lip, middle",
    "8.1": "outer upper lip, middle", "8.2": "outer lower lip, middle", "9.15": "nose tip",
    "11.1": "hairline, middle",
}
# Point name -> its label, for every point of the face model.
POINT_LABELS: dict[str, str] = {
    **MIDDLE,
    **{right: f"{what} (their right)" for (right, _left), what in PAIRS.items()},
    **{left: f"{what} (their left)" for (_right, left), what in PAIRS.items()},
}
