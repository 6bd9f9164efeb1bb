"""Web app under load, restart and fuzzing: a real `cartoonface serve` on 127.0.0.1.

1. Load: 20 jobs of a 30-second recording (real Mandarin speech from
   ../shared/bench/zh/biaobei, a different run of sentences and title per job)
   submitted at once; every job must finish, and each result page and zip must
   hold its own title and text. Prints p50 / p95 seconds from submission to done,
   per round and the median over 3 rounds (the shared machine is noisy).
2. Restart: jobs running, the server stopped (SIGTERM, then SIGKILL in a second
   round) and started again on the same instance: no finished job lost, every
   interrupted job failed with a reason.
3. Fuzz: 1000 malformed or random requests (bad ids, traversal, wrong types, bad Host headers,
   truncated files and photos, huge fields, broken multipart, wrong methods, the JSON API
   with missing, wrong and right tokens and broken fields); counts the answers by status
   class; 5xx must be 0, tracebacks in the server log 0, peak memory under 2 GB.
4. Queue: a redis-server of its own on a free loopback port, the server with
   CARTOONFACE_QUEUE and no workers of its own, `cartoonface worker` processes; 20 jobs sent
   at once through the JSON API to 2 workers and to 1 (throughput), every result checked
   against its own input; then a worker killed (SIGKILL) mid-job: where each job ends up.

All traffic goes to 127.0.0.1 only.
"""

from __future__ import annotations

import html
import http.client
import http.cookiejar
import io
import json
import os
import random
import re
import secrets
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.parse
import urllib.request
import zipfile
from collections import Counter
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import soundfile

from cartoonface.data import SAMPLE_FACES
from tests.synthetic import wav_bytes

ROOT = Path(__file__).resolve().parent.parent
BIAOBEI = ROOT.parent / "shared" / "bench" / "zh" / "biaobei"
SAMPLE_FACE = "female"
HOST = "127.0.0.1"
LOAD_JOBS = 20
LOAD_ROUNDS = 3
LOAD_SECONDS = 30.0
RESTART_JOBS = 8
RESTART_SECONDS = 10.0
FUZZ_REQUESTS = 1000
API_TOKEN = "bench-token-" + "0123456789abcdef"
QUEUE_JOBS = 20
QUEUE_SECONDS = 10.0
QUEUE_ROUNDS = 2  # rounds of 20 jobs with 2 workers and with 1, alternated
QUEUE_LEASE = 5.0  # seconds: a killed worker's job is taken again after this
GAP = 0.4  # seconds of silence between joined sentences


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind((HOST, 0))
        return probe.getsockname()[1]


class Server:
    """`cartoonface serve` on a free loopback port with its own instance folder."""

    def __init__(self, instance: Path, env: dict[str, str] | None = None) -> None:
        self.instance = instance
        self.env = {**os.environ, **(env or {})}
        self.port = free_port()
        self.base = f"http://{HOST}:{self.port}"
        self.process: subprocess.Popen[bytes] | None = None

    def start(self) -> None:
        log = open(self.instance.parent / f"server-{self.port}.log", "ab")
        self.process = subprocess.Popen(
            [sys.executable, "-m", "cartoonface", "serve", "--port", str(self.port), "--instance", str(self.instance)],
            stdout=log, stderr=subprocess.STDOUT, cwd=ROOT, env=self.env)
        log.close()
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            try:
                with urllib.request.urlopen(self.base + "/", timeout=5) as answer:
                    if answer.status == 200:
                        return
            except OSError:
                if self.process.poll() is not None:
                    break
                time.sleep(0.2)
        raise RuntimeError(f"server on port {self.port} did not start")

    def stop(self, sig: int = signal.SIGTERM) -> None:
        assert self.process is not None
        self.process.send_signal(sig)
        self.process.wait(timeout=60)


class Client:
    """A browser-like client: keeps the session cookie, reads the CSRF token, sends the form."""

    def __init__(self, base: str) -> None:
        self.base = base
        self.opener = urllib.request.build_opener(urllib.request.HTTPCookieProcessor(http.cookiejar.CookieJar()))

    def get(self, path: str, timeout: float = 30) -> tuple[int, bytes]:
        try:
            with self.opener.open(self.base + path, timeout=timeout) as answer:
                return answer.status, answer.read()
        except urllib.error.HTTPError as error:
            return error.code, error.read()

    def token(self) -> str:
        _status, page = self.get("/")
        return csrf_token(page)

    def submit(self, title: str, transcript: str, wav: bytes) -> str:
        """Send a complete form; return the job id (the form must be accepted)."""
        fields = {"csrf_token": self.token(), "face_sample": SAMPLE_FACE, "page": "audiobook", "title": title,
                  "background": "studio", "clothes": "suit", "transcript": transcript,
                  "audio": ("speech.wav", wav, "audio/wav")}
        body, kind = multipart(fields)
        request = urllib.request.Request(self.base + "/jobs", data=body, headers={"Content-Type": kind})
        try:
            with self.opener.open(request, timeout=120) as answer:
                url = answer.geturl()
        except urllib.error.HTTPError as error:
            raise RuntimeError(f"form refused ({error.code}): {error.read()[:2000]!r}") from None
        return url.rstrip("/").rsplit("/", 1)[-1]

    def status(self, job_id: str) -> dict:
        code, body = self.get(f"/jobs/{job_id}/status")
        if code != 200:
            raise RuntimeError(f"status of {job_id}: HTTP {code}")
        return json.loads(body)


def csrf_token(page: bytes) -> str:
    """The CSRF token in a form page; RuntimeError when the page has none."""
    found = re.search(rb'name="csrf_token" value="([^"]+)"', page)
    if found is None:
        raise RuntimeError(f"no csrf_token in the form page: {page[:200]!r}")
    return found.group(1).decode()


def multipart(fields: Mapping[str, object], boundary: str | None = None) -> tuple[bytes, str]:
    """Encode `fields` (name -> str, or (filename, bytes, type)) as multipart/form-data."""
    boundary = boundary or secrets.token_hex(16)
    parts = []
    for name, value in fields.items():
        if isinstance(value, tuple):
            filename, data, kind = value
            head = (f'Content-Disposition: form-data; name="{name}"; filename="{filename}"\r\n'
                    f"Content-Type: {kind}\r\n\r\n").encode()
        else:
            head = f'Content-Disposition: form-data; name="{name}"\r\n\r\n'.encode()
            data = str(value).encode()
        parts.append(b"--" + boundary.encode() + b"\r\n" + head + data + b"\r\n")
    return b"".join(parts) + b"--" + boundary.encode() + b"--\r\n", f"multipart/form-data; boundary={boundary}"


def biaobei_sentences() -> list[tuple[np.ndarray, int, str]]:
    """Every Biaobei sentence: (samples float32, rate, Hanzi text)."""
    texts = {}
    for line in (BIAOBEI / "transcripts.tsv").read_text(encoding="utf-8").splitlines()[1:]:
        cells = line.split("\t")
        texts[cells[0]] = cells[1]
    out = []
    for key in sorted(texts):
        samples, rate = soundfile.read(BIAOBEI / "wav" / f"{key}.wav", dtype="float32", always_2d=True)
        out.append((samples.mean(axis=1), rate, texts[key]))
    return out


def recording(sentences: list[tuple[np.ndarray, int, str]], start: int, seconds: float) -> tuple[bytes, str]:
    """Whole sentences from index `start` on (wrapping), with short pauses, as many as fit
    in `seconds`, padded with silence to exactly `seconds`; return (16-bit WAV bytes, transcript)."""
    rate = sentences[0][1]
    pieces, texts, used, index = [], [], 0, start
    while True:
        samples, _rate, text = sentences[index % len(sentences)]
        if used + len(samples) > seconds * rate:
            break
        pieces += [samples, np.zeros(int(GAP * rate), dtype=np.float32)]
        texts.append(text)
        used += len(samples) + int(GAP * rate)
        index += 1
    joined = np.zeros(int(seconds * rate), dtype=np.float32)
    speech = np.concatenate(pieces)[: len(joined)]
    joined[: len(speech)] = speech
    return wav_bytes(joined, rate), "".join(texts)


def wait_all(client: Client, ids: list[str], timeout: float) -> dict[str, tuple[dict, float]]:
    """Poll until every job ends; return id -> (final status, monotonic time it was seen done)."""
    finished: dict[str, tuple[dict, float]] = {}
    deadline = time.monotonic() + timeout
    while len(finished) < len(ids) and time.monotonic() < deadline:
        for job_id in ids:
            if job_id not in finished:
                status = client.status(job_id)
                if status["state"] in ("done", "failed"):
                    finished[job_id] = (status, time.monotonic())
        time.sleep(0.5)
    return finished


def result_matches(client: Client, job_id: str, title: str, transcript: str) -> bool:
    """True when the job's page and zip hold its own title and the start of its own text."""
    code, html = client.get(f"/jobs/{job_id}/site/index.html")
    code_zip, data = client.get(f"/jobs/{job_id}/download")
    if code != 200 or code_zip != 200:
        return False
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        index = next(name for name in archive.namelist() if name.endswith("/index.html"))
        zipped = archive.read(index).decode("utf-8")
    text = html.decode("utf-8")
    head = transcript[:6]
    return all(title in page and head in page for page in (text, zipped))


def load_round(server: Server, sentences: list, round_no: int) -> tuple[float, float]:
    """Submit LOAD_JOBS jobs at once, wait for all, check each result; print and return (p50, p95)."""
    client = Client(server.base)
    jobs = []
    for i in range(LOAD_JOBS):
        wav, transcript = recording(sentences, (i * 7 + round_no) % len(sentences), LOAD_SECONDS)
        jobs.append((f"load {round_no} job {i:02d}", transcript, wav))
    ids: list[str | None] = [None] * LOAD_JOBS
    started = [0.0] * LOAD_JOBS

    def send(i: int) -> None:
        title, transcript, wav = jobs[i]
        started[i] = time.monotonic()
        ids[i] = Client(server.base).submit(title, transcript, wav)

    threads = [threading.Thread(target=send, args=(i,)) for i in range(LOAD_JOBS)]
    begun = time.monotonic()
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    accepted = time.monotonic() - begun
    sent = {i: job_id for i, job_id in enumerate(ids) if job_id}
    finished = wait_all(client, list(sent.values()), timeout=3600)
    wall = time.monotonic() - begun
    done = {i: job_id for i, job_id in sent.items() if finished.get(job_id, ({},))[0].get("state") == "done"}
    failed = {job_id: finished[job_id][0]["error"] for job_id in sent.values() if job_id in finished
              and finished[job_id][0]["state"] == "failed"}
    lost = sum(1 for job_id in ids if job_id not in finished)
    matched = sum(result_matches(client, job_id, jobs[i][0], jobs[i][1]) for i, job_id in done.items())
    times = np.array([finished[job_id][1] - started[i] for i, job_id in done.items()])
    print(f"load {round_no}: all {LOAD_JOBS} accepted in {accepted:.1f} s; done {len(done)}, failed {len(failed)}, "
          f"lost {lost}, results matching their own input {matched}/{len(done)}")
    for job_id, error in failed.items():
        print(f"load {round_no}: failed {job_id}: {error}")
    if not len(times):
        return float("nan"), float("nan")
    inside = [json.loads((server.instance / "jobs" / job_id / "status.json").read_text())["result"]["seconds"]
              for job_id in done.values()]
    p50, p95 = float(np.percentile(times, 50)), float(np.percentile(times, 95))
    print(f"load {round_no}: time to done p50 {p50:.1f} s, p95 {p95:.1f} s, all done after {wall:.1f} s "
          f"({wall / len(times):.2f} s per job); pipeline.generate inside a job: median {np.median(inside):.2f} s")
    return p50, p95


def load_run(work: Path, sentences: list) -> None:
    server = Server(work / "load")
    server.start()
    try:
        print(f"load: {LOAD_ROUNDS} rounds of {LOAD_JOBS} jobs x {LOAD_SECONDS:.0f} s recording, "
              f"workers = cores ({os.cpu_count()})")
        figures = np.array([load_round(server, sentences, round_no) for round_no in range(LOAD_ROUNDS)])
        print(f"load: median over rounds: p50 {np.median(figures[:, 0]):.1f} s, p95 {np.median(figures[:, 1]):.1f} s")
    finally:
        server.stop()


def restart_round(server: Server, sentences: list, sig: int, round_no: int) -> None:
    client = Client(server.base)
    titles = {}
    ids = []
    for i in range(RESTART_JOBS):
        wav, transcript = recording(sentences, 3 * i + 40 * round_no, RESTART_SECONDS)
        title = f"restart {round_no} job {i}"
        job_id = client.submit(title, transcript, wav)
        ids.append(job_id)
        titles[job_id] = (title, transcript)
    deadline = time.monotonic() + 1800
    while time.monotonic() < deadline:
        states = {job_id: client.status(job_id)["state"] for job_id in ids}
        done_before = [job_id for job_id, state in states.items() if state == "done"]
        if len(done_before) >= 2:
            break
        time.sleep(0.3)
    server.stop(sig)
    unfinished = [job_id for job_id in ids if job_id not in done_before]
    server.start()
    time.sleep(3)  # let any orphaned worker notice its server is gone
    client = Client(server.base)
    after = {job_id: client.status(job_id) for job_id in ids}
    kept = sum(after[job_id]["state"] == "done" and result_matches(client, job_id, *titles[job_id])
               for job_id in done_before)
    # A job may finish between the last look and the stop: it must then be whole too.
    late = [job_id for job_id in unfinished if after[job_id]["state"] == "done"]
    late_whole = sum(result_matches(client, job_id, *titles[job_id]) for job_id in late)
    reasons = Counter(after[job_id]["error"].split(":")[0] for job_id in unfinished
                      if after[job_id]["state"] == "failed" and after[job_id]["error"])
    other = len(unfinished) - len(late) - sum(reasons.values())
    name = signal.Signals(sig).name
    print(f"restart ({name}): {len(done_before)} done before the stop, {kept} still done and intact after "
          f"the restart (lost {len(done_before) - kept}); of {len(unfinished)} unfinished: "
          f"{len(late)} finished during the stop ({late_whole} intact), "
          + ", ".join(f"{count} failed '{reason}'" for reason, count in sorted(reasons.items()))
          + f", {other} in any other state")


def restart_run(work: Path, sentences: list) -> None:
    server = Server(work / "restart")
    server.start()
    try:
        restart_round(server, sentences, signal.SIGTERM, 0)
        restart_round(server, sentences, signal.SIGKILL, 1)
    finally:
        server.stop()


def hostile_face(face: bytes, kind: str) -> bytes:
    """The sample face made hostile (docs/web.md, "Limits against hostile input"): "digits" a 5000-digit FAPU, "fapu" a FAPU of
    1e300, "hair" a 30,000-point hair outline."""
    obj = json.loads(face)
    if kind == "digits":
        obj["fapu"]["r1"] = 424242
        return json.dumps(obj).replace("424242", "9" * 5000).encode()
    if kind == "fapu":
        obj["fapu"]["r1"] = 1e300
    else:
        obj["hair"] = [obj["hair"][i % len(obj["hair"])] for i in range(30000)]
    return json.dumps(obj).encode()


def peak_mb(pid: int) -> float:
    """Peak resident memory (VmHWM) of process `pid` in MB, read from /proc."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    return 0.0




# A fuzz request: method, path, body (bytes, None, or ("huge", size) for a streamed body), headers.
FuzzRequest = tuple[str, str, bytes | tuple[str, int] | None, dict[str, str]]


def fuzz_requests(rng: random.Random, token: str, cookie: str, wav: bytes, face: bytes,
                  photo: bytes) -> list[FuzzRequest]:
    """FUZZ_REQUESTS (method, path, body, headers) built from `rng`."""

    def junk(n: int) -> bytes:
        return bytes(rng.getrandbits(8) for _ in range(n))

    def junk_text(n: int) -> str:
        return "".join(chr(rng.choice([rng.randrange(32, 127), rng.randrange(0x4E00, 0x9FFF), rng.randrange(1, 32)]))
                       for _ in range(n))

    ids = ["", "x", "A" * 31, "A" * 33, "../" * 11, "%2e%2e%2f" * 4, "%00" * 11, secrets.token_urlsafe(24),
           "A" * 5000, "<script>", "🙂" * 8]
    subpaths = ["", "/status", "/download", "/site/index.html", "/site/../job.json", "/site/%2e%2e/status.json",
                "/site/" + "a/" * 200, "/site/..%5cjob.json", "/nope"]
    good = {"csrf_token": token, "face_sample": SAMPLE_FACE, "page": "audiobook", "title": "t", "background": "studio",
            "clothes": "suit", "transcript": "你好。", "audio": ("a.wav", wav, "audio/wav")}
    broken_values = {
        "csrf_token": lambda: rng.choice(["", "x", token[:-1], junk_text(50)]),
        "face_sample": lambda: rng.choice(["", "../../etc/passwd", junk_text(30), "female.json"]),
        "page": lambda: rng.choice(["", "video", junk_text(10)]),
        "title": lambda: rng.choice([junk_text(300), "x" * 5000, "<script>alert(1)</script>" * 10,
                                     "bell\x07", "nul\x00", "\x1b[31mred"]),
        "background": lambda: junk_text(rng.randrange(0, 40)),
        "clothes": lambda: junk_text(rng.randrange(0, 40)),
        "transcript": lambda: rng.choice(["", junk_text(30000), "\x00" * 10, junk_text(100)]),
        "audio": lambda: rng.choice([("a.wav", wav[: rng.randrange(0, len(wav))], "audio/wav"),
                                     ("a.wav", junk(rng.randrange(0, 5000)), "audio/wav"),
                                     ("a.mp3", b"ID3" + junk(2000), "audio/mpeg"),
                                     ("a.wav", b"RIFF" + junk(4) + b"WAVE" + junk(500), "audio/wav"),
                                     ("a.ogg", b"OggS" + junk(3000), "audio/ogg"),
                                     ("a.flac", b"fLaC" + junk(3000), "audio/flac"),
                                     ("../../a.wav", wav[:1000], "text/plain")]),
        "face_file": lambda: rng.choice([("f.json", face[: rng.randrange(0, len(face))], "application/json"),
                                         ("f.json", junk(500), "application/json"),
                                         ("f.json", json.dumps({"format": "cartoonface-face", "points": junk_text(5)}).encode(),
                                          "application/json"),
                                         ("f.json", b"[" * 5000, "application/json"),
                                         ("f.json", b"1e999999", "application/json"),
                                         ("f.json", hostile_face(face, "digits"), "application/json"),
                                         ("f.json", hostile_face(face, "fapu"), "application/json"),
                                         ("f.json", hostile_face(face, "hair"), "application/json")]),
        "photo": lambda: rng.choice([("p.jpg", b"\xff\xd8\xff" + junk(rng.randrange(0, 3000)), "image/jpeg"),
                                     ("p.png", photo[: rng.randrange(0, len(photo))], "image/png"),
                                     ("p.webp", b"RIFF" + junk(4) + b"WEBP" + junk(800), "image/webp"),
                                     ("p.png", junk(2000), "image/png")]),
        "transcript_file": lambda: ("t.txt", rng.choice([junk(300), "好".encode() * 30000, b"\xff\xfe" + junk(40),
                                                         photo, "你好\x00。".encode()]),
                                    "text/plain"),
    }
    requests: list[FuzzRequest] = []
    while len(requests) < FUZZ_REQUESTS:
        kind = rng.randrange(8)
        headers = {"Cookie": cookie}
        if rng.random() < 0.05:  # a foreign or broken Host header (DNS rebinding, garbage)
            headers["Host"] = rng.choice(["rebound.example", "", "127.0.0.1:99999", "".join(chr(rng.randrange(33, 127)) for _ in range(20))])
        if kind == 0:
            requests.append(("GET", f"/jobs/{rng.choice(ids)}{rng.choice(subpaths)}", None, headers))
        elif kind == 1:
            method = rng.choice(["PUT", "DELETE", "PATCH", "POST", "OPTIONS", "GET"])
            path = rng.choice(["/", "/jobs", f"/jobs/{secrets.token_urlsafe(24)}", "/static/web/../../pyproject.toml",
                               "/static/web/web.css?" + junk_text(20).replace(" ", "")])
            requests.append((method, path, junk(rng.randrange(0, 200)) if method != "GET" else None, headers))
        elif kind in (2, 3):
            fields = dict(good)
            broken = rng.sample(sorted(broken_values), rng.randrange(1, 4))
            if kind == 3 or "face_file" not in broken:
                broken.append("face_file")  # never a fully valid form: no real jobs from the fuzzer
            for name in broken:
                fields[name] = broken_values[name]()
            if rng.random() < 0.2:
                fields.pop(rng.choice(sorted(fields)))
            body, content_type = multipart(fields)
            if rng.random() < 0.15:
                body = body[: rng.randrange(0, len(body))]  # truncated upload
            requests.append(("POST", "/jobs", body, {**headers, "Content-Type": content_type}))
        elif kind == 4:
            content_type = rng.choice(["application/json", "text/plain", "multipart/form-data",
                                       "multipart/form-data; boundary=", "application/x-www-form-urlencoded",
                                       "multipart/form-data; boundary=" + "x" * 300])
            requests.append(("POST", "/jobs", junk(rng.randrange(0, 4000)), {**headers, "Content-Type": content_type}))
        elif kind == 6:  # the JSON API: no, wrong or right token; broken fields, odd routes
            auth = rng.choice(["", f"Bearer {API_TOKEN}", f"Bearer {API_TOKEN}", "Bearer x", f"Basic {API_TOKEN}",
                               "Bearer " + "".join(chr(rng.randrange(33, 127)) for _ in range(40))])
            api_headers = {"Authorization": auth} if auth else {}
            if rng.random() < 0.3:
                path = rng.choice([f"/api/jobs/{rng.choice(ids)}", f"/api/jobs/{rng.choice(ids)}/result.zip",
                                   "/api/", "/api/nothing", "/api/jobs"])
                requests.append((rng.choice(["GET", "DELETE", "PUT"]), path, None, api_headers))
                continue
            api_fields: dict[str, object] = {"sample": SAMPLE_FACE, "transcript": "你好。",
                                             "audio": ("a.wav", wav, "audio/wav")}
            choices = {"sample": lambda: rng.choice(["", "../x", junk_text(20)]),
                       "face": broken_values["face_file"], "photo": broken_values["photo"],
                       "audio": broken_values["audio"], "transcript": broken_values["transcript"],
                       "title": broken_values["title"], "page": broken_values["page"],
                       junk_text(8).replace('"', "") or "x": lambda: junk_text(20)}
            for name in rng.sample(sorted(choices), rng.randrange(1, 4)):
                api_fields[name] = choices[name]()
            if not any(name in api_fields and api_fields[name] != good.get(name) for name in ("face", "audio")):
                api_fields["face"] = broken_values["face_file"]()  # never a valid job
            body, content_type = multipart(api_fields)
            requests.append(("POST", "/api/jobs", body, {**api_headers, "Content-Type": content_type}))
        elif kind == 7:  # hostile face models and text in otherwise good forms, through the form
            fields = dict(good)
            fields["face_file"] = ("f.json", hostile_face(face, rng.choice(["digits", "fapu", "hair"])),
                                   "application/json")
            fields[rng.choice(["title", "transcript"])] = rng.choice(["bell\x07", "nul\x00", "\x1b[31mred"])
            body, content_type = multipart(fields)
            requests.append(("POST", "/jobs", body, {**headers, "Content-Type": content_type}))
        else:
            big = rng.choice([2 << 20, 12 << 20])  # a field over the form memory limit, a body over the 5 MB cap
            body, content_type = multipart({"csrf_token": token, "title": "x"})
            requests.append(("POST", "/jobs", ("huge", big), {**headers, "Content-Type": content_type}))
    return requests


def send_raw(port: int, method: str, path: str, body, headers: dict) -> int:
    """Send one request; return the status (0 when the server closed the connection early)."""
    connection = http.client.HTTPConnection(HOST, port, timeout=120)
    path = urllib.parse.quote(path, safe="/%?=&")
    try:
        if isinstance(body, tuple):  # ("huge", n): a text field of n bytes, sent in pieces
            size = body[1]
            boundary = headers["Content-Type"].split("boundary=")[1]
            head = (f'--{boundary}\r\nContent-Disposition: form-data; name="transcript"\r\n\r\n').encode()
            tail = f"\r\n--{boundary}--\r\n".encode()
            connection.putrequest(method, path)
            for name, value in {**headers, "Content-Length": str(len(head) + size + len(tail))}.items():
                connection.putheader(name, value)
            connection.endheaders()
            try:
                connection.send(head)
                chunk = b"a" * (1 << 20)
                for start in range(0, size, len(chunk)):
                    connection.send(chunk[: min(len(chunk), size - start)])
                connection.send(tail)
            except (BrokenPipeError, ConnectionResetError):
                pass
        else:
            connection.request(method, path, body=body, headers=headers)
        answer = connection.getresponse()
        answer.read()
        return answer.status
    except (ConnectionResetError, BrokenPipeError, http.client.RemoteDisconnected):
        return 0
    finally:
        connection.close()


def fuzz_run(work: Path, sentences: list) -> None:
    server = Server(work / "fuzz", {"CARTOONFACE_MAX_UPLOAD_MB": "5", "CARTOONFACE_API_TOKEN": API_TOKEN})
    server.start()
    try:
        connection = http.client.HTTPConnection(HOST, server.port, timeout=30)
        connection.request("GET", "/")
        answer = connection.getresponse()
        page = answer.read()
        cookie = (answer.getheader("Set-Cookie") or "").split(";", 1)[0]
        connection.close()
        token = csrf_token(page)
        wav, _text = recording(sentences, 0, 3.0)
        face = (SAMPLE_FACES / f"{SAMPLE_FACE}.json").read_bytes()
        photo = (ROOT / "docs" / "photo-astronaut.png").read_bytes()
        requests = fuzz_requests(random.Random(20261125), token, cookie, wav, face, photo)
        counts: dict[str, int] = {}
        fives = []
        began = time.monotonic()
        for method, path, body, headers in requests:
            status = send_raw(server.port, method, path, body, headers)
            key = f"{status // 100}xx" if status else "closed"
            counts[key] = counts.get(key, 0) + 1
            if status >= 500:
                fives.append((method, path[:80], status))
        took = time.monotonic() - began
        alive = Client(server.base).get("/")[0]
        assert server.process is not None
        tracebacks = (work / f"server-{server.port}.log").read_text(errors="replace").count("Traceback")
        print(f"fuzz: {len(requests)} requests in {took:.1f} s: " +
              ", ".join(f"{key} {value}" for key, value in sorted(counts.items())) +
              f"; 5xx answers: {len(fives)}; tracebacks in the server log: {tracebacks}; "
              f"server peak memory {peak_mb(server.process.pid):.0f} MB; home page afterwards: {alive}")
        for item in fives[:10]:
            print(f"fuzz: 5xx {item}")
    finally:
        server.stop()


class Redis:
    """A redis-server of our own on a free loopback port, without persistence; stopped by its pid."""

    def __init__(self, folder: Path) -> None:
        self.port = free_port()
        folder.mkdir(parents=True, exist_ok=True)
        self.process = subprocess.Popen(["redis-server", "--port", str(self.port), "--bind", HOST, "--save", "",
                                         "--appendonly", "no", "--dir", str(folder)],
                                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            try:
                with socket.create_connection((HOST, self.port), timeout=1) as conn:
                    conn.sendall(b"PING\r\n")
                    if conn.recv(16).startswith(b"+PONG"):
                        return
            except OSError:
                time.sleep(0.05)
        raise RuntimeError("redis-server did not start")

    def url(self, db: int) -> str:
        return f"redis://{HOST}:{self.port}/{db}"

    def stop(self) -> None:
        os.kill(self.process.pid, signal.SIGTERM)
        self.process.wait(30)


def start_worker(instance: Path, env: dict[str, str], n: int) -> subprocess.Popen[bytes]:
    """`cartoonface worker --jobs 1` on `instance` with `env` (the queue and lease settings)."""
    with open(instance.parent / f"worker-{n}.log", "ab") as log:
        return subprocess.Popen([sys.executable, "-m", "cartoonface", "worker", "--instance", str(instance),
                                 "--jobs", "1"], stdout=log, stderr=subprocess.STDOUT, cwd=ROOT,
                                env={**os.environ, **env})


def api_submit(base: str, title: str, transcript: str, wav: bytes) -> str:
    """Send a job through the JSON API; return its id."""
    body, kind = multipart({"sample": SAMPLE_FACE, "title": title, "transcript": transcript,
                            "audio": ("speech.wav", wav, "audio/wav")})
    request = urllib.request.Request(base + "/api/jobs", data=body, headers={
        "Content-Type": kind, "Authorization": f"Bearer {API_TOKEN}"})
    with urllib.request.urlopen(request, timeout=120) as answer:
        return json.loads(answer.read())["id"]


def api_get(base: str, path: str) -> tuple[int, bytes]:
    request = urllib.request.Request(base + path, headers={"Authorization": f"Bearer {API_TOKEN}"})
    try:
        with urllib.request.urlopen(request, timeout=60) as answer:
            return answer.status, answer.read()
    except urllib.error.HTTPError as error:
        return error.code, error.read()


def api_wait(base: str, ids: list[str], timeout: float) -> dict[str, dict]:
    """Poll the API until every job is done, failed or interrupted; id -> its JSON."""
    final: dict[str, dict] = {}
    deadline = time.monotonic() + timeout
    while len(final) < len(ids) and time.monotonic() < deadline:
        for job_id in ids:
            if job_id not in final:
                job = json.loads(api_get(base, f"/api/jobs/{job_id}")[1])
                if job["state"] not in ("queued", "running"):
                    final[job_id] = job
        time.sleep(0.5)
    return final


def api_result_matches(base: str, job_id: str, title: str, transcript: str) -> bool:
    """True when the job's result.zip holds its own title and the start of its own text."""
    code, data = api_get(base, f"/api/jobs/{job_id}/result.zip")
    if code != 200:
        return False
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        page = html.unescape(archive.read(next(name for name in archive.namelist()
                                               if name.endswith("/index.html"))).decode())
    return title in page and transcript[:6] in page


def queue_round(work: Path, redis: Redis, sentences: list, workers: int, db: int) -> float:
    """QUEUE_JOBS jobs sent at once through the API to `workers` worker processes on Redis; print
    what became of them; return the wall time until all ended."""
    env = {"CARTOONFACE_QUEUE": redis.url(db), "CARTOONFACE_WORKERS": "0", "CARTOONFACE_API_TOKEN": API_TOKEN,
           "CARTOONFACE_LEASE_SECONDS": str(QUEUE_LEASE), "CARTOONFACE_QUEUE_MAX": str(QUEUE_JOBS)}
    server = Server(work / f"queue-{db}-{workers}" / "instance", env)
    server.instance.mkdir(parents=True)
    server.start()
    procs = [start_worker(server.instance, env, n) for n in range(workers)]
    try:
        jobs = []
        for i in range(QUEUE_JOBS):
            wav, transcript = recording(sentences, (i * 5 + workers) % len(sentences), QUEUE_SECONDS)
            jobs.append((f"queue {workers} job {i:02d}", transcript, wav))
        ids: list[str] = [""] * QUEUE_JOBS

        def send(i: int) -> None:
            ids[i] = api_submit(server.base, *jobs[i])

        begun = time.monotonic()
        threads = [threading.Thread(target=send, args=(i,)) for i in range(QUEUE_JOBS)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        final = api_wait(server.base, ids, 3600)
        wall = time.monotonic() - begun
        states = Counter(job["state"] for job in final.values())
        matched = sum(api_result_matches(server.base, job_id, jobs[i][0], jobs[i][1])
                      for i, job_id in enumerate(ids) if final.get(job_id, {}).get("state") == "done")
        by_worker = Counter(job["worker"]["pid"] for job in final.values() if job.get("worker"))
        memory = max(peak_mb(proc.pid) for proc in procs)
        job_memory = max((job.get("result") or {}).get("peak_memory_mb", 0) for job in final.values())
        inside = float(np.median([(job.get("result") or {}).get("seconds", 0) for job in final.values()]))
        print(f"queue ({workers} worker{'s' if workers > 1 else ''}): {QUEUE_JOBS} jobs of {QUEUE_SECONDS:.0f} s "
              f"sent at once: {dict(states)}, lost {QUEUE_JOBS - len(final)}, results matching their own input "
              f"{matched}/{states.get('done', 0)}; jobs per worker {sorted(by_worker.values())}; all ended after "
              f"{wall:.1f} s ({wall / QUEUE_JOBS:.2f} s per job; generate inside a job: median {inside:.2f} s); peak memory server "
              f"{peak_mb(server.process.pid):.0f} MB, worker consumer {memory:.0f} MB, job process {job_memory} MB")  # type: ignore[union-attr]
        return wall
    finally:
        for proc in procs:
            proc.send_signal(signal.SIGTERM)
        for proc in procs:
            proc.wait(60)
        server.stop()


def kill_round(work: Path, redis: Redis, sentences: list, db: int) -> None:
    """4 jobs on 2 workers; the worker running the first job is killed (SIGKILL) mid-job."""
    env = {"CARTOONFACE_QUEUE": redis.url(db), "CARTOONFACE_WORKERS": "0", "CARTOONFACE_API_TOKEN": API_TOKEN,
           "CARTOONFACE_LEASE_SECONDS": str(QUEUE_LEASE)}
    server = Server(work / "queue-kill" / "instance", env)
    server.instance.mkdir(parents=True)
    server.start()
    procs = {proc.pid: proc for proc in (start_worker(server.instance, env, n) for n in range(2))}
    try:
        jobs = []
        for i in range(4):
            wav, transcript = recording(sentences, 11 * i + 3, QUEUE_SECONDS)
            jobs.append((f"kill job {i}", transcript, wav))
        ids = [api_submit(server.base, *job) for job in jobs]
        deadline = time.monotonic() + 600
        victim = None
        while victim is None and time.monotonic() < deadline:
            job = json.loads(api_get(server.base, f"/api/jobs/{ids[0]}")[1])
            if job["state"] == "running" and job["progress"] >= 20:
                victim = job["worker"]["pid"]
            time.sleep(0.1)
        if victim is None:
            raise RuntimeError("no job reached 20 % within 600 s: nothing to kill")
        killed_at = time.monotonic()
        procs[victim].send_signal(signal.SIGKILL)
        procs[victim].wait(30)
        final = api_wait(server.base, ids, 1800)
        took = time.monotonic() - killed_at
        fates = [f"{final[job_id]['state']} (run {final[job_id]['worker']['run']})" if job_id in final else "lost"
                 for job_id in ids]
        matched = sum(api_result_matches(server.base, job_id, jobs[i][0], jobs[i][1])
                      for i, job_id in enumerate(ids) if final.get(job_id, {}).get("state") == "done")
        notes = final.get(ids[0], {}).get("notes", [])
        print(f"queue kill: worker pid {victim} killed while running job 0 at >= 20 %; fates: {fates}; "
              f"results matching their input {matched}; all ended {took:.1f} s after the kill; "
              f"job 0 notes: {notes}")
    finally:
        for proc in procs.values():
            if proc.poll() is None:
                proc.send_signal(signal.SIGTERM)
                proc.wait(60)
        server.stop()


def queue_run(work: Path, sentences: list) -> None:
    redis = Redis(work / "redis")
    try:
        walls: dict[int, list[float]] = {1: [], 2: []}
        for db, workers in enumerate((2, 1) * QUEUE_ROUNDS, start=1):  # alternated: the shared machine's load drifts
            walls[workers].append(queue_round(work, redis, sentences, workers, db))
        one, two = float(np.median(walls[1])), float(np.median(walls[2]))
        print(f"queue: median wall 1 worker {one:.1f} s, 2 workers {two:.1f} s: throughput 2 workers / 1 worker "
              f"= {one / two:.2f} (load average now {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)")
        kill_round(work, redis, sentences, 2 * QUEUE_ROUNDS + 1)
    finally:
        redis.stop()


def main() -> None:
    sentences = biaobei_sentences()
    with tempfile.TemporaryDirectory(prefix="cartoonface-bench-web-") as tmp:
        work = Path(tmp)
        fuzz_run(work, sentences)
        queue_run(work, sentences)
        restart_run(work, sentences)
        load_run(work, sentences)


if __name__ == "__main__":
    main()
