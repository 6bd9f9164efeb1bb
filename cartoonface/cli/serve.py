"""`cartoonface serve`: run the web app under waitress (a production WSGI server, no debug mode)."""

from __future__ import annotations

import argparse
import os
import signal
import sys
from pathlib import Path

from cartoonface.errors import OptionError

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 5000
THREADS = 8  # waitress request threads; jobs run in the app's own worker pool
# Host headers accepted when listening on IPv4 loopback (unless TRUSTED_HOSTS is set): a web
# page that rebinds its own domain name to 127.0.0.1 then cannot drive the app.
LOOPBACK_HOSTS = ("127.0.0.1", "localhost")
HELP = "run the web app (upload, progress, results)"
# Everything the server writes (jobs, their results, photo drafts) is readable by its user only.
UMASK = 0o077


def port_number(text: str) -> int:
    """argparse type: a TCP port 1..65535."""
    try:
        port = int(text)
    except ValueError:
        port = 0
    if not 1 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"{text!r}: expected a port number from 1 to 65535")
    return port


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `serve` subcommand."""
    parser = subparsers.add_parser(
        "serve", help=HELP,
        description="Run the cartoonface web app with waitress. Settings: docs/web.md "
                    "(CARTOONFACE_* environment variables or <instance>/config.py).")
    parser.add_argument("--host", default=DEFAULT_HOST, help=f"address to listen on (default {DEFAULT_HOST})")
    parser.add_argument("--port", type=port_number, default=DEFAULT_PORT, help=f"port (default {DEFAULT_PORT})")
    parser.add_argument("--instance", type=Path, default=None,
                        help="instance folder holding jobs and settings (default: $CARTOONFACE_INSTANCE_PATH "
                             "or instance/ beside the package)")
    parser.set_defaults(func=run)


def stop(signum: int, frame: object) -> None:
    """SIGTERM handler: leave the server loop the way Ctrl-C does."""
    raise KeyboardInterrupt


def run(args: argparse.Namespace) -> int:
    """Build the app and serve it until interrupted; the worker pool is closed on the way out.
    OptionError when the address cannot be listened on (in use, unknown host)."""
    import waitress

    from cartoonface.web import create_app

    os.umask(UMASK)
    app = create_app({"INSTANCE_PATH": str(args.instance)} if args.instance else None)
    if args.host in LOOPBACK_HOSTS and app.config.get("TRUSTED_HOSTS") is None:
        app.config["TRUSTED_HOSTS"] = list(LOOPBACK_HOSTS)
    runner = app.extensions["cartoonface"].runner
    # A connection that sends nothing for CHANNEL_TIMEOUT seconds (a body announced and not sent)
    # is closed; waitress checks idle connections this often (seconds).
    timeout = app.extensions["cartoonface"].settings.channel_timeout
    try:
        server = waitress.create_server(app, host=args.host, port=args.port, threads=THREADS, ident="cartoonface",
                                        channel_timeout=timeout, cleanup_interval=max(1, timeout // 2))
    except (OSError, ValueError) as exc:  # in use, not ours; waitress says ValueError for an unknown host
        runner.close()
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise OptionError(f"--host {args.host} --port {args.port}: cannot listen there ({reason})") from None
    print(f"cartoonface: serving on http://{args.host}:{args.port}/ (instance {app.instance_path})",
          file=sys.stderr, flush=True)
    signal.signal(signal.SIGTERM, stop)
    try:
        server.run()
    finally:
        runner.close()
    return 0
