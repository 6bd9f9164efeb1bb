"""`cartoonface align`: recording + transcript -> Praat TextGrid (and JSON) of sentences, syllables, mouth shapes.

A thin shell over `cartoonface.speech.analyse.analyse`: progress on
stderr, notes on stderr, a one-line summary on stdout. docs/alignment.md
describes the outputs.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

from cartoonface.cli.progress import ProgressBar
from cartoonface.errors import OptionError, TranscriptError
from cartoonface.files import read_user_text, write_text_atomic

if TYPE_CHECKING:
    from cartoonface.speech.records import Alignment

HELP = "time the sentences, syllables and mouth shapes of a recording (Praat TextGrid)"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `align` subcommand."""
    from cartoonface.exports.cues import FORMATS as CUE_FORMATS
    from cartoonface.speech.english import LANGUAGES

    parser = subparsers.add_parser(
        "align", help=HELP,
        description="Find when every sentence and syllable of the transcript is spoken in the recording and "
                    "which mouth shapes each syllable uses; write a Praat TextGrid (tiers sentences, syllables, "
                    "mouth shapes) that can be corrected in Praat and given back to `generate --alignment`.")
    parser.add_argument("audio", type=Path, metavar="AUDIO",
                        help="the recording: WAV, MP3, OGG, M4A or FLAC, at most 30 minutes")
    parser.add_argument("--transcript", type=Path, metavar="TEXT.txt",
                        help="what is said, UTF-8 text (Chinese or English; sentences end with punctuation); "
                             "without it the mouth shapes come from the audio alone (loudness and formants)")
    parser.add_argument("-o", "--output", type=Path, required=True, metavar="OUT.TextGrid", help="TextGrid to write")
    parser.add_argument("--json", type=Path, metavar="OUT.json", help="also write the alignment as JSON")
    parser.add_argument("--cues", action="append", default=[], choices=CUE_FORMATS,
                        help="also write the mouth cues in Rhubarb Lip Sync's format beside the TextGrid "
                             "(OUT.tsv, OUT.json or OUT.xml; repeatable; docs/exports.md)")
    parser.add_argument("--pause", metavar="START,END",
                        help="seconds of the first pause between sentences: segment with the thesis's "
                             "thresholds learned from it (Alg. 3.1) instead of the automatic ones")
    parser.add_argument("--language", choices=LANGUAGES, default=None,
                        help="language of the transcript and speech (default: found from its script)")
    parser.set_defaults(func=run)


def parse_pause(text: str | None) -> tuple[float, float] | None:
    """'START,END' -> (start, end) seconds, None for None; OptionError when it is not two numbers.
    Shared by `align --pause` and `generate --pause`."""
    if text is None:
        return None
    try:
        start, end = (float(value) for value in text.split(","))
    except ValueError:
        raise OptionError(f"--pause {text!r}: expected START,END in seconds, e.g. 2.1,2.8") from None
    return start, end


def check_output(path: Path, option: str) -> None:
    """OptionError when an output path is an existing folder."""
    if path.is_dir():
        raise OptionError(f"{option} {path}: is a folder; expected a file name")


def summary(alignment: Alignment, output: Path, seconds: float) -> str:
    """The one-line report of a finished alignment."""
    from cartoonface.speech.analyse import LOW_CONFIDENCE

    from cartoonface.speech.textgrid import is_english

    syllables = [s for sentence in alignment.sentences for s in sentence.syllables]
    low = sum(s.confidence < LOW_CONFIDENCE for s in syllables)
    counted = (f"{_count(sum(bool(s.text) for s in syllables), 'word')}, {_count(len(syllables), 'phone')}"
               if is_english(alignment) else _count(len(syllables), 'syllable'))
    return (
        f"{output}: {_count(len(alignment.sentences), 'sentence')}, {counted} "
        f"({low} with low confidence) in {alignment.duration:.1f} s of audio, "
        f"{_count(len(alignment.notes), 'note')}; took {seconds:.1f} s"
    )


def _count(number: int, noun: str) -> str:
    """'1 note', '3 notes'."""
    return f"{number} {noun}{'' if number == 1 else 's'}"


def run(args: argparse.Namespace) -> int:
    """Align the recording with its transcript and write the outputs; returns 0."""
    from cartoonface.exports.cues import cues_text, mouth_cues
    from cartoonface.speech.analyse import analyse
    from cartoonface.speech.audio import load_audio
    from cartoonface.speech.records import alignment_to_dict
    from cartoonface.speech.textgrid import write_textgrid

    started = time.perf_counter()
    pause = parse_pause(args.pause)
    check_output(args.output, "-o")
    if args.json is not None:
        check_output(args.json, "--json")
    cue_files = {fmt: args.output.with_suffix(f".{fmt}") for fmt in dict.fromkeys(args.cues)}
    for path in cue_files.values():
        check_output(path, "--cues")
        if path in (args.output, args.json):
            raise OptionError(f"--cues {path.suffix[1:]}: would write {path}, which is already an output; "
                              "give -o a name ending in .TextGrid")
    text = None if args.transcript is None else read_user_text(args.transcript, TranscriptError, "transcript file")
    shown = ProgressBar(sys.stderr)
    try:
        shown("decode", 0.0)
        audio = load_audio(args.audio)
        alignment = analyse(audio, text, pause=pause, progress=shown, source=str(args.transcript or "transcript"),
                            language=args.language)
    finally:
        shown.close()
    write_text_atomic(args.output, write_textgrid(alignment))
    if args.json is not None:
        write_text_atomic(args.json, json.dumps(alignment_to_dict(alignment), ensure_ascii=False, indent=1) + "\n")
    cues = mouth_cues(alignment)
    for fmt, path in cue_files.items():
        write_text_atomic(path, cues_text(cues, alignment.duration, fmt, args.audio.name))
    for note in alignment.notes:
        print(f"note: {note}", file=sys.stderr)
    print(summary(alignment, args.output, time.perf_counter() - started))
    return 0
