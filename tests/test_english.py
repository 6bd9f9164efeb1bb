"""English speech: language from the script, pocketsphinx word and phone times, mouth shapes of
seed 000 Table 1, the TextGrid's words and phones tiers, and the CLI's --language."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from cartoonface.animate.frames import sample_frames
from cartoonface.animate.timeline import build_timeline
from cartoonface.errors import TranscriptError
from cartoonface.speech.analyse import analyse
from cartoonface.speech.audio import load_audio
from cartoonface.speech.english import (
    PHONE_SHAPE, VOWELS, WORD_RE, detect_language, letters_to_sounds, new_decoder, parse_english,
)
from cartoonface.speech.textgrid import read_textgrid, read_tiers, write_textgrid
from tests.conftest import run_cli

pytestmark = pytest.mark.skipif(not shutil.which("espeak-ng"), reason="needs espeak-ng")

ROOT = Path(__file__).resolve().parent.parent
FACE = ROOT / "samples" / "faces" / "female.json"
TEXT = "Bob made a map of the moon. Mom baked apple pie."
BILABIALS = ("B", "M", "P")
FPS = 60  # frames sampled finely enough to see each phone (about 60-180 ms here)


@pytest.fixture(scope="module")
def english(tmp_path_factory) -> tuple[Path, Path]:
    """TEXT read by espeak-ng's American English voice, and the transcript file."""
    folder = tmp_path_factory.mktemp("english")
    speech, transcript = folder / "speech.wav", folder / "text.txt"
    subprocess.run(["espeak-ng", "-v", "en-us", "-w", str(speech), TEXT], check=True)
    transcript.write_text(TEXT + "\n", encoding="utf-8")
    return speech, transcript


@pytest.fixture(scope="module")
def aligned(english):
    speech, _ = english
    audio = load_audio(speech)
    return audio, analyse(audio, TEXT)


def test_language_is_found_from_the_script():
    assert detect_language(TEXT) == "en"
    assert detect_language("我去銀行。今天天氣很好。") == "zh"
    # A Mandarin text with a few Latin words, and readings in braces, stays Mandarin.
    assert detect_language("我用OK{ou1 kei1}和iPhone打電話。") == "zh"


def test_every_dictionary_phone_has_a_mouth_shape():
    from pocketsphinx import get_model_path

    dictionary = Path(get_model_path()) / "en-us" / "cmudict-en-us.dict"
    phones = {phone for line in dictionary.read_text(encoding="utf-8").splitlines() for phone in line.split()[1:]}
    assert len(phones) > 30
    assert phones <= set(PHONE_SHAPE)


def test_words_outside_the_dictionary_are_read_from_their_letters():
    decoder = new_decoder()
    made_up = ["zorblax", "plimbow", "quextrin"]
    assert all(not decoder.lookup_word(word) for word in made_up)
    (sentence,) = parse_english(" ".join(made_up) + ".", decoder, "test")
    for word in sentence.words:
        assert word.phones and set(word.phones) <= set(PHONE_SHAPE)
        assert any(p in VOWELS for p in word.phones)
        # Letters for lip closures give a lip closure.
        assert any(p in BILABIALS for p in word.phones) == bool(set("bmp") & set(word.spelling))
        assert decoder.lookup_word(word.spelling)  # added, so pocketsphinx can align it
    assert letters_to_sounds("") == ()


def test_words_and_phones_are_timed_in_order_inside_the_recording(aligned):
    audio, alignment = aligned
    assert [s.text for s in alignment.sentences] == ["Bob made a map of the moon.", "Mom baked apple pie."]
    assert alignment.sentences[0].end <= alignment.sentences[1].start
    records = [s for sentence in alignment.sentences for s in sentence.syllables]
    assert [s.text for s in records if s.text] == WORD_RE.findall(TEXT)
    assert all(0 <= s.start < s.end <= audio.duration + 1e-3 for s in records)
    assert all(a.end <= b.start + 1e-3 for a, b in zip(records, records[1:]))
    assert all(s.pinyin in PHONE_SHAPE for s in records)
    assert not alignment.notes  # aligned, not spread evenly


def test_the_mouth_follows_the_phones(aligned):
    audio, alignment = aligned
    records = [s for sentence in alignment.sentences for s in sentence.syllables]
    states = sample_frames(build_timeline(alignment, ()), FPS)

    def shown(record):
        """The strongest mouth shape in the frame nearest the middle of the phone."""
        state = states[round((record.start + record.end) / 2 * FPS)]
        return max(state.mouth, key=lambda pair: pair[1])[0]

    closures = [s for s in records if s.pinyin in BILABIALS]
    vowels = [s for s in records if s.pinyin in VOWELS]
    assert len(closures) >= 8 and len(vowels) >= 10
    assert all(shown(s) == "m" for s in closures)
    assert all(shown(s) in ("a", "e", "i", "o", "u") for s in vowels)
    assert all(shown(s) == PHONE_SHAPE[s.pinyin] for s in vowels)


def test_textgrid_has_words_and_phones_and_reads_back(aligned):
    _, alignment = aligned
    text = write_textgrid(alignment)
    _, tiers = read_tiers(text, "test")
    assert list(tiers) == ["sentences", "words", "phones", "mouth shapes"]
    assert [i.text for i in tiers["words"] if i.text] == WORD_RE.findall(TEXT)
    records = [s for sentence in alignment.sentences for s in sentence.syllables]
    assert [i.text for i in tiers["phones"] if i.text] == [s.pinyin for s in records]
    assert read_textgrid(text, "test").sentences == alignment.sentences


def test_generate_makes_an_english_page(english, tmp_path):
    speech, transcript = english
    out = tmp_path / "site"
    done = run_cli("generate", "--face", FACE, "--audio", speech, "--transcript", transcript, "-o", out, "--fps", "12")
    assert done.returncode == 0, done.stderr
    grid = (out / "alignment.TextGrid").read_text(encoding="utf-8")
    assert '"words"' in grid and '"phones"' in grid
    assert "Mom baked apple pie." in (out / "index.html").read_text(encoding="utf-8")


@pytest.mark.parametrize("case", ["language fr", "forced zh", "digits"])
def test_bad_english_input_exits_2_with_a_message(case, english, tmp_path):
    speech, transcript = english
    extra: list[str] = []
    if case == "language fr":
        extra = ["--language", "fr"]
    elif case == "forced zh":
        extra = ["--language", "zh"]
    else:
        transcript = tmp_path / "digits.txt"
        transcript.write_text("Bob made 42 maps.", encoding="utf-8")
    done = run_cli("align", speech, "--transcript", transcript, "-o", tmp_path / "out.TextGrid", *extra)
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    expected = {"language fr": "invalid choice: 'fr'", "forced zh": "looks like another language",
                "digits": "the number '42'"}[case]
    assert expected in done.stderr
    assert not (tmp_path / "out.TextGrid").exists()


def test_digits_are_refused_before_aligning():
    with pytest.raises(TranscriptError, match=re.escape("story.txt: the number '7'")):
        parse_english("Seven is 7.", new_decoder(), "story.txt")


def test_a_transcript_far_longer_than_the_speech_is_refused(aligned):
    audio, _ = aligned
    with pytest.raises(TranscriptError, match="story.txt: .* syllables to fit in"):
        analyse(audio, " ".join([TEXT] * 12), source="story.txt")


def test_align_counts_english_words_and_phones(english, tmp_path):
    speech, transcript = english
    done = run_cli("align", speech, "--transcript", transcript, "-o", tmp_path / "out.TextGrid")
    assert done.returncode == 0, done.stderr
    alignment = read_textgrid((tmp_path / "out.TextGrid").read_text(encoding="utf-8"), "out")
    phones = sum(len(sentence.syllables) for sentence in alignment.sentences)
    assert f"2 sentences, {len(WORD_RE.findall(TEXT))} words, {phones} phones" in done.stdout


def test_a_word_without_any_sound_is_refused_by_name():
    with pytest.raises(TranscriptError, match="story.txt: line 1, column 11: the word 'Gh' has no pronunciation"):
        parse_english("Bob said. Gh.", new_decoder(), "story.txt")


@pytest.mark.parametrize("word, ending", [
    ("jumped", ("P", "T")), ("named", ("M", "D")), ("wanted", ("IH", "D")), ("cats", ("T", "S")),
    ("dogs", ("G", "Z")), ("boxes", ("IH", "Z")), ("nation", ("SH", "AH", "N")),
])
def test_letter_to_sound_reads_suffixes_by_the_stem(word, ending):
    assert letters_to_sounds(word)[-len(ending):] == ending


@pytest.mark.parametrize("word, vowel", [("make", "EY"), ("time", "AY"), ("home", "OW"), ("mat", "AE"), ("tim", "IH")])
def test_a_silent_final_e_makes_the_vowel_long(word, vowel):
    phones = letters_to_sounds(word)
    assert [p for p in phones if p in VOWELS] == [vowel]


def test_accents_are_dropped_and_other_letters_refused_naming_word_line_and_column():
    decoder = new_decoder()
    (sentence,) = parse_english("A café.", decoder, "t")
    assert [w.spelling for w in sentence.words] == ["a", "cafe"]
    assert sentence.words[1].text == "café"
    with pytest.raises(TranscriptError, match=r"story.txt: line 2, column 11: the word 'Straße'.*'ß'"):
        parse_english("Hello there.\n[happy] A Straße.", decoder, "story.txt")
