"""The animation SVG: layers, each track's drawings shown by one <use> whose href tiles the timeline,
merging, rounding, references."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest
from lxml import etree

from cartoonface.errors import OptionError
from cartoonface.face.model import load_face
from cartoonface.face.state import FaceState, Pose
from cartoonface.face.lift import lift
from cartoonface.face.pose import pose_face, rig, unroll
from cartoonface.render.animation import KEY_TIME_DECIMALS, KEY_TIME_LEAD, KEY_TIME_MIN_LEAD, animation_svg, clock
from cartoonface.render.pathdata import MIRROR, TOLERANCE, compacted

ROOT = Path(__file__).resolve().parent.parent
NS = {"s": "http://www.w3.org/2000/svg"}
S = "{http://www.w3.org/2000/svg}"


@pytest.fixture(scope="module")
def face():
    return load_face(ROOT / "samples" / "faces" / "female.json")


def talking(*mouths: tuple[str, int]) -> list[FaceState]:
    """A still head saying `mouths`: (symbol, frames) in a row."""
    return [FaceState(mouth=((symbol, 1.0),)) for symbol, count in mouths for _ in range(count)]


def shows(track: etree._Element) -> etree._Element:
    """The discrete <animate> of the href of a track's one <use> (checked: discrete, frozen, its first
    value the <use>'s own href)."""
    use = track.find("s:use", NS)
    animate = use.find("s:animate", NS)
    assert animate.get("attributeName") == "href" and animate.get("calcMode") == "discrete"
    assert animate.get("fill") == "freeze", "the last drawing stays"
    assert use.get("href") == animate.get("values").split(";")[0], "without SMIL the first drawing shows"
    return animate


def intervals(track: etree._Element) -> list[tuple[int, int, etree._Element]]:
    """(begin ms, end ms, drawing) of every run of a track, in time order: the key times of its
    <use>'s href animation (fractions of its dur) and the drawings of the track's <defs> they show.
    A run ends where the next begins, the last at the end of the animation."""
    animate = shows(track)
    total = float(animate.get("dur")) * 1000
    begins = [round(float(value) * total) for value in animate.get("keyTimes").split(";")]
    values = animate.get("values").split(";")
    assert len(values) == len(begins) and begins[0] == 0
    drawings = {node.get("id"): node for node in track.find("s:defs", NS)}
    ends = begins[1:] + [round(total)]
    assert all(begin < end for begin, end in zip(begins, ends)), "time order"
    return [(begin, end, drawings[value[1:]]) for begin, end, value in zip(begins, ends, values, strict=True)]


def content(frame: etree._Element) -> bytes:
    """A drawing's elements: the `<g id>`'s children, or the drawing of one element without its id."""
    if frame.tag == f"{S}g" and frame.get("id", "").startswith("f"):
        return b"".join(etree.tostring(child) for child in frame)
    alone = etree.fromstring(etree.tostring(frame))
    del alone.attrib["id"]
    return etree.tostring(alone)


def tracks(svg: etree._Element) -> dict[str, etree._Element]:
    return {g.get("data-part"): g for g in svg.iterfind(".//s:g[@data-part]", NS)}


def test_key_times_tile_the_timeline_on_the_frame_boundaries(face):
    fps = 30
    states = talking(("m", 5), ("a", 4), ("m", 3), ("o", 2), ("m", 4), ("i", 1))
    svg = etree.fromstring(animation_svg(face, states, fps))
    animated = {name: g for name, g in tracks(svg).items() if g.find("s:use/s:animate", NS) is not None}
    assert animated, "a talking face has at least one animated track"
    end = round(len(states) * 1000 / fps)
    for name, track in animated.items():
        spans = intervals(track)
        assert spans[-1][1] >= end, name
        for _, _, frame in spans:
            assert frame.getparent() is track.find("s:defs", NS), f"{name}: drawings are only shown by the <use>"
        animate = shows(track)
        total = float(animate.get("dur"))
        for at in (float(value) * total * 1000 for value in animate.get("keyTimes").split(";")[1:]):
            boundary = round(round(at * fps / 1000) * 1000 / fps)  # whole ms, as the frames begin
            step = total * 1000 / 10 ** KEY_TIME_DECIMALS  # ms
            early = max(KEY_TIME_LEAD * step, KEY_TIME_MIN_LEAD) + 2 * step  # the lead, rounded down
            assert boundary - early <= at < boundary, (
                f"{name}: key time {at} ms is not just before a frame boundary")


def test_identical_frames_are_merged_and_written_once(face):
    states = talking(("m", 5), ("a", 4), ("m", 3), ("a", 2), ("m", 4))
    svg = etree.fromstring(animation_svg(face, states, 30))
    mouth = next(g for g in tracks(svg).values() if g.find(".//s:g[@data-shape]", NS) is not None)
    spans = intervals(mouth)
    runs = [frame for _, _, frame in spans]
    assert len(runs) == 5, "one value per run of equal frames"
    assert all(a is not b for a, b in zip(runs, runs[1:])), "neighbouring runs are different drawings"
    frames = mouth.findall("s:defs/s:g", NS)
    assert len(frames) == 2, "the rest mouth and 'a' are each written once"
    assert len({content(f) for f in frames}) == len(frames)
    shapes = sorted(f.get("data-shape") for f in frames)
    assert shapes == ["a", "m"]
    rest = next(f for f in frames if f.get("data-shape") == "m")
    assert len([span for span in spans if span[2] is rest]) == 3, "the rest mouth shows three times"
    assert len(mouth.findall("s:use", NS)) == 1, "one <use> shows them all"


def test_still_parts_stay_outside_frames(face):
    states = talking(("m", 3), ("a", 3), ("m", 3))
    svg = etree.fromstring(animation_svg(face, states, 30))
    found = tracks(svg)
    still = [name for name, g in found.items() if g.find(".//s:animate", NS) is None]
    assert {"hair", "eyes"} <= set(still)
    for name in still:
        assert not found[name].findall("s:defs", NS), f"{name} has no drawings to choose from"
        assert len(found[name]) > 0, f"{name} is drawn"


def test_a_moving_head_is_drawn_in_every_frame(face):
    turn = [FaceState(pose=Pose(turn=0.5 * i)) for i in range(12)]
    for fps in (12, 30, 60):
        hair = tracks(etree.fromstring(animation_svg(face, turn, fps)))["hair"]
        spans = intervals(hair)
        assert len(spans) == len(turn), f"{fps} fps: one drawing per pose"
        assert len({content(frame) for _, _, frame in spans}) == len(turn)


def roll_at(svg: etree._Element, layer: str, ms: int) -> tuple[float, float, float]:
    """(angle, cx, cy) of the rotation the layer's discrete <animateTransform> shows at `ms`."""
    turn = svg.find(f"s:g[@id='{layer}']/s:animateTransform", NS)
    assert turn.get("type") == "rotate" and turn.get("calcMode") == "discrete"
    values = [tuple(map(float, v.split())) for v in turn.get("values").split(";")]
    times = [float(t) * float(turn.get("dur")) * 1000 for t in turn.get("keyTimes").split(";")]
    assert times[0] == 0 and len(times) == len(values)
    return values[max(i for i, t in enumerate(times) if t <= ms + 0.01)]


def test_roll_is_a_rotation_of_the_head_layers_matching_the_posed_face(face):
    rolls = [0, 0, 4, 4, 4, -7.5, -7.5, 15, 0]
    states = [FaceState(pose=Pose(tilt=3, turn=-6, roll=r), mouth=(("a", 1.0),)) for r in rolls]
    svg = etree.fromstring(animation_svg(face, states, 30))
    face_track = tracks(svg)["face"]
    assert not face_track.findall("s:defs", NS), "the roll alone redraws nothing"
    lifted = lift(face)
    origin = rig(lifted).origin
    for index, state in enumerate(states):
        angles = {roll_at(svg, layer, round(index * 1000 / 30)) for layer in ("hair", "face")}
        assert len(angles) == 1, "hair and face turn together"
        angle, cx, cy = angles.pop()
        assert angle == pytest.approx(-state.pose.roll)
        posed = pose_face(lifted, state)
        drawn = unroll(posed, state.pose.roll, origin)
        if state.pose.roll:  # drawn without roll: as the unrolled pose, pupils within 0.05 px per degree
            flat = pose_face(lifted, dataclasses.replace(state, pose=Pose(tilt=3, turn=-6)))
            assert np.abs(drawn.hair - flat.hair).max() < 1e-6
            assert np.hypot(*(drawn.pupils - flat.pupils).T).max() < 0.05 * abs(state.pose.roll) + 1e-6
        a = np.radians(angle)  # SVG rotate(a cx cy), clockwise on screen
        for mine, theirs in ((drawn.xy, posed.xy), (drawn.hair, posed.hair)):
            moved = (mine - (cx, cy)) @ np.array([[np.cos(a), np.sin(a)], [-np.sin(a), np.cos(a)]]) + (cx, cy)
            gap = np.hypot(*(moved - theirs).T).max()
            assert gap < 1e-3, f"roll {state.pose.roll}: the turned drawing is off by {gap:.4f} px"
    assert svg.find("s:g[@id='clothes']/s:animateTransform", NS) is None


def test_a_head_that_never_rolls_has_no_rotation(face):
    svg = etree.fromstring(animation_svg(face, [FaceState(pose=Pose(turn=i)) for i in range(4)], 30))
    assert not svg.findall(".//s:animateTransform", NS)


def test_layers_references_ids_and_rounding(face):
    states = [FaceState(pose=Pose(tilt=i % 3, turn=-i % 4), blink=(i % 5) / 4, mouth=(("a", 0.5), ("o", 0.5)))
              for i in range(10)]
    data = animation_svg(face, states, 24, background="studio", clothes="suit")
    svg = etree.fromstring(data)
    assert [g.get("id") for g in svg.iterfind("s:g", NS)] == ["background", "hair", "clothes", "face"]
    ids = [node.get("id") for node in svg.iter() if node.get("id")]
    assert len(ids) == len(set(ids))
    text = data.decode()
    for target in set(re.findall(r'url\(#([^)]+)\)', text)) | set(re.findall(r'href="#([^"]+)"', text)):
        assert target in ids, f"dangling reference #{target}"
    def holder(node):  # the frame or shared definition a node is drawn with
        while node is not None and not (node.getparent().tag == f"{S}defs" or node.get("data-part")):
            node = node.getparent()
        return node

    clips = {clip.get("id"): clip for clip in svg.iter(f"{S}clipPath")}
    users = [node for node in svg.iter() if node.get("clip-path")]
    assert users, "the eyes and the mouth are clipped"
    for node in users:
        clip = clips[node.get("clip-path")[5:-1]]
        shared = clip.getparent() is svg.find("s:defs", NS)  # several drawings' clip path, never hidden
        assert shared or holder(clip) is holder(node), "a clip path shows (is not hidden) whenever its user does"
    for node in svg.find("s:g[@id='face']", NS).iter(f"{S}path"):
        assert not re.search(r"\d\.\d", node.get("d")), "face coordinates are whole pixels"


def test_user_title_is_escaped(face):
    title = '<script>alert("x")</script> & 小白兔'
    svg = etree.fromstring(animation_svg(face, talking(("m", 2)), 30, title=title))
    assert svg.findtext("s:title", namespaces=NS) == title
    assert not svg.findall(".//s:script", NS) and not svg.findall(".//script")


def test_same_input_same_bytes_and_wide_stage(face):
    states = talking(("m", 2), ("e", 3))
    assert animation_svg(face, states, 30) == animation_svg(face, states, 30)
    wide = etree.fromstring(animation_svg(face, states, 30, wide=True, background="newsroom"))
    _, _, width, height = map(float, wide.get("viewBox").split())
    assert width / height == pytest.approx(16 / 9, rel=1e-4)


@pytest.mark.parametrize("option", [{"background": "moon"}, {"clothes": "cape"}])
def test_unknown_scenery_is_refused(face, option):
    with pytest.raises(OptionError, match="expected one of"):
        animation_svg(face, talking(("m", 2)), 30, **option)


@pytest.mark.parametrize("ms", [0, 1, 33, 500, 999, 1000, 61234])
def test_clock_values_read_back(ms):
    assert round(float(clock(ms)) * 1000) == ms


def absolute_points(d: str) -> list[tuple[float, float]]:
    """Every point (end and control) of a relative m/l/c/s/z path, in absolute coordinates
    (the mirrored first control point of an `s` included)."""
    tokens = re.findall(r"[a-zA-Z]|-?\d+(?:\.\d+)?", d)
    points, x, y, start, command, index = [], 0.0, 0.0, (0.0, 0.0), "", 0
    while index < len(tokens):
        if tokens[index].isalpha():
            command = tokens[index]
            index += 1
            if command == "z":
                x, y = start
                continue
        count = {"m": 1, "l": 1, "c": 3, "s": 2}[command]
        pairs = [(x + float(tokens[index + 2 * k]), y + float(tokens[index + 2 * k + 1])) for k in range(count)]
        if command == "s":
            (px, py) = points[-2]
            pairs.insert(0, (2 * x - px, 2 * y - py))
        index += 2 * count
        points += pairs
        x, y = pairs[-1]
        if command == "m":
            start, command = (x, y), "l"
    return points


def test_compact_curves_keep_every_point_to_the_pixel():
    rng = np.random.default_rng(1)
    numbers = rng.uniform(0, 400, size=(5, 2, 13))
    paths = [f"M{a[0, 0]:.1f} {a[1, 0]:.1f}" + "".join(
        f"C{a[0, k]:.1f} {a[1, k]:.1f} {a[0, k + 1]:.1f} {a[1, k + 1]:.1f} {a[0, k + 2]:.1f} {a[1, k + 2]:.1f}"
        for k in (1, 4, 7, 10)) + "Z" for a in numbers]
    compact = compacted(paths).compact
    for d in paths:
        given = np.rint(np.array(re.findall(r"\d+\.\d", d), dtype=float).reshape(-1, 2))
        assert np.array_equal(np.array(absolute_points(compact[d])), given)
        assert len(compact[d]) < len(d)


def test_compact_polylines_drop_only_points_near_the_line():
    t = np.linspace(0, np.pi, 80)
    xs, ys = 200 + 150 * np.cos(t), 200 - 60 * np.sin(t) + 0.2 * np.sin(40 * t)
    d = f"M{xs[0]:.1f} {ys[0]:.1f}" + "".join(f"L{x:.1f} {y:.1f}" for x, y in zip(xs[1:], ys[1:])) + "Z"
    kept = np.array(absolute_points(compacted([d]).compact[d]))
    assert 3 < len(kept) < 40
    given = np.rint(np.array(re.findall(r"\d+\.\d", d), dtype=float).reshape(-1, 2))
    for x, y in given:  # every rounded input point lies near the kept polyline
        a, b = kept[:-1], kept[1:]
        ab = b - a
        u = np.clip(((x - a[:, 0]) * ab[:, 0] + (y - a[:, 1]) * ab[:, 1]) / np.maximum((ab ** 2).sum(1), 1e-9), 0, 1)
        nearest = a + u[:, None] * ab
        assert np.hypot(nearest[:, 0] - x, nearest[:, 1] - y).min() <= TOLERANCE + 1e-9


def test_other_path_commands_are_left_alone():
    odd = ["M1 1H5V7", "m1 1l2 2", "M0 0A5 5 0 0 1 10 10"]
    assert compacted(odd).compact == {d: d for d in odd}


def test_paths_of_one_skeleton_with_other_counts_are_left_alone():
    """Path data with the same command letters but numbers repeating a command (implicit
    linetos) are not read as one skeleton; written ones are, numbers in any form."""
    odd = ["M1 2 3 4", "M1 2", "M-1.5-2"]
    assert compacted(odd).compact == {d: d for d in odd}
    plain = ["M1.4,2L-3.6 .5Z", "M10 20L30-.5Z"]  # whole pixels (.5 to even: 0), relative
    assert compacted(plain).compact == {plain[0]: "m1,2l-5-2z", plain[1]: "m10,20l20-20z"}


def test_smooth_joins_drop_the_mirrored_control_point():
    rng = np.random.default_rng(2)
    paths = []
    for _ in range(4):  # Catmull-Rom-like: each join's control points mirror around it
        knots = rng.uniform(50, 350, size=(5, 2))
        tangents = rng.uniform(-30, 30, size=(5, 2))
        d = f"M{knots[0, 0]:.1f} {knots[0, 1]:.1f}"
        for k in range(4):
            c1, c2 = knots[k] + tangents[k], knots[k + 1] - tangents[k + 1]
            d += f"C{c1[0]:.1f} {c1[1]:.1f} {c2[0]:.1f} {c2[1]:.1f} {knots[k + 1, 0]:.1f} {knots[k + 1, 1]:.1f}"
        paths.append(d)
    compact = compacted(paths).compact
    for d in paths:
        assert "s" in compact[d]
        given = np.rint(np.array(re.findall(r"\d+\.\d", d), dtype=float).reshape(-1, 2))
        assert np.abs(np.array(absolute_points(compact[d])) - given).max() <= MIRROR


def test_many_drawings_have_unique_ids_and_every_reference_resolves(face):
    # enough distinct mouths, eyes and poses for ids of three base-36 digits
    symbols = ("a", "o", "e", "i", "u", "m")
    states = [FaceState(pose=Pose(tilt=(i % 7) - 3, turn=(i % 11) - 5, roll=(i % 5) - 2), blink=(i % 9) / 8,
                        mouth=((symbols[i % 6], 0.3 + 0.7 * (i % 13) / 12), (symbols[(i + 1) % 6], 0.7 - 0.7 * (i % 13) / 12)))
              for i in range(400)]
    data = animation_svg(face, states, 30)
    svg = etree.fromstring(data)
    ids = [node.get("id") for node in svg.iter() if node.get("id")]
    assert len(ids) > 1500
    assert len(ids) == len(set(ids)), "ids are unique"
    by_id = {node.get("id"): node for node in svg.iter() if node.get("id")}
    for use in svg.iter(f"{S}use"):
        target = by_id[use.get("href")[1:]]
        # a drawing (a <g>, or a drawing of one element without one), or a clip path's outline
        assert target.tag in (f"{S}g", f"{S}path", f"{S}ellipse", f"{S}circle", f"{S}use")
        if target.getparent().tag == f"{S}clipPath":  # a clip path's outline drawn again: it styles nothing itself
            assert target.tag == f"{S}path" and target.get("class") is None
            assert use.get("class"), "the <use> carries the style"
            frame = use
            while frame.getparent().tag != f"{S}defs" and frame.get("data-part") is None:
                frame = frame.getparent()
            shared = target.getparent().getparent() is svg.find("s:defs", NS)  # several drawings' clip path
            assert shared or target in frame.iter(), "the outline sits in the same frame as its use"
    for node in svg.iter():
        for value in node.attrib.values():
            for target in re.findall(r"url\(#([^)]+)\)", value):
                assert target in by_id, f"dangling reference #{target}"
