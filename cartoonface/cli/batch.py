"""`cartoonface batch MANIFEST.csv -o OUTDIR`: one book per row of a CSV manifest, each
written to OUTDIR/<name>/ as `cartoonface generate` writes it.

Every row is checked before anything runs (a bad row: one line naming the row and the
column, exit 2). Then the rows run here one after the other, or, when CARTOONFACE_QUEUE
is set, through the web app's queue (its instance folder, --instance, shared with the
workers). A row whose OUTDIR/<name>/index.html exists is done and skipped, so a batch
that was stopped is finished by running it again; with the queue, the ids of jobs sent
are kept in OUTDIR/batch-jobs.json and a rerun waits for them instead of sending them again.
"""

from __future__ import annotations

import argparse
import csv
import json
import re
import shutil
import sys
import textwrap
import time
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from cartoonface.cli.progress import ProgressBar
from cartoonface.errors import InputError, OptionError

if TYPE_CHECKING:
    from cartoonface.pipeline import Options

HELP = "make the pages of many books listed in a CSV manifest (locally or through the job queue)"
REQUIRED = ("face", "audio", "transcript")
OPTIONAL = ("name", "title", "page", "style", "background", "clothes", "fps", "seed")
NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,99}")
JOBS_FILE = "batch-jobs.json"  # row name -> job id, when the rows run through the queue
POLL = 0.5  # seconds between looks at the queued jobs' status
DESCRIPTION_WIDTH = 79  # characters per line of --help


@dataclass(frozen=True)
class Row:
    """One checked manifest row: its `number` (the header is row 1), output `name`, the face
    model file, recording and transcript paths, and the generate options."""

    number: int
    name: str
    face: Path
    audio: Path
    transcript: Path
    options: Options


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `batch` subcommand."""
    paragraphs = (
        "Make one page folder per row of MANIFEST.csv in OUTDIR/<name>/.",
        f"Columns (a header row names them): {', '.join(REQUIRED)} (required: a face model JSON file or a "
        "sample face name, the recording, the transcript as a UTF-8 text file; paths relative to the "
        f"manifest's folder), and optionally {', '.join(OPTIONAL)} (name: the output folder, default the "
        "recording's file name without extension; the rest as for `generate`). A bad row is reported "
        "with its row and column before anything runs (exit 2).",
        "Rows already done (OUTDIR/<name>/index.html exists) are skipped: run the same command again to "
        "finish a stopped batch. With CARTOONFACE_QUEUE=redis://... set (or --instance), the rows run as "
        "jobs of the web app's queue (instance folder: --instance or CARTOONFACE_INSTANCE_PATH), taken by "
        "its server or `cartoonface worker`s; otherwise one after the other here. Exit 1 when a row failed.",
    )
    parser = subparsers.add_parser(
        "batch", help=HELP, formatter_class=argparse.RawDescriptionHelpFormatter,
        description="\n\n".join(textwrap.fill(paragraph, DESCRIPTION_WIDTH) for paragraph in paragraphs))
    parser.add_argument("manifest", type=Path, metavar="MANIFEST.csv")
    parser.add_argument("-o", "--output", type=Path, required=True, metavar="OUTDIR", help="folder of the results")
    parser.add_argument("--instance", type=Path, default=None,
                        help="the web app's instance folder, for the queue (default: $CARTOONFACE_INSTANCE_PATH)")
    parser.set_defaults(func=run)


def _where(manifest: Path, number: int, column: str) -> str:
    return f"{manifest} row {number}, column {column}"


def check_row(manifest: Path, number: int, cells: dict[str, str], samples: dict[str, Path]) -> Row:
    """Row `number` of `manifest` (cells by column) checked: files exist, the face model and the
    options are valid. InputError naming the row and the column otherwise."""
    from cartoonface.face.model import load_face
    from cartoonface.pipeline import Options, check_options

    base = manifest.parent
    paths: dict[str, Path] = {}
    for column in REQUIRED:
        value = cells.get(column, "").strip()
        if not value:
            raise InputError(f"{_where(manifest, number, column)}: empty; expected a file"
                             + (" or a sample face name" if column == "face" else ""))
        path = samples[value] if column == "face" and value in samples else base / value
        if not path.is_file():
            raise InputError(f"{_where(manifest, number, column)}: {value!r} is not a file"
                             + (f" nor a sample face ({', '.join(samples)})" if column == "face" else ""))
        paths[column] = path
    try:
        load_face(paths["face"])
    except InputError as exc:
        raise InputError(f"{_where(manifest, number, 'face')}: {exc}") from None
    options = Options()
    for column in ("title", "page", "style", "background", "clothes", "fps", "seed"):
        value = cells.get(column, "").strip()
        if not value:
            continue
        kind = {field.name: field.type for field in fields(Options)}[column]
        try:
            typed: Any = int(value) if kind in ("int", int) else value
        except ValueError:
            raise InputError(f"{_where(manifest, number, column)}: {value!r} is not a whole number") from None
        try:
            check_options(replace(Options(), **{column: typed}))
        except OptionError as exc:
            raise InputError(f"{_where(manifest, number, column)}: {exc}") from None
        options = replace(options, **{column: typed})
    name = cells.get("name", "").strip() or paths["audio"].stem
    if not NAME.fullmatch(name):
        raise InputError(f"{_where(manifest, number, 'name')}: {name!r}: expected up to 100 letters, digits, "
                         "'_', '-' or '.' (a folder name), starting with a letter or digit")
    return Row(number, name, paths["face"], paths["audio"], paths["transcript"], options)


def read_manifest(manifest: Path, samples: dict[str, Path]) -> list[Row]:
    """Every row of `manifest` checked (check_row); InputError for a missing or unreadable
    file, an unknown or missing column, or two rows with the same output name."""
    try:
        text = manifest.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{manifest}: cannot read the manifest ({exc})") from None
    reader = csv.DictReader(text.splitlines())
    header = [column.strip() for column in reader.fieldnames or []]
    unknown = [column for column in header if column not in REQUIRED + OPTIONAL]
    if unknown:
        raise InputError(f"{manifest} row 1: unknown column {unknown[0]!r}; expected {', '.join(REQUIRED + OPTIONAL)}")
    missing = [column for column in REQUIRED if column not in header]
    if missing:
        raise InputError(f"{manifest} row 1: no column {missing[0]!r} (the header must name "
                         f"{', '.join(REQUIRED)})")
    rows: list[Row] = []
    seen: dict[str, int] = {}
    for number, record in enumerate(reader, start=2):
        if None in record:
            raise InputError(f"{manifest} row {number}: more cells than the header has columns")
        cells = {key.strip(): (value or "") for key, value in record.items()}
        if not any(value.strip() for value in cells.values()):
            continue
        row = check_row(manifest, number, cells, samples)
        if row.name in seen:
            raise InputError(f"{_where(manifest, number, 'name')}: {row.name!r} is also the output of row "
                             f"{seen[row.name]}; give each row its own name")
        seen[row.name] = number
        rows.append(row)
    if not rows:
        raise InputError(f"{manifest}: no rows under the header")
    return rows


def done(out: Path, row: Row) -> bool:
    """True when the row's folder is complete (generate writes it atomically)."""
    return (out / row.name / "index.html").is_file()


def run_here(rows: list[Row], out: Path, bar: ProgressBar) -> list[str]:
    """Generate each row into `out`/<name>, one after the other; return the failures' messages."""
    from cartoonface.pipeline import generate

    failures = []
    for index, row in enumerate(rows):
        def progress(stage: str, fraction: float, index: int = index, row: Row = row) -> None:
            bar(f"{index + 1}/{len(rows)} {row.name}: {stage}", (index + min(fraction, 1.0)) / len(rows))

        try:
            generate(row.face, row.audio, row.transcript, out / row.name, row.options, progress)
        except InputError as exc:
            failures.append(f"row {row.number} ({row.name}): {exc}")
    return failures


def job_spec(row: Row) -> tuple[dict[str, object], dict[str, bytes]]:
    """The web job of a row: (job.json values, files by our names)."""
    from cartoonface.web.inputs import sniff_audio

    audio = row.audio.read_bytes()
    ext = sniff_audio(audio[:16])
    if ext is None:
        raise InputError(f"row {row.number}, column audio: {row.audio} is not WAV, MP3, OGG, M4A or FLAC")
    spec = {"title": row.options.title, "page": row.options.page, "style": row.options.style or "",
            "background": row.options.background, "clothes": row.options.clothes, "fps": row.options.fps,
            "seed": row.options.seed, "face_label": row.face.name, "face_notes": [], "audio_label": row.audio.name,
            "audio_file": f"audio.{ext}", "transcript_chars": 0, "batch": row.name}
    return spec, {"face.json": row.face.read_bytes(), f"audio.{ext}": audio, "transcript.txt": row.transcript.read_bytes()}


def run_queued(rows: list[Row], out: Path, instance: Path | None, bar: ProgressBar) -> list[str]:
    """Send the rows as jobs to the web app's queue, wait for them and copy each result to
    `out`/<name>; return the failures' messages. Ids are kept in `out`/batch-jobs.json."""
    from cartoonface.files import write_text_atomic
    from cartoonface.web import configured_app
    from cartoonface.web.runner import Runner, shown_url
    from cartoonface.web.store import DONE, FAILED, create_job, job_folder, load_job
    from cartoonface.web.worker import SITE

    _app, settings = configured_app({"INSTANCE_PATH": str(instance)} if instance else None)
    runner = Runner(settings.instance, 0, queue=settings.queue, queue_max=settings.queue_max,
                    lease_seconds=settings.lease_seconds)
    record = out / JOBS_FILE
    sent: dict[str, str] = json.loads(record.read_text(encoding="utf-8")) if record.is_file() else {}
    failures: list[str] = []
    try:
        pending = {row.name: row for row in rows}
        for row in rows:
            if row.name in sent and load_job(settings.instance, sent[row.name]) is not None:
                continue
            while not runner.has_room():
                bar(f"waiting for room in the queue ({len(sent)} sent)", 0.0)
                time.sleep(POLL)
            spec, files = job_spec(row)
            sent[row.name] = create_job(settings.instance, spec, files).id
            runner.submit(job_folder(settings.instance, sent[row.name]))
            write_text_atomic(record, json.dumps(sent, indent=1))
        print(f"cartoonface batch: {len(sent)} jobs in the queue {shown_url(settings.queue)} of "
              f"{settings.instance}; waiting for its server or workers", file=sys.stderr, flush=True)
        while pending:
            fractions = []
            for name, row in list(pending.items()):
                job = load_job(settings.instance, sent[name])
                if job is None:
                    failures.append(f"row {row.number} ({name}): the job {sent[name]} is gone from the instance")
                elif job.status.state == DONE and (out / name).exists():
                    failures.append(f"row {row.number} ({name}): {out / name} exists and is not a finished "
                                    "output; remove it and run the batch again")
                elif job.status.state == DONE:
                    staging = out / f".{name}.copy"
                    shutil.rmtree(staging, ignore_errors=True)
                    shutil.copytree(job.folder / SITE, staging)
                    staging.replace(out / name)
                elif job.status.state == FAILED:
                    failures.append(f"row {row.number} ({name}): {job.status.error}")
                else:
                    fractions.append(job.status.fraction)
                    continue
                del pending[name]
            finished = len(rows) - len(pending)
            bar(f"{finished}/{len(rows)} done", (finished + sum(fractions)) / len(rows))
            if pending:
                time.sleep(POLL)
    finally:
        runner.close()
    return failures


def run(args: argparse.Namespace) -> int:
    """Check the manifest, run the rows not done yet; 0 when all are done, 1 when some failed."""
    import os

    from cartoonface.data import SAMPLE_FACES
    from cartoonface.web.config import sample_faces

    samples = sample_faces(Path(SAMPLE_FACES))
    rows = read_manifest(args.manifest, samples)
    args.output.mkdir(parents=True, exist_ok=True)
    todo = [row for row in rows if not done(args.output, row)]
    print(f"cartoonface batch: {len(rows)} rows, {len(rows) - len(todo)} done already, {len(todo)} to make",
          file=sys.stderr, flush=True)
    bar = ProgressBar(sys.stderr)
    try:
        queued = bool(os.environ.get("CARTOONFACE_QUEUE")) or args.instance is not None
        failures = run_queued(todo, args.output, args.instance, bar) if todo and queued else \
            run_here(todo, args.output, bar) if todo else []
    finally:
        bar.close()
    for failure in failures:
        print(f"cartoonface batch: failed: {failure}", file=sys.stderr)
    print(f"cartoonface batch: {len(rows) - len(failures)} of {len(rows)} rows done in {args.output}")
    return 1 if failures else 0
