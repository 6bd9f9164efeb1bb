"""Face model: sample faces, JSON round trip, validation messages, scaling (thesis 2.3.2)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from cartoonface.errors import FaceModelError
from cartoonface.face.model import (
    FAPU_NAMES,
    HAIR_POINTS,
    MAX_HAIR_POINTS,
    MAX_NUMBER_DIGITS,
    POINT_NAMES,
    computed_fapu,
    face_from_dict,
    face_to_dict,
    load_face,
    save_face,
    scale_face,
)

SAMPLES = ("female", "male")


@pytest.fixture(params=SAMPLES)
def sample_path(request, root):
    return root / "samples" / "faces" / f"{request.param}.json"


def test_samples_load_with_every_point(sample_path):
    face = load_face(sample_path)
    assert face.points.shape == (len(POINT_NAMES), 2)
    assert face.hair.shape == (HAIR_POINTS, 2)
    assert np.all(np.isfinite(face.points))
    for name in POINT_NAMES:
        assert face.point(name).shape == (2,)
    # both eyes lie on the canvas, the image-left eye (3.6) left of the image-right one (3.5)
    assert 0 < face.point("3.6")[0] < face.point("3.5")[0] < face.width


def test_point_count_matches_the_thesis(sample_path):
    # thesis 002, 2.2: 72 feature points, 23 of them the hair polygon (Alg. 2.2 step 2)
    face = load_face(sample_path)
    assert len(POINT_NAMES) + len(face.hair) == 72


def test_computed_fapus_follow_the_points(sample_path):
    face = load_face(sample_path)
    values = computed_fapu(face.points)
    for name, value in values.items():
        assert getattr(face.fapu, name) == pytest.approx(value)
    assert face.fapu.d == pytest.approx(math.dist(face.point("3.5"), face.point("3.6")))
    assert face.fapu.mw0 == pytest.approx(face.point("8.3")[0] - face.point("8.4")[0])


def test_file_value_of_a_computed_fapu_is_ignored(sample_path):
    obj = json.loads(sample_path.read_text())
    obj["fapu"]["mw0"] = obj["fapu"]["mw0"] * 3 + 7
    face = face_from_dict(obj, "edited")
    assert face.fapu.mw0 == pytest.approx(face.point("8.3")[0] - face.point("8.4")[0])


def test_save_and_load_round_trip(sample_path, tmp_path):
    face = load_face(sample_path)
    out = save_face(face, tmp_path / "copy.json")
    again = load_face(out)
    assert np.allclose(again.points, face.points, atol=0.01)
    assert np.allclose(again.hair, face.hair, atol=0.01)
    assert again.fapu == face.fapu
    assert again.palette == face.palette
    assert (again.name, again.width, again.height) == (face.name, face.width, face.height)


@pytest.mark.parametrize("factor", [0.5, 1.7, 3.0])
def test_scaling_d_scales_everything(sample_path, factor, tmp_path):
    face = load_face(sample_path)
    scaled = scale_face(face, face.fapu.d * factor)
    assert scaled.fapu.d == pytest.approx(face.fapu.d * factor)
    assert np.allclose(scaled.points, face.points * factor)
    assert np.allclose(scaled.hair, face.hair * factor)
    for name in FAPU_NAMES:
        assert getattr(scaled.fapu, name) == pytest.approx(getattr(face.fapu, name) * factor)
    assert (scaled.width, scaled.height) == pytest.approx((face.width * factor, face.height * factor))
    # a scaled face is a valid face file too
    assert load_face(save_face(scaled, tmp_path / "scaled.json")).fapu.d == pytest.approx(face.fapu.d * factor, abs=0.05)


@pytest.mark.parametrize("d", [0, -10, float("nan"), "big"])
def test_scaling_refuses_a_bad_d(sample_path, d):
    with pytest.raises(FaceModelError, match="d is"):
        scale_face(load_face(sample_path), d)


def _edit(obj, path, value):
    """Set obj[path...] = value, or delete the entry when value is DELETE."""
    target = obj
    for key in path[:-1]:
        target = target[key]
    if value is DELETE:
        del target[path[-1]]
    else:
        target[path[-1]] = value


DELETE = object()
BAD_EDITS = [
    (("version",), DELETE, "version is missing"),
    (("version",), 2, "version is 2"),
    (("format",), "svg", "format"),
    (("points", "8.4"), DELETE, "'8.4'"),
    (("points", "8.5"), [200, 300], "unknown points entry '8.5'"),
    (("points", "3.2"), [float("nan"), 100], "points['3.2']"),
    (("points", "9.15"), [200, float("inf")], "points['9.15']"),
    (("points", "2.1"), [200, 90000], "points['2.1']"),
    (("points", "4.4"), [1, 2, 3], "points['4.4']"),
    (("points", "3.4"), "low", "points['3.4']"),
    (("hair", 5), [-5000, 100], "hair[5]"),
    (("hair",), [[1, 2]], "hair"),
    (("fapu", "eyebrow_h"), -3, "fapu.eyebrow_h"),
    (("fapu", "r1"), 0, "fapu.r1"),
    (("fapu", "r2"), DELETE, "'r2'"),
    (("fapu", "eyebrow_h2"), True, "fapu.eyebrow_h2"),
    (("fapu", "shine"), 3, "unknown fapu entry 'shine'"),
    (("palette", "skin"), "peach", "palette.skin"),
    (("palette", "hair"), "#12345", "palette.hair"),
    (("palette", "lip"), DELETE, "'lip'"),
    (("canvas",), [400, -1], "canvas height"),
    (("canvas",), [100, 100], "off the 100 x 100 canvas"),
    (("fapu", "r1"), 1e300, "fapu.r1 is 1e+300"),
    (("fapu", "eyebrow_h"), 101.0, "fapu.eyebrow_h"),
    (("name",), "", "name"),
]


@pytest.mark.parametrize(("path", "value", "expected"), BAD_EDITS, ids=[str(e[0]) + repr(e[1])[:12] for e in BAD_EDITS])
def test_bad_field_gives_one_clear_error(sample_path, tmp_path, path, value, expected):
    obj = json.loads(sample_path.read_text())
    _edit(obj, list(path), value)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(obj))
    with pytest.raises(FaceModelError) as info:
        load_face(bad)
    message = str(info.value)
    assert expected in message
    assert str(bad) in message
    assert "\n" not in message


def test_eyelids_upside_down_name_the_computed_fapu(sample_path):
    obj = json.loads(sample_path.read_text())
    obj["points"]["3.2"], obj["points"]["3.4"] = obj["points"]["3.4"], obj["points"]["3.2"]
    with pytest.raises(FaceModelError, match=r"fapu.left_eye_h .*3\.4 must be below"):
        face_from_dict(obj, "flipped")


def test_malformed_json_names_the_place(tmp_path):
    bad = tmp_path / "broken.json"
    bad.write_text('{"format": "cartoonface-face", "version": 1,\n "points": {"8.4": [1, 2}')
    with pytest.raises(FaceModelError, match=r"broken.json: not valid JSON at line 2"):
        load_face(bad)


def test_missing_file_and_non_object(tmp_path):
    with pytest.raises(FaceModelError, match="no such face file"):
        load_face(tmp_path / "absent.json")
    with pytest.raises(FaceModelError, match="expected an object"):
        face_from_dict([1, 2], "list.json")


def test_to_dict_lists_every_point_and_fapu(sample_path):
    obj = face_to_dict(load_face(sample_path))
    assert obj["version"] == 1
    assert list(obj["points"]) == list(POINT_NAMES)
    assert set(obj["fapu"]) == set(FAPU_NAMES)


def test_hair_outline_of_too_many_points_is_refused(sample_path):
    obj = json.loads(sample_path.read_text())
    ring = np.linspace(0, 2 * np.pi, MAX_HAIR_POINTS + 1, endpoint=False)
    centre = np.mean(obj["hair"], axis=0)
    obj["hair"] = (centre + 60 * np.column_stack([np.cos(ring), np.sin(ring)])).tolist()
    with pytest.raises(FaceModelError, match=f"hair has {MAX_HAIR_POINTS + 1} points"):
        face_from_dict(obj, "many.json")
    obj["hair"] = obj["hair"][:MAX_HAIR_POINTS]
    assert face_from_dict(obj, "many.json").hair.shape == (MAX_HAIR_POINTS, 2)


@pytest.mark.parametrize("number", ["9" * 5000, "1" * 5000 + ".5", "-" + "7" * 200])
def test_number_of_absurd_length_names_the_field(sample_path, tmp_path, number):
    text = sample_path.read_text()
    obj = json.loads(text)
    obj["fapu"]["r2"] = 424242
    bad = tmp_path / "long.json"
    bad.write_text(json.dumps(obj).replace("424242", number))
    with pytest.raises(FaceModelError, match=rf"long.json: fapu.r2 is a number of {len(number)} characters"):
        load_face(bad)


def test_number_as_long_as_allowed_is_read(sample_path, tmp_path):
    obj = json.loads(sample_path.read_text())
    obj["fapu"]["r2"] = 424242
    padded = "12." + "0" * (MAX_NUMBER_DIGITS - 3)
    good = tmp_path / "padded.json"
    good.write_text(json.dumps(obj).replace("424242", padded))
    assert load_face(good).fapu.r2 == 12.0
