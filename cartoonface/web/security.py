"""CSRF tokens, security headers and safe download names.

CSRF: a random token kept in the signed session cookie and repeated in a
hidden form field; a POST whose field does not match is refused (synchronizer
token pattern). The session cookie is HttpOnly and SameSite=Lax.
"""

from __future__ import annotations

import hmac
import re
import secrets

from flask import Response, session

CSRF_FIELD = "csrf_token"

# The app's own pages: scripts and styles only from our files, nothing inline, no framing.
APP_CSP = ("default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data:; "
           "media-src 'self'; connect-src 'self'; frame-src 'self'; form-action 'self'; "
           "base-uri 'none'; frame-ancestors 'none'")

COMMON_HEADERS = {
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
    "Cross-Origin-Opener-Policy": "same-origin",
    "Cross-Origin-Resource-Policy": "same-origin",
    "Permissions-Policy": "camera=(), microphone=(), geolocation=()",
}


def csrf_token() -> str:
    """The session's CSRF token, made on first use."""
    token = session.get(CSRF_FIELD)
    if not isinstance(token, str) or not token:
        token = secrets.token_urlsafe(32)
        session[CSRF_FIELD] = token
    return token


def csrf_ok(sent: str | None) -> bool:
    """True when `sent` (the form field) equals the session's token."""
    expected = session.get(CSRF_FIELD)
    if not isinstance(expected, str) or not expected or not sent:
        return False
    return hmac.compare_digest(expected.encode(), sent.encode())


def add_headers(response: Response, csp: str = APP_CSP, frame_options: str = "DENY") -> Response:
    """Set the Content-Security-Policy, frame options and the common headers on `response`."""
    response.headers.setdefault("Content-Security-Policy", csp)
    response.headers.setdefault("X-Frame-Options", frame_options)
    for name, value in COMMON_HEADERS.items():
        response.headers.setdefault(name, value)
    return response


def download_name(title: str, job_id: str) -> str:
    """A safe zip file name: 'cartoonface-' + the title reduced to [A-Za-z0-9_-] (at most
    40 characters) or else the first 8 characters of the job id, + '.zip'."""
    slug = re.sub(r"[^A-Za-z0-9_-]+", "-", title).strip("-_")[:40].strip("-_")
    return f"cartoonface-{slug or job_id[:8]}.zip"
