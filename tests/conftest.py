"""Shared test fixtures."""

from __future__ import annotations

import io
import os
import re
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest
from flask.testing import FlaskClient
from PIL import Image

from cartoonface.web import create_app
from cartoonface.web.store import DONE, FAILED

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="session")
def root() -> Path:
    """The project root folder."""
    return ROOT


# Debian's chromium, as root, with the network-quiet flags this machine needs (DEPENDENCIES.md).
CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--autoplay-policy=no-user-gesture-required", "--mute-audio",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run"]


@pytest.fixture(scope="session")
def browser():
    """Headless Debian chromium driven by Playwright, one for the whole session.

    Playwright's sync API allows one running instance per thread, so every browser test
    shares this one (never a downloaded browser: `playwright install` is never called).
    """
    if not CHROMIUM.exists():
        pytest.skip("needs Debian's chromium (scripts/setup.sh installs it)")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as play:
        launched = play.chromium.launch(executable_path=str(CHROMIUM), headless=True, args=CHROMIUM_ARGS)
        yield launched
        launched.close()


def speak(text: str, path: Path, speed: int | None = None) -> Path:
    """Synthesise Mandarin `text` (Hanzi or tone-numbered pinyin) with espeak-ng into WAV `path`.

    `speed` is espeak-ng's words per minute (its default when None). Returns `path`.
    """
    rate = [] if speed is None else ["-s", str(speed)]
    subprocess.run(["espeak-ng", "-v", "cmn-latn-pinyin", *rate, "-w", str(path), text], check=True)
    return path


def spoken_inputs(folder: Path, text: str, speed: int) -> tuple[Path, Path]:
    """`text` read by espeak-ng at `speed` words per minute into `folder`/speech.wav, and the
    text itself in `folder`/text.txt (UTF-8). Returns (recording, transcript) paths."""
    speech, transcript = folder / "speech.wav", folder / "text.txt"
    speak(text, speech, speed=speed)
    transcript.write_text(text + "\n", encoding="utf-8")
    return speech, transcript


def run_cli(*args: str, cwd: Path | None = None, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    """Run `python -m cartoonface ARGS` as a user would; return the finished process."""
    return subprocess.run(
        [sys.executable, "-m", "cartoonface", *map(str, args)],
        capture_output=True,
        text=True,
        cwd=cwd or ROOT,
        timeout=timeout,
    )


def free_port() -> int:
    """A TCP port on 127.0.0.1 that nothing listens on now."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory):
    """A real `cartoonface serve` (one worker) in a subprocess on a free loopback port; yields its base URL."""
    instance = tmp_path_factory.mktemp("served")
    port = free_port()
    with open(instance / "server.log", "wb") as log:
        process = subprocess.Popen(
            [sys.executable, "-m", "cartoonface", "serve", "--port", str(port), "--instance", str(instance)],
            stdout=log, stderr=subprocess.STDOUT, cwd=ROOT, env={**os.environ, "CARTOONFACE_WORKERS": "1"})
    base = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + 60
    while True:
        try:
            with urllib.request.urlopen(base + "/", timeout=2) as answer:
                if answer.status == 200:
                    break
        except OSError:
            if process.poll() is not None or time.monotonic() > deadline:
                process.kill()
                raise AssertionError((instance / "server.log").read_text()) from None
            time.sleep(0.2)
    yield base
    process.terminate()
    process.wait(timeout=30)


class Client(FlaskClient):
    """Flask's test client, closing what each request opened: the answer (read in full)
    and the request body it encoded (a temporary file for large bodies)."""

    def open(self, *args, **kwargs):
        kwargs.setdefault("buffered", True)
        response = super().open(*args, **kwargs)
        response.request.input_stream.close()
        return response


def make_app(instance: Path, **config):
    """The app on `instance` with `config`, one worker, using the closing test client."""
    app = create_app({"INSTANCE_PATH": str(instance), "WORKERS": 1, **config})
    app.test_client_class = Client
    return app


@pytest.fixture(scope="module")
def app(tmp_path_factory: pytest.TempPathFactory):
    """One app (one worker) on a fresh instance folder for the module."""
    app = make_app(tmp_path_factory.mktemp("instance"), MAX_UPLOAD_MB=1, MAX_TRANSCRIPT_CHARS=200)
    yield app
    app.extensions["cartoonface"].runner.close()


@pytest.fixture()
def client(app):
    """A test client of the module's app."""
    return app.test_client()


# Web form helpers shared by tests/test_web.py and tests/test_web_photo.py.
TRANSCRIPT = "你好，世界。"
SPOKEN = "ni3 hao3, shi4 jie4."


@pytest.fixture(scope="session")
def spoken(tmp_path_factory: pytest.TempPathFactory) -> bytes:
    """SPOKEN said by espeak-ng: a short Mandarin recording (WAV bytes)."""
    path = tmp_path_factory.mktemp("spoken") / "speech.wav"
    speak(SPOKEN, path)
    return path.read_bytes()


def csrf(client) -> str:
    """The CSRF token of the client's session, read from the form."""
    page = client.get("/").get_data(as_text=True)
    token = re.search(r'name="csrf_token" value="([^"]+)"', page)
    assert token is not None, "the form has no csrf_token field"
    return token.group(1)


def form(client, speech: bytes, sample: str, **fields) -> dict:
    """A complete, valid form submission; `fields` replace or (None) remove entries."""
    data = {"csrf_token": csrf(client), "face_sample": sample, "page": "audiobook", "title": "Hello",
            "background": client.application.extensions["cartoonface"].limits.backgrounds[0],
            "clothes": client.application.extensions["cartoonface"].limits.clothes[0],
            "transcript": TRANSCRIPT, "audio": (io.BytesIO(speech), "speech.wav")}
    for key, value in fields.items():
        if value is None:
            data.pop(key, None)
        else:
            data[key] = value
    return data


def post(client, data: dict):
    return client.post("/jobs", data=data, content_type="multipart/form-data")


def png_bytes(width: int, height: int, colour: tuple[int, int, int]) -> bytes:
    """A plain PNG of one colour (no face in it)."""
    buffer = io.BytesIO()
    Image.new("RGB", (width, height), colour).save(buffer, format="PNG")
    return buffer.getvalue()


def wait_done(client, url: str, timeout: float = 240) -> list[dict]:
    """Poll the status endpoint until the job ends; return every status seen."""
    seen = []
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        status = client.get(f"{url}/status").get_json()
        seen.append(status)
        if status["state"] in (DONE, FAILED):
            return seen
        time.sleep(0.2)
    raise AssertionError(f"job {url} did not finish: {seen[-1]}")
