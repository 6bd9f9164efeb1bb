"""Lip sync from the audio alone (speech/audio_only.py): records, pages without text, CLI and web."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import soundfile

from cartoonface.animate.timeline import REST, mouth_keys
from cartoonface.speech.analyse import analyse
from cartoonface.speech.audio import Audio, load_audio
from cartoonface.speech.audio_only import AUDIO_ONLY_NOTE, MOUTH_CLASSES, UNTRANSCRIBED, transcribed
from cartoonface.speech.sentences import find_speech_parts
from cartoonface.speech.textgrid import load_textgrid
from cartoonface.web.store import DONE
from tests.conftest import ROOT, form, post, run_cli
from tests.conftest import wait_done

STORY = ROOT / "samples" / "speech" / "story.wav"
FACE = ROOT / "samples" / "faces" / "female.json"
STEP = 0.01  # s between the instants the mouth is looked at
WEB_SECONDS = 6.3  # the first two sentences of the story (to its second pause)


@pytest.fixture(scope="module")
def story() -> Audio:
    return load_audio(STORY)


@pytest.fixture(scope="module")
def alignment(story):
    return analyse(story, None)


def shown(alignment, times: np.ndarray) -> list[str]:
    """The mouth shape of the key frame in force at each of `times` (s)."""
    syllables = [s for sentence in alignment.sentences for s in sentence.syllables]
    keys = mouth_keys(syllables, round(alignment.duration * 1000))
    at = np.array([key.t for key in keys])
    return [keys[i].value for i in np.searchsorted(at, times * 1000, side="right") - 1]


def test_sentences_are_the_speaking_parts_without_text(story, alignment):
    parts = find_speech_parts(story)
    assert not transcribed(alignment)
    assert AUDIO_ONLY_NOTE in alignment.notes
    assert len(alignment.sentences) == len(parts)
    for sentence, part in zip(alignment.sentences, parts):
        assert sentence.text == UNTRANSCRIBED
        assert part.start <= sentence.start < sentence.end <= part.end + STEP
        for syllable in sentence.syllables:
            assert sentence.start <= syllable.start < syllable.end <= sentence.end
            assert set(syllable.shapes) <= set(MOUTH_CLASSES)


def test_syllable_rate_is_that_of_speech(story, alignment):
    speech = sum(part.duration for part in find_speech_parts(story))
    count = sum(len(sentence.syllables) for sentence in alignment.sentences)
    assert 2.0 <= count / speech <= 9.0  # Mandarin is read at 3-7 syllables per second


def test_mouth_is_open_in_speech_and_closed_in_pauses(story, alignment):
    parts = find_speech_parts(story)
    pauses = [(a.end + 0.1, b.start - 0.1) for a, b in zip(parts, parts[1:]) if b.start - a.end > 0.25]
    assert pauses
    for start, end in pauses:
        assert set(shown(alignment, np.arange(start, end, STEP))) == {REST}
    nuclei = np.array([(s.start + s.end) / 2 for sentence in alignment.sentences for s in sentence.syllables])
    opened = [MOUTH_CLASSES[shape] != "closed" for shape in shown(alignment, nuclei)]
    assert np.mean(opened) >= 0.9
    speaking = np.concatenate([np.arange(p.start + 0.1, p.end - 0.1, STEP) for p in parts])
    assert np.mean([MOUTH_CLASSES[shape] != "closed" for shape in shown(alignment, speaking)]) >= 0.6


def test_vowel_classes_vary_over_the_story(alignment):
    labels = {s.pinyin for sentence in alignment.sentences for s in sentence.syllables}
    assert {"open", "rounded", "spread"} <= labels


def test_silence_gives_no_sentences_and_says_so():
    rate = 16000
    noise = np.random.default_rng(1).normal(0.0, 1e-4, rate * 2).astype(np.float32)
    alignment = analyse(Audio(noise, rate, "quiet.wav"), None)
    assert alignment.sentences == ()
    assert any("no speech" in note for note in alignment.notes)


def test_an_explicit_empty_transcript_is_still_refused(story):
    from cartoonface.errors import TranscriptError

    with pytest.raises(TranscriptError, match="the transcript is empty"):
        analyse(story, "  ")


def test_cli_align_without_transcript_writes_a_textgrid_that_reads_back(tmp_path):
    out = tmp_path / "story.TextGrid"
    done = run_cli("align", str(STORY), "-o", str(out))
    assert done.returncode == 0, done.stderr
    assert "audio alone" in done.stderr
    again = load_textgrid(out)
    assert again.sentences and all(sentence.text == UNTRANSCRIBED for sentence in again.sentences)


def text_panel(html: str) -> bool:
    return 'aria-label="text"' in html or "cf-sentence" in html


def test_cli_generate_without_transcript_makes_a_page_without_text(tmp_path):
    out = tmp_path / "site"
    done = run_cli("generate", "--face", str(FACE), "--audio", str(STORY), "-o", str(out), "--page", "announcer")
    assert done.returncode == 0, done.stderr
    html = (out / "index.html").read_text(encoding="utf-8")
    assert 'id="cf-face"' in html and "<audio" in html
    assert not text_panel(html)
    assert UNTRANSCRIBED in (out / "alignment.TextGrid").read_text(encoding="utf-8")


def test_web_form_with_an_empty_transcript_makes_a_page_without_text(app, sample_name, story, tmp_path):
    clip = tmp_path / "clip.wav"  # the first sentences: the test app takes at most 1 MB
    soundfile.write(clip, story.samples[: int(WEB_SECONDS * story.rate)], story.rate)
    client = app.test_client()
    response = post(client, form(client, clip.read_bytes(), sample_name, transcript=" "))
    assert response.status_code == 303, response.get_data(as_text=True)
    url = response.headers["Location"]
    assert wait_done(client, url)[-1]["state"] == DONE
    html = client.get(f"{url}/site/index.html").get_data(as_text=True)
    assert 'id="cf-face"' in html and not text_panel(html)


@pytest.fixture(scope="module")
def sample_name() -> str:
    return sorted(Path(ROOT / "samples" / "faces").glob("*.json"))[0].stem
