"""Web app settings: defaults, then `<instance>/config.py`, then environment
variables `CARTOONFACE_<KEY>`, then the mapping given to create_app (docs/web.md).
"""

from __future__ import annotations

import os
import secrets
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from cartoonface.data import SAMPLE_FACES
from cartoonface.errors import OptionError
from cartoonface.files import write_bytes_atomic

# The package folder: templates/ and static/ inside it are links to the top-level
# folders in a source checkout and real folders in the wheel (pyproject package-data).
PACKAGE = Path(__file__).resolve().parents[1]

DEFAULTS: dict[str, object] = {
    "MAX_UPLOAD_MB": 200,  # MiB; a 30-minute mono 16-bit 44.1 kHz WAV is 151 MiB
    "MAX_TRANSCRIPT_CHARS": 20000,  # 30 minutes of Mandarin at ~4 syllables/s is ~7200 characters
    "WORKERS": os.cpu_count() or 1,
    "RETENTION_DAYS": 7,
    "RETENTION_MB": 2048,
    "SAMPLES_DIR": str(SAMPLE_FACES),
    # A job's worker process may use this much memory (address space, MiB) and CPU time
    # (seconds): a 30-minute recording takes about 4.2 GB and a few minutes of CPU.
    "JOB_MEMORY_MB": 6144,
    "JOB_CPU_SECONDS": 3600,
    # At most this many jobs wait for a worker; a submission beyond it is refused (429).
    "QUEUE_MAX": 20,
    # The jobs of one browser session may take this much disk (MiB) while they are kept.
    "USER_QUOTA_MB": 1024,
    # `serve`: a connection that sends nothing for this many seconds is closed.
    "CHANNEL_TIMEOUT": 10,
    # The job queue: None is Huey's SQLite storage in the instance folder (this machine only);
    # "redis://HOST:PORT/DB" is Huey's Redis storage, shared with `cartoonface worker`s elsewhere.
    "QUEUE": None,
    # A running job's worker renews its lease this often (a fifth of it); a lease not renewed
    # for LEASE_SECONDS means the worker died: the job is run again once, then marked interrupted.
    "LEASE_SECONDS": 30,
    # `Authorization: Bearer TOKEN` for the JSON API (/api/...): None turns the API off.
    "API_TOKEN": None,
}

# key -> (type, smallest value)
NUMBERS = {
    "MAX_UPLOAD_MB": (float, 0.001),
    "MAX_TRANSCRIPT_CHARS": (int, 1),
    "WORKERS": (int, 0),
    "RETENTION_DAYS": (float, 0.0),
    "RETENTION_MB": (float, 0.0),
    "JOB_MEMORY_MB": (float, 64.0),
    "JOB_CPU_SECONDS": (int, 1),
    "QUEUE_MAX": (int, 1),
    "USER_QUOTA_MB": (float, 0.001),
    "CHANNEL_TIMEOUT": (int, 1),
    "LEASE_SECONDS": (float, 1.0),
}


@dataclass(frozen=True)
class Settings:
    """Checked settings: instance folder, byte/char limits, pool size, retention, sample faces,
    per-job memory (bytes) and CPU time (seconds), queue length, per-session disk quota
    (bytes), the idle-connection timeout (seconds), the queue URL (None: SQLite in the
    instance), the workers' lease (seconds) and the API tokens (none: no API)."""

    instance: Path
    upload_bytes: int
    transcript_chars: int
    workers: int
    retention_days: float
    retention_mb: float
    samples_dir: Path
    job_memory_bytes: int
    job_cpu_seconds: int
    queue_max: int
    user_quota_bytes: int
    channel_timeout: int
    queue: str | None = None
    lease_seconds: float = 30.0
    api_tokens: tuple[str, ...] = ()


def settings_from(config: Mapping[str, object], instance: Path) -> Settings:
    """Check the app's config values; OptionError naming the CARTOONFACE_ key when one is wrong."""
    values = {}
    for key, (kind, smallest) in NUMBERS.items():
        raw = config.get(key)
        try:
            if isinstance(raw, bool) or (kind is int and isinstance(raw, float)):
                raise ValueError
            value = kind(raw)
        except (TypeError, ValueError):
            raise OptionError(f"CARTOONFACE_{key}={raw!r}: expected a {kind.__name__} "
                              f"of at least {smallest}") from None
        if not value >= smallest:
            raise OptionError(f"CARTOONFACE_{key}={raw!r}: expected at least {smallest}")
        values[key] = value
    queue = queue_url(config.get("QUEUE"))
    if values["WORKERS"] == 0 and queue is None:
        raise OptionError("CARTOONFACE_WORKERS=0: expected at least 1 (0, no job runs in the server, only "
                          "with CARTOONFACE_QUEUE set and `cartoonface worker`s taking the jobs)")
    return Settings(
        instance=instance,
        upload_bytes=int(values["MAX_UPLOAD_MB"] * 2**20),
        transcript_chars=values["MAX_TRANSCRIPT_CHARS"],
        workers=values["WORKERS"],
        retention_days=values["RETENTION_DAYS"],
        retention_mb=values["RETENTION_MB"],
        samples_dir=Path(str(config.get("SAMPLES_DIR"))),
        job_memory_bytes=int(values["JOB_MEMORY_MB"] * 2**20),
        job_cpu_seconds=values["JOB_CPU_SECONDS"],
        queue_max=values["QUEUE_MAX"],
        user_quota_bytes=int(values["USER_QUOTA_MB"] * 2**20),
        channel_timeout=values["CHANNEL_TIMEOUT"],
        queue=queue,
        lease_seconds=values["LEASE_SECONDS"],
        api_tokens=api_tokens(config.get("API_TOKEN")),
    )


def queue_url(raw: object) -> str | None:
    """The QUEUE setting checked: None/"" (SQLite in the instance) or a redis:// URL."""
    if raw in (None, ""):
        return None
    if not isinstance(raw, str) or not raw.startswith(("redis://", "rediss://", "unix://")):
        raise OptionError(f"CARTOONFACE_QUEUE={raw!r}: expected redis://HOST:PORT/DB (or unset for the "
                          "embedded SQLite queue)")
    return raw


# An API token shorter than this is refused: it is the only thing between the API and the world.
MIN_TOKEN_CHARS = 16


def api_tokens(raw: object) -> tuple[str, ...]:
    """The API_TOKEN setting checked: None (no API), one token or a list of them, each at
    least MIN_TOKEN_CHARS characters of visible ASCII."""
    if raw in (None, ""):
        return ()
    tokens = raw if isinstance(raw, list) else [raw]
    for token in tokens:
        if not (isinstance(token, str) and len(token) >= MIN_TOKEN_CHARS and token.isascii()
                and token.isprintable() and " " not in token):
            raise OptionError(f"CARTOONFACE_API_TOKEN: each token must be a string of at least "
                              f"{MIN_TOKEN_CHARS} visible ASCII characters (no spaces)")
    return tuple(tokens)


def secret_key(instance: Path) -> bytes:
    """The instance's session-signing key: read from `<instance>/secret_key`, made
    (32 random bytes, file mode 0600) on first start so sessions survive restarts."""
    path = instance / "secret_key"
    try:
        key = path.read_bytes()
    except FileNotFoundError:
        key = b""
    if len(key) < 32:
        key = secrets.token_bytes(32)
        write_bytes_atomic(path, key)
        path.chmod(0o600)
    return key


def sample_faces(folder: Path) -> dict[str, Path]:
    """The sample face models on offer: file stem -> path, for `folder`/*.json."""
    if not folder.is_dir():
        return {}
    return {path.stem: path for path in sorted(folder.glob("*.json")) if path.is_file()}
