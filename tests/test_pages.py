"""Pages: templates filled, user text escaped, links checked, the folder written."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import soundfile
from lxml import etree, html

from cartoonface.errors import OptionError
from cartoonface.render.pages import AudioSource, compile_page, copy_audio, inline_svg, page_html, write_site
from cartoonface.speech.records import Alignment, Sentence

HOSTILE = '<script>alert("x")</script> & <b>bold</b>'
SVG = "http://www.w3.org/2000/svg"


def small_svg() -> bytes:
    """A tiny SVG document as animation.py writes one (XML declaration, id cf-face)."""
    root = etree.Element(f"{{{SVG}}}svg", nsmap={None: SVG}, id="cf-face", viewBox="0 0 10 10")
    etree.SubElement(root, f"{{{SVG}}}rect", width="10", height="10")
    return etree.tostring(root, xml_declaration=True, encoding="utf-8")


def alignment(*texts: str) -> Alignment:
    """Sentences of `texts`, two seconds each with a half-second pause between."""
    sentences = tuple(Sentence(text, 2.5 * i, 2.5 * i + 2.0, ()) for i, text in enumerate(texts))
    return Alignment(sentences, 2.5 * len(texts), ())


def render(page: str = "audiobook", **changes) -> html.HtmlElement:
    """Render `page` with hostile user text everywhere unless `changes` say otherwise; parse it."""
    args: dict[str, Any] = dict(title=HOSTILE, alignment=alignment("你好。", HOSTILE), svg=small_svg(),
                audio=(AudioSource("audio.wav", "audio/wav"),), fps=25, links=((HOSTILE, "https://example.org/?a=1&b=2"),))
    args.update(changes)
    return html.document_fromstring(page_html(page, **args))


@pytest.mark.parametrize("page", ["audiobook", "announcer"])
def test_user_text_is_escaped_everywhere(page):
    doc = render(page)
    assert doc.findtext(".//title") == HOSTILE
    assert not doc.xpath("//script[not(@src)]"), "user text became a script element"
    assert not doc.xpath("//b"), "user text became markup"
    assert HOSTILE in [span.text_content() for span in doc.xpath("//span[@class='cf-sentence']")]


def test_audiobook_has_title_text_links_player_and_phone_viewport():
    doc = render()
    assert doc.findtext(".//h1") == HOSTILE
    link = doc.xpath("//nav[@class='cf-links']//a")[0]
    assert link.text_content() == HOSTILE and link.get("href") == "https://example.org/?a=1&b=2"
    audio = doc.get_element_by_id("cf-audio")
    assert audio.get("data-fps") == "25"
    assert [s.get("src") for s in audio.xpath("source")] == ["audio.wav"]
    assert "width=device-width" in doc.xpath("//meta[@name='viewport']/@content")[0]
    assert doc.xpath("//script/@src") == ["static/cartoonface.js"]


def test_sentences_carry_their_times():
    spans = render().xpath("//span[@class='cf-sentence']")
    times = [float(s.get(name)) for s in spans for name in ("data-start", "data-end")]
    expected = [t for s in alignment("a", "b").sentences for t in (s.start, s.end)]
    assert times == pytest.approx(expected)


def test_svg_is_inline_without_xml_declaration():
    text = page_html("audiobook", title="t", alignment=alignment("一。"), svg=small_svg(),
                     audio=(AudioSource("audio.wav", "audio/wav"),), fps=30)
    assert "<?xml" not in text
    doc = html.document_fromstring(text)
    assert len(doc.xpath("//svg[@id='cf-face']")) == 1
    assert doc.xpath("//figure[@class='cf-stage']/svg")


def test_announcer_has_caption_slot_and_no_links():
    doc = render("announcer")
    assert doc.xpath("//*[@data-caption]")
    assert not doc.xpath("//nav[@class='cf-links']")


@pytest.mark.parametrize("url", ["javascript:alert(1)", " JavaScript:alert(1)", "data:text/html,x", "vbscript:x"])
def test_dangerous_links_are_refused(url):
    with pytest.raises(OptionError, match="link 1"):
        render(links=(("label", url),))


@pytest.mark.parametrize("page", ["audiobook", "announcer"])
def test_a_compiled_page_is_made_without_reading_a_template(page, monkeypatch):
    """After compile_page (generate calls it while its animation waits for the reuse search) the page is
    rendered from the templates kept: none is read again, and the page is the one a new environment makes."""
    import cartoonface.render.pages as pages

    pages._environment.cache_clear()  # a new environment, as a new process has
    compile_page(page)
    loader = pages._environment().loader
    assert loader is not None

    def unreadable(environment, name):
        raise AssertionError(f"{name} read again")

    with monkeypatch.context() as patched:
        patched.setattr(loader, "get_source", unreadable)
        made = html.tostring(render(page))
    pages._environment.cache_clear()
    assert made == html.tostring(render(page))


def test_unknown_page_is_refused():
    with pytest.raises(OptionError, match="page 'poster'"):
        render("poster")


def tone(path, seconds: float = 0.5, rate: int = 16000) -> None:
    """Write a 220 Hz tone to `path` (format from its suffix)."""
    t = np.arange(int(seconds * rate)) / rate
    soundfile.write(path, (0.3 * np.sin(2 * np.pi * 220 * t)).astype(np.float32), rate)


@pytest.mark.parametrize("suffix", [".wav", ".flac"])
def test_page_audio_is_compressed_and_the_original_kept_on_request(suffix, tmp_path):
    tone(tmp_path / f"speech{suffix}", seconds=5.0)
    original = (tmp_path / f"speech{suffix}").read_bytes()
    sources = copy_audio(tmp_path / f"speech{suffix}", tmp_path / "out")
    assert sources == (AudioSource("audio.m4a", "audio/mp4"),)
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["audio.m4a"]
    copy_audio(tmp_path / f"speech{suffix}", tmp_path / "kept", keep_original=True)
    assert (tmp_path / "kept" / f"recording{suffix}").read_bytes() == original


def test_site_files_are_written(tmp_path):
    write_site(tmp_path, html="<!doctype html>", svg=small_svg(), textgrid="tg", actions="{}")
    names = {p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*") if p.is_file()}
    assert {"index.html", "animation.svg", "alignment.TextGrid", "actions.json",
            "static/cartoonface.js", "static/cartoonface.css"} <= names


def tracked_svg() -> bytes:
    """A document shaped as animation.py writes one: shared <defs> with a clip path, then two part
    tracks whose drawings hold clip paths of their own."""
    root = etree.Element(f"{{{SVG}}}svg", nsmap={None: SVG}, id="cf-face", viewBox="0 0 10 10")
    shared = etree.SubElement(root, f"{{{SVG}}}defs")
    etree.SubElement(etree.SubElement(shared, f"{{{SVG}}}clipPath", id="v0"), f"{{{SVG}}}path", d="m0,0h5v5z", id="v0_")
    for part in ("face", "eyes"):
        track = etree.SubElement(root, f"{{{SVG}}}g", {"data-part": part})
        drawings = etree.SubElement(track, f"{{{SVG}}}defs")
        for index in range(3):
            drawing = etree.SubElement(drawings, f"{{{SVG}}}g", id=f"{part}{index}")
            clip = etree.SubElement(drawing, f"{{{SVG}}}clipPath", id=f"{part}c{index}")
            etree.SubElement(clip, f"{{{SVG}}}path", d=f"m{index},0h5v5z")
            etree.SubElement(drawing, f"{{{SVG}}}rect", width="3", height="3", **{"clip-path": f"url(#{part}c{index})"})
        etree.SubElement(track, f"{{{SVG}}}use", href=f"#{part}0")
    return etree.tostring(root, xml_declaration=True, encoding="utf-8")


def test_inline_svg_undisplays_the_drawings_and_keeps_their_clip_paths_shown():
    written = etree.fromstring(tracked_svg())
    inline = etree.fromstring(str(inline_svg(tracked_svg())).encode("utf-8"))
    tags = sorted(e.tag for e in written.iter())
    assert sorted(e.tag for e in inline.iter()) == tags, "elements were lost or added"
    tracks = inline.findall(f"{{{SVG}}}g[@data-part]")
    assert len(tracks) == 2
    for track in tracks:
        drawings = track.find(f"{{{SVG}}}defs")
        assert drawings.get("style") == "display:none"
        assert not drawings.findall(f".//{{{SVG}}}clipPath"), "a clip path stayed in an undisplayed subtree"
        assert track.find(f"{{{SVG}}}use") is not None
    shared = inline.find(f"{{{SVG}}}defs")
    assert shared.get("style") is None
    written_clips = {c.get("id"): etree.tostring(c) for c in written.iter(f"{{{SVG}}}clipPath")}
    assert {c.get("id"): etree.tostring(c) for c in shared.findall(f"{{{SVG}}}clipPath")} == written_clips


def test_inline_svg_without_shared_defs_is_kept_as_written():
    root = etree.fromstring(tracked_svg())
    root.remove(root.find(f"{{{SVG}}}defs"))
    written = etree.tostring(root, encoding="unicode")
    assert str(inline_svg(written.encode("utf-8"))) == written
