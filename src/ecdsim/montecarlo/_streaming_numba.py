"""A chunk's sensitivity sums compiled with numba (an optional extra).

The same sums as :func:`ecdsim.montecarlo.streaming.sums_of` (its module docstring):
per temperature, over the samples whose deployment time is finite, the count, the
means of the inputs and of the time, the centred sums ``dx.T @ dx``, ``dx.T @ dy`` and
``dy @ dy``, and each input's bin counts and bin sums of the time. NumPy takes about 30
passes over the chunk for them (a copy, the means, 36 row products for the Gram matrix,
a bincount per input and temperature); this kernel takes two passes per distinct set of
arriving samples and two per temperature, which cut a 65,536-sample chunk's sums from
about 14 ms to 3 ms of CPU.

The bin counts and bin sums add in sample order, as ``np.bincount`` does: the same
numbers. The means and centred sums add in a fixed order of their own (sequentially; the
Gram matrix by blocks of BLOCK samples, each with four interleaved partial sums) where
NumPy adds pairwise: they differ by rounding only (relative <= n * eps, about 1e-11 for a
65,536-sample chunk in the worst case and ~1e-14 typically; tested against the NumPy
sums), far below the sampling error of any statistic built on them. The order does not
depend on the CPU (no fastmath, no BLAS), so the sums are the same bytes on any worker.
Imported only by :func:`ecdsim.montecarlo.streaming.chunk_sums` for large chunks, when
numba is installed; ``cache=True`` keeps the machine code between processes.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numba
import numpy as np

from ecdsim import _numba
from ecdsim._types import BoolArray, FloatArray

# ecdsim's set-up of numba (the compile notice) before any kernel compiles.
_numba.load()

Labels = np.ndarray[Any, np.dtype[np.uint8]]

# Samples per block of the Gram matrix's sums: the block's centred inputs (d x BLOCK)
# stay in the L1 cache while each pair of inputs is reduced over them.
BLOCK = 256


@numba.njit(cache=True, nogil=True, boundscheck=False)
def _dot(a: FloatArray, b: FloatArray, m: int) -> float:
    """``sum(a[:m] * b[:m])`` with four interleaved partial sums, added at the end: a
    fixed order (the same bytes on any CPU), four times shorter a dependency chain."""
    s0 = s1 = s2 = s3 = 0.0
    q = 0
    while q + 4 <= m:
        s0 += a[q] * b[q]
        s1 += a[q + 1] * b[q + 1]
        s2 += a[q + 2] * b[q + 2]
        s3 += a[q + 3] * b[q + 3]
        q += 4
    while q < m:
        s0 += a[q] * b[q]
        q += 1
    return (s0 + s1) + (s2 + s3)


@numba.njit(cache=True, nogil=True, boundscheck=False)
def _input_part(
    rows: FloatArray,
    labels: Labels,
    arriving: BoolArray,
    mean_x: FloatArray,
    gram: FloatArray,
    counts: FloatArray,
) -> int:
    """The inputs' part over the arriving samples; returns their count."""
    d, n = rows.shape
    total = np.zeros(d)
    count = 0
    for i in range(n):
        if arriving[i]:
            count += 1
            for j in range(d):
                total[j] += rows[j, i]
    if count == 0:
        return 0
    for j in range(d):
        mean_x[j] = total[j] / count
    dx = np.empty((d, BLOCK))
    for start in range(0, n, BLOCK):
        m = 0
        for i in range(start, min(start + BLOCK, n)):
            if arriving[i]:
                for j in range(d):
                    dx[j, m] = rows[j, i] - mean_x[j]
                    counts[j, labels[j, i]] += 1.0
                m += 1
        for j in range(d):
            for k in range(j, d):
                gram[j, k] += _dot(dx[j], dx[k], m)
    for j in range(d):
        for k in range(j + 1, d):
            gram[k, j] = gram[j, k]
    return count


@numba.njit(cache=True, nogil=True, boundscheck=False)
def _time_part(
    rows: FloatArray,
    labels: Labels,
    times: FloatArray,
    arriving: BoolArray,
    count: int,
    mean_x: FloatArray,
    cross: FloatArray,
    bin_sums: FloatArray,
) -> tuple[float, float]:
    """The time's part over the arriving samples: (mean_y, total); fills cross, bin_sums."""
    d, n = rows.shape
    sum_y = 0.0
    for i in range(n):
        if arriving[i]:
            sum_y += times[i]
    mean_y = sum_y / count
    total = 0.0
    for i in range(n):
        if arriving[i]:
            y = times[i]
            dy = y - mean_y
            total += dy * dy
            for j in range(d):
                cross[j] += (rows[j, i] - mean_x[j]) * dy
                bin_sums[j, labels[j, i]] += y
    return mean_y, total


@numba.njit(cache=True, nogil=True, boundscheck=False)
def _labels(scores: FloatArray, bins: int, labels: Labels) -> None:
    """``floor(score * bins)`` capped at ``bins - 1``: ecdsim.montecarlo.columns.bin_labels
    (the same product, truncated the same way) in one pass instead of three."""
    d, n = scores.shape
    top = bins - 1
    for j in range(d):
        for i in range(n):
            label = int(scores[j, i] * bins)
            labels[j, i] = label if label < top else top


def chunk_sums(
    rows: FloatArray,
    scores: FloatArray,
    times: Sequence[FloatArray],
    bins: int,
) -> list[tuple[float, FloatArray, float, FloatArray, FloatArray, float, FloatArray, FloatArray]]:
    """Per temperature (one array of ``times`` each): count, mean_x, mean_y, gram, cross,
    total, bin_counts, bin_sums, over the samples whose time is finite.

    ``rows`` (d, n) are the inputs [SI] and ``scores`` (d, n) their uniform scores (the
    bins are cut on them), each input's row contiguous. Temperatures whose finite samples
    are the same set share one input part.
    """
    d = rows.shape[0]
    if not 1 <= bins <= 255:
        raise ValueError(f"bins must be 1 to 255, got {bins}")
    labels = np.empty(scores.shape, dtype=np.uint8)
    _labels(scores, bins, labels)
    found = []
    parts: dict[bytes, tuple[int, FloatArray, FloatArray, FloatArray]] = {}
    for row in times:
        row = np.ascontiguousarray(row, dtype=float)
        arriving = np.isfinite(row)
        key = np.packbits(arriving).tobytes()
        if key not in parts:
            mean_x, gram, counts = np.zeros(d), np.zeros((d, d)), np.zeros((d, bins))
            count = int(_input_part(rows, labels, arriving, mean_x, gram, counts))
            parts[key] = (count, mean_x, gram, counts)
        count, mean_x, gram, counts = parts[key]
        cross, bin_sums = np.zeros(d), np.zeros((d, bins))
        if count == 0:
            found.append((0.0, mean_x, 0.0, gram, cross, 0.0, counts, bin_sums))
            continue
        mean_y, total = _time_part(rows, labels, row, arriving, count, mean_x, cross, bin_sums)
        found.append((float(count), mean_x, mean_y, gram, cross, total, counts, bin_sums))
    return found
