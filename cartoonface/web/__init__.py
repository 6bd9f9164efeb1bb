"""The cartoonface web app: upload a face model, a recording and its transcript,
follow the job's progress, play the talking face and download it as a zip.

`create_app(config=None)` builds the Flask app (docs/web.md lists the settings),
`configured_app(config=None)` only loads its settings;
`cartoonface serve` runs it under waitress.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Mapping
from pathlib import Path
from typing import IO

from flask import Flask, Request, Response

from cartoonface.render.scenery import BACKGROUNDS, CLOTHES
from cartoonface.web import api, photo_views
from cartoonface.web.config import DEFAULTS, PACKAGE, Settings, secret_key, sample_faces, settings_from
from cartoonface.web.draft_store import sweep_drafts
from cartoonface.web.inputs import MAX_ACTIONS_BYTES, MAX_FACE_BYTES, MAX_PHOTO_BYTES, MAX_TEXTGRID_BYTES, Limits
from cartoonface.web.runner import Runner
from cartoonface.web.security import add_headers
from cartoonface.web.store import apply_retention, fail_interrupted
from cartoonface.web.views import JobIdConverter, WebState, bp
from cartoonface.web.worker import JobLimits

ENV_PREFIX = "CARTOONFACE"


class UploadRequest(Request):
    """Flask's request, also closing the temporary files of uploads whose form could not be
    parsed (a truncated multipart body): Werkzeug drops those without closing them."""

    def _get_file_stream(self, total_content_length: int | None, content_type: str | None,
                         filename: str | None = None, content_length: int | None = None) -> IO[bytes]:
        stream = super()._get_file_stream(total_content_length, content_type, filename, content_length)
        self.__dict__.setdefault("_upload_streams", []).append(stream)
        return stream

    def close(self) -> None:
        super().close()
        for stream in self.__dict__.get("_upload_streams", ()):
            stream.close()


def configured_app(config: Mapping[str, object] | None = None) -> tuple[Flask, Settings]:
    """The Flask app with its settings loaded and checked, and nothing started: settings come
    from DEFAULTS, then `<instance>/config.py`, then CARTOONFACE_* environment variables,
    then `config`. The instance folder is config["INSTANCE_PATH"], else
    $CARTOONFACE_INSTANCE_PATH, else Flask's default (`instance/` beside the package); it is
    made when missing. Also used by `cartoonface worker` and `batch`. Raises OptionError
    for a bad setting."""
    config = dict(config or {})
    instance = config.get("INSTANCE_PATH") or os.environ.get(f"{ENV_PREFIX}_INSTANCE_PATH")
    app = Flask(__name__, instance_path=str(Path(str(instance)).resolve()) if instance else None,
                instance_relative_config=True, template_folder=str(PACKAGE / "templates"), static_folder=None)
    app.request_class = UploadRequest
    app.config.from_mapping(DEFAULTS)
    app.config.from_pyfile("config.py", silent=True)
    app.config.from_prefixed_env(ENV_PREFIX)
    app.config.update(config)
    app.config["DEBUG"] = False
    settings = settings_from(app.config, Path(app.instance_path))
    settings.instance.mkdir(parents=True, exist_ok=True)
    return app, settings


def create_app(config: Mapping[str, object] | None = None) -> Flask:
    """Build the app (settings as configured_app). Jobs left unfinished by a previous server
    are marked failed (embedded queue only: with Redis, workers elsewhere may be running
    them and their leases tell) and the retention limit is applied before the job runner
    starts. Raises OptionError for a bad setting."""
    app, settings = configured_app(config)
    if not app.config.get("SECRET_KEY"):
        app.config["SECRET_KEY"] = secret_key(settings.instance)
    # A request may hold the recording, a face model, a photo, a transcript file and the edited
    # TextGrid and actions.json.
    app.config["MAX_CONTENT_LENGTH"] = (settings.upload_bytes + MAX_FACE_BYTES + MAX_PHOTO_BYTES
                                        + 4 * settings.transcript_chars + MAX_TEXTGRID_BYTES + MAX_ACTIONS_BYTES
                                        + 65536)
    app.config.update(SESSION_COOKIE_HTTPONLY=True, SESSION_COOKIE_SAMESITE="Lax")

    sweep_lock = threading.Lock()

    def sweep(_folder: Path | None = None) -> None:
        with sweep_lock:
            apply_retention(settings.instance, settings.retention_days)
            sweep_drafts(settings.instance)

    if settings.queue is None:  # the embedded queue: no job of this instance runs anywhere else
        fail_interrupted(settings.instance)
    sweep()
    limits = Limits(upload_bytes=settings.upload_bytes, transcript_chars=settings.transcript_chars,
                    samples=sample_faces(settings.samples_dir), backgrounds=tuple(BACKGROUNDS),
                    clothes=tuple(CLOTHES))
    app.extensions["cartoonface"] = WebState(settings, limits, Runner(
        settings.instance, settings.workers, sweep, JobLimits(settings.job_memory_bytes, settings.job_cpu_seconds),
        settings.queue_max, queue=settings.queue, lease_seconds=settings.lease_seconds,
        requeue_on_close=settings.queue is not None))
    app.url_map.converters["jobid"] = JobIdConverter
    app.register_blueprint(bp)
    app.register_blueprint(photo_views.bp)
    app.register_blueprint(api.bp)

    @app.after_request
    def headers(response: Response) -> Response:
        response.headers.setdefault("Cache-Control", "no-store")
        return add_headers(response)

    return app
