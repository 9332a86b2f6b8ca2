"""Order-statistic ranks and exact binomial intervals: the tools every study statistic uses.

:mod:`~ecdsim.montecarlo.stats` (percentiles, stall probability) and
:mod:`~ecdsim.montecarlo.repeatability` (the paper's repeated deployments) both build on
these, so they live below both (definitions in docs/montecarlo.md).
"""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence

import numpy as np

from ecdsim._types import FloatArray

CONFIDENCE = 0.95


def rank_of(n: int, probability: float) -> int:
    """0-based rank of the ``probability`` percentile of n samples: ceil(p*n) - 1.

    >>> rank_of(100, 0.05), rank_of(100, 0.5), rank_of(101, 0.5)
    (4, 49, 50)
    """
    # Rounding the product guards ceil() against 0.29 * 100 = 28.999999999999996.
    return min(max(math.ceil(round(probability * n, 9)) - 1, 0), n - 1)


def confidence_ranks(n: int, probability: float) -> tuple[int | None, int | None]:
    """0-based ranks (r, s) of a distribution-free 95 % interval of a percentile.

    With B ~ Binomial(n, p) the number of samples below the true percentile,
    ``P(x_(r) <= q_p <= x_(s)) = P(r <= B <= s - 1)`` (1-based ranks); r and s - 1 are
    B's 2.5 % and 97.5 % quantiles. None where the rank falls outside the sample.
    """
    tail = (1.0 - CONFIDENCE) / 2.0
    low = _binomial_quantile(tail, n, probability)  # 1-based rank r
    high = _binomial_quantile(1.0 - tail, n, probability) + 1  # 1-based rank s
    return (low - 1 if low >= 1 else None, high - 1 if high <= n else None)


def _binomial_quantile(q: float, n: int, p: float) -> int:
    """The smallest k in 0..n with P(B <= k) >= q, B ~ Binomial(n, p) (scipy's binom.ppf).

    From the normal approximation, stepped to the exact answer with the binomial CDF
    (``scipy.special.bdtr``): scipy.special is loaded for the normal quantiles anyway,
    while scipy.stats costs 0.7 to 1.3 s of import on this project's machine.
    """
    from scipy.special import bdtr, ndtri

    def cdf(k: int) -> float:
        return float(bdtr(k, n, p)) if k < n else 1.0

    if p <= 0.0:
        return 0
    if p >= 1.0:
        return n if q > 0.0 else 0
    guess = n * p + float(ndtri(q)) * math.sqrt(n * p * (1.0 - p))
    k = min(max(int(guess), 0), n)
    while k > 0 and cdf(k - 1) >= q:
        k -= 1
    while k < n and cdf(k) < q:
        k += 1
    return k


def proportion_interval(successes: int, trials: int) -> tuple[float, float]:
    """Exact (Clopper-Pearson) 95 % interval of a proportion [-]."""
    from scipy.special import betaincinv  # the beta quantile, without scipy.stats' import

    tail = (1.0 - CONFIDENCE) / 2.0
    low = 0.0 if successes == 0 else float(betaincinv(successes, trials - successes + 1, tail))
    high = (
        1.0
        if successes == trials
        else float(betaincinv(successes + 1, trials - successes, 1.0 - tail))
    )
    return low, high


# Order statistics of a large sample by bracketing (order_statistics): the size from which
# it is used instead of np.partition, the systematic subsample that places the brackets,
# and their half-width in standard deviations of the subsample's rank.
BRACKET_MIN_SIZE = 1_000_000
BRACKET_SUBSAMPLE = 131_072
BRACKET_SIGMAS = 7.0


def order_statistics(
    values: FloatArray, ranks: Sequence[int], *, overwrite: bool = False
) -> FloatArray:
    """The values of the given 0-based ranks in sorted order: ``np.sort(values)[ranks]``.

    Exact, with NaN sorted last as NumPy sorts it. For a large sample each wanted rank is
    first bracketed by a sorted systematic subsample (every k-th value): the bracket's
    values are selected in a few vectorised passes, the count below it is taken, and the
    rank is read from the sorted bracket. Where a bracket does not hold its rank (the
    subsample missed, heavy ties) the whole sample is partitioned as before, so the answer
    never depends on the subsample; only the time does. ``overwrite`` lets that partition
    reorder ``values`` in place instead of copying them.
    """
    x = np.asarray(values, dtype=float).reshape(-1)
    wanted = sorted(set(ranks))
    if wanted and (wanted[0] < 0 or wanted[-1] >= x.size):
        raise IndexError(f"ranks {wanted[0]}..{wanted[-1]} outside a sample of {x.size}")
    found = _bracketed(x, wanted) if x.size >= BRACKET_MIN_SIZE else None
    if found is None:
        ordered = x if overwrite else x.copy()
        ordered.partition(wanted)
        found = {r: float(ordered[r]) for r in wanted}
    return np.array([found[r] for r in ranks], dtype=float)


def _bracketed(x: FloatArray, wanted: list[int]) -> dict[int, float] | None:
    """:func:`order_statistics` by brackets, or None where a bracket misses its ranks."""
    n = x.size
    sample = np.sort(x[:: max(1, n // BRACKET_SUBSAMPLE)])
    m = sample.size
    # Each rank's bracket, in subsample indices: about q*m of the subsample lies below
    # the rank's value (q = its probability), give or take sqrt(m q (1 - q)); brackets
    # that overlap are merged, so that each value is selected once.
    spans: list[tuple[int, int, list[int]]] = []
    for rank in wanted:
        q = (rank + 0.5) / n
        half = BRACKET_SIGMAS * math.sqrt(m * q * (1.0 - q)) + 2.0
        low, high = math.floor(q * m - half), math.ceil(q * m + half)
        if spans and low <= spans[-1][1]:
            spans[-1] = (spans[-1][0], high, [*spans[-1][2], rank])
        else:
            spans.append((low, high, [rank]))
    edges = [
        (
            float(sample[low]) if low > 0 else -math.inf,
            float(sample[high]) if high < m else math.inf,
        )
        for low, high, _ in spans
    ]
    if compiled_selection() and _disjoint(edges):
        return _bracketed_compiled(x, edges, [members for _, _, members in spans])
    selected = np.zeros(n, dtype=bool)
    inside = np.empty(n, dtype=bool)
    inside_high = np.empty(n, dtype=bool)
    belows = []
    total = 0
    for (lowest, highest), (_, _, members) in zip(edges, spans, strict=True):
        below = int(np.count_nonzero(x < lowest))
        np.greater_equal(x, lowest, out=inside)
        np.less_equal(x, highest, out=inside_high)
        inside &= inside_high
        count = int(np.count_nonzero(inside))
        total += count
        # NaN is in no bracket and below none: a rank among them is never held.
        if not (below <= members[0] and members[-1] < below + count) or total > n // 8:
            return None
        selected |= inside
        belows.append(below)
    candidates = x[selected]
    found: dict[int, float] = {}
    for (lowest, highest), (_, _, members), below in zip(edges, spans, belows, strict=True):
        part = np.sort(candidates[(candidates >= lowest) & (candidates <= highest)])
        for rank in members:
            found[rank] = float(part[rank - below])
    return found


def compiled_selection() -> bool:
    """True if the brackets are selected by the compiled pass: numba is loaded already
    (by the run's compiled exact kernel) and not switched off (ECDSIM_NUMBA=0)."""
    from ecdsim import _numba

    return "numba" in sys.modules and not _numba.switched_off()


def _disjoint(edges: list[tuple[float, float]]) -> bool:
    """True if the brackets are increasing and do not overlap (their edges are values of
    a sorted subsample, so ties can make neighbours share an edge)."""
    return all(high < low for (_, high), (low, _) in zip(edges, edges[1:], strict=False))


def _bracketed_compiled(
    x: FloatArray, edges: list[tuple[float, float]], members: list[list[int]]
) -> dict[int, float] | None:
    """The brackets' selection in one compiled pass (ecdsim.montecarlo._brackets_numba):
    the same values and counts as the NumPy passes of :func:`_bracketed`, and the same
    checks; used where numba is loaded already (its import is not worth it here)."""
    from ecdsim.montecarlo._brackets_numba import select

    n = x.size
    lows = np.array([low for low, _ in edges])
    highs = np.array([high for _, high in edges])
    candidates = np.empty(n // 8)
    spans = np.empty(n // 8, dtype=np.int64)
    below = np.empty(len(edges), dtype=np.int64)
    found_count = int(select(np.ascontiguousarray(x), lows, highs, candidates, spans, below))
    if found_count < 0:
        return None
    candidates, spans = candidates[:found_count], spans[:found_count]
    found: dict[int, float] = {}
    for s, ranks in enumerate(members):
        part = np.sort(candidates[spans == s])
        first = int(below[s])
        if not (first <= ranks[0] and ranks[-1] < first + part.size):
            return None
        for rank in ranks:
            found[rank] = float(part[rank - first])
    return found
