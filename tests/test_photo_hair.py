"""The hair from a photo (cartoonface/photo/hair.py): the outline stays off the face,
follows a fringe, is mirrored with the photo; the colour comes from the hair."""

from __future__ import annotations

from importlib.util import find_spec

import numpy as np
import pytest

pytestmark = pytest.mark.skipif(find_spec("mediapipe") is None or find_spec("cv2") is None,
                                reason="needs the photo extra")

if find_spec("mediapipe") is not None and find_spec("cv2") is not None:
    from PIL import Image
    from skimage import data

    from cartoonface.face.model import HAIR_POINTS
    from cartoonface.photo.hair import INNER_SIDE, _outline
    from cartoonface.photo.landmarks import landmarker
    from cartoonface.photo.landmarks_map import OVAL
    from cartoonface.photo.model_from_photo import face_from_photo, photo_from_image
    from cartoonface.photo.palette import polygon_mask

SIDE = 200
CENTRE = np.array([100.0, 110.0])
FACE_RADIUS = 50.0


def disk(radius: float, centre: np.ndarray = CENTRE) -> np.ndarray:
    rows, cols = np.mgrid[0:SIDE, 0:SIDE]
    return np.hypot(cols - centre[0], rows - centre[1]) <= radius


def rows_below(y: float) -> np.ndarray:
    return np.mgrid[0:SIDE, 0:SIDE][0] > y


BROW_Y = CENTRE[1] - 10  # the brows' clearance line of the synthetic faces


def bare(face: np.ndarray) -> np.ndarray:
    return face & rows_below(BROW_Y)


def lower_face_share(polygon: np.ndarray, face: np.ndarray, brow_y: float) -> float:
    area = polygon_mask(face.shape, polygon)
    return float((area & face & rows_below(brow_y)).sum() / area.sum())


def test_outline_goes_round_the_hair_and_stays_off_the_face():
    face = disk(FACE_RADIUS)
    # hair: a cap over the top half of the head, 20 px thick, down to the middle of the face
    hair = disk(FACE_RADIUS + 20) & ~face & ~rows_below(CENTRE[1])
    outline, fringe = _outline(hair, face, face, bare(face), CENTRE, 0.0, 2 * FACE_RADIUS)
    assert outline.shape == (HAIR_POINTS, 2) and not fringe
    radius = np.hypot(*(outline - CENTRE).T)
    outer = radius[INNER_SIDE:HAIR_POINTS - INNER_SIDE]
    inner = np.concatenate([radius[:INNER_SIDE], radius[HAIR_POINTS - INNER_SIDE:]])
    assert np.all(outer > FACE_RADIUS + 10) and np.all(outer < FACE_RADIUS + 25)
    assert np.all(inner < FACE_RADIUS + 5)
    # nothing of it on the face below the brows
    assert lower_face_share(outline, face, BROW_Y) < 0.02
    # the outer edge runs over the top from the image left to the image right
    top = outline[INNER_SIDE:HAIR_POINTS - INNER_SIDE]
    assert top[0, 0] < CENTRE[0] < top[-1, 0] and top[:, 1].min() < CENTRE[1] - FACE_RADIUS


def test_a_fringe_brings_the_inner_edge_down_over_the_forehead():
    face = disk(FACE_RADIUS)
    cap = disk(FACE_RADIUS + 20) & ~rows_below(CENTRE[1])
    plain, plain_fringe = _outline(cap & ~face, face, face, bare(face), CENTRE, 0.0, 2 * FACE_RADIUS)
    # a fringe: hair inside the face down to 25 px above the centre
    fringed = cap & ~(face & rows_below(CENTRE[1] - 25))
    outline, fringe = _outline(fringed, face, face, bare(face), CENTRE, 0.0, 2 * FACE_RADIUS)
    assert fringe and not plain_fringe
    middle = [0, HAIR_POINTS - 1]  # the inner points beside the top of the head
    assert np.all(outline[middle, 1] > plain[middle, 1] + 10)
    assert np.all(outline[middle, 1] <= BROW_Y)  # never below the brows


def test_no_hair_gives_a_cap_hidden_behind_the_face():
    face = disk(FACE_RADIUS)
    outline, fringe = _outline(np.zeros_like(face), face, face, bare(face), CENTRE, 0.0, 2 * FACE_RADIUS)
    assert not fringe
    assert np.all(np.hypot(*(outline - CENTRE).T) <= FACE_RADIUS + 1)
    assert np.all(outline[:, 1] < CENTRE[1])


def test_mirrored_masks_give_the_mirrored_outline():
    face = disk(FACE_RADIUS)
    # hair longer on the image left (a side parting)
    hair = (disk(FACE_RADIUS + 20) | (disk(FACE_RADIUS + 30) & (np.mgrid[0:SIDE, 0:SIDE][1] < 80))) & ~face
    hair &= ~rows_below(CENTRE[1] + 20)
    outline, _ = _outline(hair, face, face, bare(face), CENTRE, 0.0, 2 * FACE_RADIUS)
    mirrored, _ = _outline(hair[:, ::-1], face[:, ::-1], face[:, ::-1], bare(face)[:, ::-1],
                           np.array([SIDE - 1 - CENTRE[0], CENTRE[1]]), 0.0, 2 * FACE_RADIUS)
    back = np.column_stack([SIDE - 1 - mirrored[::-1, 0], mirrored[::-1, 1]])
    assert np.max(np.hypot(*(back - outline).T)) < 3.0


@pytest.fixture(scope="module")
def astronaut_face():
    photo = photo_from_image(Image.fromarray(data.astronaut()), "astronaut")
    return photo, face_from_photo(photo), landmarker().find(photo.rgb).points


def test_astronaut_hair_stays_off_the_face(astronaut_face):
    photo, result, mesh = astronaut_face
    shape = photo.rgb.shape[:2]
    brows = mesh[[105, 334], 1].max()
    area = polygon_mask(shape, result.hair)
    lower = polygon_mask(shape, mesh[list(OVAL), :2]) & rows_below_image(shape, brows)
    assert (area & lower).sum() / area.sum() < 0.03
    # and it covers the hair above the head
    top = mesh[10]
    assert area[int(top[1]) - 30, int(top[0])]


def rows_below_image(shape: tuple[int, int], y: float) -> np.ndarray:
    return np.mgrid[0:shape[0], 0:shape[1]][0] > y


def hex_rgb(colour: str) -> np.ndarray:
    return np.array([int(colour[i:i + 2], 16) for i in (1, 3, 5)], float)


def test_astronaut_hair_colour_is_her_hair(astronaut_face):
    photo, result, mesh = astronaut_face
    assert not any("eyebrow" in note for note in result.warnings)
    # the photo's pixels inside the hair outline and off the face oval
    shape = photo.rgb.shape[:2]
    region = polygon_mask(shape, result.hair) & ~polygon_mask(shape, mesh[list(OVAL), :2])
    hair = hex_rgb(result.face.palette.hair)
    assert np.linalg.norm(hair - np.median(photo.rgb[region].astype(float), axis=0)) < 30
    assert np.linalg.norm(hair - hex_rgb(result.face.palette.skin)) > 40


def test_hair_of_the_background_colour_keeps_its_own_colour(astronaut_face):
    _, original, _ = astronaut_face
    hair = hex_rgb(original.face.palette.hair)
    head = Image.fromarray(data.astronaut()).crop((120, 0, 330, 240))
    canvas = Image.new("RGB", (500, 520), tuple(int(v) for v in hair))
    canvas.paste(head, (145, 140))
    result = face_from_photo(photo_from_image(canvas, "same colour"))
    assert not any("eyebrow" in note for note in result.warnings)
    assert np.linalg.norm(hex_rgb(result.face.palette.hair) - hair) < 40


def test_astronaut_fringe_is_found(astronaut_face):
    # her hair falls over the top of her forehead
    _, result, _ = astronaut_face
    assert result.fringe


def test_no_person_found_gives_no_hair_and_a_hidden_cap(astronaut_face):
    from cartoonface.photo.hair import segment_head
    from cartoonface.photo.palette import face_colours

    photo, _, mesh = astronaut_face
    skin = face_colours(photo.rgb, mesh)["skin"]
    head = segment_head(photo.rgb, mesh, skin, 0.0, 0.0, lambda image: np.zeros(image.shape[:2]))
    assert head.hair is None and not head.fringe
    oval = polygon_mask(photo.rgb.shape[:2], mesh[list(OVAL), :2])
    cap = polygon_mask(photo.rgb.shape[:2], head.polygon)
    assert cap.any() and (cap & ~oval).sum() <= 0.02 * cap.sum()  # behind the drawn face
    # the whole window taken for the person: hair is found again, above the eyes
    found = segment_head(photo.rgb, mesh, skin, 0.0, 0.0, lambda image: np.ones(image.shape[:2]))
    assert found.hair is not None and found.polygon[:, 1].min() < mesh[10, 1]
