"""Laws of BECD and FECD over temperature, fitted to the per-temperature estimates.

Two damping laws are offered, as a registry (:data:`DAMPING_LAWS`):

* ``linear``: ``BECD(T) = B_ref * (1 + c * (T - T_ref))``, the paper's law (Eq. 1, first
  term; CDA's c = -0.004 / K). This is the law the configuration file can hold.
* ``resistivity``: ``BECD(T) = B_ref / (1 + alpha * (T - T_ref))``. Eddy-current torque
  in the linear range is proportional to the conductor's conductivity, and a metal's
  resistivity rises linearly with temperature, rho = rho_ref * (1 + alpha * (T - T_ref))
  (copper: alpha = 0.0039 / K; see e.g. Serway and Jewett, *Physics for Scientists and
  Engineers*, table 27.2). To first order in T - T_ref the two laws agree with c = -alpha.

FECD(T) is fitted as a line ``slope * T + at_0C`` (the paper's form for FL_T, section 2.3;
:func:`ecdsim.physics.laws.linear_in_temperature`).

Each law is fitted by weighted least squares to the per-temperature estimates, with
weights ``1 / se**2``. How the intervals are built depends on what is known about those
standard errors:

* **Pooled scatter** (``scatter`` given, as the drop test does). Each per-temperature
  standard error is ``s_i * sqrt(u_i)``: ``u_i`` follows from the design (the speeds)
  and is known, ``s_i**2`` is the line's residual variance with only ``n_i - 2`` degrees
  of freedom (3 for five masses). Taking such ``se_i`` as known and using the normal
  quantile makes the intervals far too short (coverage 80-86 % at a nominal 95 % with
  five masses per temperature, measured; docs/characterize.md section 2). Instead the
  residual variances of all temperatures are pooled, ``s**2 = sum(nu_i s_i**2) / nu``
  with ``nu = sum(n_i - 2)`` (one noise level for the whole campaign, as a one-stage fit
  of all drops would assume), every ``se_i`` is recomputed as ``s * sqrt(u_i)``, and the
  intervals use Student t with ``nu`` degrees of freedom. Under Gaussian noise this is
  exact for the laws linear in their parameters: the weighted estimate is normal with
  covariance ``sigma**2 (D^T U^-1 D)^-1``, and ``nu s**2 / sigma**2`` is an independent
  chi-square. The misfit statistic ``chi2 / (temperatures - 2)`` is then a ratio of two
  independent variance estimates and is tested against Fisher's F with
  ``(temperatures - 2, nu)`` degrees of freedom, so it raises 1 % false alarms at the
  1 % level.
* **Known errors** (no ``scatter``, as the trace fit, whose traces have tens of samples
  each): the standard errors are taken as known, covariance ``(D^T W D)^-1``, the normal
  quantile 1.96, and the misfit test is chi-square with (temperatures - 2) degrees of
  freedom. This is the large-sample limit of the pooled case (nu -> infinity).

Where the misfit test fails at the 1 % level (the scatter about the law is larger than
the per-temperature errors explain: the law or the errors are incomplete) the covariance
is scaled by the reduced chi-square and the intervals use Student t with
(temperatures - 2) degrees of freedom. Where a per-temperature fit has no usable standard
error (two points, or noise-free data) the fit is unweighted and the covariance comes from
the scatter about the law alone (Student t).
The laws are compared by AIC; both have two parameters, so the difference is the
difference of their weighted residual sums of squares. A difference below 2 is reported
as "the data do not tell the laws apart" (Burnham and Anderson, *Model Selection and
Multimodel Inference*, 2nd ed., Springer 2002, section 2.6).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, as_float
from ecdsim.characterize.stats import (
    EXACT_FIT_RESOLUTION,
    Estimate,
    Scatter,
    chi2_survival,
    estimates,
    f_survival,
    finite_or_none,
    linearised,
    normal_quantile,
    pooled_variance,
    t_quantile,
)
from ecdsim.physics.assembly import damper_damping_rate
from ecdsim.physics.laws import linear_in_temperature

# A misfit p-value (F or chi-square, see fit_law) below this means the law does not
# describe the values within their errors; the covariance is then scaled by the scatter.
MISFIT_LEVEL = 0.01
# Below this the AIC difference is not evidence for either law (Burnham and Anderson).
AIC_DISTINCTION = 2.0


def resistivity_law(
    temperature: ArrayLike,
    reference_damping_rate: ArrayLike,
    alpha: ArrayLike,
    reference_temperature: ArrayLike = 25.0,
) -> FloatArray:
    """Damping rate following the conductor's resistivity: ``B_ref / (1 + alpha (T - T_ref))``.

    The alternative to the paper's linear law (Eq. 1, first term): eddy-current torque is
    proportional to conductivity, resistivity linear in T (module docstring).

    Parameters
    ----------
    temperature : T [degC]
    reference_damping_rate : B_ref, the damping rate at T_ref [N*m*s/rad]
    alpha : temperature coefficient of resistivity [1/K]
    reference_temperature : T_ref [degC]

    >>> round(float(resistivity_law(125.0, 24.0, 0.004)), 12)  # 24 / 1.4
    17.142857142857
    """
    dt = np.asarray(temperature, dtype=float) - np.asarray(reference_temperature, dtype=float)
    return as_float(
        np.asarray(reference_damping_rate, dtype=float)
        / (1.0 + np.asarray(alpha, dtype=float) * dt)
    )


Evaluate = Callable[[FloatArray, FloatArray, float], FloatArray]


@dataclass(frozen=True)
class Law:
    """A two-parameter law of a quantity over temperature.

    Attributes
    ----------
    name : registry name
    formula : readable formula
    keys : JSON keys of the two parameters (they carry the units)
    evaluate : ``(T [degC], parameters, T_ref [degC]) -> value``
    jacobian : ``(T, parameters, T_ref) -> d value / d parameters``, shape (n, 2)
    initial : ``(T, value, weights, T_ref) -> parameters``, a starting point
    """

    name: str
    formula: str
    keys: tuple[str, str]
    evaluate: Evaluate
    jacobian: Evaluate
    initial: Callable[[FloatArray, FloatArray, FloatArray, float], FloatArray]


def _weighted_line(x: FloatArray, y: FloatArray, weights: FloatArray) -> tuple[float, float]:
    """(intercept, slope) of the weighted least-squares line."""
    root = np.sqrt(weights)
    design = np.column_stack([np.ones_like(x), x]) * root[:, None]
    solution = np.linalg.lstsq(design, y * root, rcond=None)[0]
    return float(solution[0]), float(solution[1])


def _linear_jacobian(t: FloatArray, p: FloatArray, t_ref: float) -> FloatArray:
    dt = t - t_ref
    return np.column_stack([1.0 + p[1] * dt, p[0] * dt])


def _linear_initial(t: FloatArray, y: FloatArray, w: FloatArray, t_ref: float) -> FloatArray:
    a, b = _weighted_line(t - t_ref, y, w)
    return np.array([a, b / a if a != 0.0 else 0.0])


def _resistivity_jacobian(t: FloatArray, p: FloatArray, t_ref: float) -> FloatArray:
    dt = t - t_ref
    den = _safe_denominator(1.0 + p[1] * dt)
    return np.column_stack([1.0 / den, -p[0] * dt / den**2])


def _resistivity_initial(t: FloatArray, y: FloatArray, w: FloatArray, t_ref: float) -> FloatArray:
    # 1/B is linear in T; weights of 1/B are w * B**4 (d(1/B) = dB / B**2).
    if not np.any(y > 0.0):
        return np.array([float(np.mean(y)), 0.0])
    positive = np.where(y > 0.0, y, np.max(y))
    i, s = _weighted_line(t - t_ref, 1.0 / positive, w * positive**4)
    return np.array([1.0 / i, s / i]) if i > 0.0 else np.array([float(np.mean(y)), 0.0])


def _resistivity_evaluate(t: FloatArray, p: FloatArray, t_ref: float) -> FloatArray:
    den = 1.0 + p[1] * (t - t_ref)
    if np.all(den > 1e-9):
        return resistivity_law(t, p[0], p[1], t_ref)
    return as_float(p[0] / _safe_denominator(den))  # a trial step at the pole


def _safe_denominator(den: FloatArray) -> FloatArray:
    """Keep a trial step of the fit away from the law's pole (1 + alpha dT = 0)."""
    return np.where(den > 1e-9, den, 1e-9)


def _line_initial(t: FloatArray, y: FloatArray, w: FloatArray, t_ref: float) -> FloatArray:
    a, b = _weighted_line(t, y, w)
    return np.array([a, b])


DAMPING_LAWS: dict[str, Law] = {
    "linear": Law(
        name="linear",
        formula="BECD(T) = B_ref * (1 + c * (T - T_ref))",
        keys=("damping_rate_ref_Nms_per_rad", "temperature_coefficient_per_K"),
        evaluate=lambda t, p, t_ref: damper_damping_rate(p[0], t, t_ref, p[1]),
        jacobian=_linear_jacobian,
        initial=_linear_initial,
    ),
    "resistivity": Law(
        name="resistivity",
        formula="BECD(T) = B_ref / (1 + alpha * (T - T_ref))",
        keys=("damping_rate_ref_Nms_per_rad", "alpha_per_K"),
        evaluate=_resistivity_evaluate,
        jacobian=_resistivity_jacobian,
        initial=_resistivity_initial,
    ),
}

FRICTION_LINE = Law(
    name="line",
    formula="FECD(T) = slope * T + at_0C",
    keys=("at_0C_Nm", "slope_Nm_per_K"),
    evaluate=lambda t, p, t_ref: linear_in_temperature(t, p[1], p[0]),
    jacobian=lambda t, p, t_ref: np.column_stack([np.ones_like(t), t]),
    initial=_line_initial,
)


class LawFitError(ValueError):
    """A law cannot be fitted to these values; the message says why."""


@dataclass(frozen=True)
class LawFit:
    """One law fitted over temperature.

    Attributes
    ----------
    law : the law
    reference_temperature : T_ref [degC]
    parameters : the two parameters with uncertainty (units in ``law.keys``)
    covariance : their covariance; None where it cannot be estimated
    quantile : the critical value used for the 95 % intervals; None with no covariance
    temperatures : the temperatures fitted [degC]
    values : the per-temperature values fitted [N*m*s/rad or N*m]
    sigma : their standard errors used as weights (1 for an unweighted fit)
    weighted : True where the per-temperature standard errors were the weights
    chi_square : weighted sum of squared residuals [-] (plain sum when unweighted)
    dof : number of temperatures minus 2
    scatter_dof : degrees of freedom of the pooled per-temperature scatter the weights
        were scaled by (nu, module docstring); None where the errors were taken as known
        or the fit is unweighted
    p_value : goodness-of-fit p-value (weighted fits with dof > 0), else None: Fisher's
        F of ``chi_square / dof`` with (dof, scatter_dof) degrees of freedom, or
        chi-square with dof where the errors were taken as known
    scaled : True where the covariance was scaled by the scatter about the law (a
        weighted fit that fails the chi-square test, or any unweighted fit)
    aic : Akaike information criterion of the fit (for comparing laws) [-]
    """

    law: Law
    reference_temperature: float
    parameters: tuple[Estimate, ...]
    covariance: FloatArray | None
    quantile: float | None
    temperatures: FloatArray
    values: FloatArray
    sigma: FloatArray
    weighted: bool
    chi_square: float
    dof: int
    scatter_dof: int | None
    p_value: float | None
    scaled: bool
    aic: float

    @property
    def parameter_values(self) -> FloatArray:
        """The two parameter values."""
        return np.array([p.value for p in self.parameters])

    def __call__(self, temperature: ArrayLike) -> FloatArray:
        """The law at temperature T [degC]."""
        t = as_float(temperature)
        return as_float(self.law.evaluate(t, self.parameter_values, self.reference_temperature))

    def band(self, temperature: ArrayLike) -> tuple[FloatArray, FloatArray] | None:
        """95 % confidence band (low, high) of the law at T [degC] (delta method)."""
        if self.covariance is None or self.quantile is None:
            return None
        t = np.atleast_1d(as_float(temperature))
        g = self.law.jacobian(t, self.parameter_values, self.reference_temperature)
        spread = self.quantile * np.sqrt(np.maximum(np.sum((g @ self.covariance) * g, 1), 0.0))
        centre = np.atleast_1d(self(t))
        return centre - spread, centre + spread

    def residuals(self) -> FloatArray:
        """Per-temperature value minus law [unit of the values]."""
        return as_float(self.values - self(self.temperatures))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        out: dict[str, Any] = {
            "law": self.law.name,
            "formula": self.law.formula,
            "reference_temperature_C": self.reference_temperature,
        }
        for key, estimate in zip(self.law.keys, self.parameters, strict=True):
            out[key] = estimate.value
            out[f"{key}_ci95"] = list(estimate.ci95) if estimate.ci95 else None
        out.update(
            weighted=self.weighted,
            chi_square=self.chi_square,
            dof=self.dof,
            scatter_dof=self.scatter_dof,
            p_value=self.p_value,
            covariance_scaled=self.scaled,
            aic=finite_or_none(self.aic),
            residuals=[float(r) for r in self.residuals()],
        )
        return out


def fit_law(
    law: Law,
    temperatures: ArrayLike,
    values: Sequence[Estimate],
    reference_temperature: float = 25.0,
    *,
    scatter: Sequence[Scatter | None] | None = None,
) -> LawFit:
    """Fit ``law`` to per-temperature estimates by weighted least squares.

    Parameters
    ----------
    law : the law to fit
    temperatures : test temperatures, at least two distinct [degC]
    values : the estimate at each temperature (value and standard error)
    reference_temperature : T_ref of the law [degC]
    scatter : the residual variance each standard error was scaled by, one per
        temperature; given (and none None), the variances are pooled and the intervals
        use Student t with the pooled degrees of freedom (module docstring). None: the
        standard errors are taken as known.
    """
    from scipy.optimize import least_squares

    t = as_float(temperatures)
    y = np.array([v.value for v in values], dtype=float)
    if np.unique(t).size < 2:
        raise LawFitError("a law over temperature needs at least two temperatures")
    errors = [v.standard_error for v in values]
    weighted = all(e is not None and math.isfinite(e) and e > 0.0 for e in errors)
    sigma = np.array(errors, dtype=float) if weighted else np.ones_like(y)
    pooled = _pool(scatter, y.size) if weighted else None
    if pooled is not None and scatter is not None:
        own = np.array([s.variance for s in scatter if s is not None])
        sigma = sigma * np.sqrt(pooled.variance / own)
    x0 = law.initial(t, y, 1.0 / sigma**2, reference_temperature)

    def residual(p: FloatArray) -> FloatArray:
        return as_float((y - law.evaluate(t, p, reference_temperature)) / sigma)

    def jacobian(p: FloatArray) -> FloatArray:
        return as_float(-law.jacobian(t, p, reference_temperature) / sigma[:, None])

    result = least_squares(residual, x0, jac=jacobian, method="lm", xtol=1e-14, ftol=1e-14)
    p = np.asarray(result.x, dtype=float)
    if law is DAMPING_LAWS["resistivity"] and np.any(1.0 + p[1] * (t - reference_temperature) <= 0):
        raise LawFitError("the fitted law has its pole inside the tested temperature range")
    weighted_residuals = residual(p)
    try:
        stats = linearised(-jacobian(p), weighted_residuals, y / sigma)
    except np.linalg.LinAlgError as exc:
        raise LawFitError(f"the law's parameters cannot be determined ({exc})") from None
    chi_square = float(np.sum(weighted_residuals**2))
    dof = stats.dof
    reduced = chi_square / dof if dof > 0 else math.nan
    covariance: FloatArray | None
    if weighted:
        p_value = _misfit_p_value(chi_square, dof, pooled)
        scaled = p_value is not None and p_value < MISFIT_LEVEL
        covariance = stats.unscaled_covariance * (reduced if scaled else 1.0)
        quantile: float | None
        if scaled:
            quantile = t_quantile(dof)
        elif pooled is not None:
            quantile = t_quantile(pooled.dof)
        else:
            quantile = normal_quantile()
        aic = chi_square + 2.0 * 2
    else:
        scaled = dof > 0
        covariance = stats.covariance
        quantile = t_quantile(dof) if dof > 0 else None
        p_value = None
        floor = y.size * (EXACT_FIT_RESOLUTION * float(np.max(np.abs(y)))) ** 2
        aic = y.size * math.log(max(chi_square, floor, 1e-300) / y.size) + 2.0 * 2
    return LawFit(
        law=law,
        reference_temperature=reference_temperature,
        parameters=estimates(p, covariance, quantile),
        covariance=covariance,
        quantile=quantile if covariance is not None else None,
        temperatures=t,
        values=y,
        sigma=sigma,
        weighted=weighted,
        chi_square=chi_square,
        dof=dof,
        scatter_dof=pooled.dof if pooled is not None else None,
        p_value=p_value,
        scaled=scaled,
        aic=aic,
    )


def _pool(scatter: Sequence[Scatter | None] | None, n: int) -> Scatter | None:
    """The pooled scatter, or None where any temperature has none to pool."""
    if scatter is None:
        return None
    if len(scatter) != n:
        raise ValueError(f"{len(scatter)} scatter entries for {n} temperatures")
    known = [s for s in scatter if s is not None and s.dof > 0 and s.variance > 0.0]
    return pooled_variance(known) if len(known) == n else None


def _misfit_p_value(chi_square: float, dof: int, pooled: Scatter | None) -> float | None:
    """p-value of the law's misfit: F(dof, nu) with pooled scatter, chi-square(dof) else.

    With pooled scatter the weights carry ``s**2`` instead of ``sigma**2``:
    ``chi_square / dof = (Q / sigma**2 / dof) / (s**2 / sigma**2)``, a ratio of two
    independent chi-squares over their dof, which is Fisher's F (Draper and Smith,
    section 2.1, the lack-of-fit F test against pure error).
    """
    if dof <= 0:
        return None
    if pooled is None:
        return chi2_survival(chi_square, dof)
    return f_survival(chi_square / dof, dof, pooled.dof)


@dataclass(frozen=True)
class LawComparison:
    """Which damping law fits better.

    Attributes
    ----------
    better : name of the better law; None where the data do not tell them apart
    delta_aic : AIC(linear) - AIC(resistivity) [-]; None where not comparable
    statement : one readable sentence
    """

    better: str | None
    delta_aic: float | None
    statement: str

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {"better": self.better, "delta_aic": self.delta_aic, "statement": self.statement}


def compare_laws(fits: dict[str, LawFit]) -> LawComparison:
    """Compare the linear and the resistivity law by AIC (both have two parameters)."""
    if "linear" not in fits or "resistivity" not in fits:
        missing = sorted({"linear", "resistivity"} - set(fits))
        return LawComparison(None, None, f"not compared: the {missing[0]} law could not be fitted")
    linear, resistivity = fits["linear"], fits["resistivity"]
    if linear.dof == 0:
        return LawComparison(
            None,
            None,
            "not compared: with two temperatures both laws pass through both points",
        )
    delta = linear.aic - resistivity.aic
    what = "weighted SSR" if linear.weighted else "SSR"
    numbers = (
        f"{what} {linear.chi_square:.4g} (linear) vs {resistivity.chi_square:.4g} "
        f"(resistivity), AIC difference {delta:+.3g}"
    )
    if abs(delta) < AIC_DISTINCTION:
        return LawComparison(None, delta, f"the data do not tell the laws apart ({numbers})")
    better = "resistivity" if delta > 0.0 else "linear"
    return LawComparison(better, delta, f"the {better} law fits better ({numbers})")


@dataclass(frozen=True)
class TemperatureLaws:
    """BECD(T) and FECD(T) laws fitted over the test temperatures.

    Attributes
    ----------
    reference_temperature : T_ref of the damping laws [degC]
    damping : the damping laws that could be fitted, by name
    damping_failures : why a damping law could not be fitted, by name
    friction : the FECD line; None if it could not be fitted
    friction_failure : why not, or None
    comparison : which damping law fits better
    """

    reference_temperature: float
    damping: dict[str, LawFit]
    damping_failures: dict[str, str]
    friction: LawFit | None
    friction_failure: str | None
    comparison: LawComparison

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "reference_temperature_C": self.reference_temperature,
            "damping_rate": {name: fit.to_dict() for name, fit in self.damping.items()},
            "damping_rate_failures": dict(self.damping_failures),
            "friction": self.friction.to_dict() if self.friction else None,
            "friction_failure": self.friction_failure,
            "comparison": self.comparison.to_dict(),
        }


def fit_temperature_laws(
    temperatures: ArrayLike,
    damping: Sequence[Estimate],
    friction: Sequence[Estimate],
    reference_temperature: float = 25.0,
    *,
    scatter: Sequence[Scatter | None] | None = None,
) -> TemperatureLaws:
    """Fit every damping law and the friction line to per-temperature estimates.

    Parameters
    ----------
    temperatures : the test temperatures, at least two [degC]
    damping : BECD at each temperature [N*m*s/rad]
    friction : FECD at each temperature [N*m]
    reference_temperature : T_ref of the damping laws [degC]
    scatter : residual variance of each temperature's fit, which scaled both its BECD
        and FECD standard errors [N*m**2]; None: the errors are taken as known (see
        :func:`fit_law`)
    """
    fits: dict[str, LawFit] = {}
    failures: dict[str, str] = {}
    for name, law in DAMPING_LAWS.items():
        try:
            fits[name] = fit_law(law, temperatures, damping, reference_temperature, scatter=scatter)
        except LawFitError as exc:
            failures[name] = str(exc)
    friction_fit: LawFit | None = None
    friction_failure: str | None = None
    try:
        friction_fit = fit_law(
            FRICTION_LINE, temperatures, friction, reference_temperature, scatter=scatter
        )
    except LawFitError as exc:
        friction_failure = str(exc)
    return TemperatureLaws(
        reference_temperature=reference_temperature,
        damping=fits,
        damping_failures=failures,
        friction=friction_fit,
        friction_failure=friction_failure,
        comparison=compare_laws(fits),
    )
