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

Each law is fitted by weighted least squares to the per-temperature estimates. How the
weights and intervals are built depends on what is known about their standard errors:

* **Per-temperature scatter** (``scatter`` given, as the drop test does). Each
  standard error is ``se_i = s_i * sqrt(u_i)``: ``u_i`` follows from the design (the
  speeds) and is known, ``s_i**2`` is the line's residual variance with only
  ``nu_i = n_i - 2`` degrees of freedom (3 for five masses). Taking such ``se_i`` as
  known, with the normal quantile, makes the intervals far too short (coverage 81-85 %
  at a nominal 95 % with five masses per temperature, measured; docs/characterize.md
  section 2), and weights ``1 / se_i**2`` favour the temperatures whose scatter came
  out small by chance. Instead:

  - weights: ``1 / (s**2 u_i)`` with the pooled ``s**2 = sum(nu_i s_i**2) / nu``,
    ``nu = sum(nu_i)``: they depend on the design only, so the estimate is unbiased
    whatever the scatter (and efficient where it is the same at every temperature);
  - errors: the estimate is linear in the values, ``theta = sum_i h_i y_i`` (linearised
    for a non-linear law), so its covariance is ``sum_i h_i h_i^T se_i**2``, each
    temperature with its own scatter, and a combination ``g . theta`` (a parameter, the
    law at some T) has Student-t intervals with the Welch-Satterthwaite degrees of
    freedom ``(sum_i c_i**2)**2 / sum_i (c_i**4 / nu_i)``, ``c_i = (g . h_i) se_i``
    (F. E. Satterthwaite, Biometrics Bulletin 2, 1946, 110-114, doi:10.2307/3002019);
    these lie between the smallest ``nu_i`` and ``nu``. This keeps 95 % where the noise
    differs between temperatures, where one pooled variance would not;
  - misfit: ``chi2 = sum((y_i - law_i)**2 / (s**2 u_i))``, and ``chi2 / (temperatures -
    2)`` is a ratio of two independent variance estimates (about the law, and of the
    drops about their lines): it is tested against Fisher's F with
    ``(temperatures - 2, nu)`` degrees of freedom, the lack-of-fit test against pure
    error (Draper and Smith, section 2.1), exact where the noise is the same at every
    temperature.

* **Known errors** (no ``scatter``, as the trace fit, whose traces have tens of samples
  each): weights ``1 / se_i**2``, covariance ``(D^T W D)^-1``, the normal quantile 1.96,
  and a chi-square misfit test with (temperatures - 2) degrees of freedom: the limit of
  the above for ``nu_i -> infinity``.

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
from ecdsim.characterize import leastsq
from ecdsim.characterize.stats import (
    CONFIDENCE,
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
    student_t_ppf,
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
    quantile : the critical value used for the 95 % intervals; None with no covariance,
        and with per-temperature scatter (each combination has its own, from
        ``effective_dof``)
    temperatures : the temperatures fitted [degC]
    values : the per-temperature values fitted [N*m*s/rad or N*m]
    sigma : their standard errors used as weights (1 for an unweighted fit)
    weighted : True where the per-temperature standard errors were the weights
    chi_square : weighted sum of squared residuals [-] (plain sum when unweighted)
    dof : number of temperatures minus 2
    scatter_dof : degrees of freedom of the pooled per-temperature scatter the weights
        were scaled by (nu, module docstring); None where the errors were taken as known
        or the fit is unweighted
    error_components : with per-temperature scatter, each temperature's contribution to
        the parameters' errors, shape (temperatures, 2): row i is ``se_i`` times the
        derivative of the parameters with respect to value i [units in ``law.keys``];
        the covariance is ``error_components.T @ error_components``. None otherwise
    component_dof : degrees of freedom of each row's ``se_i`` (n_i - 2); None with it
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
    error_components: FloatArray | None = None
    component_dof: FloatArray | None = None

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
        if self.covariance is None:
            return None
        t = np.atleast_1d(as_float(temperature))
        g = self.law.jacobian(t, self.parameter_values, self.reference_temperature)
        if self.error_components is not None and self.component_dof is not None:
            se, quantile = _component_errors(g, self.error_components, self.component_dof)
        elif self.quantile is not None:
            se = np.sqrt(np.maximum(np.sum((g @ self.covariance) * g, axis=1), 0.0))
            quantile = np.full(se.shape, self.quantile)
        else:
            return None
        centre = np.atleast_1d(self(t))
        return centre - quantile * se, centre + quantile * se

    @property
    def effective_dof(self) -> list[float] | None:
        """Welch-Satterthwaite degrees of freedom of each parameter's interval; None
        where the intervals do not use per-temperature scatter."""
        if self.error_components is None or self.component_dof is None:
            return None
        return [float(d) for d in _satterthwaite(self.error_components.T, self.component_dof)]

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
            effective_dof=self.effective_dof,
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
        temperature; given (and none None), the weights use the pooled variance and the
        intervals each temperature's own, with Welch-Satterthwaite degrees of freedom
        (module docstring). None: the standard errors are taken as known.
    """
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

    result = leastsq.solve(residual, jacobian, x0)
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
    components: FloatArray | None = None
    component_dof: FloatArray | None = None
    if weighted:
        p_value = _misfit_p_value(chi_square, dof, pooled)
        scaled = p_value is not None and p_value < MISFIT_LEVEL
        covariance = stats.unscaled_covariance * (reduced if scaled else 1.0)
        quantile: float | None
        if scaled:
            quantile = t_quantile(dof)
        elif pooled is not None and scatter is not None:
            # Welch-Satterthwaite: each temperature's error with its own scatter.
            design = -jacobian(p)  # rows: d law / d parameters / sigma_i
            influence = stats.unscaled_covariance @ design.T / sigma  # d params / d y_i
            components = as_float((influence * np.array(errors, dtype=float)).T)
            component_dof = np.array([s.dof for s in scatter if s is not None], dtype=float)
            covariance = components.T @ components
            quantile = None
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
        parameters=_parameter_estimates(p, covariance, quantile, components, component_dof),
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
        error_components=components,
        component_dof=component_dof,
    )


def _satterthwaite(contributions: FloatArray, dof: FloatArray) -> FloatArray:
    """Welch-Satterthwaite dof of sums of independent variance terms, shape (m, k):
    ``(sum c_i**2)**2 / sum(c_i**4 / nu_i)`` over each row (Satterthwaite 1946,
    Biometrics Bulletin 2, 110-114, doi:10.2307/3002019)."""
    squares = np.atleast_2d(contributions) ** 2
    total = np.sum(squares, axis=1)
    spread = np.sum(squares**2 / dof, axis=1)
    safe = np.where(spread > 0.0, spread, 1.0)
    return as_float(np.where(spread > 0.0, total**2 / safe, np.sum(dof)))


def _component_errors(
    gradient: FloatArray, components: FloatArray, component_dof: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Standard error and 95 % critical value of combinations ``g . parameters``.

    ``gradient`` has one row per combination; the variance is ``sum_i (g . c_i)**2``
    over the per-temperature error components and the critical value Student t with the
    Welch-Satterthwaite dof of those terms.
    """
    contributions = np.atleast_2d(np.asarray(gradient, dtype=float)) @ components.T
    se = np.sqrt(np.sum(contributions**2, axis=1))
    dof = _satterthwaite(contributions, component_dof)
    return se, as_float(student_t_ppf(0.5 + CONFIDENCE / 2.0, dof))


def _parameter_estimates(
    values: FloatArray,
    covariance: FloatArray | None,
    quantile: float | None,
    components: FloatArray | None,
    component_dof: FloatArray | None,
) -> tuple[Estimate, ...]:
    """Each parameter with its standard error and 95 % interval."""
    if components is None or component_dof is None:
        return estimates(values, covariance, quantile)
    se, q = _component_errors(np.eye(values.size), components, component_dof)
    return tuple(
        Estimate(float(v), float(e), (float(v - k * e), float(v + k * e)))
        for v, e, k in zip(values, se, q, strict=True)
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
