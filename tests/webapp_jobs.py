"""Stand-in computations for the explorer's worker processes (tests/test_webapp_hostile.py).

The explorer runs each computation as a job in a worker process (ecdsim.webapp.workers),
so a test replaces a job, not a function inside the server process: the job is pickled
by reference and imported by the worker from here. Each has the signature of
ecdsim.webapp.server.deploy_job and finds where to report in the config's ``title``.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any


def burn_forever(config: dict[str, Any], *rest: Any) -> Any:
    """A computation that never ends and keeps a CPU busy: writes its process id to the
    file named by the config's title, then spins."""
    Path(config["title"]).write_text(str(os.getpid()), encoding="utf-8")
    count = 0
    while True:
        count += 1


def defect(config: dict[str, Any], *rest: Any) -> Any:
    """A computation with a defect (not the user's fault)."""
    raise RuntimeError("a defect, not the user's fault")
