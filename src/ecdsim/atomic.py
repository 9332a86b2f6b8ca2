"""Atomic file output: a failed or interrupted run never corrupts an earlier result.

What a write does depends on what the target is (issue 23, item 5):

* nothing yet, or a regular file: the result is written to a temporary file beside it and
  renamed over it only on success (:func:`stage`, :func:`install`), so that it appears
  whole or not at all;
* a symbolic link: the same, at the file the link points to (followed to its end); the
  link stays a link;
* a FIFO or a character device (``-o /dev/stdout``, a named pipe): written directly, as a
  shell's ``>`` would, since there is no earlier result to keep and renaming over it
  would replace the device by a file; an error (``/dev/full``: "No space left on
  device") raises OSError like any failed write;
* a folder, a block device or a socket: OSError naming what it is, before anything is
  written (a block device is a disk: ecdsim never writes over one).

A missing folder on the way is created, and every listener registered with
:func:`on_folder_created` hears of it (the command line prints a note), so that a typing
error in a folder name does not pass unnoticed.
"""

from __future__ import annotations

import contextlib
import errno
import os
import stat
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO

_folder_listeners: list[Callable[[Path], None]] = []


def on_folder_created(listener: Callable[[Path], None]) -> None:
    """Call ``listener(folder)`` whenever a write creates a missing folder (once each).

    The library itself says nothing; the command line registers a listener that prints
    ``note: created the folder ... (it did not exist)``.
    """
    if listener not in _folder_listeners:
        _folder_listeners.append(listener)


def make_folder(folder: str | Path, *, announce: bool = True) -> list[Path]:
    """Create ``folder`` and any missing folder above it; the folders created, outermost
    first (empty if it existed). Listeners (:func:`on_folder_created`) hear of ``folder``
    when anything was created, unless ``announce`` is False (a folder the caller says
    itself, or a working folder of its own)."""
    path = Path(folder)
    missing: list[Path] = []
    probe = path
    while not probe.exists() and probe != probe.parent:
        missing.append(probe)
        probe = probe.parent
    if not missing:
        if not path.is_dir():
            raise NotADirectoryError(errno.ENOTDIR, "is a file, not a folder", str(path))
        return []
    path.mkdir(parents=True, exist_ok=True)
    for listener in list(_folder_listeners) if announce else []:
        listener(path)
    return missing[::-1]


class NotWritable(OSError):
    """A target ecdsim will not write: a folder, a block device or a socket."""


def _what(mode: int) -> str | None:
    """What a non-regular file is, in words, or None for a regular file."""
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        return "folder"
    if stat.S_ISFIFO(mode):
        return "FIFO"
    if stat.S_ISCHR(mode):
        return "character device"
    if stat.S_ISBLK(mode):
        return "block device"
    if stat.S_ISSOCK(mode):
        return "socket"
    return "special file"


STREAMS = ("FIFO", "character device")
"""Non-regular targets written directly (no temporary file, nothing to keep); so is a
link to an open file descriptor, ``"open file"`` (:func:`destination`)."""


def destination(target: str | Path) -> tuple[Path, str | None]:
    """Where a write to ``target`` goes, and what is there: ``(path, None)`` for a regular
    file or nothing (``path`` is a symbolic link's final target), ``(path, "FIFO")``,
    ``(path, "character device")`` or ``(path, "open file")`` for a target written
    directly.

    A link to one of the process's open files (``/dev/stdout`` is ``/proc/self/fd/1``)
    is written directly too, whatever it is: renaming over the file the descriptor names
    would leave the descriptor's holder (the shell's ``>``) with the old one.

    Raises :class:`NotWritable` for a folder, a block device or a socket.
    """
    try:
        mode = os.stat(target).st_mode  # through links
    except FileNotFoundError:  # nothing there, or a dangling link: written at its end
        return Path(os.path.realpath(target)), None
    what = _what(mode)
    if what in STREAMS or (what is None and _through_descriptor(Path(target))):
        return Path(target), what or "open file"
    if what is None:
        return Path(os.path.realpath(target)), None  # a link, followed to its end
    article = "an" if what[0] in "aeiou" else "a"
    raise NotWritable(
        errno.EISDIR if what == "folder" else errno.EINVAL,
        f"it is {article} {what}, not a file; ecdsim writes files, FIFOs and character devices",
        str(target),
    )


def _through_descriptor(path: Path) -> bool:
    """True if following ``path``'s links passes through ``/proc/<pid>/fd/``."""
    return _descriptor_link(path) is not None


def _descriptor_link(path: Path) -> Path | None:
    """The ``/proc/<pid>/fd/N`` link that following ``path``'s links passes through, if any."""
    probe = Path(os.path.abspath(path))
    for _ in range(40):  # the kernel's own limit on links followed
        if len(probe.parts) == 5 and probe.parts[:2] == ("/", "proc") and probe.parts[3] == "fd":
            return probe
        if not probe.is_symlink():
            return None
        probe = Path(os.path.abspath(probe.parent / os.readlink(probe)))
    return None


def _own_descriptor(path: Path) -> int | None:
    """N where ``path`` leads to this process's open descriptor N (``/dev/stdout``: 1)."""
    link = _descriptor_link(path)
    if link is None or link.parts[2] not in {"self", str(os.getpid())}:
        return None
    return int(link.parts[4]) if link.parts[4].isdigit() else None


@contextlib.contextmanager
def _direct(path: Path) -> Iterator[IO[bytes]]:
    """A stream writing straight into ``path`` (a FIFO, a device, an open file).

    One of this process's own descriptors (``-o /dev/stdout``) is written through a
    duplicate of it, at its current position and after what Python has buffered for it:
    opened anew, a file it is redirected to would be truncated and written from its start,
    under what this process prints afterwards.
    """
    import sys

    number = _own_descriptor(path)
    if number is None:
        with open(path, "wb") as stream:
            yield stream
        return
    for shown in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):  # replaced or closed streams: nothing to flush
            shown.flush()
    with os.fdopen(os.dup(number), "wb") as stream:
        yield stream


def stage(target: str | Path) -> Path:
    """A new, empty temporary file beside ``target`` (``.NAME.*.tmp``; beside the file a
    symbolic link points to), to be written and then installed by :func:`install` (or
    removed by the caller on failure). Missing folders are created (:func:`make_folder`).

    The temporary file lives in the same folder so that :func:`os.replace` is an atomic
    rename on POSIX and Windows. mkstemp creates it private (0600); it gets the mode a
    plain open() would give, so that the result is as readable as any other file the
    user writes. On an exception here (an interrupt) nothing is left behind.

    Raises :class:`NotWritable` where the target is not a regular file (nor missing):
    a FIFO or a device cannot be renamed over (:func:`write_with` writes those directly).
    """
    import tempfile

    final, what = destination(target)
    if what is not None:
        raise NotWritable(
            errno.EINVAL, f"it is a {what}; ecdsim writes this output only to a file", str(target)
        )
    make_folder(final.parent)
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
    """Sync a file written by way of :func:`stage` and rename it to ``target`` (to the file
    a symbolic link points to, the link kept): it appears whole or not at all. The
    temporary file is removed on failure."""
    try:
        with open(temporary, "rb+") as stream:
            os.fsync(stream.fileno())
        os.replace(temporary, destination(target)[0])
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
    return Path(target)


@contextlib.contextmanager
def atomic_path(target: str | Path) -> Iterator[Path]:
    """Yield a temporary path to write; on success it replaces ``target`` atomically.

    On any exception the temporary file is removed and the earlier ``target`` is left
    untouched (:func:`stage`). For a FIFO or a character device the temporary file is
    in the system's temporary folder and its bytes are copied into the target.
    """
    final, what = destination(target)
    if what is not None:
        import shutil
        import tempfile

        with tempfile.TemporaryDirectory(prefix="ecdsim-") as folder:
            temporary = Path(folder) / final.name
            yield temporary
            with open(temporary, "rb") as source, _direct(final) as sink:
                shutil.copyfileobj(source, sink)
        return
    temporary = stage(final)
    try:
        yield temporary
        os.replace(temporary, final)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


def write_text(target: str | Path, text: str) -> Path:
    """Write text atomically (UTF-8) and return the final path."""
    return write_with(target, lambda stream: stream.write(text.encode("utf-8")))


def write_with(target: str | Path, writer: Callable[[IO[bytes]], object]) -> Path:
    """Call ``writer`` with a binary stream and install the result atomically (a FIFO or
    a character device is written directly; see the module docstring)."""
    final, what = destination(target)
    if what is not None:
        with _direct(final) as stream:
            writer(stream)
            stream.flush()  # an error of the device (ENOSPC for /dev/full) is raised here
        return Path(target)
    with atomic_path(final) as temporary, temporary.open("wb") as stream:
        writer(stream)
        stream.flush()
        os.fsync(stream.fileno())
    return Path(target)
