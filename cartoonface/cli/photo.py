"""`cartoonface face from-photo`: a face model from a portrait photo (docs/photo.md).

A thin shell over cartoonface.photo.model_from_photo. Registered under `face` by cli/face.py
through `register_from_photo`; the photo extra is imported only when the action runs.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from cartoonface.errors import OptionError


def register_from_photo(actions: argparse._SubParsersAction) -> None:
    """Add the `from-photo` action to the `face` command's action subparsers."""
    parser = actions.add_parser(
        "from-photo", help="make a face model from a portrait photo (needs the photo extra)",
        description="Find the largest face in a portrait photo and write its cartoon face model: the named "
                    "points, hair polygon and colours. A face that is not neutral (open mouth, smile, head "
                    "turned or leaning) gives a warning and is normalised. docs/photo.md.")
    parser.add_argument("photo", type=Path, metavar="PHOTO", help="the portrait (JPEG, PNG, WebP, ...)")
    parser.add_argument("-o", "--output", type=Path, required=True, metavar="FACE.json",
                        help="face model file to write (docs/face-model.md)")
    parser.add_argument("--preview", type=Path, metavar="PREVIEW.svg",
                        help="also draw the cartoon face (SVG; with a PNG beside it)")
    parser.add_argument("--overlay", type=Path, metavar="OVERLAY.png",
                        help="also write the photo with the detected points and hair polygon drawn on it")
    parser.add_argument("--name", default=None, help="the face's name (default: the photo's file name)")
    parser.set_defaults(func=run_from_photo)


def run_from_photo(args: argparse.Namespace) -> int:
    """`face from-photo`: photo -> face JSON (+ preview, overlay); warnings on stderr."""
    for option, path, suffix in (("-o", args.output, ".json"), ("--preview", args.preview, ".svg"),
                                 ("--overlay", args.overlay, ".png")):
        if path is not None and path.suffix.lower() != suffix:
            raise OptionError(f"{option} {path}: expected a file name ending in {suffix}")
    name = args.name if args.name is not None else args.photo.stem
    if not name.strip():
        raise OptionError("--name is empty; expected a name for the face")

    from cartoonface.face.model import save_face
    from cartoonface.face.state import FaceState
    from cartoonface.files import write_bytes_atomic
    from cartoonface.photo.model_from_photo import face_from_photo, load_photo
    from cartoonface.photo.pictures import overlay_png
    from cartoonface.render.elements import svg_bytes
    from cartoonface.render.png import svg_to_png
    from cartoonface.render.svg import face_svg

    photo = load_photo(args.photo)
    result = face_from_photo(photo, name)
    for note in result.warnings:
        print(f"cartoonface: warning: {args.photo}: {note}", file=sys.stderr)
    written = [save_face(result.face, args.output)]
    if args.preview is not None:
        data = svg_bytes(face_svg(result.face, FaceState()))
        written.append(write_bytes_atomic(args.preview, data))
        written.append(write_bytes_atomic(args.preview.with_suffix(".png"), svg_to_png(data)))
    if args.overlay is not None:
        written.append(write_bytes_atomic(args.overlay, overlay_png(photo, result)))
    print(" ".join(str(path) for path in written))
    return 0
