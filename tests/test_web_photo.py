"""Face from a photo in the web app: upload, detected points over the photo, cartoon
preview, edited points, and the job that uses them (Flask test client; one browser test)."""

from __future__ import annotations

import io
import json
import os
import re
import time
from pathlib import Path

import numpy as np
import pytest
from lxml import etree
from markupsafe import escape
from PIL import Image

from cartoonface.face.model import POINT_NAMES, face_from_dict
from cartoonface.web import inputs, photo_views
from cartoonface.files import TRASH_PREFIX, remove_folder
from cartoonface.web.draft_store import (DRAFT_SECONDS, EDIT_FILE, MAX_DRAFTS, drafts_root, linear_map, load_draft,
                                         sweep_drafts)
from cartoonface.web.inputs import MAX_PHOTO_BYTES
from cartoonface.web.store import load_job, new_id
from tests.conftest import SPOKEN, TRANSCRIPT, csrf, form, png_bytes, post, speak

pytest.importorskip("mediapipe", reason="needs the photo extra (scripts/setup.sh)")

SVG_NS = "{http://www.w3.org/2000/svg}"
BAD_NAME = "<img src=x onerror=alert(1)>.jpg"


def astronaut_jpeg() -> bytes:
    """skimage's astronaut portrait as JPEG bytes."""
    from skimage import data

    buffer = io.BytesIO()
    Image.fromarray(data.astronaut()).save(buffer, "JPEG", quality=90)
    return buffer.getvalue()


@pytest.fixture(scope="module")
def photo() -> bytes:
    return astronaut_jpeg()


@pytest.fixture(scope="module")
def speech(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A short Mandarin recording made with espeak-ng (a WAV file) of tests/test_web.py's text."""
    path = tmp_path_factory.mktemp("speech") / "speech.wav"
    speak(SPOKEN, path)
    return path


def upload(client, content: bytes, name: str = "astro.jpg", token: str | None = "") -> object:
    data = {"photo": (io.BytesIO(content), name)}
    if token is not None:
        data["csrf_token"] = token or csrf(client)
    return client.post("/photos", data=data, content_type="multipart/form-data")


@pytest.fixture()
def draft_url(client, photo) -> str:
    """The editor URL of a fresh draft of the astronaut photo."""
    response = upload(client, photo, BAD_NAME)
    assert response.status_code == 303, response.get_data(as_text=True)
    return response.headers["Location"]


def page_points(page: str) -> dict[str, list[float]]:
    """The points the editor page holds in its form field."""
    value = re.search(r'id="points" value="([^"]+)"', page).group(1)
    return json.loads(value.replace("&#34;", '"'))


def draft_of(app, url: str):
    return load_draft(Path(app.instance_path), url.rsplit("/", 1)[1])


def test_upload_shows_the_points_over_the_photo_and_the_cartoon(app, client, draft_url):
    page = client.get(draft_url).get_data(as_text=True)
    draft = draft_of(app, draft_url)
    names = re.findall(r'<circle class="point"[^>]*data-name="([^"]+)"', page)
    assert names == list(POINT_NAMES)
    assert "<title>2.1: chin</title>" in page
    # the user's file name and the photo's warnings are shown escaped
    assert str(escape(BAD_NAME)) in page and BAD_NAME not in page
    for warning in draft.warnings:
        assert str(escape(warning)) in page
    photo = Image.open(io.BytesIO(client.get(draft_url + "/photo.jpg").data))
    assert photo.format == "JPEG"
    assert f'viewBox="0 0 {photo.width} {photo.height}"' in page
    # the detected points lie on the photo, the eyes above the mouth above the chin
    points = page_points(page)
    assert all(0 <= x <= photo.width and 0 <= y <= photo.height for x, y in points.values())
    assert points["3.5"][1] < points["8.1"][1] < points["2.1"][1]
    preview = client.get(draft_url + "/preview.svg")
    assert preview.mimetype == "image/svg+xml"
    root = etree.fromstring(preview.data)
    assert [g.get("id") for g in root.findall(f"{SVG_NS}g")] == ["background", "hair", "clothes", "face"]
    script = re.search(r'<script src="([^"]+)"', page).group(1)
    assert client.get(script).status_code == 200
    assert "script-src 'self'" in client.get(draft_url).headers["Content-Security-Policy"]


def test_several_faces_are_warned_about_and_the_largest_is_used(app, client):
    from skimage import data

    astronaut = Image.fromarray(data.astronaut())
    canvas = Image.new("RGB", (900, 512), (200, 200, 200))
    canvas.paste(astronaut, (0, 0))
    canvas.paste(astronaut.resize((320, 320)), (560, 100))
    buffer = io.BytesIO()
    canvas.save(buffer, "PNG")
    response = upload(client, buffer.getvalue(), "two.png")
    assert response.status_code == 303
    page = client.get(response.headers["Location"]).get_data(as_text=True)
    assert re.search(r'id="photo-warnings">.*2 faces in the photo; using the largest', page, re.S)
    # the shown part of the photo is around the larger face (the left one)
    draft = draft_of(app, response.headers["Location"])
    assert draft.size[0] < 560 * 1.1


def test_a_busy_server_says_so(app, client, photo, monkeypatch):
    monkeypatch.setattr(photo_views, "DETECT_WAIT", 0.05)
    assert inputs.DETECTING.acquire(timeout=5)
    try:
        answer = upload(client, photo)
    finally:
        inputs.DETECTING.release()
    assert answer.status_code == 429
    assert "busy" in answer.get_data(as_text=True)
    assert upload(client, photo).status_code == 303


def test_moving_a_point_moves_the_cartoon_and_is_saved(app, client, draft_url):
    token = csrf(client)
    points = page_points(client.get(draft_url).get_data(as_text=True))
    before = face_from_dict(dict(draft_of(app, draft_url).face), "before")
    points["2.1"][1] += 15.0
    answer = client.post(draft_url + "/preview", data={"csrf_token": token, "points": json.dumps(points)})
    assert answer.status_code == 200
    root = etree.fromstring(answer.get_json()["svg"].encode("utf-8"))
    assert root.find(f"{SVG_NS}g[@id='face']") is not None
    after = face_from_dict(dict(draft_of(app, draft_url).face), "after")
    chin = POINT_NAMES.index("2.1")
    assert after.points[chin, 1] > before.points[chin, 1] + 1.0
    moved = np.flatnonzero(np.any(np.abs(after.points - before.points) > 1e-6, axis=1))
    assert [POINT_NAMES[i] for i in moved] == ["2.1"]
    # the page shows the point where it was left
    assert page_points(client.get(draft_url).get_data(as_text=True))["2.1"] == pytest.approx(points["2.1"], abs=0.01)
    assert etree.fromstring(client.get(draft_url + "/preview.svg").data).find(f"{SVG_NS}g[@id='face']") is not None


def test_a_point_somewhere_impossible_is_warned_about_and_asked_again(app, client, draft_url):
    token = csrf(client)
    points = page_points(client.get(draft_url).get_data(as_text=True))
    answer = client.post(draft_url + "/preview", data={"csrf_token": token, "points": json.dumps(points)})
    assert answer.get_json()["warnings"] == []
    chin, mouth = np.array(points["2.1"]), np.array(points["8.2"])
    points["3.6"] = ((chin + mouth) / 2).tolist()  # an iris dragged below the mouth
    answer = client.post(draft_url + "/preview", data={"csrf_token": token, "points": json.dumps(points)})
    assert answer.status_code == 200
    assert [w["point"] for w in answer.get_json()["warnings"]] == ["3.6"]
    assert "below the mouth" in answer.get_json()["warnings"][0]["message"]
    page = client.get(draft_url).get_data(as_text=True)  # the editor shows the warning with the saved points
    assert re.search(r'<li data-point="3.6">point 3.6 \(iris centre', page)
    assert re.search(r'class="point warn"[^>]*data-name="3.6"', page)
    saved = client.post(draft_url, data={"csrf_token": token, "points": json.dumps(points)})
    assert saved.status_code == 400
    text = saved.get_data(as_text=True)
    assert 'id="use-anyway"' in text and "below the mouth" in text
    assert page_points(text)["3.6"] == pytest.approx(points["3.6"], abs=0.01)
    anyway = client.post(draft_url, data={"csrf_token": token, "points": json.dumps(points), "accept_warnings": "1"})
    assert anyway.status_code == 303 and "/?photo=" in anyway.headers["Location"]


def points_with(points: dict, change) -> str:
    changed = json.loads(json.dumps(points))
    result = change(changed)
    return result if isinstance(result, str) else json.dumps(changed)


@pytest.mark.parametrize("change, expected", [
    (lambda p: p["2.1"].__setitem__(1, float("nan")), "point 2.1 is [" ),
    (lambda p: p["3.5"].__setitem__(0, float("inf")), "point 3.5 is ["),
    (lambda p: p.__setitem__("8.5", [1, 2]), "unknown point '8.5'"),
    (lambda p: p.__setitem__("<script>", [1, 2]), "unknown point '<script>'"),
    (lambda p: p.pop("9.15"), "point '9.15' is missing"),
    (lambda p: p.__setitem__("2.1", "middle"), "point 2.1 is middle; expected [x, y] numbers"),
    (lambda p: p.__setitem__("2.1", [1, True]), "point 2.1 is [1, True]; expected [x, y] numbers"),
    (lambda p: p.__setitem__("2.1", [1, 2, 3]), "expected [x, y] numbers"),
    (lambda p: p.__setitem__("2.1", [1e6, 10]), "is outside the photo"),
    (lambda p: "[1, 2]", "a JSON list; expected an object"),
    (lambda p: "{not json", "points: not JSON"),
    (lambda p: "x" * 20000, "characters; expected at most"),
])
def test_bad_points_are_refused_with_a_clear_message(app, client, draft_url, change, expected):
    token = csrf(client)
    points = page_points(client.get(draft_url).get_data(as_text=True))
    saved = (draft_of(app, draft_url).folder / EDIT_FILE).read_bytes()
    answer = client.post(draft_url + "/preview", data={"csrf_token": token, "points": points_with(points, change)})
    assert answer.status_code == 400
    assert expected in answer.get_json()["error"]
    assert (draft_of(app, draft_url).folder / EDIT_FILE).read_bytes() == saved
    page = client.post(draft_url, data={"csrf_token": token, "points": points_with(points, change)})
    assert page.status_code == 400
    assert str(escape(expected)) in page.get_data(as_text=True)


def test_a_point_dragged_off_the_face_names_the_point(app, client, draft_url):
    token = csrf(client)
    points = page_points(client.get(draft_url).get_data(as_text=True))
    photo = Image.open(io.BytesIO(client.get(draft_url + "/photo.jpg").data))
    points["3.6"] = [photo.width * 1.2, photo.height * 1.2]  # on the edge margin: allowed, but far from the face
    answer = client.post(draft_url + "/preview", data={"csrf_token": token, "points": json.dumps(points)})
    assert answer.status_code == 400
    assert "point 3.6 (iris centre (their left)) cannot make a cartoon face" in answer.get_json()["error"]


def test_csrf_is_required_everywhere(app, client, photo, draft_url):
    points = page_points(client.get(draft_url).get_data(as_text=True))
    answer = upload(client, photo, token=None)
    assert answer.status_code == 400 and "expired" in answer.get_data(as_text=True)
    for token in (None, "forged"):
        data = {"points": json.dumps(points)} | ({"csrf_token": token} if token else {})
        answer = client.post(draft_url + "/preview", data=data)
        assert answer.status_code == 400 and "expired" in answer.get_json()["error"]
        answer = client.post(draft_url, data=data)
        assert answer.status_code == 400 and "expired" in answer.get_data(as_text=True)
    fresh = app.test_client()  # another browser: its own session, so the page's token is not its own
    answer = fresh.post(draft_url + "/preview", data={"csrf_token": csrf(client), "points": json.dumps(points)})
    assert answer.status_code == 400


@pytest.mark.parametrize("content, name, expected", [
    (b"just text, not an image" * 10, "notes.jpg", "notes.jpg: not a photo this app reads (by its content)"),
    (b"\xff\xd8\xff\xe0" + b"\x00" * 200, "broken.jpg", "broken.jpg: "),
    (None, "grey.png", "grey.png: no face found in the photo"),
    (b"", "", "Choose a photo of a face"),
])
def test_unusable_uploads_are_reported(client, content, name, expected):
    content = png_bytes(320, 240, (128, 128, 128)) if content is None else content
    answer = upload(client, content, name)
    assert answer.status_code == 400
    page = answer.get_data(as_text=True)
    assert str(escape(expected)) in page
    assert "/tmp" not in page and "photo.jpg" not in page and "photo.png" not in page


def test_a_photo_over_the_size_limit_is_refused(client):
    answer = upload(client, b"\xff\xd8\xff" + bytes(MAX_PHOTO_BYTES), "huge.jpg")
    assert answer.status_code == 400
    assert "huge.jpg: a photo must be at most 20 MB" in answer.get_data(as_text=True)


@pytest.mark.parametrize("path", ["/photos/short", "/photos/" + "a" * 33, "/photos/../jobs",
                                  "/photos/%2e%2e%2fsecret_key", "/photos/{new}", "/photos/{new}/photo.jpg",
                                  "/photos/{new}/preview.svg"])
def test_bad_or_unknown_ids_are_404(client, path):
    assert client.get(path.format(new=new_id())).status_code == 404


def test_posting_to_an_unknown_id_is_404(client):
    token = csrf(client)
    for path in (f"/photos/{new_id()}/preview", f"/photos/{new_id()}", "/photos/nope/preview"):
        assert client.post(path, data={"csrf_token": token, "points": "{}"}).status_code == 404


def test_the_checked_face_becomes_the_jobs_face_model(app, client, draft_url, speech):
    token = csrf(client)
    points = page_points(client.get(draft_url).get_data(as_text=True))
    points["8.3"][0] += 4.0
    answer = client.post(draft_url, data={"csrf_token": token, "points": json.dumps(points)})
    assert answer.status_code == 303
    draft_id = draft_url.rsplit("/", 1)[1]
    assert answer.headers["Location"] == f"/?photo={draft_id}"
    page = client.get(answer.headers["Location"]).get_data(as_text=True)
    assert f'name="face_draft" value="{draft_id}"' in page and 'id="face_sample"' not in page
    draft = draft_of(app, draft_url)
    sent = form(client, speech.read_bytes(), "", face_sample=None, face_draft=draft_id)
    response = post(client, sent)
    assert response.status_code == 303, response.get_data(as_text=True)
    job = load_job(Path(app.instance_path), response.headers["Location"].rsplit("/", 1)[1])
    stored = json.loads((job.folder / "face.json").read_text(encoding="utf-8"))
    assert stored == json.loads(json.dumps(draft.face))
    assert face_from_dict(stored, "face.json").point("8.3")[0] != draft.base["points"]["8.3"][0]
    assert job.spec["face_label"] == f"{BAD_NAME} (points checked)"
    assert job.spec["face_notes"] == [f"{BAD_NAME}: {warning}" for warning in draft.warnings]


def test_a_draft_that_is_gone_is_reported_in_the_form(client, speech):
    gone = new_id()
    page = client.get(f"/?photo={gone}")
    assert page.status_code == 404 and "no longer kept" in page.get_data(as_text=True)
    response = post(client, form(client, speech.read_bytes(), "", face_sample=None, face_draft=gone))
    assert response.status_code == 400
    text = response.get_data(as_text=True)
    assert 'id="face_sample-error"' in text and "no longer kept" in text
    assert 'id="face_sample"' in text  # the sample choice is offered again


def test_old_and_surplus_drafts_are_swept(tmp_path):
    root = drafts_root(tmp_path)
    now = time.time()
    ids = [new_id() for _ in range(MAX_DRAFTS + 2)]
    for age, draft_id in enumerate(ids):
        folder = root / draft_id
        folder.mkdir(parents=True)
        (folder / EDIT_FILE).write_text("{}", encoding="utf-8")
        os.utime(folder / EDIT_FILE, (now - age, now - age))
    stale = new_id()
    (root / stale).mkdir()
    (root / stale / EDIT_FILE).write_text("{}", encoding="utf-8")
    os.utime(root / stale / EDIT_FILE, (now - DRAFT_SECONDS - 1, now - DRAFT_SECONDS - 1))
    deleted = sweep_drafts(tmp_path, now)
    assert set(deleted) == {stale, *ids[MAX_DRAFTS:]}
    assert sorted(p.name for p in root.iterdir()) == sorted(ids[:MAX_DRAFTS])


def test_a_deleted_draft_is_gone_and_a_half_deleted_one_is_cleared_by_the_next_sweep(tmp_path):
    root = drafts_root(tmp_path)
    kept, gone = new_id(), new_id()
    for draft_id in (kept, gone):
        (root / draft_id).mkdir(parents=True)
        (root / draft_id / EDIT_FILE).write_text("{}", encoding="utf-8")
    remove_folder(root / gone)
    remove_folder(root / gone)  # a second delete finds nothing and says nothing
    assert [p.name for p in root.iterdir()] == [kept]
    leftover = root / f"{TRASH_PREFIX}{new_id()}"
    leftover.mkdir()
    (leftover / EDIT_FILE).write_text("{}", encoding="utf-8")
    assert sweep_drafts(tmp_path) == []
    assert [p.name for p in root.iterdir()] == [kept]


def test_linear_map_recovers_an_affine_map():
    rng = np.random.default_rng(3)
    photo = rng.uniform(0, 500, size=(49, 2))
    matrix = np.array([[0.4, -0.1], [0.08, 0.45]])
    model = photo @ matrix.T + [12.0, -7.0]
    assert linear_map(photo, model) == pytest.approx(matrix)


# --- in a real browser -------------------------------------------------------------------


@pytest.mark.browser
def test_check_drag_and_generate_in_chromium(server, speech, browser, tmp_path):
    jpeg = tmp_path / "astronaut.jpg"
    jpeg.write_bytes(astronaut_jpeg())
    context = browser.new_context(viewport={"width": 1100, "height": 900})
    refused = []
    context.on("console", lambda message: refused.append(message.text)
               if "Content Security Policy" in message.text or "Refused" in message.text else None)
    page = context.new_page()
    page.goto(server + "/")
    page.click("#photo-check")
    page.set_input_files("#photo", str(jpeg))
    page.click("#find-face")
    page.wait_for_url(f"{server}/photos/*")
    circles = page.locator("circle.point")
    assert circles.count() == len(POINT_NAMES)
    assert page.locator("#photo-warnings li").count() >= 1

    corner = 'circle.point[data-name="8.3"]'
    before = float(page.get_attribute(corner, "cx"))
    page.focus(corner)
    page.keyboard.press("Shift+ArrowRight")
    assert float(page.get_attribute(corner, "cx")) > before
    page.click("#reset-points")
    assert float(page.get_attribute(corner, "cx")) == pytest.approx(before, abs=0.01)
    page.wait_for_function("() => document.getElementById('preview').src.startsWith('data:')", timeout=10_000)
    reset = page.evaluate("() => [document.getElementById('preview').src,"
                          " document.getElementById('editor').getAttribute('data-updated')]")

    chin = page.locator('circle.point[data-name="2.1"]')
    chin.hover()
    assert page.inner_text("#point-name").startswith("2.1: chin")
    start = json.loads(page.input_value("#points"))["2.1"]
    box = chin.bounding_box()
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(x, y)
    page.mouse.down()
    page.mouse.move(x, y + 25, steps=5)
    page.mouse.up()
    page.wait_for_function("(seen) => document.getElementById('editor').getAttribute('data-updated') !== seen",
                           arg=reset[1], timeout=10_000)
    shown = page.evaluate("() => document.getElementById('preview').src")
    assert shown.startswith("data:image/svg+xml") and shown != reset[0]
    moved = json.loads(page.input_value("#points"))["2.1"]
    assert moved[1] > start[1] + 5
    assert page.is_hidden("#points-error")

    page.click("#use-face")
    page.wait_for_url(f"{server}/?photo=*")
    page.locator("#chosen-face").wait_for()
    page.set_input_files("#audio", str(speech))
    page.fill("#transcript", TRANSCRIPT)
    page.click("#generate")
    page.wait_for_url(f"{server}/jobs/*")
    assert "astronaut.jpg (points checked)" in page.inner_text(".meta")
    assert page.inner_text("#face-notes").startswith("astronaut.jpg: ")
    page.wait_for_selector("#result", timeout=120_000)
    assert refused == []
    context.close()

    # on a phone: a finger drags a point (pointer events from touch)
    phone = browser.new_context(viewport={"width": 390, "height": 844}, has_touch=True, is_mobile=True)
    page = phone.new_page()
    page.goto(server + "/photos")
    page.set_input_files("#photo", str(jpeg))
    page.click("#find-face")
    page.wait_for_url(f"{server}/photos/*")
    start = json.loads(page.input_value("#points"))["2.1"]
    page.locator('circle.point[data-name="2.1"]').scroll_into_view_if_needed()  # under the cartoon on a phone
    box = page.locator('circle.point[data-name="2.1"]').bounding_box()
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    touch = phone.new_cdp_session(page)
    touch.send("Input.dispatchTouchEvent", {"type": "touchStart", "touchPoints": [{"x": x, "y": y}]})
    for step in range(1, 6):
        touch.send("Input.dispatchTouchEvent", {"type": "touchMove", "touchPoints": [{"x": x, "y": y + 4 * step}]})
    touch.send("Input.dispatchTouchEvent", {"type": "touchEnd", "touchPoints": []})
    page.wait_for_function("() => document.getElementById('editor').hasAttribute('data-updated')", timeout=10_000)
    assert json.loads(page.input_value("#points"))["2.1"][1] > start[1] + 5

    # the cartoon is above the photo; zoom spreads the points, which keep their size on screen
    cartoon, photo_box = page.locator("#preview").bounding_box(), page.locator("#overlay").bounding_box()
    assert cartoon["y"] + cartoon["height"] <= photo_box["y"]
    iris, other = (page.locator(f'circle.point[data-name="{name}"]') for name in ("3.6", "3.5"))

    def apart() -> float:
        a, b = iris.bounding_box(), other.bounding_box()
        return abs((a["x"] + a["width"] / 2) - (b["x"] + b["width"] / 2))

    iris.focus()  # selected: drawn larger, and the zoom centres on it
    size, distance = iris.bounding_box()["width"], apart()
    page.click("#zoom-in")
    page.click("#zoom-in")
    assert float(page.get_attribute("#editor", "data-zoom")) == pytest.approx(2.25)
    assert apart() == pytest.approx(distance * 2.25, rel=0.05)
    assert iris.bounding_box()["width"] == pytest.approx(size, rel=0.05)
    for button in ("#zoom-in", "#zoom-out", "#zoom-fit", "#use-face"):
        target = page.locator(button).bounding_box()
        assert target["width"] >= 44 and target["height"] >= 44, button
    # a touch 20 px beside a point (a 44 px target) takes it
    page.click("#zoom-fit")

    def swipe(x: float, y: float, to_x: float, to_y: float) -> None:
        """A finger from (x, y) to (to_x, to_y), then wait for the cartoon of the new points."""
        seen = page.get_attribute("#editor", "data-updated")
        touch.send("Input.dispatchTouchEvent", {"type": "touchStart", "touchPoints": [{"x": x, "y": y}]})
        for step in range(1, 9):
            at = {"x": x + (to_x - x) * step / 8, "y": y + (to_y - y) * step / 8}
            touch.send("Input.dispatchTouchEvent", {"type": "touchMove", "touchPoints": [at]})
        touch.send("Input.dispatchTouchEvent", {"type": "touchEnd", "touchPoints": []})
        page.wait_for_function("(seen) => document.getElementById('editor').getAttribute('data-updated') !== seen",
                               arg=seen, timeout=10_000)

    chin = page.locator('circle.point[data-name="2.1"]')
    chin.scroll_into_view_if_needed()
    start = json.loads(page.input_value("#points"))["2.1"]
    box = chin.bounding_box()
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2 + 20
    swipe(x, y, x, y + 6)
    assert json.loads(page.input_value("#points"))["2.1"][1] > start[1] + 3
    # an iris dragged below the mouth: warned beside the point and in the list
    box, chin_box = iris.bounding_box(), chin.bounding_box()
    swipe(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2, chin_box["x"] - 10, chin_box["y"] - 8)
    assert page.is_visible("#point-tip") and "point 3.6" in page.inner_text("#point-tip")
    assert page.locator('#point-warning-list li[data-point="3.6"]').count() == 1
    assert "warn" in (iris.get_attribute("class") or "")
    phone.close()


def test_the_main_form_waits_for_the_same_photo_lock(client, photo, monkeypatch, speech):
    monkeypatch.setattr(inputs, "DETECT_WAIT", 0.05)
    assert inputs.DETECTING.acquire(timeout=5)
    try:
        answer = post(client, form(client, speech.read_bytes(), "", face_sample=None, photo=(io.BytesIO(photo), "me.jpg")))
    finally:
        inputs.DETECTING.release()
    assert answer.status_code == 400
    assert inputs.PHOTO_BUSY in answer.get_data(as_text=True)
