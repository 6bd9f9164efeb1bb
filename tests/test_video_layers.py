"""The MP4's frames put together from layers (exports/layers.py, exports/compositor.py) are the
frames of the whole document: the newsroom announcer (background, desk in front, moving
clothes, rolled head) put together piece by piece against the resolved document drawn whole."""

from __future__ import annotations

import multiprocessing
import shutil
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from cartoonface.exports.compositor import PAD_COLOUR, Compositor, draw, stage
from cartoonface.exports.frames import FrameDocuments
from cartoonface.exports.layers import FOOTPRINT_SHRINK, Layers, bounds, footprint_bounds, spills, union
from cartoonface.exports.video import fit
from cartoonface.pipeline import Options, generate
from tests.conftest import spoken_inputs

ROOT = Path(__file__).resolve().parent.parent
FACE = ROOT / "samples" / "faces" / "male.json"
FPS = 24
SIZE = (640, 360)  # the video: the 16:9 stage fills it
pytestmark = pytest.mark.skipif(not shutil.which("espeak-ng"), reason="needs espeak-ng")


_SCENE: tuple | None = None  # (frames, layers, stage) for the forked drawing processes


def in_child(function, *args):
    """`function(*args)` in a forked process: libvips starts threads when it draws, and a process
    that has drawn must not fork afterwards (write_video's workers in a later test would hang)."""
    with multiprocessing.get_context("fork").Pool(1) as pool:
        return pool.apply(function, args)


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    """The layers and stage of a short newsroom announcer page, with its frame documents and distinct frames."""
    global _SCENE
    folder = tmp_path_factory.mktemp("layers")
    speech, transcript = spoken_inputs(folder, "你好。今天天气很好，我们出去走走吧。", speed=150)
    result = generate(FACE, speech, transcript, folder / "site",
                      Options(page="announcer", fps=FPS, background="newsroom", clothes="sweater"))
    frames = FrameDocuments((result.out_dir / "animation.svg").read_bytes(), FPS, result.frames)
    layers = Layers(frames, fit(frames.view_size, SIZE))
    keys = [frames.key(frame) for frame in range(result.frames)]
    distinct = [frame for frame in range(result.frames) if frame == 0 or keys[frame] != keys[frame - 1]]
    with multiprocessing.get_context("fork").Pool(1) as pool:
        built = stage(layers, distinct, SIZE, pool.map)
    _SCENE = (frames, layers, built)
    yield frames, layers, built, distinct
    _SCENE = None


def whole_frame(frame: int) -> np.ndarray:
    """The resolved document of `frame` drawn whole on the video's background, (h, w, 3) float."""
    assert _SCENE is not None
    drawn = draw(_SCENE[0].document(frame, *SIZE))
    picture = Image.new("RGB", SIZE, PAD_COLOUR)
    picture.paste(drawn, (0, 0), drawn)
    return np.asarray(picture, dtype=float)


def composed(order: list[int]) -> list[np.ndarray]:
    """The frames `order` put together one after another by one compositor, (h, w, 3) float each."""
    assert _SCENE is not None
    compositor = Compositor(_SCENE[2])
    return [np.asarray(compositor.frame(frame), dtype=float) for frame in order]


def piece_bounds(looks: list[tuple[int, int]]) -> list[tuple[int, int, int, int] | None]:
    """For each (animated piece index, frame): the bounds of the piece drawn alone on the whole picture."""
    assert _SCENE is not None
    layers = _SCENE[1]
    whole = layers.whole()
    return [bounds(draw(layers.document(layers.piece_text(layers.animated[index], frame), whole, frame)), whole)
            for index, frame in looks]


def test_the_still_background_is_the_base_and_the_face_layer_is_cut_into_its_tracks(scene):
    frames, layers, _, _ = scene
    order = {element: k for k, element in enumerate(frames.root.iter())}
    positions = [order[piece.element] for piece in layers.pieces]
    assert positions == sorted(positions)  # paint order
    assert layers.base and all(not piece.tracks for piece in layers.base)
    assert all(piece.element.get("id") != "face" for piece in layers.pieces)
    parts = {piece.element.get("data-part") for piece in layers.animated}
    assert {"face", "eyes", "features"} <= parts
    desk = [piece for piece in layers.animated if piece.element.get("id") == "desk"]
    assert desk and not desk[0].tracks  # in front of the moving clothes: pasted over them, never redrawn
    assert all(piece.tracks for piece in layers.animated if piece.element.get("data-part"))


def test_frames_put_together_are_the_whole_document_drawn(scene):
    frames, _, _, distinct = scene
    # forwards, then back and forth: pieces come from the cache and the restored regions must hold
    chosen = distinct[:: max(1, len(distinct) // 8)]
    order = [*chosen, *reversed(chosen[:-1]), chosen[len(chosen) // 2]]
    whole = dict(zip(chosen, in_child(_whole_frames, chosen), strict=True))
    for frame, put in zip(order, in_child(composed, order), strict=True):
        own = np.abs(put - whole[frame])
        others = [np.abs(put - whole[other]).mean() for other in chosen if frames.key(other) != frames.key(frame)]
        # pasting straight-alpha pieces one by one rounds edge pixels differently from drawing
        # them into one canvas: a level at a few edge pixels (measured: mean 0.004)
        assert own.mean() < 0.05 and np.percentile(own, 99.9) <= 3, (frame, own.mean())
        assert not others or own.mean() < 0.2 * min(others), (frame, own.mean(), others)


def _whole_frames(chosen: list[int]) -> list[np.ndarray]:
    """whole_frame of each of `chosen`."""
    return [whole_frame(frame) for frame in chosen]


def test_every_look_of_a_piece_stays_inside_its_box(scene):
    _, layers, built, distinct = scene
    asked = []
    for index, piece in enumerate(layers.animated):
        looks = {piece.look(frame): frame for frame in distinct}
        asked += [(index, frame) for frame in list(looks.values())[:: max(1, len(looks) // 5)]]
    for (index, _), seen in zip(asked, in_child(piece_bounds, asked), strict=True):
        box = built.boxes[index]
        if seen is not None:
            assert box is not None and union([box, seen]) == box, (index, seen, box)


def test_a_footprint_covers_a_thin_line_and_a_box_edge_is_told():
    width, height = 64, 48
    picture = Image.new("RGBA", (width // FOOTPRINT_SHRINK, height // FOOTPRINT_SHRINK))
    assert footprint_bounds(picture, (0, 0, width, height), (width, height)) is None
    picture.putpixel((5, 3), (0, 0, 0, 1))  # one barely covered shrunk pixel
    x, y, w, h = footprint_bounds(picture, (0, 0, width, height), (width, height))
    # the full-size pixels under it and one shrunk pixel around, inside the picture
    assert x <= 5 * FOOTPRINT_SHRINK and x + w >= 6 * FOOTPRINT_SHRINK and y <= 3 * FOOTPRINT_SHRINK
    assert x + w <= width and y + h <= height and w == 3 * FOOTPRINT_SHRINK
    box, picture_box = (10, 10, 20, 20), (0, 0, 100, 100)
    assert not spills((12, 12, 5, 5), box, picture_box)
    assert spills((10, 12, 5, 5), box, picture_box) and spills((12, 12, 18, 5), box, picture_box)
    assert not spills((0, 0, 5, 5), (0, 0, 20, 20), picture_box)  # the picture's own edge
