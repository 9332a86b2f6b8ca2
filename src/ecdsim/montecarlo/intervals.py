"""Order-statistic ranks and exact binomial intervals: the tools every study statistic uses.

:mod:`~ecdsim.montecarlo.stats` (percentiles, stall probability) and
:mod:`~ecdsim.montecarlo.repeatability` (the paper's repeated deployments) both build on
these, so they live below both (definitions in docs/montecarlo.md).
"""

from __future__ import annotations

import math

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
