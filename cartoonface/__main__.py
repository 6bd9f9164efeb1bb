"""`python -m cartoonface` is the same as the `cartoonface` command."""

from cartoonface.cli import main

raise SystemExit(main())
