"""The bounded worker pool: `workers` threads, each running one job at a time in a
child process, so jobs use every core and a crash in one job cannot take the server
down. Children are forked from a multiprocessing forkserver that has imported the
pipeline once, so a job starts in milliseconds instead of paying ~1 s of imports.

Jobs wait in a FIFO queue in memory; their state lives on disk (store.py), so a
restart loses nothing but the queue, and those jobs are marked failed then.
"""

from __future__ import annotations

import multiprocessing
import queue
import signal
import threading
import time
from collections.abc import Callable
from multiprocessing.process import BaseProcess
from pathlib import Path

from cartoonface.web.store import FAILED, FINAL_STATES, Status, read_status, write_status
from cartoonface.web.worker import JobLimits, forked_main

FORKSERVER = multiprocessing.get_context("forkserver")

STOPPED = "Stopped: the server shut down while this job was running. Please submit it again."


class QueueFull(Exception):
    """The runner already has its maximum of jobs waiting."""


class Runner:
    """A pool of `workers` threads running jobs (by folder) in child processes held to
    `limits` (None: unlimited), with at most `queue_max` jobs waiting (None: no cap).

    `after_job(folder)` is called in the worker thread after each job ends
    (used for the retention sweep)."""

    def __init__(self, workers: int, after_job: Callable[[Path], None] = lambda folder: None,
                 limits: JobLimits | None = None, queue_max: int | None = None) -> None:
        self._queue: queue.Queue[Path | None] = queue.Queue()
        self._waiting: list[Path] = []
        self._queue_max = queue_max
        self._limits = limits
        self._after_job = after_job
        self._lock = threading.Lock()
        self._running: dict[Path, BaseProcess] = {}
        self._closed = False
        FORKSERVER.set_forkserver_preload(["cartoonface.web.worker"])
        self._threads = [threading.Thread(target=self._work, name=f"cartoonface-job-{i}", daemon=True)
                         for i in range(workers)]
        for thread in self._threads:
            thread.start()

    def submit(self, folder: Path) -> None:
        """Queue the stored job in `folder` (its status.json says queued); QueueFull when
        `queue_max` jobs are waiting already (check has_room() before storing a job)."""
        with self._lock:
            if self._closed:
                raise RuntimeError("the job runner is closed")
            if not self._has_room():
                raise QueueFull(folder)
            self._waiting.append(folder)
        self._queue.put(folder)

    def _has_room(self) -> bool:
        return self._queue_max is None or len(self._waiting) < self._queue_max

    def has_room(self) -> bool:
        """True when another job may be queued now."""
        with self._lock:
            return self._has_room()

    def ahead_of(self, folder: Path) -> int | None:
        """How many queued jobs will start before the one in `folder`; None when it is not waiting."""
        with self._lock:
            return self._waiting.index(folder) if folder in self._waiting else None

    def close(self, timeout: float = 5.0) -> None:
        """Stop: drop waiting jobs (they stay queued on disk until the next start marks them),
        terminate running ones (marked failed, STOPPED) and join the threads."""
        with self._lock:
            self._closed = True
            running = list(self._running.items())
        while True:
            try:
                self._queue.get_nowait()
            except queue.Empty:
                break
        with self._lock:
            self._waiting.clear()
        for _thread in self._threads:
            self._queue.put(None)
        for _folder, process in running:
            process.terminate()
        deadline = time.monotonic() + timeout
        for thread in self._threads:
            thread.join(max(0.0, deadline - time.monotonic()))

    def _work(self) -> None:
        while True:
            folder = self._queue.get()
            if folder is None:
                return
            with self._lock:
                if folder in self._waiting:
                    self._waiting.remove(folder)
            try:
                self._run(folder)
            finally:
                self._after_job(folder)

    def _run(self, folder: Path) -> None:
        with self._lock:
            if self._closed:
                return
            process = FORKSERVER.Process(target=forked_main, args=(str(folder), self._limits),
                                         name=f"cartoonface-{folder.name}")
            process.start()
            self._running[folder] = process
        try:
            process.join()
            code = process.exitcode
            process.close()
        finally:
            with self._lock:
                self._running.pop(folder, None)
                closed = self._closed
        try:
            status = read_status(folder)
        except FileNotFoundError:
            return
        if status.state not in FINAL_STATES:
            reason = STOPPED if closed else self._died(code)
            write_status(folder, Status(state=FAILED, stage=status.stage, fraction=status.fraction,
                                        error=reason, updated=time.time()))

    def _died(self, code: int | None) -> str:
        """The user message for a worker process that ended with exit code `code` before its
        job's status was final: stopped by the CPU limit, out of its address space (a
        segmentation fault under the memory limit), killed (the hard CPU limit, or the system
        out of memory), or else died."""
        if self._limits is not None and code == -signal.SIGXCPU:
            return self._limits.cpu_message()
        # Under the address-space limit a stack that cannot grow is a segmentation fault, not a
        # MemoryError (seen in tests/test_web.py's over-memory job: SIGSEGV inside numpy's mean
        # while decoding, about every other run once the worker's imports grew a little).
        if self._limits is not None and code == -signal.SIGSEGV:
            return self._limits.memory_message()
        if code == -signal.SIGKILL:
            return ("The job was stopped by the system (killed), most likely for using too much memory "
                    "or processor time. A shorter recording needs less.")
        return (f"Internal error: the worker process ended unexpectedly (exit code {code}); "
                "the job's worker.log on the server has the details.")
