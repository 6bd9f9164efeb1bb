"""Timing and mouth robustness to how the silence between sentences was recorded or edited.

The Biaobei sentences (../shared/bench/zh/biaobei) are joined into one recording per split
(dev 000001-000035: the only sentences tuned on; held-out 000036-000070: the figures to
report) in several conditions:

* natural: the files end to end as recorded (their own leading and trailing silence);
* zeros: each file cut to its reference speech (first syllable start - EDGE to last syllable
  end + EDGE) and joined with GAP seconds of exact digital zeros (also before and after), as
  edited recordings, joined files and TTS often are;
* gate: the natural join through a noise gate: whatever stays below GATE_DB of the peak for
  longer than GATE_HOLD is multiplied by GATE_FLOOR (speech, then near-zero);
* dc: the natural join plus a DC offset of DC;
* -40 dB: the natural join scaled to a peak of -40 dBFS and stored as 16-bit;
* clipped: the natural join amplified by CLIP_GAIN and clipped to [-1, 1];
* 8-bit: the natural join written as an 8-bit unsigned WAV and read back by load_audio.

For each: `alignment.analyse` with the transcript (each sentence ended by 。), the share of
syllable onsets within 50 ms of the reference (sentences whose syllable count differs from the
reference are left out, as in bench/segment.py), how many frames at 30 fps show an open mouth
(anything but pure `m`) inside the reference's silences (farther than QUIET_MARGIN from any
reference syllable), and the fewest frames the lips stay closed at the start of a b/p/m
syllable.
"""

from __future__ import annotations

import csv
import io
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import soundfile

from bench.align import read_tiers
from cartoonface.animate.frames import sample_frames
from cartoonface.animate.timeline import build_timeline
from cartoonface.speech.analyse import analyse
from cartoonface.speech.records import Alignment
from cartoonface.speech.audio import Audio, load_audio

ZH = Path(__file__).resolve().parents[1].parent / "shared" / "bench" / "zh"
DEV = range(1, 36)        # Biaobei 000001-000035: tuning (bench/align.py TUNING)
HELD_OUT = range(36, 71)  # Biaobei 000036-000070: reported
EDGE = 0.05               # seconds of the file kept around its reference speech in the zeros join
GAP = 0.3                 # seconds of exact zeros between (and around) the sentences
GATE_DB = -40.0           # noise gate threshold, dB below the peak (10 ms RMS)
GATE_HOLD = 0.05          # seconds the level must stay below the threshold before the gate closes
GATE_FLOOR = 1e-4         # gain of the closed gate (-80 dB)
DC = 0.1                  # DC offset added, full scale
QUIET_DB = -40.0          # peak level of the quiet condition, dBFS
CLIP_GAIN = 4.0           # gain before clipping
FPS = 30
QUIET_MARGIN = 0.12       # seconds: frames closer than this to a reference syllable may be moving
LIMIT = 0.05              # seconds: an onset within this of the reference is right
SILENCE = {"sil", "sp", ""}
OPENNESS = ("a", "o", "h", "n", "u", "h'", "r", "e", "z", "i")  # by lip gap dn - up (MNS0), face/mouth.py MOUTH_SHAPES


@dataclass(frozen=True)
class Sentence:
    """One Biaobei file: samples, transcript sentence, reference syllables (start, end, pinyin)."""

    samples: np.ndarray
    rate: int
    text: str
    syllables: tuple[tuple[float, float, str], ...]
    final: tuple[float, float]  # reference start and end of the last syllable's final (vowel)


def sentences(ids: range) -> list[Sentence]:
    folder = ZH / "biaobei"
    rows = {int(row["id"]): row for row in csv.DictReader((folder / "transcripts.tsv").open(encoding="utf-8"), delimiter="\t")}
    out = []
    for number in ids:
        row = rows[number]
        audio = load_audio(folder / "wav" / f"{row['id']}.wav")
        tier = read_tiers(folder / "TextGrid" / f"{row['id']}.TextGrid")["syllables_pinyin"]
        syllables = tuple((a, b, t) for a, b, t in tier if t not in SILENCE)
        phones = read_tiers(folder / "TextGrid" / f"{row['id']}.TextGrid")["phones"]
        final = next((a, b) for a, b, t in reversed(phones) if t not in SILENCE)
        out.append(Sentence(audio.samples, audio.rate, row["hanzi_meta"].rstrip(".") + "。", syllables, final))
    return out


@dataclass(frozen=True)
class Joined:
    """A joined recording and its reference syllables (start, end, pinyin) per sentence on its clock."""

    audio: Audio
    text: str
    references: tuple[tuple[tuple[float, float, str], ...], ...]
    finals: tuple[tuple[float, float], ...]


def join(items: list[Sentence], zeros: bool) -> Joined:
    """The sentences end to end as recorded, or cut to their speech and separated by GAP s of zeros."""
    rate = items[0].rate
    pieces, references, finals, position = [], [], [], 0.0
    gap = np.zeros(round(GAP * rate), dtype=np.float32)
    if zeros:
        pieces.append(gap)
        position += GAP
    for item in items:
        offset = 0.0
        samples = item.samples
        if zeros:
            first = max(0, int((item.syllables[0][0] - EDGE) * rate))
            last = min(len(samples), int((item.syllables[-1][1] + EDGE) * rate))
            samples, offset = samples[first:last], first / rate
        references.append(tuple((a - offset + position, b - offset + position, p) for a, b, p in item.syllables))
        finals.append((item.final[0] - offset + position, item.final[1] - offset + position))
        pieces.append(samples)
        position += len(samples) / rate
        if zeros:
            pieces.append(gap)
            position += GAP
    audio = Audio(np.concatenate(pieces).astype(np.float32), rate, "joined")
    return Joined(audio, "".join(item.text for item in items), tuple(references), tuple(finals))


def gated(audio: Audio) -> Audio:
    """`audio` through a noise gate (GATE_DB, GATE_HOLD, GATE_FLOOR), switched per 10 ms frame."""
    hop = audio.rate // 100
    count = len(audio.samples) // hop
    frames = audio.samples[: count * hop].reshape(count, hop)
    level = 10 * np.log10(np.mean(np.square(frames, dtype=np.float64), axis=1) + 1e-20)
    below = level < 20 * np.log10(np.abs(audio.samples).max()) + GATE_DB
    hold = round(GATE_HOLD * 100)
    closed = np.zeros(count, dtype=bool)
    run = 0
    for k, quiet in enumerate(below):
        run = run + 1 if quiet else 0
        closed[k] = run > hold
    gain = np.repeat(np.where(closed, GATE_FLOOR, 1.0), hop)
    samples = audio.samples.copy()
    samples[: count * hop] *= gain.astype(np.float32)
    return Audio(samples, audio.rate, "gated")


def stored(samples: np.ndarray, rate: int, subtype: str, folder: Path) -> Audio:
    """`samples` written as a WAV of `subtype` (FLOAT, PCM_16, PCM_U8) and read back by load_audio."""
    path = folder / "condition.wav"
    buffer = io.BytesIO()
    soundfile.write(buffer, np.clip(samples, -1, 1), rate, subtype=subtype, format="WAV")
    path.write_bytes(buffer.getvalue())
    return load_audio(path)


def conditions(items: list[Sentence], folder: Path) -> dict[str, Joined]:
    """Every condition of the module docstring, each stored as a WAV file and read back by load_audio."""
    natural, zeros = join(items, zeros=False), join(items, zeros=True)
    samples, rate = natural.audio.samples, natural.audio.rate
    peak = float(np.abs(samples).max())
    made = {
        "natural": (natural, samples, "FLOAT"),
        "zeros": (zeros, zeros.audio.samples, "FLOAT"),
        "gate": (natural, gated(natural.audio).samples, "FLOAT"),
        "dc": (natural, samples + DC, "FLOAT"),
        "-40 dB": (natural, samples * (10 ** (QUIET_DB / 20) / peak), "PCM_16"),
        "clipped": (natural, samples * CLIP_GAIN, "FLOAT"),
        "8-bit": (natural, samples, "PCM_U8"),
    }
    return {label: Joined(stored(x, rate, subtype, folder), joined.text, joined.references, joined.finals)
            for label, (joined, x, subtype) in made.items()}


def onset_share(alignment: Alignment, joined: Joined) -> tuple[float, int, int]:
    """(share of onsets within LIMIT, onsets scored, sentences left out)."""
    errors, left_out = [], 0
    for sentence, reference in zip(alignment.sentences, joined.references, strict=True):
        if len(sentence.syllables) != len(reference):
            left_out += 1
            continue
        errors += [abs(s.start - r[0]) for s, r in zip(sentence.syllables, reference, strict=True)]
    values = np.round(np.array(errors), 6)
    return float(np.mean(values <= LIMIT)), len(values), left_out


def mouth_figures(alignment: Alignment, joined: Joined) -> tuple[int, int, int]:
    """(open frames in silence, silent frames, fewest closed frames at a b/p/m onset).

    Silence: frames farther than QUIET_MARGIN from every reference syllable. Closed: the
    mouth shows pure `m`; counted over the run of closed frames that holds the frame nearest
    the aligned syllable's start (0 when that frame is open).
    """
    states = sample_frames(build_timeline(alignment, ()), FPS)
    times = np.arange(len(states)) / FPS
    closed = np.array([s.mouth == (("m", 1.0),) for s in states])
    busy = np.zeros(len(states), dtype=bool)
    for reference in joined.references:
        for start, end, _ in reference:
            busy |= (times > start - QUIET_MARGIN) & (times < end + QUIET_MARGIN)
    quiet = ~busy
    shortest = []
    for sentence in alignment.sentences:
        for syllable in sentence.syllables:
            if syllable.pinyin[:1] not in ("b", "p", "m") or syllable.shapes[0] != "m":
                continue
            k = int(np.argmin(np.abs(times - syllable.start)))
            near = [j for j in (k - 1, k, k + 1) if 0 <= j < len(states) and closed[j]]
            if not near:
                shortest.append(0)
                continue
            left = right = near[0]
            while left > 0 and closed[left - 1]:
                left -= 1
            while right + 1 < len(states) and closed[right + 1]:
                right += 1
            shortest.append(right - left + 1)
    return int(np.sum(quiet & ~closed)), int(np.sum(quiet)), min(shortest, default=0)


def final_vowels(alignment: Alignment, joined: Joined) -> tuple[int, int, float]:
    """(late, count, median ms): over the sentence-final syllables whose widest shape (the first
    of its shapes in OPENNESS order) is not their first shape, how many reach it (its key frame
    on the timeline's mouth track) after the middle of the reference final (the vowel), how many
    such syllables there are, and the median time from the middle of the final to that key."""
    mouth = build_timeline(alignment, ()).track("mouth")
    late, offsets = 0, []
    for sentence, (first, last) in zip(alignment.sentences, joined.finals, strict=True):
        syllable = sentence.syllables[-1]
        wide = next((shape for shape in OPENNESS if shape in syllable.shapes), None)
        if wide is None or wide == syllable.shapes[0]:
            continue
        key = next(k.t / 1000 for k in mouth.keys if k.value == wide and k.t / 1000 >= syllable.start - 1e-3)
        offsets.append(1000 * (key - (first + last) / 2))
        late += offsets[-1] > 0
    return late, len(offsets), float(np.median(offsets)) if offsets else float("nan")


def report(name: str, ids: range, folder: Path) -> None:
    items = sentences(ids)
    print(f"{name} (Biaobei {ids.start:06d}-{ids.stop - 1:06d}): onsets within {LIMIT * 1000:.0f} ms, "
          f"open-mouth frames in silence at {FPS} fps, fewest closed frames at b/p/m")
    base = None
    for label, joined in conditions(items, folder).items():
        started = time.perf_counter()
        alignment = analyse(joined.audio, joined.text)
        seconds = time.perf_counter() - started
        share, count, left_out = onset_share(alignment, joined)
        base = share if base is None else base
        opened, quiet, shortest = mouth_figures(alignment, joined)
        late, finals, offset = final_vowels(alignment, joined)
        print(f"  {label:<8} {100 * share:5.1f}% ({100 * (share - base):+5.1f}) of {count} onsets"
              f" ({left_out} sentences left out); open {opened}/{quiet} silent frames; "
              f"b/p/m closed >= {shortest} frames; sentence-final widest shape after the vowel's middle "
              f"{late}/{finals} (median {offset:+.0f} ms); {joined.audio.duration / seconds:.0f}x real time", flush=True)


def main() -> None:
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        report("held-out", HELD_OUT, Path(folder))
        report("dev", DEV, Path(folder))


if __name__ == "__main__":
    main()
