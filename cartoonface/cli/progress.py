"""Progress on stderr for long commands."""

from __future__ import annotations

from typing import TextIO

BAR_WIDTH = 24  # characters


class ProgressBar:
    """A progress(stage, fraction) callback for `stream`.

    On a terminal it draws one self-overwriting bar line; elsewhere (a log file, a
    pipe) it writes one line when a stage starts and one when the work is done, so
    logs stay readable.
    """

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream
        self.terminal = stream.isatty()
        self.open = False  # a bar line is drawn and not yet ended
        self.stage = ""  # the last stage written (logs only)

    def __call__(self, stage: str, fraction: float) -> None:
        if self.terminal:
            filled = round(fraction * BAR_WIDTH)
            self.stream.write(f"\r[{'#' * filled}{'.' * (BAR_WIDTH - filled)}] {fraction:4.0%} {stage:<8}")
            self.open = True
            if fraction >= 1:
                self.close()
        elif stage != self.stage or fraction >= 1:
            self.stream.write(f"{fraction:4.0%} {stage}\n")
            self.stage = stage
        self.stream.flush()

    def close(self) -> None:
        """End the bar's line (before notes, an error message or the summary)."""
        if self.open:
            self.stream.write("\n")
            self.open = False
