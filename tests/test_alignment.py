"""Reconciling transcript sentences with speaking parts, and analyse() from recording to timed syllables."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from cartoonface.errors import TranscriptError
from cartoonface.speech.analyse import FAST_RATE, MAX_PIECE, MAX_RATE, analyse, sentence_pieces
from cartoonface.speech.reconcile import reconcile
from cartoonface.speech.audio import Audio, load_audio
from cartoonface.speech.sentences import find_speech_parts
from cartoonface.speech.transcript import parse_transcript
from tests.conftest import speak
from tests.espeak import synthesize
from tests.synthetic import noisy, recording


def test_one_part_per_sentence_is_kept():
    samples, truth = recording([8, 12, 6], [0.7, 0.8])
    audio = noisy(samples)
    parts = find_speech_parts(audio)
    assert reconcile(audio, parts, [8, 12, 6]) == parts


def test_two_sentences_without_a_pause_are_split_at_the_short_pause():
    samples, truth = recording([9, 7, 10], [0.16, 0.9])
    audio = noisy(samples)
    parts = find_speech_parts(audio)
    assert len(parts) == 2  # the 0.16 s pause is too short to end a speaking part
    spans = reconcile(audio, parts, [9, 7, 10])
    assert len(spans) == 3
    assert truth[0].end - 0.05 <= spans[0].end == spans[1].start <= truth[1].start + 0.05  # cut inside part 1
    assert spans[1].end < spans[2].start  # the pause between the parts


def test_a_sentence_with_a_long_inner_pause_merges_two_parts():
    samples, truth = recording([6, 6, 10], [0.8, 0.9])
    audio = noisy(samples)
    parts = find_speech_parts(audio)
    assert len(parts) == 3
    spans = reconcile(audio, parts, [12, 10])
    assert len(spans) == 2
    assert spans[0].start == parts[0].start and spans[0].end == parts[1].end
    assert spans[1] == parts[2]
    alignment = analyse(audio, "我们今天一起去公园散步吧。天气非常好大家都很高兴。")  # 12 and 10 syllables
    assert [note for note in alignment.notes if "merged" in note] == [
        "sentence 1 «我们今天一起去公园散步吧。»: speaking parts 1-2 merged (the speaker paused 1 time(s) inside it)"
    ]


def test_more_sentences_than_dips_still_gives_every_sentence_time():
    samples, _ = recording([12], [])
    audio = noisy(samples)
    parts = find_speech_parts(audio)
    counts = [1, 2, 1, 3, 1, 2, 2]
    spans = reconcile(audio, parts, counts)
    assert len(spans) == len(counts)
    assert all(span.end > span.start for span in spans)
    assert all(a.end <= b.start for a, b in zip(spans, spans[1:]))


def test_long_sentences_are_cut_into_pieces_at_commas():
    clauses = ["我们今天一起去公园散步", "天气非常好", "大家都很高兴地唱歌跳舞"] * 8
    text = "，".join(clauses) + "。" + "短句。"
    parsed = parse_transcript(text, "long")
    pieces, owners = sentence_pieces(parsed)
    assert owners[-1] == 1 and owners.count(1) == 1 and set(owners[:-1]) == {0}
    assert all(len(piece.syllables) <= MAX_PIECE for piece in pieces)
    assert [s for piece in pieces[:-1] for s in piece.syllables] == list(parsed[0].syllables)
    ends = {end + 1 for end in parsed[0].clause_ends}
    position = 0
    for piece in pieces[:-2]:
        position += len(piece.syllables)
        assert position in ends  # cut at a comma


def test_a_long_unpunctuated_sentence_is_aligned_in_pieces():
    samples, truth = recording([150], [])
    text = "我们今天一起去公园散步天气非常好大家都很高兴" * 7  # 154 syllables, no punctuation
    alignment = analyse(noisy(samples), text)
    assert len(alignment.sentences) == 1
    syllables = alignment.sentences[0].syllables
    assert len(syllables) == 154
    assert all(a.start < a.end <= b.start + 1e-6 for a, b in zip(syllables, syllables[1:]))
    assert not any("split" in note for note in alignment.notes)


def test_empty_transcript_is_refused():
    samples, _ = recording([5], [])
    with pytest.raises(TranscriptError, match="story.txt: the transcript is empty"):
        analyse(noisy(samples), " \n\t", source="story.txt")


def test_transcript_far_longer_than_the_speech_is_refused():
    samples, _ = recording([6], [])  # about 1.5 s of speech
    text = "今天天气很好我们一起去公园散步吧。" * 3
    with pytest.raises(TranscriptError, match="story.txt: .* syllables to fit in .* is this the transcript"):
        analyse(noisy(samples), text, source="story.txt")


def test_transcript_too_long_for_a_natural_rate_is_aligned_but_flagged():
    audio = noisy(recording([8], [])[0])
    speech = sum(part.end - part.start for part in find_speech_parts(audio))
    syllables = round(speech * (FAST_RATE + MAX_RATE) / 2)  # between the usual and the refused rate
    text = "天" * syllables + "。"
    alignment = analyse(audio, text, source="story.txt")
    assert sum(len(s.syllables) for s in alignment.sentences) == syllables
    assert any("fast for Mandarin" in note for note in alignment.notes)
    assert not any("fast for Mandarin" in note for note in analyse(audio, "天" * 8 + "。").notes)


def test_transcript_in_another_language_is_refused():
    samples, _ = recording([8], [])
    with pytest.raises(TranscriptError, match="story.txt: the transcript looks like another language"):
        analyse(noisy(samples), "Good morning, how are you today?", source="story.txt", language="zh")


def test_a_few_latin_words_in_chinese_text_are_accepted():
    samples, _ = recording([8], [])
    alignment = analyse(noisy(samples), "我用iPhone和OK{ou1 kei1}上网。", source="story.txt")
    assert len(alignment.sentences) == 1


def espeak_audio(folder, texts: list[str], pauses: list[float]) -> tuple[Audio, list[float]]:
    """The `texts` read by espeak-ng one after another with `pauses` seconds between them; (audio, starts)."""
    pieces, starts, position = [], [], 0.0
    for index, text in enumerate(texts):
        path = folder / f"{index}.wav"
        speak(text, path)
        audio = load_audio(path)
        loud = np.flatnonzero(np.abs(audio.samples) > 0.01)
        speech = audio.samples[loud[0] : loud[-1] + 1]
        gap = np.zeros(int(pauses[index] * audio.rate) if index < len(pauses) else 0, np.float32)
        starts.append(position)
        position += (len(speech) + len(gap)) / audio.rate
        pieces += [speech, gap]
    return Audio(np.concatenate(pieces), audio.rate, "espeak"), starts


@pytest.mark.skipif(shutil.which("espeak-ng") is None, reason="espeak-ng is a Debian dependency (scripts/setup.sh)")
def test_sentences_run_together_are_split_where_the_aligner_puts_the_boundary(tmp_path):
    texts = ["我们今天去公园散步。", "天气非常好。", "大家都很高兴。"]
    audio, starts = espeak_audio(tmp_path, texts, [0.0, 0.9])
    parts = find_speech_parts(audio)
    assert len(parts) == 2  # the first two sentences are read without a pause
    alignment = analyse(audio, "".join(texts))
    assert len(alignment.sentences) == 3
    assert abs(alignment.sentences[1].start - starts[1]) < 0.15
    assert any("speaking part 1" in note and "split" in note and "sentences 1 and 2" in note for note in alignment.notes)


@pytest.mark.skipif(shutil.which("espeak-ng") is None, reason="espeak-ng is a Debian dependency (scripts/setup.sh)")
def test_analyse_espeak_speech(tmp_path):
    texts = ["你好，我是老师。", "今天天气很好。", "我们去公园吧！"]
    pieces = []
    for index, text in enumerate(texts):
        path = tmp_path / f"{index}.wav"
        speak(text, path)
        audio = load_audio(path)
        pieces += [audio.samples, np.zeros(int(0.8 * audio.rate), np.float32)]
    audio = Audio(np.concatenate(pieces), audio.rate, "espeak")
    stages = []
    alignment = analyse(audio, "".join(texts), progress=lambda stage, fraction: stages.append((stage, fraction)))
    expected = parse_transcript("".join(texts), "transcript")
    assert [s.text for s in alignment.sentences] == [s.text for s in expected]
    assert alignment.duration == audio.duration
    syllables = [s for sentence in alignment.sentences for s in sentence.syllables]
    assert [s.pinyin for s in syllables] == [s.pinyin for sentence in expected for s in sentence.syllables]
    assert all(a.end <= b.start + 1e-6 for a, b in zip(syllables, syllables[1:]))
    assert all(s.shapes and 0 <= s.confidence <= 1 for s in syllables)
    parts = find_speech_parts(audio)
    assert len(parts) == len(texts)
    for sentence in alignment.sentences:  # no sentence crosses a pause between speaking parts
        assert any(p.start - 1e-6 <= sentence.start < sentence.end <= p.end + 1e-6 for p in parts)
    assert stages[0] == ("segment", 0.0) and stages[-1] == ("align", 1.0)


def paused_speech(chunks: list[str], pause: float) -> tuple[Audio, list[float]] | None:
    """Each of `chunks` (Hanzi, no punctuation) read by espeak-ng, its own syllables' readings,
    with `pause` seconds of faint noise between chunks; (audio, true onset of every syllable)
    or None when espeak-ng cannot read them syllable by syllable."""
    pieces, onsets, position, rate = [], [], 0.0, 0
    rng = np.random.default_rng(0)
    for chunk in chunks:
        pinyin = [s.pinyin for sentence in parse_transcript(chunk) for s in sentence.syllables]
        speech = synthesize(pinyin)
        if speech is None:
            return None
        rate = speech.rate
        onsets += [position + t for t in speech.onsets]
        gap = np.zeros(int(pause * rate), np.float32)
        pieces += [speech.samples, gap]
        position += (speech.samples.size + gap.size) / rate
    samples = np.concatenate(pieces)
    samples = samples + (1e-3 * rng.standard_normal(samples.size)).astype(np.float32)
    return Audio(samples, rate, "espeak"), onsets


@pytest.mark.skipif(shutil.which("espeak-ng") is None, reason="espeak-ng is a Debian dependency (scripts/setup.sh)")
def test_pauses_in_a_long_unpunctuated_sentence_land_between_the_right_syllables():
    # 79 syllables > MAX_PIECE: the sentence is cut into pieces by count (at 40), while the
    # reader paused before syllables 20, 39 and 59 (inside words, too)
    chunks = ["我们今天一起去公园散步天气非常好大家都很", "高兴地唱歌跳舞小朋友在草地上跑来跑去老", "师站在树下看着他们笑了起来时间过得很快转",
              "眼太阳就要下山了我们收拾好东西准备回家去"]
    made = paused_speech(chunks, 0.5)
    if made is None:
        pytest.skip("espeak-ng does not read these syllables one by one")
    audio, truth = made
    alignment = analyse(audio, "".join(chunks))
    syllables = [s for sentence in alignment.sentences for s in sentence.syllables]
    assert len(syllables) == len(truth) > MAX_PIECE
    after_pauses = [20, 39, 59]
    errors = [abs(syllables[k].start - truth[k]) for k in after_pauses]
    assert max(errors) < 0.1, errors
