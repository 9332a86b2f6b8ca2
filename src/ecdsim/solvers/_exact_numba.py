"""The exact solution's ordinary case compiled with numba (an optional extra).

Imported only by :func:`ecdsim.solvers.exact_kernel.solve_fast` for large batches, never at
start-up; ``cache=True`` keeps the machine code between processes (``__pycache__``), so
the compilation (about 1 s) is paid once per installation. The formulas are the
reference's (:mod:`ecdsim.physics.quasistatic`, ``docs/model.md``), one case at a time
(with ``-ln(b/a)`` for the reference's ``ln a - ln b``, one log instead of two); a case
that is not ordinary (module docstring of :mod:`ecdsim.solvers.exact_kernel`) is
flagged for the reference.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ecdsim import _numba
from ecdsim._types import BoolArray, FloatArray

# ecdsim's set-up of numba (the compile notice) before any kernel compiles.
_numba.load()

SERIES_LIMIT = 1e-6  # ecdsim.solvers.exact_kernel.SERIES_LIMIT


@numba.njit(cache=True, nogil=True, boundscheck=False, error_model="numpy")
def ordinary(
    angles: FloatArray,
    torques: FloatArray,
    friction: FloatArray,
    damping: FloatArray,
    time: FloatArray,
    start: FloatArray,
    end: FloatArray,
    peak: FloatArray,
    exceptional: BoolArray,
) -> None:  # pragma: no cover - compiled; its Python body is checked by the tests' kernel runs
    """Deployment time and speeds of every ordinary case of (n, rows, cols) arrays."""
    n, rows, cols = angles.shape
    for p in range(rows):
        for q in range(cols):
            f = friction[p, q]
            rate = damping[p, q]
            a = torques[0, p, q] - f
            if not (rate > 0.0 and rate < np.inf and a > 0.0):
                exceptional[p, q] = True
                continue
            first = a
            top = a
            total = 0.0
            ok = True
            for i in range(n - 1):
                b = torques[i + 1, p, q] - f
                length = angles[i + 1, p, q] - angles[i, p, q]
                if not (b > 0.0 and length > 0.0):
                    ok = False
                    break
                r = b / a
                x = 1.0 - r
                if abs(x) < SERIES_LIMIT:
                    ratio = 1.0 - x / 2.0 - x * x / 12.0
                elif b < 0.5 * a:
                    # The reference takes ln a - ln b; -ln(b/a) is one log instead of two
                    # and as accurate (b/a is rounded once: 1e-16 absolute in a log of at
                    # least ln 2) unless b/a leaves the normal range: then the reference.
                    if not r > 1e-300:
                        ok = False
                        break
                    ratio = x / -math.log(r)
                else:
                    ratio = x / -math.log1p(-x)
                mean = a * ratio
                if not mean > 0.0:
                    ok = False
                    break
                total += rate * length / mean
                if b > top:
                    top = b
                a = b
            fastest = top / rate
            if not (ok and fastest < np.inf):
                exceptional[p, q] = True
                continue
            time[p, q] = total
            start[p, q] = first / rate
            end[p, q] = a / rate
            peak[p, q] = fastest
