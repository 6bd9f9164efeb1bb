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
files. Then `alignment.analyse` runs on the joined recording with the transcript
(the sentences of the files, each ended by 。); a boundary is right when the
sentence before it ends, and the one after starts, within 0.3 s of the speech
edges of the files at the join. "Run together": the files with their silences
cut off, butted together (no pause between sentences at all), comparing the
reconciling's own cut points with the shipped joint alignment of the sentences
sharing a part. On Biaobei joined, the syllable onsets of the whole analyse()
against the corpus's reference. Speed: median of 5 runs, times real time, of
find_speech_parts on the joined Biaobei set and on a 30-minute recording made by
repeating it.
"""

from __future__ import annotations

import csv
import re
import statistics
import time
from pathlib import Path

import numpy as np

from bench.align import read_tiers
from cartoonface.speech.analyse import analyse
from cartoonface.speech.reconcile import reconcile
from cartoonface.speech.audio import Audio, load_audio
from cartoonface.speech.sentences import Span, find_speech_parts
from cartoonface.speech.transcript import parse_transcript

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


def analysed_right(audio: Audio, text: str, extents: list[Span]) -> tuple[int, int]:
    """(right, sentences): how many sentence boundaries analyse() puts within TOLERANCE of the join.

    Right = the sentence before ends, and the one after starts, within TOLERANCE of
    the end and start of the speech of the files on either side of the join.
    """
    sentences = analyse(audio, text).sentences
    right = sum(
        abs(sentences[k].end - extents[k].end) <= TOLERANCE
        and abs(sentences[k + 1].start - extents[k + 1].start) <= TOLERANCE
        for k in range(min(len(sentences), len(extents)) - 1)
    )
    return right, len(sentences)


def speed(audio: Audio, runs: int = 5) -> float:
    """Median times real time of find_speech_parts on `audio`."""
    times = []
    for _ in range(runs):
        started = time.perf_counter()
        find_speech_parts(audio)
        times.append(time.perf_counter() - started)
    return audio.duration / statistics.median(times)


def report_onsets(audio: Audio, text: str, references: list[list[float]]) -> None:
    """Syllable onset error of the whole analyse() (segment, reconcile, align) against `references`
    (onset seconds per sentence, on the joined recording's clock); sentences whose syllable count
    differs from the reference (other readings of numbers or erhua) are left out."""
    started = time.perf_counter()
    sentences = analyse(audio, text).sentences
    seconds = time.perf_counter() - started
    errors, left_out = [], 0
    for sentence, reference in zip(sentences, references, strict=True):
        if len(sentence.syllables) != len(reference):
            left_out += 1
            continue
        errors += [abs(s.start - onset) * 1000 for s, onset in zip(sentence.syllables, reference, strict=True)]
    values = np.array(errors)
    print(f"  analyse() syllable onsets against the reference ({len(values)} onsets, {left_out} sentences left out): "
          f"median {np.median(values):.1f} ms, p90 {np.percentile(values, 90):.1f} ms, within 20 / 50 / 100 ms "
          f"{np.mean(values <= 20):.1%} / {np.mean(values <= 50):.1%} / {np.mean(values <= 100):.1%}; "
          f"{audio.duration / seconds:.0f}x real time")


def report_joined(name: str, paths: list[Path], text: str) -> Audio:
    """Print the joined-recording figures for one set (transcript `text`); return the joined audio."""
    audio, joins, extents = joined(paths)
    auto = find_speech_parts(audio)
    first_pause = (extents[0].end + 0.05, extents[1].start - 0.05)
    thesis = find_speech_parts(audio, pause=first_pause)
    print(f"{name} joined: {len(paths)} sentences, {audio.duration:.1f} s")
    for mode, parts in (("automatic", auto), ("thesis (first pause given)", thesis)):
        print(f"  {mode:<27} {len(parts):3d} parts, {boundaries_found(parts, joins)}/{len(joins)} "
              f"sentence boundaries inside a pause between parts")
    right, count = analysed_right(audio, text, extents)
    print(f"  analyse() with the transcript: {count} sentences, {right}/{len(joins)} boundaries "
          f"within {TOLERANCE} s")
    return audio


def report_run_together(name: str, paths: list[Path], text: str) -> None:
    """Figures for the files of a set butted together with their silences cut off (no pauses at all)."""
    audios = [load_audio(path) for path in paths]
    pieces, extents, position = [], [], 0.0
    for audio in audios:
        loud = np.flatnonzero(np.abs(audio.samples) > 0.05 * np.abs(audio.samples).max())
        pieces.append(audio.samples[loud[0] : loud[-1] + 1])
        extents.append(Span(position, position + len(pieces[-1]) / audio.rate))
        position = extents[-1].end
    together = Audio(np.concatenate(pieces), audios[0].rate, "run together")
    parts = find_speech_parts(together)
    counts = [len(sentence.syllables) for sentence in parse_transcript(text, name)]
    spans = reconcile(together, parts, counts)
    dip_right = sum(abs(spans[k + 1].start - extents[k + 1].start) <= TOLERANCE for k in range(len(spans) - 1))
    right, _ = analysed_right(together, text, extents)
    print(f"{name} run together (silences cut, {together.duration:.1f} s): {len(parts)} parts; boundaries within "
          f"{TOLERANCE} s: {dip_right}/{len(paths) - 1} at the reconciling's dips, {right}/{len(paths) - 1} "
          "after aligning the sentences of a part together (shipped)")


def thchs30() -> None:
    folder = ZH / "thchs30_mfa_example"
    rows = list(csv.DictReader((folder / "transcripts.tsv").open(encoding="utf-8"), delimiter="\t"))
    alone = [len(find_speech_parts(load_audio(folder / row["wav"]))) for row in rows]
    print(f"THCHS-30 each file alone (1 sentence, no punctuation): parts per file {alone}")
    rows = [row for row in rows if row["hanzi"]]  # 894 has no Hanzi transcript
    paths = [folder / row["wav"] for row in rows]
    text = "".join(row["hanzi"] + "。" for row in rows)
    report_joined("THCHS-30", paths, text)
    report_run_together("THCHS-30", paths, text)


def biaobei() -> Audio:
    folder = ZH / "biaobei"
    rows = list(csv.DictReader((folder / "transcripts.tsv").open(encoding="utf-8"), delimiter="\t"))
    paths = [folder / "wav" / f"{row['id']}.wav" for row in rows]
    texts = [row["hanzi_meta"].rstrip(".") + "。" for row in rows]
    same = 0
    for row, path in zip(rows, paths, strict=True):
        clauses = len([c for c in re.split(r"[,.，。!?！？;；、]", row["hanzi_meta"]) if c.strip()])
        same += len(find_speech_parts(load_audio(path))) == clauses
    print(f"Biaobei each file alone: parts = punctuation clauses in {same}/{len(rows)} files")
    report_joined("Biaobei 000001-000020", paths[:20], "".join(texts[:20]))
    report_run_together("Biaobei 000001-000020", paths[:20], "".join(texts[:20]))
    audio = report_joined("Biaobei", paths, "".join(texts))
    _, joins, _ = joined(paths)
    references = []
    for row, offset in zip(rows, [0.0, *joins], strict=True):
        tier = read_tiers(folder / "TextGrid" / f"{row['id']}.TextGrid")["syllables_pinyin"]
        references.append([start + offset for start, _, label in tier if label not in ("sil", "sp", "")])
    report_onsets(audio, "".join(texts), references)
    return audio


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
