"""Least-squares statistics shared by every fit: covariance, standard errors, intervals.

All fits in :mod:`ecdsim.characterize` are (possibly linearised) least-squares problems
``observed = model(parameters) + noise`` with independent, equal-variance noise. At the
solution, with the design matrix ``D = d model / d parameters`` (for a straight line
``D = [1, x]``), the residuals ``e`` and ``dof = n - p``::

    s**2       = sum(e**2) / dof                    (residual variance)
    covariance = s**2 * (D^T D)^-1                  (exact for a line, Gauss-Newton else)
    ci95       = value +- t(0.975, dof) * sqrt(diag(covariance))

Reference: N. R. Draper and H. Smith, *Applied Regression Analysis*, 3rd ed., Wiley 1998,
chapters 1-2 (line), 8 (residuals, leverage) and 24 (non-linear least squares).
The distributions' tails and quantiles come from :mod:`ecdsim.characterize.distributions`
(no scipy import: ``scipy.special`` alone costs more than a whole ``ecdsim fit
drop-test``) for finite positive degrees of freedom up to its ``MAX_DOF``; larger ones
go to ``scipy.special`` (``stdtrit``, ``stdtr``, ``chdtrc``, ``fdtrc``, what
``scipy.stats`` computes them with after its argument checks), and arguments outside the
plain domain (a non-positive or infinite dof, a probability of 0 or 1, NaN) to
``scipy.stats``, so the answers are its answers (tests/test_characterize_stats.py and
tests/test_characterize_distributions.py check that the ways agree).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from statistics import NormalDist
from typing import Any

import numpy as np

from ecdsim._types import FloatArray
from ecdsim.characterize import distributions

CONFIDENCE = 0.95
# Singular values below this fraction of the largest mean the parameters cannot be told
# apart by the data (the design matrix is rank deficient to float64 resolution).
RANK_TOLERANCE = 1e-10
# A residual standard deviation below this fraction of the observations' magnitude is
# float64 round-off: the data lie exactly on the model, and tests that divide by the
# residual scatter (outliers, curvature) have nothing to test.
EXACT_FIT_RESOLUTION = 1e-11


def t_quantile(dof: float, confidence: float = CONFIDENCE) -> float:
    """Two-sided Student-t critical value: ``t`` with ``P(|T_dof| <= t) = confidence``.

    >>> round(t_quantile(1), 4)
    12.7062
    """
    return float(student_t_ppf(0.5 + confidence / 2.0, dof))


def normal_quantile(confidence: float = CONFIDENCE) -> float:
    """Two-sided standard-normal critical value (1.95996... for 95 %).

    >>> round(normal_quantile(), 5)
    1.95996
    """
    return NormalDist().inv_cdf(0.5 + confidence / 2.0)


def t_two_sided_p(statistic: float, dof: int) -> float:
    """Two-sided p-value of a t statistic with ``dof`` degrees of freedom."""
    return float(2.0 * student_t_sf(abs(statistic), dof))


def chi2_survival(value: float, dof: int) -> float:
    """``P(chi2_dof > value)``: the p-value of a chi-square goodness-of-fit statistic."""
    if _plain(dof) and math.isfinite(value) and value >= 0.0:
        if _lean(dof):
            return distributions.chi2_tail(value, float(dof))
        from scipy.special import chdtrc

        return float(chdtrc(dof, value))
    from scipy import stats

    return float(stats.chi2.sf(value, dof))


def f_survival(value: float, dof_numerator: int, dof_denominator: int) -> float:
    """``P(F > value)`` for Fisher's F with the given degrees of freedom: the p-value of
    a ratio of two independent variance estimates (a lack-of-fit test).

    >>> round(f_survival(1.0, 3, 10**9), 6) == round(chi2_survival(3.0, 3), 6)
    True
    """
    if _plain(dof_numerator) and _plain(dof_denominator) and math.isfinite(value) and value >= 0:
        if _lean(dof_numerator) and _lean(dof_denominator):
            return distributions.f_tail(value, float(dof_numerator), float(dof_denominator))
        from scipy.special import fdtrc

        return float(fdtrc(dof_numerator, dof_denominator, value))
    from scipy import stats

    return float(stats.f.sf(value, dof_numerator, dof_denominator))


def _plain(dof: Any) -> bool:
    """True when every dof is finite and positive (scipy.stats' checks then pass)."""
    d = np.asarray(dof, dtype=float)
    return bool(np.all(np.isfinite(d) & (d > 0.0)))


def _lean(dof: Any) -> bool:
    """True when every (plain) dof is within what :mod:`distributions` computes to
    1e-12 relative."""
    return bool(np.all(np.asarray(dof, dtype=float) <= distributions.MAX_DOF))


_t_quantile = np.vectorize(distributions.student_t_quantile, otypes=[float])
_t_tail = np.vectorize(distributions.student_t_tail, otypes=[float])


def student_t_ppf(probability: float, dof: Any) -> Any:
    """Student-t quantile ``scipy.stats.t.ppf(probability, dof)`` (dof may be an array)."""
    if _plain(dof) and 0.0 < probability < 1.0:
        if _lean(dof):
            return _t_quantile(probability, np.asarray(dof, dtype=float))
        from scipy.special import stdtrit

        return stdtrit(np.asarray(dof, dtype=float), probability)
    from scipy import stats

    return stats.t.ppf(probability, dof)


def student_t_sf(statistic: Any, dof: Any) -> Any:
    """Student-t upper tail ``scipy.stats.t.sf(statistic, dof)`` (arrays broadcast)."""
    x = np.asarray(statistic, dtype=float)
    if _plain(dof) and bool(np.all(np.isfinite(x))):
        if _lean(dof):
            return _t_tail(x, np.asarray(dof, dtype=float))
        from scipy.special import stdtr

        return stdtr(np.asarray(dof, dtype=float), -x)
    from scipy import stats

    return stats.t.sf(statistic, dof)


def finite_or_none(value: float) -> float | None:
    """``value`` as a JSON-safe float, or None where it is NaN or infinite."""
    return float(value) if math.isfinite(value) else None


@dataclass(frozen=True)
class Estimate:
    """One fitted parameter with its uncertainty.

    Attributes
    ----------
    value : the estimate [unit of the parameter]
    standard_error : its standard error [same unit]; None where the data leave no
        degrees of freedom to estimate it
    ci95 : 95 % confidence interval (low, high) [same unit]; None with the standard error
    """

    value: float
    standard_error: float | None
    ci95: tuple[float, float] | None

    def interval(self) -> list[float] | None:
        """The 95 % confidence interval as a JSON list ``[low, high]``, or None."""
        return list(self.ci95) if self.ci95 is not None else None

    def to_dict(self, key: str, unit: str = "") -> dict[str, Any]:
        """``{key+unit: value, key_se+unit: ..., key_ci95+unit: [low, high] | None}`` for JSON.

        ``unit`` is a key suffix naming the unit, e.g. ``"_Nm"``; every key ends in it, the
        interval's too (docs/json.md: a name holding a number with a unit ends in it).

        >>> Estimate(2.0, 0.5, (1.0, 3.0)).to_dict("friction", "_Nm")
        {'friction_Nm': 2.0, 'friction_se_Nm': 0.5, 'friction_ci95_Nm': [1.0, 3.0]}
        """
        return {
            f"{key}{unit}": self.value,
            f"{key}_se{unit}": self.standard_error,
            f"{key}_ci95{unit}": self.interval(),
        }


def estimates(
    values: FloatArray, covariance: FloatArray | None, quantile: float | None
) -> tuple[Estimate, ...]:
    """Estimates from parameter values, their covariance and a critical value.

    ``covariance`` or ``quantile`` None gives estimates without uncertainty.
    """
    out = []
    for i, value in enumerate(np.asarray(values, dtype=float)):
        if covariance is None or quantile is None:
            out.append(Estimate(float(value), None, None))
            continue
        v = float(value)
        se = math.sqrt(max(float(covariance[i, i]), 0.0))
        out.append(Estimate(v, se, (v - quantile * se, v + quantile * se)))
    return tuple(out)


@dataclass(frozen=True)
class Scatter:
    """The residual scatter a fit's standard errors were scaled by.

    A fit's standard errors are ``s * sqrt(u)`` with ``u`` the unscaled variance (known
    from the design) and ``s**2`` the residual variance, itself an estimate with ``dof``
    degrees of freedom. Combining fits (the laws over temperature) needs both: an
    error's own degrees of freedom, and the pooled ``s**2`` of fits that share one noise
    level (:func:`pooled_variance`).

    Attributes
    ----------
    variance : residual variance ``s**2`` [unit of the observations**2]
    dof : its degrees of freedom n - p
    """

    variance: float
    dof: int


def pooled_variance(scatter: Sequence[Scatter]) -> Scatter:
    """The pooled residual variance ``sum(dof_i s_i**2) / sum(dof_i)`` of fits sharing one
    noise level, with ``sum(dof_i)`` degrees of freedom (Draper and Smith, section 2.1,
    "pure error": under Gaussian noise ``sum(dof_i s_i**2) / sigma**2`` is chi-square
    with ``sum(dof_i)`` degrees of freedom).

    >>> pooled_variance([Scatter(1.0, 3), Scatter(3.0, 1)])
    Scatter(variance=1.5, dof=4)
    """
    dof = sum(s.dof for s in scatter)
    if dof <= 0:
        raise ValueError("pooling needs at least one degree of freedom")
    return Scatter(sum(s.dof * s.variance for s in scatter) / dof, dof)


@dataclass(frozen=True)
class Linearised:
    """The statistics of a least-squares fit, linearised at the solution.

    Attributes
    ----------
    n_points : number of observations n
    dof : degrees of freedom n - p
    residuals : observed minus fitted [unit of the observations]
    residual_variance : ``s**2 = sum(e**2) / dof`` [unit**2]; NaN where dof == 0
    unscaled_covariance : ``(D^T D)^-1`` [parameter units**2 / observation unit**2]
    covariance : ``s**2 (D^T D)^-1``; None where dof == 0 (no scatter to scale by)
    leverage : diagonal of the hat matrix ``D (D^T D)^-1 D^T`` [-]
    exact : True where the residuals are float64 round-off (the data lie on the model)
    """

    n_points: int
    dof: int
    residuals: FloatArray
    residual_variance: float
    unscaled_covariance: FloatArray
    covariance: FloatArray | None
    leverage: FloatArray
    exact: bool

    @property
    def residual_std(self) -> float | None:
        """``s`` [unit of the observations]; None where dof == 0."""
        return math.sqrt(self.residual_variance) if self.dof > 0 else None

    @property
    def scatter(self) -> Scatter | None:
        """``s**2`` with its degrees of freedom; None where dof == 0 or the fit is exact
        (then the standard errors are round-off, not uncertainty)."""
        if self.dof <= 0 or self.exact:
            return None
        return Scatter(self.residual_variance, self.dof)

    def studentized(self) -> FloatArray:
        """Externally studentised residuals ``e_i / (s_(i) sqrt(1 - h_i))``.

        ``s_(i)`` is the residual standard deviation with point i left out (Draper and
        Smith, section 8.1); under the model each follows Student's t with dof - 1
        degrees of freedom. NaN where it is not defined (dof < 2, leverage 1, or an
        exact fit).
        """
        n_out = self.dof - 1
        e = self.residuals
        h = self.leverage
        if n_out < 1 or self.exact:
            return np.full(e.shape, np.nan)
        free = h < 1.0 - 1e-12
        one_minus_h = np.where(free, 1.0 - h, 1.0)
        ssr = float(np.sum(e * e))
        s_out_sq = np.maximum((ssr - e * e / one_minus_h) / n_out, 0.0)
        defined = free & (s_out_sq > 0.0)
        denominator = np.sqrt(np.where(defined, s_out_sq, 1.0) * one_minus_h)
        return np.where(defined, e / denominator, np.nan)


def linearised(design: FloatArray, residuals: FloatArray, observed: FloatArray) -> Linearised:
    """Statistics of a least-squares fit from its design (Jacobian) matrix at the solution.

    Parameters
    ----------
    design : ``d model / d parameters``, shape (n, p) [observation unit / parameter unit]
    residuals : observed minus fitted, shape (n,) [observation unit]
    observed : the observations, shape (n,), used only to judge round-off

    Raises ``np.linalg.LinAlgError`` where the design is rank deficient: the data cannot
    tell the parameters apart.
    """
    d = np.asarray(design, dtype=float)
    e = np.asarray(residuals, dtype=float)
    n, p = d.shape
    # Scale the columns to unit length before the SVD so that parameters of very
    # different size (N*m and N*m*s/rad) do not spoil the rank test.
    norms = np.linalg.norm(d, axis=0)
    if np.any(norms == 0.0):
        raise np.linalg.LinAlgError("a parameter has no effect on the model")
    u, s, vt = np.linalg.svd(d / norms, full_matrices=False)
    if s[-1] <= RANK_TOLERANCE * s[0]:
        raise np.linalg.LinAlgError("the parameters cannot be told apart by these data")
    v_scaled = vt.T / s
    unscaled = (v_scaled @ v_scaled.T) / np.outer(norms, norms)
    leverage = np.sum(u * u, axis=1)
    dof = n - p
    ssr = float(np.sum(e * e))
    variance = ssr / dof if dof > 0 else math.nan
    scale = float(np.max(np.abs(observed))) if n else 0.0
    exact = dof > 0 and math.sqrt(variance) <= EXACT_FIT_RESOLUTION * max(scale, 1e-300)
    return Linearised(
        n_points=n,
        dof=dof,
        residuals=e,
        residual_variance=variance,
        unscaled_covariance=unscaled,
        covariance=variance * unscaled if dof > 0 else None,
        leverage=leverage,
        exact=exact,
    )
