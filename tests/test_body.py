"""The body under the head (issue 11): shoulders that follow the head and breathe, drawn as
transforms of the clothes layer, the news desk, and the neck joined to the head throughout."""

from __future__ import annotations

import itertools
import json
import shutil
from dataclasses import replace

import numpy as np
import pytest
from lxml import etree

from cartoonface.animate.body import FOLLOW, body_motion, follow
from cartoonface.face.lift import lift
from cartoonface.face.model import load_face
from cartoonface.face.pose import pose_face
from cartoonface.face.state import FaceState, Pose
from cartoonface.pipeline import Options, generate
from cartoonface.render.animation import animation_svg
from cartoonface.render.scenery import BACKGROUNDS, CLOTHES, NECK_TOP, figure_of, neck_pivot
from tests.conftest import ROOT, spoken_inputs
from tests.shapes import polygon

SVG = "{http://www.w3.org/2000/svg}"
FPS = 30


@pytest.fixture(params=("female", "male"), scope="module")
def face(request):
    return load_face(ROOT / "samples" / "faces" / f"{request.param}.json")


def _layer(root, name):
    return root.find(f"{SVG}g[@id='{name}']")


def _at_frames(animation, count: int) -> list[list[float]]:
    """The numbers of a discrete <animateTransform>'s value shown at each of `count` frames."""
    values = [[float(v) for v in value.split()] for value in animation.get("values").split(";")]
    times = np.array([float(t) for t in animation.get("keyTimes").split(";")]) * float(animation.get("dur"))  # s
    index = np.searchsorted(times, (np.arange(count) + 0.5) / FPS, side="right") - 1
    return [values[i] for i in index]


def test_the_shoulders_follow_a_share_of_the_head_late_and_smoothly():
    head = np.r_[np.zeros(30), np.full(60, 10.0)]  # the head leans 10 degrees at frame 30
    torso = follow(head, FPS)
    assert torso[:30] == pytest.approx(0.0)
    assert torso[-1] == pytest.approx(FOLLOW * 10.0, rel=0.02)  # a share of the head's angle
    half = int(np.argmax(torso >= FOLLOW * 5.0))
    assert half - 30 >= 0.1 * FPS  # halfway only a tenth of a second or more after the head
    steps = np.diff(torso[30:])
    assert (steps >= 0).all() and steps.max() < 0.2 * FOLLOW * 10.0  # no jump: eased in


def test_body_motion_needs_a_breath_per_frame():
    with pytest.raises(ValueError, match="one per frame"):
        body_motion([FaceState()] * 3, np.zeros(2), FPS)


def _breathing(count: int = 60) -> tuple[list[FaceState], np.ndarray]:
    states = [FaceState(pose=Pose(0, 8.0 if i >= 20 else 0.0, -6.0 if i >= 20 else 0.0)) for i in range(count)]
    breaths = np.clip(np.sin(np.linspace(0, np.pi, count)), 0, 1).round(2)
    return states, breaths


@pytest.mark.parametrize("clothes", CLOTHES)
def test_the_clothes_layer_breathes_and_follows_the_head(face, clothes):
    states, breaths = _breathing()
    root = etree.fromstring(animation_svg(face, states, FPS, clothes=clothes, wide=True,
                                          body=body_motion(states, breaths, FPS)))
    layer = _layer(root, "clothes")
    neck_moves = layer[0].find(f"{SVG}animateTransform[@type='translate']")
    neck_dy = [v[1] for v in _at_frames(neck_moves, len(states))]
    assert min(neck_dy) < 0 == neck_dy[0]  # the neck rises a little with the breath
    torso = layer.find(f"{SVG}g[@class='torso']")
    if clothes == "none":
        assert torso is None
        return
    shift = _at_frames(torso.find(f"{SVG}animateTransform[@type='translate']"), len(states))
    lean = _at_frames(torso.find(f".//{SVG}animateTransform[@type='rotate']"), len(states))
    dy = [v[1] for v in shift]
    assert min(dy) < 2 * min(neck_dy) < 0  # the shoulders rise more than the neck
    assert int(np.argmin(dy)) == pytest.approx(int(np.argmax(breaths)), abs=3)  # highest at the deepest breath
    assert shift[-1][0] > 0 and lean[-1][0] > 0  # towards the head's turn (image right) and roll
    for values in (shift, lean):  # ... but late: halfway a tenth of a second or more after the head moved
        assert next(i for i, v in enumerate(values) if v[0] >= values[-1][0] / 2) - 20 >= 0.1 * FPS
    drawn = {element.tag for element in torso.iter()}
    assert f"{SVG}path" in drawn  # the garment is inside the moving group, drawn once


def test_a_still_body_adds_no_animation(face):
    root = etree.fromstring(animation_svg(face, [FaceState()] * 10, FPS, clothes="suit", wide=True,
                                          body=body_motion([FaceState()] * 10, np.zeros(10), FPS)))
    assert _layer(root, "clothes").find(f".//{SVG}animateTransform") is None


@pytest.mark.parametrize("background", BACKGROUNDS)
def test_the_news_desk_stands_in_front_of_the_body_in_the_newsroom(face, background):
    root = etree.fromstring(animation_svg(face, [FaceState()], FPS, background=background, clothes="suit", wide=True))
    layers = [child.get("id") for child in root if child.get("id")]
    if background != "newsroom":
        assert "desk" not in layers
        return
    assert layers.index("clothes") < layers.index("desk") < layers.index("face")
    top = min(float(rect.get("y")) for rect in _layer(root, "desk").iter(f"{SVG}rect"))
    figure = figure_of(face, (0, 0, face.width, face.height))
    assert neck_pivot(figure) < top < float(root.get("height"))  # below the shoulders, inside the picture


def test_the_neck_joins_the_head_at_every_pose_while_breathing(face):
    angles = (-15.0, 0.0, 15.0)
    poses = [Pose(*p) for p in itertools.product(angles, angles, angles)]
    states = [FaceState(pose=pose) for pose in poses for _ in range(2)]
    breaths = np.array([0.0, 1.0] * len(poses))
    root = etree.fromstring(animation_svg(face, states, FPS, clothes="shirt", wide=True,
                                          body=body_motion(states, breaths, FPS)))
    layer = _layer(root, "clothes")
    neck_dy = [v[1] for v in _at_frames(layer[0].find(f"{SVG}animateTransform[@type='translate']"), len(states))]
    torso_dy = [v[1] for v in _at_frames(layer.find(f"{SVG}g[@class='torso']/{SVG}animateTransform"), len(states))]
    corners = polygon(layer.find(f".//{SVG}path[@class='neck']").get("d"))
    outline = polygon(layer.find(f".//{SVG}g[@class='torso']//{SVG}path").get("d").replace("C", "L"))
    collar = outline[:, 1].min()  # the top of the torso, where the neck goes in
    lifted = lift(face)
    fw = np.ptp(face.points[:, 0])
    for frame, state in enumerate(states):
        chin = pose_face(lifted, state).p("2.1")
        top, foot = corners[:, 1].min() + neck_dy[frame], corners[:, 1].max() + neck_dy[frame]
        assert top <= chin[1] - NECK_TOP * fw / 3, (state.pose, frame)  # its top behind the jaw
        assert foot >= collar + torso_dy[frame], (state.pose, frame)  # its foot inside the collar


@pytest.mark.skipif(not shutil.which("espeak-ng"), reason="needs espeak-ng")
def test_a_generated_announcer_breathes_and_its_breaths_are_editable(tmp_path):
    speech, transcript = spoken_inputs(tmp_path, "今天天气很好。我们去公园。", speed=160)
    options = Options(page="announcer", background="newsroom", clothes="suit", seed=2)
    site = generate(ROOT / "samples" / "faces" / "male.json", speech, transcript, tmp_path / "site", options).out_dir
    document = json.loads((site / "actions.json").read_text(encoding="utf-8"))
    assert [a for a in document["actions"] if a["kind"] == "breath"]
    root = etree.fromstring((site / "animation.svg").read_bytes())
    torso = _layer(root, "clothes").find(f"{SVG}g[@class='torso']")
    rises = {v[1] for v in _at_frames(torso.find(f"{SVG}animateTransform[@type='translate']"), 100)}
    assert min(rises) < 0  # the shoulders rise
    assert _layer(root, "desk") is not None
    document["actions"] = [a for a in document["actions"] if a["kind"] != "breath"]
    (tmp_path / "edited.json").write_text(json.dumps(document), encoding="utf-8")
    edited = generate(ROOT / "samples" / "faces" / "male.json", speech, transcript, tmp_path / "edited",
                      replace(options, actions=tmp_path / "edited.json")).out_dir
    layer = _layer(etree.fromstring((edited / "animation.svg").read_bytes()), "clothes")
    shifts = layer.findall(f".//{SVG}animateTransform[@type='translate']")
    assert all(float(v.split()[1]) == 0 for shift in shifts for v in shift.get("values").split(";"))  # no breathing


def test_a_desk_below_the_picture_is_left_out(face):
    from cartoonface.render.svg import face_svg

    portrait = face_svg(face, FaceState(), background="newsroom", clothes="suit")  # the canvas ends above the desk
    assert _layer(portrait, "desk") is None
    assert _layer(portrait, "clothes") is not None
