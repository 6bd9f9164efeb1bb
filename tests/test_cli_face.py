"""`cartoonface face render | sheet | diagram`, run as a user would."""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
import pytest
from lxml import etree
from PIL import Image

from cartoonface.cli import main
from cartoonface.face.lift import LIFTED_NAMES
from cartoonface.face.mouth import MOUTH_SYMBOLS
from tests.conftest import ROOT, run_cli

FEMALE = ROOT / "samples" / "faces" / "female.json"
SVG = "{http://www.w3.org/2000/svg}"


def png_pixels(path: Path) -> np.ndarray:
    with Image.open(io.BytesIO(path.read_bytes())) as image:
        return np.asarray(image.convert("RGB"))


def test_render_writes_svg_and_a_non_blank_png(tmp_path: Path) -> None:
    out = tmp_path / "out" / "face.svg"
    done = run_cli("face", "render", FEMALE, "-o", out, "--turn", "-12", "--tilt", "5", "--roll", "3",
                   "--blink", ".4", "--smile", "1", "--brow", "0.5", "--mouth", "a", "--png")
    assert done.returncode == 0, done.stderr
    root = etree.parse(str(out)).getroot()
    assert [g.get("id") for g in root.findall(f"{SVG}g")] == ["background", "hair", "clothes", "face"]
    rgb = png_pixels(out.with_suffix(".png"))
    assert rgb.shape[:2] == (480, 400)
    assert len(np.unique(rgb.reshape(-1, 3), axis=0)) > 50


def test_render_options_change_the_drawing(tmp_path: Path) -> None:
    plain, turned = tmp_path / "plain.svg", tmp_path / "turned.svg"
    assert main(["face", "render", str(FEMALE), "-o", str(plain)]) == 0
    assert main(["face", "render", str(FEMALE), "-o", str(turned), "--turn", "15"]) == 0
    assert plain.read_bytes() != turned.read_bytes()
    assert not plain.with_suffix(".png").exists()


def write_face(tmp_path: Path, change) -> Path:
    obj = json.loads(FEMALE.read_text(encoding="utf-8"))
    change(obj)
    path = tmp_path / "face.json"
    path.write_text(json.dumps(obj), encoding="utf-8")
    return path


def _nan(obj: dict) -> None:
    obj["points"]["3.2"][1] = float("nan")


BAD_FACES = {
    "malformed": (lambda tmp: _text(tmp, '{"format": "cartoonface-face", "points": {'), "JSON"),
    "missing point": (lambda tmp: write_face(tmp, lambda o: o["points"].pop("8.4")), "'8.4'"),
    "nan": (lambda tmp: write_face(tmp, _nan), "3.2"),
    "no file": (lambda tmp: tmp / "absent.json", "absent.json"),
}


def _text(tmp: Path, text: str) -> Path:
    path = tmp / "broken.json"
    path.write_text(text, encoding="utf-8")
    return path


def check_refused(done, named: str, out: Path) -> None:
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert named in lines[0]
    assert "Traceback" not in done.stderr
    assert not out.exists() and not out.with_suffix(".png").exists()
    assert not list(out.parent.glob(".*tmp"))


@pytest.mark.parametrize("case", sorted(BAD_FACES))
def test_bad_face_files_are_refused_in_one_line(tmp_path: Path, case: str) -> None:
    make, named = BAD_FACES[case]
    out = tmp_path / "out.svg"
    check_refused(run_cli("face", "render", make(tmp_path), "-o", out, "--png"), named, out)


@pytest.mark.parametrize(("option", "value", "named"), [("--turn", "40", "--turn 40"), ("--mouth", "x", "'x'")])
def test_bad_options_are_refused_in_one_line(tmp_path: Path, option: str, value: str, named: str) -> None:
    out = tmp_path / "out.svg"
    check_refused(run_cli("face", "render", FEMALE, "-o", out, option, value, "--png"), named, out)


@pytest.mark.parametrize(("args", "named"), [
    (("render", "--tilt", "-15.5"), "--tilt"),
    (("render", "--roll", "nan"), "--roll"),
    (("render", "--blink", "1.5"), "--blink"),
    (("render", "--smile", "-0.1"), "--smile"),
    (("render", "--brow", "lots"), "--brow"),
    (("render", "--mouth", "A"), "'A'"),
    (("render", "--emotion", "joy"), "--emotion 'joy'"),
    (("render", "--emotion", "sad", "--intensity", "1.2"), "--intensity 1.2"),
    (("sheet",), "8.4"),
    (("diagram",), "8.4"),
])
def test_every_action_and_option_is_checked(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                            args: tuple[str, ...], named: str) -> None:
    face = FEMALE if args[0] == "render" else write_face(tmp_path, lambda o: o["points"].pop("8.4"))
    out = tmp_path / "out.svg"
    assert main(["face", args[0], str(face), "-o", str(out), "--png", *args[1:]]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and named in err[0]
    assert not out.exists() and not out.with_suffix(".png").exists()


def test_output_must_be_an_svg_name(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out.png"
    assert main(["face", "render", str(FEMALE), "-o", str(out)]) == 2
    assert ".svg" in capsys.readouterr().err and not out.exists()


def test_sheet_shows_every_mouth_shape_and_row(tmp_path: Path) -> None:
    out = tmp_path / "sheet.svg"
    done = run_cli("face", "sheet", FEMALE, "-o", out, "--png")
    assert done.returncode == 0, done.stderr
    root = etree.parse(str(out)).getroot()
    texts = ["".join(t.itertext()) for t in root.iter(f"{SVG}text")]
    assert set(MOUTH_SYMBOLS) <= set(texts)
    heads = root.findall(f"{SVG}g[@class='cf-face']")
    rows = [t for t in texts if t not in MOUTH_SYMBOLS]
    assert len(heads) == len(rows) * len(MOUTH_SYMBOLS) and len(rows) >= 6
    ids = [e.get("id") for e in root.iter() if e.get("id")]
    assert len(ids) == len(set(ids))
    rgb = png_pixels(out.with_suffix(".png"))
    assert rgb.shape[1] > 12 * 60 and len(np.unique(rgb.reshape(-1, 3), axis=0)) > 50


def test_diagram_labels_every_point(tmp_path: Path) -> None:
    out = tmp_path / "diagram.svg"
    assert main(["face", "diagram", str(FEMALE), "-o", str(out)]) == 0
    root = etree.parse(str(out)).getroot()
    labels = {name for t in root.iter(f"{SVG}text") for name in (t.text or "").split("/")}
    hair = len(json.loads(FEMALE.read_text(encoding="utf-8"))["hair"])
    assert set(LIFTED_NAMES) | {str(i) for i in range(hair)} <= labels


def test_help_describes_the_options(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(["face", "render", "--help"])
    assert exit_.value.code == 0
    text = capsys.readouterr().out
    for option in ("--tilt", "--turn", "--roll", "--blink", "--smile", "--brow", "--mouth", "--png"):
        assert option in text


def test_output_that_is_a_folder_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "taken.svg"
    out.mkdir()
    assert main(["face", "render", str(FEMALE), "-o", str(out), "--png"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "folder" in err[0]
    assert out.is_dir() and not out.with_suffix(".png").exists()
