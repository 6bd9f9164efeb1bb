"""`make demo` (`python -m cartoonface.demo`): the sample audio book from samples/ into out/demo/.

Uses the first sample face model (cartoonface/data/faces, sorted by name), the speech
samples/speech/story.wav and its transcript story.txt (made by
samples/speech/make_speech.py), and prints the page to open.
"""

from __future__ import annotations

import sys
from pathlib import Path

from cartoonface.cli.generate import summary
from cartoonface.data import SAMPLE_FACES
from cartoonface.cli.progress import ProgressBar
from cartoonface.errors import InputError
from cartoonface.pipeline import Options, generate

ROOT = Path(__file__).resolve().parent.parent
SAMPLES = ROOT / "samples"
OUT = ROOT / "out" / "demo"
TITLE = "小白兔和月亮"  # the sample story: "The little white rabbit and the moon"


def main() -> int:
    """Generate out/demo/ and print its index.html as a file:// URL; 2 on bad samples."""
    faces = sorted(SAMPLE_FACES.glob("*.json"))
    if not faces:
        print(f"cartoonface demo: no face model in {SAMPLE_FACES}", file=sys.stderr)
        return 2
    speech = SAMPLES / "speech"
    options = Options(page="audiobook", title=TITLE,
                      links=(("The thesis's audio book (ch. 7.3)", "https://en.wikipedia.org/wiki/Audiobook"),))
    bar = ProgressBar(sys.stderr)
    try:
        result = generate(faces[0], speech / "story.wav", speech / "story.txt", OUT, options, bar)
    except InputError as exc:
        bar.close()
        print(f"cartoonface demo: error: {exc}", file=sys.stderr)
        return 2
    print(summary(result))
    print(f"Open {(OUT / 'index.html').as_uri()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
