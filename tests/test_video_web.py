"""The web form takes a video of the speaker in place of a recording (tests/data/grid, CC BY 4.0)."""

from __future__ import annotations

import io
import subprocess
from pathlib import Path

from cartoonface.speech.audio import ffmpeg_exe
from cartoonface.web.store import DONE, FAILED, load_job
from tests.conftest import form, post, wait_done
from tests.clips import GRID, make_clip

SAMPLE = "female"


def job_of(app, response):
    return load_job(Path(app.instance_path), response.headers["Location"].rstrip("/").rsplit("/", 1)[-1])


def test_a_video_upload_makes_a_page_driven_by_it(app, client):
    data = form(client, b"", SAMPLE, transcript="", audio=(io.BytesIO(GRID.read_bytes()), "me.mpg"))
    response = post(client, data)
    assert response.status_code == 303, response.get_data(as_text=True)
    job = job_of(app, response)
    assert job.spec["video"] is True and 2.9 < float(str(job.spec["duration"])) < 3.1
    seen = wait_done(client, response.headers["Location"])
    assert seen[-1]["state"] == DONE, seen[-1]
    site = job.folder / "site"
    assert (site / "audio.m4a").is_file() and (site / "animation.svg").stat().st_size > 10_000


def test_sound_in_an_mp4_box_is_still_a_recording(app, client, tmp_path):
    m4a = tmp_path / "speech.m4a"
    subprocess.run([ffmpeg_exe(), "-nostdin", "-v", "error", "-i", str(GRID), "-vn", "-c:a", "aac", str(m4a)],
                   check=True)
    response = post(client, form(client, b"", SAMPLE, transcript="", audio=(io.BytesIO(m4a.read_bytes()), "s.m4a")))
    assert response.status_code == 303, response.get_data(as_text=True)
    assert job_of(app, response).spec["video"] is False


def test_a_video_without_a_face_fails_with_its_name(app, client, tmp_path):
    pattern = make_clip(tmp_path / "pattern.webm", "-f", "lavfi", "-i", "testsrc=size=160x120:rate=10", "-t", "1",
                        "-f", "lavfi", "-i", "sine=frequency=200", "-t", "1")
    response = post(client, form(client, b"", SAMPLE, transcript="",
                                 audio=(io.BytesIO(pattern.read_bytes()), "holiday.webm")))
    assert response.status_code == 303, response.get_data(as_text=True)
    seen = wait_done(client, response.headers["Location"])
    assert seen[-1]["state"] == FAILED and "holiday.webm" in seen[-1]["error"] and "face" in seen[-1]["error"]
    assert str(tmp_path) not in seen[-1]["error"]


def test_a_garbled_video_is_refused_by_the_form(client):
    garbled = b"\x1a\x45\xdf\xa3" + b"\x00garbage" * 100
    response = post(client, form(client, b"", SAMPLE, transcript="", audio=(io.BytesIO(garbled), "clip.webm")))
    assert response.status_code == 400
    assert "clip.webm" in response.get_data(as_text=True)
