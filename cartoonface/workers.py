"""A second process for work that can run beside the main one (the two cores of issue 16).

`helper_pool(workers)` opens a forked one-process pool when `workers` is 2 or more (the caller
decides, e.g. by `processes()`: no pool for a process with a CPU-time limit,
whose limit counts per process); `offloaded(pool, fn, *args)` queues `fn(*args)` there and
returns a getter of its result that computes it here instead when the pool has not begun it, is
None, could not start, or broke (no memory, a killed child), its result handed back through a
`memory_file` when given one (`helper_process`: a pool with its memory file); `forked(workers, fn, *args)` runs
`fn(*args)` in a child forked there and then, which inherits the arguments instead of receiving
them pickled (work on a large state built in this process); `from_both_ends(pool, jobs)` shares a
list of jobs with the pool as they go; `shares(costs)` splits work in two.
The results are the same either way: the child is a fork of this process running the same code.
`collector_paused()` keeps Python's cycle collector from running during a job (and its children).
"""

from __future__ import annotations

import gc
import mmap
import multiprocessing
import os
import pickle
import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from multiprocessing.connection import Connection
from typing import Any, NamedTuple, TypeVar, cast

T = TypeVar("T")
# Jobs `from_both_ends` keeps given to the pool and not done: one under way and one waiting, so the
# pool goes on while this process is busy with a job of its own; each more is a job this process
# may wait for at the end (a ProcessPoolExecutor hands a waiting job to its process at once, and
# it can no longer be taken back).
AHEAD = 2


def processes() -> int:
    """How many processes a job may work with (generate's analysis helper, animation_svg's second
    drawing process): 2 on a machine with two cores or more that can fork, unless this process has
    a CPU-time limit (a web job's, web/worker.py: the limit counts per process, so the job's work
    stays in it) or is a daemon (which may not start processes)."""
    if "fork" not in multiprocessing.get_all_start_methods():
        return 1  # the pools fork (no pickling of the face and its caches)
    import resource  # POSIX only, like fork

    limited = resource.getrlimit(resource.RLIMIT_CPU)[0] != resource.RLIM_INFINITY
    return 1 if limited or multiprocessing.current_process().daemon or (os.cpu_count() or 1) < 2 else 2


@contextmanager
def helper_pool(workers: int, wait: bool = True) -> Iterator[Executor | None]:
    """A one-process pool, forked at once, or None when `workers` < 2, fork is missing or fails.

    Forked at once, the helper holds no pipe of a subprocess the caller starts later (generate's
    ffmpeg: a helper forked while another thread starts it could keep its output open, and the
    thread reading it would wait for the helper). On leaving, work not yet started is cancelled;
    work under way is waited for, and the process's end, unless `wait` is False (for a caller that
    has taken every result: the process then ends on its own, its exit, ~7 ms of freeing the
    drawing helper's memory, off this process's way)."""
    if workers < 2 or "fork" not in multiprocessing.get_all_start_methods():
        yield None
        return
    try:
        pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("fork"))
    except (OSError, RuntimeError):  # no memory, no semaphore for the pool's queues
        yield None
        return
    try:
        pool.submit(int)  # forks the process now
    except (BrokenProcessPool, OSError, RuntimeError):  # fork or thread start failed
        pool.shutdown(wait=False, cancel_futures=True)
        yield None
        return
    try:
        yield pool
    finally:
        pool.shutdown(wait=wait, cancel_futures=True)


class Helper(NamedTuple):
    """A one-process pool (helper_pool's; None: none) and a memory file its process inherited
    (memory_file's; None: none), for offloaded's `through`."""

    pool: Executor | None
    through: int | None


@contextmanager
def helper_process(workers: int, wait: bool = True) -> Iterator[Helper]:
    """helper_pool(workers, wait) and a memory_file made before its fork, which its process holds: a
    helper to hand large results back from (offloaded's `through`) for more than one job (generate's
    analysis helper then draws half the frames: render/animation.py)."""
    with memory_file() as through, helper_pool(workers, wait) as pool:
        yield Helper(pool, through)


@contextmanager
def memory_file() -> Iterator[int | None]:
    """An anonymous file in memory (os.memfd_create: its descriptor) for a pool forked inside the
    `with` to hand large results back through (offloaded's `through`, one result taken before the
    next is asked for: each is written from the file's start); None where there is no
    such file (not Linux, no memory). Closed on leaving (its memory freed once the pool's process,
    which inherited it, has ended too)."""
    try:
        descriptor = os.memfd_create("cartoonface-result")
    except (AttributeError, OSError):
        yield None
        return
    try:
        yield descriptor
    finally:
        os.close(descriptor)


def offloaded(pool: Executor | None, fn: Callable[..., T], *args: object, through: int | None = None) -> Callable[[], T]:
    """fn(*args) queued in `pool`; returns a function giving its result. Computed in this
    process when the pool has not begun it by then (so a caller done with its own share takes
    over the queued rest, asking for the last first), or when `pool` is None or cannot run it
    (fork or thread start failed, broken pool). An exception raised by `fn` itself is raised by
    the getter. `through`: a memory_file the pool's process inherited: the result is pickled into
    it there and read here from a mapping of the file, only its size sent through the pool's pipe (a result of
    many megabytes then costs neither the pipe's copies in 64 KB pieces nor this process's reading
    thread taking turns with its main one: docs/BENCHMARKS.md, "xfer")."""
    future: Future[Any] | None = None
    job: Callable[..., object] = fn if through is None else _written
    job_args = args if through is None else (through, fn, args)
    if pool is not None:
        try:
            future = pool.submit(job, *job_args)
        except (BrokenProcessPool, OSError, RuntimeError):
            future = None

    def result() -> T:
        if future is not None and not future.cancel():  # begun (or done) there
            try:
                value = future.result()
                return value if through is None else cast(T, _read(through, value))
            except (BrokenProcessPool, OSError, MemoryError):  # lost, or its result cannot be mapped here
                pass
        return fn(*args)

    return result


def _written(through: int, fn: Callable[..., object], args: tuple[object, ...]) -> int:
    """In the pool's process: fn(*args) pickled into the memory file `through` from its start; its
    size in bytes."""
    value = fn(*args)
    with open(through, "wb", closefd=False) as file:
        file.seek(0)
        pickle.dump(value, file, protocol=pickle.HIGHEST_PROTOCOL)
        return file.tell()


def _read(through: int, size: int) -> object:
    """The object pickled into the first `size` bytes of the memory file `through` (_written); the
    file is emptied then (its memory let go while it stays open for the next result)."""
    with mmap.mmap(through, size, access=mmap.ACCESS_READ) as view:
        value = pickle.loads(view)
    os.ftruncate(through, 0)
    return value


def from_both_ends(pool: Executor | None, jobs: Sequence[tuple[Callable[..., T], tuple[object, ...], Callable[[], T]]],
                   progress: Callable[[float], None] | None = None) -> list[T]:
    """The result of each of `jobs` (fn, args, here), in order, the jobs given costliest first: the
    pool runs fn(*args) of the jobs from the front, given AHEAD at a time (topped up each time this
    process is between jobs), and this process computes here() (the same result, from what it
    holds: the pool may be sent less) of the jobs from the back, until the two meet; then it waits
    for the pool's last ones. Whatever one process's share of other work before (the pool's first
    job may be long), neither waits for the other much longer than a cheap job takes. With no pool,
    or one that cannot run them (fork failed, broken pool), the jobs are done here. An exception
    raised by a job is raised here. `progress(fraction)`: the share of the jobs done, before each
    job done here."""
    results: dict[int, T] = {}
    given: dict[int, Future[T]] = {}
    front, back = 0, len(jobs)
    while front < back:
        while pool is not None and front < back and sum(not f.done() for f in given.values()) < AHEAD:
            fn, args, _ = jobs[front]
            try:
                given[front] = pool.submit(fn, *args)
            except (BrokenProcessPool, OSError, RuntimeError):
                pool = None  # the rest is done here
                break
            front += 1
        if front < back:
            if progress is not None:
                progress((len(jobs) - back + sum(f.done() for f in given.values())) / len(jobs))
            back -= 1
            results[back] = jobs[back][2]()
    for k, future in given.items():
        try:
            results[k] = future.result()
        except (BrokenProcessPool, OSError, MemoryError):  # the pool's process was lost: done here
            results[k] = jobs[k][2]()
    return [results[k] for k in range(len(jobs))]


def forked(workers: int, fn: Callable[..., T], *args: object) -> Callable[[], T]:
    """fn(*args) begun in a child process forked now when `workers` is 2 or more: the child holds
    `args` as they are here (nothing is pickled but the result, sent back through a pipe). Returns
    a function giving the result, waiting for it (not for the child's exit); computed in this process instead when
    `workers` < 2 or fork is missing, or the child could not start or did not send a result (no
    memory, killed, `fn` raised: the exception is then raised here by computing it again). A child
    whose result is never asked for waits on its pipe (daemonic: it ends with this process)."""
    if workers < 2 or "fork" not in multiprocessing.get_all_start_methods():
        return lambda: fn(*args)
    context = multiprocessing.get_context("fork")
    try:
        receiver, sender = context.Pipe(duplex=False)
        child = context.Process(target=_send, args=(sender, fn, args), daemon=True)
        child.start()
    except (OSError, RuntimeError):  # no memory, no process or pipe left
        return lambda: fn(*args)
    sender.close()  # the child's end: its exit without a result then reads as EOF here

    def result() -> T:
        try:
            value: T = receiver.recv()
        except (EOFError, OSError):
            value = fn(*args)
        finally:
            receiver.close()
            # its exit (a few ms of letting go of its address space) waited for by a thread, not here
            threading.Thread(target=child.join, daemon=True).start()
        return value

    return result


def _send(sender: Connection, fn: Callable[..., object], args: tuple[object, ...]) -> None:
    """In a forked child: send fn(*args) through `sender` (nothing when it raises: forked's parent
    then computes it itself)."""
    try:
        value = fn(*args)
    except BaseException:  # the parent computes it again and raises it there
        os._exit(1)
    sender.send(value)
    sender.close()


def shares(costs: Sequence[float], besides: float = 0.0) -> tuple[list[int], list[int]]:
    """Indices of `costs` split into two lists of about equal total (the largest first, each to
    the lighter side; ties to the first), each list in increasing order; `besides`: the cost of
    other work the second list's process does (in the same units), counted in its total."""
    sides: tuple[list[int], list[int]] = ([], [])
    totals = [0.0, besides]
    for index in sorted(range(len(costs)), key=lambda i: -costs[i]):
        side = 0 if totals[0] <= totals[1] else 1
        sides[side].append(index)
        totals[side] += costs[index]
    return sorted(sides[0]), sorted(sides[1])


@contextmanager
def collector_paused() -> Iterator[None]:
    """Pause Python's cycle collector inside the `with` (or the function it decorates); the
    collector runs again after it as it did before. Children forked inside inherit the pause.

    A `generate` job makes millions of containers (tuples of parts and numbers, lists) that hold
    no reference cycles: they are freed by reference counting, and the collector's passes over
    them found nothing but took ~10 % of the job's CPU time (~0.4 s of 3.5 s on the 3-minute
    bench book; a pass of the oldest generation walks every container alive); render/animation.py's
    animation_svg runs under it too. The few hundred objects in cycles a job leaves are collected
    after it (docs/BENCHMARKS.md, "Collector paused")."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()
