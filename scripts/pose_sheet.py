"""Contact sheets of head poses (docs/pose.md): for a face model, one row per (tilt, roll) and
one column per turn, all in degrees, neutral expression, mouth shut.

    .venv/bin/python scripts/pose_sheet.py samples/faces/female.json docs/pose-female.png
    .venv/bin/python scripts/pose_sheet.py FACE.json OUT.png --tilt -15 --cell 150

`--tilt T` keeps only the rows tilted T degrees (the tilt -15 crops of docs/pose.md);
`--cell` sets the width of a cell in pixels.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from lxml import etree

from cartoonface.face.model import load_face
from cartoonface.face.state import FaceState, Pose
from cartoonface.render.png import svg_to_png
from cartoonface.render.sheet import sheet_svg

TURNS = (-15.0, -10.0, 0.0, 10.0, 15.0)
# (tilt, roll) of each row: level, nods both ways, rolls, and the combined corners
ROWS = ((0.0, 0.0), (15.0, 0.0), (-15.0, 0.0), (15.0, 15.0), (-15.0, -15.0), (15.0, -15.0), (-15.0, 15.0))
CELL = 110.0  # px: default width of a cell


def main(face_path: str, out_path: str, tilt: float | None = None, cell: float = CELL) -> None:
    """Write the pose sheet of the face model `face_path` as a palette PNG to `out_path`: the
    rows of ROWS (only those tilted `tilt` degrees unless None), cells `cell` pixels wide."""
    face = load_face(Path(face_path))
    rows = [(f"tilt {row_tilt:+g}\nroll {roll:+g}",
             [FaceState(pose=Pose(tilt=row_tilt, turn=turn, roll=roll)) for turn in TURNS])
            for row_tilt, roll in ROWS if tilt is None or row_tilt == tilt]
    root = sheet_svg(face, rows, [f"turn {turn:+g}" for turn in TURNS], cell)
    Path(out_path).write_bytes(svg_to_png(etree.tostring(root), palette=True))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("face")
    parser.add_argument("out")
    parser.add_argument("--tilt", type=float, default=None)
    parser.add_argument("--cell", type=float, default=CELL)
    args = parser.parse_args()
    main(args.face, args.out, args.tilt, args.cell)
