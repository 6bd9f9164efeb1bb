"""Pitch peaks with other time steps of Praat's To Pitch (ac), against the method's own noise.

`prosody.pitch_peaks` (the accent peaks that raise the brows and nod the head) picks, per syllable,
the frame of highest F0; on a flat top which frame that is depends on where the frames fall. So a
change of step is judged against the same step with its frames moved: the 20 ms step (the setting
before issue 16's seventh session) is the reference, and compared with
- itself, its frames moved by 5 and by 10 ms (half a step): how much the peaks change by where the
  frames fall alone, the noise any step has;
- 30 and 40 ms steps, and 40 ms with its frames moved by 20 ms (half of its step).
Per setting: peaks added / removed / moved (the same syllable's peak at another time), the
syllables that peak in one setting only (added + removed) as a share of all, the moves past a frame
at 30 fps, the largest move; and the track's CPU on the 190 s
book (median of 3). The recordings and their halves are bench/pitch_candidates.py's (85 recordings
sorted by name: even positions tune, odd ones held out; the 190 s book on its own).

Run: `.venv/bin/python -m bench pitch_step` from the project root (~1 minute).
"""

from __future__ import annotations

from bench.pitch_candidates import Item, aligned_items, compare, cpu

REFERENCE = "20 ms"
# name -> bench/pitch_candidates.track's keywords: time step and frame shift (s)
SETTINGS: dict[object, dict[str, float]] = {
    REFERENCE: {"step": 0.02},
    "20 ms, frames moved 5 ms": {"step": 0.02, "shift": 0.005},
    "20 ms, frames moved 10 ms": {"step": 0.02, "shift": 0.01},
    "30 ms": {"step": 0.03},
    "40 ms": {"step": 0.04},
    "40 ms, frames moved 20 ms": {"step": 0.04, "shift": 0.02},
    "speech/pitch.py, 40 ms": {"step": 0.04, "ours": True},
    "speech/pitch.py, 40 ms, frames moved 20 ms": {"step": 0.04, "shift": 0.02, "ours": True},
}


def table(title: str, items: list[Item], book: Item | None) -> None:
    """Print the figures of every setting against REFERENCE on `items` (with CPU on `book`'s audio)."""
    print(f"{title}: {len(items)} recordings")
    print("| setting | added / removed / moved | peaking in one only, share of syllables | moved past a frame | largest move | track CPU, 190 s |")
    print("| --- | --- | --- | --- | --- | --- |")
    for name, keywords in SETTINGS.items():
        c = compare(items, name, REFERENCE)
        spent = (f"{cpu(book.audio, step=keywords['step'], ours=bool(keywords.get('ours'))):.3f} s"
                 if book is not None and "shift" not in keywords else "")
        print(f"| {name} | {c['added']} / {c['removed']} / {c['moved']} | {100 * (c['added'] + c['removed']) / c['syllables']:.1f} % of "
              f"{c['syllables']} ({c['peaks']} peaks at {REFERENCE}) | {c['past_frame']} | "
              f"{1000 * c['max_shift']:.0f} ms | {spent} |")


def main() -> None:
    """Align every recording, compare the peaks per setting, print the tuning, held-out and book tables."""
    distinct, book = aligned_items(SETTINGS)
    table("tuning half (even positions)", distinct[0::2], None)
    table("held-out half (odd positions)", distinct[1::2], None)
    table("the 190 s book", [book], book)


if __name__ == "__main__":
    main()
