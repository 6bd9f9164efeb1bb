"""Atomic output: complete or absent, with ordinary permissions."""

from __future__ import annotations

import os
import random
import stat

import pytest

from cartoonface.files import atomic_directory, folder_size, write_bytes_atomic, write_text_atomic


def test_write_replaces_whole_file_and_leaves_no_temp(tmp_path):
    target = tmp_path / "sub" / "a.txt"
    write_text_atomic(target, "first")
    write_text_atomic(target, "second")
    assert target.read_text() == "second"
    assert sorted(p.name for p in target.parent.iterdir()) == ["a.txt"]


def test_written_file_is_readable_by_others_like_a_plain_open(tmp_path):
    mask = os.umask(0o022)
    try:
        path = write_bytes_atomic(tmp_path / "b.bin", b"x")
    finally:
        os.umask(mask)
    assert stat.S_IMODE(path.stat().st_mode) == 0o644


def test_failed_directory_leaves_nothing_and_keeps_the_old_one(tmp_path):
    out = tmp_path / "out"
    with atomic_directory(out) as tmp:
        (tmp / "index.html").write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_directory(out) as tmp:
            (tmp / "index.html").write_text("half")
            raise RuntimeError("boom")
    assert (out / "index.html").read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_directory_gets_ordinary_permissions(tmp_path):
    mask = os.umask(0o022)
    try:
        with atomic_directory(tmp_path / "o") as tmp:
            (tmp / "f").write_text("x")
    finally:
        os.umask(mask)
    assert stat.S_IMODE((tmp_path / "o").stat().st_mode) == 0o755


def test_folder_size_counts_every_file_below_once(tmp_path):
    rng = random.Random(7)
    sizes = [rng.randrange(0, 5000) for _ in range(6)]
    for i, size in enumerate(sizes):
        path = tmp_path / "site" / ("deep/er" if i % 2 else "") / f"f{i}.bin"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(bytes(size))
    big = tmp_path / "outside.bin"
    big.write_bytes(bytes(100_000))
    link = tmp_path / "site" / "link"
    link.symlink_to(big)
    assert folder_size(tmp_path / "site") == sum(sizes) + link.lstat().st_size
