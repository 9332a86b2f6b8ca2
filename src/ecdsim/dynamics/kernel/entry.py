"""The kernel's entry points, compiled or plain by :func:`ecdsim.dynamics.kernel.build.backend`.

* :func:`solve_cases`: cases of a batch from release to the end of their runs
  (:mod:`ecdsim.dynamics.kernel.loop`);
* :func:`sample_cases`: their time series from the recorded spans
  (:mod:`ecdsim.dynamics.kernel.sample`).
"""

from __future__ import annotations

from ecdsim.dynamics.kernel.loop import solve_cases
from ecdsim.dynamics.kernel.sample import sample_cases

__all__ = ["sample_cases", "solve_cases"]
