"""Face from a photo (cartoonface.photo.model_from_photo, `cartoonface face from-photo`).

The photos are skimage.data.astronaut() (a 512 x 512 portrait shipped by scikit-image)
and pictures the tests make from it. Needs the photo extra (mediapipe, OpenCV,
scikit-image); without it the module is skipped with the reason.
"""

from __future__ import annotations

import io
import json
import struct
import zlib
from importlib.util import find_spec

import numpy as np
import pytest
from lxml import etree

from tests.conftest import run_cli

MISSING = [name for name in ("mediapipe", "cv2", "skimage") if find_spec(name) is None]
pytestmark = pytest.mark.skipif(
    bool(MISSING), reason=f"the photo extra is not installed (missing {', '.join(MISSING)}): "
                          "scripts/setup.sh installs it")

if not MISSING:
    from PIL import Image
    from skimage import data

    from cartoonface.cli import main
    from cartoonface.errors import InputError
    from cartoonface.face.model import POINT_INDEX, POINT_NAMES, load_face
    from cartoonface.photo.model_from_photo import face_from_photo, load_photo, photo_from_image

# Where the astronaut's features are in the 512 x 512 photo (x0, y0, x1, y1), read off
# the picture by eye; generous boxes that do not overlap.
REGIONS = {
    "image-left eye": ((188, 92, 216, 112), ("3.6", "3.12", "3.8", "3.2", "3.4")),
    "image-right eye": ((232, 92, 264, 112), ("3.5", "3.7", "3.11", "3.1", "3.3")),
    "nose": ((206, 106, 244, 134), ("9.15", "9.4", "9.5", "9.1", "9.2", "9.13", "9.14")),
    "mouth": ((198, 134, 252, 162), ("8.1", "8.2", "8.3", "8.4", "8.9", "8.10", "2.2", "2.3")),
}


def partner(name: str) -> str:
    """The mirror partner of a point name (odd <-> even on the image right / left)."""
    pairs = {"2.13": "2.14", "3.1": "3.2", "3.3": "3.4", "3.5": "3.6", "3.7": "3.12", "3.11": "3.8",
             "4.1": "4.2", "4.3": "4.4", "4.3a": "4.4a", "4.5": "4.6", "8.3": "8.4", "8.10": "8.9",
             "9.1": "9.2", "9.5": "9.4", "9.7": "9.6", "9.13": "9.14", "10.1": "10.2", "10.7": "10.8",
             "10.9": "10.10", "11.3": "11.2", "11.3a": "11.2a"}
    pairs.update({b: a for a, b in pairs.items()})
    return pairs.get(name, name)


MIRROR = [POINT_INDEX[partner(n)] for n in POINT_NAMES]


def astronaut() -> Image.Image:
    return Image.fromarray(data.astronaut())


def from_image(image: Image.Image, name: str = "test"):
    return face_from_photo(photo_from_image(image, name), name)


@pytest.fixture(scope="module")
def original():
    return from_image(astronaut())


def test_features_land_in_their_regions(original):
    for region, ((x0, y0, x1, y1), names) in REGIONS.items():
        for name in names:
            x, y = original.points[POINT_INDEX[name]]
            assert x0 <= x <= x1 and y0 <= y <= y1, f"{name} at ({x:.0f}, {y:.0f}) is not in the {region}"


def test_model_is_a_frontal_face_in_order(original):
    face = original.face
    p = face.point
    assert abs(p("3.6")[1] - p("3.5")[1]) < 0.03 * face.fapu.d  # levelled
    assert p("3.12")[0] < p("3.6")[0] < p("3.8")[0] < p("9.15")[0] < p("3.11")[0] < p("3.5")[0] < p("3.7")[0]
    assert p("4.4")[1] < p("3.2")[1] < p("3.6")[1] < p("3.4")[1] < p("9.15")[1] < p("8.1")[1] < p("8.2")[1] < p("2.1")[1]
    assert p("10.2")[0] < p("11.2")[0] and p("10.1")[0] > p("11.3")[0]  # ears outside the temples
    assert p("11.1")[1] < p("4.4")[1]
    hair = face.hair
    assert len(hair) == 23
    assert hair[:, 1].min() < p("11.1")[1]  # hair above the forehead
    assert 0.5 * face.fapu.d < face.fapu.mw0 < 1.5 * face.fapu.d


def test_smiling_open_mouth_is_warned_and_closed(original):
    notes = " ".join(original.warnings)
    assert "open" in notes and "smiles" in notes
    photo_gap = original.points[POINT_INDEX["2.3"], 1] - original.points[POINT_INDEX["2.2"], 1]
    mouth_width = original.points[POINT_INDEX["8.3"], 0] - original.points[POINT_INDEX["8.4"], 0]
    assert photo_gap > 0.08 * mouth_width
    face = original.face
    assert face.point("2.3")[1] - face.point("2.2")[1] < 0.01 * face.fapu.d
    corners = (face.point("8.3")[1] + face.point("8.4")[1]) / 2
    assert corners >= face.point("2.2")[1] - 0.01 * face.fapu.d


def test_palette_comes_from_the_face_not_the_background():
    # the head on a green background: no sampled colour may be green
    head = astronaut().crop((120, 0, 330, 240))
    canvas = Image.new("RGB", (500, 520), (0, 200, 0))
    canvas.paste(head, (145, 140))
    result = from_image(canvas)
    palette = result.face.palette
    for key in ("skin", "hair", "brow", "iris", "lip"):
        r, g, b = (int(getattr(palette, key)[i:i + 2], 16) for i in (1, 3, 5))
        assert not (g > r + 40 and g > b + 40), f"{key} {getattr(palette, key)} is the background green"
    skin = np.array([int(palette.skin[i:i + 2], 16) for i in (1, 3, 5)])
    assert skin[0] > skin[2]  # skin is warm


def test_mirrored_photo_gives_the_mirrored_model(original):
    flipped = from_image(astronaut().transpose(Image.Transpose.FLIP_LEFT_RIGHT))
    d = original.face.fapu.d
    model = original.face.points.copy()
    model[:, 0] = 400.0 - model[:, 0]
    error = np.hypot(*(flipped.face.points[MIRROR] - model).T)
    assert np.median(error) < 0.03 * d and error.max() < 0.12 * d, POINT_NAMES[int(np.argmax(error))]
    photo = original.points.copy()
    photo[:, 0] = 512.0 - photo[:, 0]
    assert np.median(np.hypot(*(flipped.points[MIRROR] - photo).T)) < 1.5
    assert flipped.turn == pytest.approx(-original.turn, abs=3)
    # the hair outline covers the mirrored area (its points may slide along it)
    from cartoonface.photo.palette import polygon_mask

    hair = np.column_stack([400.0 - original.face.hair[:, 0], original.face.hair[:, 1]])
    mirrored, found = polygon_mask((480, 400), hair), polygon_mask((480, 400), flipped.face.hair)
    assert (mirrored & found).sum() / (mirrored | found).sum() > 0.85


def test_scaled_photo_gives_the_same_model(original):
    bigger = from_image(astronaut().resize((768, 768), Image.Resampling.LANCZOS))
    d = original.face.fapu.d
    assert np.median(np.hypot(*(bigger.points - 1.5 * original.points).T)) < 2.0
    assert np.median(np.hypot(*(bigger.face.points - original.face.points).T)) < 0.03 * d


def test_rotated_photo_is_levelled(original):
    # PIL turns counter-clockwise on screen: the head leans with its top to the image left
    rotated = from_image(astronaut().rotate(10, resample=Image.Resampling.BICUBIC, fillcolor=(128, 128, 128)))
    assert rotated.roll - original.roll == pytest.approx(-10, abs=2)
    d = original.face.fapu.d
    error = np.hypot(*(rotated.face.points - original.face.points).T)
    assert np.median(error) < 0.05 * d
    # the hair outline covers the same area (its points may slide along it)
    from cartoonface.photo.palette import polygon_mask

    before, after = (polygon_mask((480, 400), face.hair) for face in (original.face, rotated.face))
    assert (before & after).sum() / (before | after).sum() > 0.8
    # the detected photo points follow the turned face
    a = np.radians(10)
    rel = original.points - 256
    turned = np.column_stack([np.cos(a) * rel[:, 0] + np.sin(a) * rel[:, 1],
                              -np.sin(a) * rel[:, 0] + np.cos(a) * rel[:, 1]]) + 256
    assert np.median(np.hypot(*(rotated.points - turned).T)) < 2.0


def test_largest_of_two_faces_is_used():
    canvas = Image.new("RGB", (900, 520), (200, 200, 200))
    canvas.paste(astronaut(), (0, 0))
    canvas.paste(astronaut().resize((300, 300)), (580, 100))
    result = from_image(canvas)
    assert any("2 faces" in note for note in result.warnings)
    assert result.points[:, 0].max() < 512


def test_grayscale_alpha_and_exif_photos(tmp_path, original):
    grey_path = tmp_path / "grey.jpg"
    astronaut().convert("L").save(grey_path, quality=92)
    grey = face_from_photo(load_photo(grey_path))
    for key in ("skin", "hair", "lip"):
        colour = getattr(grey.face.palette, key)
        channels = [int(colour[i:i + 2], 16) for i in (1, 3, 5)]
        assert max(channels) - min(channels) <= 2, f"{key} {colour} is not grey"

    rgba = np.array(astronaut().convert("RGBA"))
    rgba[:, :120, 3] = 0
    alpha_path = tmp_path / "alpha.png"
    Image.fromarray(rgba).save(alpha_path)
    photo = load_photo(alpha_path)
    assert photo.rgb.shape == (512, 512, 3) and (photo.rgb[:, :120] == 255).all()
    assert np.median(np.hypot(*(face_from_photo(photo).points - original.points).T)) < 1.5

    exif = Image.Exif()
    exif[0x0112] = 6  # "rotate 90 degrees clockwise to display"
    exif_path = tmp_path / "exif.jpg"
    astronaut().rotate(90, expand=True).save(exif_path, quality=95, exif=exif)
    upright = face_from_photo(load_photo(exif_path))
    assert np.median(np.hypot(*(upright.points - original.points).T)) < 1.5


def test_huge_photo_is_scaled_down(tmp_path, original):
    path = tmp_path / "huge.jpg"
    astronaut().resize((7072, 7072), Image.Resampling.BILINEAR).save(path, quality=80)
    photo = load_photo(path)
    assert max(photo.rgb.shape) <= 2048 and photo.scale == pytest.approx(max(photo.rgb.shape) / 7072)
    result = face_from_photo(photo)
    k = max(photo.rgb.shape) / 512
    assert np.median(np.hypot(*(result.points - k * original.points).T)) < 2.0 * k


def _bomb_png() -> bytes:
    """A PNG whose header declares 30000 x 30000 pixels (and carries almost no data)."""
    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
    header = struct.pack(">IIBBBBB", 30000, 30000, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(b"\0" * 64)) + chunk(b"IEND", b"")


def _bad_photos(tmp_path):
    jpeg = io.BytesIO()
    astronaut().save(jpeg, "JPEG", quality=90)
    small = io.BytesIO()
    astronaut().resize((200, 200)).save(small, "PNG")
    noface = io.BytesIO()
    Image.fromarray(data.coffee()).save(noface, "PNG")
    files = {
        "text.jpg": (b"not a picture\n", "not an image"),
        "cut.jpg": (jpeg.getvalue()[: len(jpeg.getvalue()) // 2], "truncated"),
        "coffee.png": (noface.getvalue(), "no face found"),
        "small.png": (small.getvalue(), "photo too small"),
        "bomb.png": (_bomb_png(), "too large"),
    }
    for name, (content, _) in files.items():
        (tmp_path / name).write_bytes(content)
    return {tmp_path / name: expected for name, (_, expected) in files.items()}


def test_bad_photos_are_refused_by_name(tmp_path, capsys):
    for path, expected in _bad_photos(tmp_path).items():
        with pytest.raises(InputError, match=expected) as caught:
            face_from_photo(load_photo(path))
        assert str(path) in str(caught.value)
        assert main(["face", "from-photo", str(path), "-o", str(tmp_path / "out.json")]) == 2
        err = capsys.readouterr().err
        assert expected in err and "Traceback" not in err
    assert not (tmp_path / "out.json").exists()
    with pytest.raises(InputError, match="no such photo"):
        load_photo(tmp_path / "missing.jpg")


def test_cli_writes_face_preview_and_overlay(tmp_path):
    photo = tmp_path / "astronaut.jpg"
    astronaut().save(photo, quality=92)
    out, preview, overlay = tmp_path / "face.json", tmp_path / "preview.svg", tmp_path / "overlay.png"
    done = run_cli("face", "from-photo", photo, "-o", out, "--preview", preview, "--overlay", overlay)
    assert done.returncode == 0, done.stderr
    assert "warning" in done.stderr and "open" in done.stderr
    face = load_face(out)
    assert face.name == "astronaut" and len(face.hair) == 23
    assert json.loads(out.read_text())["format"] == "cartoonface-face"
    root = etree.parse(str(preview)).getroot()
    assert root.find(".//{http://www.w3.org/2000/svg}g[@id='face']") is not None
    assert preview.with_suffix(".png").read_bytes().startswith(b"\x89PNG")
    with Image.open(overlay) as image:
        assert image.size == (512, 512)
    bad = run_cli("face", "from-photo", photo, "-o", tmp_path / "face.txt")
    assert bad.returncode == 2 and "ending in .json" in bad.stderr


def test_turned_head_is_warned_and_turned_back(original):
    from dataclasses import replace

    from cartoonface.photo.landmarks import landmarker
    from cartoonface.photo.landmarks_map import eyes
    from cartoonface.photo.model_from_photo import face_from_landmarks

    photo = photo_from_image(astronaut(), "turned")
    found = landmarker().find(photo.rgb)
    # turn the mesh 25 degrees about the vertical axis through the eyes (nose to the image right)
    mesh = found.points.copy()
    centre, _d = eyes(mesh)
    a = np.radians(25)
    rel = mesh - centre
    mesh[:, 0] = centre[0] + np.cos(a) * rel[:, 0] - np.sin(a) * rel[:, 2]
    mesh[:, 2] = centre[2] + np.sin(a) * rel[:, 0] + np.cos(a) * rel[:, 2]
    turned = face_from_landmarks(photo, replace(found, points=mesh))
    assert turned.turn - original.turn == pytest.approx(25, abs=3)
    assert any("turned 2" in note for note in turned.warnings)
    assert not any("turned" in note for note in original.warnings)
    d = original.face.fapu.d
    assert np.median(np.hypot(*(turned.face.points - original.face.points).T)) < 0.05 * d


def test_missing_photo_extra_is_a_clear_error(monkeypatch):
    import sys

    from cartoonface.photo.landmarks import Landmarker, PhotoExtraMissing, landmarker

    landmarker()  # mediapipe fully imported first, so hiding one module leaves no half import behind
    monkeypatch.setitem(sys.modules, "mediapipe.python.solutions", None)
    with pytest.raises(PhotoExtraMissing, match=r"needs the photo extra .*cartoonface\[photo\]"):
        Landmarker()
    assert issubclass(PhotoExtraMissing, InputError)
