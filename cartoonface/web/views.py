"""The web app's routes (blueprint "web").

GET  /                          the form and this browser's recent jobs
POST /jobs                      check the form, store and queue a job, 303 to its page
GET  /jobs/<id>                 progress, error, or the result (player + zip download)
GET  /jobs/<id>/status          JSON: state, stage, percent, error
GET  /jobs/<id>/site/<path>     the generated folder's files (shown in an iframe)
GET  /jobs/<id>/download        the generated folder as a zip
GET  /samples/<name>.svg        a sample face's thumbnail for the form
The "face from a photo" routes (/photos...) are in photo_views.py.
"""

from __future__ import annotations

import mimetypes
import time
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from flask import (Blueprint, Response, abort, current_app, jsonify, redirect, render_template, request,
                   send_file, send_from_directory, session, url_for)
from flask.globals import request_ctx
from werkzeug.exceptions import HTTPException, RequestEntityTooLarge
from werkzeug.routing import BaseConverter
from werkzeug.wrappers import Response as BaseResponse

from cartoonface.files import remove_folder
from cartoonface.exports.captions import CAPTIONS_NAME
from cartoonface.web.config import PACKAGE, Settings
from cartoonface.web.draft_store import draft_choice, load_draft
from cartoonface.face.model import load_face
from cartoonface.web.inputs import (ACTIONS_FILE, MAX_ACTIONS_BYTES, MAX_PHOTO_BYTES, MAX_TEXTGRID_BYTES, MAX_TITLE,
                                    LANGUAGE_CHOICES, MOOD_CHOICES, PAGES, STYLE_CHOICES, TEXTGRID_FILE, Limits, check_submission,
                                    form_values, megabytes)
from cartoonface.web.point_editor import preview_svg
from cartoonface.web.runner import QueueFull, Runner
from cartoonface.web.security import CSRF_FIELD, add_headers, csrf_ok, csrf_token, download_name
from cartoonface.web.store import DONE, ID_PATTERN, QUEUED, Job, Status, create_job, load_job, space_problem
from cartoonface.web.worker import SITE, VIDEO_NAME, VIDEO_STAGE, ZIP_NAME

RECENT = 20  # jobs remembered per browser session
THUMBNAIL_MAX_AGE = 3600  # seconds a browser may keep a sample face's thumbnail

DRAFT_GONE = "The face from your photo is no longer kept (photos are kept for a day); please upload it again."

QUEUED_LABEL = "Waiting for a free worker"
STAGES = {
    "": "Starting",
    "decode": "Reading the recording",
    "segment": "Finding the sentences",
    "align": "Timing the syllables",
    "schedule": "Planning blinks and head moves",
    "frames": "Posing the face in every frame",
    "svg": "Drawing the frames",
    "pages": "Writing the pages",
    VIDEO_STAGE: "Making the video",
}
# The pipeline's stages in order (name, label), listed on the job page with the current one
# marked; a job that makes a video has its stage too, after the pages.
STAGE_LIST = tuple((name, label) for name, label in STAGES.items() if name and name != VIDEO_STAGE)
VIDEO_STAGE_LIST = (*STAGE_LIST, (VIDEO_STAGE, STAGES[VIDEO_STAGE]))

# The generated pages (render/pages.py) load their script and CSS from files and hold
# the SVG inline. They run sandboxed (an opaque origin: no access to this app's cookies
# or pages even if a page were ever wrong), so their files must be loadable from there.
SITE_CSP = ("sandbox allow-scripts; default-src 'none'; script-src 'self'; "
            "style-src 'self' 'unsafe-inline'; img-src 'self' data:; media-src 'self' data:; font-src 'self'; "
            "form-action 'none'; base-uri 'none'; frame-ancestors 'self'")

SITE_TYPES = {
    ".html": "text/html",
    ".svg": "image/svg+xml",
    ".js": "text/javascript",
    ".css": "text/css",
    ".json": "application/json",
    ".txt": "text/plain",
    ".textgrid": "text/plain",
    ".wav": "audio/wav",
    ".mp3": "audio/mpeg",
    ".ogg": "audio/ogg",
    ".m4a": "audio/mp4",
    ".flac": "audio/flac",
    ".mp4": "video/mp4",
    ".png": "image/png",
    ".woff2": "font/woff2",
}


class JobIdConverter(BaseConverter):
    """URL part that only matches the exact shape of a job id (anything else is a 404)."""

    regex = ID_PATTERN.pattern


@dataclass(frozen=True)
class WebState:
    """What the routes share: checked settings, form limits and the job runner."""

    settings: Settings
    limits: Limits
    runner: Runner


bp = Blueprint("web", __name__, static_folder=str(PACKAGE / "static" / "web"), static_url_path="/static/web")


def state() -> WebState:
    """The running app's WebState."""
    return current_app.extensions["cartoonface"]


def stage_label(status: Status, ahead: int | None = None) -> str:
    """What the job is doing, for people: waiting (with the number of jobs `ahead` of it in
    the queue, when known), or the pipeline stage it is in."""
    if status.state == QUEUED:
        if ahead is None:
            return QUEUED_LABEL
        return f"{QUEUED_LABEL}: {ahead} job{'' if ahead == 1 else 's'} ahead of you"
    return STAGES.get(status.stage, status.stage)


def job_label(job: Job) -> str:
    """stage_label of the stored `job`, with its place in the queue when it is waiting."""
    ahead = state().runner.ahead_of(job.folder) if job.status.state == QUEUED else None
    return stage_label(job.status, ahead)


def busy_message() -> str:
    """The form error when the queue is full."""
    return (f"The server is busy: {state().settings.queue_max} jobs are waiting for a worker. "
            "Please try again in a few minutes.")


def stored_job(job_id: str) -> Job:
    """The job `job_id` or a 404."""
    job = load_job(state().settings.instance, job_id)
    if job is None:
        abort(404, description="No such job. It may have been removed by the retention limit.")
    return job


def recent_jobs() -> list[Job]:
    """This browser's recent jobs that still exist, newest first."""
    ids = session.get("jobs", [])
    jobs = [load_job(state().settings.instance, job_id) for job_id in ids if isinstance(job_id, str)]
    return [job for job in jobs if job is not None]


def render_form(values: dict[str, str], errors: dict[str, str], status: int = 200) -> tuple[str, int]:
    """The home page: the form filled with `values`, `errors` by field, and recent jobs."""
    limits = state().limits
    defaults = {"face_sample": next(iter(limits.samples), ""), "page": "audiobook", "title": "",
                "background": limits.backgrounds[0] if limits.backgrounds else "",
                "clothes": limits.clothes[0] if limits.clothes else "", "transcript": ""}
    shown = {**defaults, **{key: value for key, value in values.items() if value}}
    draft = load_draft(state().settings.instance, shown["face_draft"]) if shown.get("face_draft") else None
    return render_template(
        "web/index.html", values=shown, errors=errors, limits=limits, pages=PAGES, styles=STYLE_CHOICES, moods=MOOD_CHOICES, languages=LANGUAGE_CHOICES, draft=draft,
        max_title=MAX_TITLE, upload_mb=megabytes(limits.upload_bytes), photo_mb=megabytes(MAX_PHOTO_BYTES),
        textgrid_mb=megabytes(MAX_TEXTGRID_BYTES), actions_mb=megabytes(MAX_ACTIONS_BYTES),
        csrf=csrf_token(),
        csrf_field=CSRF_FIELD, jobs=recent_jobs(),
    ), status


@bp.app_template_filter("when")
def when(epoch: float) -> str:
    """Epoch seconds as 'YYYY-MM-DD HH:MM UTC'."""
    return time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime(epoch))


@bp.get("/")
def index() -> tuple[str, int]:
    """The empty form and this browser's recent jobs; ?photo=<id> chooses the face of that
    photo draft (photo_views.py)."""
    draft_id = request.args.get("photo", "")
    if draft_id and load_draft(state().settings.instance, draft_id) is None:
        return render_form({}, {"face_sample": DRAFT_GONE}, 404)
    return render_form({"face_draft": draft_id}, {})


@lru_cache(maxsize=32)
def _thumbnail(path: Path, modified: float) -> bytes:
    """The cartoon of the face model at `path` (last changed at `modified`, part of the cache
    key), neutral and still: SVG bytes, drawn once per sample and version."""
    return preview_svg(load_face(path))


@bp.get("/samples/<name>.svg")
def sample_face(name: str) -> Response:
    """The thumbnail of the sample face `name` shown in the form (404 for any other name)."""
    path = state().limits.samples.get(name)
    if path is None:
        abort(404, description="No such sample face.")
    response = Response(_thumbnail(path, path.stat().st_mtime), mimetype="image/svg+xml")
    response.headers["Cache-Control"] = f"private, max-age={THUMBNAIL_MAX_AGE}"
    return response


@bp.post("/jobs")
def submit() -> BaseResponse | tuple[str, int]:
    """Check the form; store and queue the job and 303 to its page, or the form again (400)."""
    values = form_values(request.form)
    if not csrf_ok(request.form.get(CSRF_FIELD)):
        return render_form(values, {"form": "This form has expired or did not come from this page. "
                                            "Please check the fields and press Generate again."}, 400)
    if not state().runner.has_room():
        return render_form(values, {"form": busy_message()}, 429)
    draft_id = values["face_draft"]
    chosen = draft_choice(state().settings.instance, draft_id) if draft_id else None
    checked = check_submission(request.form, request.files, state().limits, chosen)
    if draft_id and chosen is None:
        values["face_draft"] = ""
        return render_form(values, {**(checked if isinstance(checked, dict) else {}), "face_sample": DRAFT_GONE}, 400)
    if isinstance(checked, dict):
        return render_form(values, checked, 400)
    settings = state().settings
    problem = space_problem(settings.instance, [i for i in session.get("jobs", []) if isinstance(i, str)],
                            sum(len(data) for data in checked.files.values()), settings.user_quota_bytes,
                            int(settings.retention_mb * 2**20))
    if problem:
        return render_form(values, {"form": problem}, 429)
    job = create_job(settings.instance, checked.spec, checked.files)
    try:
        state().runner.submit(job.folder)
    except QueueFull:  # filled up while this form was checked
        remove_folder(job.folder)
        return render_form(values, {"form": busy_message()}, 429)
    session["jobs"] = [job.id, *[i for i in session.get("jobs", []) if isinstance(i, str)]][:RECENT]
    return redirect(url_for(".job_page", job_id=job.id), code=303)


@bp.get("/jobs/<jobid:job_id>")
def job_page(job_id: str) -> str:
    """The job's progress, its error, or its player and download link."""
    job = stored_job(job_id)
    return render_template("web/job.html", job=job, status=job.status, stage=job_label(job),
                           pages=PAGES, done=job.status.state == DONE,
                           stages=VIDEO_STAGE_LIST if job.spec.get("mp4") else STAGE_LIST,
                           textgrid_name=TEXTGRID_FILE, actions_name=ACTIONS_FILE,
                           captions=(job.folder / SITE / CAPTIONS_NAME).is_file(),
                           video=video_link(job))


def video_link(job: Job) -> dict[str, str] | None:
    """The job's MP4 for the result page: its `file` in the generated folder and the `name` it
    downloads as (the zip's name with .mp4); None when the job has none."""
    if not (job.folder / SITE / VIDEO_NAME).is_file():
        return None
    return {"file": VIDEO_NAME, "name": Path(download_name(job.title, job.id)).with_suffix(".mp4").name}


@bp.get("/jobs/<jobid:job_id>/status")
def job_status(job_id: str) -> Response:
    """The job's progress as JSON (state, stage, stage_label, percent, error), not cached."""
    job = stored_job(job_id)
    status = job.status
    response = jsonify(state=status.state, stage=status.stage, stage_label=job_label(job),
                       percent=status.percent, error=status.error)
    response.headers["Cache-Control"] = "no-store"
    return response


@bp.get("/jobs/<jobid:job_id>/site/<path:name>")
def site_file(job_id: str, name: str) -> Response:
    """A file of the generated folder with its media type, sandboxed (404 until the job is done)."""
    job = stored_job(job_id)
    if job.status.state != DONE:
        abort(404, description="This job has no result (yet).")
    kind = SITE_TYPES.get(Path(name).suffix.lower()) or mimetypes.guess_type(name)[0] or "application/octet-stream"
    response = send_from_directory(job.folder / SITE, name, mimetype=kind)
    response.headers["Cross-Origin-Resource-Policy"] = "cross-origin"
    return add_headers(response, SITE_CSP, "SAMEORIGIN")


@bp.get("/jobs/<jobid:job_id>/download")
def download(job_id: str) -> Response:
    """The generated folder as a zip attachment with a safe name (404 until the job is done)."""
    job = stored_job(job_id)
    if job.status.state != DONE or not (job.folder / ZIP_NAME).is_file():
        abort(404, description="This job has no result to download (yet).")
    return send_file(job.folder / ZIP_NAME, mimetype="application/zip", as_attachment=True,
                     download_name=download_name(job.title, job.id))


@bp.app_errorhandler(RequestEntityTooLarge)
def too_large(error: RequestEntityTooLarge) -> tuple[str, int]:
    """A request over MAX_CONTENT_LENGTH: the empty form with the limits (413)."""
    limit = megabytes(state().limits.upload_bytes)
    return render_form({}, {"form": f"The upload is too large: the limit is {limit} MB for the recording, "
                                    f"{megabytes(MAX_PHOTO_BYTES)} MB for a photo and a few MB for the rest. "
                                    "Please choose the files again."}, 413)


@bp.app_errorhandler(HTTPException)
def http_error(error: HTTPException) -> tuple[str | Response, int] | Response:
    """Any other 4xx/5xx from routing or Werkzeug as a small page (plain text when the
    Host header was refused: no URL can be built for a page then)."""
    if request_ctx.url_adapter is None:
        return Response(f"{error.code} {error.name}: {error.description}\n", status=error.code,
                        mimetype="text/plain")
    if request.path.startswith("/api/"):
        return jsonify(error=error.description or error.name, field=None), error.code or 500
    return render_template("web/error.html", code=error.code, name=error.name,
                           description=error.description), error.code or 500


@bp.app_errorhandler(Exception)
def internal_error(error: Exception) -> tuple[str | Response, int] | Response:
    """A bug: logged with its traceback, a 500 page without details."""
    current_app.logger.exception("unhandled error on %s %s", request.method, request.path)
    if request_ctx.url_adapter is None:
        return Response("500 Internal error\n", status=500, mimetype="text/plain")
    if request.path.startswith("/api/"):
        return jsonify(error="Something went wrong on the server; the log has the details.", field=None), 500
    return render_template("web/error.html", code=500, name="Internal error",
                           description="Something went wrong on the server; the log has the details."), 500
