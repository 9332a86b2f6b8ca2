"""Which noise model do a drop test's residuals support? (issue 23, item 7)

A drop test's scatter lies in the torque (``--noise torque``, the default) or in the
recorded time (``--noise timing``), and the intervals hold only under the model that is
true: timing-noise drops (1 %) reduced with the torque model give friction intervals that
cover 99 % instead of 95 %; torque-noise drops reduced with the timing model, 81 %
(docs/characterize.md section 2). The two leave different marks in the residuals:

* a relative timing error ``eps`` moves the torque-speed point by ``BECD * w * eps``, so
  under the torque model the residuals' scatter grows in proportion to the speed;
* a torque error ``e`` moves the drop time by ``e / (torque - FECD) = e / (BECD * w)``
  relative, so under the timing model the log-time residuals' scatter falls as 1 / speed.

The check tests the fitted model against that alternative, from its own residuals: per
temperature k, the residuals ``r`` of the line (linearised design ``D_k``), and
``x_i = log w_i`` under the torque model (``-log w_i`` under the timing model), the
alternative's scatter being ``sigma_k exp(x_i)``. The statistic is the log likelihood
ratio of the alternative to the fitted model, each with its own scale per temperature
(so a noisier hot temperature is no evidence) and the line refitted by weighted least
squares under the alternative:

    Lambda = sum_k n_k / 2 * log(RSS0_k / RSS1_k) - sum_i x_i

(``RSS0_k = r^T r``; ``RSS1_k`` the weighted refit's residual sum of squares, weights
``exp(-x_i)``). Its distribution when the fitted model is right does not depend on the
unknown scales: residuals are ``(I - H_k) g`` with g standard normal (H_k the hat matrix
of ``D_k``), so it is simulated (:data:`DRAWS` draws with a fixed seed: the same answer
every run; a log of more than :data:`MAX_POINTS` drops is checked on evenly spaced rows,
exactly, see :func:`_subset`) and the p-value is the share of simulated statistics at
least as large, a Monte Carlo
test (Barnard 1963; Davison and Hinkley, *Bootstrap Methods*, 1997, section 4.2.5): it
holds its level exactly for any number of drops, where the chi-square or normal
approximations did not (with five drops per temperature a normal score test fired 12 %
of the time at a nominal 5 %). A p-value at most :data:`LEVEL` is a finding.

How often it speaks (tests/test_characterize_noisecheck.py, seeded campaigns of 5
temperatures x 5 masses): under the right model in 5 % of campaigns, as designed; under
the wrong one in about 40 % with five drops per temperature, in most campaigns with
twenty. Few drops per temperature carry little information about how the scatter varies;
silence is no proof that the model is right.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ecdsim._types import FloatArray
from ecdsim.characterize.findings import FitWarning

LEVEL = 0.05
"""A p-value at or below this is a finding (a warning in the fit's output)."""
DRAWS = 999
"""Simulated statistics per check (p-values in steps of 0.001)."""
SEED = 20261127
"""The simulation's seed: a fit's check gives the same answer every run."""
MAX_POINTS = 5_000
"""The most residuals a check uses: a larger log is checked on evenly spaced rows of each
temperature (:func:`_subset`), exactly (see there), at a bounded cost."""
BLOCK_VALUES = 2_000_000
"""Simulated residuals held at once (16 MB)."""


@dataclass(frozen=True)
class Group:
    """One temperature's line, as the check needs it.

    Attributes
    ----------
    residuals : the fitted model's residuals (torque [N*m] or log time [-])
    design : d model / d (FECD, BECD) at the solution, shape (n, 2)
    exponent : ``x_i``, the alternative's scatter being ``sigma exp(x_i)`` [-]
    """

    residuals: FloatArray
    design: FloatArray
    exponent: FloatArray


@dataclass(frozen=True)
class NoiseCheck:
    """The check's outcome.

    Attributes
    ----------
    fitted : the noise model of the fit ("torque" or "timing")
    other : the alternative tested
    log_likelihood_ratio : Lambda, the alternative's log likelihood over the fitted
        model's (positive: the residuals look more like the alternative's)
    p_value : the Monte Carlo p-value of Lambda under the fitted model
    n_points : drops used (of temperatures with at least one residual degree of freedom;
        at most about MAX_POINTS)
    n_temperatures : temperatures used
    """

    fitted: str
    other: str
    log_likelihood_ratio: float
    p_value: float
    n_points: int
    n_temperatures: int

    @property
    def other_fits_better(self) -> bool:
        """True when the residuals reject the fitted model for the other (p <= LEVEL)."""
        return self.p_value <= LEVEL

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (``noise_check`` of ``ecdsim fit drop-test --json``)."""
        return {
            "fitted_model": self.fitted,
            "alternative": self.other,
            "log_likelihood_ratio": self.log_likelihood_ratio,
            "p_value": self.p_value,
            "level": LEVEL,
            "alternative_fits_better": self.other_fits_better,
            "n_points": self.n_points,
            "n_temperatures": self.n_temperatures,
        }

    def warning(self) -> FitWarning | None:
        """The finding, or None when the residuals do not reject the fitted model."""
        if not self.other_fits_better:
            return None
        pattern = (
            "grows with speed, as a relative timing error's does"
            if self.other == "timing"
            else "falls with speed, as a torque error's does"
        )
        ratio = math.exp(min(self.log_likelihood_ratio, 700.0))  # finite for any fit
        return FitWarning(
            "noise_model",
            f"the residuals fit --noise {self.other} better than --noise {self.fitted}: "
            f"their scatter {pattern} (likelihood ratio {ratio:.3g}, "
            f"p = {self.p_value:.2g}, {self.n_points} drops); the intervals hold only under "
            f"the model that fits: refit with --noise {self.other}",
        )


def _statistic(groups: list[tuple[FloatArray, FloatArray, FloatArray, FloatArray]]) -> FloatArray:
    """Lambda for each column of the residual matrices (one column per data set).

    Each group is (residuals (n, m), q (n, 2) orthonormal basis of the design's columns,
    qw (n, 2) the same of the weighted design, weights exp(-x) (n,)).
    """
    total: FloatArray | None = None
    for residuals, _q, qw, weights in groups:
        n = residuals.shape[0]
        rss0 = np.sum(residuals * residuals, axis=0)
        weighted = residuals * weights[:, None]
        # The fitted line lies in the design's span, so the weighted refit's residual is
        # the weighted residual projected off the weighted design's span.
        projected = weighted - qw @ (qw.T @ weighted)
        rss1 = np.sum(projected * projected, axis=0)
        term = 0.5 * n * (np.log(rss0) - np.log(rss1)) + float(np.sum(np.log(weights)))
        total = term if total is None else total + term
    assert total is not None
    return total


def _subset(n: int, m: int) -> np.ndarray[Any, np.dtype[np.intp]]:
    """``m`` evenly spaced indices of ``n`` rows (all of them when m >= n).

    A check on a subset S of a line's rows is as exact as on all: projected off the span
    of the subset's own design rows D_S, the full fit's residuals r_S have the covariance
    ``sigma**2 (I - H_S)`` the simulation draws from, since
    ``(I - H_S) (I - D_S (D^T D)^-1 D_S^T) (I - H_S) = I - H_S`` (``(I - H_S) D_S = 0``).
    """
    if m >= n:
        return np.arange(n)
    return np.unique(np.round(np.linspace(0.0, n - 1.0, m)).astype(np.intp))


def check_noise_model(fitted: str, other: str, lines: list[Group]) -> NoiseCheck | None:
    """Test the fitted noise model against the other one from its residuals (module
    docstring); None where no temperature has a residual degree of freedom (the caller
    leaves out exact fits: round-off says nothing about noise)."""
    groups = []
    n_points = 0
    total = sum(np.size(line.residuals) for line in lines)
    for line in lines:
        r = np.asarray(line.residuals, dtype=float)
        d = np.asarray(line.design, dtype=float)
        x = np.asarray(line.exponent, dtype=float)
        if r.size <= d.shape[1] or not np.all(np.isfinite(r)) or not np.all(np.isfinite(x)):
            continue
        if total > MAX_POINTS:
            keep = _subset(r.size, max(d.shape[1] + 1, math.ceil(r.size * MAX_POINTS / total)))
            r, d, x = r[keep], d[keep], x[keep]
        q = np.linalg.qr(d)[0]
        # Residuals of a least-squares fit are orthogonal to its design (to round-off, or
        # to the linearisation for the nonlinear fits): the part off its span is used,
        # as the simulated residuals are.
        off = r - q @ (q.T @ r)
        if not float(np.sum(off * off)) > 0.0:
            continue
        # Weights exp(-x) scaled by exp(mean x) per temperature: the factor changes
        # RSS1_k by exp(2 mean x) and the weights' log sum by -n_k mean x, which cancel,
        # so Lambda is the same and the weights stay near 1.
        weights = np.exp(-(x - np.mean(x)))
        qw = np.linalg.qr(d * weights[:, None])[0]
        groups.append((off[:, None], q, qw, weights))
        n_points += r.size
    if not groups:
        return None
    observed = float(_statistic(groups)[0])
    draws = DRAWS
    rng = np.random.default_rng(SEED)
    at_least = 0
    block = max(1, min(draws, BLOCK_VALUES // n_points))
    for start in range(0, draws, block):
        count = min(block, draws - start)
        simulated_groups = []
        for residuals, q, qw, weights in groups:
            g = rng.standard_normal((residuals.shape[0], count))
            simulated_groups.append((g - q @ (q.T @ g), q, qw, weights))
        at_least += int(np.sum(_statistic(simulated_groups) >= observed))
    p_value = (1.0 + at_least) / (draws + 1.0)
    return NoiseCheck(
        fitted=fitted,
        other=other,
        log_likelihood_ratio=observed,
        p_value=p_value,
        n_points=n_points,
        n_temperatures=len(groups),
    )
