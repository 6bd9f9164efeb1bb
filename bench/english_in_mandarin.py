"""Onsets of Mandarin sentences with English words inside, before (words skipped) and after (read).

No recording of Mandarin with English words is in ../shared/bench, so the material is
synthetic: each sentence of SENTENCES is cut into its Mandarin runs and English words; a
Mandarin run is read by espeak-ng's cmn-latn-pinyin voice from the project's own pinyin
(tests/espeak.py: the onset of every syllable is known), an English word by its en-us voice
(the onset of the word is where its speech starts); the pieces, trimmed of their silence,
are joined without a gap. The whole Mandarin path (`analyse(..., language="zh")`) times
each sentence:
- after: the sentence as written (English words read, english_in_mandarin.py);
- before: the sentence without its English words, which is what the reading did before
  (each skipped with a note), so the English words have no onset and count as misses.
The table gives the share of onsets within WITHIN of the reference: all of them (Mandarin
syllables and English word starts), the Mandarin syllables only, the English words only.
Nothing was tuned on this material.

Run: `.venv/bin/python -m bench english_in_mandarin` from the project root.
"""

from __future__ import annotations

import re
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import soundfile
from scipy import signal

from cartoonface.speech.analyse import analyse
from cartoonface.speech.transcript import parse_transcript
from tests.espeak import synthesize
from tests.synthetic import RATE, noisy

WITHIN = 0.05  # seconds
LEAD = 0.5  # seconds of silence before and after each sentence
TRIM = 0.02  # a piece's speech starts and ends where it passes this share of its peak
SENTENCES = (
    "我今天用Python写了一个小程序。",
    "请把这个file发到我的email里。",
    "他在Google工作了三年。",
    "我们周末去听了一场concert，很好听。",
    "这个project的deadline是下周五。",
    "你的password太简单了。",
    "她每天早上都喝一杯coffee。",
    "老板说meeting改到下午三点。",
    "我在YouTube上看到一个很有意思的video。",
    "这款software需要update一下。",
)
PIECE_RE = re.compile(r"[A-Za-z]+|[^A-Za-z]+")


def _trimmed(samples: np.ndarray) -> tuple[np.ndarray, int]:
    """(samples from the first to the last loud one, index of the first)."""
    loud = np.flatnonzero(np.abs(samples) > TRIM * np.abs(samples).max())
    return samples[loud[0] : loud[-1] + 1], int(loud[0])


def _english(word: str, folder: Path) -> tuple[np.ndarray, int]:
    """espeak-ng en-us reading `word`: (samples, rate)."""
    path = folder / f"{word}.wav"
    subprocess.run(["espeak-ng", "-v", "en-us", "-w", str(path), word], check=True)
    samples, rate = soundfile.read(path, dtype="float32")
    return samples, rate


def pieces_of(sentence: str) -> list[tuple[str, list[str]]]:
    """The sentence as parse_transcript reads it, cut into pieces: ("", pinyin of a run of
    Mandarin syllables) or (English word, pinyin of its syllables)."""
    pieces: list[tuple[str, list[str]]] = []
    for syllable in parse_transcript(sentence)[0].syllables:
        english = not syllable.text or syllable.text.isascii()
        if syllable.text.isascii() and syllable.text or not pieces or (not english and pieces[-1][0]):
            pieces.append((syllable.text if english else "", []))
        pieces[-1][1].append(syllable.pinyin)
    return pieces


def spoken(sentence: str, folder: Path) -> tuple[np.ndarray, list[float | None]]:
    """The synthetic recording of `sentence` at RATE, and the reference onset (seconds) of each
    of its syllables as parse_transcript reads it (None on the later syllables of an English word)."""
    pieces: list[np.ndarray] = []
    onsets: list[float | None] = []
    position = LEAD
    rate = 0
    for word, pinyin in pieces_of(sentence):
        if word:
            samples, rate = _english(word, folder)
            speech, _ = _trimmed(samples)
            onsets += [position] + [None] * (len(pinyin) - 1)
        else:
            synthesis = synthesize(pinyin)
            if synthesis is None:
                raise SystemExit("espeak-ng or its cmn-latn-pinyin voice is missing")
            speech, first = _trimmed(synthesis.samples)
            rate = synthesis.rate
            onsets += [position + max(onset * rate - first, 0) / rate for onset in synthesis.onsets]
        pieces.append(speech)
        position += len(speech) / rate
    silence = np.zeros(int(LEAD * rate), np.float32)
    joined = np.concatenate([silence, *pieces, silence])
    return signal.resample_poly(joined, RATE, rate).astype(np.float32), onsets


def onset_hits(sentence: str, folder: Path) -> dict[str, list[bool]]:
    """For `sentence`: per kind ("before mandarin", "before english", "after mandarin",
    "after english") whether each reference onset was found within WITHIN."""
    samples, onsets = spoken(sentence, folder)
    audio = noisy(samples)
    english = [word for word, _ in pieces_of(sentence) if word]
    texts = [s.text for s in parse_transcript(sentence)[0].syllables]
    is_english = [not text or text.isascii() for text in texts]  # Mandarin syllables show their Hanzi
    hits: dict[str, list[bool]] = {"before mandarin": [], "before english": [], "after mandarin": [],
                                   "after english": []}
    after = [s.start for part in analyse(audio, sentence, language="zh").sentences for s in part.syllables]
    for start, onset, flag in zip(after, onsets, is_english, strict=True):
        if onset is not None:
            hits["after english" if flag else "after mandarin"].append(abs(start - onset) <= WITHIN)
    without = "".join(p for p in PIECE_RE.findall(sentence) if not (p.isascii() and p.isalpha()))
    before = iter(s.start for part in analyse(audio, without, language="zh").sentences for s in part.syllables)
    for onset, flag in zip(onsets, is_english, strict=True):
        if onset is None:
            continue
        if flag:
            hits["before english"].append(False)  # skipped: no onset
        else:
            hits["before mandarin"].append(abs(next(before) - onset) <= WITHIN)
    assert len(english) == len(hits["after english"])
    return hits


def main() -> None:
    """Print the table of onsets within WITHIN, before and after, over all SENTENCES."""
    hits: dict[str, list[bool]] = {}
    with tempfile.TemporaryDirectory() as folder:
        for sentence in SENTENCES:
            for kind, found in onset_hits(sentence, Path(folder)).items():
                hits.setdefault(kind, []).extend(found)
    print(f"| reading | all onsets within {WITHIN * 1000:.0f} ms | Mandarin syllables | English words |")
    print("| --- | --- | --- | --- |")
    for name in ("before", "after"):
        mandarin, english = hits[f"{name} mandarin"], hits[f"{name} english"]
        every = mandarin + english
        print(f"| {name} | {np.mean(every):.1%} of {len(every)} | {np.mean(mandarin):.1%} of {len(mandarin)} "
              f"| {np.mean(english):.1%} of {len(english)} |")


if __name__ == "__main__":
    main()
