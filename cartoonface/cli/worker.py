"""`cartoonface worker`: take jobs from the web app's queue and run them (docs/web.md, "Workers")."""

from __future__ import annotations

import argparse
import os
import signal
import socket
import sys
import threading
from pathlib import Path

from cartoonface.cli.serve import UMASK, stop

HELP = "run the web app's jobs from its queue (on this or another machine)"
DESCRIPTION = """\
Take the web app's jobs from its queue and run them, each in its own process held to
JOB_MEMORY_MB and JOB_CPU_SECONDS. Give it the same settings as the server: the queue
CARTOONFACE_QUEUE=redis://HOST:PORT/DB (unset: the SQLite queue in the instance folder,
this machine only) and the server's instance folder (--instance or CARTOONFACE_INSTANCE_PATH;
on another machine a shared mount of it, e.g. NFS: the path may differ, the files must be
the same). Start as many workers on as many machines as you like; the server can run none
itself (CARTOONFACE_WORKERS=0). A worker renews a lease on the job it runs every
LEASE_SECONDS/5: a job whose worker died (no renewal for LEASE_SECONDS) is run again by
another worker, once; a second loss marks it interrupted. Ctrl-C or SIGTERM stops the
worker and hands its running jobs back to the queue."""


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `worker` subcommand."""
    parser = subparsers.add_parser("worker", help=HELP, description=DESCRIPTION,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--instance", type=Path, default=None,
                        help="the server's instance folder (default: $CARTOONFACE_INSTANCE_PATH or instance/ "
                             "beside the package)")
    parser.add_argument("--jobs", type=int, default=None, metavar="N",
                        help="jobs run at the same time (default: the WORKERS setting, else the number of cores)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run jobs until interrupted; running jobs go back to the queue on the way out. OptionError
    for a bad setting or a queue it cannot reach."""
    from cartoonface.errors import OptionError
    from cartoonface.web import configured_app
    from cartoonface.web.runner import Runner, shown_url
    from cartoonface.web.worker import JobLimits

    os.umask(UMASK)
    _app, settings = configured_app({"INSTANCE_PATH": str(args.instance)} if args.instance else None)
    jobs = args.jobs if args.jobs is not None else (settings.workers or os.cpu_count() or 1)
    if jobs < 1:
        raise OptionError(f"--jobs {jobs}: expected at least 1")
    runner = Runner(settings.instance, jobs, limits=JobLimits(settings.job_memory_bytes, settings.job_cpu_seconds),
                    queue=settings.queue, lease_seconds=settings.lease_seconds, requeue_on_close=True)
    print(f"cartoonface worker: host {socket.gethostname()} pid {os.getpid()}, {jobs} job(s) at a time, "
          f"queue {shown_url(settings.queue)}, instance {settings.instance}", file=sys.stderr, flush=True)
    signal.signal(signal.SIGTERM, stop)
    try:
        threading.Event().wait()
    except KeyboardInterrupt:
        print("cartoonface worker: stopping; running jobs go back to the queue", file=sys.stderr, flush=True)
    finally:
        runner.close()
    return 0
