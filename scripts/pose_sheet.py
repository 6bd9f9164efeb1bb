"""Contact sheets of head poses (docs/pose.md): for a face model, one row per (tilt, roll) and
one column per turn, all in degrees, neutral expression, mouth shut.

    .venv/bin/python scripts/pose_sheet.py samples/faces/female.json docs/pose-female.png
"""

from __future__ import annotations

import sys
from pathlib import Path

from lxml import etree

from cartoonface.face.model import load_face
from cartoonface.face.state import FaceState, Pose
from cartoonface.render.png import svg_to_png
from cartoonface.render.sheet import sheet_svg

TURNS = (-15.0, -10.0, 0.0, 10.0, 15.0)
# (tilt, roll) of each row: level, nods both ways, rolls, and the combined corners
ROWS = ((0.0, 0.0), (15.0, 0.0), (-15.0, 0.0), (15.0, 15.0), (-15.0, -15.0), (15.0, -15.0), (-15.0, 15.0))
CELL = 110.0


def main(face_path: str, out_path: str) -> None:
    """Write the pose sheet of the face model `face_path` as a palette PNG to `out_path`."""
    face = load_face(Path(face_path))
    rows = [(f"tilt {tilt:+g}\nroll {roll:+g}",
             [FaceState(pose=Pose(tilt=tilt, turn=turn, roll=roll)) for turn in TURNS]) for tilt, roll in ROWS]
    root = sheet_svg(face, rows, [f"turn {turn:+g}" for turn in TURNS], CELL)
    Path(out_path).write_bytes(svg_to_png(etree.tostring(root), palette=True))


if __name__ == "__main__":
    main(*sys.argv[1:3])
