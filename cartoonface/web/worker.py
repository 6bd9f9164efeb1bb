"""Run one stored job in its own process: forked by the runner (`forked_main`), or by hand
as `python -m cartoonface.web.worker JOB_FOLDER PARENT_PID`.

The job runs the same library call as `cartoonface generate`
(`cartoonface.pipeline.generate`), writes its progress to status.json as it
goes, zips the generated folder for download (without the recording, which
`download_zip` adds when it is downloaded, so that it is stored once), makes the
MP4 video when the job asks for one (exports/video.py, as `generate --mp4`:
drawn in processes it forks, into the generated folder after the zip) and ends
with status done, or failed with the user message of an InputError. Any other
exception is a bug: its traceback goes to stderr (the job's worker.log) and the
user sees a short internal-error message. When the consumer that started it is
gone, or its run was given up (runner.py, leases), the worker stops at the next
progress report.
"""

from __future__ import annotations

import io
import json
import multiprocessing
import os
import resource
import signal
import sys
import time
import traceback
import zipfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import parselmouth  # noqa: F401  (loaded in the forkserver that preloads this module, before a job's memory
# limit: generate imports it only for the formants of a job without a transcript (speech/audio_only.py), and
# under RLIMIT_AS a library may fail to map)

from cartoonface.errors import InputError
from cartoonface.exports.cues import FORMATS as CUE_FORMATS
from cartoonface.files import write_bytes_atomic
from cartoonface.pipeline import Options, generate
from cartoonface.web.store import DONE, FAILED, RUNNING, Status, read_spec, write_status

# Progress is written at most this often (seconds), plus on every stage change.
PROGRESS_INTERVAL = 0.25

SITE = "site"
DEFAULT_OPTIONS = Options()  # fps and seed of jobs that do not set them (the form does not)
ZIP_NAME = "site.zip"
VIDEO_NAME = "video.mp4"  # the job's MP4 (spec "mp4"), in the generated folder but not in its zip
VIDEO_STAGE = "video"  # the progress stage of making it (exports/video.py reports "video")
# The share of the progress bar the pages take when a video follows; the video (made about
# as fast as real time) takes the rest.
PAGES_SHARE = 0.5


# The CPU-time limit is a soft limit (SIGXCPU, answered with OverCpu); the process is
# killed at the hard limit this many seconds later, should the handler not get to run.
CPU_GRACE = 5


class Orphaned(Exception):
    """The server process that started this worker has gone away."""


class OverCpu(BaseException):
    """The job used up its CPU time (SIGXCPU at the soft RLIMIT_CPU); a BaseException, so
    no `except Exception` on the way up can swallow it."""


@dataclass(frozen=True)
class JobLimits:
    """What one job's process may use: `memory_bytes` of address space (RLIMIT_AS) and
    `cpu_seconds` of CPU time (RLIMIT_CPU)."""

    memory_bytes: int
    cpu_seconds: int

    def memory_message(self) -> str:
        """The user message for a job stopped by the memory limit."""
        return (f"The job used more than {self.memory_bytes / 2**30:.3g} GB of memory and was stopped. "
                "A shorter recording needs less.")

    def cpu_message(self) -> str:
        """The user message for a job stopped by the CPU-time limit."""
        return (f"The job used more than {self.cpu_seconds} s of processor time and was stopped. "
                "A shorter recording needs less.")


def _over_cpu(signum: int, frame: object) -> None:
    raise OverCpu


def apply_limits(limits: JobLimits) -> None:
    """Limit this process (and what it forks) to `limits`: RLIMIT_AS (an allocation beyond it
    raises MemoryError) and RLIMIT_CPU (SIGXCPU raises OverCpu; killed CPU_GRACE s later)."""
    used = int(resource.getrusage(resource.RUSAGE_SELF).ru_utime + resource.getrusage(resource.RUSAGE_SELF).ru_stime)
    resource.setrlimit(resource.RLIMIT_AS, (limits.memory_bytes, limits.memory_bytes))
    soft = used + limits.cpu_seconds
    resource.setrlimit(resource.RLIMIT_CPU, (soft, soft + CPU_GRACE))
    signal.signal(signal.SIGXCPU, _over_cpu)


def zip_folder(folder: Path, top: str) -> bytes:
    """Return a zip (bytes) of every file under `folder`, stored under the folder name `top`/."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for path in sorted(folder.rglob("*")):
            if path.is_file():
                archive.write(path, f"{top}/{path.relative_to(folder).as_posix()}")
    return buffer.getvalue()


def zip_top_name(spec: Mapping[str, object]) -> str:
    """The folder name inside the download zip: 'cartoonface-' + first 8 characters of the id."""
    return f"cartoonface-{str(spec['id'])[:8]}"


def user_message(error: InputError, folder: Path, spec: dict[str, object]) -> str:
    """The error's message with the job's own file paths replaced by what the user called
    them (their file names, "transcript"), so no server path is shown."""
    message = str(error)
    names = {
        folder / str(spec["audio_file"]): str(spec.get("audio_label", "recording")),
        folder / "face.json": str(spec.get("face_label", "face model")),
        folder / "transcript.txt": "transcript",
        **{folder / str(spec[f"{kind}_file"]): str(spec.get(f"{kind}_label", spec[f"{kind}_file"]))
           for kind in ("textgrid", "actions") if spec.get(f"{kind}_file")},
        folder / SITE / VIDEO_NAME: "video",
        folder: "job",
    }
    for path, label in names.items():
        message = message.replace(str(path), label)
    return message


def run_job(folder: Path, server_alive: Callable[[], bool]) -> None:
    """Generate the job stored in `folder`, writing status.json as it goes; stop
    (Orphaned) at a progress report when `server_alive()` is False."""
    spec = read_spec(folder)
    video = bool(spec.get("mp4"))
    last_stage, last_time = "", 0.0

    def progress(stage: str, fraction: float) -> None:
        """Report `fraction` (0..1) of the whole job done, in `stage`."""
        nonlocal last_stage, last_time
        if not server_alive():
            raise Orphaned(stage)
        now = time.monotonic()
        if stage == last_stage and now - last_time < PROGRESS_INTERVAL:
            return
        last_stage, last_time = stage, now
        write_status(folder, Status(state=RUNNING, stage=stage, fraction=min(max(fraction, 0.0), 1.0),
                                    updated=time.time()))

    def pages_progress(stage: str, fraction: float) -> None:
        """The pipeline's `fraction` of the pages, on the pages' share of the bar."""
        progress(stage, fraction * PAGES_SHARE if video else fraction)

    def video_progress(stage: str, fraction: float) -> None:
        """write_video's `fraction` of the video, on the rest of the bar after the pages."""
        progress(VIDEO_STAGE, PAGES_SHARE + fraction * (1 - PAGES_SHARE))

    write_status(folder, Status(state=RUNNING, updated=time.time()))
    options = Options(page=str(spec["page"]), title=str(spec["title"]), style=str(spec.get("style") or "") or None,
                      background=str(spec["background"]), clothes=str(spec["clothes"]), cues=CUE_FORMATS,
                      emotion=str(spec.get("mood") or "") or None, language=str(spec.get("language") or "") or None,
                      fps=int(str(spec.get("fps", DEFAULT_OPTIONS.fps))), seed=int(str(spec.get("seed", DEFAULT_OPTIONS.seed))),
                      alignment=folder / str(spec["textgrid_file"]) if spec.get("textgrid_file") else None,
                      actions=folder / str(spec["actions_file"]) if spec.get("actions_file") else None)
    transcript = folder / "transcript.txt"  # absent when the form's transcript was left empty
    try:
        given = folder / str(spec["audio_file"])  # a recording, or a video of the speaker
        result = generate(folder / "face.json", None if spec.get("video") else given,
                          transcript if transcript.is_file() else None, folder / SITE, options, pages_progress,
                          video=given if spec.get("video") else None)
        write_bytes_atomic(folder / ZIP_NAME, zip_folder(folder / SITE, zip_top_name(spec)))
        if video:  # the sound of a video of the speaker is in the pages' own audio file
            # imported here, not in the forkserver that preloads this module: libvips is loaded
            # only in the processes that make a video
            from cartoonface.exports.video import write_site_video

            video_progress(VIDEO_STAGE, 0.0)
            write_site_video(result.out_dir, options.fps, result.duration, None if spec.get("video") else given,
                             result.out_dir / VIDEO_NAME, progress=video_progress)
    except InputError as exc:
        write_status(folder, Status(state=FAILED, stage=last_stage, error=user_message(exc, folder, spec),
                                    updated=time.time()))
        return
    summary = {
        "duration": result.duration,
        "frames": result.frames,
        "size": result.size,
        "seconds": result.seconds,
        "notes": list(result.notes),
        # the job process's peak resident memory (Linux reports ru_maxrss in KiB)
        "peak_memory_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024),
    }
    write_status(folder, Status(state=DONE, stage=VIDEO_STAGE if video else "pages", fraction=1.0, updated=time.time(), result=summary))


def _stage(folder: Path) -> str:
    return str(json.loads((folder / "status.json").read_text(encoding="utf-8")).get("stage", ""))


def main(folder: Path, server_alive: Callable[[], bool], limits: JobLimits | None = None) -> int:
    """Run the job in `folder` (under `limits`, for the messages, when given); return the exit
    code: 0 once the status is final, 3 when the server went away, 4 when the job hit a limit
    of `limits`, 1 after an internal error (traceback on stderr). The failed status is written
    after the except clause, when the traceback's frames (and the job's arrays) are freed: at
    the memory limit there would be no room to write it inside."""
    try:
        run_job(folder, server_alive)
        return 0
    except Orphaned:
        print("worker: the server went away; stopping", file=sys.stderr)
        return 3
    except (MemoryError, OverCpu) as exc:
        if limits is None:
            raise
        message, code = (limits.memory_message() if isinstance(exc, MemoryError) else limits.cpu_message()), 4
    except Exception as exc:  # a bug, or a library's own error for a failed allocation or the CPU limit
        if limits is not None and out_of_memory(exc):
            message, code = limits.memory_message(), 4
        elif limits is not None and any(isinstance(link, OverCpu) for link in _chain(exc)):
            message, code = limits.cpu_message(), 4
        else:  # a bug: keep the details for the log, tell the user briefly
            traceback.print_exc()
            message, code = "", 1
    stage = _stage(folder)
    message = message or (f"Internal error while generating (stage {stage or 'start'}); "
                          "the job's worker.log on the server has the details.")
    print(f"worker: {message}", file=sys.stderr)
    write_status(folder, Status(state=FAILED, stage=stage, updated=time.time(), error=message))
    return code


# What libraries say instead of raising MemoryError when an allocation fails (C++ std::bad_alloc
# through parselmouth, errno ENOMEM through the OS, a thread whose stack does not fit under the
# address-space limit, a library imported under it that cannot be mapped, ...).
OUT_OF_MEMORY_WORDS = ("bad_alloc", "cannot allocate memory", "out of memory", "memoryerror", "can't start new thread",
                       "failed to map segment from shared object")


def out_of_memory(exc: BaseException) -> bool:
    """Whether `exc`, or an exception it was raised from or while handling, is a failed
    allocation: a MemoryError, or a message of OUT_OF_MEMORY_WORDS."""
    return any(isinstance(link, MemoryError) or any(word in str(link).lower() for word in OUT_OF_MEMORY_WORDS)
               for link in _chain(exc))


def _chain(exc: BaseException) -> list[BaseException]:
    """`exc` and the exceptions it was raised from or while handling, innermost last."""
    links: list[BaseException] = []
    current: BaseException | None = exc
    while current is not None and all(current is not link for link in links):
        links.append(current)
        current = current.__cause__ or current.__context__
    return links


def forked_main(folder: str, limits: JobLimits | None = None, given_up: str | None = None) -> None:
    """Entry point in a process the runner started through the forkserver: the process is
    held to `limits` (None: not limited), output goes to the job's worker.log; the server is alive while
    multiprocessing's parent sentinel is open (the forkserver itself outlives a killed
    server while its children run) and no file `given_up` exists (the runner's claim that
    this run was given up and the job queued again)."""
    log = os.open(Path(folder) / "worker.log", os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    os.dup2(log, 1)
    os.dup2(log, 2)
    os.close(log)
    server = multiprocessing.parent_process()
    if server is None:
        sys.exit("worker: forked_main runs only in a process the runner started; by hand: "
                 "python -m cartoonface.web.worker JOB_FOLDER PARENT_PID")
    if limits is not None:
        apply_limits(limits)
    mark = Path(given_up) if given_up else None
    sys.exit(main(Path(folder), lambda: server.is_alive() and not (mark is not None and mark.exists()), limits))


if __name__ == "__main__":
    # By hand: python -m cartoonface.web.worker JOB_FOLDER PARENT_PID (alive while it is our parent).
    parent_pid = int(sys.argv[2])
    raise SystemExit(main(Path(sys.argv[1]), lambda: os.getppid() == parent_pid))
