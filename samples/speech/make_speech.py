"""Regenerate the sample speech `story.wav` from the transcript `story.txt`.

Run from the project root: `.venv/bin/python samples/speech/make_speech.py`.
The voice is Debian's espeak-ng reading the Hanzi with its Mandarin-as-pinyin
voice (`cmn-latn-pinyin`; plain `cmn` misreads Hanzi in espeak-ng 1.51, see
/work/shared/DEPENDENCIES.md), a female variant at 150 words a minute, one sentence after another so
espeak-ng puts its sentence pauses between them. espeak-ng is deterministic:
the same text gives the same file.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

HERE = Path(__file__).resolve().parent
VOICE = "cmn-latn-pinyin+f3"
RATE = 150  # words a minute (espeak-ng -s)


def main() -> None:
    """Synthesise story.txt (one sentence a line) to story.wav beside it."""
    text = (HERE / "story.txt").read_text(encoding="utf-8")
    sentences = " ".join(line.strip() for line in text.splitlines() if line.strip())
    subprocess.run(
        ["espeak-ng", "-v", VOICE, "-s", str(RATE),
         "-w", str(HERE / "story.wav"), sentences],
        check=True,
    )
    print(HERE / "story.wav")


if __name__ == "__main__":
    main()
