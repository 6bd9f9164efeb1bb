"""Exports: Rhubarb mouth cues (TSV/JSON/XML) and WebVTT captions, as functions and from the CLI."""

from __future__ import annotations

import base64
import json
import random
import re
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from cartoonface.exports.captions import captions_vtt, vtt_time
from cartoonface.exports.cues import FORMATS, REST, RHUBARB_SHAPE, RHUBARB_SHAPES, cues_text, mouth_cues
from cartoonface.face.mouth import MOUTH_SYMBOLS
from cartoonface.speech.mouth_shapes import shape_onsets
from cartoonface.speech.records import Alignment, Sentence, Syllable
from tests.conftest import run_cli, spoken_inputs

ROOT = Path(__file__).resolve().parent.parent
FACE = ROOT / "samples" / "faces" / "female.json"
TEXT = "你好。谢谢你。"
needs_espeak = pytest.mark.skipif(not shutil.which("espeak-ng"), reason="needs espeak-ng")


def random_alignment(seed: int) -> Alignment:
    """Sentences of random syllables (random shapes, lengths and pauses) over a random duration."""
    rng = random.Random(seed)
    sentences = []
    time = rng.uniform(0.0, 0.5)
    for number in range(rng.randint(1, 4)):
        start = time
        syllables = []
        for _ in range(rng.randint(1, 6)):
            length = rng.uniform(0.005, 0.4)
            shapes = tuple(rng.choice(MOUTH_SYMBOLS) for _ in range(rng.randint(1, 4)))
            syllables.append(Syllable("字", "zi4", shapes, time, time + length, 1.0))
            time += length + rng.choice((0.0, 0.0, rng.uniform(0.0, 0.2)))
        sentences.append(Sentence(f"第{number}句 <a & b> -->", start, time, tuple(syllables)))
        time += rng.uniform(0.1, 1.0)
    return Alignment(tuple(sentences), time + rng.uniform(0.0, 1.0), ())


def shape_at(alignment: Alignment, t: float) -> str:
    """The Rhubarb shape the alignment's mouth-shape tier shows at time t (X outside syllables)."""
    for sentence in alignment.sentences:
        for s in sentence.syllables:
            if s.start <= t < s.end:
                onsets = [s.start + f * (s.end - s.start) for f in shape_onsets(len(s.shapes))]
                index = max(k for k, onset in enumerate(onsets) if onset <= t)
                return RHUBARB_SHAPE[s.shapes[index]]
    return REST


def test_every_mandarin_shape_has_a_rhubarb_shape():
    assert set(RHUBARB_SHAPE) == set(MOUTH_SYMBOLS)
    assert set(RHUBARB_SHAPE.values()) <= set(RHUBARB_SHAPES) - {REST}
    assert RHUBARB_SHAPE["m"] == "A" and RHUBARB_SHAPE["a"] == "D" and RHUBARB_SHAPE["u"] == "F"


@pytest.mark.parametrize("seed", range(20))
def test_cues_tile_the_recording_and_follow_the_shapes(seed):
    alignment = random_alignment(seed)
    cues = mouth_cues(alignment)
    assert cues[0].start == 0
    assert cues[-1].end == int(alignment.duration * 100 + 1e-6)
    for earlier, later in zip(cues, cues[1:]):
        assert earlier.end == later.start and earlier.value != later.value
    assert all(c.end > c.start and c.value in RHUBARB_SHAPES for c in cues)
    # Wherever the cues differ from the alignment's shapes, a boundary of the alignment is
    # within 0.01 s (rounding to hundredths, shapes shorter than that dropped).
    boundaries = [0.0]
    for sentence in alignment.sentences:
        for s in sentence.syllables:
            boundaries += [s.start + f * (s.end - s.start) for f in shape_onsets(len(s.shapes))] + [s.end]
    for step in range(cues[-1].end * 10):
        t = step / 1000
        shown = next(c.value for c in cues if c.start <= step / 10 < c.end)
        if shown != shape_at(alignment, t):
            assert min(abs(t - b) for b in boundaries) <= 0.01, (t, shown)

def test_the_three_formats_carry_the_same_cues():
    alignment = random_alignment(7)
    cues = mouth_cues(alignment)
    expected = [(c.start / 100, c.end / 100, c.value) for c in cues]
    duration = int(alignment.duration * 100) / 100

    tsv = [line.split("\t") for line in cues_text(cues, alignment.duration, "tsv", "a.wav").splitlines()]
    assert [(float(t), v) for t, v in tsv[:-1]] == [(start, value) for start, _, value in expected]
    assert (float(tsv[-1][0]), tsv[-1][1]) == (duration, REST)
    assert all(re.fullmatch(r"\d+\.\d\d", t) for t, _ in tsv)

    data = json.loads(cues_text(cues, alignment.duration, "json", "a & b.wav"))
    assert data["metadata"] == {"soundFile": "a & b.wav", "duration": duration}
    assert [(c["start"], c["end"], c["value"]) for c in data["mouthCues"]] == expected

    root = ET.fromstring(cues_text(cues, alignment.duration, "xml", "a & b.wav").encode("utf-8"))
    assert root.tag == "rhubarbResult"
    assert root.findtext("metadata/soundFile") == "a & b.wav"
    assert float(root.findtext("metadata/duration") or "") == duration
    assert [(float(c.get("start") or ""), float(c.get("end") or ""), c.text) for c in root.iter("mouthCue")] == expected
    with pytest.raises(ValueError, match="dat"):
        cues_text(cues, alignment.duration, "dat", "a.wav")


def parse_vtt(text: str) -> list[tuple[str, str, str]]:
    """(start, end, text) of every cue of a WebVTT file."""
    assert text.startswith("WEBVTT\n\n")
    cues = []
    for block in text.strip().split("\n\n")[1:]:
        _number, timing, body = block.split("\n")
        start, end = timing.split(" --> ")
        cues.append((start, end, body))
    return cues


@pytest.mark.parametrize("seed", range(5))
def test_captions_are_the_sentences_at_their_times(seed):
    alignment = random_alignment(seed)
    cues = parse_vtt(captions_vtt(alignment))
    assert [(start, end) for start, end, _ in cues] == [(vtt_time(s.start), vtt_time(s.end)) for s in alignment.sentences]
    for (_, _, body), sentence in zip(cues, alignment.sentences, strict=True):
        assert "-->" not in body and "<" not in body
        assert body.replace("&lt;", "<").replace("&gt;", ">").replace("&amp;", "&") == sentence.text


def test_vtt_time_reads_back():
    for seconds in (0.0, 0.0005, 59.9994, 61.25, 3600 * 2 + 62.5):
        hours, minutes, rest = vtt_time(seconds).split(":")
        assert abs(int(hours) * 3600 + int(minutes) * 60 + float(rest) - seconds) <= 0.0005
        assert 0 <= int(minutes) < 60 and float(rest) < 60


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> tuple[Path, Path]:
    """A short espeak-ng recording and its transcript file."""
    return spoken_inputs(tmp_path_factory.mktemp("exports"), TEXT, speed=150)


@needs_espeak
def test_generate_writes_cues_and_captions_and_the_page_tracks_them(inputs, tmp_path):
    speech, transcript = inputs
    out = tmp_path / "site"
    done = run_cli("generate", "--face", str(FACE), "--audio", str(speech), "--transcript", str(transcript),
                   "-o", str(out), "--cues", "tsv", "--cues", "xml")
    assert done.returncode == 0, done.stderr
    assert (out / "mouth-cues.tsv").is_file() and (out / "mouth-cues.xml").is_file()
    assert not (out / "mouth-cues.json").exists()
    lines = (out / "mouth-cues.tsv").read_text(encoding="utf-8").splitlines()
    assert {line.split("\t")[1] for line in lines} > {"X"}
    assert len(parse_vtt((out / "captions.vtt").read_text(encoding="utf-8"))) == 2
    track = re.search(r'<track kind="captions" src="data:text/vtt;base64,([^"]+)"',
                      (out / "index.html").read_text(encoding="utf-8"))
    assert track and base64.b64decode(track[1]) == (out / "captions.vtt").read_bytes()


@needs_espeak
def test_align_writes_cues_beside_the_textgrid(inputs, tmp_path):
    speech, transcript = inputs
    done = run_cli("align", str(speech), "--transcript", str(transcript), "-o", str(tmp_path / "a.TextGrid"),
                   "--cues", "json")
    assert done.returncode == 0, done.stderr
    data = json.loads((tmp_path / "a.json").read_text(encoding="utf-8"))
    assert data["metadata"]["soundFile"] == speech.name and len(data["mouthCues"]) > 2


@pytest.mark.parametrize("command", ["generate", "align"])
def test_bad_cue_format_exits_2(command, tmp_path):
    args = ["--face", str(FACE)] if command == "generate" else []
    done = run_cli(command, *(["x.wav"] if command == "align" else ["--audio", "x.wav"]), *args,
                   "--transcript", "t.txt", "-o", str(tmp_path / "o"), "--cues", "dat")
    assert done.returncode == 2 and "dat" in done.stderr and "Traceback" not in done.stderr
    assert set(FORMATS) <= set(re.findall(r"'(\w+)'", done.stderr))
