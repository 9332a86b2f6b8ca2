"""Demonstrated reliability of a test campaign (docs/qualification.md).

* **Success run.** N deployments without a failure demonstrate, at confidence C, a
  reliability of at least ``R = (1 - C)**(1/N)``: a unit of reliability R would pass all N
  with probability ``R**N``, which is ``1 - C`` there. The N needed for a target R is the
  smallest with ``R**N <= 1 - C``: ``ceil(ln(1 - C) / ln R)``.
* **With failures** (f of N): the exact one-sided binomial (Clopper-Pearson) bound, the
  smallest R with ``P(X <= f) >= 1 - C`` for X failures of N at probability ``1 - R``,
  which is the beta quantile ``R_L = B^-1(1 - C; N - f, f + 1)``; for f = 0 it is the
  success-run formula exactly (``B(x; N, 1) = x**N``). C. J. Clopper and E. S. Pearson,
  Biometrika 26 (1934) 404-413.
* **A probability of missing a requirement** from k misses of n samples: ``k / n`` with
  its exact two-sided interval and its one-sided upper bound (the miss probability a
  qualification statement quotes), the same binomial bounds.
* **Repeated deployments of one unit** (a life test, ``ecdsim repeat``): failures at
  deployments ``t_1 <= ... <= t_n`` of N are fitted by the power-law (Weibull) process of
  Crow (L. H. Crow, "Reliability analysis for complex, repairable systems", in
  Reliability and Biometry, SIAM 1974, 379-410, and AMSAA Technical Report 138, 1975;
  MIL-HDBK-189): expected failures
  ``lambda t**beta``, for a test ended at N (time-truncated)
  ``beta = n / sum ln(N / t_i)``, ``lambda = n / N**beta``; given n, ``-beta ln(t_i/N)``
  are independent unit exponentials, so ``2 n beta / beta_hat`` is chi-square with 2n
  degrees of freedom, which gives beta's exact interval. beta > 1: failures come faster
  as the unit ages (wear-out); beta < 1: slower.
* **Lives of several units** (cycles to failure, some units suspended): the two-parameter
  Weibull distribution by maximum likelihood with right censoring, intervals from the
  Fisher information on log scale (W. Weibull, J. Appl. Mech. 18 (1951) 293-297;
  W. Q. Meeker and L. A. Escobar, Statistical Methods for Reliability Data, Wiley 1998,
  chapter 8).

The quantiles come from ``scipy.special`` (``betaincinv``, ``bdtr``, ``chdtri``,
``ndtri``), imported where used.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, as_float

CONFIDENCE = 0.95


def _check_confidence(confidence: float) -> None:
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence {confidence!r} must lie strictly between 0 and 1")


def _check_counts(runs: int, failures: int) -> None:
    if runs < 1:
        raise ValueError(f"runs {runs!r} must be at least 1")
    if not 0 <= failures <= runs:
        raise ValueError(f"failures {failures!r} must lie between 0 and the runs ({runs})")


def success_run_reliability(runs: int, confidence: float = CONFIDENCE) -> float:
    """Reliability demonstrated by ``runs`` successes in a row: ``(1 - C)**(1/N)`` [-].

    >>> round(success_run_reliability(22, 0.9), 4)
    0.9006
    """
    _check_counts(runs, 0)
    _check_confidence(confidence)
    return float((1.0 - confidence) ** (1.0 / runs))


def reliability_lower_bound(runs: int, failures: int, confidence: float = CONFIDENCE) -> float:
    """One-sided Clopper-Pearson lower bound of the reliability from f failures in N [-].

    ``B^-1(1 - C; N - f, f + 1)``; the success-run formula for f = 0 and 0 for f = N.

    >>> round(reliability_lower_bound(10, 0, 0.9), 12) == round(0.1 ** 0.1, 12)
    True
    """
    _check_counts(runs, failures)
    _check_confidence(confidence)
    if failures == runs:
        return 0.0
    if failures == 0:
        return success_run_reliability(runs, confidence)
    from scipy.special import betaincinv

    return float(betaincinv(runs - failures, failures + 1, 1.0 - confidence))


def runs_needed(reliability: float, confidence: float = CONFIDENCE, failures: int = 0) -> int:
    """The fewest deployments that demonstrate ``reliability`` at ``confidence`` when
    ``failures`` of them may fail: the smallest N with ``P(X <= f) <= 1 - C``, X ~
    Binomial(N, 1 - R) (``ceil(ln(1 - C) / ln R)`` for f = 0).

    >>> runs_needed(0.9, 0.9)
    22
    """
    _check_confidence(confidence)
    if not 0.0 < reliability < 1.0:
        raise ValueError(f"reliability {reliability!r} must lie strictly between 0 and 1")
    if failures < 0:
        raise ValueError(f"failures {failures!r} must be >= 0")
    # ln(1 - C) / ln R, a hair above an integer by rounding, must not add a run: the
    # guard below checks the candidate against the bound itself.
    start = max(1, math.ceil(math.log(1.0 - confidence) / math.log(reliability) - 1e-9))
    if failures == 0:
        n = start
        while reliability**n > 1.0 - confidence:
            n += 1
        while n > 1 and reliability ** (n - 1) <= 1.0 - confidence:
            n -= 1
        return n
    from scipy.special import bdtr

    n = start + failures
    while float(bdtr(failures, n, 1.0 - reliability)) > 1.0 - confidence:
        n += 1
    return n


def proportion_interval(
    count: int, trials: int, confidence: float = CONFIDENCE
) -> tuple[float, float]:
    """Exact two-sided (Clopper-Pearson) interval of a proportion ``count / trials`` [-]."""
    _check_counts(trials, count)
    _check_confidence(confidence)
    from scipy.special import betaincinv

    tail = (1.0 - confidence) / 2.0
    low = 0.0 if count == 0 else float(betaincinv(count, trials - count + 1, tail))
    high = 1.0 if count == trials else float(betaincinv(count + 1, trials - count, 1.0 - tail))
    return low, high


def upper_bound(count: int, trials: int, confidence: float = CONFIDENCE) -> float:
    """One-sided upper bound of a proportion at ``confidence`` [-]: ``1 - R_L`` with the
    misses as failures (for no miss ``1 - (1 - C)**(1/n)``, about ``3 / n`` at 95 %)."""
    return 1.0 - reliability_lower_bound(trials, count, confidence)


@dataclass(frozen=True)
class Demonstrated:
    """What a campaign of N deployments with f failures demonstrates.

    Attributes
    ----------
    runs : N
    failures : f
    confidence : C [-]
    observed : the observed reliability ``1 - f / N`` [-]
    lower_bound : the reliability demonstrated at C [-] (one-sided Clopper-Pearson)
    """

    runs: int
    failures: int
    confidence: float
    observed: float
    lower_bound: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "runs": self.runs,
            "failures": self.failures,
            "confidence": self.confidence,
            "observed_reliability": self.observed,
            "demonstrated_reliability": self.lower_bound,
            "bound": "success run" if self.failures == 0 else "binomial (Clopper-Pearson)",
        }


def demonstrated(runs: int, failures: int = 0, confidence: float = CONFIDENCE) -> Demonstrated:
    """The reliability a campaign demonstrates (module docstring)."""
    bound = reliability_lower_bound(runs, failures, confidence)
    return Demonstrated(runs, failures, confidence, 1.0 - failures / runs, bound)


@dataclass(frozen=True)
class MissProbability:
    """How often a requirement is missed, from a sample.

    Attributes
    ----------
    misses : k, samples that miss it
    samples : n
    probability : k / n [-]
    interval : exact two-sided interval at ``confidence`` [-]
    upper : one-sided upper bound at ``confidence`` [-]
    confidence : C [-]
    """

    misses: int
    samples: int
    probability: float
    interval: tuple[float, float]
    upper: float
    confidence: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "misses": self.misses,
            "samples": self.samples,
            "probability": self.probability,
            "interval95": list(self.interval),
            "upper95": self.upper,
        }


def miss_probability(misses: ArrayLike, confidence: float = CONFIDENCE) -> MissProbability:
    """The probability of missing a requirement from a boolean array of misses."""
    flags = np.asarray(misses, dtype=bool).reshape(-1)
    k, n = int(np.count_nonzero(flags)), int(flags.size)
    return MissProbability(
        k, n, k / n, proportion_interval(k, n, confidence), upper_bound(k, n, confidence),
        confidence,
    )  # fmt: skip


@dataclass(frozen=True)
class PowerLawProcess:
    """Crow's power-law (Weibull) process fitted to one unit's failing deployments.

    Attributes
    ----------
    failures : the deployment numbers that failed (1-based), sorted
    runs : N, deployments made (the test ends after deployment N)
    beta : shape beta_hat [-]: > 1 failures come faster with use, < 1 slower
    beta_interval : exact two-sided interval of beta at ``confidence``
    scale : lambda_hat = n / N**beta [1/deployment**beta]
    confidence : C [-]
    """

    failures: tuple[int, ...]
    runs: int
    beta: float
    beta_interval: tuple[float, float]
    scale: float
    confidence: float

    @property
    def intensity(self) -> float:
        """Failures per deployment at the end of the test, ``lambda beta N**(beta - 1)``."""
        return float(self.scale * self.beta * self.runs ** (self.beta - 1.0))

    def expected_failures(self, deployments: float) -> float:
        """Expected failures in the first ``deployments``: ``lambda t**beta``."""
        return float(self.scale * deployments**self.beta)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "model": "power-law (Crow-AMSAA) process, time-truncated at the last deployment",
            "failed_deployments": list(self.failures),
            "runs": self.runs,
            "beta": self.beta,
            "beta_interval95": list(self.beta_interval),
            "lambda": self.scale,
            "failure_intensity_at_end": self.intensity,
        }


def power_law_process(
    failures: Sequence[int], runs: int, confidence: float = CONFIDENCE
) -> PowerLawProcess | None:
    """Fit Crow's power-law process to the failing deployment numbers of one unit.

    None where it is not defined: no failure, or every failure at the last deployment
    (``sum ln(N / t_i) = 0``).
    """
    _check_confidence(confidence)
    times = sorted(int(k) for k in failures)
    if not times:
        return None
    if times[0] < 1 or times[-1] > runs:
        raise ValueError(f"failed deployments must lie in 1..{runs}, got {times}")
    n = len(times)
    total = float(sum(math.log(runs / t) for t in times))
    if total <= 0.0:
        return None
    from scipy.special import chdtri

    beta = n / total
    tail = (1.0 - confidence) / 2.0
    # 2 n beta / beta_hat ~ chi2(2n): beta in beta_hat * [chi2_low, chi2_high] / (2 n).
    low = beta * float(chdtri(2 * n, 1.0 - tail)) / (2 * n)
    high = beta * float(chdtri(2 * n, tail)) / (2 * n)
    return PowerLawProcess(tuple(times), runs, beta, (low, high), n / runs**beta, confidence)


@dataclass(frozen=True)
class WeibullFit:
    """A two-parameter Weibull fitted to lives, some suspended (right-censored).

    Attributes
    ----------
    shape : beta [-]
    scale : eta, the characteristic life [unit of the lives]
    shape_interval, scale_interval : two-sided intervals at ``confidence`` (Fisher
        information, normal on log scale)
    covariance : covariance of (beta, eta)
    failures : r, lives that ended in a failure
    suspensions : lives that did not
    confidence : C [-]
    """

    shape: float
    scale: float
    shape_interval: tuple[float, float]
    scale_interval: tuple[float, float]
    covariance: FloatArray
    failures: int
    suspensions: int
    confidence: float

    def reliability(self, life: ArrayLike) -> FloatArray:
        """``exp(-(t / eta)**beta)``, the probability of surviving to ``life`` [-]."""
        return as_float(np.exp(-((as_float(life) / self.scale) ** self.shape)))

    def b_life(self, fraction: float) -> float:
        """The life by which ``fraction`` of units fail (B10: 0.1)."""
        return float(self.scale * (-math.log1p(-fraction)) ** (1.0 / self.shape))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "shape": self.shape,
            "shape_interval95": list(self.shape_interval),
            "scale": self.scale,
            "scale_interval95": list(self.scale_interval),
            "b10_life": self.b_life(0.1),
            "failures": self.failures,
            "suspensions": self.suspensions,
            "estimator": "maximum likelihood, right-censored; Fisher-matrix intervals",
        }


def weibull_fit(lives: ArrayLike, failed: ArrayLike, confidence: float = CONFIDENCE) -> WeibullFit:
    """Maximum-likelihood Weibull fit of lives (cycles or time) with suspensions.

    The log-likelihood ``r ln beta - r beta ln eta + (beta - 1) sum_F ln t_i -
    sum_all (t_i / eta)**beta`` is maximised over eta in closed form,
    ``eta**beta = sum_all t_i**beta / r``, leaving the score equation of beta
    ``sum t^beta ln t / sum t^beta - 1/beta - mean_F ln t = 0``, which is increasing in
    beta and solved by bisection. Needs two failures at distinct lives.
    """
    _check_confidence(confidence)
    t = as_float(lives).reshape(-1)
    dead = np.asarray(failed, dtype=bool).reshape(-1)
    if t.size != dead.size:
        raise ValueError("lives and failure flags differ in length")
    if not np.all(np.isfinite(t) & (t > 0.0)):
        raise ValueError("every life must be a finite number > 0")
    r = int(np.count_nonzero(dead))
    if r < 2 or np.unique(t[dead]).size < 2:
        raise ValueError("a Weibull fit needs at least two failures at different lives")
    scale_t = float(np.max(t))
    x = np.log(t / scale_t)  # lives relative to the longest: no overflow in t**beta
    mean_failed = float(np.mean(x[dead]))

    def score(beta: float) -> float:
        w = np.exp(beta * x)
        return float(np.sum(w * x) / np.sum(w)) - 1.0 / beta - mean_failed

    low, high = 1e-3, 1.0
    while score(high) < 0.0:
        low, high = high, high * 2.0
        if high > 1e4:
            raise ValueError("the lives are too close together for a Weibull fit")
    for _ in range(200):
        mid = 0.5 * (low + high)
        if score(mid) < 0.0:
            low = mid
        else:
            high = mid
        if high - low <= 1e-14 * high:
            break
    beta = 0.5 * (low + high)
    eta = scale_t * float(np.sum(np.exp(beta * x)) / r) ** (1.0 / beta)
    z = (t / eta) ** beta
    log_ratio = np.log(t / eta)
    # Observed information (minus the Hessian) at the maximum, where sum z = r.
    d_bb = r / beta**2 + float(np.sum(z * log_ratio**2))
    d_ee = beta**2 * r / eta**2
    d_be = -beta / eta * float(np.sum(z * log_ratio))
    information = np.array([[d_bb, d_be], [d_be, d_ee]])
    covariance = as_float(np.linalg.inv(information))
    from scipy.special import ndtri

    k = float(ndtri(0.5 + confidence / 2.0))
    sb = math.sqrt(covariance[0, 0]) / beta
    se = math.sqrt(covariance[1, 1]) / eta
    return WeibullFit(
        shape=beta,
        scale=eta,
        shape_interval=(beta * math.exp(-k * sb), beta * math.exp(k * sb)),
        scale_interval=(eta * math.exp(-k * se), eta * math.exp(k * se)),
        covariance=covariance,
        failures=r,
        suspensions=int(t.size - r),
        confidence=confidence,
    )


def life_test(
    deployment_times: ArrayLike,
    minimum: float | None = None,
    maximum: float | None = None,
    confidence: float = CONFIDENCE,
) -> list[dict[str, Any]]:
    """What a life test of one unit shows, per column (temperature) of its times.

    A deployment fails where it never arrives (time +inf) or arrives outside
    ``[minimum, maximum]`` [s] where given. Per column: the failed deployments (1-based),
    the demonstrated reliability (:func:`demonstrated`), the drift of the time (last
    minus first, the mean drift per deployment and the largest departure from the
    first, over arriving deployments) and, where deployments fail, Crow's power-law
    process (:func:`power_law_process`).

    Parameters
    ----------
    deployment_times : time of each deployment [s], shape (N,) or (N, m), +inf if stalled
    minimum, maximum : the requirement's window [s], None where free
    confidence : C of the demonstrated reliability and of the intervals [-]
    """
    times = as_float(deployment_times)
    if times.ndim == 1:
        times = times[:, np.newaxis]
    runs = int(times.shape[0])
    out = []
    for j in range(times.shape[1]):
        t = times[:, j]
        failed = ~np.isfinite(t)
        if minimum is not None:
            failed |= np.isfinite(t) & (t < minimum)
        if maximum is not None:
            failed |= ~(t <= maximum)
        failures = [int(k) + 1 for k in np.flatnonzero(failed)]
        arriving = t[np.isfinite(t)]
        drift: dict[str, float | None] = {"total_s": None, "per_deployment_s": None,
                                          "largest_departure_s": None}  # fmt: skip
        if np.isfinite(t[0]) and np.isfinite(t[-1]):
            total = float(t[-1] - t[0])
            drift["total_s"] = total
            drift["per_deployment_s"] = total / (runs - 1) if runs > 1 else 0.0
        if np.isfinite(t[0]) and arriving.size:
            drift["largest_departure_s"] = float(np.max(np.abs(arriving - t[0])))
        process = power_law_process(failures, runs, confidence) if failures else None
        out.append(
            {
                "failed_deployments": failures,
                "demonstrated": demonstrated(runs, len(failures), confidence).to_dict(),
                "drift": drift,
                "power_law_process": None if process is None else process.to_dict(),
            }
        )
    return out
