"""One pass over a large sample for :func:`ecdsim.montecarlo.intervals.order_statistics`.

The NumPy bracketing takes six passes over the whole column per bracket (the count
below it, two comparisons, their conjunction, its count, the union of the selections)
and one more to gather the candidates: about 30 passes for a percentile's five
brackets, some 100 ms for a column of 10 million samples. This kernel takes one: each
value is placed among the brackets' sorted edges, counted in its region and, when it
falls inside a bracket, copied out with its bracket's number. The selection is the same
(the same comparisons, NaN in no bracket and below none), so the order statistics read
from it are the same numbers. Imported only where numba is already loaded (a run that
used the compiled exact kernel), never for its own sake.
"""

from __future__ import annotations

from typing import Any

import numba
import numpy as np

from ecdsim import _numba
from ecdsim._types import FloatArray

# ecdsim's set-up of numba (the compile notice) before any kernel compiles.
_numba.load()


@numba.njit(cache=True, nogil=True, boundscheck=False)
def select(
    x: FloatArray,
    lows: FloatArray,
    highs: FloatArray,
    candidates: FloatArray,
    spans: np.ndarray[Any, np.dtype[np.int64]],
    below: np.ndarray[Any, np.dtype[np.int64]],
) -> int:
    """Fill ``below[s]`` with the count of x < lows[s] and copy the values inside bracket
    s (lows[s] <= v <= highs[s]) to ``candidates`` with s in ``spans``, in sample order.

    The brackets are disjoint and increasing. Returns the number of candidates, or -1
    if they would overflow ``candidates`` (the caller then partitions the whole sample).
    """
    count = lows.size
    regions = np.zeros(count + 1, dtype=np.int64)  # values with r edges <= them
    m = 0
    limit = candidates.size
    for i in range(x.size):
        v = x[i]
        if v != v:  # NaN: in no bracket, below none
            continue
        r = 0
        while r < count and lows[r] <= v:
            r += 1
        regions[r] += 1
        if r > 0 and v <= highs[r - 1]:
            if m == limit:
                return -1
            candidates[m] = v
            spans[m] = r - 1
            m += 1
    total = 0
    for s in range(count):
        total += regions[s]
        below[s] = total
    return m
