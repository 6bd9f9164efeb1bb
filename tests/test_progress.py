"""Progress on stderr: a bar on a terminal, readable lines in a log."""

from __future__ import annotations

import io

from cartoonface.cli.progress import ProgressBar


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_log_gets_one_line_per_stage_and_one_when_done():
    log = io.StringIO()
    bar = ProgressBar(log)
    for stage, fraction in [("decode", 0.0), ("align", 0.2), ("align", 0.3), ("pages", 0.9), ("pages", 1.0)]:
        bar(stage, fraction)
    bar.close()
    lines = log.getvalue().splitlines()
    assert [line.split()[-1] for line in lines] == ["decode", "align", "pages", "pages"]
    assert "\r" not in log.getvalue() and lines[-1].startswith("100%")


def test_terminal_gets_one_overwritten_line_ended_once():
    screen = Terminal()
    bar = ProgressBar(screen)
    bar("decode", 0.0)
    bar("align", 0.5)
    bar.close()
    bar.close()
    text = screen.getvalue()
    assert text.count("\r") == 2 and text.count("\n") == 1 and text.endswith("\n")
