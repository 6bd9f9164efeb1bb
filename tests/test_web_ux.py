"""The form's and pages' usability through Flask's test client: sample faces as pictures,
options labelled by what they affect, and the advanced section that takes a corrected
TextGrid and an edited actions.json (offered for download on every finished job)."""

from __future__ import annotations

import io
import json
import re

import pytest
from lxml import etree

from cartoonface.speech.textgrid import read_textgrid
from cartoonface.web.inputs import MAX_ACTIONS_BYTES
from tests.conftest import ROOT, make_app, post, wait_done
from tests.conftest import form as full_form

STORY = ROOT / "samples" / "speech"
TRANSCRIPT = (STORY / "story.txt").read_text(encoding="utf-8")
FIRST = TRANSCRIPT.splitlines()[0]
EDITED = FIRST.replace("小白兔", "小黑兔")  # the first sentence as corrected in the TextGrid


@pytest.fixture(scope="module")
def app(tmp_path_factory: pytest.TempPathFactory):
    """One app (one worker) taking the sample story (25 s: long enough for blinks and nods)."""
    app = make_app(tmp_path_factory.mktemp("instance"), MAX_UPLOAD_MB=4, MAX_TRANSCRIPT_CHARS=2000)
    yield app
    app.extensions["cartoonface"].runner.close()


@pytest.fixture(scope="module")
def speech() -> bytes:
    """The sample story's recording (WAV bytes)."""
    return (STORY / "story.wav").read_bytes()


def form(client, speech: bytes, sample: str, **fields) -> dict:
    """A complete, valid form for the sample story; `fields` replace or (None) remove entries."""
    return full_form(client, speech, sample, **{"transcript": TRANSCRIPT, **fields})


@pytest.fixture(scope="module")
def samples(app) -> list[str]:
    return list(app.extensions["cartoonface"].limits.samples)


@pytest.fixture(scope="module")
def first_job(app, speech, samples) -> tuple[str, str, str]:
    """A finished job with the automatic timing and actions: (job url, its TextGrid, its actions.json)."""
    client = app.test_client()
    url = post(client, form(client, speech, samples[0])).headers["Location"]
    assert wait_done(client, url)[-1]["state"] == "done"
    page = client.get(url).get_data(as_text=True)
    links = {name: re.search(rf'id="download-{name}" href="([^"]+)"', page) for name in ("textgrid", "actions")}
    assert all(links.values()), "the result page links the TextGrid and actions.json"
    textgrid, actions = (client.get(links[name].group(1)) for name in ("textgrid", "actions"))  # type: ignore[union-attr]
    assert textgrid.status_code == actions.status_code == 200
    return url, textgrid.get_data(as_text=True), actions.get_data(as_text=True)


def submit(client, speech: bytes, sample: str, **files: tuple[bytes, str]):
    """Post the form with the recording and the advanced files `files` (field -> (bytes, name))."""
    fields = {field: (io.BytesIO(data), name) for field, (data, name) in files.items()}
    return post(client, form(client, speech, sample, **fields))


def test_sample_faces_are_radio_buttons_with_their_cartoon(client, samples):
    page = client.get("/").get_data(as_text=True)
    for name in samples:
        assert f'<input type="radio" name="face_sample" value="{name}"' in page
        assert f'src="/samples/{name}.svg"' in page
        answer = client.get(f"/samples/{name}.svg")
        assert answer.status_code == 200 and answer.mimetype == "image/svg+xml"
        assert etree.fromstring(answer.get_data()).tag.endswith("svg")
    assert re.search(r'name="face_sample" value="[^"]+" checked', page)  # one is chosen
    drawn = {client.get(f"/samples/{name}.svg").get_data() for name in samples}
    assert len(drawn) == len(samples)  # each sample has its own picture
    for bad in ("nobody", "..%2f..%2fetc%2fpasswd", "female.json"):
        assert client.get(f"/samples/{bad}.svg").status_code == 404


def test_options_say_what_they_affect(client):
    page = client.get("/").get_data(as_text=True)
    assert "(announcer)" not in page
    for field in ("style", "title", "background", "clothes"):
        help_line = re.search(rf'<p class="help" id="{field}-help">([^<]+)</p>', page)
        assert help_line and len(help_line.group(1)) > 20, field
        assert re.search(rf'id="{field}"[^>]*aria-describedby="{field}-help"', page), field
    assert "both kinds of page" in page


def test_the_advanced_section_is_folded_away_with_its_two_files(client):
    page = client.get("/").get_data(as_text=True)
    section = re.search(r'<details class="advanced" id="advanced">(.*?)</details>', page, re.S)
    assert section, "a closed <details> section"
    assert 'type="file" id="textgrid_file" name="textgrid_file"' in section.group(1)
    assert 'type="file" id="actions_file" name="actions_file"' in section.group(1)


def test_the_result_page_says_how_to_correct_and_upload_again(client, first_job):
    url, textgrid, actions = first_job
    page = client.get(url).get_data(as_text=True)
    assert "Advanced" in page and "Praat" in page
    assert read_textgrid(textgrid, "job").sentences[0].text == FIRST
    assert json.loads(actions)["actions"]


def test_a_corrected_textgrid_and_edited_actions_are_used(app, speech, samples, first_job):
    _url, textgrid, actions = first_job
    automatic = json.loads(actions)
    assert any(row["kind"] == "blink" for row in automatic["actions"])
    edited_actions = {**automatic, "actions": [row for row in automatic["actions"] if row["kind"] != "blink"]}
    assert EDITED != FIRST
    corrected = textgrid.replace(FIRST, EDITED)
    client = app.test_client()
    # as Praat saves a TextGrid holding Chinese: UTF-16 with a byte order mark
    response = submit(client, speech, samples[0],
                      textgrid_file=(corrected.encode("utf-16"), "mine.TextGrid"),
                      actions_file=(json.dumps(edited_actions).encode(), "mine.json"))
    assert response.status_code == 303, response.get_data(as_text=True)
    url = response.headers["Location"]
    assert wait_done(client, url)[-1]["state"] == "done"
    job_page = client.get(url).get_data(as_text=True)
    assert "timing from your TextGrid mine.TextGrid" in job_page and "actions from your mine.json" in job_page
    made = client.get(f"{url}/site/alignment.TextGrid").get_data(as_text=True)
    assert read_textgrid(made, "job").sentences[0].text == EDITED
    used = json.loads(client.get(f"{url}/site/actions.json").get_data(as_text=True))
    assert not any(row["kind"] == "blink" for row in used["actions"])
    assert len(used["actions"]) == len(edited_actions["actions"])
    assert EDITED in client.get(f"{url}/site/index.html").get_data(as_text=True)


@pytest.mark.parametrize("field, content, expected", [
    ("textgrid_file", b"\x89PNG\r\n\x1a\n\x00\x00", "not a text file"),
    ("textgrid_file", "just some words".encode(), "mine"),
    ("actions_file", b"{not json", "not valid JSON"),
    ("actions_file", b'{"format": "cartoonface-actions", "version": 1, "actions": [{"kind": "blink", "start": '
                     + b"9" * 5000 + b', "duration": 0.2}]}', "too long"),
    ("actions_file", b'{"format": "cartoonface-actions", "version": 1, "actions": [{"kind": "wink", '
                     b'"start": 0.1, "duration": 0.2, "amplitude": 1.0}]}', "wink"),
    ("actions_file", b"[" * 100000, "nested too deeply"),
    ("actions_file", b" " * (MAX_ACTIONS_BYTES + 1), "larger than"),
])
def test_bad_edited_files_come_back_in_their_field(client, speech, samples, field, content, expected):
    response = submit(client, speech, samples[0], **{field: (content, "mine.bin")})
    text = response.get_data(as_text=True)
    assert response.status_code == 400
    message = re.search(rf'<p class="field-error" id="{field}-error" role="alert">([^<]*)</p>', text)
    assert message and expected in message.group(1) and "mine.bin" in message.group(1), message
    assert "cartoonface-upload-" not in text  # no server path
    assert '<details class="advanced" id="advanced" open>' in text


def test_a_textgrid_longer_than_the_recording_is_refused(client, speech, samples, first_job):
    _url, textgrid, _actions = first_job
    last = read_textgrid(textgrid, "job").sentences[-1].end
    stretched = re.sub(r"(xmax = )([0-9.]+)", lambda m: f"{m.group(1)}{float(m.group(2)) + 10:g}", textgrid)
    stretched = re.sub(r"(xmin = )([0-9.]+)", lambda m: f"{m.group(1)}{float(m.group(2)) + 10:g}"
                       if float(m.group(2)) > 0 else m.group(0), stretched)
    response = submit(client, speech, samples[0], textgrid_file=(stretched.encode(), "late.TextGrid"))
    text = response.get_data(as_text=True)
    assert response.status_code == 400 and last > 0
    assert re.search(r'id="textgrid_file-error"[^>]*>late.TextGrid: a sentence ends at', text), text[:2000]
