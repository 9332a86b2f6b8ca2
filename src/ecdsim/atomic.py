"""Atomic file output: a failed or interrupted run never corrupts an earlier result."""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO


@contextlib.contextmanager
def atomic_path(target: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; on success it replaces ``target`` atomically.

    The temporary file lives in the same folder so that :func:`os.replace` is an atomic
    rename on POSIX and Windows. On any exception the temporary file is removed and the
    earlier ``target`` is left untouched.
    """
    final = Path(target)
    final.parent.mkdir(parents=True, exist_ok=True)
    handle, name = tempfile.mkstemp(prefix=f".{final.name}.", suffix=".tmp", dir=final.parent)
    temporary = Path(name)
    try:
        os.close(handle)
        # mkstemp creates the file private (0600); give it the mode a plain open() would,
        # so that the result is as readable as any other file the user writes. Inside the
        # try, so that an interrupt here still removes the temporary file.
        umask = os.umask(0)
        os.umask(umask)
        temporary.chmod(0o666 & ~umask)
        yield temporary
        os.replace(temporary, final)
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
