"""The explorer's computations in worker processes, killed at the time limit (issue 23, item 6).

A computation ran in a thread of the server: at the time limit the client got its 503,
but a thread cannot be stopped, so the work went on (measured: a compliant mesh at six
temperatures kept the server's CPU busy for 90 s more; 50 temperatures cost about 14
CPU-minutes a request). Here every computation runs in a worker process of a small pool
shared by the whole server process; at the deadline the worker is killed (SIGKILL, or
TerminateProcess on Windows) and a fresh one takes its place at the next request, so the
CPU is free the moment the client is told.

The workers are long-lived, so that a request does not pay for a process's start: each
imports ecdsim once and keeps NumPy's and numba's compiled code warm (a process started
per request cost 0.12 s more for the paper example and 0.7 s more with the dynamic
method, which loads its compiled kernels anew in each process). A worker is a fresh
interpreter (``python -c``, not ``multiprocessing``): nothing of the server is inherited
(forking a process that runs an event loop and thread pools can deadlock) and the
server's main script is not imported again (``multiprocessing``'s spawn does that, which
breaks a script that starts the explorer without an ``if __name__ == "__main__"`` guard).
Workers start lazily, when a request finds no idle one (the start, about a second of
imports, is not counted in the request's limit); at most :func:`pool_size` computations
run at once, and a request waits for a free worker within its own limit.

A job is a module-level function (pickled by reference) returning a :class:`Reply`; it
runs in the worker and gets only plain data (the request's fields), never the server's
objects. Parent and worker exchange pickled frames (an 8-byte length, then the bytes) over
the worker's stdin and stdout; the worker's own prints go to stderr.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import struct
import subprocess
import sys
import threading
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import IO, Any


@dataclass(frozen=True)
class Reply:
    """What a job answers: the HTTP response to send, or the traceback of a defect.

    Attributes
    ----------
    status : HTTP status code
    body : the response body
    media_type : its content type
    headers : further headers (``Content-Disposition``)
    defect : the traceback of an unexpected exception in the job, for the server's log
        (the body then says "internal error (Name); please report it")
    """

    status: int
    body: bytes
    media_type: str = "application/json"
    headers: dict[str, str] = field(default_factory=dict)
    defect: str | None = None


class Timeout(Exception):
    """The computation was stopped at its time limit (its worker killed)."""


class Busy(Exception):
    """No worker became free within the time limit."""


class WorkerDied(Exception):
    """The worker process ended while computing (killed from outside, out of memory)."""


def as_reply(compute: Callable[[], Any]) -> Reply:
    """Run ``compute`` (in a worker: it returns a Starlette ``Response`` or raises an
    ``HTTPException``, a refusal) and turn the outcome into a :class:`Reply`."""
    import json

    from starlette.exceptions import HTTPException

    try:
        response = compute()
    except HTTPException as exc:
        raw: Any = exc.detail
        detail = raw if isinstance(raw, list) else [str(raw)]
        return Reply(exc.status_code, json.dumps({"errors": detail}).encode())
    kept = {k: v for k, v in response.headers.items() if k.lower() == "content-disposition"}
    return Reply(
        response.status_code,
        bytes(response.body),
        response.media_type or "application/octet-stream",
        kept,
    )


def pool_size() -> int:
    """Computations at once: one per CPU, 2 to 4 (two, so that one slow request never
    queues every other; at most four processes of some 150 MB each)."""
    return max(2, min(4, os.cpu_count() or 1))


_LENGTH = struct.Struct("!Q")
# The longest a worker may take to start (import ecdsim and the server) [s].
START_LIMIT_S = 120.0


def _send(stream: IO[bytes], message: object) -> None:
    data = pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL)
    stream.write(_LENGTH.pack(len(data)) + data)
    stream.flush()


def _receive(stream: IO[bytes]) -> Any:
    """The next frame's object; EOFError when the other side is gone."""
    header = _read_exactly(stream, _LENGTH.size)
    return pickle.loads(_read_exactly(stream, _LENGTH.unpack(header)[0]))  # noqa: S301 - our own child


def _read_exactly(stream: IO[bytes], size: int) -> bytes:
    parts: list[bytes] = []
    while size:
        chunk = stream.read(size)
        if not chunk:
            raise EOFError
        parts.append(chunk)
        size -= len(chunk)
    return b"".join(parts)


def serve() -> None:
    """A worker's loop (run as ``python -c``): take ``(job, args)`` frames from stdin,
    answer ``job(*args)`` on stdout, until stdin closes. The first frame is the server's
    ``sys.path``, so that jobs import as they do there, and the modules to import before
    the first job (the server's own: what its jobs use)."""
    import importlib
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the server's, which ends us
    replies = os.fdopen(os.dup(sys.stdout.fileno()), "wb")
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())  # stray prints must not corrupt frames
    requests = sys.stdin.buffer
    try:
        sys.path[:], preload = _receive(requests)
        for name in preload:  # imported before any request's time limit runs
            importlib.import_module(name)
        _send(replies, "ready")
        while True:
            job, args = _receive(requests)
            try:
                reply = job(*args)
            except Exception as exc:
                name = type(exc).__name__
                body = f'{{"errors": ["internal error ({name}); please report it"]}}'.encode()
                reply = Reply(500, body, defect=traceback.format_exc())
            _send(replies, reply)
    except (EOFError, BrokenPipeError):
        return


class _Worker:
    """One worker process and the server's ends of its pipes."""

    def __init__(self, preload: tuple[str, ...]) -> None:
        self.process = subprocess.Popen(
            [sys.executable, "-c", "from ecdsim.webapp.workers import serve; serve()"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
        )
        self.killed = False
        assert self.process.stdin is not None
        assert self.process.stdout is not None
        self.requests: IO[bytes] = self.process.stdin
        self.replies: IO[bytes] = self.process.stdout
        # Started: the interpreter imports ecdsim and the server (a second or two), which
        # no request's time limit counts; a start that hangs is ended.
        timer = threading.Timer(START_LIMIT_S, self.kill)
        timer.daemon = True
        timer.start()
        try:
            _send(self.requests, (list(sys.path), list(preload)))
            if _receive(self.replies) != "ready":
                raise EOFError
        except (EOFError, OSError) as exc:
            self.kill()
            raise WorkerDied from exc
        finally:
            timer.cancel()

    def alive(self) -> bool:
        return not self.killed and self.process.poll() is None

    def kill(self) -> None:
        """End the process at once and reap it (its CPU use stops here)."""
        self.killed = True
        with contextlib.suppress(OSError):
            self.process.kill()
        self.process.wait()
        for stream in (self.requests, self.replies):
            with contextlib.suppress(OSError):
                stream.close()


class WorkerPool:
    """Worker processes for jobs, each job stopped at its deadline (module docstring)."""

    def __init__(self, size: int, preload: tuple[str, ...] = ()) -> None:
        self.size = size
        self.preload = preload
        self._slots = threading.BoundedSemaphore(size)
        self._idle: list[_Worker] = []
        self._lock = threading.Lock()

    def call(self, job: Callable[..., Reply], args: tuple[Any, ...], limit_s: float) -> Reply:
        """``job(*args)`` in a worker, answered within ``limit_s`` seconds (blocking).

        Raises :class:`Busy` if no worker becomes free in time, :class:`Timeout` when the
        job runs past the limit (its worker is killed at the deadline), and
        :class:`WorkerDied` if its process ends while computing.
        """
        if not self._slots.acquire(timeout=max(limit_s, 0.0)):
            raise Busy
        try:
            worker = self._take()  # a worker's start is not counted in the limit
            deadline = time.monotonic() + limit_s
            # The deadline kills the worker; the read below then ends at once.
            timer = threading.Timer(max(deadline - time.monotonic(), 0.0), worker.kill)
            timer.daemon = True
            timer.start()
            try:
                _send(worker.requests, (job, args))
                reply: Reply = _receive(worker.replies)
            except (EOFError, OSError, pickle.UnpicklingError) as exc:
                timer.cancel()
                worker.kill()
                if time.monotonic() >= deadline:
                    raise Timeout from exc
                raise WorkerDied from exc
            except BaseException:
                timer.cancel()
                worker.kill()  # an interrupt: the job must not run on
                raise
            timer.cancel()
            if not worker.alive():  # killed just as it answered: the answer came in time
                return reply
            self._give_back(worker)
            return reply
        finally:
            self._slots.release()

    def _take(self) -> _Worker:
        with self._lock:
            while self._idle:
                worker = self._idle.pop()
                if worker.alive():
                    return worker
                worker.kill()
        return _Worker(self.preload)

    def _give_back(self, worker: _Worker) -> None:
        with self._lock:
            self._idle.append(worker)

    def close(self) -> None:
        """End every idle worker (those computing end with their request)."""
        with self._lock:
            idle, self._idle = self._idle, []
        for worker in idle:
            worker.kill()


_POOL: WorkerPool | None = None
_POOL_LOCK = threading.Lock()


def shared_pool(preload: tuple[str, ...] = ()) -> WorkerPool:
    """The process's one pool (every explorer app of the process shares it); its idle
    workers are ended when the process exits. ``preload``: the modules each worker
    imports as it starts (fixed by the first call)."""
    global _POOL
    with _POOL_LOCK:
        if _POOL is None:
            import atexit

            _POOL = WorkerPool(pool_size(), preload)
            atexit.register(_POOL.close)
        return _POOL
