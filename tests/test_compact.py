"""The compactor's shared definitions (render/compact.py): a clip path that several drawings hold
alike (an eye's outline under different gazes) is written once, and the frames using it look the
same as when each frame carries its own copy."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
from lxml import etree
from PIL import Image

from cartoonface.face.model import load_face
from cartoonface.face.state import FaceState, Pose
from cartoonface.render.animation import animation_svg
from cartoonface.render.png import svg_to_png
from tests.stills import frozen

ROOT = Path(__file__).resolve().parent.parent
NS = {"s": "http://www.w3.org/2000/svg"}
S = "{http://www.w3.org/2000/svg}"
FPS = 30
# A still head looking about (gaze_h, gaze_v in degrees), then turning, so that some eye
# outlines repeat under different gazes and others do not.
GAZES = ((0.0, 0.0), (6.0, 0.0), (-6.0, 2.0), (0.0, 5.0), (9.0, -3.0), (0.0, 0.0))


@pytest.fixture(scope="module")
def face():
    return load_face(ROOT / "samples" / "faces" / "female.json")


def looking_about() -> list[FaceState]:
    """Frames of a still head glancing about, then of a turning head; mouths vary."""
    still = [FaceState(gaze_h=h, gaze_v=v, mouth=((symbol, 1.0),))
             for (h, v), symbol in zip(GAZES, "aoeium", strict=True) for _ in range(2)]
    turning = [FaceState(pose=Pose(turn=float(i), tilt=i / 2), gaze_h=3.0 * (i % 2)) for i in range(4)]
    return still + turning


def pixels(data: bytes) -> np.ndarray:
    with Image.open(io.BytesIO(svg_to_png(data))) as image:
        return np.asarray(image.convert("RGBA"), dtype=np.int16)


def test_clip_paths_shared_by_several_drawings_are_written_once(face):
    svg = etree.fromstring(animation_svg(face, looking_about(), FPS))
    defs = svg.find("s:defs", NS)
    shared = [clip for clip in defs.iterfind("s:clipPath", NS)]
    assert shared, "the still head's eye outlines are shared by the drawings of its gazes"
    outlines = [etree.tostring(clip[0]).replace(f' id="{clip[0].get("id")}"'.encode(), b"") for clip in shared]
    assert len(outlines) == len(set(outlines)), "each shared clip path once"
    used = {node.get("clip-path")[5:-1] for node in svg.iter() if node.get("clip-path")}
    for clip in shared:
        assert clip.get("id") in used
        users = [node for node in svg.iter() if node.get("clip-path") == f"url(#{clip.get('id')})"]
        assert len(users) >= 2, "only clip paths of two or more drawings are shared"
    inside = [clip for clip in svg.find("s:g[@id='face']", NS).iter(f"{S}clipPath")]
    assert inside, "the turning head's clip paths, each of one drawing, stay in their frames"


def in_frame_copies(data: bytes) -> bytes:
    """The still SVG `data` with each reference to a shared clip path (a `clip-path` or a `<use>`
    of its outline) given a copy of it of its own, placed just before the referring element and
    the shared ones removed: the form the compactor wrote before it shared them."""
    svg = etree.fromstring(data)
    shared = {clip.get("id"): clip for clip in svg.find("s:defs", NS).iterfind("s:clipPath", NS)}
    referring = [node for node in svg.iter() if node.get("clip-path", "")[5:-1] in shared
                 or node.get("href", "")[1:-1] in shared]
    for number, node in enumerate(referring):
        name = node.get("clip-path", "")[5:-1] or node.get("href")[1:-1]
        copy = etree.fromstring(etree.tostring(shared[name]))
        copy.set("id", f"copy{number}")
        copy[0].set("id", f"copy{number}_")
        node.addprevious(copy)
        if node.get("clip-path"):
            node.set("clip-path", f"url(#copy{number})")
        else:
            node.set("href", f"#copy{number}_")
    for clip in shared.values():
        clip.getparent().remove(clip)
    return etree.tostring(svg)


@pytest.mark.parametrize("frame", [0, 3, 7, 9, 12, 15])
def test_a_frame_with_shared_clip_paths_looks_as_with_its_own(face, frame):
    # the frame at the same time, drawn with the shared clip paths and with copies of its own
    still = frozen(animation_svg(face, looking_about(), FPS), frame, FPS)
    before = in_frame_copies(still)
    assert before != still, "the frame uses shared clip paths"
    after, own = pixels(still), pixels(before)
    assert after.shape == own.shape
    differ = np.abs(after - own).max(axis=2) > 2
    assert differ.mean() < 1e-4, f"{differ.sum()} pixels differ"
