"""Where users set emotions: transcript markup, default mood, emotion actions, the pipeline."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from cartoonface.animate.actions import actions_from_json, actions_to_json
from cartoonface.animate.behaviour import emotion_actions, marked_spans
from cartoonface.errors import OptionError, TranscriptError
from cartoonface.pipeline import Options, generate
from cartoonface.speech.records import Alignment, Sentence, Syllable
from cartoonface.speech.transcript import emotion_marks, parse_transcript
from tests.conftest import ROOT, spoken_inputs

PLAIN = "从前，有一只小白兔。每天晚上，它看月亮。\n月亮说：你好！"
MARKED = "[sad 0.5]从前，有一只小白兔。[happy]每天晚上，[surprise]它看月亮[/surprise]。\n[wink]月亮说[/]：你好！"


def _syllables(text: str) -> list[str]:
    return [s.pinyin for sentence in parse_transcript(text) for s in sentence.syllables]


def test_marks_are_never_read_and_never_counted() -> None:
    assert _syllables(MARKED) == _syllables(PLAIN)
    assert [s.text for s in parse_transcript(MARKED)] == [s.text for s in parse_transcript(PLAIN)]


def test_marks_cover_their_sentence_or_their_span() -> None:
    sad, happy, surprise, wink = emotion_marks(MARKED)
    assert (sad.name, sad.intensity, sad.first, sad.last) == ("sad", 0.5, 0, 7)  # 从前有一只小白兔
    assert (happy.first, happy.last) == (8, 15)  # 每天晚上它看月亮: to the end of its sentence
    assert (surprise.first, surprise.last) == (12, 15)
    assert (wink.first, wink.last) == (16, 18) and wink.where == "line 2, column 1"
    assert emotion_marks(PLAIN) == ()


def test_a_mark_inside_a_sentence_starts_at_its_words() -> None:
    (happy,) = emotion_marks("今天[happy]天气很好。我们去公园。")
    assert (happy.first, happy.last) == (2, 5)


@pytest.mark.parametrize(("text", "named"), [
    ("你好[joy]世界。", "line 1, column 3: unknown emotion 'joy'"),
    ("你好。\n世界[happy 1.5]。", "line 2, column 3: intensity '1.5'"),
    ("你好。\n[happy 很]世界。", "line 2, column 1: intensity '很'"),
    ("你好[happy世界。", "line 1, column 3: '[' without a closing ']'"),
    ("你好]世界。", "line 1, column 3: ']' without an opening '['"),
    ("你好[/sad]世界。", "line 1, column 3: closing mark [/sad] with no open mark"),
    ("你好[]世界。", "line 1, column 3: empty mark"),
    ("你好世界。[happy]", "line 1, column 6: the mark [happy] stands over no spoken syllable"),
])
def test_broken_markup_names_what_and_where(text: str, named: str) -> None:
    with pytest.raises(TranscriptError) as caught:
        emotion_marks(text, "story.txt")
    assert str(caught.value).startswith("story.txt: ") and named in str(caught.value)


def _alignment(count: int) -> Alignment:
    syllables = tuple(Syllable(text="啊", pinyin="a1", shapes=("a",), start=1 + 0.3 * i, end=1.3 + 0.3 * i,
                               confidence=1.0) for i in range(count))
    return Alignment(sentences=(Sentence("啊" * count, 1.0, 1 + 0.3 * count, syllables),), duration=10.0, notes=())


def test_marks_are_timed_by_their_syllables() -> None:
    (happy,) = emotion_marks("啊啊[happy]啊啊啊[/]啊。")
    assert marked_spans(_alignment(6), (happy,)) == (("happy", 1.0, 1.6, 2.5),)
    assert marked_spans(_alignment(4), (happy,)) is None  # an alignment of other text


def test_emotion_actions_ease_in_before_and_out_after_and_never_overlap_one_emotion() -> None:
    spans = [("happy", 1.0, 1.0, 2.0), ("happy", 0.6, 2.3, 3.0), ("fear", 1.0, 2.8, 3.5), ("sad", 0.5, 5.0, 6.0)]
    for default in (None, ("sad", 0.3), ("happy", 0.2)):
        actions = emotion_actions(spans, 10.0, default)
        assert all(a.kind == "emotion" and 0 <= a.start and a.end <= 10.0 + 1e-9 for a in actions)
        for name in {a.emotion for a in actions}:
            same = sorted((a for a in actions if a.emotion == name), key=lambda a: a.start)
            assert all(a.end <= b.start + 1e-9 for a, b in zip(same, same[1:])), (default, name)
        assert actions_from_json(actions_to_json(actions), "a.json", 10.0) == tuple(
            sorted(actions, key=lambda a: (a.start, a.kind, a.emotion)))
    happy = [a for a in emotion_actions(spans, 10.0) if a.emotion == "happy"]
    assert len(happy) == 1 and happy[0].amplitude == 1.0  # the two happy spans join
    assert happy[0].start == pytest.approx(0.6) and happy[0].start + happy[0].attack == pytest.approx(1.0)
    covered = emotion_actions((), 10.0, ("sad", 0.3))
    assert [(a.start, a.end, a.amplitude) for a in covered] == [(0.0, 10.0, 0.3)]


@pytest.mark.skipif(not shutil.which("espeak-ng"), reason="needs espeak-ng")
def test_generate_reads_the_markup_and_the_default_mood(tmp_path: Path) -> None:
    speech, _ = spoken_inputs(tmp_path, "今天天气很好。我们去公园。", speed=160)
    marked = tmp_path / "marked.txt"
    marked.write_text("今天天气很好。[surprise]我们去公园。", encoding="utf-8")
    result = generate(ROOT / "samples" / "faces" / "female.json", speech, marked, tmp_path / "out",
                      Options(fps=12, emotion="sad", intensity=0.4))
    actions = json.loads((result.out_dir / "actions.json").read_text(encoding="utf-8"))["actions"]
    moods = {(a["emotion"], a["amplitude"]) for a in actions if a["kind"] == "emotion"}
    assert moods == {("surprise", 1.0), ("sad", 0.4)}
    with pytest.raises(OptionError, match="emotion 'joy'"):
        generate(ROOT / "samples" / "faces" / "female.json", speech, marked, tmp_path / "bad", Options(emotion="joy"))
    with pytest.raises(TranscriptError, match="line 1, column 1"):
        generate(ROOT / "samples" / "faces" / "female.json", speech, "[joy]你好。", tmp_path / "bad", Options())
    assert not (tmp_path / "bad").exists()
