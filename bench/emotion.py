"""Emotions (face/emotion.py) and their transfer (face/rbf.py): how far apart they look, how
well the RBF predicts a moved point, and what they cost in `generate`.

Figures, for each sample face (female, male) and, with the photo extra, the face made from
scikit-image's astronaut portrait (public domain; docs/photo.md):
- pixels: each emotion at intensity 1 against neutral, and every pair of emotions, in a frontal
  render (bench/mouth.py's measures: `face` = pixels differing by more than CHANGED in a channel,
  a share of the face outline's pixels; `figure` = issue 10's measure). Goals (issue 13, face
  measure): each emotion >= 2 %, each pair >= 1 %.
- leave-one-out: each moved point of each template left out of the RBF's centres and predicted
  from the others; the median error in pixels (d = 100 px on both faces) per width rule
  (face/rbf.py WIDTHS) against plain FAPU scaling, which predicts no move for a point it is
  not given.
- generate: samples/speech/story.wav with its transcript as it is and with a mark on every
  sentence (MARKED) and a default mood: SVG bytes per minute of audio (30 fps), in all and by
  track (bench/generate.py's bytes_by_track), and the wall time of `pipeline.generate` (median
  of RUNS).

`python -m bench.emotion --pictures DIR` also writes the contact sheets emotions x mouth
shapes (emotions-female.png, emotions-male.png), the emotions on the astronaut's face
(emotions-astronaut.png) and the plain scaling / RBF / RBF as drawn comparison (emotions-rbf.png)
into DIR.
"""

from __future__ import annotations

import itertools
import statistics
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from bench.generate import bytes_by_track
from bench.mouth import CHANGED, ISSUE_CHANGED, changed, face_mask, figure_mask, picture, render
from cartoonface.animate.timeline import LIPS_SPEAKING
from cartoonface.data import SAMPLE_FACES
from cartoonface.face.emotion import EMOTIONS, drawn_moves, emotion_displacements, template_fapu, template_points
from cartoonface.face.lift import lift
from cartoonface.face.model import POINT_NAMES, FaceModel, load_face
from cartoonface.face.mouth import MOUTH_SYMBOLS
from cartoonface.face.pose import rig
from cartoonface.face.rbf import WIDTHS, deform, leave_one_out
from cartoonface.face.state import FaceState
from cartoonface.pipeline import Options, generate
from cartoonface.render.elements import svg_bytes
from cartoonface.render.png import svg_to_png
from cartoonface.render.sheet import sheet_svg
from cartoonface.render.svg import face_svg

ROOT = Path(__file__).resolve().parents[1]
STORY = ROOT / "samples" / "speech"
# The story with a mark on each sentence (one of them inside its sentence, one closed).
MARKED = ("[sad 0.6]从前，有一只小白兔住在森林里。\n"
          "[happy]每天晚上，它都会坐在草地上看月亮。\n"
          "有一天，[surprise]月亮对小白兔说[/surprise]：[happy 0.8]你好，我的好朋友。\n"
          "[happy]小白兔高兴地跳了起来。\n"
          "[wink]从那以后[/wink]，它们每天晚上都一起聊天。\n")
DEFAULT_MOOD = ("happy", 0.3)
RUNS = 3
GOAL_EMOTION = 0.02
GOAL_PAIR = 0.01
SHEET_CELL = 96.0  # contact sheet cell width, pixels
CROP = (70, 90, 330, 370)  # the head in a sample face's 400 x 480 canvas, for the RBF picture
DOT, DOT_COLOUR = 2.5, (220, 30, 30)  # the marks of the points only the RBF moves
ASTRONAUT_SHAPES = ("a", "i", "u")  # the astronaut's sheet: the rest mouth and these shapes
REST = "rest"  # the contact sheet's first column: the closed mouth with the emotion's whole lips (gamma 1)


def faces() -> list[tuple[str, FaceModel]]:
    """(label, face): the two samples, and the astronaut's face when the photo extra is installed."""
    out = [(name, load_face(SAMPLE_FACES / f"{name}.json")) for name in ("female", "male")]
    try:
        from skimage import data

        from cartoonface.photo.model_from_photo import face_from_photo, photo_from_image
    except ImportError:
        return out
    photo = photo_from_image(Image.fromarray(data.astronaut()), "astronaut")
    return out + [("astronaut (photo)", face_from_photo(photo, "astronaut").face)]


def pixel_shares(face: FaceModel) -> tuple[dict[str, tuple[float, float]], dict[tuple[str, str], float]]:
    """({emotion: (face share, figure share) against neutral}, {(a, b): face share}) at intensity 1."""
    neutral = render(face, FaceState())
    renders = {name: render(face, FaceState(emotion=((name, 1.0),))) for name in EMOTIONS}
    area, figure = int(face_mask(face).sum()), int(figure_mask(neutral).sum())
    singles = {name: (changed(neutral, image, CHANGED) / area, changed(neutral, image, ISSUE_CHANGED) / figure)
               for name, image in renders.items()}
    pairs = {(a, b): changed(renders[a], renders[b], CHANGED) / area for a, b in itertools.combinations(EMOTIONS, 2)}
    return singles, pairs


def loo_errors(face: FaceModel) -> dict[str, dict[str, float]]:
    """{emotion: {width rule or "plain": median leave-one-out error in pixels}} over the points
    each template moves."""
    out: dict[str, dict[str, float]] = {}
    for name in EMOTIONS:
        names, values = template_points(name), template_fapu(name, face.fapu)
        moved = np.abs(values).max(axis=1) > 0
        row = {"plain": float(np.median(np.linalg.norm(values[moved], axis=1)))}
        for widths in WIDTHS:
            row[widths] = float(np.median(leave_one_out(face.points, names, values, widths)[moved]))
        out[name] = row
    return out


def generate_figures() -> dict[str, tuple[float, float, str]]:
    """{"plain" / "marked": (SVG MB per minute of audio, median wall seconds of generate, the
    SVG's KB per minute by track: bench/generate.py's bytes_by_track)}."""
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        marked = Path(tmp) / "marked.txt"
        marked.write_text(MARKED, encoding="utf-8")
        for label, transcript, options in (("plain", STORY / "story.txt", Options()),
                                           ("marked", marked, Options(emotion=DEFAULT_MOOD[0],
                                                                      intensity=DEFAULT_MOOD[1]))):
            seconds, svg, duration = [], b"", 1.0
            for run in range(RUNS):
                out_dir = Path(tmp) / f"{label}{run}"
                result = generate(SAMPLE_FACES / "female.json", STORY / "story.wav", transcript, out_dir, options)
                seconds.append(result.seconds)
                svg, duration = (out_dir / "animation.svg").read_bytes(), result.duration
            out[label] = (len(svg) / 1e6 * 60 / duration, statistics.median(seconds), bytes_by_track(svg, duration / 60))
    return out


def main() -> None:
    """Print the pixel, leave-one-out and generate figures."""
    for name, face in faces():
        singles, pairs = pixel_shares(face)
        print(f"{name}: vs neutral (face measure, figure measure in brackets): " + ", ".join(
            f"{e} {100 * f:.1f} % ({100 * g:.1f} %)" for e, (f, g) in singles.items()))
        closest = sorted(pairs.items(), key=lambda item: item[1])[:3]
        print("  closest pairs: " + ", ".join(f"{a}/{b} {100 * v:.2f} %" for (a, b), v in closest))
        ok = min(f for f, _ in singles.values()) >= GOAL_EMOTION and closest[0][1] >= GOAL_PAIR
        print(f"  goals (each >= {100 * GOAL_EMOTION:g} %, pairs >= {100 * GOAL_PAIR:g} %): {'met' if ok else 'NOT met'}")
        errors = loo_errors(face)
        rules = ("plain",) + WIDTHS
        print("  leave-one-out median error, px (d = %g): " % face.fapu.d + "; ".join(
            f"{e} " + " ".join(f"{r} {errors[e][r]:.1f}" for r in rules) for e in EMOTIONS))
        print("  median over emotions: " + ", ".join(
            f"{r} {statistics.median(errors[e][r] for e in EMOTIONS):.2f}" for r in rules))
        started = time.perf_counter()
        rig.cache_clear()
        rig(lift(face))
        print(f"  rig with the emotions' RBF transfer: {1000 * (time.perf_counter() - started):.1f} ms")
    for label, (per_minute, seconds, tracks) in generate_figures().items():
        print(f"story {label}: SVG {per_minute:.2f} MB per minute, generate {seconds:.2f} s (median of {RUNS}); {tracks}")


def contact_sheet(face: FaceModel, shapes: tuple[str, ...] = MOUTH_SYMBOLS, across: bool = False) -> bytes:
    """PNG (256 colours): neutral and each emotion at intensity 1 (rows, or columns when
    `across`) x the rest mouth (gamma 1) and the mouth `shapes` as spoken (gamma LIPS_SPEAKING)."""
    moods = ("neutral",) + EMOTIONS
    grid = [[FaceState(emotion=() if name == "neutral" else ((name, 1.0),), lips=1.0 if s == REST else LIPS_SPEAKING)
             .with_mouth("m" if s == REST else s) for s in (REST, *shapes)] for name in moods]
    if across:
        rows = [(s, [line[k] for line in grid]) for k, s in enumerate((REST, *shapes))]
        root = sheet_svg(face, rows, list(moods), SHEET_CELL)
    else:
        root = sheet_svg(face, list(zip(moods, grid, strict=True)), [REST, *shapes], SHEET_CELL)
    return svg_to_png(svg_bytes(root), palette=True)


def rbf_picture(face: FaceModel) -> Image.Image:
    """Happy, surprise and disgust (columns) by plain FAPU scaling (top row), by the RBF with all
    its moves (middle row) and by the RBF as the animation draws it (face/emotion.py drawn_moves:
    the ears and the forehead under the hair held, the contour moved only across itself; bottom
    row), the points no template names marked in red in the two RBF rows."""
    raw = np.array([deform(face.points, template_points(name), template_fapu(name, face.fapu)) for name in EMOTIONS])
    tiles = []
    for moves, dots in ((emotion_displacements(face, None), False), (raw, True), (drawn_moves(face, raw), True)):
        row = []
        for name in ("happy", "surprise", "disgust"):
            moved = moves[EMOTIONS.index(name)]
            image = picture(face_svg(replace(face, points=face.points + moved), FaceState()))
            if dots:
                draw = ImageDraw.Draw(image)
                named = set(template_points(name))
                for point, (x, y) in zip(POINT_NAMES, face.points + moved, strict=True):
                    if point not in named:
                        draw.ellipse((x - DOT, y - DOT, x + DOT, y + DOT), fill=DOT_COLOUR)
            row.append(image.crop(CROP))
        tiles.append(row)
    width, height = tiles[0][0].size
    sheet = Image.new("RGB", (len(tiles[0]) * width, len(tiles) * height), "white")
    for r, row in enumerate(tiles):
        for c, tile in enumerate(row):
            sheet.paste(tile, (c * width, r * height))
    return sheet


def pictures(folder: Path) -> None:
    """Write the contact sheets and the RBF comparison into `folder`."""
    folder.mkdir(parents=True, exist_ok=True)
    for name in ("female", "male"):
        (folder / f"emotions-{name}.png").write_bytes(contact_sheet(load_face(SAMPLE_FACES / f"{name}.json")))
    photo_faces = faces()[2:]
    if photo_faces:
        (folder / "emotions-astronaut.png").write_bytes(contact_sheet(photo_faces[0][1], ASTRONAUT_SHAPES, True))
    rbf_picture(load_face(SAMPLE_FACES / "female.json")).quantize(256).save(folder / "emotions-rbf.png")


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--pictures":
        pictures(Path(sys.argv[2]))
    else:
        main()
