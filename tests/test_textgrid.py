"""Praat TextGrid write/read: exact round trip, Praat's short format, and errors naming line and tier."""

from __future__ import annotations

import re

import pytest

from cartoonface.errors import AlignmentError
from cartoonface.speech.records import Alignment, Sentence, Syllable
from cartoonface.speech.mouth_shapes import shape_onsets, shapes_for
from cartoonface.speech.textgrid import TIERS, load_textgrid, read_textgrid, write_textgrid


def syllable(text: str, pinyin: str, start: float, end: float) -> Syllable:
    return Syllable(text, pinyin, shapes_for(pinyin), start, end, 0.8)


def sample() -> Alignment:
    first = (
        syllable("你", "ni3", 0.3127, 0.5551),
        syllable("好", "hao3", 0.5551, 0.8123),
    )
    second = (
        syllable("说", "shuo1", 1.5009, 1.7001),
        syllable("话", "hua4", 1.7301, 1.9),
        syllable("了", "le5", 1.9, 2.25),
    )
    sentences = (
        Sentence("你好。", 0.3127, 0.8123, first),
        Sentence('说"话了"', 1.5009, 2.25, second),
    )
    return Alignment(sentences, 3.0, ("a note",))


@pytest.fixture()
def alignment() -> Alignment:
    return sample()


def assert_same_timing(read: Alignment, original: Alignment) -> None:
    assert len(read.sentences) == len(original.sentences)
    for got, want in zip(read.sentences, original.sentences, strict=True):
        assert got.text == want.text
        assert round(got.start, 3) == round(want.start, 3) and round(got.end, 3) == round(want.end, 3)
        assert [(s.text, s.pinyin, s.shapes) for s in got.syllables] == [
            (s.text, s.pinyin, s.shapes) for s in want.syllables
        ]
        for a, b in zip(got.syllables, want.syllables, strict=True):
            assert round(a.start, 3) == round(b.start, 3) and round(a.end, 3) == round(b.end, 3)


def move_first_syllable(text: str) -> str:
    """Move the first syllable's start (and the empty interval before it) to 0.1 s, before its sentence."""
    head, tier = text.split('name = "syllables"')
    tier = tier.replace("xmax = 0.3127 ", "xmax = 0.1 ", 1).replace("xmin = 0.3127 ", "xmin = 0.1 ", 1)
    return head + 'name = "syllables"' + tier


def test_round_trip_is_exact_to_the_millisecond(alignment):
    text = write_textgrid(alignment)
    read = read_textgrid(text, "edited.TextGrid")
    assert read.duration == alignment.duration
    assert_same_timing(read, alignment)
    assert all(s.confidence == 1.0 for sentence in read.sentences for s in sentence.syllables)
    assert write_textgrid(read) == text


def test_long_format_has_three_contiguous_tiers(alignment):
    text = write_textgrid(alignment)
    assert text.startswith('File type = "ooTextFile"\nObject class = "TextGrid"\n')
    names = re.findall(r'name = "([^"]*)"', text)
    assert tuple(names) == TIERS
    for block in text.split("item [")[2:]:
        times = [float(v) for v in re.findall(r"x(?:min|max) = ([\d.]+)", block)[2:]]
        starts, ends = times[::2], times[1::2]
        assert starts[0] == 0 and ends[-1] == alignment.duration
        assert all(a == b for a, b in zip(ends, starts[1:]))


def test_mouth_shape_tier_follows_in_syllable_onsets(alignment):
    text = write_textgrid(alignment)
    tier = text.split('name = "mouth shapes"')[1]
    intervals = re.findall(r'xmin = ([\d.]+) \n\s+xmax = ([\d.]+) \n\s+text = "([^"]*)"', tier)
    labelled = [(float(a), float(b), t) for a, b, t in intervals if t]
    expected = []
    for sentence in alignment.sentences:
        for s in sentence.syllables:
            onsets = shape_onsets(len(s.shapes))
            for k, shape in enumerate(s.shapes):
                start = s.start + onsets[k] * (s.end - s.start)
                end = s.start + onsets[k + 1] * (s.end - s.start) if k + 1 < len(s.shapes) else s.end
                expected.append((round(start, 6), round(end, 6), shape))
    assert [(round(a, 6), round(b, 6), t) for a, b, t in labelled] == expected


def test_reads_praat_short_format(alignment):
    long_text = write_textgrid(alignment)
    values = re.findall(r'"(?:[^"]|"")*"|<exists>|(?<=[=\s])-?\d+(?:\.\d+)?(?=\s*\n)', long_text)
    short = '"ooTextFile"\n"TextGrid"\n' + "\n".join(values[2:]) + "\n"
    assert "xmin" not in short
    assert_same_timing(read_textgrid(short, "short.TextGrid"), alignment)


def test_edited_boundary_and_label_are_read(alignment):
    text = write_textgrid(alignment).replace("xmax = 0.5551 ", "xmax = 0.6 ", 1)
    text = text.replace("xmin = 0.5551 ", "xmin = 0.6 ", 1)
    text = text.replace('"好 hao3"', '"号 hao4"')
    read = read_textgrid(text, "edited.TextGrid")
    first, second = read.sentences[0].syllables
    assert first.end == 0.6 and second.start == 0.6
    assert (second.text, second.pinyin) == ("号", "hao4")


def test_without_mouth_tier_shapes_come_from_pinyin(alignment):
    text = write_textgrid(alignment)
    cut = text.split("    item [3]:")[0].replace("size = 3 ", "size = 2 ", 1)
    read = read_textgrid(cut, "two-tiers.TextGrid")
    assert read.sentences[0].syllables[1].shapes == shapes_for("hao3")


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda t: t.replace('"ooTextFile"', '"something"'), r"line 1: expected \"ooTextFile\""),
        (lambda t: t.replace('name = "syllables"', 'name = "words"'), "no interval tier named 'syllables'"),
        (
            lambda t: t.replace("xmax = 0.8123 ", "xmax = oops ", 1),
            r"line \d+: expected xmax of interval 2 of tier sentences",
        ),
        (lambda t: t.replace("xmin = 1.5009 ", "xmin = 2.9 ", 1), r"line \d+: tier sentences, interval 4"),
        (lambda t: t.replace('text = "u"', 'text = "q"', 1), "tier mouth shapes, label 'q'"),
        (lambda t: t[: len(t) // 2], "ends early"),
        (move_first_syllable, "'你 ni3' .* outside every interval of tier sentences"),
    ],
)
def test_malformed_textgrid_names_line_or_tier(alignment, edit, message):
    with pytest.raises(AlignmentError, match=message) as caught:
        read_textgrid(edit(write_textgrid(alignment)), "bad.TextGrid")
    assert "bad.TextGrid" in str(caught.value)


def test_not_a_textgrid():
    with pytest.raises(AlignmentError, match=r"notes.txt, line 1: expected \"ooTextFile\""):
        read_textgrid('"hello" world\n', "notes.txt")
    with pytest.raises(AlignmentError, match="empty.TextGrid: the TextGrid ends early"):
        read_textgrid("", "empty.TextGrid")


@pytest.mark.parametrize("encoding", ["utf-8", "utf-8-sig", "utf-16"])
def test_load_textgrid_in_the_encodings_praat_writes(alignment, tmp_path, encoding):
    path = tmp_path / "saved.TextGrid"
    path.write_bytes(write_textgrid(alignment).encode(encoding))
    assert_same_timing(load_textgrid(path), alignment)


def test_load_textgrid_errors(tmp_path):
    with pytest.raises(AlignmentError, match="missing.TextGrid: no such TextGrid file"):
        load_textgrid(tmp_path / "missing.TextGrid")
    binary = tmp_path / "binary.TextGrid"
    binary.write_bytes(bytes(range(256)))
    with pytest.raises(AlignmentError, match="binary.TextGrid: not a text file"):
        load_textgrid(binary)
