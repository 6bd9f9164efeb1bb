"""Jobs on disk: one folder per job under `<instance>/jobs/<id>/`.

A job folder holds `job.json` (what was asked: written once, when the folder
is created atomically with the inputs), `status.json` (state, stage, progress,
error, result summary: rewritten atomically as the job moves on), the inputs
(`face.json`, `audio.<ext>`, `transcript.txt`, names chosen here, never taken
from the user), the generated `site/` folder and `site.zip`.

The disk is the only record: a restarted server lists the same jobs, and a job
left `queued` or `running` by a stopped server is marked failed with a reason.
"""

from __future__ import annotations

import json
import os
import re
import secrets
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from cartoonface.files import atomic_directory, folder_size, remove_folder, write_text_atomic

# secrets.token_urlsafe(24) gives 32 characters of this alphabet (24 random bytes, 192 bits).
ID_BYTES = 24
ID_PATTERN = re.compile(r"[A-Za-z0-9_-]{32}")

QUEUED, RUNNING, DONE, FAILED = "queued", "running", "done", "failed"
FINAL_STATES = (DONE, FAILED)

# A job folder and its files are the server user's alone (its inputs are someone's recording).
FOLDER_MODE, FILE_MODE = 0o700, 0o600

INTERRUPTED = "Interrupted: the server stopped before this job finished. Please submit it again."


@dataclass(frozen=True)
class Status:
    """Where a job is: `state` (queued/running/done/failed), the pipeline `stage`,
    `fraction` 0..1 of the whole job, `error` (a user message when failed),
    `updated` (epoch seconds), `result` (summary of pipeline.Result when done) and
    `interrupted` (failed because its server or worker stopped, not because of the job)."""

    state: str
    stage: str = ""
    fraction: float = 0.0
    error: str = ""
    updated: float = 0.0
    result: Mapping[str, object] | None = None
    interrupted: bool = False

    @property
    def percent(self) -> int:
        """Progress in whole percent, 0..100 (100 only when done)."""
        if self.state == DONE:
            return 100
        return max(0, min(99, int(self.fraction * 100)))

    def to_dict(self) -> dict[str, object]:
        """The JSON form written to status.json."""
        return {
            "state": self.state,
            "stage": self.stage,
            "fraction": self.fraction,
            "error": self.error,
            "updated": self.updated,
            "result": dict(self.result) if self.result is not None else None,
            "interrupted": self.interrupted,
        }


@dataclass(frozen=True)
class Job:
    """One submission as stored: `id`, the request (`spec`, from job.json), its `status`
    and `folder` on disk."""

    id: str
    folder: Path
    spec: Mapping[str, object]
    status: Status

    @property
    def title(self) -> str:
        """The title the user gave (may be empty)."""
        return str(self.spec.get("title", ""))

    @property
    def created(self) -> float:
        """Submission time, epoch seconds."""
        created = self.spec.get("created", 0.0)
        if not isinstance(created, (int, float)):
            raise ValueError(f"job.json: created is {created!r}; expected epoch seconds")
        return float(created)


def new_id() -> str:
    """Return a fresh unguessable job id (32 characters of [A-Za-z0-9_-])."""
    return secrets.token_urlsafe(ID_BYTES)


def valid_id(job_id: str) -> bool:
    """True when `job_id` has the exact shape new_id() makes (so it is safe in a path)."""
    return ID_PATTERN.fullmatch(job_id) is not None


def jobs_root(instance: Path) -> Path:
    """The folder holding every job folder."""
    return instance / "jobs"


def job_folder(instance: Path, job_id: str) -> Path:
    """The folder of job `job_id`; ValueError unless the id has the token shape."""
    if not valid_id(job_id):
        raise ValueError(f"job id {job_id!r} is not 32 characters of [A-Za-z0-9_-]")
    return jobs_root(instance) / job_id


def create_job(instance: Path, spec: Mapping[str, object], files: Mapping[str, bytes]) -> Job:
    """Store a new queued job with its inputs; return it.

    `spec` is the request (JSON-serialisable); `files` maps our own file names
    (e.g. "audio.wav") to their bytes. The folder appears complete or not at all.
    """
    job_id = new_id()
    created = time.time()
    full_spec = {**spec, "id": job_id, "created": created}
    status = Status(state=QUEUED, updated=created)
    target = job_folder(instance, job_id)
    with atomic_directory(target) as tmp:
        tmp.chmod(FOLDER_MODE)
        contents = {**files, "job.json": json.dumps(full_spec, ensure_ascii=False).encode("utf-8"),
                    "status.json": json.dumps(status.to_dict()).encode("utf-8")}
        for name, data in contents.items():
            with os.fdopen(os.open(tmp / name, os.O_WRONLY | os.O_CREAT | os.O_EXCL, FILE_MODE), "wb") as out:
                out.write(data)
    return Job(job_id, target, full_spec, status)


def write_status(folder: Path, status: Status) -> None:
    """Replace the job's status.json atomically."""
    write_text_atomic(folder / "status.json", json.dumps(status.to_dict(), ensure_ascii=False))


def read_status(folder: Path) -> Status:
    """Read the job's status.json (FileNotFoundError when the job is gone)."""
    data = json.loads((folder / "status.json").read_text(encoding="utf-8"))
    return Status(
        state=str(data["state"]),
        stage=str(data.get("stage", "")),
        fraction=float(data.get("fraction", 0.0)),
        error=str(data.get("error", "")),
        updated=float(data.get("updated", 0.0)),
        result=data.get("result"),
        interrupted=bool(data.get("interrupted", False)),
    )


def read_spec(folder: Path) -> dict[str, object]:
    """Read the job's job.json."""
    return json.loads((folder / "job.json").read_text(encoding="utf-8"))


def load_job(instance: Path, job_id: str) -> Job | None:
    """The stored job `job_id`, or None when the id is malformed or no such job is readable."""
    if not valid_id(job_id):
        return None
    folder = job_folder(instance, job_id)
    try:
        return Job(job_id, folder, read_spec(folder), read_status(folder))
    except (OSError, ValueError, KeyError):  # gone, or not a job folder this app wrote
        return None


def list_jobs(instance: Path) -> list[Job]:
    """Every stored job, newest first."""
    root = jobs_root(instance)
    if not root.is_dir():
        return []
    jobs = [load_job(instance, entry.name) for entry in root.iterdir() if valid_id(entry.name)]
    return sorted((job for job in jobs if job is not None), key=lambda job: job.created, reverse=True)


def fail_interrupted(instance: Path) -> list[str]:
    """Mark every job left queued or running as failed (INTERRUPTED); return their ids.

    Called when the server starts, before any worker runs.
    """
    marked = []
    for job in list_jobs(instance):
        if job.status.state not in FINAL_STATES:
            write_status(job.folder, Status(state=FAILED, stage=job.status.stage,
                                            fraction=job.status.fraction, error=INTERRUPTED,
                                            updated=time.time(), interrupted=True))
            marked.append(job.id)
    return marked


def apply_retention(instance: Path, max_age_days: float, now: float | None = None) -> list[str]:
    """Delete finished jobs older than `max_age_days`; return the deleted ids. Queued and
    running jobs are never deleted, nor is a finished job before that age (when the disk
    limits are reached, new submissions are refused instead: see space_problem)."""
    now = time.time() if now is None else now
    deleted = []
    for job in list_jobs(instance):
        if job.status.state in FINAL_STATES and now - job.created > max_age_days * 86400:
            remove_folder(job.folder)
            deleted.append(job.id)
    return deleted


def space_problem(instance: Path, own_ids: list[str], incoming: int, quota: int, total_limit: int) -> str:
    """Why a new job of `incoming` bytes cannot be stored, or "" when it can: the jobs of this
    user (`own_ids`) would take more than `quota` bytes, or all jobs more than `total_limit`."""
    own = sum(folder_size(job_folder(instance, job_id)) for job_id in own_ids if valid_id(job_id))
    if own + incoming > quota:
        return (f"Your jobs take {own / 2**20:.3g} MB of the {quota / 2**20:.3g} MB kept for each user, "
                f"too little for this one ({incoming / 2**20:.1f} MB). They are deleted "
                "after the retention age; please try again then, or with a shorter recording.")
    total = folder_size(jobs_root(instance)) if jobs_root(instance).is_dir() else 0
    if total + incoming > total_limit:
        return ("The server's storage for jobs is full. Finished jobs are deleted after the retention age; "
                "please try again later.")
    return ""
