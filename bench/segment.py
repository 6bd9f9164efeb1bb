"""Sentence segmentation (sentences.find_speech_parts) and reconciliation on real recordings.

Sets, all from ../shared/bench/zh/:

* THCHS-30 (6 news sentences, no punctuation in the transcripts): each file alone
  (1 sentence each), and the 6 files joined as recorded (their own leading and
  trailing silence is the pause between sentences: 6 sentences).
* Biaobei (70 read sentences, commas inside some): the files joined as recorded
  (70 sentences, and the first 20 alone); per file, speaking parts against punctuation clauses.
* Chao 1922 (noisy gramophone, isolated syllables): parts against the runs of
  labelled syllables between `sil` intervals of 0.3 s or more.

For a joined recording a sentence boundary is found when a pause between two
speaking parts (automatic mode, then the thesis's mode with the first pause
selected as the silence between the first two files) contains the join of the
files. Then `alignment.reconcile` lays the transcript's sentences (syllable
counts from the pinyin) over the automatic parts; a boundary is right when it
falls within 0.3 s of the join's pause. Speed: median of 5 runs, times real
time, on the joined Biaobei set and on a 30-minute recording made by repeating it.
"""

from __future__ import annotations

import csv
import re
import statistics
import time
from pathlib import Path

import numpy as np

from cartoonface.speech.alignment import reconcile
from cartoonface.speech.audio import Audio, load_audio
from cartoonface.speech.sentences import Span, find_speech_parts

ZH = Path(__file__).resolve().parents[1].parent / "shared" / "bench" / "zh"
TOLERANCE = 0.3  # seconds: a reconciled boundary this close to the join's pause is right


def joined(paths: list[Path]) -> tuple[Audio, list[float], list[Span]]:
    """The recordings at `paths` end to end: (audio, join times, speech extent of each file)."""
    audios = [load_audio(path) for path in paths]
    rate = audios[0].rate
    assert all(audio.rate == rate for audio in audios)
    joins, extents, position = [], [], 0.0
    for audio in audios:
        loud = np.flatnonzero(np.abs(audio.samples) > 0.05 * np.abs(audio.samples).max())
        extents.append(Span(position + loud[0] / rate, position + loud[-1] / rate))
        position += audio.duration
        joins.append(position)
    samples = np.concatenate([audio.samples for audio in audios])
    return Audio(samples, rate, "joined"), joins[:-1], extents


def boundaries_found(parts: tuple[Span, ...], joins: list[float]) -> int:
    """How many joins fall inside a pause between consecutive speaking parts."""
    pauses = [(a.end, b.start) for a, b in zip(parts, parts[1:])]
    return sum(any(start <= join <= end for start, end in pauses) for join in joins)


def reconciled_right(audio: Audio, parts: tuple[Span, ...], counts: list[int], extents: list[Span]) -> int:
    """How many sentence boundaries reconcile() puts within TOLERANCE of the pause at the join."""
    spans, _ = reconcile(audio, parts, counts, [""] * len(counts))
    right = 0
    for k in range(len(spans) - 1):
        pause_start, pause_end = extents[k].end, extents[k + 1].start
        right += spans[k].end <= pause_end + TOLERANCE and spans[k + 1].start >= pause_start - TOLERANCE
    return right


def speed(audio: Audio, runs: int = 5) -> float:
    """Median times real time of find_speech_parts on `audio`."""
    times = []
    for _ in range(runs):
        started = time.perf_counter()
        find_speech_parts(audio)
        times.append(time.perf_counter() - started)
    return audio.duration / statistics.median(times)


def report_joined(name: str, paths: list[Path], counts: list[int]) -> Audio:
    """Print the joined-recording figures for one set; return the joined audio."""
    audio, joins, extents = joined(paths)
    auto = find_speech_parts(audio)
    first_pause = (extents[0].end + 0.05, extents[1].start - 0.05)
    thesis = find_speech_parts(audio, pause=first_pause)
    print(f"{name} joined: {len(paths)} sentences, {audio.duration:.1f} s")
    for mode, parts in (("automatic", auto), ("thesis (first pause given)", thesis)):
        print(f"  {mode:<27} {len(parts):3d} parts, {boundaries_found(parts, joins)}/{len(joins)} "
              f"sentence boundaries inside a pause between parts")
    right = reconciled_right(audio, auto, counts, extents)
    print(f"  reconciled with the transcript: {right}/{len(joins)} boundaries within {TOLERANCE} s of the pause")
    return audio


def thchs30() -> None:
    folder = ZH / "thchs30_mfa_example"
    rows = list(csv.DictReader((folder / "transcripts.tsv").open(encoding="utf-8"), delimiter="\t"))
    paths = [folder / row["wav"] for row in rows]
    counts = [len(re.findall(r"[1-5]", row["pinyin_words"])) for row in rows]
    alone = [len(find_speech_parts(load_audio(path))) for path in paths]
    print(f"THCHS-30 each file alone (1 sentence, no punctuation): parts per file {alone}")
    report_joined("THCHS-30", paths, counts)


def biaobei() -> Audio:
    folder = ZH / "biaobei"
    rows = list(csv.DictReader((folder / "transcripts.tsv").open(encoding="utf-8"), delimiter="\t"))
    paths = [folder / "wav" / f"{row['id']}.wav" for row in rows]
    counts = [int(row["n_syll"]) for row in rows]
    same = 0
    for row, path in zip(rows, paths, strict=True):
        clauses = len([c for c in re.split(r"[,.，。!?！？;；、]", row["hanzi_meta"]) if c.strip()])
        same += len(find_speech_parts(load_audio(path))) == clauses
    print(f"Biaobei each file alone: parts = punctuation clauses in {same}/{len(rows)} files")
    report_joined("Biaobei 000001-000020", paths[:20], counts[:20])
    return report_joined("Biaobei", paths, counts)


def chao() -> None:
    folder = ZH / "chao1922_tone_change"
    text = (folder / "chao1922_tone_paradigm.TextGrid").read_text(encoding="utf-8")
    found = re.findall(r"xmin = ([\d.]+)\s*\n\s*xmax = ([\d.]+)\s*\n\s*text = \"([^\"]*)\"", text)
    runs: list[list[float]] = []
    for start, end, label in found:
        start, end = float(start), float(end)
        if label in ("", "sil"):
            continue
        if runs and start - runs[-1][1] < 0.3:
            runs[-1][1] = end
        else:
            runs.append([start, end])
    parts = find_speech_parts(load_audio(folder / "chao1922_tone_paradigm.wav"))
    matched = sum(any(p.start - 0.15 <= a and b <= p.end + 0.15 for p in parts) for a, b in runs)
    print(f"Chao 1922: {len(parts)} parts found for {len(runs)} labelled runs "
          f"(runs of syllables between pauses of 0.3 s or more); {matched} runs lie inside one part")


def main() -> None:
    thchs30()
    audio = biaobei()
    chao()
    print(f"speed on Biaobei joined ({audio.duration:.0f} s): {speed(audio):.0f}x real time")
    repeats = int(np.ceil(1800 / audio.duration))
    long = Audio(np.tile(audio.samples, repeats)[: 1800 * audio.rate], audio.rate, "30 minutes")
    print(f"speed on 30 minutes (Biaobei joined, repeated): {speed(long, runs=3):.0f}x real time")


if __name__ == "__main__":
    main()
