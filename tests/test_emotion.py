"""Emotions (face/emotion.py) and their RBF transfer (face/rbf.py): properties on the sample faces."""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np
import pytest

from cartoonface.errors import OptionError
from cartoonface.face.emotion import (
    ACROSS_MIN, CONTOUR, EARS, EMOTIONS, FEATURE_POINTS, FOREHEAD, LIP_POINTS, drawn_moves, emotion_displacements,
    held_points, lip_split, template_fapu, template_points,
)
from cartoonface.face.lift import LIFTED_INDEX, lift
from cartoonface.face.model import POINT_INDEX, POINT_NAMES, load_face, scale_face
from cartoonface.face.mouth import MOUTH_SYMBOLS, shown_parts
from cartoonface.face.pose import pose_face
from cartoonface.face.rbf import WIDTHS, clusters, deform, leave_one_out
from cartoonface.face.state import FaceState, Pose
from cartoonface.render.mouth import ROWS, mouth_outlines
from tests.conftest import ROOT
from tests.shapes import area, crossings, sample

POSES = (Pose(),) + tuple(Pose(*corner) for corner in itertools.product((-15, 15), repeat=3))
EYES = (("3.12", "3.2", "3.8", "3.4"), ("3.7", "3.1", "3.11", "3.3"))


@pytest.fixture(params=("female", "male"), scope="module")
def face(request):
    return load_face(ROOT / "samples" / "faces" / f"{request.param}.json")


def test_every_emotion_moves_the_face_and_scales_with_its_intensity(face) -> None:
    lifted = lift(face)
    neutral = pose_face(lifted, FaceState()).xy
    pupils = [LIFTED_INDEX["3.5"], LIFTED_INDEX["3.6"]]  # kept inside the lids: not linear
    for name in EMOTIONS:
        full = np.delete(pose_face(lifted, FaceState(emotion=((name, 1.0),))).xy - neutral, pupils, axis=0)
        half = np.delete(pose_face(lifted, FaceState(emotion=((name, 0.5),))).xy - neutral, pupils, axis=0)
        assert np.abs(full).max() > 0.05 * face.fapu.d, name
        np.testing.assert_allclose(half, full / 2, atol=1e-9, err_msg=name)
    assert np.array_equal(pose_face(lifted, FaceState(emotion=(("sad", 0.0),))).xy, neutral)


def test_the_emotions_differ_from_each_other(face) -> None:
    moves = emotion_displacements(face)
    for a, b in itertools.combinations(range(len(EMOTIONS)), 2):
        assert np.abs(moves[a] - moves[b]).max() > 0.03 * face.fapu.d, (EMOTIONS[a], EMOTIONS[b])


def test_templates_scale_with_the_face(face) -> None:
    """A face twice as big moves every point twice as far (FAPU units), by both transfers."""
    big = scale_face(face, 2 * face.fapu.d)
    for widths in (None, "cluster"):
        np.testing.assert_allclose(emotion_displacements(big, widths), 2 * emotion_displacements(face, widths),
                                   atol=1e-6 * face.fapu.d)


def test_rbf_moves_the_named_points_exactly_and_the_others_smoothly(face) -> None:
    plain = emotion_displacements(face, None)
    for widths in WIDTHS:
        rbf = emotion_displacements(face, widths)
        for k, name in enumerate(EMOTIONS):
            rows = [POINT_INDEX[p] for p in template_points(name)]
            np.testing.assert_allclose(rbf[k, rows], plain[k, rows])
            free = [i for i in range(len(POINT_NAMES)) if i not in rows]
            largest = np.linalg.norm(plain[k], axis=1).max()
            assert np.linalg.norm(rbf[k, free], axis=1).max() <= largest, (widths, name)
            if widths == "cluster":
                raw = deform(face.points, template_points(name), template_fapu(name, face.fapu), widths)
                assert np.abs(raw[free]).max() > 0.005 * face.fapu.d, name  # plain scaling leaves them
                assert not plain[k, free].any()


def test_the_drawn_moves_hold_the_ears_and_forehead_and_move_the_contour_only_across_it(face) -> None:
    """drawn_moves: the held points never move; a contour point no template names moves along
    the perpendicular of its neighbours' chord by the RBF move's share that way (the rest of the
    RBF's move is perpendicular to what is kept), at least ACROSS_MIN d or not at all; other points
    keep the RBF's move. Some emotion still moves a cheek of the contour across it."""
    assert held_points(face) == EARS + FOREHEAD  # the samples' hair covers the forehead
    raw = np.array([deform(face.points, template_points(n), template_fapu(n, face.fapu)) for n in EMOTIONS])
    drawn = drawn_moves(face, raw)
    assert np.array_equal(drawn, emotion_displacements(face))
    held = [POINT_INDEX[p] for p in held_points(face)]
    assert not drawn[:, held].any() and np.abs(raw[:, held]).max() > 0.01 * face.fapu.d
    ring = [POINT_INDEX[p] for p in CONTOUR]
    contour = [k for k, p in enumerate(CONTOUR) if p not in FEATURE_POINTS and POINT_INDEX[p] not in held]
    for k in contour:
        row = ring[k]
        chord = face.points[ring[(k + 1) % len(ring)]] - face.points[ring[k - 1]]
        kept, dropped = drawn[:, row], raw[:, row] - drawn[:, row]
        np.testing.assert_allclose(kept @ chord, 0.0, atol=1e-9)
        np.testing.assert_allclose((kept * dropped).sum(axis=1), 0.0, atol=1e-9)
        size = np.linalg.norm(kept, axis=1)
        assert ((size == 0) | (size >= ACROSS_MIN * face.fapu.d)).all()
    moved = [ring[k] for k in contour]
    assert np.linalg.norm(drawn[:, moved], axis=2).max() >= ACROSS_MIN * face.fapu.d
    others = [i for i in range(len(POINT_NAMES)) if i not in held + moved]
    np.testing.assert_array_equal(drawn[:, others], raw[:, others])


def test_a_bare_forehead_follows_the_rbf(face) -> None:
    """Hair that does not reach above the forehead (no front layer over it): only the ears are held."""
    top = face.point("11.1")[1]
    bare = replace(face, hair=face.hair[face.hair[:, 1] > top])
    assert held_points(bare) == EARS
    forehead = [POINT_INDEX[p] for p in FOREHEAD]
    assert np.linalg.norm(emotion_displacements(bare)[:, forehead], axis=2).max() >= ACROSS_MIN * face.fapu.d


def test_rbf_is_linear_in_the_moves(face) -> None:
    names = template_points("happy")
    values = template_fapu("happy", face.fapu)
    np.testing.assert_allclose(deform(face.points, names, 3 * values), 3 * deform(face.points, names, values))


def test_clusters_cover_every_point_with_a_positive_width(face) -> None:
    shape = clusters(face.points)
    assert shape.label.shape == (len(POINT_NAMES),)
    assert set(shape.label.tolist()) == set(range(12))
    assert (shape.sigma >= 1).all()


def test_leave_one_out_predicts_a_shared_move_better_than_plain_scaling(face) -> None:
    """Every feature point moved alike (the face shifted): each width rule predicts a left-out
    point's move with less error than plain scaling (which predicts none), in the median."""
    move = np.tile([0.0, -0.05 * face.fapu.d], (len(FEATURE_POINTS), 1))
    for widths in WIDTHS:
        errors = leave_one_out(face.points, FEATURE_POINTS, move, widths)
        assert np.median(errors) < 0.5 * np.linalg.norm(move[0]), widths
        assert errors.max() < np.linalg.norm(move[0]), widths


def test_lip_split_separates_the_lips(face) -> None:
    moves = emotion_displacements(face)
    rest, lips = lip_split(moves)
    np.testing.assert_array_equal(rest + lips, moves)
    lip_rows = [POINT_INDEX[p] for p in LIP_POINTS]
    assert not rest[:, lip_rows].any()
    assert not np.delete(lips, lip_rows, axis=1).any()
    assert set(LIP_POINTS) <= set(FEATURE_POINTS)


def test_lips_gamma_scales_only_the_lips(face) -> None:
    lifted = lift(face)
    at_rest = pose_face(lifted, FaceState(emotion=(("surprise", 1.0),))).xy
    talking = pose_face(lifted, FaceState(emotion=(("surprise", 1.0),), lips=0.0)).xy
    neutral = pose_face(lifted, FaceState()).xy
    brows = [LIFTED_INDEX[p] for p in ("4.1", "4.2", "4.5", "4.6")]
    np.testing.assert_allclose(at_rest[brows], talking[brows])
    chin = LIFTED_INDEX["8.2"]
    np.testing.assert_allclose(talking[chin], neutral[chin])
    assert at_rest[chin][1] > neutral[chin][1] + 0.1 * face.fapu.mns0


@pytest.mark.parametrize("bad", [
    (("joy", 1.0),), (("sad", 1.5),), (("sad", -0.1),), (("sad", float("nan")),), (("sad", 1.0), ("sad", 0.5)),
    ("sad",),
])
def test_bad_emotions_are_refused_naming_them(bad) -> None:
    with pytest.raises(OptionError, match="emotion|intensity"):
        FaceState(emotion=bad)
    with pytest.raises(OptionError, match="lips"):
        FaceState(lips=1.5)


def test_every_emotion_mouth_blend_and_pose_draws_sound_eyes_and_lips(face) -> None:
    """Lids never cross (lower lid at or below the upper one across the eye, to 0.01 d: shut lids
    meet at one height but not always at one x), each open eye's iris centre lies between its
    lids, the eye
    outlines and the lips never cross themselves; emotions x mouth shapes x weights x poses."""
    lifted = lift(face)
    weights = (0.5, 1.0)
    moods = [((name, w),) for name in EMOTIONS for w in weights] + [(("happy", 0.5), ("sad", 0.5))]
    for mood, symbol, pose, lips in itertools.product(moods, MOUTH_SYMBOLS, POSES, (1.0, 0.5)):
        state = FaceState(pose=pose, emotion=mood, lips=lips).with_mouth(symbol)
        posed = pose_face(lifted, state)
        where = f"{mood} {symbol} {pose} lips {lips}"
        for (outer, upper, inner, lower), pupil in zip(EYES, posed.pupils, strict=True):
            o, u, i, lo = (posed.p(n) for n in (outer, upper, inner, lower))
            axis = np.array([-(i - o)[1], (i - o)[0]]) * np.sign((i - o)[0])  # down the face, across the eye
            opening = (lo - u) @ axis / np.hypot(*axis)
            assert opening >= -0.01 * face.fapu.d, where
            if opening > 0.01 * face.fapu.d:  # an open eye; a shut one is a line
                assert crossings(np.array([o, u, i, lo])) == 0, where
                share = (pupil - u) @ (lo - u) / ((lo - u) @ (lo - u))  # the iris centre between the lids
                assert 0 < share < 1, where
        out = mouth_outlines(posed.xy[ROWS], posed.mouth @ shown_parts(), face.fapu.d)
        lips_outline = sample(out.lips)
        assert area(lips_outline) > 0 and crossings(lips_outline) == 0, where
