"""``ecdsim`` with the Monte Carlo run held after a given number of chunks (a test helper).

    python -m tests.montecarlo_gate FD CHUNKS ecdsim-arguments...

runs the command line as ``ecdsim`` does, except that once ``CHUNKS`` chunks of the run
are on disk (its ``progress`` callback has been called for them, in the run's main
thread, after each chunk is written and installed), it writes one byte to the file
descriptor ``FD`` (a pipe the test passed) and waits there until a signal ends it. The
test that interrupts a run reads that byte and sends its signal: the interruption lands
after exactly that many chunks, in the middle of the run, however fast or slow the
machine is, so that no deadline or process priority decides the test (a run that ends or
fails before the gate closes the pipe, which the test reads as its end).

The wait is in the main thread, where Python delivers SIGINT as a KeyboardInterrupt, so a
Ctrl-C stops the run as it would between two chunks; the writer thread and any worker
processes carry on meanwhile, as they would while the main thread waits for a result.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any


def gated(run: Callable[..., Any], fd: int, chunks: int) -> Callable[..., Any]:
    """``ecdsim.montecarlo.run`` whose progress callback holds the run after ``chunks``."""

    def held_run(
        plan: Any,
        out: Path,
        executor: Any = None,
        *,
        resume: bool = False,
        progress: Callable[[int, int], None] | None = None,
    ) -> Any:
        calls = 0

        def held(done: int, total: int) -> None:
            nonlocal calls
            if progress is not None:
                progress(done, total)
            calls += 1  # the first call is the start, then one per chunk on disk
            if calls == chunks + 1:
                os.write(fd, b"!")
                os.close(fd)
                while True:  # until the test's signal: SIGINT raises KeyboardInterrupt here
                    time.sleep(3600.0)

        return run(plan, out, executor, resume=resume, progress=held)

    return held_run


def main() -> None:
    fd, chunks, *args = sys.argv[1:]
    import ecdsim.montecarlo
    from ecdsim.cli.app import main as ecdsim_main

    # The command imports ``run`` from the package when it starts: replaced there.
    ecdsim.montecarlo.run = gated(ecdsim.montecarlo.run, int(fd), int(chunks))
    sys.argv = ["ecdsim", *args]
    ecdsim_main()


if __name__ == "__main__":
    main()
