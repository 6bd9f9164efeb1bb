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
from cartoonface.render.mouth import (ROWS, TEXTS, all_mouth_outlines, all_mouth_texts, drawn_mouth_texts,
                                      mouth_outlines, mouth_texts)
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
    assert [dict(zip(TEXTS, distinct[number], strict=True)) for number in which] == texts  # in TEXTS order
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


def test_parts_handed_on_with_their_forms_make_what_cutting_their_text_makes(face):
    """The Form and slots all_face_parts hands on with each part it draws (but the chin shadows drawn
    as ellipses) give compact.drawn_parts the path data, skeletons and values that cutting the parts'
    texts apart gives: the same Drawn, for mixed states and every mouth shape alone (tongue, teeth,
    bite drawn or not)."""
    from cartoonface.render.compact import drawn_parts

    states = random_states(40, 11) + [FaceState(mouth=((symbol, 1.0),), lips=0.5) for symbol in MOUTH_SYMBOLS]
    forms: dict = {}
    drawn = all_face_parts(face, pose_faces(lift(face), states), "u", forms=forms)
    parts = list(dict.fromkeys(part for parts in drawn for part in parts))
    assert {part.text[:8] for part in parts if part not in forms} == {"<ellipse"}  # the uncut chin shadows
    assert any(part.name == "chin-shadow" for part in forms)  # and the cut ones (paths) handed on
    assert len({form for part, (form, _) in forms.items() if part.name == "mouth"}) >= 4
    assert drawn_parts(parts, formed=forms) == drawn_parts(parts)


def test_a_form_gives_what_cutting_gives_or_leaves_the_part_to_be_cut():
    """compact.form_of finds where a drawing function writes its slots (path data, positions, sizes;
    constants kept as written); parts drawn by it, handed to drawn_parts with their Form, get the
    skeleton and values of their text cut apart, also where the Form's skeleton is not theirs (two
    path data compacting alike, a size that is no plain number: cut then). A slot written into an
    attribute a skeleton keeps is refused."""
    from cartoonface.render.compact import POSITIONS, drawn_parts, form_of
    from cartoonface.render.elements import Part

    def draw(slots):
        outline, lid, x, r = slots
        return Part("eye", f'<g class="eye"><path d="{outline}" fill="#fff"/><circle cx="{x}" cy="4.5" r="{r}"/>'
                           f'<ellipse cx="{x}" cy="2" rx="3" ry="{r}"/><path d="{lid}"/></g>',
                    (f'<clipPath id="e"><path d="{outline}"/></clipPath>',))

    form = form_of(draw, 4)
    assert form.paths == (0, 1)
    assert [(slot, name in POSITIONS) for (slot, _, _), name in zip(form.fields, ("cx", "cy", "r", "cx", "cy", "rx", "ry"))] \
        == [(2, True), (-1, True), (3, False), (2, True), (-1, True), (-1, False), (3, False)]
    slots = [("M1 2L3 4", "M5 6C7 8 9 10 11 12", "10.5", "3"), ("M1 2L3 4", "M5 6C7 8 9 10 11 12", "11.5", ".5"),
             ("M1 2L30 4", "M1 2L30 4", "7", "2"), ("M1.2 2L3 4", "M1 2L3 4", "7.3", "2"),  # paths alike
             ("M1 2L3 4", "M5 6C7 8 9 10 11 12", "7", "-2")]  # a size not plain
    parts = [draw(list(texts)) for texts in slots]
    formed = {part: (form, texts) for part, texts in zip(parts, slots, strict=True)}
    assert drawn_parts(parts, formed=formed) == drawn_parts(parts)
    assert len(set(drawn_parts(parts).skeletons)) == 3
    with pytest.raises(ValueError):
        form_of(lambda slots: Part("line", f'<path d="{slots[0]}" stroke-width="{slots[1]}"/>'), 2)


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


def test_a_mouth_filled_into_its_kinds_templates_is_what_the_mouth_drawing_writes(face):
    """render/svg.py draws each distinct mouth by filling the templates of its kind (tongue drawn or
    not, widths of the teeth and the bite) with its texts: the part render/svg.py's _mouth writes of
    them, for mixed states and every mouth shape alone."""
    from cartoonface.render.svg import _mouth, _mouth_part, _style_texts

    states = random_states(40, 13) + [FaceState(mouth=((symbol, 1.0),), lips=0.5) for symbol in MOUTH_SYMBOLS]
    posed = pose_faces(lift(face), states)
    shown = (posed.mouth[:, None, :] @ shown_parts())[:, 0]
    mouths, _ = drawn_mouth_texts(posed.xy[:, ROWS], shown, face.fapu.d)
    kinds = {(texts[TEXTS.index("tongue_ry")] == "0", texts[TEXTS.index("bite_width")] == "0") for texts in mouths}
    assert len(kinds) >= 3  # shut and open mouths, with and without a bite
    for texts in mouths:
        assert _mouth_part(face, "u", texts, None) == _mouth(dict(zip(TEXTS, texts, strict=True)), "u", _style_texts(face))
