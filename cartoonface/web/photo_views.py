"""The "face from a photo" routes (blueprint "photo"): upload a photo, see the detected
points over it beside the cartoon, drag points to correct them, then go on to the form
with that face (draft_store.py stores it, point_editor.py checks the points; docs/web.md).

GET  /photos                    the upload form
POST /photos                    read the photo, find the face, store a draft, 303 to its editor
GET  /photos/<id>               the editor: photo with draggable points, cartoon preview, warnings
GET  /photos/<id>/photo.jpg     the photo the points are drawn on
GET  /photos/<id>/preview.svg   the cartoon of the current points
POST /photos/<id>/preview       JSON: the edited points -> the preview SVG (saved) and warnings, or the error
POST /photos/<id>               save the edited points, 303 to the form with this face chosen (asks
                                again when a point is somewhere impossible)
"""

from __future__ import annotations

import json

from flask import Blueprint, Response, abort, jsonify, redirect, render_template, request, url_for
from werkzeug.wrappers import Response as BaseResponse

from cartoonface.errors import InputError
from cartoonface.face.model import POINT_NAMES
from cartoonface.web.draft_store import PHOTO_FILE, Draft, create_draft, load_draft, save_edit, sweep_drafts
from cartoonface.web.inputs import (DETECT_WAIT, MAX_PHOTO_BYTES, PHOTO_BUSY, megabytes, photo_slot, read_upload, shown_name,
                                    sniff_image)
from cartoonface.web.point_editor import MAX_POINTS_CHARS, PointWarning, edited_face, implausible, parse_points, preview_svg
from cartoonface.web.point_labels import POINT_LABELS
from cartoonface.web.security import CSRF_FIELD, csrf_ok, csrf_token
from cartoonface.web.store import new_id
from cartoonface.web.views import state

# The editor's point dots: this share of the photo's long side, at least MIN_POINT_RADIUS px.
POINT_RADIUS_SHARE = 0.008
MIN_POINT_RADIUS = 2.0

EXPIRED = "This form has expired or did not come from this page. Please try again."
# The save form's field that says: use these points despite the warnings.
ACCEPT_FIELD = "accept_warnings"

bp = Blueprint("photo", __name__)


def stored_draft(draft_id: str) -> Draft:
    """The draft `draft_id` or a 404."""
    draft = load_draft(state().settings.instance, draft_id)
    if draft is None:
        abort(404, description="No such photo. Photos are kept for a day; please upload it again.")
    return draft


def render_upload(error: str = "", status: int = 200) -> tuple[str, int]:
    """The upload form with `error` (may be empty)."""
    return render_template("web/photo_upload.html", error=error, photo_mb=megabytes(MAX_PHOTO_BYTES),
                           csrf=csrf_token(), csrf_field=CSRF_FIELD), status


def render_editor(draft: Draft, error: str = "", status: int = 200, confirm: bool = False) -> tuple[str, int]:
    """The editor page of `draft`, with `error` (may be empty) above the points and the warnings
    about points in impossible places; `confirm`: they were just refused on save, so the page
    offers to use the face anyway."""
    points = [(name, POINT_LABELS[name], float(x), float(y)) for name, (x, y) in zip(POINT_NAMES, draft.points)]
    width, height = draft.size
    radius = max(MIN_POINT_RADIUS, POINT_RADIUS_SHARE * max(width, height))
    return render_template("web/photo_edit.html", draft=draft, points=points, radius=radius,
                           hair=" ".join(f"{x:.1f},{y:.1f}" for x, y in draft.hair),
                           points_json=json.dumps(dict(zip(POINT_NAMES, draft.points.round(2).tolist()))),
                           detected_json=json.dumps(dict(zip(POINT_NAMES, draft.detected.round(2).tolist()))),
                           error=error, csrf=csrf_token(), csrf_field=CSRF_FIELD,
                           max_points_chars=MAX_POINTS_CHARS, warnings=implausible(draft.points, draft.detected),
                           confirm=confirm), status


def warnings_json(warnings: tuple[PointWarning, ...]) -> list[dict[str, str]]:
    """The warnings as JSON for the editor's script: [{"point", "message"}]."""
    return [{"point": warning.point, "message": warning.message} for warning in warnings]


@bp.get("/photos")
def upload_form() -> tuple[str, int]:
    """The photo upload form."""
    return render_upload()


@bp.post("/photos")
def upload() -> BaseResponse | tuple[str, int]:
    """Read the uploaded photo and find the face: 303 to the new draft's editor, or the
    upload form with the reason (400; 429 when another photo is being read too long)."""
    if not csrf_ok(request.form.get(CSRF_FIELD)):
        return render_upload(EXPIRED, 400)
    upload_file = request.files.get("photo")
    data, too_big = read_upload(upload_file, MAX_PHOTO_BYTES)
    if data is None:
        return render_upload("Choose a photo of a face (JPEG, PNG or WebP).", 400)
    name = shown_name(upload_file, "photo")
    if too_big:
        return render_upload(f"{name}: a photo must be at most {megabytes(MAX_PHOTO_BYTES)} MB.", 400)
    ext = sniff_image(data[:12])
    if ext is None:
        return render_upload(f"{name}: not a photo this app reads (by its content); expected JPEG, PNG or WebP.", 400)
    instance = state().settings.instance
    with photo_slot(DETECT_WAIT) as free:
        if not free:
            return render_upload(PHOTO_BUSY, 429)
        try:
            draft = create_draft(instance, data, ext, name, new_id())
        except InputError as exc:
            return render_upload(str(exc), 400)
    sweep_drafts(instance)
    return redirect(url_for(".editor", draft_id=draft.id), code=303)


@bp.get("/photos/<jobid:draft_id>")
def editor(draft_id: str) -> tuple[str, int]:
    """The photo with its points (draggable), the cartoon beside it and the photo's warnings."""
    return render_editor(stored_draft(draft_id))


@bp.get("/photos/<jobid:draft_id>/photo.jpg")
def photo(draft_id: str) -> Response:
    """The upright, display-sized photo of the draft."""
    draft = stored_draft(draft_id)
    return Response((draft.folder / PHOTO_FILE).read_bytes(), mimetype="image/jpeg")


@bp.get("/photos/<jobid:draft_id>/preview.svg")
def preview(draft_id: str) -> Response:
    """The cartoon of the draft's current model (SVG)."""
    draft = stored_draft(draft_id)
    face, _obj = edited_face(draft, draft.points)
    return Response(preview_svg(face), mimetype="image/svg+xml")


@bp.post("/photos/<jobid:draft_id>/preview")
def update_preview(draft_id: str) -> tuple[Response, int]:
    """Form fields csrf_token and points (JSON: point name -> [x, y] in photo.jpg pixels):
    save the points and answer {"svg": the new preview}; 400 {"error": why} for a bad
    token or bad points (nothing saved)."""
    draft = stored_draft(draft_id)
    if not csrf_ok(request.form.get(CSRF_FIELD)):
        return jsonify(error=EXPIRED), 400
    try:
        points = parse_points(request.form.get("points", ""), draft.size)
        face, obj = edited_face(draft, points)
    except InputError as exc:
        return jsonify(error=str(exc)), 400
    save_edit(draft, points, obj)
    return jsonify(svg=preview_svg(face).decode("utf-8"),
                   warnings=warnings_json(implausible(points, draft.detected))), 200


@bp.post("/photos/<jobid:draft_id>")
def use_face(draft_id: str) -> BaseResponse | tuple[str, int]:
    """Save the edited points (form field points, as for the preview) and 303 to the
    form with this face chosen; the editor again with the reason (400) when they are bad,
    or with the warnings and a "use it anyway" button (400) when some point is somewhere
    impossible (point_editor.implausible) and the form field accept_warnings was not sent."""
    draft = stored_draft(draft_id)
    if not csrf_ok(request.form.get(CSRF_FIELD)):
        return render_editor(draft, EXPIRED, 400)
    try:
        points = parse_points(request.form.get("points", ""), draft.size)
        _face, obj = edited_face(draft, points)
    except InputError as exc:
        return render_editor(draft, str(exc), 400)
    save_edit(draft, points, obj)
    if implausible(points, draft.detected) and not request.form.get(ACCEPT_FIELD):
        return render_editor(stored_draft(draft_id), "", 400, confirm=True)
    return redirect(url_for("web.index", photo=draft.id), code=303)
