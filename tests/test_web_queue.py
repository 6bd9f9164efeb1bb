"""Jobs on the Huey queue: a real redis-server on a free loopback port (stopped by its pid),
`cartoonface worker` processes taking jobs from it, a worker killed mid-job, the CPU cap,
and `cartoonface batch` here and through the queue."""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
import zipfile
from collections.abc import Iterator
from pathlib import Path

import pytest

from cartoonface.render.scenery import BACKGROUNDS, CLOTHES
from cartoonface.web.runner import MAX_RUNS, WORKER_LOST, Runner, current_lease, reaped_path
from cartoonface.web.store import DONE, FAILED, QUEUED, create_job, load_job
from cartoonface.web.worker import ZIP_NAME, JobLimits
from tests.conftest import ROOT, SPOKEN, TRANSCRIPT, speak

SAMPLES = ROOT / "samples" / "faces"
REDIS = shutil.which("redis-server")
LEASE = 3.0  # seconds: short, so a dead worker is noticed quickly
REPEAT = 4  # the sentence spoken this many times: a job of a few seconds, long enough to be killed mid-way
LONG_REPEAT = 40  # a job that needs more than a second of CPU time
# Skipped without redis-server, except in CI (CI=true), where scripts/setup.sh must have installed it.
needs_redis = pytest.mark.skipif(REDIS is None and not os.environ.get("CI"),
                                 reason="redis-server is not installed (scripts/setup.sh installs it)")


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


@pytest.fixture(scope="module")
def redis_port(tmp_path_factory: pytest.TempPathFactory) -> Iterator[int]:
    """A redis-server of our own on a free loopback port, without persistence; stopped by its pid."""
    port = free_port()
    assert REDIS is not None, "redis-server is not installed: run scripts/setup.sh as root"
    folder = tmp_path_factory.mktemp("redis")
    server = subprocess.Popen([str(REDIS), "--port", str(port), "--bind", "127.0.0.1", "--save", "",
                               "--appendonly", "no", "--dir", str(folder)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 20
    while True:
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=1) as conn:
                conn.sendall(b"PING\r\n")
                if conn.recv(16).startswith(b"+PONG"):
                    break
        except OSError:
            pass
        assert time.monotonic() < deadline and server.poll() is None, "redis-server did not start"
        time.sleep(0.05)
    yield port
    os.kill(server.pid, signal.SIGTERM)
    server.wait(10)


@pytest.fixture(scope="module")
def speech(tmp_path_factory: pytest.TempPathFactory) -> bytes:
    """The test sentence spoken REPEAT times (WAV bytes, a few seconds)."""
    path = tmp_path_factory.mktemp("speech") / "speech.wav"
    speak(" ".join([SPOKEN] * REPEAT), path)
    return path.read_bytes()


@pytest.fixture(scope="module")
def long_speech(tmp_path_factory: pytest.TempPathFactory) -> bytes:
    """The test sentence spoken LONG_REPEAT times (WAV bytes, about a minute)."""
    path = tmp_path_factory.mktemp("speech") / "long.wav"
    speak(" ".join([SPOKEN] * LONG_REPEAT), path)
    return path.read_bytes()


def inputs(speech: bytes, repeat: int = REPEAT) -> dict[str, bytes]:
    face = sorted(SAMPLES.glob("*.json"))[0].read_bytes()
    return {"face.json": face, "audio.wav": speech, "transcript.txt": (TRANSCRIPT * repeat).encode()}


def spec(title: str) -> dict[str, object]:
    return {"title": title, "page": "audiobook", "background": BACKGROUNDS[0], "clothes": CLOTHES[0],
            "face_label": "f", "audio_label": "a.wav", "audio_file": "audio.wav", "duration": 1.0,
            "transcript_chars": 5}


class Workers:
    """`cartoonface worker` processes on `instance` and the Redis database `url`, stopped by pid."""

    def __init__(self, instance: Path, url: str, count: int) -> None:
        env = {**os.environ, "CARTOONFACE_QUEUE": url, "CARTOONFACE_LEASE_SECONDS": str(LEASE)}
        self.processes = []
        for _ in range(count):
            with open(instance.parent / f"worker-{len(list(instance.parent.glob('worker-*.log')))}.log", "wb") as log:
                self.processes.append(subprocess.Popen(
                    [sys.executable, "-m", "cartoonface", "worker", "--instance", str(instance), "--jobs", "1"],
                    env=env, stdout=subprocess.DEVNULL, stderr=log))

    @property
    def pids(self) -> set[int]:
        return {process.pid for process in self.processes}

    def kill(self, pid: int) -> None:
        os.kill(pid, signal.SIGKILL)
        next(process for process in self.processes if process.pid == pid).wait(10)

    def stop(self) -> None:
        for process in self.processes:
            if process.poll() is None:
                os.kill(process.pid, signal.SIGTERM)
        for process in self.processes:
            process.wait(30)


def wait_until(check, timeout: float = 120.0, every: float = 0.05):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = check()
        if value:
            return value
        time.sleep(every)
    raise AssertionError(f"timed out after {timeout} s")


def setup(tmp_path: Path, redis_port: int, db: int, workers: int) -> tuple[Path, str, Workers, Runner]:
    """An instance folder, its Redis database `db`, `workers` worker processes and a runner
    that only queues (and watches the leases, like a server with WORKERS=0)."""
    instance = tmp_path / "instance"
    instance.mkdir()
    url = f"redis://127.0.0.1:{redis_port}/{db}"
    return instance, url, Workers(instance, url, workers), Runner(instance, 0, queue=url, lease_seconds=LEASE)


@needs_redis
def test_jobs_spread_over_two_workers_each_with_its_own_result(tmp_path, redis_port, speech):
    instance, _url, workers, runner = setup(tmp_path, redis_port, 1, 2)
    try:
        jobs = [create_job(instance, spec(f"book {i}"), inputs(speech)) for i in range(4)]
        for job in jobs:
            runner.submit(job.folder)
        wait_until(lambda: all(load_job(instance, job.id).status.state not in (QUEUED, "running") for job in jobs))
    finally:
        workers.stop()
        runner.close()
    ran_by = set()
    for i, job in enumerate(jobs):
        status = load_job(instance, job.id).status
        assert status.state == DONE, status
        lease = current_lease(job.folder)
        assert lease is not None and lease["run"] == 1
        ran_by.add(lease["pid"])
        with zipfile.ZipFile(job.folder / ZIP_NAME) as archive:
            page = next(archive.read(name) for name in archive.namelist() if name.endswith("index.html"))
            assert f"book {i}".encode() in page
            assert any(name.endswith("/audio.m4a") for name in archive.namelist())
    assert ran_by == workers.pids


@needs_redis
def test_a_job_whose_worker_is_killed_is_run_again_then_marked_interrupted(tmp_path, redis_port, speech):
    instance, _url, workers, runner = setup(tmp_path, redis_port, 2, 2)
    try:
        job = create_job(instance, spec("killed twice"), inputs(speech))
        runner.submit(job.folder)
        first = wait_until(lambda: current_lease(job.folder))
        workers.kill(int(first["pid"]))
        # The surviving worker notices the lease is not renewed and runs the job again.
        second = wait_until(lambda: (lease := current_lease(job.folder)) and lease["run"] == 2 and lease)
        assert reaped_path(job.folder, 1).exists()
        assert second["pid"] in workers.pids - {first["pid"]}
        workers.kill(int(second["pid"]))
        # No worker is left: the runner's own watch gives the job up after MAX_RUNS runs.
        status = wait_until(lambda: (s := load_job(instance, job.id).status).state == FAILED and s, timeout=30)
    finally:
        workers.stop()
        runner.close()
    assert MAX_RUNS == 2
    assert status.interrupted and status.error == WORKER_LOST


@needs_redis
def test_a_killed_workers_job_finishes_on_the_other_worker(tmp_path, redis_port, speech):
    instance, _url, workers, runner = setup(tmp_path, redis_port, 3, 2)
    try:
        job = create_job(instance, spec("survives"), inputs(speech))
        runner.submit(job.folder)
        first = wait_until(lambda: current_lease(job.folder))
        workers.kill(int(first["pid"]))
        wait_until(lambda: load_job(instance, job.id).status.state in (DONE, FAILED))
    finally:
        workers.stop()
        runner.close()
    assert load_job(instance, job.id).status.state == DONE
    assert current_lease(job.folder)["run"] == 2
    assert (job.folder / "site" / "index.html").is_file()


@needs_redis
def test_a_stopped_worker_hands_its_job_back_to_the_queue(tmp_path, redis_port, speech):
    instance, url, workers, runner = setup(tmp_path, redis_port, 4, 1)
    try:
        job = create_job(instance, spec("handed back"), inputs(speech))
        runner.submit(job.folder)
        wait_until(lambda: current_lease(job.folder))
        workers.stop()  # SIGTERM: the job goes back to the queue as run 2
        assert wait_until(lambda: load_job(instance, job.id).status.state == QUEUED, timeout=30)
        assert runner.waiting() == [job.id]
        again = Workers(instance, url, 1)
        try:
            wait_until(lambda: load_job(instance, job.id).status.state in (DONE, FAILED))
        finally:
            again.stop()
    finally:
        runner.close()
    assert load_job(instance, job.id).status.state == DONE


def test_an_unreachable_queue_is_a_clear_error(tmp_path):
    done = subprocess.run([sys.executable, "-m", "cartoonface", "worker", "--instance", str(tmp_path)],
                          env={**os.environ, "CARTOONFACE_QUEUE": f"redis://127.0.0.1:{free_port()}/0"},
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    assert "CARTOONFACE_QUEUE=redis://127.0.0.1:" in done.stderr and "Traceback" not in done.stderr


def test_worker_help_explains_the_queue_and_shared_folder():
    done = subprocess.run([sys.executable, "-m", "cartoonface", "worker", "--help"], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 0
    for words in ("CARTOONFACE_QUEUE", "NFS", "--instance", "interrupted"):
        assert words in done.stdout


def test_a_job_over_its_cpu_time_fails_alone_with_a_clear_message(tmp_path, long_speech):
    job = create_job(tmp_path, spec("greedy"), inputs(long_speech, LONG_REPEAT))
    limits = JobLimits(memory_bytes=4 << 30, cpu_seconds=1)
    runner = Runner(tmp_path, 1, limits=limits)
    try:
        runner.submit(job.folder)
        wait_until(lambda: load_job(tmp_path, job.id).status.state in (DONE, FAILED))
    finally:
        runner.close()
    assert load_job(tmp_path, job.id).status.error == limits.cpu_message()


def test_the_recording_is_stored_once_and_the_download_has_the_pages_audio(tmp_path, speech):
    job = create_job(tmp_path, spec("once"), inputs(speech))
    runner = Runner(tmp_path, 1)
    try:
        runner.submit(job.folder)
        wait_until(lambda: load_job(tmp_path, job.id).status.state in (DONE, FAILED))
    finally:
        runner.close()
    assert load_job(tmp_path, job.id).status.state == DONE
    copies = [path for path in job.folder.rglob("*") if path.is_file() and path.read_bytes() == speech]
    assert len(copies) == 1  # the job's input; the page plays a compressed copy
    with zipfile.ZipFile(job.folder / ZIP_NAME) as archive:
        names = archive.namelist()
        assert not any(name.endswith(".wav") for name in names)
        assert any(name.endswith("/audio.m4a") for name in names)
        assert archive.testzip() is None


# --- cartoonface batch ----------------------------------------------------------------------


def manifest(folder: Path, speech: bytes, rows: list[str]) -> Path:
    (folder / "talk.wav").write_bytes(speech)
    (folder / "talk.txt").write_text(TRANSCRIPT * REPEAT, encoding="utf-8")
    path = folder / "books.csv"
    path.write_text("\n".join(["name,face,audio,transcript,title,page", *rows]) + "\n", encoding="utf-8")
    return path


def batch(path: Path, out: Path, env: dict[str, str] | None = None, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "cartoonface", "batch", str(path), "-o", str(out), *extra],
                          capture_output=True, text=True, timeout=300, env={**os.environ, **(env or {})})


def test_batch_makes_each_row_and_skips_finished_ones(tmp_path, speech):
    sample = sorted(SAMPLES.glob("*.json"))[0].stem
    path = manifest(tmp_path, speech, [f"one,{sample},talk.wav,talk.txt,First,audiobook",
                                       f"two,{sample},talk.wav,talk.txt,Second,announcer"])
    done = batch(path, tmp_path / "out")
    assert done.returncode == 0, done.stderr
    assert "First" in (tmp_path / "out" / "one" / "index.html").read_text(encoding="utf-8")
    assert "Second" in (tmp_path / "out" / "two" / "index.html").read_text(encoding="utf-8")
    shutil.rmtree(tmp_path / "out" / "two")
    before = (tmp_path / "out" / "one" / "index.html").stat().st_mtime_ns
    again = batch(path, tmp_path / "out")
    assert again.returncode == 0, again.stderr
    assert "1 done already, 1 to make" in again.stderr
    assert (tmp_path / "out" / "one" / "index.html").stat().st_mtime_ns == before
    assert (tmp_path / "out" / "two" / "index.html").is_file()


@pytest.mark.parametrize("row, where", [
    ("x,{sample},talk.wav,talk.txt,T,radio", "row 3, column page"),
    ("x,{sample},missing.wav,talk.txt,T,audiobook", "row 3, column audio"),
    ("x,nobody,talk.wav,talk.txt,T,audiobook", "row 3, column face"),
    ("../up,{sample},talk.wav,talk.txt,T,audiobook", "row 3, column name"),
    ("ok,{sample},talk.wav,talk.txt,T,audiobook", "row 3, column name"),  # the same name as row 2
])
def test_batch_names_the_bad_row_and_column_and_exits_2(tmp_path, speech, row, where):
    sample = sorted(SAMPLES.glob("*.json"))[0].stem
    path = manifest(tmp_path, speech, [f"ok,{sample},talk.wav,talk.txt,T,audiobook", row.format(sample=sample)])
    done = batch(path, tmp_path / "out")
    assert done.returncode == 2
    assert where in done.stderr and "Traceback" not in done.stderr
    assert not (tmp_path / "out" / "ok").exists()


@needs_redis
def test_batch_through_the_queue_with_a_worker(tmp_path, redis_port, speech):
    instance, url, workers, runner = setup(tmp_path, redis_port, 5, 1)
    runner.close()
    sample = sorted(SAMPLES.glob("*.json"))[0].stem
    path = manifest(tmp_path, speech, [f"a,{sample},talk.wav,talk.txt,Queued A,audiobook",
                                       f"b,{sample},talk.wav,talk.txt,Queued B,audiobook"])
    try:
        done = batch(path, tmp_path / "out", {"CARTOONFACE_QUEUE": url}, "--instance", str(instance))
    finally:
        workers.stop()
    assert done.returncode == 0, done.stderr
    assert "Queued B" in (tmp_path / "out" / "b" / "index.html").read_text(encoding="utf-8")
    sent = json.loads((tmp_path / "out" / "batch-jobs.json").read_text(encoding="utf-8"))
    assert set(sent) == {"a", "b"}
    assert all(current_lease(instance / "jobs" / job_id)["pid"] in workers.pids for job_id in sent.values())
