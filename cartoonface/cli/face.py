"""`cartoonface face`: draw a face model as SVG (and PNG): one state, a contact sheet, the point diagram.

A thin shell over cartoonface.face (load, pose) and cartoonface.render.svg. Every
option is checked before anything is written; outputs are written atomically.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import TYPE_CHECKING

from cartoonface.cli.photo import register_from_photo
from cartoonface.errors import OptionError
from cartoonface.files import write_bytes_atomic

if TYPE_CHECKING:
    from lxml import etree

    from cartoonface.face.state import FaceState

# The contact sheet: one row per pose and expression, one column per basic mouth shape.
# Rows: label, (tilt, turn, roll), blink, smile, brow.
SHEET_ROWS: tuple[tuple[str, tuple[float, float, float], float, float, float], ...] = (
    ("front\nneutral", (0, 0, 0), 0, 0, 0),
    ("turn -15\nneutral", (0, -15, 0), 0, 0, 0),
    ("turn 15\nneutral", (0, 15, 0), 0, 0, 0),
    ("tilt -15\nbrow 1", (-15, 0, 0), 0, 0, 1),
    ("tilt 15\nblink 1", (15, 0, 0), 1, 0, 0),
    ("roll -15\nsmile 1", (0, 0, -15), 0, 1, 0),
    ("roll 15\nblink .5, brow .5", (0, 0, 15), 0.5, 0, 0.5),
    ("tilt -15 turn 15 roll -15\nsmile .5", (-15, 15, -15), 0, 0.5, 0),
    ("tilt 15 turn -15 roll 15\nsmile 1, brow 1", (15, -15, 15), 0, 1, 1),
)
SHEET_CELL = 104.0  # cell width in pixels
ANGLES = ("tilt", "turn", "roll")  # the pose options, Pose's fields
HELP = "draw a face model as SVG: one pose and expression, a contact sheet, the point diagram"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `face` subcommand with its `render`, `sheet`, `diagram` and `from-photo` actions."""
    from cartoonface.face.emotion import EMOTIONS
    from cartoonface.face.mouth import MOUTH_SYMBOLS
    from cartoonface.face.state import MAX_ANGLE

    parser = subparsers.add_parser(
        "face", help=HELP,
        description="Draw a face model (JSON, docs/face-model.md) as SVG, optionally also as PNG.")
    actions = parser.add_subparsers(dest="action", metavar="ACTION", required=True)

    render = actions.add_parser(
        "render", help="draw the face in one pose, expression and mouth shape",
        description=f"Draw the face in one head pose (each angle within +-{MAX_ANGLE:g} degrees), with amounts "
                    "0..1 of blink, smile and eyebrow raise and one basic mouth shape, on the canvas of the "
                    "face model with a plain background and a shirt.")
    _common(render, "OUT.svg")
    for name, what in (("tilt", "nod about the X axis; positive looks down"),
                       ("turn", "turn about the Y axis; positive turns the nose to the image right"),
                       ("roll", "roll about the Z axis; positive leans the top of the head to the image left")):
        render.add_argument(f"--{name}", default="0", metavar="DEG",
                            help=f"degrees of {what} (-{MAX_ANGLE:g}..{MAX_ANGLE:g}, default 0)")
    for name, what in (("blink", "closing of the eyelids (1: shut)"), ("smile", "smile with squint"),
                       ("brow", "eyebrow raise")):
        render.add_argument(f"--{name}", default="0", metavar="X", help=f"amount of {what}, 0..1 (default 0)")
    render.add_argument("--mouth", default="m", metavar="SYMBOL",
                        help=f"basic mouth shape, one of {' '.join(MOUTH_SYMBOLS)} (thesis 5.2.2; default m, "
                             "the closed rest shape)")
    render.add_argument("--emotion", default=None, metavar="NAME",
                        help=f"emotion, one of {' '.join(EMOTIONS)} (docs/emotions.md; default none)")
    render.add_argument("--intensity", default="1", metavar="X",
                        help="intensity of the --emotion, 0..1 (default 1)")
    render.set_defaults(func=run_render)

    sheet = actions.add_parser(
        "sheet", help="contact sheet: poses and expressions (rows) x the 12 mouth shapes (columns)",
        description="Draw a labelled grid of the head: one row per pose (tilt turn roll in degrees) and "
                    f"expression, one column per basic mouth shape ({' '.join(MOUTH_SYMBOLS)}).")
    _common(sheet, "SHEET.svg")
    sheet.set_defaults(func=run_sheet)

    diagram = actions.add_parser(
        "diagram", help="the labelled diagram of the model's points (docs/face-model.md)",
        description="Draw the frontal face faded with every feature point (black), additional point A..S "
                    "(red) and hair point (blue, numbered) labelled.")
    _common(diagram, "DIAGRAM.svg")
    diagram.set_defaults(func=run_diagram)

    register_from_photo(actions)


def _common(parser: argparse.ArgumentParser, out: str) -> None:
    """The arguments every action takes: the face file, -o and --png."""
    parser.add_argument("face", type=Path, metavar="FACE.json", help="face model file (docs/face-model.md)")
    parser.add_argument("-o", "--output", type=Path, required=True, metavar=out, help="SVG file to write")
    parser.add_argument("--png", action="store_true", help="also write a PNG beside it (same name, .png)")


def _number(text: str, option: str) -> float:
    """The finite number in `text` given to `option`; OptionError naming the option otherwise."""
    try:
        value = float(text)
    except ValueError:
        raise OptionError(f"--{option} {text!r}: expected a number") from None
    if not math.isfinite(value):
        raise OptionError(f"--{option} {text!r}: expected a finite number")
    return value


def _state(args: argparse.Namespace) -> FaceState:
    """The FaceState the render options describe (OptionError names a bad one; Pose checks the angles)."""
    from cartoonface.face.emotion import EMOTIONS
    from cartoonface.face.mouth import MOUTH_SYMBOLS
    from cartoonface.face.state import FaceState, Pose

    if args.mouth not in MOUTH_SYMBOLS:
        raise OptionError(f"--mouth {args.mouth!r}: unknown mouth shape; expected one of {' '.join(MOUTH_SYMBOLS)}")
    angles = {}
    for name in ANGLES:
        angles[name] = _number(getattr(args, name), name)
        try:
            Pose(**{name: angles[name]})
        except OptionError as exc:
            raise OptionError(f"--{name} {angles[name]:g}: {exc}") from None
    amounts = {}
    for name in ("blink", "smile", "brow"):
        amounts[name] = _number(getattr(args, name), name)
        if not 0 <= amounts[name] <= 1:
            raise OptionError(f"--{name} {amounts[name]:g}: out of range; expected 0 to 1")
    intensity = _number(args.intensity, "intensity")
    if not 0 <= intensity <= 1:
        raise OptionError(f"--intensity {intensity:g}: out of range; expected 0 to 1")
    emotion: tuple[tuple[str, float], ...] = ()
    if args.emotion is not None:
        if args.emotion not in EMOTIONS:
            raise OptionError(f"--emotion {args.emotion!r}: unknown emotion; expected one of {' '.join(EMOTIONS)}")
        emotion = ((args.emotion, intensity),)
    pose = Pose(**angles)
    return FaceState(pose, amounts["blink"], amounts["smile"], amounts["brow"],
                     emotion=emotion).with_mouth(args.mouth)


def _write(root: etree._Element, args: argparse.Namespace, palette: bool = False) -> int:
    """Write the SVG (and with --png the PNG, with a 256-colour `palette` if asked) for `root`;
    print what was written; exit code 0."""
    from cartoonface.render.elements import svg_bytes
    from cartoonface.render.png import svg_to_png

    if args.output.suffix.lower() != ".svg":
        raise OptionError(f"-o {args.output}: expected a file name ending in .svg")
    data = svg_bytes(root)
    png = svg_to_png(data, palette) if args.png else None
    outputs = [(args.output, data)] + ([(args.output.with_suffix(".png"), png)] if png is not None else [])
    for path, _ in outputs:
        if path.is_dir():
            raise OptionError(f"-o {args.output}: {path} is a folder; expected a file name")
    written = []
    for path, content in outputs:
        try:
            written.append(write_bytes_atomic(path, content))
        except OSError as exc:
            raise OptionError(f"-o {args.output}: cannot write {path}: {exc.strerror}") from None
    print(" ".join(str(path) for path in written))
    return 0


def run_render(args: argparse.Namespace) -> int:
    """`face render`: one state of the face on its canvas."""
    from cartoonface.face.model import load_face
    from cartoonface.render.svg import face_svg

    state = _state(args)
    return _write(face_svg(load_face(args.face), state), args)


def run_sheet(args: argparse.Namespace) -> int:
    """`face sheet`: SHEET_ROWS x MOUTH_SYMBOLS."""
    from cartoonface.face.model import load_face
    from cartoonface.face.mouth import MOUTH_SYMBOLS
    from cartoonface.face.state import FaceState, Pose
    from cartoonface.render.sheet import sheet_svg

    face = load_face(args.face)
    rows = [(label, [FaceState(Pose(*angles), blink, smile, brow).with_mouth(m) for m in MOUTH_SYMBOLS])
            for label, angles, blink, smile, brow in SHEET_ROWS]
    return _write(sheet_svg(face, rows, list(MOUTH_SYMBOLS), SHEET_CELL), args, palette=True)


def run_diagram(args: argparse.Namespace) -> int:
    """`face diagram`: the labelled point diagram."""
    from cartoonface.face.model import load_face
    from cartoonface.render.diagram import diagram_svg

    return _write(diagram_svg(load_face(args.face)), args, palette=True)
