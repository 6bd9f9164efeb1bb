"""The web app through Flask's test client: every route, limit and error, with the real pipeline."""

from __future__ import annotations

import io
import json
import stat
import os
import re
import socket
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest
from markupsafe import escape

from cartoonface.errors import OptionError
from cartoonface.face.model import face_from_dict
from cartoonface.pipeline import STAGES
from cartoonface.render.scenery import BACKGROUNDS, CLOTHES
from cartoonface.web import create_app
from cartoonface.web.inputs import MAX_PHOTO_BYTES
from cartoonface.web.runner import STOPPED, QueueFull, Runner
from cartoonface.web.views import stage_label
from cartoonface.web.worker import JobLimits, out_of_memory
from cartoonface.web.security import download_name
from cartoonface.web.store import (DONE, FAILED, FILE_MODE, FOLDER_MODE, INTERRUPTED, QUEUED, RUNNING, Status, apply_retention,
                                   create_job, list_jobs, load_job, new_id, space_problem, valid_id,
                                   write_status)
from tests.conftest import ROOT, TRANSCRIPT, Client, csrf, form, make_app, png_bytes, post, run_cli, wait_done
from tests.synthetic import wav_bytes

SAMPLES = ROOT / "samples" / "faces"
XSS = "<script>alert('x')</script>"


@pytest.fixture(scope="module")
def speech(spoken: bytes) -> bytes:
    """A short Mandarin recording (WAV bytes): conftest's `spoken`."""
    return spoken


@pytest.fixture(scope="module")
def sample_name() -> str:
    """The first sample face shipped in samples/faces."""
    return sorted(SAMPLES.glob("*.json"))[0].stem





@pytest.fixture(scope="module")
def done_job(app, speech, sample_name) -> tuple[str, list[dict]]:
    """One job with a <script> title and transcript, run to the end: (url, statuses seen)."""
    client = app.test_client()
    response = post(client, form(client, speech, sample_name, title=XSS, transcript=TRANSCRIPT + XSS))
    assert response.status_code == 303, response.get_data(as_text=True)
    url = response.headers["Location"]
    return url, wait_done(client, url)


def job_id_of(url: str) -> str:
    return url.rstrip("/").rsplit("/", 1)[-1]


# --- the happy path --------------------------------------------------------------------------

def test_home_page_offers_the_form_with_samples_and_a_csrf_token(client, sample_name):
    page = client.get("/").get_data(as_text=True)
    assert f'<input type="radio" name="face_sample" value="{sample_name}"' in page
    for name in ("face_file", "photo", "audio", "transcript", "transcript_file", "title", "background", "clothes"):
        assert f'name="{name}"' in page
    assert 'value="audiobook"' in page and 'value="announcer"' in page
    assert len(csrf(client)) >= 32


def test_a_job_reaches_done_with_rising_progress(done_job):
    url, seen = done_job
    assert seen[-1]["state"] == DONE, seen[-1]
    assert seen[-1]["percent"] == 100
    percents = [status["percent"] for status in seen]
    assert percents == sorted(percents)
    assert all(0 <= p <= 100 for p in percents)


def test_result_page_escapes_the_title_and_frames_the_generated_page(client, done_job):
    url, _ = done_job
    page = client.get(url).get_data(as_text=True)
    assert XSS not in page
    assert "&lt;script&gt;" in page
    assert f'src="{url}/site/index.html"' in page
    assert f'href="{url}/download"' in page


def test_generated_page_is_served_with_its_types_and_escaped(client, done_job):
    url, _ = done_job
    response = client.get(f"{url}/site/index.html")
    assert response.status_code == 200
    assert response.mimetype == "text/html"
    html = response.get_data(as_text=True)
    assert XSS not in html
    assert "sandbox allow-scripts" in response.headers["Content-Security-Policy"]
    assert response.headers["X-Frame-Options"] == "SAMEORIGIN"
    linked = re.findall(r'(?:src|href)="(static/[^"]+|[^":/]+\.(?:wav|mp3|ogg|m4a|svg))"', html)
    assert linked
    types = {".css": "text/css", ".js": "text/javascript", ".wav": "audio/wav", ".svg": "image/svg+xml"}
    for name in linked:
        served = client.get(f"{url}/site/{name}")
        assert served.status_code == 200, name
        expected = types.get(Path(name).suffix)
        if expected:
            assert served.mimetype == expected


def test_zip_download_is_the_folder_generate_writes(app, client, done_job, tmp_path, sample_name):
    url, _ = done_job
    response = client.get(f"{url}/download")
    assert response.status_code == 200
    assert response.mimetype == "application/zip"
    disposition = response.headers["Content-Disposition"]
    assert disposition.startswith("attachment;")
    assert re.fullmatch(r'attachment; filename=[A-Za-z0-9_.-]+\.zip', disposition)
    archive = zipfile.ZipFile(io.BytesIO(response.data))
    names = archive.namelist()
    tops = {name.split("/", 1)[0] for name in names}
    assert len(tops) == 1
    top = tops.pop()
    # `cartoonface generate` on the job's own inputs and choices writes the same files byte for byte.
    job = load_job(Path(app.instance_path), job_id_of(url))
    spec = job.spec
    out = tmp_path / "cli"
    done = run_cli("generate", "--face", job.folder / "face.json", "--audio", job.folder / str(spec["audio_file"]),
                   "--transcript", job.folder / "transcript.txt", "-o", out, "--page", spec["page"],
                   "--title", spec["title"], "--background", spec["background"], "--clothes", spec["clothes"],
                   "--cues", "tsv", "--cues", "json", "--cues", "xml")
    assert done.returncode == 0, done.stderr
    expected = {path.relative_to(out).as_posix(): path.read_bytes() for path in out.rglob("*") if path.is_file()}
    got = {name[len(top) + 1:]: archive.read(name) for name in names if not name.endswith("/")}
    assert set(got) == set(expected)
    assert "index.html" in got
    assert all(got[name] == expected[name] for name in expected)


def test_recent_jobs_are_listed_for_the_browser_that_made_them(app, speech, sample_name):
    client = app.test_client()
    response = post(client, form(client, speech, sample_name, title="mine <b>bold</b>"))
    job_id = job_id_of(response.headers["Location"])
    page = client.get("/").get_data(as_text=True)
    assert f'href="/jobs/{job_id}"' in page
    assert "mine &lt;b&gt;bold&lt;/b&gt;" in page
    other = app.test_client().get("/").get_data(as_text=True)
    assert job_id not in other


# --- headers -------------------------------------------------------------------------------------

@pytest.mark.parametrize("path", ["/", "/static/web/web.css", "/jobs/" + "A" * 32, "/nope"])
def test_security_headers_on_every_answer(client, path):
    response = client.get(path)
    headers = response.headers
    assert headers["X-Content-Type-Options"] == "nosniff"
    assert headers["Referrer-Policy"] == "no-referrer"
    assert headers["X-Frame-Options"] == "DENY"
    csp = headers["Content-Security-Policy"]
    assert "frame-ancestors 'none'" in csp
    assert "script-src 'self'" in csp and "unsafe-inline" not in csp


def test_untrusted_host_headers_are_refused_when_hosts_are_set(tmp_path):
    app = make_app(tmp_path, TRUSTED_HOSTS=["127.0.0.1", "localhost"])
    try:
        client = app.test_client()
        refused = client.get("/", headers={"Host": "rebound.example:5000"})
        assert refused.status_code == 400
        assert refused.mimetype == "text/plain"
        assert refused.headers["X-Content-Type-Options"] == "nosniff"
        assert client.get("/", headers={"Host": "127.0.0.1:5000"}).status_code == 200
        assert client.get("/", headers={"Host": "localhost:5000"}).status_code == 200
    finally:
        app.extensions["cartoonface"].runner.close()


def test_app_never_runs_in_debug_mode(tmp_path):
    app = make_app(tmp_path, DEBUG=True)
    try:
        assert app.debug is False
    finally:
        app.extensions["cartoonface"].runner.close()


def test_status_endpoint_answers_json_that_is_not_cached(client, done_job):
    url, _ = done_job
    response = client.get(f"{url}/status")
    assert response.mimetype == "application/json"
    assert response.headers["Cache-Control"] == "no-store"
    assert set(response.get_json()) == {"state", "stage", "stage_label", "percent", "error"}


# --- CSRF ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("token", [None, "", "forged-token"])
def test_submission_without_the_session_csrf_token_is_refused(app, client, speech, sample_name, token):
    before = len(list_jobs(Path(app.instance_path)))
    data = form(client, speech, sample_name, title="kept title", csrf_token=token)
    response = post(client, data)
    assert response.status_code == 400
    page = response.get_data(as_text=True)
    assert "expired or did not come from this page" in page
    assert 'value="kept title"' in page
    assert len(list_jobs(Path(app.instance_path))) == before


def test_token_from_another_session_is_refused(app, speech, sample_name):
    first, second = app.test_client(), app.test_client()
    data = form(second, speech, sample_name, csrf_token=csrf(first))
    assert post(second, data).status_code == 400


# --- ids and paths -----------------------------------------------------------------------------------

BAD_IDS = ["abc", "A" * 31, "A" * 33, "A" * 31 + ".", "A" * 31 + "%2e", "..%2f..%2fetc%2fpasswd", "%00" + "A" * 29]


@pytest.mark.parametrize("bad", BAD_IDS)
@pytest.mark.parametrize("suffix", ["", "/status", "/download", "/site/index.html"])
def test_malformed_ids_are_not_found(client, bad, suffix):
    response = client.get(f"/jobs/{bad}{suffix}")
    assert response.status_code == 404
    assert "<script" not in response.get_data(as_text=True).split("</head>")[1]


@pytest.mark.parametrize("suffix", ["", "/status", "/download", "/site/index.html"])
def test_unknown_well_formed_id_is_not_found(client, suffix):
    missing = new_id()
    assert valid_id(missing)
    response = client.get(f"/jobs/{missing}{suffix}")
    assert response.status_code == 404
    assert "No such job" in response.get_data(as_text=True)


@pytest.mark.parametrize("name", ["../job.json", "..%2fjob.json", "%2e%2e/status.json", "static/../../job.json",
                                  "/etc/passwd", "..\\job.json", "../transcript.txt"])
def test_site_files_cannot_escape_the_generated_folder(client, done_job, name):
    url, _ = done_job
    response = client.get(f"{url}/site/{name}", follow_redirects=True)
    assert response.status_code == 404
    assert b'"face_label"' not in response.data


def test_id_shape_check_is_strict():
    assert valid_id(new_id())
    assert len({new_id() for _ in range(100)}) == 100
    for bad in ["", "../" + "A" * 29, "A" * 31 + "/", "A" * 31 + "\n", "Ä" * 32]:
        assert not valid_id(bad)


def test_download_names_keep_only_safe_characters():
    job_id = new_id()
    for title in [XSS, "../../etc/passwd", '"; filename=evil.exe', "你好", "", "a" * 300, "report 2026"]:
        name = download_name(title, job_id)
        assert re.fullmatch(r"cartoonface-[A-Za-z0-9_-]{1,40}\.zip", name), name
    assert download_name("你好", job_id) == f"cartoonface-{job_id[:8]}.zip"


# --- form checks ------------------------------------------------------------------------------------

def errors_of(response) -> str:
    assert response.status_code == 400, response.status_code
    return response.get_data(as_text=True)


def test_audio_type_is_decided_by_content_not_name(client, speech, sample_name):
    page = errors_of(post(client, form(client, speech, sample_name, audio=(io.BytesIO(b"hello " * 50), "talk.wav"))))
    assert "talk.wav: not a recording" in page
    accepted = post(client, form(client, speech, sample_name, audio=(io.BytesIO(speech), "notes.txt")))
    assert accepted.status_code == 303


def test_corrupt_wav_is_reported_with_the_users_file_name(client, speech, sample_name):
    corrupt = speech[:44] + bytes(np.random.default_rng(1).integers(0, 256, 40, dtype=np.uint8))
    corrupt = corrupt[:4] + (len(corrupt) * 50).to_bytes(4, "little") + corrupt[8:]
    page = errors_of(post(client, form(client, corrupt, sample_name, audio=(io.BytesIO(corrupt), "broken.wav"))))
    assert re.search(r'id="audio-error"[^>]*>broken\.wav: ', page)
    assert "/tmp" not in page and "recording.wav" not in page


def test_missing_recording_is_asked_for(client, speech, sample_name):
    page = errors_of(post(client, form(client, speech, sample_name, audio=None)))
    assert 'id="audio-error"' in page and "Choose a recording" in page


def test_recording_over_the_size_limit_is_refused_in_the_form(client, speech, sample_name):
    big = wav_bytes(np.zeros(600_000), 16000)  # 1.2 MB > MAX_UPLOAD_MB = 1
    page = errors_of(post(client, form(client, speech, sample_name, audio=(io.BytesIO(big), "long.wav"),
                                       title="still here")))
    assert "long.wav: the recording is larger than 1 MB" in page
    assert 'value="still here"' in page


def test_request_far_over_the_limit_gets_413_with_a_message(client, speech, sample_name):
    huge = b"RIFF" + bytes(36 << 20)  # over 1 MB recording + 20 MB photo + 8 MB TextGrid + the rest
    response = post(client, form(client, speech, sample_name, audio=(io.BytesIO(huge), "huge.wav")))
    assert response.status_code == 413
    assert "The upload is too large" in response.get_data(as_text=True)


def test_recording_over_30_minutes_is_refused(tmp_path, speech, sample_name):
    app = make_app(tmp_path, MAX_UPLOAD_MB=40)
    try:
        client = app.test_client()
        rate = 8000
        t = np.arange(int(rate * (30 * 60 + 2))) / rate
        long = wav_bytes(0.3 * np.sin(2 * np.pi * 220 * t) * (np.sin(2 * np.pi * 0.5 * t) > 0), rate)
        page = errors_of(post(client, form(client, speech, sample_name, audio=(io.BytesIO(long), "lecture.wav"))))
        assert "lecture.wav" in page and "30 minutes" in page
    finally:
        app.extensions["cartoonface"].runner.close()


def test_transcript_limits_and_encoding(client, speech, sample_name):
    page = errors_of(post(client, form(client, speech, sample_name, transcript="好" * 201)))
    assert "201 characters; at most 200" in page
    latin1 = "你好".encode("big5")
    page = errors_of(post(client, form(client, speech, sample_name, transcript_file=(io.BytesIO(latin1), "t.txt"))))
    assert "t.txt: not a text file: expected UTF-8 text" in page
    page = errors_of(post(client, form(client, speech, sample_name,
                                       transcript_file=(io.BytesIO("好".encode() * 300), "long.txt"))))
    assert 'id="transcript_file-error"' in page and "long.txt" in page


@pytest.mark.parametrize("content, expected", [
    (png_bytes(40, 30, (200, 10, 10)) * 30, "not a text file (it holds NUL bytes)"),
    (b"\xff\xfe" + "好".encode("utf-16-le") * 2000, "not a text file"),
    ("你好\x07世界。".encode(), "control character U+0007"),
])
def test_binary_or_control_characters_in_a_transcript_file_are_refused(client, speech, sample_name, content, expected):
    page = errors_of(post(client, form(client, speech, sample_name, transcript_file=(io.BytesIO(content), "t.bin"))))
    assert 'id="transcript_file-error"' in page
    assert expected in page
    assert "longer than" not in page


def test_the_mood_and_the_markup_reach_the_job(app, client, speech, sample_name):
    response = post(client, form(client, speech, sample_name, transcript="[happy]你好，世界。", mood="sad"))
    assert response.status_code == 303
    job = load_job(Path(app.instance_path), job_id_of(response.headers["Location"]))
    assert (job.folder / "transcript.txt").read_text(encoding="utf-8") == "[happy]你好，世界。"
    assert job.spec["mood"] == "sad"


@pytest.mark.parametrize("language", ["", "zh", "en"])
def test_the_language_choice_reaches_the_job(app, client, speech, sample_name, language):
    response = post(client, form(client, speech, sample_name, language=language))
    assert response.status_code == 303
    assert load_job(Path(app.instance_path), job_id_of(response.headers["Location"])).spec["language"] == language


def test_transcript_file_is_used_instead_of_pasted_text(app, client, speech, sample_name):
    response = post(client, form(client, speech, sample_name, transcript="",
                                 transcript_file=(io.BytesIO("\ufeff你好，世界。\r\n".encode()), "t.txt")))
    assert response.status_code == 303
    job = load_job(Path(app.instance_path), job_id_of(response.headers["Location"]))
    assert (job.folder / "transcript.txt").read_text(encoding="utf-8") == "你好，世界。"


@pytest.mark.parametrize("content, expected", [
    (b"\x89PNG\r\n\x1a\n", "not a face model: expected UTF-8 JSON"),
    (b"{\"format\": ", "not a face model: expected UTF-8 JSON"),
    (b"[" * 100_000, "the JSON is nested too deeply"),
    (b"1e999999", "face.json"),
    (b"[1, 2, 3]", "face.json"),
    (b"{\"format\": \"cartoonface-face\", \"version\": 1}", "face.json"),
])
def test_uploaded_face_model_is_validated(client, speech, sample_name, content, expected):
    page = errors_of(post(client, form(client, speech, sample_name, face_file=(io.BytesIO(content), "face.json"))))
    assert 'id="face_file-error"' in page
    assert expected in page


def test_uploaded_face_model_is_used_instead_of_the_sample(app, client, speech, sample_name):
    faces = sorted(SAMPLES.glob("*.json"))
    upload = faces[-1].read_bytes()
    response = post(client, form(client, speech, sample_name, face_sample="no-such-sample",
                                 face_file=(io.BytesIO(upload), "mine.json")))
    assert response.status_code == 303
    job = load_job(Path(app.instance_path), job_id_of(response.headers["Location"]))
    assert (job.folder / "face.json").read_bytes() == upload
    assert job.spec["face_label"] == "mine.json"


PHOTO = ROOT / "docs" / "photo-astronaut.png"


def test_a_photo_becomes_the_face_model_with_its_notes(app, client, speech, sample_name):
    response = post(client, form(client, speech, sample_name, photo=(io.BytesIO(PHOTO.read_bytes()), "me.png")))
    assert response.status_code == 303, response.get_data(as_text=True)
    job = load_job(Path(app.instance_path), job_id_of(response.headers["Location"]))
    model = face_from_dict(json.loads((job.folder / "face.json").read_text(encoding="utf-8")), "face.json")
    assert model.points.shape[1] == 2
    assert job.spec["face_label"] == "me.png"
    page = client.get(f"/jobs/{job.id}").get_data(as_text=True)
    for note in job.spec["face_notes"]:
        assert note.startswith("me.png: ")
        assert str(escape(note)) in page
    assert wait_done(client, f"/jobs/{job.id}")[-1]["state"] == DONE


@pytest.mark.parametrize("content, name, expected", [
    (b"just text, not an image" * 10, "me.jpg", "me.jpg: not a photo this app reads (by its content)"),
    (b"\xff\xd8\xff\xe0" + bytes(300), "broken.jpg", "broken.jpg: "),
    (png_bytes(320, 320, (200, 180, 160)), "wall.png", "wall.png: "),
])
def test_unusable_photos_are_reported_in_the_form(client, speech, sample_name, content, name, expected):
    page = errors_of(post(client, form(client, speech, sample_name, photo=(io.BytesIO(content), name))))
    assert re.search(r'id="photo-error"[^>]*>' + re.escape(str(escape(expected))), page)
    assert "/tmp" not in page and "photo.jpg" not in page and "photo.png" not in page


def test_photo_size_and_either_model_or_photo(client, speech, sample_name):
    big = b"\xff\xd8\xff" + bytes(MAX_PHOTO_BYTES)
    page = errors_of(post(client, form(client, speech, sample_name, photo=(io.BytesIO(big), "huge.jpg"))))
    assert "huge.jpg: a photo must be at most 20 MB" in page
    face = sorted(SAMPLES.glob("*.json"))[0].read_bytes()
    page = errors_of(post(client, form(client, speech, sample_name, photo=(io.BytesIO(PHOTO.read_bytes()), "me.png"),
                                       face_file=(io.BytesIO(face), "face.json"))))
    assert "Give either a face model (JSON) or a photo, not both." in page


@pytest.mark.parametrize("field, value, message", [
    ("face_sample", "../../etc/passwd", "Choose one of the sample faces"),
    ("page", "video", "Choose one of the page kinds"),
    ("background", "<img src=x>", "Choose one of the backgrounds"),
    ("clothes", "", "Choose one of the clothes"),
    ("style", "lively", "Choose one of the styles"),
    ("mood", "joy", "Choose one of the moods"),
    ("language", "fr", "Choose one of the languages"),
    ("transcript", "你好。\n世界[joy]。", "line 2, column 3: unknown emotion &#39;joy&#39;"),
    ("transcript", "你好[/sad]世界。", "line 1, column 3: closing mark [/sad]"),
    ("title", "x" * 201, "at most 200 are accepted"),
    ("title", "ring\x07bell", "control character U+0007"),
    ("title", "\x1b[31mred", "control character U+001B"),
    ("title", "nul\x00", "control character U+0000"),
    ("transcript", "你好\x00世界。", "control character U+0000"),
    ("transcript", "你好\x1b世界。", "control character U+001B"),
])
def test_choices_and_title_are_checked(client, speech, sample_name, field, value, message):
    page = errors_of(post(client, form(client, speech, sample_name, **{field: value})))
    assert f'id="{field}-error"' in page
    assert message in page
    assert "<img src=x>" not in page


def test_form_comes_back_with_what_the_user_entered_escaped(client, speech, sample_name):
    page = errors_of(post(client, form(client, speech, sample_name, audio=None, title=XSS,
                                       transcript=TRANSCRIPT + XSS, page="announcer")))
    assert XSS not in page
    assert 'value="&lt;script&gt;alert(&#39;x&#39;)&lt;/script&gt;"' in page
    assert f"{TRANSCRIPT}&lt;script&gt;" in page
    assert re.search(r'value="announcer" checked', page)


def test_wrong_methods_and_unknown_paths_answer_4xx(client):
    assert client.get("/jobs").status_code == 405
    assert client.put("/").status_code == 405
    assert client.post("/jobs/" + new_id()).status_code == 405
    assert client.get("/static/web/../../pyproject.toml").status_code == 404


def test_non_multipart_and_garbage_bodies_are_4xx(client):
    token = csrf(client)
    assert client.post("/jobs", data=b"\x00\xff" * 100, content_type="application/octet-stream").status_code == 400
    assert client.post("/jobs", data="csrf_token=" + token, content_type="application/x-www-form-urlencoded").status_code == 400
    broken = b"--xx\r\nContent-Disposition: form-data; name=\"audio\"; filename=\"a.wav\"\r\n\r\nRIFF"
    assert client.post("/jobs", data=broken, content_type="multipart/form-data; boundary=xx").status_code == 400


# --- jobs on disk, failures, restart, retention ----------------------------------------------------

def stored_inputs(speech: bytes) -> dict[str, bytes]:
    face = sorted(SAMPLES.glob("*.json"))[0].read_bytes()
    return {"face.json": face, "audio.wav": speech, "transcript.txt": TRANSCRIPT.encode()}


def spec(title: str = "t") -> dict[str, object]:
    return {"title": title, "page": "audiobook", "background": BACKGROUNDS[0], "clothes": CLOTHES[0], "face_label": "f",
            "audio_label": "a.wav", "audio_file": "audio.wav", "duration": 1.0, "transcript_chars": 5}


def test_a_job_the_pipeline_refuses_shows_its_error(app, client, speech):
    instance = Path(app.instance_path)
    files = stored_inputs(speech)
    files["audio.wav"] = b"RIFF\x10\x00\x00\x00WAVEfmt "  # truncated: the pipeline's own check refuses it
    job = create_job(instance, spec(XSS), files)
    app.extensions["cartoonface"].runner.submit(job.folder)
    seen = wait_done(client, f"/jobs/{job.id}")
    assert seen[-1]["state"] == FAILED
    assert seen[-1]["error"]
    page = client.get(f"/jobs/{job.id}").get_data(as_text=True)
    assert 'id="job-error"' in page
    assert seen[-1]["error"].startswith("a.wav: ")
    assert str(job.folder) not in seen[-1]["error"]
    assert str(escape(seen[-1]["error"])) in page
    assert XSS not in page
    assert client.get(f"/jobs/{job.id}/download").status_code == 404
    assert client.get(f"/jobs/{job.id}/site/index.html").status_code == 404


def test_a_waiting_job_shows_its_place_and_progress(app, client, speech):
    job = create_job(Path(app.instance_path), spec(XSS), stored_inputs(speech))  # stored, never queued
    status = client.get(f"/jobs/{job.id}/status").get_json()
    assert (status["state"], status["percent"], status["stage_label"]) == (QUEUED, 0, "Waiting for a free worker")
    page = client.get(f"/jobs/{job.id}").get_data(as_text=True)
    assert '<progress id="progress" max="100" value="0">' in page
    assert f'data-status-url="/jobs/{job.id}/status"' in page
    assert "/static/web/job.js" in page
    assert XSS not in page
    write_status(job.folder, Status(state=RUNNING, stage="svg", fraction=0.42))
    status = client.get(f"/jobs/{job.id}/status").get_json()
    assert (status["percent"], status["stage_label"]) == (42, "Drawing the frames")
    assert client.get("/static/web/job.js").status_code == 200


def test_the_job_page_lists_every_stage_with_those_passed_ticked(app, client, speech):
    job = create_job(Path(app.instance_path), spec("stages"), stored_inputs(speech))  # stored, never queued
    names = [name for name, _ in STAGES]
    for at, current in enumerate(names):
        write_status(job.folder, Status(state=RUNNING, stage=current, fraction=0.5))
        page = client.get(f"/jobs/{job.id}").get_data(as_text=True)
        marks = re.findall(r'<li data-stage="([a-z]+)"( class="(done|current)")?', page)
        assert [name for name, _, _ in marks] == names
        assert [mark for _, _, mark in marks] == ["done"] * at + ["current"] + [""] * (len(names) - at - 1)
        assert all(stage_label(Status(state=RUNNING, stage=name)) in page for name in names)


def test_restart_keeps_finished_jobs_and_fails_interrupted_ones(tmp_path, speech, sample_name):
    first = make_app(tmp_path)
    client = first.test_client()
    response = post(client, form(client, speech, sample_name, title="survivor"))
    url = response.headers["Location"]
    assert wait_done(client, url)[-1]["state"] == DONE
    first.extensions["cartoonface"].runner.close()
    # What a server killed mid-way leaves behind: one job still queued, one running.
    queued = create_job(tmp_path, spec("never started"), stored_inputs(speech))
    running = create_job(tmp_path, spec("half done"), stored_inputs(speech))
    write_status(running.folder, Status(state=RUNNING, stage="frames", fraction=0.5))

    second = make_app(tmp_path)
    try:
        again = second.test_client()
        again.set_cookie("session", client.get_cookie("session").value)
        assert again.get(f"{url}/status").get_json()["state"] == DONE
        assert again.get(f"{url}/download").status_code == 200
        assert "survivor" in again.get("/").get_data(as_text=True)
        for job in (queued, running):
            status = again.get(f"/jobs/{job.id}/status").get_json()
            assert status["state"] == FAILED
            assert status["error"] == INTERRUPTED
            assert "Interrupted: the server stopped" in again.get(f"/jobs/{job.id}").get_data(as_text=True)
    finally:
        second.extensions["cartoonface"].runner.close()


def test_closing_the_runner_fails_the_job_it_was_running(tmp_path, speech):
    job = create_job(tmp_path, spec(), stored_inputs(speech))
    runner = Runner(tmp_path, 1)
    runner.submit(job.folder)
    deadline = time.monotonic() + 60
    while load_job(tmp_path, job.id).status.state == QUEUED and time.monotonic() < deadline:
        time.sleep(0.02)
    assert load_job(tmp_path, job.id).status.state == RUNNING
    runner.close()
    status = load_job(tmp_path, job.id).status
    assert (status.state, status.error) == (FAILED, STOPPED)


def test_a_worker_whose_server_is_gone_stops_without_finishing(tmp_path, speech):
    job = create_job(tmp_path, spec(), stored_inputs(speech))
    # Parent pid 1 is not the worker's parent: it acts as if its server had died.
    done = subprocess.run([sys.executable, "-m", "cartoonface.web.worker", str(job.folder), "1"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 3
    assert "the server went away" in done.stderr
    assert load_job(tmp_path, job.id).status.state == RUNNING
    assert not (job.folder / "site").exists()


def test_unreadable_job_folders_are_skipped(app, client):
    broken = Path(app.instance_path) / "jobs" / new_id()
    broken.mkdir(parents=True)
    (broken / "job.json").write_text("{not json")
    assert client.get(f"/jobs/{broken.name}").status_code == 404
    assert broken.name not in {job.id for job in list_jobs(Path(app.instance_path))}


def test_retention_by_age_and_by_total_size(tmp_path, speech):
    now = time.time()
    jobs = [create_job(tmp_path, spec(f"job {i}"), {"audio.wav": bytes(300_000)}) for i in range(4)]
    for age_days, job in zip([30, 3, 2, 1], jobs):
        data = json.loads((job.folder / "job.json").read_text())
        data["created"] = now - age_days * 86400
        (job.folder / "job.json").write_text(json.dumps(data))
        write_status(job.folder, Status(state=DONE))
    write_status(jobs[1].folder, Status(state=RUNNING))  # never deleted while it runs
    deleted = apply_retention(tmp_path, max_age_days=7, now=now)
    assert deleted == [jobs[0].id]  # too old; younger finished jobs stay whatever their size
    assert {job.id for job in list_jobs(tmp_path)} == {job.id for job in jobs[1:]}
    # a full disk refuses new jobs instead: per user, then all together
    mine = [jobs[2].id, jobs[3].id]
    assert "of the 0.5 MB kept for each user" in space_problem(tmp_path, mine, 1000, 2**19, 10 * 2**20)
    assert space_problem(tmp_path, mine, 1000, 2**20, 10 * 2**20) == ""
    assert "storage for jobs is full" in space_problem(tmp_path, [], 1000, 2**20, 2**19)
    assert not any(path.name.startswith(".deleted") for path in (tmp_path / "jobs").iterdir())


# --- configuration and the serve command ---------------------------------------------------------------

def test_settings_from_environment_and_instance_file(tmp_path, monkeypatch, speech, sample_name):
    (tmp_path / "config.py").write_text("MAX_TRANSCRIPT_CHARS = 3\nRETENTION_DAYS = 1\n")
    monkeypatch.setenv("CARTOONFACE_INSTANCE_PATH", str(tmp_path))
    monkeypatch.setenv("CARTOONFACE_WORKERS", "1")
    monkeypatch.setenv("CARTOONFACE_MAX_UPLOAD_MB", "2")
    app = create_app()
    app.test_client_class = Client
    try:
        settings = app.extensions["cartoonface"].settings
        assert settings.instance == tmp_path.resolve()
        assert (settings.transcript_chars, settings.workers, settings.upload_bytes) == (3, 1, 2 << 20)
        assert settings.retention_days == 1
        client = app.test_client()
        assert "at most 3 are accepted" in errors_of(post(client, form(client, speech, sample_name)))
    finally:
        app.extensions["cartoonface"].runner.close()


@pytest.mark.parametrize("key, value", [("WORKERS", 0), ("WORKERS", "many"), ("MAX_UPLOAD_MB", -1),
                                        ("MAX_TRANSCRIPT_CHARS", 2.5), ("RETENTION_DAYS", True)])
def test_bad_settings_name_the_variable(tmp_path, key, value):
    with pytest.raises(OptionError, match=f"CARTOONFACE_{key}"):
        create_app({"INSTANCE_PATH": str(tmp_path), key: value})


def test_secret_key_is_kept_in_the_instance_folder(tmp_path):
    apps = [make_app(tmp_path) for _ in range(2)]
    for app in apps:
        app.extensions["cartoonface"].runner.close()
    assert apps[0].secret_key == apps[1].secret_key
    assert (tmp_path / "secret_key").stat().st_mode & 0o077 == 0


def test_serve_command_is_registered_with_its_options():
    done = run_cli("serve", "--help")
    assert done.returncode == 0
    for option in ("--host", "--port", "--instance"):
        assert option in done.stdout
    assert "127.0.0.1" in done.stdout and "5000" in done.stdout


def test_serve_refuses_bad_settings_with_exit_2(tmp_path):
    done = subprocess.run([sys.executable, "-m", "cartoonface", "serve", "--instance", str(tmp_path), "--port", "1"],
                          capture_output=True, text=True, timeout=60, env={**os.environ, "CARTOONFACE_WORKERS": "0"})
    assert done.returncode == 2
    assert "CARTOONFACE_WORKERS" in done.stderr
    assert "Traceback" not in done.stderr


def test_serve_reports_a_port_it_cannot_use(tmp_path):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        done = run_cli("serve", "--instance", tmp_path, "--port", port, timeout=60)
    assert done.returncode == 2
    assert f"--port {port}: cannot listen there" in done.stderr
    assert "Traceback" not in done.stderr
    done = run_cli("serve", "--port", "70000")
    assert done.returncode == 2
    assert "expected a port number from 1 to 65535" in done.stderr


# --- limits a hostile job cannot break ---------------------------------------------------------


def test_a_job_over_its_memory_limit_fails_alone_with_a_clear_message(tmp_path, speech):
    job = create_job(tmp_path, spec(), stored_inputs(speech))
    runner = Runner(tmp_path, 1, limits=JobLimits(memory_bytes=300 << 20, cpu_seconds=600))
    try:
        runner.submit(job.folder)
        deadline = time.monotonic() + 120
        while load_job(tmp_path, job.id).status.state not in (DONE, FAILED) and time.monotonic() < deadline:
            time.sleep(0.1)
    finally:
        runner.close()
    status = load_job(tmp_path, job.id).status
    assert status.state == FAILED
    assert status.error == JobLimits(300 << 20, 600).memory_message()
    assert "0.293 GB of memory" in status.error


def test_a_library_error_from_a_failed_allocation_counts_as_out_of_memory():
    def chained(inner: BaseException, outer: Exception) -> Exception:
        try:
            raise outer from inner
        except Exception as exc:
            return exc

    assert out_of_memory(MemoryError())
    assert out_of_memory(RuntimeError("std::bad_alloc"))  # parselmouth's C++ allocation failure
    assert out_of_memory(chained(MemoryError(), ValueError("could not read the recording")))
    # a library imported under the job's address-space limit (dlopen cannot map it)
    assert out_of_memory(ImportError("libfoo.so: failed to map segment from shared object"))
    assert not out_of_memory(ValueError("could not read the recording"))
    assert not out_of_memory(chained(KeyError("x"), RuntimeError("a bug")))


def test_the_queue_is_capped_and_tells_a_waiting_job_its_place(tmp_path, speech):
    jobs = [create_job(tmp_path, spec(f"job {i}"), stored_inputs(speech)) for i in range(3)]
    runner = Runner(tmp_path, 1, queue_max=1)
    try:
        runner.submit(jobs[0].folder)
        deadline = time.monotonic() + 60
        while load_job(tmp_path, jobs[0].id).status.state == QUEUED and time.monotonic() < deadline:
            time.sleep(0.02)
        assert runner.has_room()
        runner.submit(jobs[1].folder)
        assert runner.ahead_of(jobs[1].folder) == 0
        assert not runner.has_room()
        with pytest.raises(QueueFull):
            runner.submit(jobs[2].folder)
    finally:
        runner.close()
    assert stage_label(Status(state=QUEUED), 3) == "Waiting for a free worker: 3 jobs ahead of you"


def test_job_folders_and_files_are_private(tmp_path, speech):
    job = create_job(tmp_path, spec(), stored_inputs(speech))
    assert stat.S_IMODE(job.folder.stat().st_mode) == FOLDER_MODE
    modes = {path.name: stat.S_IMODE(path.stat().st_mode) for path in job.folder.iterdir()}
    assert set(modes) == {"face.json", "audio.wav", "transcript.txt", "job.json", "status.json"}
    assert set(modes.values()) == {FILE_MODE}
