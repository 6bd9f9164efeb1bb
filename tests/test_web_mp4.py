"""The web app's MP4 option (issue 14): the form's checkbox and the API's `mp4` field make a
job that also renders the video, offered for download beside the cues and captions.
Real Flask app, real jobs on conftest's espeak speech."""

from __future__ import annotations

import io
import re
import subprocess
import time
import wave
import zipfile
from pathlib import Path

import pytest

from cartoonface.speech.audio import ffmpeg_exe
from cartoonface.web.store import DONE, RUNNING, Status, create_job, read_spec, write_status
from cartoonface.web.worker import SITE, VIDEO_NAME, user_message
from cartoonface.errors import AudioError
from tests.conftest import ROOT, form, make_app, post, wait_done

SAMPLE = sorted((ROOT / "samples" / "faces").glob("*.json"))[0].stem
TOKEN = "test-token-mp4-0123456789abcdef"
JOB_TIMEOUT = 240  # seconds a job may take on a busy machine
VIDEO_SIZE = "1280x720"  # the web's video is 720p (exports/video.py DEFAULT_SIZE)


@pytest.fixture(scope="module")
def app(tmp_path_factory: pytest.TempPathFactory):
    """One app (one worker) with the form and the JSON API."""
    app = make_app(tmp_path_factory.mktemp("instance"), API_TOKEN=TOKEN, MAX_UPLOAD_MB=1, MAX_TRANSCRIPT_CHARS=200)
    yield app
    app.extensions["cartoonface"].runner.close()


def run_form_job(app, speech: bytes, **fields) -> tuple[str, list[dict]]:
    """Submit the form with `fields` and wait: (job page url, statuses seen)."""
    client = app.test_client()
    response = post(client, form(client, speech, SAMPLE, **fields))
    assert response.status_code == 303, response.get_data(as_text=True)
    url = response.headers["Location"]
    return url, wait_done(client, url)


@pytest.fixture(scope="module")
def video_job(app, spoken: bytes) -> tuple[str, list[dict]]:
    return run_form_job(app, spoken, mp4="1")


@pytest.fixture(scope="module")
def plain_job(app, spoken: bytes) -> tuple[str, list[dict]]:
    return run_form_job(app, spoken)


def seconds_of(wav: bytes) -> float:
    """The duration of a WAV recording (seconds)."""
    with wave.open(io.BytesIO(wav)) as reader:
        return reader.getnframes() / reader.getframerate()


def probe(video: Path) -> str:
    """ffmpeg's description of the file's streams (the bundled ffmpeg has no ffprobe)."""
    return subprocess.run([ffmpeg_exe(), "-hide_banner", "-i", str(video)], capture_output=True, text=True).stderr


def duration_of(info: str) -> float:
    h, m, s = re.search(r"Duration: (\d+):(\d+):([\d.]+)", info).groups()
    return int(h) * 3600 + int(m) * 60 + float(s)


def test_the_form_offers_the_video_as_an_option(app):
    page = app.test_client().get("/").get_data(as_text=True)
    assert re.search(r'<input type="checkbox" id="mp4" name="mp4" value="1"[^>]*>', page)
    assert "Also make an MP4 video" in page


def test_a_video_job_ends_done_with_a_video_stage_after_the_pages(video_job):
    url, seen = video_job
    assert seen[-1]["state"] == DONE, seen[-1]
    percents = [status["percent"] for status in seen]
    assert percents == sorted(percents)
    stages = [status["stage"] for status in seen if status["state"] == "running"]
    assert "video" in stages
    assert "video" not in stages[:stages.index("video")] and "pages" not in stages[stages.index("video"):]
    during = [status for status in seen if status["stage"] == "video" and status["state"] == "running"]
    assert all(status["stage_label"] == "Making the video" for status in during)


def test_the_result_page_offers_the_video_and_it_plays_for_the_recording(app, video_job, spoken, tmp_path):
    url, _ = video_job
    client = app.test_client()
    page = client.get(url).get_data(as_text=True)
    link = re.search(r'<a id="download-video" class="button" href="([^"]+)" download="([^"]+)">'
                     r'Download the video \(MP4\)</a>', page)
    assert link is not None, page
    assert link.group(1) == f"{url}/site/{VIDEO_NAME}"
    assert link.group(2) == "cartoonface-Hello.mp4"  # the title, as the zip is named
    response = client.get(link.group(1))
    assert response.status_code == 200
    assert response.mimetype == "video/mp4"
    video = tmp_path / "talk.mp4"
    video.write_bytes(response.get_data())
    info = probe(video)
    assert re.search(rf"Video: h264 .*yuv420p.*\b{VIDEO_SIZE}\b", info), info
    assert re.search(r"Audio: aac", info), info
    assert abs(duration_of(info) - seconds_of(spoken)) < 0.1, info


def test_the_video_is_not_stored_again_in_the_pages_zip(app, video_job):
    url, _ = video_job
    archive = zipfile.ZipFile(io.BytesIO(app.test_client().get(f"{url}/download").get_data()))
    names = archive.namelist()
    assert any(name.endswith("/index.html") for name in names)
    assert not any(name.endswith(".mp4") for name in names), names


def test_a_job_without_the_option_has_no_video(app, plain_job):
    url, seen = plain_job
    assert seen[-1]["state"] == DONE, seen[-1]
    assert "video" not in [status["stage"] for status in seen]
    client = app.test_client()
    page = client.get(url).get_data(as_text=True)
    assert "download-video" not in page and "(MP4)" not in page
    assert "Making the video" not in page
    assert client.get(f"{url}/site/{VIDEO_NAME}").status_code == 404


def test_the_form_refuses_a_value_that_is_not_yes_or_no(app, spoken):
    client = app.test_client()
    response = post(client, form(client, spoken, SAMPLE, mp4="maybe"))
    assert response.status_code == 400
    assert "expected true or false" in response.get_data(as_text=True)


def auth() -> dict[str, str]:
    return {"Authorization": f"Bearer {TOKEN}"}


def api_fields(speech: bytes, **changes: str) -> dict:
    return {"sample": SAMPLE, "transcript": "你好，世界。", "audio": (io.BytesIO(speech), "talk.wav"), **changes}


def test_the_api_makes_the_video_when_asked_and_links_it(app, spoken):
    client = app.test_client()
    response = client.post("/api/jobs", data=api_fields(spoken, mp4="true"), headers=auth(),
                           content_type="multipart/form-data")
    assert response.status_code == 201, response.get_data(as_text=True)
    assert response.get_json()["links"]["video"] is None  # not made yet
    url = response.headers["Location"]
    deadline = time.monotonic() + JOB_TIMEOUT
    job = response.get_json()
    while job["state"] in ("queued", "running") and time.monotonic() < deadline:
        time.sleep(0.2)
        job = client.get(url, headers=auth()).get_json()
    assert job["state"] == "done", job
    video = client.get(job["links"]["video"])
    assert (video.status_code, video.mimetype) == (200, "video/mp4")
    assert len(video.get_data()) > 0


def test_the_api_names_the_field_of_a_bad_value(app, spoken):
    response = app.test_client().post("/api/jobs", data=api_fields(spoken, mp4="sometimes"), headers=auth(),
                                      content_type="multipart/form-data")
    assert response.status_code == 400
    assert response.get_json()["field"] == "mp4"


def test_a_failed_video_names_the_video_not_a_server_path(tmp_path):
    folder = tmp_path / "job"
    spec = {"audio_file": "audio.wav", "audio_label": "talk.wav"}
    error = AudioError(f"{folder / SITE / VIDEO_NAME}: ffmpeg could not make the video (broken)")
    message = user_message(error, folder, spec)
    assert str(tmp_path) not in message
    assert message.startswith("video: ffmpeg could not make the video")


def test_the_page_of_a_running_video_job_lists_the_video_stage_last(app, video_job):
    url, _ = video_job
    done = Path(app.instance_path) / "jobs" / url.rsplit("/", 1)[-1]
    spec = {key: value for key, value in read_spec(done).items() if key not in ("id", "created")}
    job = create_job(Path(app.instance_path), spec, {name: (done / name).read_bytes()
                                                      for name in ("face.json", str(spec["audio_file"]))})
    write_status(job.folder, Status(state=RUNNING, stage="video", fraction=0.7))  # stored, never queued
    client = app.test_client()
    page = client.get(f"/jobs/{job.id}").get_data(as_text=True)
    marks = re.findall(r'<li data-stage="([a-z]+)"( class="(done|current)")?', page)
    assert [name for name, _, _ in marks][-2:] == ["pages", "video"]
    assert [mark for _, _, mark in marks] == ["done"] * (len(marks) - 1) + ["current"]
    assert '<h2 id="stage">Making the video</h2>' in page
    assert client.get(f"/jobs/{job.id}/status").get_json()["percent"] == 70


def test_a_form_sent_back_with_an_error_keeps_the_box_ticked(app, spoken):
    client = app.test_client()
    for sent, ticked in (("1", True), (None, False)):
        response = post(client, form(client, spoken, SAMPLE, page="no-such-page", mp4=sent))
        assert response.status_code == 400
        box = re.search(r'<input type="checkbox" id="mp4"[^>]*>', response.get_data(as_text=True))
        assert box is not None
        assert (" checked" in box.group()) == ticked
