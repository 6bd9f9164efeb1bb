"""The published output folder: the audio-book and virtual-announcer pages (thesis 002, ch. 7).

`page_html` fills a Jinja template from `templates/` (autoescape on: every
user text is escaped) with the animation SVG inline, so the page script can
drive its SMIL clock from the `<audio>` element even when the page is opened
from `file://` (an `<object>`/`<embed>` document is another origin there and
cannot be reached by the script). `write_site` writes the folder: index.html,
animation.svg, static/ (CSS and the sync script), the audio, alignment.TextGrid
and actions.json. docs/output.md describes the folder and the page behaviour.
"""

from __future__ import annotations

import base64
import functools
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import urlsplit

import jinja2
from markupsafe import Markup

from cartoonface import __version__
from cartoonface.errors import OptionError
from cartoonface.files import write_bytes_atomic
from cartoonface.render.animation import PARTS_ID
from cartoonface.render.moved import moved_tracks
from cartoonface.speech.records import Alignment
from cartoonface.speech.audio import page_copy
from cartoonface.speech.audio_only import transcribed

PAGES = ("audiobook", "announcer")
# Inside the package (a symlink to the top-level folders in a source checkout,
# real folders in the wheel): see pyproject.toml package-data.
PACKAGE = Path(__file__).resolve().parent.parent
TEMPLATES = PACKAGE / "templates"
STATIC = PACKAGE / "static"
AUDIO_STEM = "audio"
# The recording as given, kept beside the page audio on request (copy_audio keep_original).
ORIGINAL_STEM = "recording"
MEDIA_TYPES = {
    ".wav": "audio/wav",
    ".mp3": "audio/mpeg",
    ".m4a": "audio/mp4",
    ".aac": "audio/aac",
    ".ogg": "audio/ogg",
    ".oga": "audio/ogg",
    ".opus": "audio/ogg",
    ".flac": "audio/flac",
    ".webm": "audio/webm",
}
LINK_SCHEMES = ("", "http", "https", "mailto")
# The inline SVG as render/animation.py writes it: a track and its drawings, the end of the
# document's shared <defs> (the first), a clip path (lxml writes no nested ones; its content read
# up to the first "</clipPath>" a "<" at a time, not by a lazy ".*?" a character at a time; one
# group, so that splitting on it gives the text between clip paths and the clip paths in turn).
TRACK_DEFS = re.compile(r'(<g data-part="[^"]*">)<defs>')
DEFS_END = "</defs>"
CLIP_PATH = re.compile(r"(<clipPath\b[^>]*?(?:/>|>[^<]*(?:<(?!/clipPath>)[^<]*)*</clipPath>))")
HIDDEN_DEFS = '<defs style="display:none">'
PARTS_DEFS = f'<defs id="{PARTS_ID}">'  # render/animation.py: the parts the tracks' drawings share


@dataclass(frozen=True)
class AudioSource:
    """One `<source>` of the page's audio element: file `name` in the folder, media `type`."""

    name: str
    type: str


@dataclass(frozen=True)
class Link:
    """A link shown under the audio-book text."""

    label: str
    url: str


def check_links(links: Sequence[tuple[str, str]]) -> tuple[Link, ...]:
    """Validate (label, url) pairs; return them as Links.

    Raises OptionError for an empty label or url, or a url whose scheme is not
    http, https or mailto (a relative url is fine): `javascript:` links never
    reach a page.
    """
    checked = []
    for index, (label, url) in enumerate(links):
        if not label.strip() or not url.strip():
            raise OptionError(f"link {index + 1}: expected a label and a url, got {label!r} {url!r}")
        if urlsplit(url.strip()).scheme.lower() not in LINK_SCHEMES:
            raise OptionError(f"link {index + 1}: url {url!r} must be http, https, mailto or relative")
        checked.append(Link(label.strip(), url.strip()))
    return tuple(checked)


@functools.cache
def _environment() -> jinja2.Environment:
    """The Jinja environment over `templates/`, autoescaping everything: one per process, which
    keeps the templates it compiled (compile_page)."""
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(TEMPLATES),
        autoescape=True,
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
    )


def compile_page(page: str) -> None:
    """Compile the templates of the `page` (one of PAGES) into the environment, which keeps them: its
    own and the parts at the top of `templates/` (those of no page), ~7 ms a process, taken by generate
    while it would wait (render/animation.py's `meanwhile`) rather than when the page is made."""
    others = {f"{other}.html" for other in PAGES if other != page}
    environment = _environment()
    for name in environment.list_templates(filter_func=lambda name: "/" not in name and name not in others):
        environment.get_template(name)


def inline_svg(svg: bytes) -> Markup:
    """The SVG document `svg` (UTF-8 bytes from lxml, so already escaped) as markup for an HTML page.

    The XML declaration is dropped. The part tracks' drawings (each `<g data-part>`'s `<defs>`,
    shown only through the track's `<use>`) and the parts they share (`<defs id="cf-parts">`) are
    put out of the rendering with
    `style="display:none"`, so the browser builds no style or layout for the thousands it is not
    showing (the sprite-sheet way: a `<use>` still draws its clone); the clip paths inside them move
    first to the document's own `<defs>`, where they stay in effect (a clip path in an undisplayed
    subtree clips nothing). Same drawing, page ready in about half the time (docs/BENCHMARKS.md,
    "Page load in Chromium"). The tracks' reused drawings are shown by moving their source
    (render/moved.py: Chromium clones every `<use>`'s target at load, shown or not). A document
    without a `<defs>` before its first track is kept as written.
    """
    text = svg.decode("utf-8")
    if text.startswith("<?xml"):
        text = text[text.index("?>") + 2 :].lstrip()
    first_track = TRACK_DEFS.search(text)
    shared_end = text.find(DEFS_END)
    if first_track is None or not 0 <= shared_end < first_track.start():
        return Markup(text)
    pieces = CLIP_PATH.split(moved_tracks(text[shared_end:]))  # the text between clip paths, a clip path, ...
    tracks = TRACK_DEFS.sub(rf"\1{HIDDEN_DEFS}", "".join(pieces[::2])).replace(PARTS_DEFS, f'<defs id="{PARTS_ID}" style="display:none">', 1)
    return Markup(text[:shared_end] + "".join(pieces[1::2]) + tracks)


def page_html(
    page: str,
    *,
    title: str,
    alignment: Alignment,
    svg: bytes,
    audio: Sequence[AudioSource],
    fps: int,
    links: Sequence[tuple[str, str]] = (),
    lang: str = "zh",
    captions: str | None = None,
) -> str:
    """The HTML of the `page` ("audiobook" or "announcer") as a string.

    `alignment` gives the sentences (text, start and end in seconds) that the
    page highlights as they are spoken (none, and no text panel, for one made from the audio
    alone: speech/audio_only.py); `svg` is the animation document, put
    inline; `audio` the sources of the `<audio>` clock, best first; `captions` the WebVTT
    text of the sentences, the audio's `<track>` (None: no track). The track is a data: URL:
    from `file://` Chromium refuses to load a track file beside the page (another origin).
    """
    if page not in PAGES:
        raise OptionError(f"page {page!r}: expected one of {', '.join(PAGES)}")
    template = _environment().get_template(f"{page}.html")
    return template.render(
        title=title or "cartoonface",
        sentences=alignment.sentences if transcribed(alignment) else (),
        svg=inline_svg(svg),
        audio=tuple(audio),
        fps=fps,
        links=check_links(links) if page == "audiobook" else (),
        lang=lang,
        captions_url=None if captions is None else "data:text/vtt;base64," + base64.b64encode(
            captions.encode("utf-8")).decode("ascii"),
        version=__version__,
    )


def copy_audio(source: str | os.PathLike[str], folder: str | os.PathLike[str],
               keep_original: bool = False, compressed: Path | None = None) -> tuple[AudioSource, ...]:
    """Put the recording `source` into `folder` compressed for the page (audio.m4a, speech/audio.py
    page_copy; `compressed`: that file made already, copied in) and, when `keep_original`, byte for
    byte as recording.<suffix>.

    Returns the page's audio sources (the compressed one).
    """
    original = Path(source)
    target = Path(folder)
    playable = (page_copy(original, target, stem=AUDIO_STEM) if compressed is None
                else write_bytes_atomic(target / compressed.name, compressed.read_bytes()))
    if keep_original:
        write_bytes_atomic(target / f"{ORIGINAL_STEM}{original.suffix.lower() or '.original'}", original.read_bytes())
    return (AudioSource(playable.name, MEDIA_TYPES[playable.suffix]),)


def write_site(
    folder: str | os.PathLike[str],
    *,
    html: str,
    svg: bytes,
    textgrid: str,
    actions: str,
) -> None:
    """Write index.html, animation.svg, static/, alignment.TextGrid and actions.json into `folder`.

    The audio goes in separately (`copy_audio`), before the page is written.
    """
    target = Path(folder)
    write_bytes_atomic(target / "index.html", html.encode("utf-8"))
    write_bytes_atomic(target / "animation.svg", svg)
    write_bytes_atomic(target / "alignment.TextGrid", textgrid.encode("utf-8"))
    write_bytes_atomic(target / "actions.json", actions.encode("utf-8"))
    for asset in sorted(STATIC.iterdir()):
        if asset.is_file():
            write_bytes_atomic(target / "static" / asset.name, asset.read_bytes())
