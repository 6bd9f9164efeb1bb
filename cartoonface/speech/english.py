"""English speech: transcript -> sentences and words, word and phone times with pocketsphinx, mouth shapes.

`analyse_english` does for English what `analyse.analyse` does for Mandarin: it
splits the recording into speaking parts (`sentences.py`), lays the sentences over
them (`reconcile.py`), then aligns the words of each run of touching sentences
with pocketsphinx 5 (its en-us acoustic model and CMU dictionary ship inside the
wheel; nothing is downloaded): a first pass gives word times, a second pass
(`set_alignment`) the phone times. Each phone becomes one `Syllable` record whose
`pinyin` is the ARPAbet phone, `text` the word on its first phone ("" on the
others), and `shapes` the one mouth shape of seed 000 Table 1 (PHONE_SHAPE), so
the key-frame timing downstream (animate/timeline.py) is the Mandarin one.
Words outside the dictionary get a pronunciation from a letter-to-sound rule
table (`letters_to_sounds`). docs/english.md has the details.
"""

from __future__ import annotations

import re
import unicodedata
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from cartoonface.errors import TranscriptError
from cartoonface.speech.audio import Audio
from cartoonface.speech.dsp import resample_poly
from cartoonface.speech.reconcile import reconcile
from cartoonface.speech.records import Alignment, Sentence, Syllable
from cartoonface.speech.sentences import Span, find_speech_parts, high_passed
from cartoonface.speech.stretches import FALLBACK_CONFIDENCE
from cartoonface.speech.readings import HAN_RE, position_of

LANGUAGES = ("zh", "en")
RATE = 16000  # Hz: the sample rate of pocketsphinx's en-us acoustic model
FRAME = 0.01  # seconds per pocketsphinx frame (its default frate 100)
PCM_SCALE = 32767  # float samples -1..1 -> 16-bit PCM
# Search beam of the second try when the default beams find no alignment: synthetic speech
# (espeak-ng) lies so far from the acoustic model that every path is pruned (1e-60 and 1e-80
# were not enough for the test sentence of tests/test_english.py).
WIDE_BEAM = 1e-200
# English is read at about 3-7 syllables (vowel phones) per second of speech, as Mandarin: more than
# MAX_RATE (analyse.MAX_RATE) means the transcript is far longer than the recording.
MAX_RATE = 12.0
# pocketsphinx gives no calibrated confidence: phones it aligned get this one; phones spread
# evenly after a failed alignment get stretches.FALLBACK_CONFIDENCE.
ALIGNED_CONFIDENCE = 1.0

# Seed 000 Table 1 ("Conversion table from phoneme to mouth shape"): the 14 visemes and the
# phonemes of each, in the ARPAbet of pocketsphinx's dictionary. Phonemes of the dictionary
# that the table does not name are put with the nearest one: AH (= AX) and AW with 1, AO
# (/ɔ/, listed with OY) with 4, EH with 5 (as EY), DH with 14 (as TH), ZH with 3 (as SH).
# Table 1 puts SIL in viseme 1; here silence is the rest mouth of the timeline instead.
VISEME_PHONES: dict[int, tuple[str, ...]] = {
    1: ("AA", "AE", "AH", "AW", "HH", "Y"),
    2: ("B", "M", "P"),
    3: ("CH", "JH", "SH", "ZH"),
    4: ("UW", "OY", "W", "UH", "AO"),
    5: ("AY", "EY", "ER", "EH"),
    6: ("F", "V"),
    7: ("IH", "IY"),
    8: ("G", "K"),
    9: ("N", "NG"),
    10: ("OW",),
    11: ("R",),
    12: ("S", "Z"),
    13: ("D", "L", "T"),
    14: ("TH", "DH"),
}
# Each viseme of Table 1 drawn with the nearest of the model's twelve shapes (thesis 002, 5.2.2;
# face/mouth.py): open a, rounded u and o, spread i, mid e, closed m, lip-under-teeth f, rounded
# sibilant r (for /ʃ/ and /r/), teeth-closed z, the velar h, the wide-cornered n, and h' for the
# tongue-tip consonants /d l t/ and /θ/. docs/english.md gives the reasons.
VISEME_SHAPE: dict[int, str] = {
    1: "a", 2: "m", 3: "r", 4: "u", 5: "e", 6: "f", 7: "i", 8: "h", 9: "n", 10: "o", 11: "r", 12: "z",
    13: "h'", 14: "h'",
}
PHONE_SHAPE: dict[str, str] = {phone: VISEME_SHAPE[v] for v, phones in VISEME_PHONES.items() for phone in phones}
# A phone's record holds its shape HELD times: the timeline (animate/timeline.py) then puts keys at
# the phone's start and at 81 % of it (thesis 002, 5.3, two shapes), so the shape is held through
# the phone and blends into the next in its last part, instead of only being reached at its start.
HELD = 2
VOWELS = frozenset({"AA", "AE", "AH", "AO", "AW", "AY", "EH", "ER", "EY", "IH", "IY", "OW", "OY", "UH", "UW"})

# Letter-to-sound fallback for words outside the dictionary: letter groups tried longest
# first at each position (our rules, a crude reading of English spelling; docs/english.md).
SPELLING: dict[str, str] = {
    "tch": "CH", "sch": "S K", "igh": "AY", "ough": "OW",
    "nk": "NG K", "kn": "N", "wr": "R", "oe": "OW", "ew": "UW", "oa": "OW", "ue": "UW",
    "ch": "CH", "sh": "SH", "th": "TH", "ph": "F", "wh": "W", "ck": "K", "ng": "NG", "qu": "K W", "gh": "",
    "ee": "IY", "ea": "IY", "oo": "UW", "ou": "AW", "ow": "OW", "oi": "OY", "oy": "OY", "ai": "EY", "ay": "EY",
    "au": "AO", "aw": "AO", "ei": "EY", "ey": "IY", "ie": "IY", "er": "ER", "ir": "ER", "ur": "ER",
    "ar": "AA R", "or": "AO R",
    "a": "AE", "b": "B", "c": "K", "d": "D", "e": "EH", "f": "F", "g": "G", "h": "HH", "i": "IH", "j": "JH",
    "k": "K", "l": "L", "m": "M", "n": "N", "o": "AA", "p": "P", "q": "K", "r": "R", "s": "S", "t": "T",
    "u": "AH", "v": "V", "w": "W", "x": "K S", "y": "IY", "z": "Z",
}
_LONGEST = max(len(group) for group in SPELLING)
# Letter-to-sound rules before the letter groups (ours; each kept because it lowered the phone
# error on the tuning half of bench/english.py's sample, docs/BENCHMARKS.md). Suffixes read after
# their stem ("S"/"D": voiced or not by the stem's last sound, _suffix_phones).
SUFFIXES = {"ing": "IH NG", "ly": "L IY", "es": "S", "ed": "D", "s": "S"}
_KEEP_S = ("s", "u", "i")  # -ss, -us, -is are not plurals
_SIBILANTS = frozenset({"S", "Z", "SH", "ZH", "CH", "JH"})
_VOICELESS = frozenset({"P", "T", "K", "F", "TH", "S", "SH", "CH"})
_VOWEL_LETTERS = frozenset("aeiouy")
# A vowel letter before one consonant and a final silent e is long (make, time, home, tune).
_MAGIC_E_RE = re.compile(r"(?<![aeiou])([aeiou])([bcdfgklmnprstvz])e$")
LONG_VOWEL = {"a": "EY", "e": "IY", "i": "AY", "o": "OW", "u": "UW"}
# Word endings of words with a vowel letter before them (or alone: a final o, a).
ENDINGS = {"tion": "SH AH N", "sion": "ZH AH N", "ture": "CH ER", "ous": "AH S", "ism": "IH Z AH M",
           "ier": "IY ER", "ian": "IY AH N", "ity": "AH T IY", "ia": "IY AH", "lle": "L", "or": "ER", "le": "AH L",
           "al": "AH L", "el": "AH L", "en": "AH N", "on": "AH N", "an": "AH N", "o": "OW",
           "a": "AH"}
SOFT = {"c": "S"}  # before e, i, y (a soft g too made the tuning half worse: get, give, girl)
# Words: runs of Latin letters (ASCII, Latin-1 and Latin Extended-A/B: café, Straße) with inner
# apostrophes; accents are dropped for the dictionary (english_letters), other letters refused.
LETTERS = "A-Za-z\u00c0-\u00d6\u00d8-\u00f6\u00f8-\u024f"
WORD_RE = re.compile(rf"[{LETTERS}]+(?:'[{LETTERS}]+)*")
SPELLING_RE = re.compile(r"[a-z]+(?:'[a-z]+)*")
SENTENCE_END_RE = re.compile(r"(?<=[.!?;])\s+|\n\s*\n")
MARK_RE = re.compile(r"\[[^\]\n]*\]")  # emotion marks (transcript.py); the pipeline reads them
LATIN_RE = re.compile(r"[A-Za-z]+")
FILLERS = frozenset({"<sil>", "<s>", "</s>"})  # the aligner's silences, not words of the transcript


@dataclass(frozen=True)
class Word:
    """One word to align: `text` as written, `spelling` (lower case, the dictionary key) and its ARPAbet `phones`."""

    text: str
    spelling: str
    phones: tuple[str, ...]


@dataclass(frozen=True)
class EnglishSentence:
    """One sentence of an English transcript: its `text` as written and its words."""

    text: str
    words: tuple[Word, ...]


def phone_shapes(phone: str) -> tuple[str, ...]:
    """The shapes of the record of an ARPAbet `phone`: its Table 1 shape HELD times."""
    return (PHONE_SHAPE[phone],) * HELD


def detect_language(text: str) -> str:
    """'en' when `text` has more Latin words than Chinese characters (readings in braces not
    counted), else 'zh'."""
    plain = re.sub(r"\{[^}]*\}", "", text)
    return "en" if len(LATIN_RE.findall(plain)) > len(HAN_RE.findall(plain)) else "zh"


def split_sentences(text: str) -> list[str]:
    """The sentences of an English transcript (without emotion marks): cut after . ! ? ; or at a
    blank line; those without words are dropped."""
    plain = MARK_RE.sub(" ", text)
    parts = (" ".join(part.split()) for part in SENTENCE_END_RE.split(plain))
    return [part for part in parts if WORD_RE.search(part)]


def letters_to_sounds(spelling: str) -> tuple[str, ...]:
    """ARPAbet phones for a lower-case word by our spelling rules (docs/english.md): the
    suffixes -s -es -ed -ing -ly read after the stem (SUFFIXES, -s and -ed voiced after a voiced
    sound), a long vowel before consonant + silent final e (LONG_VOWEL), word endings
    (ENDINGS), c soft before e i y, y as Y or IH by its neighbours, then the SPELLING letter
    groups longest first (doubled letters read once). Empty when no letter is known."""
    return tuple(_read(spelling.replace("'", "")))


def _read(word: str) -> list[str]:
    """The phones of `word` (lower case, letters only) by the rules of letters_to_sounds."""
    for suffix, ending in SUFFIXES.items():
        stem = word[: -len(suffix)]
        if word.endswith(suffix) and len(stem) > 2 and _VOWEL_LETTERS & set(stem) and not stem.endswith(_KEEP_S):
            if suffix in ("ed", "es") and _MAGIC_E_RE.search(stem + "e"):
                stem += "e"  # named, makes: the stem's silent e
            phones = _read(stem)
            return phones + _suffix_phones(ending, phones)
    match = _MAGIC_E_RE.search(word)
    if match and len(word) > 2:
        head, vowel, consonant = word[: match.start()], match.group(1), match.group(2)
        return _groups(head) + LONG_VOWEL[vowel].split() + _groups(consonant)
    for ending, sounds in ENDINGS.items():
        head = word[: -len(ending)]
        if word.endswith(ending) and (len(ending) == 1 or _VOWEL_LETTERS & set(head)) and head:
            return _groups(head) + sounds.split()
    if len(word) > 2 and word.endswith("e") and word[-2] not in "aeiouy":
        word = word[:-1]
    return _groups(word)


def _suffix_phones(ending: str, stem: list[str]) -> list[str]:
    """The phones of a suffix after `stem`'s: -s as S or Z (IH Z after a sibilant), -ed as T, D
    or IH D, by the stem's last sound."""
    last = stem[-1] if stem else ""
    if ending == "S":
        return ["IH", "Z"] if last in _SIBILANTS else ["S"] if last in _VOICELESS else ["Z"]
    if ending == "D":
        return ["IH", "D"] if last in ("T", "D") else ["T"] if last in _VOICELESS else ["D"]
    return ending.split()


def _y_sound(before: str, after: str) -> str:
    """The sound of a y between the letters `before` and `after` ("" at an edge), or "" to
    read it by SPELLING: Y before a vowel at the start (yes), IH between consonants (analyst)."""
    if not before and after in _VOWEL_LETTERS and after:
        return "Y"
    if before and after and before not in _VOWEL_LETTERS and after not in _VOWEL_LETTERS:
        return "IH"
    return ""


def _groups(word: str) -> list[str]:
    """SPELLING letter groups of `word`, longest first; c before e, i, y reads S (SOFT)."""
    phones: list[str] = []
    position = 0
    while position < len(word):
        following = word[position + 1 : position + 2]
        letter = word[position]
        if letter in SOFT and following and following in "eiy":
            phones.append(SOFT[letter])
            position += 1
            continue
        if letter == "y" and (sound := _y_sound(word[position - 1 : position], following)):
            phones.append(sound)
            position += 1
            continue
        for size in range(min(_LONGEST, len(word) - position), 0, -1):
            group = word[position : position + size]
            if group in SPELLING:
                sounds = SPELLING[group].split()
                if sounds and phones and sounds[0] == phones[-1] and size == 1:
                    sounds = sounds[1:]  # a doubled letter: "ll" is one L
                phones += sounds
                position += size
                break
        else:
            position += 1
    return phones


@cache
def dictionary() -> dict[str, tuple[str, ...]]:
    """The CMU pronouncing dictionary inside the pocketsphinx wheel (the one its Decoder uses):
    lower-case spelling -> ARPAbet phones of its first pronunciation."""
    from pocketsphinx import get_model_path

    words: dict[str, tuple[str, ...]] = {}
    path = Path(get_model_path("en-us")) / "cmudict-en-us.dict"
    for line in path.read_text(encoding="utf-8").splitlines():
        spelling, _, phones = line.partition(" ")
        if phones and "(" not in spelling:
            words.setdefault(spelling, tuple(phones.split()))
    return words


def pronounce(spelling: str) -> tuple[tuple[str, ...], bool]:
    """A lower-case word -> (its ARPAbet phones, from the dictionary?): the dictionary's first
    pronunciation, else `letters_to_sounds` (empty when no letter is known)."""
    known = dictionary().get(spelling)
    return (known, True) if known else (letters_to_sounds(spelling), False)


def english_letters(word: str) -> str:
    """`word` with accents dropped (café -> cafe) and ’ as '; one character for each of `word`'s."""
    out = []
    for ch in word:
        plain = unicodedata.normalize("NFD", ch)[0]
        out.append("'" if plain == "\u2019" else plain)
    return "".join(out)


def parse_english(text: str, decoder, source: str) -> tuple[EnglishSentence, ...]:
    """Sentences and words of an English transcript, each word with its phones from the
    decoder's dictionary or, outside it, from `letters_to_sounds` (added to the decoder's
    dictionary). Raises TranscriptError naming `source` when the text has no words, holds
    digits (numbers must be written as words), or a word has a letter that is not English
    (after accents are dropped) or no pronunciation (naming the word, line and column)."""
    blanked = MARK_RE.sub(lambda mark: " " * len(mark.group()), text)
    number = re.search(r"\d+", blanked)
    if number:
        raise TranscriptError(f"{source}: the number {number.group()!r} in an English transcript; "
                              "expected numbers written as words (twenty one)")
    places = (f"{source}: {position_of(text, match.start())}" for match in WORD_RE.finditer(blanked))
    sentences = []
    for sentence in split_sentences(text):
        words = tuple(_word(match.group(), decoder, next(places)) for match in WORD_RE.finditer(sentence))
        sentences.append(EnglishSentence(sentence, words))
    if not sentences:
        raise TranscriptError(f"{source}: no English words in the transcript; expected the text spoken in the recording")
    return tuple(sentences)


def _word(text: str, decoder, where: str) -> Word:
    """The Word for `text` with phones from the dictionary, else from the letters (then added to
    it); TranscriptError starting with `where` when it has none."""
    spelling = english_letters(text).lower()
    if not SPELLING_RE.fullmatch(spelling):
        strange = next(c for c, plain in zip(text, spelling) if not ("a" <= plain <= "z" or plain == "'"))
        raise TranscriptError(f"{where}: the word {text!r} has no pronunciation ({strange!r} is not an English "
                              "letter); expected English words")
    known = decoder.lookup_word(spelling)
    if known:
        return Word(text, spelling, tuple(known.split()))
    phones = letters_to_sounds(spelling)
    if not phones:
        raise TranscriptError(f"{where}: the word {text!r} has no pronunciation; expected English words")
    decoder.add_word(spelling, " ".join(phones), True)
    return Word(text, spelling, phones)


def new_decoder(beam: float | None = None, words: tuple[Word, ...] = ()):
    """A pocketsphinx Decoder for forced alignment with the en-us model inside the wheel, its
    search beams `beam` (None: pocketsphinx's defaults), knowing the pronunciations of `words`."""
    from pocketsphinx import Decoder

    beams = {} if beam is None else {"beam": beam, "wbeam": beam, "pbeam": beam}
    decoder = Decoder(samprate=RATE, lm=None, bestpath=False, loglevel="FATAL", **beams)
    for word in words:
        if not decoder.lookup_word(word.spelling):
            decoder.add_word(word.spelling, " ".join(word.phones), True)
    return decoder


def analyse_english(
    audio: Audio,
    transcript_text: str,
    pause: tuple[float, float] | None = None,
    progress: Callable[[str, float], None] | None = None,
    source: str = "transcript",
) -> Alignment:
    """Time every sentence, word and phone of the English `transcript_text` in `audio`.

    Arguments as `analyse.analyse`. Returns an Alignment whose syllable records are phones
    (module docstring). Raises TranscriptError for an empty transcript, digits, a word
    without pronunciation or one far longer than the speech (over MAX_RATE syllables per
    second); OptionError for a pause outside the recording.
    """
    report = progress or (lambda stage, fraction: None)
    if not transcript_text.strip():
        raise TranscriptError(f"{source}: the transcript is empty; expected the text spoken in the recording")
    decoder = new_decoder()
    spoken = parse_english(transcript_text, decoder, source)
    notes: list[str] = []
    report("segment", 0.0)
    filtered = high_passed(audio)  # the energy of the segmentation and of the reconciling's dips
    parts = find_speech_parts(audio, pause, filtered)
    if not parts:
        parts = (Span(0.0, round(audio.duration, 3)),)
        notes.append("no speaking part told apart from noise: the whole recording is taken as speech")
    report("segment", 1.0)
    counts = [max(1, sum(p in VOWELS for w in s.words for p in w.phones)) for s in spoken]
    speech = sum(part.duration for part in parts)
    if sum(counts) > MAX_RATE * speech:
        raise TranscriptError(
            f"{source}: {sum(counts)} syllables to fit in {speech:.1f} s of speech (English is read at 3-7 "
            f"per second, at most {MAX_RATE:g} accepted): is this the transcript of this recording?"
        )
    spans = reconcile(audio, parts, counts, filtered)
    sentences: list[Sentence] = []
    wide = None  # the decoder with WIDE_BEAM, made when first needed
    for block in _blocks(spans):
        report("align", len(sentences) / len(spoken))
        span = Span(spans[block[0]].start, spans[block[-1]].end)
        group = [spoken[k] for k in block]
        words = [w for s in group for w in s.words]
        timed = align_words(audio, span, words, decoder)
        if timed is None:
            wide = wide or new_decoder(WIDE_BEAM, tuple(w for s in spoken for w in s.words))
            timed = align_words(audio, span, words, wide)
        if timed is None:
            notes.append(f"sentences {block[0] + 1}-{block[-1] + 1} ({span.start:.2f}-{span.end:.2f} s): "
                         "pocketsphinx found no alignment; the phones are spread evenly over the speech")
            timed = _spread(words, span)
        position = 0
        for sentence in group:
            phones = [p for w in timed[position : position + len(sentence.words)] for p in w]
            position += len(sentence.words)
            start = phones[0].start if phones else span.start
            end = phones[-1].end if phones else span.start
            sentences.append(Sentence(sentence.text, start, end, tuple(phones)))
    report("align", 1.0)
    return Alignment(tuple(sentences), audio.duration, tuple(notes))


def _blocks(spans: tuple[Span, ...]) -> list[list[int]]:
    """Indices of the sentences in runs whose reconciled spans touch (cut inside one speaking part)."""
    blocks = [[0]]
    for index in range(1, len(spans)):
        if spans[index - 1].end >= spans[index].start:
            blocks[-1].append(index)
        else:
            blocks.append([index])
    return blocks


def align_words(audio: Audio, span: Span, words: list[Word], decoder) -> list[list[Syllable]] | None:
    """The phones of each of `words`, spoken in order inside `span` of `audio`, timed by pocketsphinx
    (two passes: words, then phones). Returns one list of phone records per word, or None when
    pocketsphinx finds no alignment (too little audio for the words)."""
    pcm = _pcm(audio, span)
    try:
        decoder.set_align_text(" ".join(w.spelling for w in words))
        for attempt in range(2):  # the first pass times the words; set_alignment() makes the second time the phones
            decoder.start_utt()
            decoder.process_raw(pcm, full_utt=True)
            decoder.end_utt()
            if attempt == 0:
                if decoder.hyp() is None:  # (hyp() after the phone pass crashes pocketsphinx 5.1.1)
                    return None
                decoder.set_alignment()
        alignment = decoder.get_alignment()
    except RuntimeError:
        return None
    if alignment is None:
        return None
    # Each word's phones are read while its entry is current: an entry kept past the next one crashes pocketsphinx.
    entries = [[(phone.name, phone.start, phone.duration) for phone in entry]
               for entry in alignment.words() if entry.name.split("(")[0] not in FILLERS]
    if len(entries) != len(words):
        return None
    timed = []
    for word, entry in zip(words, entries, strict=True):
        phones: list[Syllable] = []
        for name, first, frames in entry:
            if name not in PHONE_SHAPE:
                continue  # a silence inside the word
            start = span.start + first * FRAME
            end = min(start + frames * FRAME, audio.duration)
            phones.append(Syllable("" if phones else word.text, name, phone_shapes(name),
                                   round(start, 3), round(max(end, start), 3), ALIGNED_CONFIDENCE))
        timed.append(phones)
    return timed


def _spread(words: list[Word], span: Span) -> list[list[Syllable]]:
    """The phones of `words` spread evenly over `span` (when alignment failed), low confidence."""
    total = sum(len(w.phones) for w in words)
    step = span.duration / max(total, 1)
    timed, k = [], 0
    for word in words:
        phones = []
        for index, phone in enumerate(word.phones):
            start = span.start + k * step
            phones.append(Syllable(word.text if index == 0 else "", phone, phone_shapes(phone),
                                   round(start, 3), round(start + step, 3), FALLBACK_CONFIDENCE))
            k += 1
        timed.append(phones)
    return timed


def _pcm(audio: Audio, span: Span) -> bytes:
    """The samples of `span` resampled to RATE as 16-bit little-endian PCM bytes."""
    part = audio.samples[int(span.start * audio.rate) : int(np.ceil(span.end * audio.rate))]
    if audio.rate != RATE:
        part = resample_poly(part, RATE, audio.rate)
    return (np.clip(part, -1.0, 1.0) * PCM_SCALE).astype("<i2").tobytes()
