"""Drawing many states at once (face/pose.py pose_faces, render/geometry.py all_face_shapes,
render/mouth.py all_mouth_outlines / all_mouth_texts, render/svg.py all_face_parts): each state
in a batch comes out to the last bit as it does alone, whatever the other states of its batch;
the compactor's extents read off numbers are the extents of the written path data; path data
compacted in two processes and put together are compacted as all at once."""

from __future__ import annotations

import numpy as np
import pytest

from cartoonface.face.lift import lift
from cartoonface.face.model import load_face
from cartoonface.face.mouth import MOUTH_SYMBOLS, shown_parts
from cartoonface.face.pose import PosedFaces, pose_face, pose_faces, rig, unroll, unroll_faces
from cartoonface.face.state import FaceState, Pose
from cartoonface.render.compact import _extent, part_paths
from cartoonface.render.geometry import all_face_shapes, face_shapes
from cartoonface.render.mouth import (ROWS, all_mouth_outlines, all_mouth_texts, drawn_mouth_texts, mouth_outlines,
                                      mouth_texts)
from cartoonface.render.pathdata import _alike_rows, _groups, compacted, merged
from cartoonface.render.svg import all_face_parts, face_parts
from tests.conftest import ROOT

FIELDS = ("xy", "hair", "front", "pupils", "mouth")


@pytest.fixture(params=("female", "male"), scope="module")
def face(request):
    return load_face(ROOT / "samples" / "faces" / f"{request.param}.json")


def random_states(count: int, seed: int) -> list[FaceState]:
    """Mixed states: poses over the whole range (some frontal, some unrolled), blinks, smiles,
    brows, blends of two mouth shapes, gazes, emotions on some."""
    rng = np.random.default_rng(seed)
    states = []
    for index in range(count):
        angles = rng.uniform(-15, 15, 3).round(2) * (index % 4 != 0)
        first, second = rng.choice(MOUTH_SYMBOLS, 2, replace=False)
        weight = float(rng.uniform(0.2, 0.8))
        emotion = (("happy", float(rng.uniform(0, 1))),) if index % 3 == 0 else ()
        states.append(FaceState(pose=Pose(*angles.tolist()), blink=float(rng.uniform()), smile=float(rng.uniform()),
                                brow=float(rng.uniform()), mouth=((str(first), 1 - weight), (str(second), weight)),
                                gaze_h=float(rng.uniform(-10, 10)), gaze_v=float(rng.uniform(-10, 10)),
                                emotion=emotion, lips=float(rng.uniform())))
    return states


def same_faces(batch: PosedFaces, single) -> None:
    """`single` (PosedFace) and `batch` (one PosedFace of a batch) hold the same numbers, bit for bit."""
    for name in FIELDS:
        assert np.array_equal(getattr(batch, name), getattr(single, name)), name
    assert batch.nose_side == single.nose_side
    assert np.array_equal(batch.iris_r, single.iris_r)


def test_a_state_posed_in_a_batch_is_posed_as_alone(face):
    lifted = lift(face)
    states = random_states(24, 1)
    batch = pose_faces(lifted, states)
    backwards = pose_faces(lifted, states[::-1])
    assert len(batch) == len(states)
    for index, state in enumerate(states):
        same_faces(batch[index], pose_face(lifted, state))
        same_faces(backwards[len(states) - 1 - index], batch[index])


def test_unrolled_in_a_batch_as_alone_and_unrolled_faces_untouched(face):
    lifted = lift(face)
    origin = rig(lifted).origin
    states = random_states(16, 2)
    rolls = [state.pose.roll for state in states]
    batch = unroll_faces(pose_faces(lifted, states), rolls, origin)
    for index, state in enumerate(states):
        alone = unroll(pose_face(lifted, state), state.pose.roll, origin)
        same_faces(batch[index], alone)
        if not state.pose.roll:
            same_faces(batch[index], pose_face(lifted, state))
    # turning back keeps distances in the image plane
    posed = pose_faces(lifted, states)
    for index in range(len(states)):
        before = np.linalg.norm(posed.xy[index, :, None] - posed.xy[index, None], axis=2)
        after = np.linalg.norm(batch.xy[index, :, None] - batch.xy[index, None], axis=2)
        assert np.allclose(before, after)


def test_shapes_mouths_and_parts_in_a_batch_as_alone(face):
    lifted = lift(face)
    states = random_states(12, 3) + [FaceState(pose=Pose(2, -6, 0)).with_mouth(symbol) for symbol in MOUTH_SYMBOLS]
    posed = pose_faces(lifted, states)
    assert {int(side) for side in posed.nose_side} == {-1, 1}  # both nose plans in one batch
    shapes = all_face_shapes(posed)
    shown = np.array([posed[index].mouth @ shown_parts() for index in range(len(states))])
    outlines = all_mouth_outlines(posed.xy[:, ROWS], shown, face.fapu.d)
    assert {o.tongue[3] == 0 for o in outlines} == {True, False}  # shut and open mouths built together
    texts = all_mouth_texts(outlines)
    distinct, which = drawn_mouth_texts(posed.xy[:, ROWS], shown, face.fapu.d)
    assert [distinct[number] for number in which] == texts
    assert len(distinct) == len({tuple(mouth.items()) for mouth in texts})  # each mouth written once
    parts = all_face_parts(face, posed, "u")
    for index in range(len(states)):
        alone = posed[index]
        assert shapes[index] == face_shapes(alone)
        single = mouth_outlines(alone.xy[ROWS], alone.mouth @ shown_parts(), face.fapu.d)
        assert np.array_equal(outlines[index].rows, single.rows)
        assert outlines[index].tongue == single.tongue and outlines[index].gloss == single.gloss
        assert texts[index] == mouth_texts(single)
        assert parts[index] == face_parts(face, alone, "u")


def test_extents_read_off_the_numbers_are_those_of_the_text(face):
    lifted = lift(face)
    paths = [d for shapes in all_face_shapes(pose_faces(lifted, random_states(20, 4))) for d in shapes.values()]
    done = compacted(paths)
    compact, extents = done.compact, done.extents
    assert extents and set(extents) <= set(compact.values())
    for d in set(compact.values()):
        if d in extents:
            assert extents[d] == _extent(d)


def test_path_data_compacted_in_two_halves_as_all_at_once(face):
    lifted = lift(face)
    drawn = [list(shapes.values()) for shapes in all_face_shapes(pose_faces(lifted, random_states(40, 6)))]
    paths = [d for shapes in drawn for d in shapes]
    whole = compacted(paths)
    assert whole.firsts  # the corner-cut outlines, whose first path data chooses the points kept
    # drawings left out (a process draws states the parts of another's stand for): extra path data
    extra = [d for shapes in all_face_shapes(pose_faces(lifted, random_states(40, 7))) for d in shapes.values()]
    other_firsts = 0
    for cut in (5, 20, 35):
        halves = [d for shapes in drawn[:cut] for d in shapes], [d for shapes in drawn[cut:] for d in shapes]
        for done, given in ((merged(compacted(halves[0]), compacted(halves[1] + extra)), paths + extra),
                            (merged(compacted(halves[1]), compacted(halves[0])), paths),
                            (compacted(halves[0] + extra), halves[0] + extra)):
            other_firsts += done.firsts != whole.firsts
            groups = _groups(set(given))  # each corner-cut skeleton's path data, all compacted with its first
            assert all(done.members[skeleton] == sorted(groups[skeleton]) and done.members[skeleton][0] == first
                       for skeleton, first in done.firsts.items())
            result = compacted(paths, done)
            assert {d: result.compact[d] for d in set(paths)} == whole.compact
            assert all(result.extents[form] == whole.extents[form] for form in whole.extents)
            assert result.firsts == whole.firsts
    assert other_firsts  # some went on from other first path data than all at once have


def test_alike_rows_group_equal_rows():
    marks = np.random.default_rng(5).random((300, 11)) < 0.15
    groups = _alike_rows(marks)
    assert sorted(index for _, rows in groups for index in rows.tolist()) == list(range(len(marks)))
    assert len({pattern for pattern, _ in groups}) == len(groups)
    for pattern, rows in groups:
        assert all(tuple(marks[row].tolist()) == pattern for row in rows)


def test_path_data_compacted_from_its_numbers_as_drawn_as_from_its_text(face):
    """The numbers all_face_parts hands on with the path data it drew (pathdata.Tenths) compact
    them as reading their text does: the same compact forms, extents and firsts."""
    lifted = lift(face)
    tenths: dict[str, np.ndarray] = {}
    drawn = all_face_parts(face, pose_faces(lifted, random_states(40, 8)), "u", tenths=tenths)
    paths = list(part_paths((part.text, *part.clips) for parts in drawn for part in parts))
    assert len(tenths.keys() & set(paths)) > len(set(paths)) / 2  # the hair, outlines, mouths
    ties = np.concatenate([row[row % 10 == 5] // 10 % 2 for row in tenths.values()])
    assert set(ties.tolist()) == {0, 1}  # halves of a pixel to round, to an even and to an odd whole
    assert compacted(paths, tenths=tenths) == compacted(paths)
    partly = dict(list(tenths.items())[::2])  # a skeleton's paths some taken from tenths, some read
    assert compacted(paths, tenths=partly) == compacted(paths)
