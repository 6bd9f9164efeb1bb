"""The web app's point editor (cartoonface/web/photo_views.py): time to upload a photo and
get its draft (first one with the model load, then the median), time of one preview
update (the debounced POST of edited points), and the sizes sent to the browser.

Run: .venv/bin/python -m bench web_photo
"""

from __future__ import annotations

import io
import json
import re
import statistics
import tempfile
import time

from PIL import Image

UPLOADS = 6
UPDATES = 30


def found(pattern: str, html: str) -> str:
    """The first group of `pattern` in the page `html`; AssertionError naming the pattern when absent."""
    match = re.search(pattern, html)
    assert match is not None, f"the page has no {pattern!r}"
    return match.group(1)


def main() -> None:
    """Print the figures (photo: skimage.data.astronaut() as JPEG; Flask test client, one process)."""
    from skimage import data

    from cartoonface.web import create_app

    with tempfile.TemporaryDirectory() as instance:
        app = create_app({"INSTANCE_PATH": instance, "WORKERS": 1})
        try:
            client = app.test_client()
            page = client.get("/photos").get_data(as_text=True)
            token = found(r'name="csrf_token" value="([^"]+)"', page)
            buffer = io.BytesIO()
            Image.fromarray(data.astronaut()).save(buffer, "JPEG", quality=90)
            uploads = []
            for _ in range(UPLOADS):
                started = time.perf_counter()
                answer = client.post("/photos", data={"csrf_token": token,
                                                      "photo": (io.BytesIO(buffer.getvalue()), "a.jpg")})
                uploads.append(time.perf_counter() - started)
                assert answer.status_code == 303, answer.status_code
            editor = answer.headers["Location"]
            html = client.get(editor).get_data(as_text=True)
            points = json.loads(found(r'id="points" value="([^"]+)"', html).replace("&#34;", '"'))
            updates = []
            for _ in range(UPDATES):
                points["2.1"][1] += 0.5
                started = time.perf_counter()
                answer = client.post(editor + "/preview", data={"csrf_token": token, "points": json.dumps(points)})
                updates.append(time.perf_counter() - started)
                assert answer.status_code == 200, answer.get_json()
            svg = len(answer.get_json()["svg"].encode("utf-8"))
            jpeg = len(client.get(editor + "/photo.jpg").data)
        finally:
            app.extensions["cartoonface"].runner.close()
    print(f"upload astronaut (512x512 JPEG, {len(buffer.getvalue()) // 1024} kB): first {uploads[0]:.2f} s "
          f"(with the model load), median of the next {UPLOADS - 1}: {statistics.median(uploads[1:]):.3f} s")
    print(f"preview update (POST points -> SVG), median of {UPDATES}: {1000 * statistics.median(updates):.1f} ms")
    print(f"editor page {len(html.encode('utf-8')) // 1024} kB, photo.jpg {jpeg // 1024} kB, "
          f"preview SVG {svg // 1024} kB")
