"""The MP4 export: played back by ffmpeg (streams, duration) and compared with Chromium's frame of the SVG."""

from __future__ import annotations

import io
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from cartoonface.errors import OptionError
from cartoonface.exports.frames import FrameDocuments
from cartoonface.exports.video import fit, parse_size, write_video
from cartoonface.pipeline import Options, generate
from cartoonface.speech.audio import ffmpeg_exe
from tests.conftest import run_cli, spoken_inputs

ROOT = Path(__file__).resolve().parent.parent
FACE = ROOT / "samples" / "faces" / "female.json"
SIZE = (400, 480)  # the face canvas: the video's picture is the SVG's, unscaled
FPS = 24
SET_SVG_TIME = "t => { const s = document.documentElement; s.pauseAnimations(); s.setCurrentTime(t); }"
pytestmark = pytest.mark.skipif(not shutil.which("espeak-ng"), reason="needs espeak-ng")


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """A short generated folder and its video at the face's own size."""
    folder = tmp_path_factory.mktemp("video")
    speech, transcript = spoken_inputs(folder, "你好。谢谢你。", speed=150)
    result = generate(FACE, speech, transcript, folder / "site", Options(fps=FPS, clothes="none"))
    video = folder / "face.mp4"
    reports: list[float] = []
    drawn = write_video((result.out_dir / "animation.svg").read_bytes(), FPS, result.duration, speech, video, SIZE,
                        lambda stage, fraction: reports.append(fraction))
    return result, video, drawn, reports


def probe(video: Path) -> str:
    """ffmpeg's description of the file (it has no ffprobe; `-i` alone prints the same streams)."""
    return subprocess.run([ffmpeg_exe(), "-hide_banner", "-i", str(video)], capture_output=True, text=True).stderr


def decoded_frame(video: Path, seconds: float) -> np.ndarray:
    """The video's picture at `seconds`, (h, w, 3) float RGB."""
    raw = subprocess.run([ffmpeg_exe(), "-v", "error", "-ss", f"{seconds:.4f}", "-i", str(video), "-frames:v", "1",
                          "-f", "rawvideo", "-pix_fmt", "rgb24", "-"], capture_output=True, check=True).stdout
    return np.frombuffer(raw, dtype=np.uint8).reshape(SIZE[1], SIZE[0], 3).astype(float)


def test_the_file_plays_back_as_h264_and_aac_as_long_as_the_speech(made):
    result, video, drawn, reports = made
    info = probe(video)
    assert re.search(r"Video: h264 .*yuv420p.*\b400x480\b.*\b24 fps", info), info
    assert re.search(r"Audio: aac", info), info
    h, m, s = re.search(r"Duration: (\d+):(\d+):([\d.]+)", info).groups()
    assert abs(int(h) * 3600 + int(m) * 60 + float(s) - result.duration) < 0.1
    assert 1 < drawn < result.frames  # still stretches are drawn once
    assert reports == sorted(reports) and reports[-1] == 1.0


def test_a_frame_is_the_svg_frame_chromium_shows_at_that_time(made, browser):
    result, video, _, _ = made
    page = browser.new_page(viewport={"width": SIZE[0], "height": SIZE[1]})
    page.goto((result.out_dir / "animation.svg").as_uri(), wait_until="load")

    def chromium(seconds: float) -> np.ndarray:
        page.evaluate(SET_SVG_TIME, seconds)
        page.wait_for_timeout(100)
        return np.asarray(Image.open(io.BytesIO(page.screenshot())).convert("RGB"), dtype=float)

    frames = list(range(0, result.frames, result.frames // 6))
    # Chromium in the middle of each frame; ffmpeg at the frame's start (its -ss drops the
    # frames that start before the time asked for).
    shown = {k: chromium((k + 0.5) / FPS) for k in frames}
    page.close()
    for k in frames:
        picture = decoded_frame(video, k / FPS)
        own = np.abs(picture - shown[k]).mean()
        others = [np.abs(picture - shown[j]).mean() for j in frames if j != k]
        # H.264 at CRF 23 and two rasterisers differ by about a level on average; the frame
        # is nearer to Chromium's picture at its own time than at any other sampled time.
        assert own < 2.5 and own < min(others), (k, own, others)

def test_frame_documents_hide_what_the_frame_hides(made):
    result, _, _, _ = made
    frames = FrameDocuments((result.out_dir / "animation.svg").read_bytes(), FPS, result.frames)
    for frame in (0, result.frames // 2, result.frames - 1):
        document = frames.document(frame, *SIZE)
        assert "<set" not in document and "animateTransform" not in document and 'visibility="hidden"' not in document
        assert document.count('data-part="face"') == 1 and document.count("data-shape=") == 1


def test_sizes():
    assert parse_size("1280x720") == (1280, 720) and parse_size(" 640 X 360 ") == (640, 360)
    for bad in ("1280", "1281x720", "0x0", "9000x720", "axb"):
        with pytest.raises(OptionError, match="--size"):
            parse_size(bad)
    for view in ((400, 480), (853.3, 480), (100, 100)):
        width, height = fit(view, (1280, 720))
        assert width <= 1280 and height <= 720 and width % 2 == height % 2 == 0
        assert max(1280 - width, 720 - height) <= 2 or abs(width / height - view[0] / view[1]) < 0.01


@pytest.mark.parametrize("extra", [["--mp4", "out.avi"], ["--size", "100x101", "--mp4", "o.mp4"]])
def test_bad_video_options_exit_2(extra, tmp_path):
    done = run_cli("generate", "--face", str(FACE), "--audio", "x.wav", "--transcript", "t.txt",
                   "-o", str(tmp_path / "o"), *extra, cwd=tmp_path)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert ("--mp4" in done.stderr) or ("--size" in done.stderr)
    assert not (tmp_path / "o").exists()
