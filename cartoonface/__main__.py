"""`python -m cartoonface` is the same as the `cartoonface` command."""

from cartoonface.cli import command

raise SystemExit(command())
