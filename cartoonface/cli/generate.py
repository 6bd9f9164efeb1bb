"""`cartoonface generate`: face model + recording + transcript -> page folder.

A thin shell over `cartoonface.pipeline.generate`: parses the options, shows a
progress bar on stderr and prints a one-line summary on stdout.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from cartoonface.animate.style import PAGE_STYLES, STYLES
from cartoonface.cli.align import parse_pause
from cartoonface.cli.progress import ProgressBar
from cartoonface.errors import OptionError

if TYPE_CHECKING:
    from collections.abc import Callable

    import numpy as np

    from cartoonface.pipeline import Result

    Pitch = Callable[[], tuple[np.ndarray, np.ndarray]]

HELP = "make the talking-face pages from a face, a recording (or a video) and its transcript"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `generate` subcommand."""
    from cartoonface.exports.cues import FORMATS as CUE_FORMATS
    from cartoonface.face.emotion import EMOTIONS
    from cartoonface.pipeline import Options
    from cartoonface.render.pages import PAGES
    from cartoonface.render.scenery import BACKGROUNDS, CLOTHES
    from cartoonface.speech.english import LANGUAGES

    defaults = Options()
    parser = subparsers.add_parser(
        "generate", help=HELP,
        description="Make a folder with index.html (audio book or virtual announcer), animation.svg, the "
                    "audio, alignment.TextGrid and actions.json. Open index.html in a browser (docs/output.md).")
    parser.add_argument("--face", type=Path, required=True, metavar="FACE.json", help="face model (docs/face-model.md)")
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--audio", type=Path, metavar="SPEECH",
                        help="the recording: WAV, MP3, OGG, M4A or FLAC, at most 30 minutes")
    source.add_argument("--video", type=Path, metavar="CLIP",
                        help="instead of --audio: a video of a person talking (MP4, WebM, MOV or MPEG-1, at most "
                             "10 minutes); the cartoon moves its head, eyes, brows and mouth as the person does and "
                             "the page plays the clip's sound (docs/video.md)")
    parser.add_argument("--transcript", type=Path, metavar="TEXT.txt",
                        help="what is said, UTF-8 text; without it the lip sync comes from the audio alone "
                             "and the page shows no text")
    parser.add_argument("-o", "--output", type=Path, required=True, metavar="OUTDIR",
                        help="folder to write (replaced if it holds a previous output)")
    parser.add_argument("--page", choices=PAGES, default=defaults.page, help="page kind (default %(default)s)")
    parser.add_argument("--title", default=defaults.title, help="page title")
    parser.add_argument("--fps", type=int, default=defaults.fps, help="frames per second, 12-60 (default %(default)s)")
    parser.add_argument("--seed", type=int, default=defaults.seed,
                        help="seed of the blinks and head movements (default %(default)s)")
    page_defaults = ", ".join(f"{page}: {style}" for page, style in PAGE_STYLES.items())
    parser.add_argument("--style", choices=STYLES, default=None,
                        help=f"performance: how much the head, eyes, brows and smile move (default by page: {page_defaults})")
    parser.add_argument("--actions", type=Path, metavar="ACTIONS.json",
                        help="an edited actions.json to use instead of a new schedule (docs/actions.md)")
    parser.add_argument("--alignment", type=Path, metavar="EDITED.TextGrid",
                        help="an edited alignment.TextGrid to use instead of aligning again")
    parser.add_argument("--background", choices=BACKGROUNDS, default=defaults.background,
                        help="backdrop (default %(default)s)")
    parser.add_argument("--clothes", choices=CLOTHES, default=defaults.clothes, help="clothes (default %(default)s)")
    parser.add_argument("--emotion", choices=EMOTIONS, default=None,
                        help="default mood where the transcript's [emotion] marks set none (docs/emotions.md)")
    parser.add_argument("--intensity", type=float, default=defaults.intensity, metavar="X",
                        help="intensity of the --emotion, 0..1 (default %(default)s)")
    parser.add_argument("--pause", metavar="S,E",
                        help="a stretch of pure silence in the recording (start,end seconds): sentence "
                             "segmentation then uses the thesis's threshold from it (Alg. 3.1)")
    parser.add_argument("--language", choices=LANGUAGES, default=None,
                        help="language of the transcript and speech (default: found from its script)")
    parser.add_argument("--link", action="append", default=[], metavar="LABEL=URL",
                        help="a link under the audio-book text (repeatable)")
    parser.add_argument("--mp4", type=Path, metavar="OUT.mp4",
                        help="also render the animation with its sound as an MP4 video (H.264 + AAC) at --fps")
    parser.add_argument("--size", default="1280x720", metavar="WxH",
                        help="the MP4's size in pixels (default %(default)s); the picture is centred on it")
    parser.add_argument("--keep-original", action="store_true",
                        help="also put the recording as given into the folder (recording.EXT); the page "
                             "plays a compressed copy, audio.m4a")
    parser.add_argument("--cues", action="append", default=[], choices=CUE_FORMATS,
                        help="also write the mouth cues as mouth-cues.FORMAT in Rhubarb Lip Sync's format "
                             "(repeatable; docs/exports.md)")
    parser.set_defaults(func=run)


def begun(argv: list[str]) -> tuple[Path, Pitch] | None:
    """(recording, getter of its pitch track) for `generate`'s arguments `argv` when they name a
    recording (--audio PATH or --audio=PATH) and no edited actions (--actions, which need no track):
    prosody.recording_pitch computed in a child forked now (workers.forked), before this process
    imports the library (~0.2 s with the second core idle), so the track, the largest piece of the
    analysis (0.5-0.6 s of CPU for 3 minutes), is mostly done before the analysis begins. None
    otherwise. `run` uses it only for the recording its parsed arguments name."""
    from cartoonface.workers import forked, processes  # light (multiprocessing); numpy is imported in the child

    named: dict[str, str] = {}
    for flag, following in zip(argv, [*argv[1:], ""]):
        name, equals, value = flag.partition("=")
        if name in ("--audio", "--actions"):
            named[name] = value if equals else following
    if not named.get("--audio") or "--actions" in named:
        return None
    recording = Path(named["--audio"])
    return recording, forked(processes(), _recording_pitch, recording)


def _recording_pitch(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """prosody.recording_pitch, imported where it runs (begun's child: not in this process before its fork)."""
    from cartoonface.animate.prosody import recording_pitch

    return recording_pitch(path)


def parse_link(text: str) -> tuple[str, str]:
    """'LABEL=URL' -> (label, url); OptionError without '='."""
    label, sep, url = text.partition("=")
    if not sep:
        raise OptionError(f"--link {text!r}: expected LABEL=URL")
    return label, url


def check_mp4_path(path: Path) -> None:
    """OptionError unless `path` names an .mp4 file that can be written (its folder exists)."""
    if path.suffix.lower() != ".mp4":
        raise OptionError(f"--mp4 {path}: expected a file name ending in .mp4")
    if path.is_dir() or not path.absolute().parent.is_dir():
        raise OptionError(f"--mp4 {path}: expected an .mp4 file name in an existing folder")


def summary(result: Result) -> str:
    """The one-line report of a finished run."""
    return (f"{result.out_dir}: {result.duration:.1f} s of audio, {result.frames} frames, "
            f"{result.size / 1e6:.1f} MB written in {result.seconds:.1f} s; open {result.out_dir / 'index.html'}")


def run(args: argparse.Namespace) -> int:
    """Generate the folder; print the summary and any notes. Returns 0."""
    from cartoonface.exports.video import parse_size, write_site_video
    from cartoonface.pipeline import Options, generate

    options = Options(
        page=args.page, title=args.title, fps=args.fps, seed=args.seed, style=args.style, background=args.background,
        clothes=args.clothes, actions=args.actions, alignment=args.alignment, pause=parse_pause(args.pause),
        links=tuple(parse_link(link) for link in args.link), emotion=args.emotion, intensity=args.intensity,
        cues=tuple(dict.fromkeys(args.cues)), keep_original=args.keep_original, language=args.language,
    )
    size = parse_size(args.size)
    if args.mp4 is not None:
        check_mp4_path(args.mp4)
    bar = ProgressBar(sys.stderr)
    try:
        early = getattr(args, "begun", None)
        pitch = early[1] if early is not None and early[0] == args.audio else None
        result = generate(args.face, args.audio, args.transcript, args.output, options, bar, video=args.video,
                          pitch=pitch)
        if args.mp4 is not None:
            write_site_video(result.out_dir, options.fps, result.duration, args.audio, args.mp4, size, bar)
    finally:
        bar.close()
    for note in result.notes:
        print(f"note: {note}", file=sys.stderr)
    print(summary(result))
    return 0
