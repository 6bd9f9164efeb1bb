"""What an installed cartoonface gets: the wheel's files, and a command line that starts light."""

from __future__ import annotations

import json
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
# Checkout folders whose files the installed program reads, and where they land in the wheel.
PACKAGE_DATA = {
    ROOT / "templates": "cartoonface/templates",
    ROOT / "static": "cartoonface/static",
    ROOT / "cartoonface" / "data" / "faces": "cartoonface/data/faces",
}
# Modules `cartoonface --help` must not load: together they took ~1.3 s to import (docs/BENCHMARKS.md).
HEAVY_MODULES = ("numpy", "scipy", "lxml", "flask", "pypinyin", "jinja2", "mediapipe", "cv2")


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> zipfile.ZipFile:
    """The wheel built from the checkout (no dependencies, no build isolation: offline, ~2 s)."""
    out = tmp_path_factory.mktemp("wheel")
    done = subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--no-build-isolation",
                           str(ROOT), "-w", str(out)], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    (path,) = out.glob("cartoonface-*.whl")
    with zipfile.ZipFile(path) as archive:
        yield archive


@pytest.mark.parametrize("source", list(PACKAGE_DATA), ids=lambda p: p.relative_to(ROOT).as_posix())
def test_wheel_holds_every_data_file_with_its_content(wheel, source):
    files = [p for p in source.rglob("*") if p.is_file() and "__pycache__" not in p.parts]
    assert files, f"{source} is empty"
    names = set(wheel.namelist())
    for file in files:
        name = f"{PACKAGE_DATA[source]}/{file.relative_to(source).as_posix()}"
        assert name in names, f"{name} missing from the wheel"
        assert wheel.read(name) == file.read_bytes(), f"{name} differs from {file}"


def test_wheel_sample_faces_are_face_models(wheel):
    faces = [n for n in wheel.namelist() if n.startswith("cartoonface/data/faces/") and n.endswith(".json")]
    assert faces
    for name in faces:
        assert json.loads(wheel.read(name))["format"] == "cartoonface-face", name


def test_wheel_has_no_tests_bench_or_checkout_files(wheel):
    tops = {name.split("/")[0] for name in wheel.namelist()}
    assert tops == {"cartoonface", next(t for t in tops if t.endswith(".dist-info"))}
    assert not [n for n in wheel.namelist() if "/tests/" in n or "__pycache__" in n or n.endswith(".pyc")]


def test_wheel_declares_the_command(wheel):
    (entry_points,) = [n for n in wheel.namelist() if n.endswith(".dist-info/entry_points.txt")]
    assert "cartoonface = cartoonface.cli:command" in wheel.read(entry_points).decode()


@pytest.mark.parametrize("code", ["import cartoonface.cli",
                                  "from cartoonface.cli import build_parser; build_parser().format_help()"])
def test_cli_start_loads_no_heavy_module(code):
    """Importing the CLI and building its --help load none of the heavy libraries."""
    check = f"import sys\n{code}\nprint(' '.join(m for m in {HEAVY_MODULES!r} if m in sys.modules))"
    done = subprocess.run([sys.executable, "-c", check], capture_output=True, text=True, timeout=60, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == []


def test_wheel_holds_the_lexicon(wheel):
    lexicon = ROOT / "cartoonface" / "data" / "lexicon.txt"
    assert wheel.read("cartoonface/data/lexicon.txt") == lexicon.read_bytes()


# Modules `cartoonface generate` does not import before an audio job's work (issue 16's start-up): pypinyin
# (0.2 s; speech/lexicon.py holds its answers), scipy, the video tracking, urllib.request (via xml.sax).
NOT_AT_START = ("pypinyin", "scipy", "cartoonface.video.track", "cartoonface.video.drive", "urllib.request")


def test_generate_start_loads_only_what_an_audio_job_needs():
    check = ("import sys\nimport cartoonface.cli.generate, cartoonface.pipeline, cartoonface.exports.video\n"
             f"print(' '.join(m for m in sys.modules if m in {NOT_AT_START!r} or m.split('.')[0] in {NOT_AT_START!r}))")
    done = subprocess.run([sys.executable, "-c", check], capture_output=True, text=True, timeout=60, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == []
