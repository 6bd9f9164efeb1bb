"""pipeline.generate: the folder it writes, determinism, edited inputs, and bad inputs leaving nothing behind."""

from __future__ import annotations

import gc
import json
import math
import shutil
from pathlib import Path

import pytest
from lxml import etree, html

from cartoonface.errors import ActionsError, AudioError, FaceModelError, InputError, OptionError, TranscriptError
from cartoonface.pipeline import STAGES, Options, generate
from cartoonface.speech.textgrid import read_textgrid
from tests.conftest import spoken_inputs

pytestmark = pytest.mark.skipif(not shutil.which("espeak-ng"), reason="needs espeak-ng")

ROOT = Path(__file__).resolve().parent.parent
FACE = ROOT / "samples" / "faces" / "male.json"
TEXT = "今天天气很好。我们去公园。"


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> tuple[Path, Path]:
    """A short espeak-ng Mandarin recording and its transcript file."""
    return spoken_inputs(tmp_path_factory.mktemp("inputs"), TEXT, speed=160)


@pytest.fixture(scope="module")
def made(inputs, tmp_path_factory):
    """One generated audio-book folder, its Result and the progress reports."""
    speech, transcript = inputs
    out = tmp_path_factory.mktemp("made") / "book"
    reports: list[tuple[str, float]] = []
    result = generate(FACE, speech, transcript, out, Options(title="天气", seed=5),
                      lambda stage, fraction: reports.append((stage, fraction)))
    return result, reports


def test_folder_has_every_file_and_result_adds_up(made):
    result, _ = made
    names = {p.relative_to(result.out_dir).as_posix() for p in result.out_dir.rglob("*") if p.is_file()}
    assert {"index.html", "animation.svg", "audio.m4a", "alignment.TextGrid", "actions.json",
            "static/cartoonface.js", "static/cartoonface.css"} <= names
    assert result.size == sum(p.stat().st_size for p in result.out_dir.rglob("*") if p.is_file())
    assert result.frames == math.ceil(round(result.duration * 1000) * 30 / 1000)
    assert result.seconds > 0
    doc = html.document_fromstring((result.out_dir / "index.html").read_text(encoding="utf-8"))
    assert doc.findtext(".//h1") == "天气"
    assert "".join(s.text_content() for s in doc.xpath("//span[@class='cf-sentence']")) == TEXT


def test_page_svg_is_the_animation_file(made):
    result, _ = made
    page = html.document_fromstring((result.out_dir / "index.html").read_text(encoding="utf-8"))
    standalone = etree.fromstring((result.out_dir / "animation.svg").read_bytes())
    inline = page.xpath("//svg[@id='cf-face']")[0]
    assert len(inline.xpath(".//animate")) == len(standalone.findall(".//{http://www.w3.org/2000/svg}animate")) > 0


def test_progress_goes_through_every_stage_in_order(made):
    _, reports = made
    stages = [stage for stage, _ in reports]
    assert [s for i, s in enumerate(stages) if i == 0 or stages[i - 1] != s] == [name for name, _ in STAGES]
    fractions = [fraction for _, fraction in reports]
    assert fractions == sorted(fractions) and fractions[0] == 0 and fractions[-1] == 1


def test_same_seed_same_bytes_other_seed_other_schedule(inputs, made, tmp_path):
    result, _ = made
    speech, transcript = inputs
    again = generate(FACE, speech, transcript, tmp_path / "again", Options(title="天气", seed=5))
    for name in ("animation.svg", "actions.json", "index.html"):
        assert (again.out_dir / name).read_bytes() == (result.out_dir / name).read_bytes()
    other = generate(FACE, speech, transcript, tmp_path / "other", Options(title="天气", seed=6))
    assert (other.out_dir / "actions.json").read_bytes() != (result.out_dir / "actions.json").read_bytes()


def test_the_cycle_collector_pauses_during_a_job_and_is_left_as_found(inputs, tmp_path):
    speech, transcript = inputs
    assert gc.isenabled()
    during: list[bool] = []
    generate(FACE, speech, transcript, tmp_path / "book", Options(), lambda stage, fraction: during.append(gc.isenabled()))
    assert during and not any(during)
    assert gc.isenabled()
    fake = tmp_path / "speech.wav"
    fake.write_text("not a recording", encoding="utf-8")
    with pytest.raises(AudioError):  # a job that fails restores it too
        generate(FACE, fake, transcript, tmp_path / "failed", Options())
    assert gc.isenabled()
    gc.disable()  # a caller that paused it keeps it paused
    try:
        with pytest.raises(AudioError):
            generate(FACE, fake, transcript, tmp_path / "failed", Options())
        assert not gc.isenabled()
    finally:
        gc.enable()


def test_edited_actions_and_alignment_are_used(inputs, made, tmp_path):
    result, _ = made
    speech, transcript = inputs
    actions = json.loads((result.out_dir / "actions.json").read_text(encoding="utf-8"))
    actions["actions"] = [{"kind": "turn", "start": 0.5, "duration": 0.6, "amplitude": 12.0}]
    edited = tmp_path / "actions.json"
    edited.write_text(json.dumps(actions), encoding="utf-8")
    grid = tmp_path / "edited.TextGrid"  # saved by Praat: UTF-16 with a byte order mark
    grid.write_text((result.out_dir / "alignment.TextGrid").read_text(encoding="utf-8"), encoding="utf-16")
    redone = generate(FACE, speech, transcript, tmp_path / "redone", Options(actions=edited, alignment=grid))
    written = json.loads((redone.out_dir / "actions.json").read_text(encoding="utf-8"))["actions"]
    assert [(a["kind"], a["start"], a["amplitude"]) for a in written] == [("turn", 0.5, 12.0)]
    given = read_textgrid(grid.read_text(encoding="utf-16"), "given")
    used = read_textgrid((redone.out_dir / "alignment.TextGrid").read_text(encoding="utf-8"), "used")
    syllables = [[(y.text, y.start, y.end) for s in a.sentences for y in s.syllables] for a in (given, used)]
    assert [t for t, _, _ in syllables[0]] == [t for t, _, _ in syllables[1]]
    assert [t for _, a, b in syllables[0] for t in (a, b)] == pytest.approx([t for _, a, b in syllables[1] for t in (a, b)],
                                                                            abs=1e-5)


def test_announcer_draws_the_chosen_scenery(inputs, tmp_path):
    speech, transcript = inputs
    result = generate(FACE, speech, transcript, tmp_path / "news",
                      Options(page="announcer", background="classroom", clothes="sweater", fps=12))
    svg = etree.fromstring((result.out_dir / "animation.svg").read_bytes())
    layers = [g.get("id") for g in svg if g.tag == "{http://www.w3.org/2000/svg}g"]
    assert layers == ["background", "hair", "clothes", "face"]
    x, y, w, h = map(float, svg.get("viewBox").split())
    assert w / h == pytest.approx(16 / 9, rel=0.01)
    assert result.frames == math.ceil(round(result.duration * 1000) * 12 / 1000)


def actions_file(tmp_path: Path, **action) -> Path:
    """An actions.json holding one action."""
    path = tmp_path / "actions.json"
    path.write_text(json.dumps({"format": "cartoonface-actions", "version": 1, "actions": [action]}), encoding="utf-8")
    return path


BAD = {
    "missing face": (lambda tmp, s, t: (tmp / "nope.json", s, t, Options()), FaceModelError),
    "missing audio": (lambda tmp, s, t: (FACE, tmp / "nope.wav", t, Options()), AudioError),
    "missing transcript": (lambda tmp, s, t: (FACE, s, tmp / "nope.txt", Options()), TranscriptError),
    "fps 0": (lambda tmp, s, t: (FACE, s, t, Options(fps=0)), OptionError),
    "angle 40": (lambda tmp, s, t: (FACE, s, t, Options(actions=actions_file(
        tmp, kind="tilt", start=0.2, duration=0.5, amplitude=40))), ActionsError),
    "past the end": (lambda tmp, s, t: (FACE, s, t, Options(actions=actions_file(
        tmp, kind="brow", start=60, duration=0.5, amplitude=0.5))), ActionsError),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_input_raises_and_leaves_no_folder(case, inputs, tmp_path):
    make_args, error = BAD[case]
    speech, transcript = inputs
    face, audio, text, options = make_args(tmp_path, speech, transcript)
    out = tmp_path / "out" / "site"
    before = sorted(tmp_path.rglob("*"))
    with pytest.raises(error) as raised:
        generate(face, audio, text, out, options)
    assert str(raised.value)
    assert not out.exists()
    assert [p for p in tmp_path.rglob("*") if p not in before and p != out.parent] == []


def test_unreadable_audio_is_an_input_error(inputs, tmp_path):
    _, transcript = inputs
    fake = tmp_path / "speech.wav"
    fake.write_text("this is not a recording", encoding="utf-8")
    with pytest.raises(AudioError, match="speech.wav"):
        generate(FACE, fake, transcript, tmp_path / "out", Options())
    assert not (tmp_path / "out").exists()


def test_folder_with_other_files_is_not_replaced(inputs, tmp_path):
    speech, transcript = inputs
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "thesis.txt").write_text("keep me", encoding="utf-8")
    with pytest.raises(InputError, match="other files"):
        generate(FACE, speech, transcript, tmp_path / "docs", Options())
    assert (tmp_path / "docs" / "thesis.txt").read_text(encoding="utf-8") == "keep me"
