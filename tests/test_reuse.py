"""Drawings shown as an affine transform of an earlier drawing of their track (render/reuse.py):
the transform found puts every point within the tolerance, what is not a transform is written,
the document's references resolve and the frames look as when every drawing is written."""

from __future__ import annotations

import io
import pickle
from pathlib import Path

import numpy as np
import pytest
from lxml import etree
from PIL import Image

from cartoonface.face.lift import lift
from cartoonface.face.model import load_face
from cartoonface.face.pose import pose_face, pose_faces
from cartoonface.face.state import FaceState, Pose
from cartoonface.render.animation import MOUTH_TRACK, PARTS_ID, animation_svg
from cartoonface.render.png import svg_to_png
from cartoonface.render.reuse import (CANDIDATES, FIT_POINTS, TOLERANCE, Shape, _inverses, _largest, _largest_single,
                                      _near, _recipe, _scale_change, _single_slack, find, find_alike, fit, joined,
                                      read_parts, shapes_from, shapes_of)
from cartoonface.render.svg import all_face_parts, face_parts
from tests.stills import frozen

ROOT = Path(__file__).resolve().parent.parent
NS = {"s": "http://www.w3.org/2000/svg"}
S = "{http://www.w3.org/2000/svg}"
FPS = 30


@pytest.fixture(scope="module")
def face():
    return load_face(ROOT / "samples" / "faces" / "female.json")


def nodding(count: int) -> list[FaceState]:
    """`count` frames of a head turning and nodding slowly (a fraction of a degree a frame) while it
    talks and glances: drawings that differ by small pose changes, and mouths that change."""
    mouths = "amfoeiu"
    return [FaceState(pose=Pose(turn=6 * np.sin(i / 9), tilt=3 * np.sin(i / 13), roll=2 * np.sin(i / 11)),
                      gaze_h=4 * np.sin(i / 5), mouth=((mouths[i // 4 % len(mouths)], 1.0),))
            for i in range(count)]


@pytest.fixture(scope="module")
def documents(face):
    """The animation of `nodding` with every drawing written (tolerance 0) and with reuse."""
    states = nodding(90)
    return animation_svg(face, states, FPS, tolerance=0), animation_svg(face, states, FPS)


def part_shape(face, state: FaceState, name: str) -> Shape:
    parts = {part.name: part for part in face_parts(face, pose_face(lift(face), state), "u")}
    shape = shapes_of([(parts[name].text, *parts[name].clips)])[0]
    assert shape is not None and len(shape.points) > 10
    return shape


def apply(matrix: str, points: np.ndarray) -> np.ndarray:
    """SVG's matrix(a b c d e f) applied to `points` (N, 2)."""
    a, b, c, d, e, f = (float(v) for v in matrix.split())
    return np.column_stack([a * points[:, 0] + c * points[:, 1] + e, b * points[:, 0] + d * points[:, 1] + f])


def moved(shape: Shape, linear: np.ndarray, shift: tuple[float, float], noise: float = 0.0) -> Shape:
    rng = np.random.default_rng(7)
    points = shape.points @ linear.T + shift + rng.uniform(-noise, noise, shape.points.shape)
    return Shape(shape.skeleton, points, shape.stroke)


def turn(degrees: float, scale: float = 1.0) -> np.ndarray:
    angle = np.radians(degrees)
    return scale * np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])


@pytest.mark.parametrize("linear, shift, noise", [
    (turn(0.4), (1.3, -0.6), 0.0),
    (turn(-0.3, 1.01), (-2.0, 0.4), 0.15),
    (np.array([[1.0, 0.004], [0.0, 0.995]]), (0.0, 0.0), 0.1),  # a small shear, unequal scale
    (np.array([[-1.0, 0.0], [0.0, 1.0]]), (400.0, 0.0), 0.0),  # the mirror image: an affine too
])
def test_a_transformed_drawing_is_shown_by_a_transform_that_puts_every_point_within_the_tolerance(
        face, linear, shift, noise):
    source = part_shape(face, FaceState(gaze_h=3.0), "eye-l")
    target = moved(source, linear, shift, noise)
    found = find([source, target])
    assert set(found) == {1} and found[1].source == 0
    distances = np.hypot(*(apply(found[1].matrix, source.points) - target.points).T)
    assert distances.max() <= TOLERANCE
    assert found[1].error >= distances.max() - 1e-9, "the error told covers every point"


@pytest.mark.parametrize("shift, noise", [((0.0, 0.0), 0.2), ((2.0, -1.0), 0.2), ((0.3, 1.6), 0.0)])
def test_a_matrix_is_written_as_short_as_the_tolerance_allows(face, shift, noise):
    """A drawing that is an earlier one moved (and drawn a little off, `noise` px) is shown by that
    shift, not by the least-squares matrix's turn and scale of a few ten-thousandths."""
    source = part_shape(face, FaceState(mouth=(("a", 1.0),)), "mouth")
    target = moved(source, np.eye(2), shift, noise)
    found = find([source, target])
    a, b, c, d, e, f = (float(v) for v in found[1].matrix.split())
    assert (a, b, c, d) == (1, 0, 0, 1), found[1].matrix
    assert np.hypot(e - shift[0], f - shift[1]) < TOLERANCE
    distances = np.hypot(*(apply(found[1].matrix, source.points) - target.points).T)
    assert distances.max() <= TOLERANCE and found[1].error >= distances.max() - 1e-9


def test_what_is_not_a_transform_of_an_earlier_drawing_is_written(face):
    source = part_shape(face, FaceState(mouth=(("a", 1.0),)), "mouth")
    bent = source.points.copy()
    bent[len(bent) // 2] += (1.5, 0.0)  # one point off by more than the tolerance
    blended = part_shape(face, FaceState(mouth=(("a", 0.5), ("e", 0.5))), "mouth")
    assert find([source, Shape(source.skeleton, bent, source.stroke)]) == {}
    assert blended.skeleton == source.skeleton, "the same elements, other numbers"
    assert find([source, blended]) == {}, "a mouth half way to another shape is not a transform of it"
    # a scale that moves no point far from the centre still thickens the strokes: 9 px lid shadow
    eye = part_shape(face, FaceState(), "eye-l")
    centre = eye.points.mean(axis=0)
    grown = Shape(eye.skeleton, (eye.points - centre) * 1.2 + centre, eye.stroke)
    assert eye.stroke >= 2 and find([eye, grown], tolerance=1000.0)[1].error >= 0.2 * eye.stroke / 2


def test_a_part_is_found_among_all_earlier_parts_of_its_skeleton_not_only_recent_ones(face):
    """A mouth under another pose, many mouths of other mixes after the one it repeats."""
    source = part_shape(face, FaceState(mouth=(("a", 1.0),)), "mouth")
    mixes = [(("a", 1 - w), ("e", w)) for w in np.linspace(0.05, 0.95, 3 * CANDIDATES)]
    others = [shape for shape in (part_shape(face, FaceState(mouth=mix), "mouth") for mix in mixes)
              if shape.skeleton == source.skeleton]  # some mixes show the teeth: another skeleton
    assert len(others) > CANDIDATES
    target = moved(source, turn(0.3, 0.99), (1.5, -2.0))
    shapes = [source, *others, target]
    assert len(shapes) - 1 not in find(shapes), "beyond the recent drawings find looks at"
    found = find_alike(shapes)
    assert found[len(shapes) - 1].source == 0
    distances = np.hypot(*(apply(found[len(shapes) - 1].matrix, source.points) - target.points).T)
    assert distances.max() <= TOLERANCE
    assert all(reuse.error <= TOLERANCE for reuse in found.values())


def test_the_points_taken_from_the_numbers_as_drawn_are_those_read_from_the_text_to_the_bit(face):
    """The drawing hands the reuse search the numbers of its path data in tenths (pathdata.Tenths),
    and the drawing helper its parts read there (read_parts, pickled as sent back): the shapes are
    those read from the parts' texts, each number to the bit, whether all, some or none of the path
    data are in it, and for any choice of the parts read, in any order."""
    tenths: dict[str, np.ndarray] = {}
    drawn = all_face_parts(face, pose_faces(lift(face), nodding(12)), "u", tenths=tenths)
    parts = [(part.text, *part.clips) for drawing in drawn for part in drawing]
    parts[5:5] = [('<g class="x" transform="rotate(3)"><path d="M1 2L3 4"/></g>',), ('<rect width="2" height="3"/>',)]
    some = dict(list(tenths.items())[::2])
    read = shapes_of(parts)
    assert [index for index, shape in enumerate(read) if shape is None] == [5, 6], "what is not read"
    assert len({shape.skeleton for shape in read if shape is not None}) > 5
    chosen = np.random.default_rng(3).permutation(len(parts))[:len(parts) // 2].tolist()
    sent = pickle.loads(pickle.dumps(read_parts(parts, {}, tenths)))
    for taken_shapes, wanted in ((shapes_of(parts, tenths), range(len(parts))), (shapes_of(parts, some), range(len(parts))),
                                 (shapes_from(sent, chosen), chosen)):
        for index, taken in zip(wanted, taken_shapes, strict=True):
            shape = read[index]
            assert (shape is None) == (taken is None)
            if shape is not None and taken is not None:
                assert (taken.skeleton, taken.stroke) == (shape.skeleton, shape.stroke)
                assert taken.points.tobytes() == shape.points.tobytes()


def test_parts_read_from_their_forms_and_slots_are_those_read_from_their_texts(face):
    """A drawing process reads its parts from the slots it drew them from, placed as their Form
    (compact.Form) places them (read_parts' `formed`): the same skeletons, numbers to the bit and
    strokes as read from the texts, for every Form drawn (the mouths' many); a part whose slots are
    not its text's (no Form of it) is read from its text."""
    tenths: dict[str, np.ndarray] = {}
    forms: dict = {}
    drawn = all_face_parts(face, pose_faces(lift(face), nodding(60)), "u", tenths=tenths, forms=forms)
    distinct = list(dict.fromkeys(part for drawing in drawn for part in drawing))
    texts = [(part.text, *part.clips) for part in distinct]
    formed = [forms.get(part) for part in distinct]
    assert len({known[0] for known in formed if known is not None}) > 15 and None in formed, "many Forms; chin shadows none"
    liar = next(index for index, known in enumerate(formed) if known is not None and known[0].paths)
    form, slots = formed[liar]  # the first part of its Form, with another path data in its slot
    formed[liar] = (form, (slots[0].replace("1", "2", 1), *slots[1:]))
    assert formed[liar][1] != slots and _recipe(form, slots, texts[liar]) and not _recipe(*formed[liar], texts[liar])
    read, taken = read_parts(texts, {}, tenths), read_parts(texts, {}, tenths, formed)
    assert (taken.skeletons, taken.strokes) == (read.skeletons, read.strokes)
    assert taken.skeleton.tolist() == read.skeleton.tolist() and taken.row.tolist() == read.row.tolist()
    assert all(mine.tobytes() == theirs.tobytes() for mine, theirs in zip(taken.numbers, read.numbers, strict=True))


def test_a_drawing_s_shape_is_its_parts_one_after_another(face):
    """joined puts each drawing's parts' points together in one go for drawings alike: as
    concatenated one by one, the skeletons joined, the widest stroke; None where a part is."""
    drawn = all_face_parts(face, pose_faces(lift(face), nodding(12)), "u")
    shapes = shapes_of([(part.text, *part.clips) for drawing in drawn for part in drawing])
    drawings = [shapes[start:start + len(drawn[0])] for start in range(0, len(shapes), len(drawn[0]))]
    drawings += [drawings[0][::-1], drawings[1][:3], [*drawings[2][:2], None]]
    for parts, shape in zip(drawings, joined(drawings), strict=True):
        if any(part is None for part in parts):
            assert shape is None
            continue
        assert shape is not None
        assert shape.skeleton == "|".join(part.skeleton for part in parts if part is not None)
        assert shape.points.tobytes() == np.concatenate([part.points for part in parts if part is not None]).tobytes()
        assert shape.stroke == max(part.stroke for part in parts if part is not None)


def test_the_fit_measured_in_single_precision_is_within_its_slack_of_double_precision():
    """reuse._choose takes the pairs near on the samples from single precision and measures in
    double only those within _single_slack of the tolerance: the slack bounds the difference,
    for matrices near the identity (the pairs that matter) and far from it, points far from 0."""
    rng = np.random.default_rng(16)
    count = 4096
    sources = rng.uniform(-800, 1200, (count, 24, 2)).astype(np.float32)
    linear = np.where(np.arange(count)[:, None, None] % 2, np.eye(2) + rng.normal(0, 0.01, (count, 2, 2)),
                      rng.normal(0, 3, (count, 2, 2)))
    matrices = np.round(np.concatenate([linear, rng.uniform(-500, 500, (count, 2, 1))], axis=2), 4)
    targets = (np.einsum("mij,mnj->mni", matrices[:, :, :2], sources) + matrices[:, None, :, 2]
               + rng.normal(0, 0.3, (count, 24, 2))).astype(np.float32)
    double = _largest(sources, matrices, targets)
    single = _largest_single(np.transpose(sources, (2, 1, 0)), matrices, np.transpose(targets, (2, 1, 0)))
    largest = float(max(np.abs(sources).max(), np.abs(targets).max()))
    assert np.all(np.abs(single - double) <= _single_slack(matrices, largest))
    assert np.any(single != double), "single precision differs, within the slack"


def hypotenuses(sources: np.ndarray, matrices: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """The largest distance (M,) of each of `sources` (M, N, 2) mapped by `matrices` (M, 2, 3) from
    `targets`, np.hypot of every point's offsets: what reuse._largest computes with fewer np.hypot."""
    mapped = [matrices[:, row, 0, None] * sources[..., 0] + matrices[:, row, 1, None] * sources[..., 1]
              + matrices[:, row, 2, None] - targets[..., row] for row in (0, 1)]
    return np.max(np.hypot(*mapped), axis=1)


@pytest.mark.parametrize("points", [3, 24, 150])
def test_the_largest_distance_is_np_hypots_to_the_bit_with_ties_near_ties_and_tiny_offsets(points):
    """reuse._largest takes np.hypot only where the square sum is near its largest: the same numbers
    as np.hypot of every point, for pairs in general and for offsets set exactly (sources at 0 under
    the identity): points at the same distance in other directions, equal or an ulp apart (square
    sums that may round the other way), and distances whose squares are subnormal or vanish."""
    rng = np.random.default_rng(points)
    count = 3000
    sources = rng.uniform(-300, 700, (count, points, 2))
    matrices = np.concatenate([np.eye(2) + rng.normal(0, 0.01, (count, 2, 2)), rng.normal(0, 2, (count, 2, 1))], axis=2)
    targets = (np.einsum("mij,mnj->mni", matrices[:, :, :2], sources) + matrices[:, None, :, 2]
               + rng.normal(0, 0.3, sources.shape))
    assert _largest(sources, matrices, targets).tobytes() == hypotenuses(sources, matrices, targets).tobytes()
    angles = rng.uniform(0, 2 * np.pi, (count, points))
    radii = 0.4 * (1 + rng.integers(-2, 3, (count, points)) * 2.0 ** -52)
    scales = np.array([1, 2.0 ** -460, 2.0 ** -530, 2.0 ** -600])[np.arange(count) % 4, None]
    offsets = (scales * radii)[..., None] * np.stack([np.cos(angles), np.sin(angles)], axis=2)
    identity = np.broadcast_to(np.eye(2, 3), (count, 2, 3))
    assert _largest(np.zeros_like(offsets), identity, -offsets).tobytes() == hypotenuses(
        np.zeros_like(offsets), identity, -offsets).tobytes()


def test_the_near_pairs_are_those_within_the_tolerance_on_every_sample_in_double_precision():
    """reuse._near measures in single precision, on a few samples first, in double precision only
    near the tolerance: the pairs it finds are those within it (widened by the strokes) measured on
    every sample in double precision, for pairs on both sides of it and near it."""
    rng = np.random.default_rng(5)
    count = 4000
    earlier_points = rng.uniform(-200, 900, (count, FIT_POINTS, 2))
    linear = np.eye(2) + rng.normal(0, 0.002, (count, 2, 2))
    noise = rng.normal(0, 1, earlier_points.shape) * rng.uniform(0, 0.3, (count, 1, 1))
    later_points = np.einsum("mij,mnj->mni", linear, earlier_points) + rng.uniform(-3, 3, (count, 1, 2)) + noise
    samples = np.concatenate([earlier_points, later_points]).astype(np.float32)
    earlier, later = np.arange(count), np.arange(count) + count
    matrices = fit(_inverses(samples)[earlier], samples[later])
    strokes = rng.choice([0.0, 1.0, 3.0], 2 * count)
    near, scales = _near(samples, np.ascontiguousarray(samples.transpose(2, 1, 0)), matrices, earlier, later, strokes,
                         float(np.max(np.abs(samples))), TOLERANCE)
    every_scale = _scale_change(matrices[:, :, :2])
    within = every_scale * np.maximum(strokes[earlier], strokes[later]) / 2 + hypotenuses(
        samples[earlier].astype(float), matrices, samples[later].astype(float))
    assert near.tolist() == np.flatnonzero(within <= TOLERANCE).tolist()
    assert scales.tobytes() == every_scale[near].tobytes()
    assert count / 10 < len(near) < count * 9 / 10 and np.sum(np.abs(within - TOLERANCE) < 0.01) > 10


def test_reused_drawings_point_at_written_drawings_of_their_track_and_every_reference_resolves(documents):
    exact, reused = (etree.fromstring(data) for data in documents)
    assert len(documents[1]) < 0.9 * len(documents[0]), "reuse makes the document smaller"
    ids = {node.get("id") for node in reused.iter() if node.get("id")}
    for node in reused.iter():
        for name, value in node.attrib.items():
            if name == "href" or value.startswith("url(#"):
                assert value.removeprefix("url(").removesuffix(")").removeprefix("#") in ids, value
    count = 0
    for track, exact_track in zip(reused.iterfind(".//s:g[@data-part]", NS), exact.iterfind(".//s:g[@data-part]", NS),
                                  strict=True):
        defs = track.find("s:defs", NS)
        own = {node.get("id"): node for node in defs} if defs is not None else {}
        assert len(own) <= len(exact_track.find("s:defs", NS)), "no more drawings than written without reuse"
        for node in own.values():
            if node.tag == f"{S}use" and node.get("href", "").startswith("#f"):
                count += 1
                source = own[node.get("href")[1:]]
                assert source.tag != f"{S}use" or not source.get("transform"), "no chains of reuse"
                assert node.get("transform") is None or len(node.get("transform")[7:-1].split()) == 6
    assert count > 0
    assert 'transform="matrix(1 0 0 1 0 0)"' not in documents[1].decode(), "a drawing unmoved is that drawing"
    # every frame shows the mouth shape it shows with every drawing written (a drawing shown as
    # another one unmoved keeps its own shape)
    for frame in range(0, 90, 3):
        assert shown_shape(documents[1], frame) == shown_shape(documents[0], frame)
    # parts reused on their own (a mouth, an eye) inside drawings written in full: transforms of a
    # part in the shared parts' <defs>, which is itself written (no chains)
    shared = {node.get("id"): node for node in reused.find(f"s:defs[@id='{PARTS_ID}']", NS)}
    alone = [node for track in reused.iterfind(".//s:g[@data-part]", NS) for drawing in track.iterfind("s:defs/s:g", NS)
             for node in drawing.iter(f"{S}use") if node.get("transform", "").startswith("matrix(")]
    assert alone, "some parts are reused on their own"
    for node in alone:
        source = shared[node.get("href")[1:]]
        assert source.tag != f"{S}use" and source.find(f".//{S}use[@transform]") is None


def shown_shape(data: bytes, frame: int) -> str | None:
    """The data-shape of the mouth track's drawing frame `frame` of the animation `data` shows."""
    still = etree.fromstring(frozen(data, frame, FPS))
    track = still.find(f".//s:g[@data-part='{MOUTH_TRACK}']", NS)
    drawing = track.find(f"s:defs/*[@id='{track.find('s:use', NS).get('href')[1:]}']", NS)
    return drawing.get("data-shape")


def pixels(data: bytes) -> np.ndarray:
    with Image.open(io.BytesIO(svg_to_png(data))) as image:
        return np.asarray(image.convert("RGB"), dtype=np.int16)


def outside(a: np.ndarray, b: np.ndarray, slack: int = 16) -> np.ndarray:
    """Pixels of `b` outside the range `a` takes in their 3x3 neighbourhood by more than `slack`
    levels: where an edge of `b` lies more than a pixel from `a`'s (or a colour changed)."""
    pad = np.pad(a, ((1, 1), (1, 1), (0, 0)), mode="edge")
    rows, columns = a.shape[:2]
    near = np.stack([pad[1 + dy:1 + dy + rows, 1 + dx:1 + dx + columns] for dy in (-1, 0, 1) for dx in (-1, 0, 1)])
    return np.any((b < near.min(axis=0) - slack) | (b > near.max(axis=0) + slack), axis=2)


@pytest.mark.parametrize("frame", [5, 23, 41, 60, 88])
def test_a_frame_with_reused_drawings_looks_as_with_every_drawing_written(documents, frame):
    exact, reused = (pixels(frozen(data, frame, FPS)) for data in documents)
    difference = np.abs(exact - reused).max(axis=2)
    # edges move by a fraction of a pixel (the tolerance beside the whole-pixel rounding of both
    # drawings): a thin antialiased rim, under a level on average over the picture (from one frame
    # to the next of this nodding head the exact pictures differ by 1-5 levels on average)
    assert difference.mean() < 1.0
    moved_far = outside(exact, reused) | outside(reused, exact)
    assert moved_far.mean() < 1e-3, f"{moved_far.sum()} pixels farther than a pixel from the exact picture's"
