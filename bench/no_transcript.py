"""Lip sync without a transcript (speech/audio_only.py) against the transcript-aligned result.

For every recording of the Biaobei dev set (tuning half 000001-000035, held-out half
000036-000070), of AISHELL-3 (2) and of THCHS-30 (the MFA example, 7): the mouth key frames of both alignments
(animate/timeline.mouth_keys, the shape shown from each key to the next) are sampled at
FPS frames per second, each frame's shape put in its mouth class (audio_only.MOUTH_CLASSES:
closed, open, rounded, spread), and the share of frames in the same class is reported
(pooled over the set; the per-recording median too), with the confusion of the classes and
the speed of `analyse_audio` in times real time. The transcript-aligned result is
`analyse.analyse` with the transcript as written (Biaobei: bench/align.py's recordings;
AISHELL-3: the hanzi column of transcripts.tsv; THCHS-30: the .lab files, spaces removed).

`python -m bench no_transcript`; `python -m bench.no_transcript sweep` scores the tuning
half for a grid of the thresholds (CLOSURE_DB and the vowel-class z-scores).
"""

from __future__ import annotations

import csv
import itertools
import sys
import time

import numpy as np

from bench.align import TUNING, ZH, Recording, biaobei, load_audio
from cartoonface.animate.timeline import mouth_keys
from cartoonface.speech import audio_only
from cartoonface.speech.analyse import analyse
from cartoonface.speech.audio_only import MOUTH_CLASSES, analyse_audio
from cartoonface.speech.records import Alignment

FPS = 30
CLASSES = ("closed", "open", "rounded", "spread")


def aishell3() -> list[Recording]:
    """The AISHELL-3 recordings with their hanzi transcripts (no reference parts: not needed here)."""
    folder = ZH / "aishell3_charsiu"
    rows = csv.DictReader((folder / "transcripts.tsv").open(encoding="utf-8"), delimiter="\t")
    return [Recording(row["wav"], load_audio(folder / row["wav"]), (), row["hanzi"]) for row in rows]


def thchs30() -> list[Recording]:
    """The THCHS-30 recordings of the MFA example with their word-spaced transcripts joined."""
    folder = ZH / "thchs30_mfa_example"
    return [Recording(lab.stem, load_audio(lab.with_suffix(".wav")), (), "".join(lab.read_text(encoding="utf-8").split()))
            for lab in sorted(folder.glob("*.lab")) if not lab.name.endswith(".pinyin.lab")]


def frame_classes(alignment: Alignment, duration: float) -> np.ndarray:
    """(F,) index into CLASSES of the mouth shown at each of FPS frames per second over `duration` s."""
    syllables = [s for sentence in alignment.sentences for s in sentence.syllables]
    keys = mouth_keys(syllables, round(duration * 1000))
    times = np.array([key.t for key in keys])
    values = np.array([CLASSES.index(MOUTH_CLASSES[str(key.value)]) for key in keys])
    frames = np.arange(int(duration * FPS)) * 1000 / FPS
    return values[np.searchsorted(times, frames, side="right") - 1]


def references(recordings: list[Recording]) -> list[np.ndarray]:
    """The frame classes of the transcript-aligned result of each recording."""
    return [frame_classes(analyse(r.audio, r.text, source=r.name), r.audio.duration) for r in recordings]


def score(recordings: list[Recording], refs: list[np.ndarray]) -> tuple[float, float, float, np.ndarray]:
    """(pooled share of frames in the same class, median per recording, times real time, 4x4 confusion
    counts [reference class, audio-only class]) of analyse_audio on `recordings`."""
    confusion = np.zeros((len(CLASSES), len(CLASSES)), dtype=int)
    shares, seconds, audio = [], 0.0, 0.0
    for recording, ref in zip(recordings, refs, strict=True):
        started = time.perf_counter()
        alignment = analyse_audio(recording.audio)
        seconds += time.perf_counter() - started
        audio += recording.audio.duration
        mine = frame_classes(alignment, recording.audio.duration)
        shares.append(float(np.mean(mine == ref)))
        np.add.at(confusion, (ref, mine), 1)
    return float(np.trace(confusion) / confusion.sum()), float(np.median(shares)), audio / seconds, confusion


def report(name: str, recordings: list[Recording]) -> None:
    """Print the agreement, speed and confusion of one set."""
    refs = references(recordings)
    pooled, median, speed, confusion = score(recordings, refs)
    base = float(np.max(confusion.sum(axis=1)) / confusion.sum())
    closed_or_not = float((confusion[0, 0] + confusion[1:, 1:].sum()) / confusion.sum())
    print(f"{name}: {len(recordings)} recordings, same mouth class {100 * pooled:.1f} % of frames "
          f"(median per recording {100 * median:.1f} %; always the commonest class: {100 * base:.1f} %), "
          f"closed or not the same {100 * closed_or_not:.1f} % of frames, {speed:.0f}x real time")
    print("  reference \\ audio only: " + " ".join(f"{c:>8}" for c in CLASSES))
    for name_, row in zip(CLASSES, confusion):
        print(f"  {name_:>22}: " + " ".join(f"{100 * v / max(row.sum(), 1):7.1f}%" for v in row))


def sweep() -> None:
    """Agreement on the tuning half for a grid of thresholds."""
    tuning = [r for r in biaobei() if int(r.name) in TUNING]
    refs = references(tuning)
    for closure, open_z, round_z, spread_z in itertools.product((10.0, 15.0, 20.0, 99.0), (0.3, 0.5, 0.8),
                                                               (-0.3, -0.5, -0.8), (0.3, 0.5, 0.8)):
        audio_only.CLOSURE_DB, audio_only.OPEN_Z = closure, open_z
        audio_only.ROUNDED_Z, audio_only.SPREAD_Z = round_z, spread_z
        pooled, median, _, _ = score(tuning, refs)
        print(f"closure {closure:g} dB, open z {open_z:g}, rounded z {round_z:g}, spread z {spread_z:g}: "
              f"{100 * pooled:.1f} % (median {100 * median:.1f} %)", flush=True)


def main() -> None:
    records = biaobei()
    report("Biaobei tuning 000001-000035", [r for r in records if int(r.name) in TUNING])
    report("Biaobei held-out 000036-000070", [r for r in records if int(r.name) not in TUNING])
    report("AISHELL-3 (2 speakers)", aishell3())
    report("THCHS-30 (MFA example)", thchs30())


if __name__ == "__main__":
    sweep() if sys.argv[1:] == ["sweep"] else main()
