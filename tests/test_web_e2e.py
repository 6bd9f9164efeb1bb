"""End to end in real Chromium against a real `cartoonface serve` on a free loopback port."""

from __future__ import annotations

import http.client
import socket
import time
import zipfile
from pathlib import Path

import pytest

from cartoonface.web.config import DEFAULTS
from tests.conftest import ROOT, speak

pytestmark = pytest.mark.browser

SPOKEN = "ni3 hao3, shi4 jie4. jin1 tian1 tian1 qi4 hen3 hao3."
TRANSCRIPT = "你好，世界。今天天气很好。"
TITLE = "<script>window.pwned=1</script>早安"


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A face model JSON, a short espeak-ng recording, a corrupt WAV and the transcript file."""
    folder = tmp_path_factory.mktemp("inputs")
    wav = folder / "speech.wav"
    speak(SPOKEN, wav)
    corrupt = folder / "corrupt.wav"
    corrupt.write_bytes(wav.read_bytes()[:44] + b"\x07garbage" * 3)
    transcript = folder / "transcript.txt"
    transcript.write_text(TRANSCRIPT, encoding="utf-8")
    return {"face": sorted((ROOT / "samples" / "faces").glob("*.json"))[0], "wav": wav, "corrupt": corrupt,
            "transcript": transcript}


def fill_form(page, base: str, inputs: dict[str, Path], wav: Path) -> None:
    page.goto(base + "/")
    page.set_input_files("#face_file", str(inputs["face"]))
    page.set_input_files("#audio", str(wav))
    page.set_input_files("#transcript_file", str(inputs["transcript"]))
    page.check("input[name=page][value=announcer]")
    page.fill("#title", TITLE)


def moving(page, element, wait: float = 1.0) -> bool:
    """True when two screenshots of `element` taken `wait` seconds apart differ."""
    first = element.screenshot()
    page.wait_for_timeout(wait * 1000)
    return element.screenshot() != first


def play_and_check_motion(page, frame, element) -> None:
    """The page script holds the face still until the audio plays (so it ran: the CSP let it),
    then the face moves with the audio clock."""
    frame.wait_for_function("() => document.getElementById('cf-face').animationsPaused()")
    assert not moving(page, element, 0.5)
    frame.evaluate("() => document.getElementById('cf-audio').play()")
    frame.wait_for_function("() => document.getElementById('cf-audio').currentTime > 0.2", timeout=10_000)
    assert moving(page, element)
    lag = frame.evaluate("() => Math.abs(document.getElementById('cf-face').getCurrentTime()"
                         " - document.getElementById('cf-audio').currentTime)")
    assert lag < 0.25


def test_generate_watch_play_download_and_open_from_file(server, inputs, browser, tmp_path):
    context = browser.new_context(accept_downloads=True, viewport={"width": 1100, "height": 1400})
    refused = []
    context.on("console", lambda message: refused.append(message.text)
               if "Content Security Policy" in message.text or "Refused" in message.text else None)
    page = context.new_page()
    fill_form(page, server, inputs, inputs["wav"])
    page.click("#generate")
    page.wait_for_url(f"{server}/jobs/*")
    page.wait_for_function("() => { const p = document.getElementById('percent');"
                           " return p && p.textContent === '100%'; }", polling="raf", timeout=240_000)
    page.wait_for_selector("#result", timeout=30_000)
    assert page.evaluate("() => window.pwned") is None
    assert TITLE in page.inner_text("h1")

    frame = page.frame_locator("#result")
    frame.locator("#cf-face").wait_for()
    player = page.locator("#result").element_handle().content_frame()
    assert player.evaluate("() => window.pwned") is None
    play_and_check_motion(page, player, page.locator("#result"))

    with page.expect_download() as caught:
        page.click("#download")
    download = caught.value
    assert download.suggested_filename.endswith(".zip")
    archive = tmp_path / download.suggested_filename
    download.save_as(archive)
    unpacked = tmp_path / "unpacked"
    with zipfile.ZipFile(archive) as zipped:
        zipped.extractall(unpacked)
    index = next(unpacked.glob("*/index.html"))

    offline = context.new_page()
    offline.goto(index.as_uri())
    offline.locator("#cf-face").wait_for()
    assert offline.evaluate("() => window.pwned") is None
    play_and_check_motion(offline, offline, offline.locator("#cf-face"))
    assert refused == []
    context.close()


def test_corrupt_recording_is_reported_in_the_form(server, inputs, browser):
    context = browser.new_context()
    page = context.new_page()
    fill_form(page, server, inputs, inputs["corrupt"])
    page.click("#generate")
    error = page.locator("#audio-error")
    error.wait_for()
    assert "corrupt.wav" in error.inner_text()
    assert page.input_value("#title") == TITLE
    assert page.is_checked("input[name=page][value=announcer]")
    context.close()


def test_served_on_loopback_only_loopback_host_names_are_accepted(server):
    port = int(server.rsplit(":", 1)[1])
    answers = {}
    for host in ("rebound.example", f"127.0.0.1:{port}", f"localhost:{port}"):
        connection = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
        connection.request("GET", "/", headers={"Host": host})
        answers[host] = connection.getresponse().status
        connection.close()
    assert answers == {"rebound.example": 400, f"127.0.0.1:{port}": 200, f"localhost:{port}": 200}


def test_a_body_announced_and_not_sent_is_dropped_within_seconds(server):
    port = int(server.rsplit(":", 1)[1])
    timeout = DEFAULTS["CHANNEL_TIMEOUT"]
    assert isinstance(timeout, int)
    with socket.create_connection(("127.0.0.1", port), timeout=120) as slow:
        slow.sendall(b"POST /jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: multipart/form-data; boundary=x\r\n"
                     b"Content-Length: 314572800\r\n\r\n--x\r\n")
        started = time.monotonic()
        while slow.recv(65536):
            pass
        held = time.monotonic() - started
    # closed once idle for CHANNEL_TIMEOUT, found by a sweep every CHANNEL_TIMEOUT / 2
    assert held < 2 * timeout, held
