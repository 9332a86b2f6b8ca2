"""Atomic file output: a failed or interrupted run never corrupts an earlier result."""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO


def stage(target: str | Path) -> Path:
    """A new, empty temporary file beside ``target`` (``.NAME.*.tmp``), to be written and
    then installed by :func:`install` (or removed by the caller on failure).

    The temporary file lives in the same folder so that :func:`os.replace` is an atomic
    rename on POSIX and Windows. mkstemp creates it private (0600); it gets the mode a
    plain open() would give, so that the result is as readable as any other file the
    user writes. On an exception here (an interrupt) nothing is left behind.
    """
    final = Path(target)
    final.parent.mkdir(parents=True, exist_ok=True)
    handle, name = tempfile.mkstemp(prefix=f".{final.name}.", suffix=".tmp", dir=final.parent)
    temporary = Path(name)
    try:
        os.close(handle)
        umask = os.umask(0)
        os.umask(umask)
        temporary.chmod(0o666 & ~umask)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise
    return temporary


def install(temporary: Path, target: str | Path) -> Path:
    """Sync a file written by way of :func:`stage` and rename it to ``target``: it appears
    whole or not at all. The temporary file is removed on failure."""
    try:
        with open(temporary, "rb+") as stream:
            os.fsync(stream.fileno())
        os.replace(temporary, target)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
    return Path(target)


@contextlib.contextmanager
def atomic_path(target: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; on success it replaces ``target`` atomically.

    On any exception the temporary file is removed and the earlier ``target`` is left
    untouched (:func:`stage`).
    """
    temporary = stage(target)
    try:
        yield temporary
        os.replace(temporary, target)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


def write_text(target: str | Path, text: str) -> Path:
    """Write text atomically (UTF-8) and return the final path."""
    return write_with(target, lambda stream: stream.write(text.encode("utf-8")))


def write_with(target: str | Path, writer: Callable[[IO[bytes]], object]) -> Path:
    """Call ``writer`` with a binary stream and install the result atomically."""
    with atomic_path(target) as temporary, temporary.open("wb") as stream:
        writer(stream)
        stream.flush()
        os.fsync(stream.fileno())
    return Path(target)
