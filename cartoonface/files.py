"""Atomic file output: nothing already produced is lost or half-written.

Write to a temporary file beside the target, then rename over it. For a whole
output folder, build it under a temporary name and rename it into place.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from cartoonface.errors import InputError


TRASH_PREFIX = ".deleted-"  # a folder being removed is renamed to this prefix + its name first


def remove_folder(folder: Path) -> None:
    """Remove `folder` (a job or a draft): renamed to TRASH_PREFIX + its name first, so readers
    never see half of it and a sweep can finish a removal that was cut short. A folder that is
    already gone is no error."""
    trash = folder.with_name(f"{TRASH_PREFIX}{folder.name}")
    try:
        os.replace(folder, trash)
    except FileNotFoundError:
        return
    shutil.rmtree(trash, ignore_errors=True)


def _umask() -> int:
    """Return the process umask without changing it for longer than a moment."""
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_bytes_atomic(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write `data` to `path` through a temporary file and a rename; return the path."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
        # mkstemp makes the file private (0600); give it the mode a plain open() would.
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
    return target


def write_text_atomic(path: str | os.PathLike[str], text: str) -> Path:
    """Write UTF-8 `text` to `path` atomically; return the path."""
    return write_bytes_atomic(path, text.encode("utf-8"))


@contextlib.contextmanager
def atomic_directory(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary folder that replaces `path` only if the block succeeds.

    On an exception the temporary folder is removed and `path` is untouched,
    so no partial output folder is ever left behind.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent))
    # mkdtemp makes the folder private (0700); give it the mode a plain mkdir() would.
    os.chmod(tmp, 0o777 & ~_umask())
    try:
        yield tmp
        if target.exists():
            old = target.with_name(f".{target.name}.old")
            shutil.rmtree(old, ignore_errors=True)
            os.replace(target, old)
            os.replace(tmp, target)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, target)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def read_user_text(path: str | os.PathLike[str], error: type[InputError], what: str) -> str:
    """Return the UTF-8 text (a BOM allowed) of the user's file at `path`.

    Any failure raises `error` with a message naming the file and `what` it should be
    (e.g. "transcript file"), so the user knows which input to fix.
    """
    try:
        return Path(path).read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise error(f"{path}: no such {what}") from None
    except IsADirectoryError:
        raise error(f"{path}: is a folder; expected a {what}") from None
    except UnicodeDecodeError:
        raise error(f"{path}: not UTF-8 text; expected a {what} saved as UTF-8") from None
    except OSError as exc:
        raise error(f"{path}: cannot read the {what} ({exc.strerror})") from None


def folder_size(folder: str | os.PathLike[str]) -> int:
    """Total bytes of the files under `folder` (symbolic links counted as themselves, not
    followed); files removed while it counts are left out."""
    total = 0
    for base, _dirs, names in os.walk(folder):
        for name in names:
            try:
                total += os.lstat(os.path.join(base, name)).st_size
            except FileNotFoundError:
                continue
    return total
