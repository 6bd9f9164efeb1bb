"""The JSON API for programs (blueprint "api"), on when API_TOKEN is set (docs/web.md, "API").

POST /api/jobs                    multipart: face file or sample name, audio, transcript (file or
                                  text), options as fields; 201 with the job (JSON)
GET  /api/jobs/<id>               the job: state, progress, stage, worker, notes, error, links
GET  /api/jobs/<id>/result.zip    the generated folder as a zip (404 until done)

Every request carries `Authorization: Bearer TOKEN`. A token sees only its own jobs, and its
jobs share the per-user disk quota (USER_QUOTA_MB). Errors are JSON
`{"error": message, "field": name or null}` with a 4xx status.
"""

from __future__ import annotations

import hashlib
import hmac

from flask import Blueprint, Response, g, jsonify, request, send_file, url_for
from werkzeug.datastructures import FileStorage, MultiDict
from werkzeug.exceptions import RequestEntityTooLarge

from cartoonface.files import remove_folder
from cartoonface.web.inputs import Submission, check_submission, megabytes
from cartoonface.web.runner import QueueFull, current_lease, reaped_path
from cartoonface.web.security import download_name
from cartoonface.web.store import DONE, Job, create_job, list_jobs, load_job, space_problem
from cartoonface.web.views import busy_message, job_label, state
from cartoonface.web.worker import SITE, VIDEO_NAME, ZIP_NAME

bp = Blueprint("api", __name__, url_prefix="/api")

# API field -> the form field that check_submission reads (the same checks as the form).
TEXT_FIELDS = {"sample": "face_sample", "title": "title", "page": "page", "style": "style",
               "background": "background", "clothes": "clothes", "mood": "mood", "language": "language",
               "transcript": "transcript", "mp4": "mp4"}
FILE_FIELDS = {"face": "face_file", "photo": "photo", "audio": "audio", "transcript": "transcript_file",
               "textgrid": "textgrid_file", "actions": "actions_file"}
# A form field's error -> the API field to name.
FIELD_OF = {form: api for api, form in {**TEXT_FIELDS, **FILE_FIELDS}.items()} | {"form": None}
OWNER_PREFIX = "api:"


class ApiError(Exception):
    """Answered as the JSON error `message` naming `field` with HTTP `status`."""

    def __init__(self, status: int, message: str, field: str | None = None) -> None:
        super().__init__(message)
        self.status, self.message, self.field = status, message, field


def api_error(status: int, message: str, field: str | None = None) -> tuple[Response, int]:
    """The JSON error answer: {"error", "field"} with `status`."""
    return jsonify(error=message, field=field), status


@bp.errorhandler(ApiError)
def answer_error(error: ApiError) -> tuple[Response, int]:
    """An ApiError as its JSON answer."""
    return api_error(error.status, error.message, error.field)


def owner_of(token: str) -> str:
    """What job.json records as the owner of a token's jobs: a hash, never the token."""
    return OWNER_PREFIX + hashlib.sha256(token.encode("utf-8")).hexdigest()[:32]


@bp.before_request
def authenticate() -> tuple[Response, int] | None:
    """404 when the API is off, 401 without a valid Bearer token; sets g.api_owner."""
    tokens = state().settings.api_tokens
    if not tokens:
        return api_error(404, "The API is off: the server has no CARTOONFACE_API_TOKEN.")
    scheme, _, given = request.headers.get("Authorization", "").partition(" ")
    matches = [hmac.compare_digest(given.strip().encode("utf-8", "replace"), token.encode("utf-8"))
               for token in tokens]
    if scheme.lower() != "bearer" or not any(matches):
        response, status = api_error(401, "Send the API token as the header 'Authorization: Bearer TOKEN'.",
                                     "Authorization")
        response.headers["WWW-Authenticate"] = 'Bearer realm="cartoonface"'
        return response, status
    g.api_owner = owner_of(given.strip())
    return None


def own_job(job_id: str) -> Job | None:
    """The job `job_id` when it exists and this token made it."""
    job = load_job(state().settings.instance, job_id)
    return job if job is not None and job.spec.get("owner") == g.api_owner else None


def notes(job: Job) -> list[str]:
    """What the user should know: the face's notes, the pipeline's, and runs given up."""
    result = job.status.result or {}
    found = [str(note) for source in (job.spec.get("face_notes"), result.get("notes"))
             if isinstance(source, list) for note in source]
    run = 1
    while reaped_path(job.folder, run).exists():
        why = reaped_path(job.folder, run).read_text(encoding="utf-8", errors="replace")
        found.append(f"Run {run} did not finish ({why}).")
        run += 1
    return found


def job_json(job: Job) -> dict[str, object]:
    """The job as the API shows it."""
    status = job.status
    lease = current_lease(job.folder)
    done = status.state == DONE
    return {
        "id": job.id,
        "title": job.title,
        "created": job.created,
        "state": "interrupted" if status.interrupted else status.state,
        "progress": status.percent,
        "stage": status.stage,
        "stage_label": job_label(job),
        "worker": {key: lease.get(key) for key in ("host", "pid", "run")} if lease else None,
        "notes": notes(job),
        "error": status.error or None,
        "result": dict(status.result) if done and status.result else None,
        "links": {
            "self": url_for(".job", job_id=job.id),
            "page": url_for("web.job_page", job_id=job.id),
            "result_zip": url_for(".result_zip", job_id=job.id) if done else None,
            "site": url_for("web.site_file", job_id=job.id, name="index.html") if done else None,
            "video": url_for("web.site_file", job_id=job.id, name=VIDEO_NAME)
            if done and (job.folder / SITE / VIDEO_NAME).is_file() else None,
        },
    }


def submission_fields() -> tuple[MultiDict[str, str], MultiDict[str, FileStorage]]:
    """The request's fields renamed for check_submission, with the form's defaults for the
    options; ApiError 400 naming an unknown field, or when no face is given."""
    limits = state().limits
    for name in request.form:
        if name not in TEXT_FIELDS:
            raise ApiError(400, f"Unknown field {name!r}; expected {', '.join(sorted(TEXT_FIELDS))} "
                                  f"(and files {', '.join(sorted(FILE_FIELDS))}).", name)
    for name in request.files:
        if name not in FILE_FIELDS:
            raise ApiError(400, f"Unknown file {name!r}; expected files {', '.join(sorted(FILE_FIELDS))}.", name)
    defaults = {"page": "audiobook", "style": "", "title": "",
                "background": limits.backgrounds[0] if limits.backgrounds else "",
                "clothes": limits.clothes[0] if limits.clothes else ""}
    form: MultiDict[str, str] = MultiDict(defaults)
    for api, field in TEXT_FIELDS.items():
        if api in request.form:
            form[field] = request.form[api]
    files: MultiDict[str, FileStorage] = MultiDict()
    for api, field in FILE_FIELDS.items():
        if api in request.files:
            files[field] = request.files[api]
    if "face_sample" not in form and "face_file" not in files and "photo" not in files:
        raise ApiError(400, "Give a face: a face model file (face), a photo (photo) or a sample name (sample).",
                       "face")
    return form, files


@bp.post("/jobs")
def submit() -> tuple[Response, int]:
    """Check the fields as the form does; store and queue the job; 201 with its JSON."""
    runner, settings = state().runner, state().settings
    if not runner.has_room():
        return api_error(429, busy_message())
    form, files = submission_fields()
    checked = check_submission(form, files, state().limits)
    if not isinstance(checked, Submission):
        field, message = next(iter(checked.items()))
        return api_error(400, message, FIELD_OF.get(field, field))
    owner = g.api_owner
    own = [job.id for job in list_jobs(settings.instance) if job.spec.get("owner") == owner]
    problem = space_problem(settings.instance, own, sum(len(data) for data in checked.files.values()),
                            settings.user_quota_bytes, int(settings.retention_mb * 2**20))
    if problem:
        return api_error(429, problem)
    job = create_job(settings.instance, {**checked.spec, "owner": owner}, checked.files)
    try:
        runner.submit(job.folder)
    except QueueFull:
        remove_folder(job.folder)
        return api_error(429, busy_message())
    response = jsonify(job_json(job))
    response.headers["Location"] = url_for(".job", job_id=job.id)
    return response, 201


@bp.get("/jobs/<jobid:job_id>")
def job(job_id: str) -> Response | tuple[Response, int]:
    """The job's JSON (not cached); 404 for another token's job or none."""
    found = own_job(job_id)
    if found is None:
        return api_error(404, "No such job for this token. It may have been removed by the retention limit.")
    response = jsonify(job_json(found))
    response.headers["Cache-Control"] = "no-store"
    return response


@bp.get("/jobs/<jobid:job_id>/result.zip")
def result_zip(job_id: str) -> Response | tuple[Response, int]:
    """The generated folder as a zip (the same as the page's download); 404 until done."""
    found = own_job(job_id)
    if found is None:
        return api_error(404, "No such job for this token. It may have been removed by the retention limit.")
    if found.status.state != DONE or not (found.folder / ZIP_NAME).is_file():
        return api_error(404, f"The job has no result (it is {job_json(found)['state']}).")
    return send_file(found.folder / ZIP_NAME, mimetype="application/zip", as_attachment=True,
                     download_name=download_name(found.title, found.id))


@bp.errorhandler(RequestEntityTooLarge)
def too_large(error: RequestEntityTooLarge) -> tuple[Response, int]:
    """A request over the size limit (413)."""
    return api_error(413, f"The request is too large: the limit is {megabytes(state().limits.upload_bytes)} MB "
                          "for the recording and a few MB for the rest.")
