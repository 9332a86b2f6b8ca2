"""A fluid damper's power law fitted to bench data, the way the ECD's drop tests are.

Torque-speed points at several temperatures (a CSV: ``temperature``, ``speed``,
``torque``, any unit in brackets) are reduced in two steps, as docs/characterize.md
reduces drop tests (docs/qualification.md, section 3):

1. **One line per temperature**, in logarithms: the power law ``T = T_r (w / w_r)**n`` is
   ``ln T = ln T_r + n ln(w / w_r)``, fitted by ordinary least squares
   (:func:`ecdsim.characterize.linefit.fit_line`): n and ``ln T_r`` with Student-t 95 %
   intervals, R^2, the bending test (a log-log line that bends is not a power law) and
   the outlier test. Residuals in logarithms are relative torque errors: the scatter is
   taken as a constant fraction of the torque (a load cell's percentage accuracy).
   ``w_r`` is a reference speed inside the tested range (a power of ten near the middle
   by default), where ``T_r`` is well determined and nearly uncorrelated with n.
2. **Laws over temperature** (:func:`ecdsim.characterize.templaws.fit_law`, the same
   weighting by the pooled scatter and Welch-Satterthwaite intervals as the ECD's laws):
   ``ln T_r(T) = ln T_r,ref + B (1/T_K - 1/T_ref,K)`` (Arrhenius-Andrade) and
   ``n(T) = n_ref + s (T - T_ref)``.

The result is the ``[fluid_damper.power_law]`` section (:func:`fluid_damper_text`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, as_float
from ecdsim._version import __version__
from ecdsim.characterize.csvdata import (
    Column,
    Table,
    above_absolute_zero,
    positive,
    read_table,
    temperature_groups,
)
from ecdsim.characterize.findings import FitWarning
from ecdsim.characterize.linefit import LineFit, LineFitError, fit_line
from ecdsim.characterize.stats import Estimate
from ecdsim.characterize.templaws import Law, LawFit, LawFitError, _weighted_line, fit_law
from ecdsim.config.units import SPEED, TEMPERATURE, TORQUE

KELVIN_OFFSET = 273.15

COLUMNS = (
    Column("temperature", TEMPERATURE, "temperature_C", required=False,
           check=above_absolute_zero),
    Column("speed", SPEED, "speed_rad_s", check=positive("rad/s")),
    Column("torque", TORQUE, "torque_Nm", check=positive("N*m")),
)  # fmt: skip


def _inverse_kelvin(t: FloatArray, t_ref: float) -> FloatArray:
    return as_float(1.0 / (t + KELVIN_OFFSET) - 1.0 / (t_ref + KELVIN_OFFSET))


def _line_in(x_of: Any) -> Any:
    def initial(t: FloatArray, y: FloatArray, w: FloatArray, t_ref: float) -> FloatArray:
        return np.array(_weighted_line(x_of(t, t_ref), y, w))

    return initial


ARRHENIUS = Law(
    name="arrhenius",
    formula="ln T_r(T) = ln T_r,ref + B * (1/T_K - 1/T_ref,K)",
    keys=("log_torque_ref", "activation_K"),
    evaluate=lambda t, p, t_ref: as_float(p[0] + p[1] * _inverse_kelvin(t, t_ref)),
    jacobian=lambda t, p, t_ref: np.column_stack([np.ones_like(t), _inverse_kelvin(t, t_ref)]),
    initial=_line_in(_inverse_kelvin),
)
EXPONENT_LINE = Law(
    name="exponent",
    formula="n(T) = n_ref + s * (T - T_ref)",
    keys=("exponent_ref", "exponent_slope_per_K"),
    evaluate=lambda t, p, t_ref: as_float(p[0] + p[1] * (t - t_ref)),
    jacobian=lambda t, p, t_ref: np.column_stack([np.ones_like(t), t - t_ref]),
    initial=_line_in(lambda t, t_ref: as_float(t - t_ref)),
)


def default_reference_speed(speeds: ArrayLike) -> float:
    """A power of ten near the middle of the tested speeds (in logarithms) [rad/s].

    >>> default_reference_speed([0.01, 0.03, 0.3, 1.0])
    0.1
    """
    middle = float(np.mean(np.log10(as_float(speeds))))
    return float(10.0 ** round(middle))


@dataclass(frozen=True)
class FluidTemperatureFit:
    """The power law at one temperature.

    Attributes
    ----------
    temperature : T [degC]
    rows : file rows of its points
    speed, torque : the points [rad/s, N*m]
    line : the fit of ln T on ln(w / w_r): intercept ln T_r, slope n
    reference_speed : w_r [rad/s]
    """

    temperature: float
    rows: tuple[int, ...]
    speed: FloatArray
    torque: FloatArray
    line: LineFit
    reference_speed: float

    @property
    def exponent(self) -> Estimate:
        """n with its 95 % interval [-]."""
        return self.line.slope

    @property
    def reference_torque(self) -> Estimate:
        """T_r = exp(ln T_r) [N*m], its interval the exponentials of ln T_r's (its
        standard error the delta method's, T_r * se(ln T_r))."""
        log = self.line.intercept
        value = math.exp(log.value)
        se = None if log.standard_error is None else value * log.standard_error
        ci = None if log.ci95 is None else (math.exp(log.ci95[0]), math.exp(log.ci95[1]))
        return Estimate(value, se, ci)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (SI)."""
        line = self.line
        curvature = line.curvature
        return {
            "temperature_C": self.temperature,
            "n_points": line.n_points,
            "rows": list(self.rows),
            **self.exponent.to_dict("exponent"),
            **self.reference_torque.to_dict("torque_at_reference", "_Nm"),
            "r_squared_log": line.r_squared,
            "relative_scatter": line.statistics.residual_std,
            "bending": None if curvature is None else curvature.bending,
            "curvature_p_value": None if curvature is None else curvature.p_value,
            "outlier_rows": [int(r) for r, o in zip(self.rows, line.outliers, strict=True) if o],
            "points": [
                {"speed_rad_s": float(w), "torque_Nm": float(t)}
                for w, t in zip(self.speed, self.torque, strict=True)
            ],
        }


@dataclass(frozen=True)
class FluidFitResult:
    """Everything a fluid-damper bench reduction found.

    Attributes
    ----------
    table : the data read
    reference_speed : w_r [rad/s]
    reference_temperature : T_ref of the laws [degC]
    fits : one power law per temperature, coldest first
    failed : (temperature, rows, reason) of temperatures that could not be fitted
    torque_law : ln T_r(T) (Arrhenius-Andrade); None with fewer than two temperatures
    exponent_law : n(T); None likewise
    warnings : flags (bending, outliers, extrapolation, a law not fitted)
    """

    table: Table
    reference_speed: float
    reference_temperature: float
    fits: tuple[FluidTemperatureFit, ...]
    failed: tuple[tuple[float, tuple[int, ...], str], ...]
    torque_law: LawFit | None
    exponent_law: LawFit | None
    warnings: tuple[FitWarning, ...]

    def law_constants(self) -> dict[str, float]:
        """The ``[fluid_damper.power_law]`` constants (SI): torque at w_r and T_ref,
        exponent and its slope, activation B; with one temperature, that temperature's
        law and no temperature dependence."""
        if self.torque_law is not None and self.exponent_law is not None:
            log_torque, activation = self.torque_law.parameter_values
            exponent, slope = self.exponent_law.parameter_values
            return {
                "torque": math.exp(float(log_torque)),
                "activation": float(activation),
                "exponent": float(exponent),
                "exponent_slope": float(slope),
            }
        fit = self.fits[0]
        return {
            "torque": fit.reference_torque.value,
            "activation": 0.0,
            "exponent": fit.exponent.value,
            "exponent_slope": 0.0,
        }

    def torque_ratio(self, cold: float, hot: float) -> float:
        """How many times the damping torque at w_r is at ``cold`` that at ``hot`` [degC],
        by the fitted law (exp(B (1/T_cold - 1/T_hot)))."""
        activation = self.law_constants()["activation"]
        return math.exp(activation * (1.0 / (cold + KELVIN_OFFSET) - 1.0 / (hot + KELVIN_OFFSET)))

    def to_dict(self) -> dict[str, Any]:
        """The JSON document of ``ecdsim fit fluid-damper --json`` (docs/qualification.md)."""
        temps = [f.temperature for f in self.fits]
        return {
            "ecdsim_version": __version__,
            "kind": "fluid_damper",
            "source": self.table.source,
            "source_sha256": self.table.sha256,
            "reference_speed_rad_s": self.reference_speed,
            "reference_temperature_C": self.reference_temperature,
            "temperatures": [f.to_dict() for f in self.fits],
            "failed_temperatures": [
                {"temperature_C": t, "rows": list(rows), "error": why}
                for t, rows, why in self.failed
            ],
            "torque_law": None if self.torque_law is None else self.torque_law.to_dict(),
            "exponent_law": None if self.exponent_law is None else self.exponent_law.to_dict(),
            "power_law": self.law_constants(),
            "cold_to_hot_torque_ratio": (
                self.torque_ratio(min(temps), max(temps)) if len(temps) >= 2 else None
            ),
            "bad_rows": [b.to_dict() for b in self.table.bad_rows],
            "warnings": [w.to_dict() for w in self.warnings],
        }


def read_fluid_bench(path: str | Path) -> Table:
    """The usable rows of a fluid-damper bench CSV (ConfigError for a file that cannot be
    used)."""
    return read_table(path, COLUMNS)


def fit_temperature(
    temperature: float,
    rows: Sequence[int],
    speed: ArrayLike,
    torque: ArrayLike,
    reference_speed: float,
) -> FluidTemperatureFit:
    """One temperature's power law (step 1 of the module docstring); LineFitError where
    the points cannot define it."""
    w = as_float(speed)
    t = as_float(torque)
    line = fit_line(np.log(w / reference_speed), np.log(t))
    return FluidTemperatureFit(
        temperature, tuple(int(r) for r in rows), w, t, line, reference_speed
    )


def fit_fluid(
    temperatures: ArrayLike,
    speeds: ArrayLike,
    torques: ArrayLike,
    rows: ArrayLike,
    table: Table,
    reference_speed: float | None = None,
    reference_temperature: float = 25.0,
) -> FluidFitResult:
    """Both steps of the module docstring on points in SI (temperatures in degC)."""
    temps = as_float(temperatures)
    w = as_float(speeds)
    torque = as_float(torques)
    row_numbers = np.asarray(rows)
    speed_ref = default_reference_speed(w) if reference_speed is None else reference_speed
    fits: list[FluidTemperatureFit] = []
    failed: list[tuple[float, tuple[int, ...], str]] = []
    warnings: list[FitWarning] = []
    for temperature, members in temperature_groups(temps):
        group_rows = tuple(int(r) for r in row_numbers[members])
        try:
            fit = fit_temperature(temperature, group_rows, w[members], torque[members], speed_ref)
        except LineFitError as exc:
            failed.append((temperature, group_rows, str(exc)))
            continue
        fits.append(fit)
        warnings.extend(_flags(fit))
    if not (w.min() <= speed_ref <= w.max()):
        warnings.append(
            FitWarning(
                "reference_speed_outside",
                f"the reference speed {speed_ref:g} rad/s lies outside the tested speeds "
                f"({w.min():.4g} to {w.max():.4g} rad/s): T_r is extrapolated",
            )
        )
    torque_law = exponent_law = None
    if len(fits) >= 2:
        temps_fitted = [f.temperature for f in fits]
        scatter = [f.line.statistics.scatter for f in fits]
        for name in ("torque", "exponent"):
            law, values = (
                (ARRHENIUS, [f.line.intercept for f in fits])
                if name == "torque"
                else (EXPONENT_LINE, [f.line.slope for f in fits])
            )
            try:
                fitted = fit_law(law, temps_fitted, values, reference_temperature, scatter=scatter)
            except LawFitError as exc:
                warnings.append(FitWarning(f"{name}_law", f"the {name} law: {exc}"))
                continue
            if name == "torque":
                torque_law = fitted
            else:
                exponent_law = fitted
    elif fits:
        warnings.append(
            FitWarning(
                "one_temperature",
                "one temperature only: no law over temperature (activation 0, exponent "
                "constant); test at two or more temperatures",
            )
        )
    return FluidFitResult(
        table=table,
        reference_speed=speed_ref,
        reference_temperature=reference_temperature,
        fits=tuple(fits),
        failed=tuple(failed),
        torque_law=torque_law,
        exponent_law=exponent_law,
        warnings=tuple(warnings),
    )


def _flags(fit: FluidTemperatureFit) -> list[FitWarning]:
    out = []
    curvature = fit.line.curvature
    t = fit.temperature
    if curvature is not None and curvature.bending:
        out.append(
            FitWarning(
                "not_a_power_law",
                f"at {t:g} degC the log-log points bend (p = {curvature.p_value:.2g}): the "
                "torque is not a power of the speed over the tested range",
                t,
            )
        )
    if fit.line.outliers.any():
        rows = [r for r, o in zip(fit.rows, fit.line.outliers, strict=True) if o]
        out.append(FitWarning("outlier", f"at {t:g} degC rows {rows} are outliers (kept)", t))
    return out


def fit_fluid_bench(
    path: str | Path, reference_speed: float | None = None, reference_temperature: float = 25.0
) -> FluidFitResult:
    """Read and reduce a fluid-damper bench CSV (module docstring)."""
    table = read_fluid_bench(path)
    temps = table.values.get("temperature")
    speeds = table.values["speed"]
    warnings: list[FitWarning] = []
    if temps is None:
        temps = as_float(np.full(speeds.shape, reference_temperature))
        warnings.append(
            FitWarning(
                "no_temperature",
                f"no temperature column: the points are taken at {reference_temperature:g} degC",
            )
        )
    result = fit_fluid(
        temps, speeds, table.values["torque"], table.rows, table, reference_speed,
        reference_temperature,
    )  # fmt: skip
    if warnings:
        from dataclasses import replace

        result = replace(result, warnings=(*warnings, *result.warnings))
    return result
