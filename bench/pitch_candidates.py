"""Pitch peaks with fewer candidates per frame in Praat's To Pitch (ac), on real recordings.

`prosody.pitch_peaks` (the accent peaks that raise the brows and nod the head) is computed for every
recording here that the analysis aligns, with the pitch track of Praat's default 15 candidates per
frame and with each smaller count down to 6 (Praat raises any count below pitch ceiling / pitch floor,
500 / 75 Hz, to 6). Against 15, per count: the share of recordings with the same peak tuple, the
peaks added, removed and moved (the same syllable's peak at another frame) and by how much, as a
share of all syllables, the share of voiced frames with another F0, and the track's CPU on the 190 s
book (median of 3).

Recordings (../shared/bench, read in place): Biaobei 000001-000070, the two AISHELL-3 sentences,
the five THCHS-30 sentences with a Hanzi transcript, the English ones bench/english.py aligns
(reference words as transcript), the project's sample story, and the 190 s THCHS-30 book of
bench/generate.py. The recordings but the book (its sentences are THCHS-30's, repeated), sorted by
name: the even-numbered half tunes (the count is chosen on it), the odd-numbered half is held out
(reported); the book on its own line, with the track's CPU.

Run: `.venv/bin/python -m bench pitch_candidates` from the project root (~3 minutes).
"""

from __future__ import annotations

import csv
import statistics
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bench.english import MATERIAL, ROOT, reference_words, transcript_of
from bench.generate import TARGET_SECONDS, build_input
from cartoonface.animate import prosody
from cartoonface.speech.analyse import analyse
from cartoonface.speech.audio import Audio, load_audio
from cartoonface.speech.pitch import pitch_track

COUNTS = range(15, 5, -1)  # Praat's default first: the reference
FRAME = 1 / 30  # seconds: a peak moved by more than one frame at 30 fps is seen elsewhere
SAMPLES = Path(__file__).resolve().parent.parent / "samples" / "speech"
BOOK = "thchs30_book_190s"  # the name of bench/generate.py's 190 s input among the items


@dataclass(frozen=True)
class Item:
    """One aligned recording: its audio, syllable starts (n,) s, and the peaks and tracks per
    setting (a count here, a named time step in bench/pitch_step.py)."""

    name: str
    audio: Audio
    starts: np.ndarray
    peaks: dict[object, tuple[float, ...]]
    tracks: dict[object, tuple[np.ndarray, np.ndarray]]


def material() -> list[tuple[str, Path, str, str | None]]:
    """(name, wav, transcript, language) of every recording used."""
    zh = ROOT / "zh"
    rows: list[tuple[str, Path, str, str | None]] = []
    with (zh / "biaobei" / "transcripts.tsv").open(encoding="utf-8") as handle:
        for row in csv.DictReader(handle, delimiter="\t"):
            rows.append((f"biaobei/{row['id']}", zh / "biaobei" / "wav" / f"{row['id']}.wav", row["hanzi_meta"], "zh"))
    for folder in ("aishell3_charsiu", "thchs30_mfa_example"):
        with (zh / folder / "transcripts.tsv").open(encoding="utf-8") as handle:
            for row in csv.DictReader(handle, delimiter="\t"):
                if row["hanzi"].strip():
                    rows.append((f"{folder}/{row['wav']}", zh / folder / row["wav"], row["hanzi"], "zh"))
    for _, wav, reference, tier in MATERIAL:
        rows.append((f"en/{Path(wav).stem}", ROOT / wav, transcript_of(ROOT / wav, reference_words(ROOT / reference, tier)), "en"))
    rows.append(("sample/story", SAMPLES / "story.wav", (SAMPLES / "story.txt").read_text(encoding="utf-8"), None))
    return rows


def track(audio: Audio, count: int, step: float = prosody.TIME_STEP, shift: float = 0.0,
          ours: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Praat's To Pitch (ac) (times, f0) with `count` candidates per frame, frames every `step` s
    (`ours`: speech/pitch.py's instead, prosody.pitch_track's tracker, its own count); `shift` s of
    silence put before the recording move the frame grid by that much (the times are given back on
    the recording's clock)."""
    pad = round(shift * audio.rate)
    samples = np.concatenate([np.zeros(pad), np.asarray(audio.samples, dtype=np.float64)])
    if ours:
        times, f0 = pitch_track(samples, audio.rate, step, prosody.PITCH_FLOOR, prosody.PITCH_CEILING)
        return times - pad / audio.rate, f0
    import parselmouth  # Praat's own: imported only for its tracks

    sound = parselmouth.Sound(samples, sampling_frequency=float(audio.rate))
    pitch = sound.to_pitch_ac(time_step=step, pitch_floor=prosody.PITCH_FLOOR,
                              pitch_ceiling=prosody.PITCH_CEILING, max_number_of_candidates=count)
    f0 = np.array(pitch.selected_array["frequency"], dtype=float)
    f0[f0 <= 0] = np.nan
    return np.array(pitch.xs(), dtype=float) - pad / audio.rate, f0


def item(name: str, wav: Path, text: str, language: str | None,
         settings: dict[object, dict[str, float]] | None = None) -> Item:
    """Align `wav` once and compute its peaks for every setting: name -> track()'s keywords
    (default: every count of COUNTS)."""
    audio = load_audio(wav)
    alignment = analyse(audio, text, source=str(wav), language=language)
    starts = np.array([s.start for sentence in alignment.sentences for s in sentence.syllables], dtype=float)
    chosen = settings or {count: {"count": count} for count in COUNTS}
    tracks = {key: track(audio, **{"count": 15, **keywords}) for key, keywords in chosen.items()}  # type: ignore[arg-type]
    peaks = {key: prosody.pitch_peaks(audio, alignment, tracks[key]) for key in chosen}
    return Item(name, audio, starts, peaks, tracks)


def by_syllable(starts: np.ndarray, peaks: tuple[float, ...]) -> dict[int, float]:
    """{syllable index: peak time} (a peak lies in its syllable, rounded to the ms)."""
    return {int(np.searchsorted(starts, t + 5e-4, side="right")) - 1: t for t in peaks}


def compare(items: list[Item], count: object, reference: object = 15) -> dict[str, float]:
    """Figures of setting `count` against setting `reference` over `items`: same tuple, peaks added /
    removed / moved, their share of syllables, the largest move and the moves past a frame, the
    share of voiced frames with another F0 (when both tracks have the same frames, else NaN)."""
    same = added = removed = moved = syllables = 0
    shifts: list[float] = []
    changed_frames = voiced_frames = 0
    other_grid = False
    for it in items:
        old, new = by_syllable(it.starts, it.peaks[reference]), by_syllable(it.starts, it.peaks[count])
        same += it.peaks[reference] == it.peaks[count]
        added += len(new.keys() - old.keys())
        removed += len(old.keys() - new.keys())
        moves = [abs(new[k] - old[k]) for k in old.keys() & new.keys() if new[k] != old[k]]
        moved += len(moves)
        shifts += moves
        syllables += len(it.starts)
        f_old, f_new = it.tracks[reference][1], it.tracks[count][1]
        if len(f_old) != len(f_new):  # other frames: not compared frame by frame
            other_grid = True
            continue
        voiced = np.isfinite(f_old) | np.isfinite(f_new)
        voiced_frames += int(voiced.sum())
        changed_frames += int((voiced & ~((f_old == f_new) | (np.isnan(f_old) & np.isnan(f_new)))).sum())
    changed = added + removed + moved
    return {"same": same / len(items), "added": added, "removed": removed, "moved": moved,
            "changed_share": changed / syllables, "max_shift": max(shifts, default=0.0),
            "frames": float("nan") if other_grid else changed_frames / max(voiced_frames, 1),
            "past_frame": sum(shift > FRAME for shift in shifts), "syllables": syllables,
            "peaks": sum(len(it.peaks[reference]) for it in items)}


def cpu(audio: Audio, count: int = 15, step: float = prosody.TIME_STEP, ours: bool = False) -> float:
    """Median CPU seconds of 3 tracks of `audio` with `count` candidates and frames every `step` s
    (`ours`: speech/pitch.py's)."""
    spent = []
    for _ in range(3):
        started = time.process_time()
        track(audio, count, step, ours=ours)
        spent.append(time.process_time() - started)
    return statistics.median(spent)


def table(title: str, items: list[Item], book: Audio | None) -> None:
    """Print the figures of every count on `items`."""
    print(f"{title}: {len(items)} recordings")
    print("| count | same peaks | added / removed / moved | changed, share of syllables | largest move | voiced frames with another F0 | track CPU, 190 s |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for count in COUNTS:
        c = compare(items, count)
        spent = f"{cpu(book, count):.3f} s" if book is not None else ""
        print(f"| {count} | {100 * c['same']:.1f} % | {c['added']} / {c['removed']} / {c['moved']} "
              f"| {100 * c['changed_share']:.2f} % of {c['syllables']} ({c['peaks']} peaks at 15) "
              f"| {1000 * c['max_shift']:.0f} ms | {100 * c['frames']:.2f} % | {spent} |")


def aligned_items(settings: dict[object, dict[str, float]] | None = None) -> tuple[list[Item], Item]:
    """item() of every recording (its `settings`), sorted by name, without the 190 s book; and the book's."""
    with tempfile.TemporaryDirectory() as tmp:
        book, text, _ = build_input(Path(tmp), TARGET_SECONDS)
        rows = [*material(), (BOOK, book, text.read_text(encoding="utf-8"), "zh")]
        items = sorted((item(*row, settings=settings) for row in rows), key=lambda it: it.name)
    return [it for it in items if it.name != BOOK], next(it for it in items if it.name == BOOK)


def main() -> None:
    """Align every recording, compare the peaks per count, print the tuning and held-out tables."""
    distinct, book = aligned_items()
    table("tuning half (even positions)", distinct[0::2], None)
    table("held-out half (odd positions)", distinct[1::2], None)
    table("the 190 s book", [book], book.audio)


if __name__ == "__main__":
    main()
