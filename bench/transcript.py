"""Transcript readings against the reference pinyin of the real Mandarin sets, and speed.

Biaobei's `syllables_std_pinyin` has the surface tones (after 3-3 sandhi and the 一/不
changes) and erhua as one syllable, so it checks readings, tone changes and syllable counts.
THCHS-30 and AISHELL-3 give citation tones: only the toneless readings and the counts are
compared there. Baseline: pypinyin alone on the same text (phrase aware, no Traditional
conversion needed, no sandhi, erhua, numbers), one reading per Hanzi.
"""

from __future__ import annotations

import csv
import difflib
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

from pypinyin import Style, lazy_pinyin

from cartoonface.speech.transcript import parse_transcript

DATA = Path(__file__).resolve().parent.parent.parent / "shared" / "bench" / "zh"
_HAN = re.compile(r"[\u4e00-\u9fff]")


def _rows(name: str) -> list[dict[str, str]]:
    with open(DATA / name / "transcripts.tsv", encoding="utf-8") as handle:
        return list(csv.DictReader(handle, delimiter="\t"))


def _ours(text: str) -> list[str]:
    return [s.pinyin for sentence in parse_transcript(text) for s in sentence.syllables]


def _baseline(text: str) -> list[str]:
    hans = "".join(_HAN.findall(text))
    return lazy_pinyin(hans, style=Style.TONE3, neutral_tone_with_five=True, v_to_u=True)


def _norm(pinyin: str, tone: bool) -> str:
    pinyin = pinyin.replace("v", "ü")
    return pinyin if tone else pinyin.rstrip("12345")


def _score(pairs: list[tuple[list[str], list[str]]], tone: bool) -> tuple[float, float]:
    """(share of sentences with the reference's syllable count, share of matching syllables)."""
    same_count = sum(len(ours) == len(ref) for ours, ref in pairs) / len(pairs)
    hits = total = 0
    for ours, ref in pairs:
        a = [_norm(p, tone) for p in ours]
        b = [_norm(p, tone) for p in ref]
        hits += sum(block.size for block in difflib.SequenceMatcher(None, a, b).get_matching_blocks())
        total += len(b)
    return same_count, hits / total


def _report(name: str, texts: list[str], refs: list[list[str]], tone: bool) -> None:
    for label, read in (("ours", _ours), ("pypinyin alone", _baseline)):
        pairs = [(read(t), r) for t, r in zip(texts, refs)]
        count, toneless = _score(pairs, tone=False)
        line = (f"{name:10s} {label:15s} sentences {len(texts):3d}  same count {count:6.1%}  "
                f"syllables right (toneless) {toneless:6.1%}")
        if tone:
            line += f"  (with surface tone) {_score(pairs, tone=True)[1]:6.1%}"
        print(line)


def main() -> None:
    """Print reading accuracy per set and the parsing speed in characters per second."""
    biaobei = _rows("biaobei")
    texts = [r["hanzi_meta"] for r in biaobei]
    _report("biaobei", texts, [r["syllables_std_pinyin"].split() for r in biaobei], tone=True)
    thchs = [r for r in _rows("thchs30_mfa_example") if r["hanzi"].strip()]
    refs = [re.findall(r"[a-zü]+[1-5]", r["pinyin_words"]) for r in thchs]
    _report("thchs30", [r["hanzi"] for r in thchs], refs, tone=False)
    aishell = _rows("aishell3_charsiu")
    _report("aishell3", [r["hanzi"] for r in aishell], [r["pinyin"].split() for r in aishell], tone=False)

    parse_transcript("你好。")   # dictionaries loaded once, as in a running process
    text = "".join(texts) * 20
    times = []
    for _ in range(5):
        started = time.perf_counter()
        parse_transcript(text)
        times.append(time.perf_counter() - started)
    chars = len(_HAN.findall(text))
    print(f"speed: {chars} Hanzi in {statistics.median(times):.2f} s (median of 5): "
          f"{chars / statistics.median(times):,.0f} Hanzi/s")
    started = time.perf_counter()
    subprocess.run([sys.executable, "-c", "from cartoonface.speech.transcript import parse_transcript;"
                    "parse_transcript('你好。')"], check=True)
    print(f"cold start (new Python process, import + first sentence): "
          f"{time.perf_counter() - started:.2f} s")
