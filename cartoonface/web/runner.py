"""Jobs on a Huey queue (https://huey.readthedocs.io): the job ids wait in Huey's storage,
SQLite in the instance folder by default (no server; this machine only) or Redis with
`CARTOONFACE_QUEUE=redis://HOST:PORT/DB` (shared by `cartoonface worker`s on other
machines that see the same job folder). A message is (job id, run number); each job's
state stays on disk (store.py).

A consumer (`workers` threads; none in a server whose workers run elsewhere) takes a
message and runs the job in a child process forked from a multiprocessing forkserver
that imported the pipeline once (a job starts in milliseconds, and a crash or a limit
ends only its job). While the child runs, its thread renews the run's lease
(`lease-<run>.json`: host, pid, time) every fifth of `lease_seconds`. Every consumer
(and every server) watches the leases: a job whose lease is older than `lease_seconds`
lost its worker; it is queued once more as run 2 and, if that dies too, marked failed
as interrupted. A claim file (`reaped-<run>`, created exclusively) makes sure one
watcher acts on it, and the old run's process stops at its next progress report.
"""

from __future__ import annotations

import json
import logging
import multiprocessing
import os
import signal
import socket
import sqlite3
import threading
import time
from collections.abc import Callable
from multiprocessing.process import BaseProcess
from pathlib import Path
from urllib.parse import urlsplit

from huey import Huey, RedisHuey, SqliteHuey
from huey.consumer import Consumer
from redis.exceptions import RedisError

from cartoonface.errors import OptionError
from cartoonface.files import write_text_atomic
from cartoonface.web.store import (FAILED, FINAL_STATES, QUEUED, Status, jobs_root, list_jobs, read_status,
                                   valid_id, write_status)
from cartoonface.web.worker import JobLimits, forked_main

FORKSERVER = multiprocessing.get_context("forkserver")
LOG = logging.getLogger(__name__)
# What the queue's storage raises when it cannot be reached or read.
QUEUE_ERRORS = (RedisError, sqlite3.Error)

QUEUE_NAME = "cartoonface"
SQLITE_FILE = "queue.sqlite3"  # in the instance folder
# An idle consumer thread asks the SQLite queue for work at most this many seconds apart
# (Redis is read with a blocking pop and answers at once).
POLL_MAX = 0.5
# A run's lease is renewed this many times per LEASE_SECONDS.
RENEWALS_PER_LEASE = 5
# The retention sweep runs this often (seconds) besides after each job.
SWEEP_EVERY = 60.0
# Threads of the BLAS/OpenMP libraries in a job process (unless set in the environment): jobs run
# side by side, one per core, so one thread each rather than numpy's default of one per core
# (two jobs on 2 cores would spin 4). On the shared bench machine the effect was within its noise
# (docs/BENCHMARKS.md, "Web app: ... the queue on Redis").
JOB_MATHS_THREADS = 1
MATHS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
# A job is run at most this many times (the first run and one more after its worker died).
MAX_RUNS = 2

STOPPED = "Stopped: the server shut down while this job was running. Please submit it again."
WORKER_LOST = ("Interrupted: the worker running this job stopped (twice) before it finished. "
               "Please submit it again.")


class QueueFull(Exception):
    """The queue already holds its maximum of waiting jobs."""


class _Consumer(Consumer):
    """Huey's consumer without its signal handlers: it runs inside the server or the worker
    command, which handle SIGINT/SIGTERM themselves (and may start it outside the main thread)."""

    def _set_signal_handlers(self) -> None:
        pass


def make_huey(instance: Path, url: str | None) -> Huey:
    """The Huey instance of the queue: Redis at `url`, else SQLite in `instance`. Results are
    not kept (a job's state is its folder)."""
    if url:
        return RedisHuey(QUEUE_NAME, url=url, results=False)
    return SqliteHuey(QUEUE_NAME, filename=str(instance / SQLITE_FILE), results=False)


def shown_url(url: str | None) -> str:
    """The queue for messages: the Redis URL without its password, or the SQLite default."""
    if not url:
        return f"(unset: SQLite, {SQLITE_FILE} in the instance folder)"
    parts = urlsplit(url)
    return parts._replace(netloc=parts.netloc.rpartition("@")[2]).geturl()


def lease_path(folder: Path, run: int) -> Path:
    """The lease file of run number `run` of the job in `folder`."""
    return folder / f"lease-{run}.json"


def reaped_path(folder: Path, run: int) -> Path:
    """The claim file that says run `run` was given up (its process must stop)."""
    return folder / f"reaped-{run}"


def claim(path: Path, text: str = "") -> bool:
    """Create `path` exclusively (0600) with `text`; False when it exists already."""
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except FileExistsError:
        return False
    with os.fdopen(fd, "w", encoding="utf-8") as out:
        out.write(text)
    return True


def current_lease(folder: Path) -> dict[str, object] | None:
    """The lease of the job's latest run: {"run", "host", "pid", "renewed" (epoch s)}, or
    None when no run has started."""
    runs = sorted((int(path.stem.split("-", 1)[1]) for path in folder.glob("lease-*.json")
                   if path.stem.split("-", 1)[1].isdigit()), reverse=True)
    for run in runs:
        try:
            return json.loads(lease_path(folder, run).read_text(encoding="utf-8"))
        except (OSError, ValueError):  # being written for the first time
            continue
    return None


def _lease_text(run: int) -> str:
    return json.dumps({"run": run, "host": socket.gethostname(), "pid": os.getpid(), "renewed": time.time()})


class Runner:
    """The queue of the jobs under `instance`/jobs (Huey over Redis at `queue`, else SQLite)
    and, with `workers` > 0, a consumer running them in child processes held to `limits`
    (None: unlimited). At most `queue_max` jobs wait (None: no cap). `after_job(folder)` is
    called after each job ends and with None every minute (the retention sweep). On
    close(), a running job is marked failed (STOPPED), or with `requeue_on_close` queued
    again for another worker."""

    def __init__(self, instance: Path, workers: int, after_job: Callable[[Path | None], None] = lambda folder: None,
                 limits: JobLimits | None = None, queue_max: int | None = None, *, queue: str | None = None,
                 lease_seconds: float = 30.0, requeue_on_close: bool = False) -> None:
        self._jobs = jobs_root(instance)
        self._jobs.mkdir(parents=True, exist_ok=True)
        self._huey = make_huey(instance, queue)
        try:
            self._huey.pending_count()
        except QUEUE_ERRORS as exc:
            raise OptionError(f"CARTOONFACE_QUEUE={shown_url(queue)}: cannot use the queue ({exc})") from None
        self._task = self._huey.task(name="run_job")(self._run)
        self._queue_max = queue_max
        self._limits = limits
        self._after_job = after_job
        self._lease = lease_seconds
        self._requeue_on_close = requeue_on_close
        self._lock = threading.Lock()
        self._running: dict[Path, tuple[BaseProcess, int]] = {}
        self._closed = threading.Event()
        for name in MATHS_THREAD_VARIABLES:  # read by the forkserver's numpy when it starts
            os.environ.setdefault(name, str(JOB_MATHS_THREADS))
        FORKSERVER.set_forkserver_preload(["cartoonface.web.worker"])
        self._consumer: _Consumer | None = None
        if workers:
            self._consumer = _Consumer(self._huey, workers=workers, worker_type="thread", periodic=False,
                                       max_delay=POLL_MAX, check_worker_health=False)
            self._consumer.start()
        self._watcher = threading.Thread(target=self._watch, name="cartoonface-leases", daemon=True)
        self._watcher.start()

    # --- the queue --------------------------------------------------------------------------

    def submit(self, folder: Path) -> None:
        """Queue the stored job in `folder` (its status.json says queued); QueueFull when
        `queue_max` jobs are waiting already (check has_room() before storing a job)."""
        if self._closed.is_set():
            raise RuntimeError("the job runner is closed")
        if not self.has_room():
            raise QueueFull(folder)
        try:
            self._task(folder.name, 1)
        except QUEUE_ERRORS as exc:  # Redis unreachable: refused like a full queue, the reason logged
            LOG.error("cannot queue job %s: %s", folder.name, exc)
            raise QueueFull(folder) from exc

    def has_room(self) -> bool:
        """True when another job may be queued now (False when the queue cannot be reached)."""
        try:
            return self._queue_max is None or self._huey.pending_count() < self._queue_max
        except QUEUE_ERRORS as exc:
            LOG.error("cannot read the queue: %s", exc)
            return False

    def waiting(self) -> list[str]:
        """The ids of the jobs waiting in the queue, the next to start first."""
        return [str(task.args[0]) for task in self._huey.pending() if task.args]

    def ahead_of(self, folder: Path) -> int | None:
        """How many queued jobs will start before the one in `folder`; None when it is not waiting
        (or the queue cannot be read just now)."""
        try:
            waiting = self.waiting()
        except QUEUE_ERRORS:
            return None
        return waiting.index(folder.name) if folder.name in waiting else None

    def close(self, timeout: float = 5.0) -> None:
        """Stop taking jobs; end running ones (marked failed, STOPPED, or queued again with
        `requeue_on_close`); waiting jobs stay in the queue's storage."""
        self._closed.set()
        with self._lock:  # under the lock: a process leaves _running before it is closed
            for process, _run in self._running.values():
                process.terminate()
        if self._consumer is not None:
            self._consumer.shutdown_timeout = timeout
            self._consumer.stop(graceful=True)
        self._watcher.join(timeout)
        pool = getattr(self._huey.storage, "pool", None)  # Redis: its connections
        if pool is not None:
            pool.disconnect()
        self._huey.storage.close()

    # --- running a job (in a consumer thread) -------------------------------------------------

    def _run(self, job_id: str, run: int) -> None:
        """Huey task: run number `run` of job `job_id`, unless it is gone, finished or taken."""
        if not valid_id(job_id):
            return
        folder = self._jobs / job_id
        try:
            if read_status(folder).state in FINAL_STATES:
                return
        except (OSError, ValueError, KeyError):
            return
        if self._closed.is_set() or not claim(lease_path(folder, run), _lease_text(run)):
            if self._closed.is_set():
                self._task(job_id, run)  # not started here: leave it for another worker
            return
        try:
            self._supervise(folder, run)
        finally:
            self._after_job(folder)

    def _supervise(self, folder: Path, run: int) -> None:
        ended = threading.Event()
        renewer = threading.Thread(target=self._renew, args=(folder, run, ended), daemon=True,
                                   name=f"cartoonface-lease-{folder.name}")
        renewer.start()
        try:
            with self._lock:
                process = FORKSERVER.Process(target=forked_main, args=(str(folder), self._limits,
                                                                       str(reaped_path(folder, run))),
                                             name=f"cartoonface-{folder.name}")
                process.start()
                self._running[folder] = (process, run)
                if self._closed.is_set():  # close() came while the process was starting
                    process.terminate()
            process.join()
            with self._lock:
                self._running.pop(folder, None)
            code = process.exitcode
            process.close()
        finally:
            ended.set()
            renewer.join()
            with self._lock:
                self._running.pop(folder, None)
        try:
            status = read_status(folder)
        except (OSError, ValueError, KeyError):
            return
        if status.state in FINAL_STATES or reaped_path(folder, run).exists():
            return
        if self._closed.is_set():
            if self._requeue_on_close:
                self._give_up(folder, run, "the worker running it was stopped")
            else:
                write_status(folder, Status(state=FAILED, stage=status.stage, fraction=status.fraction,
                                            error=STOPPED, updated=time.time(), interrupted=True))
            return
        write_status(folder, Status(state=FAILED, stage=status.stage, fraction=status.fraction,
                                    error=self._died(code), updated=time.time()))

    def _renew(self, folder: Path, run: int, ended: threading.Event) -> None:
        """Renew the lease of run `run` every lease/RENEWALS_PER_LEASE s until `ended` is set or
        the run is given up."""
        while not ended.wait(self._lease / RENEWALS_PER_LEASE):
            if reaped_path(folder, run).exists():
                return
            write_text_atomic(lease_path(folder, run), _lease_text(run))

    def _died(self, code: int | None) -> str:
        """The user message for a worker process that ended with exit code `code` before its
        job's status was final: stopped by the CPU limit, out of its address space (a
        segmentation fault under the memory limit), killed (the hard CPU limit, or the system
        out of memory), or else died."""
        if self._limits is not None and code == -signal.SIGXCPU:
            return self._limits.cpu_message()
        # Under the address-space limit C code that does not check a failed allocation, or a
        # stack that cannot grow, crashes with a segmentation fault instead of raising
        # MemoryError (seen in tests/test_web.py's over-memory job inside numpy while decoding).
        if self._limits is not None and code == -signal.SIGSEGV:
            return self._limits.memory_message()
        if code == -signal.SIGKILL:
            return ("The job was stopped by the system (killed), most likely for using too much memory "
                    "or processor time. A shorter recording needs less.")
        return (f"Internal error: the worker process ended unexpectedly (exit code {code}); "
                "the job's worker.log on the server has the details.")

    # --- leases ---------------------------------------------------------------------------------

    def _give_up(self, folder: Path, run: int, why: str) -> None:
        """Run `run` of the job in `folder` will not finish (`why`): unless another watcher
        did so already, queue run + 1, or after MAX_RUNS runs mark the job interrupted."""
        if not claim(reaped_path(folder, run), why):
            return
        try:
            status = read_status(folder)
        except (OSError, ValueError, KeyError):
            return
        if status.state in FINAL_STATES:
            return
        if run >= MAX_RUNS:
            write_status(folder, Status(state=FAILED, stage=status.stage, fraction=status.fraction,
                                        error=WORKER_LOST, updated=time.time(), interrupted=True))
            return
        write_status(folder, Status(state=QUEUED, updated=time.time()))
        try:
            self._task(folder.name, run + 1)
        except QUEUE_ERRORS as exc:  # cannot queue it again: say so rather than leave it waiting
            LOG.error("cannot queue job %s again: %s", folder.name, exc)
            write_status(folder, Status(state=FAILED, stage=status.stage, fraction=status.fraction,
                                        error=WORKER_LOST, updated=time.time(), interrupted=True))

    def reap(self, now: float | None = None) -> list[str]:
        """Give up every unfinished job whose latest lease is older than `lease_seconds`
        (its worker died); return their ids."""
        now = time.time() if now is None else now
        given_up = []
        for job in list_jobs(self._jobs.parent):
            if job.status.state in FINAL_STATES:
                continue
            lease = current_lease(job.folder)
            if lease is None or now - float(str(lease.get("renewed", 0))) <= self._lease:
                continue
            run = int(str(lease.get("run", 1)))
            if reaped_path(job.folder, run).exists():
                continue
            self._give_up(job.folder, run, f"its worker {lease.get('host')} pid {lease.get('pid')} "
                                           f"renewed no lease for {now - float(str(lease.get('renewed', 0))):.0f} s")
            given_up.append(job.id)
        return given_up

    def _watch(self) -> None:
        """Reap lost runs every half lease; call after_job(None) (retention) every SWEEP_EVERY s."""
        last_sweep = time.monotonic()
        while not self._closed.wait(self._lease / 2):
            try:
                self.reap()
                if time.monotonic() - last_sweep >= SWEEP_EVERY:
                    last_sweep = time.monotonic()
                    self._after_job(None)
            except OSError:  # a job folder removed while it was read: look again next time
                continue
            except QUEUE_ERRORS as exc:  # the queue is down just now: look again next time
                LOG.error("lease watch: %s", exc)
