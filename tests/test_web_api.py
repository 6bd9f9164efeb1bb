"""The JSON API (/api/...) through Flask's test client, with the real pipeline and queue."""

from __future__ import annotations

import io
import os
import socket
import time
import zipfile

import pytest

from cartoonface.web.api import owner_of
from tests.conftest import ROOT, TRANSCRIPT, make_app

SAMPLES = ROOT / "samples" / "faces"
TOKEN = "test-token-0123456789abcdef"
OTHER = "other-token-0123456789abcdef"
TITLE = "API <book> & co"


@pytest.fixture(scope="module")
def speech(spoken: bytes) -> bytes:
    """A short Mandarin recording (WAV bytes): conftest's `spoken`."""
    return spoken


@pytest.fixture(scope="module")
def api_app(tmp_path_factory: pytest.TempPathFactory):
    app = make_app(tmp_path_factory.mktemp("instance"), API_TOKEN=[TOKEN, OTHER], MAX_UPLOAD_MB=1)
    yield app
    app.extensions["cartoonface"].runner.close()


def auth(token: str = TOKEN) -> dict[str, str]:
    return {"Authorization": f"Bearer {token}"}


def sample() -> str:
    return sorted(SAMPLES.glob("*.json"))[0].stem


def fields(speech: bytes, **changes) -> dict:
    data = {"sample": sample(), "title": TITLE, "transcript": TRANSCRIPT, "audio": (io.BytesIO(speech), "talk.wav")}
    for key, value in changes.items():
        if value is None:
            data.pop(key)
        else:
            data[key] = value
    return data


def submit(client, data: dict, token: str = TOKEN):
    return client.post("/api/jobs", data=data, headers=auth(token), content_type="multipart/form-data")


def wait(client, url: str, token: str = TOKEN, timeout: float = 120) -> dict:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        job = client.get(url, headers=auth(token)).get_json()
        if job["state"] not in ("queued", "running"):
            return job
        time.sleep(0.1)
    raise AssertionError(f"{url} did not finish")


@pytest.fixture(scope="module")
def done_job(api_app, speech) -> dict:
    client = api_app.test_client()
    response = submit(client, fields(speech))
    assert response.status_code == 201, response.get_data(as_text=True)
    assert response.headers["Location"] == response.get_json()["links"]["self"]
    return wait(client, response.headers["Location"])


def test_a_job_runs_to_done_with_its_worker_and_links(done_job):
    assert (done_job["state"], done_job["progress"], done_job["error"]) == ("done", 100, None)
    assert done_job["title"] == TITLE
    # Embedded queue: the consumer is in this process; the worker names its host and pid.
    assert done_job["worker"] == {"host": socket.gethostname(), "pid": os.getpid(), "run": 1}
    assert done_job["result"]["frames"] > 0
    assert done_job["links"]["result_zip"] == f"/api/jobs/{done_job['id']}/result.zip"


def test_the_result_zip_is_the_generated_folder_with_its_audio(api_app, done_job):
    response = api_app.test_client().get(done_job["links"]["result_zip"], headers=auth())
    assert response.status_code == 200 and response.mimetype == "application/zip"
    with zipfile.ZipFile(io.BytesIO(response.data)) as archive:
        names = archive.namelist()
        page = archive.read(next(name for name in names if name.endswith("/index.html"))).decode()
        audio = next(name for name in names if name.endswith("/audio.m4a"))
        assert archive.getinfo(audio).file_size > 0
    assert "API &lt;book&gt; &amp; co" in page and "audio.m4a" in page


def test_another_token_cannot_see_the_job(api_app, done_job):
    client = api_app.test_client()
    for url in (done_job["links"]["self"], done_job["links"]["result_zip"]):
        response = client.get(url, headers=auth(OTHER))
        assert response.status_code == 404 and "No such job" in response.get_json()["error"]


@pytest.mark.parametrize("headers", [{}, {"Authorization": "Bearer wrong-token-0123456789abcdef"},
                                     {"Authorization": f"Basic {TOKEN}"}, {"Authorization": "Bearer"}])
def test_requests_without_the_token_get_401(api_app, done_job, headers):
    response = api_app.test_client().get(done_job["links"]["self"], headers=headers)
    assert response.status_code == 401
    assert response.headers["WWW-Authenticate"].startswith("Bearer")
    assert response.get_json()["field"] == "Authorization"


def test_the_api_is_off_without_a_token(tmp_path):
    app = make_app(tmp_path)
    try:
        response = app.test_client().post("/api/jobs", headers=auth())
    finally:
        app.extensions["cartoonface"].runner.close()
    assert response.status_code == 404 and "CARTOONFACE_API_TOKEN" in response.get_json()["error"]


def test_a_transcript_file_and_a_face_file(api_app, speech):
    client = api_app.test_client()
    face = (SAMPLES / f"{sample()}.json").read_bytes()
    data = fields(speech, sample=None, transcript=(io.BytesIO(TRANSCRIPT.encode()), "t.txt"),
                  face=(io.BytesIO(face), "me.json"), page="announcer")
    response = submit(client, data)
    assert response.status_code == 201, response.get_data(as_text=True)
    assert wait(client, response.headers["Location"])["state"] == "done"


@pytest.mark.parametrize("change, field", [
    ({"page": "radio"}, "page"),
    ({"audio": None}, "audio"),
    ({"sample": "nobody"}, "sample"),
    ({"sample": None}, "face"),
    ({"face": (io.BytesIO(b"{not json"), "f.json")}, "face"),
    ({"transcript": "bad\x07text"}, "transcript"),
    ({"transcript": (io.BytesIO(b"\x89PNG\r\n\x1a\n\x00\x00"), "t.txt")}, "transcript"),
    ({"title": "x" * 500}, "title"),
    ({"colour": "red"}, "colour"),
    ({"audio": (io.BytesIO(b"not audio at all"), "a.wav")}, "audio"),
])
def test_bad_fields_are_400_naming_the_field(api_app, speech, change, field):
    response = submit(api_app.test_client(), fields(speech, **change))
    assert response.status_code == 400
    body = response.get_json()
    assert body["field"] == field and body["error"]


def test_too_large_and_unknown_routes_answer_json(api_app, speech):
    client = api_app.test_client()
    big = fields(speech, audio=(io.BytesIO(b"\0" * (api_app.config["MAX_CONTENT_LENGTH"] + 1)), "big.wav"))
    response = submit(client, big)
    assert response.status_code == 413 and "too large" in response.get_json()["error"]
    for method, path in (("GET", "/api/nothing"), ("DELETE", "/api/jobs"), ("GET", "/api/jobs/short")):
        response = client.open(path, method=method, headers=auth())
        assert 400 <= response.status_code < 500 and "error" in response.get_json()


def test_the_disk_quota_is_per_token(tmp_path, speech):
    app = make_app(tmp_path, API_TOKEN=[TOKEN, OTHER], USER_QUOTA_MB=len(speech) * 1.5 / 2**20)
    try:
        client = app.test_client()
        assert submit(client, fields(speech)).status_code == 201
        refused = submit(client, fields(speech))
        assert refused.status_code == 429 and "Your jobs take" in refused.get_json()["error"]
        assert submit(client, fields(speech), OTHER).status_code == 201
    finally:
        app.extensions["cartoonface"].runner.close()
    assert owner_of(TOKEN) != owner_of(OTHER) and TOKEN not in owner_of(TOKEN)
