"""Fit recorded deployments (angle against time) against the exact quasi-static solution.

A trace is the deployed angle phi(t) of a spring deployment, released from rest at
t = 0, phi = 0. The model is the core's exact solution of ``B dphi/dt = T_spring(phi) - F``
(:data:`ecdsim.solvers.EXACT` on a :class:`~ecdsim.solvers.QuasiStaticProblem`, no second
copy of the formula), with the spring and travel from a configuration file.

What one trace can tell. For a linear spring the solution is
``phi(t) = (a / k) * (1 - exp(-k t / B))`` with ``a = Ts - F`` and ``k = (Ts - Te) / L``:
the trace fixes ``a / B`` and ``k / B`` and nothing else. Multiplying every torque and B by
the same factor leaves the trace unchanged, so B, F and the spring torques cannot all be
fitted together, from any number of traces. Two fits are therefore offered:

* ``damper`` (default): BECD and the total friction F = FECD + FS_T per trace, the spring
  from the configuration. FECD is reported as F - FS_T with FS_T from the configuration.
* ``spring`` (``--fit-spring``): the spring's start and end torques at its reference
  temperature, jointly over all traces (with the configuration's spring temperature
  coefficient), BECD and the friction taken from the configuration's ECD and load.

Parameters are fitted by ``scipy.optimize.least_squares`` and then polished by
Gauss-Newton steps to the least-squares optimum itself (:func:`_polish`), so that the
answer does not depend on the path the solver took (nor on the CPU's BLAS kernels):
docs/reproducibility.md. Intervals come from the Jacobian at the solution,
``covariance = s**2 (J^T J)^-1`` with Student t (n - p dof).
The residuals of a recorded trace are usually correlated in time (resolver error,
vibration), which makes these intervals too narrow; the Durbin-Watson statistic is
reported and a value below 1 raises a warning.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np

from ecdsim._types import FloatArray, as_float
from ecdsim._version import __version__
from ecdsim.characterize.csvdata import (
    TIME,
    Column,
    Table,
    above_absolute_zero,
    non_negative,
    read_table,
    temperature_groups,
)
from ecdsim.characterize.droptest import FailedTemperature, law_warnings
from ecdsim.characterize.findings import FitWarning
from ecdsim.characterize.stats import (
    Estimate,
    Linearised,
    estimates,
    finite_or_none,
    linearised,
    t_quantile,
)
from ecdsim.characterize.templaws import TemperatureLaws, fit_temperature_laws
from ecdsim.config import Config
from ecdsim.config.units import ANGLE, TEMPERATURE
from ecdsim.jsonrows import RowTable
from ecdsim.model import LinearSpring, Load
from ecdsim.solvers import EXACT, QuasiStaticProblem

TRACE_COLUMNS = (
    Column("time", TIME, "time_s", check=non_negative("s")),
    Column("angle", ANGLE, "angle_rad"),
    Column("temperature", TEMPERATURE, "temperature_C", required=False, check=above_absolute_zero),
)
DEFAULT_TEMPERATURE = 25.0
# A Durbin-Watson statistic below this means strongly correlated residuals (2 = none).
CORRELATED_RESIDUALS = 1.0
# A trace reaching beyond the configured travel by more than this fraction is suspect.
TRAVEL_MARGIN = 0.02

Mode = Literal["damper", "spring"]


@dataclass(frozen=True)
class Trace:
    """One recorded deployment.

    Attributes
    ----------
    temperature : T [degC]
    rows : file row of each sample
    time : time since release [s], increasing
    angle : deployed angle [rad]
    """

    temperature: float
    rows: np.ndarray[Any, np.dtype[np.int64]]
    time: FloatArray
    angle: FloatArray


def problem_for(
    load: Load, temperature: float, damping_rate: float, friction: float
) -> QuasiStaticProblem:
    """The quasi-static problem of ``load`` at T [degC] with BECD [N*m*s/rad], F [N*m]."""
    angles, torques = load.drive.breakpoints(load.travel, temperature)
    return QuasiStaticProblem(
        angles=np.asarray(angles, dtype=float),
        torques=np.asarray(torques, dtype=float),
        friction=np.asarray(friction, dtype=float),
        damping_rate=np.asarray(damping_rate, dtype=float),
    )


def model_angle(problem: QuasiStaticProblem, times: FloatArray) -> FloatArray:
    """Deployed angle [rad] at the given times [s] by the exact solver."""
    return as_float(np.reshape(EXACT.trajectory(problem, times).angle, -1))


def durbin_watson(residuals: FloatArray) -> float | None:
    """``sum(diff(e)**2) / sum(e**2)`` of time-ordered residuals; None if all are zero.

    2 for uncorrelated residuals, towards 0 for positively correlated ones (J. Durbin and
    G. S. Watson, Biometrika 37, 1950).

    >>> round(durbin_watson(np.array([1.0, -1.0, 1.0, -1.0])), 12)
    3.0
    """
    e = np.asarray(residuals, dtype=float)
    total = float(np.sum(e * e))
    if total == 0.0:
        return None
    return float(np.sum(np.diff(e) ** 2)) / total


@dataclass(frozen=True)
class TraceCurve:
    """A trace with the fitted model's angle and the residual statistics.

    Attributes
    ----------
    trace : the recorded data
    problem : the fitted quasi-static problem (to redraw the model)
    fitted : model angle at the sample times [rad]
    r_squared : coefficient of determination of the angle [-]
    durbin_watson : residual autocorrelation statistic (2: none); None for an exact fit
    """

    trace: Trace
    problem: QuasiStaticProblem
    fitted: FloatArray
    r_squared: float
    durbin_watson: float | None

    @property
    def residuals(self) -> FloatArray:
        """Recorded minus model angle [rad]."""
        return as_float(self.trace.angle - self.fitted)

    @property
    def deployment_time(self) -> float:
        """The fitted model's deployment time [s]; inf where it stalls."""
        return float(np.reshape(EXACT.solve(self.problem).deployment_time, -1)[0])

    def to_dict(self, *, points_as_table: bool = False) -> dict[str, Any]:
        """Residual summary and points for JSON (``points_as_table``: as columns, a
        :class:`~ecdsim.jsonrows.RowTable` that :func:`ecdsim.jsonrows.write_json` streams).
        """
        e = self.residuals
        points = RowTable(
            {
                "row": self.trace.rows,
                "time_s": self.trace.time,
                "angle_rad": self.trace.angle,
                "residual_rad": e,
            }
        )
        return {
            "temperature_C": self.trace.temperature,
            "n_points": int(self.trace.time.size),
            "r_squared": self.r_squared,
            "rms_residual_rad": float(np.sqrt(np.mean(e * e))),
            "durbin_watson": self.durbin_watson,
            "fitted_deployment_time_s": finite_or_none(self.deployment_time),
            "points": points if points_as_table else points.records(),
        }


@dataclass(frozen=True)
class TraceFit:
    """BECD and friction fitted to one trace (``damper`` mode).

    Attributes
    ----------
    curve : data, model and residuals
    statistics : least-squares statistics (2 parameters)
    damping_rate : BECD [N*m*s/rad]
    total_friction : F = FECD + FS_T, all friction the trace sees [N*m]
    system_friction : FS_T from the configuration [N*m]
    friction : FECD = F - FS_T [N*m] (FS_T taken as exact)
    """

    curve: TraceCurve
    statistics: Linearised
    damping_rate: Estimate
    total_friction: Estimate
    system_friction: float
    friction: Estimate

    @property
    def temperature(self) -> float:
        """T [degC]."""
        return self.curve.trace.temperature

    def to_dict(self, *, points_as_table: bool = False) -> dict[str, Any]:
        """One entry of the ``temperatures`` list of the JSON document."""
        out = {
            "temperature_C": self.temperature,
            "n_points": self.statistics.n_points,
            **self.damping_rate.to_dict("damping_rate", "_Nms_per_rad"),
            **self.friction.to_dict("friction", "_Nm"),
            "total_friction_Nm": self.total_friction.value,
            "total_friction_ci95_Nm": self.total_friction.interval(),
            "system_friction_Nm": self.system_friction,
            "residual_std_rad": self.statistics.residual_std,
            "dof": self.statistics.dof,
        }
        out.update(self.curve.to_dict(points_as_table=points_as_table))
        return out


@dataclass(frozen=True)
class SpringFit:
    """Spring torques fitted jointly to every trace (``spring`` mode).

    Attributes
    ----------
    start_torque : Ts at the spring's reference temperature [N*m]
    end_torque : Te at the spring's reference temperature [N*m]
    reference_temperature : the spring's reference temperature [degC]
    statistics : joint least-squares statistics (2 parameters)
    curves : one per trace
    """

    start_torque: Estimate
    end_torque: Estimate
    reference_temperature: float
    statistics: Linearised
    curves: tuple[TraceCurve, ...]

    def to_dict(self) -> dict[str, Any]:
        """The ``spring`` entry of the JSON document."""
        ts, te = self.start_torque, self.end_torque
        return {
            "start_torque_Nm": ts.value,
            "start_torque_ci95_Nm": ts.interval(),
            "end_torque_Nm": te.value,
            "end_torque_ci95_Nm": te.interval(),
            "reference_temperature_C": self.reference_temperature,
            "n_points": self.statistics.n_points,
            "residual_std_rad": self.statistics.residual_std,
            "dof": self.statistics.dof,
        }


@dataclass(frozen=True)
class TraceResult:
    """Everything a trace fit found.

    Attributes
    ----------
    table : the data read (usable rows, bad-row report, notes)
    config : the configuration that gave the spring (and, in spring mode, the ECD)
    mode : "damper" or "spring"
    fits : damper mode: one fit per temperature, coldest first
    spring : spring mode: the joint spring fit
    failed : traces (or, in spring mode, the joint fit) that could not be fitted
    laws : damper mode with two or more temperatures: BECD(T) and FECD(T) laws
    reference_temperature : T_ref of the damping laws [degC]
    warnings : flags raised
    """

    table: Table
    config: Config
    mode: Mode
    fits: tuple[TraceFit, ...]
    spring: SpringFit | None
    failed: tuple[FailedTemperature, ...]
    laws: TemperatureLaws | None
    reference_temperature: float
    warnings: tuple[FitWarning, ...] = field(default=())

    @property
    def curves(self) -> tuple[TraceCurve, ...]:
        """Data and model of every fitted trace."""
        if self.spring is not None:
            return self.spring.curves
        return tuple(f.curve for f in self.fits)

    def to_dict(self, *, points_as_table: bool = False) -> dict[str, Any]:
        """The JSON document of ``ecdsim fit trace --json`` (docs/characterize.md).

        ``points_as_table``: points as streamable columns (:meth:`TraceCurve.to_dict`).
        """
        return {
            "ecdsim_version": __version__,
            "kind": "trace",
            "mode": self.mode,
            "source": self.table.source,
            "source_sha256": self.table.sha256,
            "config": self.config.source,
            "config_sha256": self.config.sha256,
            "reference_temperature_C": self.reference_temperature,
            "temperatures": (
                [f.to_dict(points_as_table=points_as_table) for f in self.fits]
                if self.spring is None
                else [c.to_dict(points_as_table=points_as_table) for c in self.spring.curves]
            ),
            "spring": self.spring.to_dict() if self.spring else None,
            "failed_temperatures": [f.to_dict() for f in self.failed],
            "temperature_laws": self.laws.to_dict() if self.laws else None,
            "bad_rows": [b.to_dict() for b in self.table.bad_rows],
            "excluded_rows": self.table.excluded_rows,
            "warnings": [w.to_dict() for w in self.warnings],
        }


class TraceFitError(ValueError):
    """A trace cannot be fitted; the message says why."""


def read_traces(
    path: str | Path, temperature: float | None = None
) -> tuple[Table, list[Trace], list[FitWarning]]:
    """Read a trace CSV file and split it into one trace per temperature.

    Without a ``temperature_C`` column every row belongs to one trace at ``temperature``
    (or 25 degC, with a warning, where that is None too).
    """
    table = read_table(path, TRACE_COLUMNS)
    warnings = [FitWarning("ignored_column", note) for note in table.notes]
    v = table.values
    if table.has("temperature"):
        if temperature is not None:
            warnings.append(
                FitWarning(
                    "temperature_ignored",
                    f"the file has a temperature column; --temperature {temperature:g} is ignored",
                )
            )
        groups = temperature_groups(v["temperature"])
    else:
        if temperature is None:
            temperature = DEFAULT_TEMPERATURE
            warnings.append(
                FitWarning(
                    "temperature_assumed",
                    f"no temperature column and no --temperature: the trace is taken to be at "
                    f"{DEFAULT_TEMPERATURE:g} degC",
                )
            )
        groups = [(temperature, np.arange(table.rows.size))]
    traces = []
    for temp, members in groups:
        order = members[np.argsort(v["time"][members], kind="stable")]
        traces.append(Trace(temp, table.rows[order], v["time"][order], v["angle"][order]))
    return table, traces, warnings


# The Jacobian's step, a fraction of each parameter's scale. Five-point central
# differences err by about h**4 |f^(5)| / 30 (truncation) plus 1.5 eps |f| / h (round-off,
# eps = 2.2e-16): at h = 1e-4 both are about 1e-12 of the derivative, against 1e-10 for
# the three-point formula at its best step. That error is what leaves the Gauss-Newton
# fixed point uncertain, so it sets the digits the fit reproduces (docs/reproducibility.md).
JACOBIAN_STEP = 1e-4
# Gauss-Newton polish: stop when a step is below this fraction of the parameters' scale
# (the fixed point's round-off, measured 1e-14 to 2e-12 on the shipped traces) ...
POLISH_STEP = 1e-12
# ... or after this many steps (from the solver's answer two or three steps reach it).
POLISH_STEPS = 8


def _central_jacobian(
    model: Callable[[FloatArray], FloatArray], p: FloatArray, scale: FloatArray
) -> FloatArray:
    """d model / d p by five-point central differences, steps JACOBIAN_STEP of the scale."""
    columns = []
    for i in range(p.size):
        step = np.zeros_like(p)
        step[i] = JACOBIAN_STEP * scale[i]
        near = model(p + step) - model(p - step)
        far = model(p + 2.0 * step) - model(p - 2.0 * step)
        columns.append((8.0 * near - far) / (12.0 * step[i]))
    return np.column_stack(columns)


def _polish(
    model: Callable[[FloatArray], FloatArray],
    observed: FloatArray,
    p: FloatArray,
    lower: FloatArray,
    scale: FloatArray,
) -> FloatArray:
    """Gauss-Newton steps from the solver's answer ``p`` to the least-squares optimum.

    ``least_squares`` stops when its cost changes by less than ``ftol`` of itself; the
    cost is flat at the optimum, so that leaves the parameters about sqrt(ftol) away from
    it, at a point that depends on the path (measured: 1e-9 relative, differing between
    BLAS kernels). Gauss-Newton steps with an accurate Jacobian converge to the optimum
    itself (the fixed point ``J^T r = 0``); a step that would raise the cost beyond
    round-off, cross a bound or leave the finite numbers ends the polish at the last point.
    """
    r = observed - model(p)
    cost = float(r @ r)
    previous = math.inf
    for _ in range(POLISH_STEPS):
        step = np.linalg.lstsq(_central_jacobian(model, p, scale), r, rcond=None)[0]
        size = float(np.max(np.abs(step) / scale))
        trial = p + step
        if not (np.all(np.isfinite(trial)) and np.all(trial >= lower)):
            break
        r_trial = observed - model(trial)
        trial_cost = float(r_trial @ r_trial)
        if not math.isfinite(trial_cost) or trial_cost > cost * (1.0 + 1e-12):
            break
        p, r, cost = trial, r_trial, trial_cost
        if size <= POLISH_STEP or size >= previous:
            break  # converged, or at the fixed point's round-off
        previous = size
    return p


def _least_squares(
    model: Callable[[FloatArray], FloatArray],
    observed: FloatArray,
    x0: FloatArray,
    lower: FloatArray,
) -> tuple[FloatArray, Linearised]:
    """Fit ``observed = model(p)``; the solution and its linearised statistics."""
    from scipy.optimize import least_squares

    if not (np.all(np.isfinite(x0)) and float(np.max(np.abs(x0))) > 0.0):
        # A zero start torque (a valid config, issue 11 item 2) drives nothing: there is
        # no motion of the configured load to fit the damper against.
        raise TraceFitError(
            "the configuration's load gives no drive torque, so there is nothing to fit the "
            "trace against (is [load] start_torque 0?)"
        )
    scale = np.maximum(np.abs(x0), 1e-3 * float(np.max(np.abs(x0))))
    result = least_squares(
        lambda p: model(p) - observed,
        x0,
        jac="3-point",
        bounds=(lower, np.full_like(x0, np.inf)),
        x_scale=scale,
        method="trf",
        xtol=1e-13,
        ftol=1e-13,
        gtol=1e-13,
        max_nfev=500,
    )
    if not result.success:
        raise TraceFitError(f"the least-squares fit did not converge ({result.message})")
    p = _polish(model, observed, np.asarray(result.x, dtype=float), lower, scale)
    if np.any((lower > 0.0) & (p <= lower * (1.0 + 1e-9))):
        raise TraceFitError("the fit ran into a bound (a torque or damping rate <= 0)")
    design = _central_jacobian(model, p, scale)
    try:
        stats = linearised(design, observed - model(p), observed)
    except np.linalg.LinAlgError:
        raise TraceFitError(
            "the trace cannot tell the parameters apart (is the spring torque constant over "
            "the travel? then only (torque - friction) / damping is seen)"
        ) from None
    return p, stats


def _curve(trace: Trace, problem: QuasiStaticProblem) -> TraceCurve:
    fitted = model_angle(problem, trace.time)
    e = trace.angle - fitted
    total = float(np.sum((trace.angle - np.mean(trace.angle)) ** 2))
    r_squared = 1.0 - float(np.sum(e * e)) / total if total > 0.0 else math.nan
    return TraceCurve(trace, problem, fitted, r_squared, durbin_watson(e))


def _check_trace(trace: Trace, n_parameters: int) -> None:
    if trace.time.size <= n_parameters:
        raise TraceFitError(
            f"{trace.time.size} sample(s): more than {n_parameters} are needed to fit "
            f"{n_parameters} parameters with an uncertainty"
        )
    if np.unique(trace.time).size < 2 or float(np.ptp(trace.angle)) <= 0.0:
        raise TraceFitError("the trace does not move (one time, or a constant angle)")


def initial_damper_guess(trace: Trace, load: Load, config: Config) -> tuple[float, float]:
    """A starting (BECD, F) for a damper fit, from the trace's start.

    Near t = 0 the exact solution is ``phi = w0 t - (k w0 / B) t**2 / 2 + ...`` with
    ``w0 = (Ts - F) / B`` and k the spring's torque drop per radian; a quadratic fitted to
    the first 80 % of the travel gives B and F. Falls back to the configuration's ECD.
    """
    angles, torques = load.drive.breakpoints(load.travel, trace.temperature)
    start, end = float(np.ravel(torques)[0]), float(np.ravel(torques)[-1])
    travel = float(np.ravel(angles)[-1])
    moving = np.ptp(trace.time) > 0.0
    mean_speed = float(np.ptp(trace.angle) / np.ptp(trace.time)) if moving else 0.0
    ecd = config.system.ecd.at(trace.temperature)
    fs = float(load.system_friction(trace.temperature))
    fallback = (float(ecd.ecd_damping_rate), float(ecd.ecd_friction) + fs)
    if not (math.isfinite(fallback[0]) and fallback[0] > 0.0 and fallback[1] < start):
        # The configuration's ECD is no help here: half the start torque against friction.
        fallback = (0.5 * start / max(mean_speed, 1e-12), 0.5 * start)
    early = (trace.angle < 0.8 * travel) & (trace.time > 0.0)
    k = (start - end) / travel
    if np.count_nonzero(early) < 3 or k <= 0.0:
        return fallback
    t = trace.time[early]
    c1, c2 = np.linalg.lstsq(np.column_stack([t, t * t]), trace.angle[early], rcond=None)[0]
    if c1 <= 0.0 or c2 >= 0.0:
        return fallback
    b = -k * c1 / (2.0 * c2)
    friction = start - b * c1
    return (float(b), float(friction)) if friction < start else fallback


def fit_damper_trace(trace: Trace, config: Config) -> TraceFit:
    """Fit BECD and the total friction to one trace, the spring from ``config``.

    Raises :class:`TraceFitError` where the trace cannot be fitted.
    """
    _check_trace(trace, 2)
    load = config.system.load
    temperature = trace.temperature

    def model(p: FloatArray) -> FloatArray:
        return model_angle(problem_for(load, temperature, p[0], p[1]), trace.time)

    x0 = np.array(initial_damper_guess(trace, load, config))
    p, stats = _least_squares(model, trace.angle, x0, np.array([1e-9 * x0[0], -np.inf]))
    quantile = t_quantile(stats.dof) if stats.dof > 0 else None
    damping, total = estimates(p, stats.covariance, quantile)
    fs = float(load.system_friction(temperature))
    friction = Estimate(
        total.value - fs,
        total.standard_error,
        (total.ci95[0] - fs, total.ci95[1] - fs) if total.ci95 else None,
    )
    curve = _curve(trace, problem_for(load, temperature, p[0], p[1]))
    return TraceFit(curve, stats, damping, total, fs, friction)


def fit_spring_traces(traces: list[Trace], config: Config) -> SpringFit:
    """Fit the linear spring's reference torques jointly to every trace.

    BECD(T) and the total friction FECD(T) + FS_T come from ``config``. Raises
    :class:`TraceFitError` where the configuration's spring is not linear or the fit fails.
    """
    load = config.system.load
    spring = load.spring
    if not isinstance(spring, LinearSpring):
        raise TraceFitError(
            "--fit-spring needs a linear spring (load.start_torque and load.end_torque) in "
            "the configuration; a spring_table cannot be fitted"
        )
    for trace in traces:
        _check_trace(trace, 2)
    known = []
    for trace in traces:
        ecd = config.system.ecd.at(trace.temperature)
        fs = float(load.system_friction(trace.temperature))
        known.append((float(ecd.ecd_damping_rate), float(ecd.ecd_friction) + fs))

    def problems(p: FloatArray) -> list[QuasiStaticProblem]:
        fitted_load = replace(load, spring=replace(spring, start_torque=p[0], end_torque=p[1]))
        return [
            problem_for(fitted_load, trace.temperature, b, f)
            for trace, (b, f) in zip(traces, known, strict=True)
        ]

    def model(p: FloatArray) -> FloatArray:
        return np.concatenate(
            [model_angle(q, t.time) for q, t in zip(problems(p), traces, strict=True)]
        )

    observed = np.concatenate([t.angle for t in traces])
    x0 = np.array([float(spring.start_torque), float(spring.end_torque)])
    p, stats = _least_squares(model, observed, x0, np.array([1e-9 * x0[0], 0.0]))
    quantile = t_quantile(stats.dof) if stats.dof > 0 else None
    start, end = estimates(p, stats.covariance, quantile)
    curves = tuple(_curve(t, q) for t, q in zip(traces, problems(p), strict=True))
    return SpringFit(start, end, spring.reference_temperature, stats, curves)


def fit_traces(
    path: str | Path,
    config: Config,
    mode: Mode = "damper",
    temperature: float | None = None,
    reference_temperature: float = 25.0,
) -> TraceResult:
    """Read a trace CSV file and fit it against the exact solution (see module docstring).

    Raises :class:`~ecdsim.config.ConfigError` for an unreadable file or one with no
    usable row; traces that cannot be fitted are reported in ``failed``.

    Parameters
    ----------
    path : the CSV file (``time_s``, ``angle_rad``, optionally ``temperature_C``)
    config : the configuration giving the spring and travel (and, in spring mode, the ECD)
    mode : "damper" (fit BECD and friction) or "spring" (fit the spring torques)
    temperature : temperature of a file without a temperature column [degC]
    reference_temperature : T_ref of the damping laws [degC]
    """
    gravity = config.system.load.gravity
    if gravity is not None and bool(np.any(gravity.amplitude > 0.0)):
        from ecdsim.config.errors import ConfigError

        # The trace model is the piecewise-linear exact solution; a sine drive would be
        # fitted as if absent, and the damper would absorb gravity's torque unseen.
        raise ConfigError(
            [
                "load.gravity: the trace fit does not model gravity; fit a trace of an "
                "offloaded (flight-like) test with a config without [load.gravity], or "
                "offload = 1"
            ],
            config.source,
        )
    table, traces, warnings = read_traces(path, temperature)
    travel = float(np.max(config.system.load.travel))
    for trace in traces:
        reach = float(np.max(trace.angle))
        if reach > travel * (1.0 + TRAVEL_MARGIN):
            warnings.append(
                FitWarning(
                    "beyond_travel",
                    f"{trace.temperature:g} degC: the trace reaches {reach:.4g} rad, beyond the "
                    f"configured travel {travel:.4g} rad",
                    trace.temperature,
                )
            )
    fits: list[TraceFit] = []
    failed: list[FailedTemperature] = []
    spring: SpringFit | None = None
    if mode == "spring":
        try:
            spring = fit_spring_traces(traces, config)
        except TraceFitError as exc:
            temps = ", ".join(f"{t.temperature:g}" for t in traces)
            rows = tuple(int(r) for t in traces for r in t.rows)
            failed.append(FailedTemperature(traces[0].temperature, rows, f"({temps} degC) {exc}"))
        curves: tuple[TraceCurve, ...] = spring.curves if spring else ()
    else:
        for trace in traces:
            try:
                fits.append(fit_damper_trace(trace, config))
            except TraceFitError as exc:
                rows = tuple(int(r) for r in trace.rows)
                failed.append(FailedTemperature(trace.temperature, rows, str(exc)))
        curves = tuple(f.curve for f in fits)
    for curve in curves:
        dw = curve.durbin_watson
        if dw is not None and dw < CORRELATED_RESIDUALS and not _exact(curve):
            warnings.append(
                FitWarning(
                    "correlated_residuals",
                    f"{curve.trace.temperature:g} degC: the residuals are correlated in time "
                    f"(Durbin-Watson {dw:.2f}); the model misses a systematic effect and the "
                    "intervals are too narrow",
                    curve.trace.temperature,
                )
            )
    laws = None
    if len(fits) >= 2:
        laws = fit_temperature_laws(
            [f.temperature for f in fits],
            [_law_input(f.damping_rate, f) for f in fits],
            [_law_input(f.friction, f) for f in fits],
            reference_temperature,
        )
        warnings.extend(law_warnings(laws))
    return TraceResult(
        table=table,
        config=config,
        mode=mode,
        fits=tuple(fits),
        spring=spring,
        failed=tuple(failed),
        laws=laws,
        reference_temperature=reference_temperature,
        warnings=tuple(warnings),
    )


def _exact(curve: TraceCurve) -> bool:
    e = curve.residuals
    return float(np.sqrt(np.mean(e * e))) <= 1e-9 * float(np.max(np.abs(curve.trace.angle)))


def _law_input(estimate: Estimate, fit: TraceFit) -> Estimate:
    """Drop round-off standard errors of an exact fit (see droptest.law_input)."""
    return Estimate(estimate.value, None, None) if fit.statistics.exact else estimate
