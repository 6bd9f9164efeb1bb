"""WebVTT captions of the sentences (W3C WebVTT: a header line, then one cue per sentence)."""

from __future__ import annotations

from cartoonface.speech.records import Alignment

CAPTIONS_NAME = "captions.vtt"
MILLISECONDS = 1000


def vtt_time(seconds: float) -> str:
    """Seconds -> WebVTT timestamp hh:mm:ss.ttt (whole milliseconds)."""
    total = round(seconds * MILLISECONDS)
    hours, rest = divmod(total, 3600 * MILLISECONDS)
    minutes, rest = divmod(rest, 60 * MILLISECONDS)
    whole, millis = divmod(rest, MILLISECONDS)
    return f"{hours:02d}:{minutes:02d}:{whole:02d}.{millis:03d}"


def _cue_text(text: str) -> str:
    """A sentence as cue text: &, < and > escaped (so no '-->'), lines joined by spaces."""
    flat = " ".join(text.split())
    return flat.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def captions_vtt(alignment: Alignment) -> str:
    """The alignment's sentences as a WebVTT file's text: one numbered cue per sentence from its
    start to its end (a sentence that lasts under a millisecond is left out)."""
    blocks = ["WEBVTT"]
    for sentence in alignment.sentences:
        start, end = vtt_time(sentence.start), vtt_time(sentence.end)
        if end <= start:
            continue
        blocks.append(f"{len(blocks)}\n{start} --> {end}\n{_cue_text(sentence.text)}")
    return "\n\n".join(blocks) + "\n"
