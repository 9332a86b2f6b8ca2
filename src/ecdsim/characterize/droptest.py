"""Drop-test reduction (paper section 7, Figure 7): masses on a flywheel turn the damper.

A mass m hangs from a string wound on a flywheel of radius r on the ECD's input shaft;
released from rest, it turns the shaft through an angle theta in a time t. At steady
speed the damper's torque balances the weight's::

    torque = m * g * r - F_rig                          (F_rig: the rig's own friction)
    speed  = theta / t                                   (steady state, the paper's reading)

and the points of one temperature lie on the line ``torque = FECD + BECD * speed``
(Eq. 5). Released from rest, the shaft first accelerates. With the total inertia
``J = J_rig + m r**2`` (the falling mass acts as ``m r**2`` at the shaft), constant
torque against linear damping and Coulomb friction gives (derivation in
``docs/characterize.md``)::

    J dw/dt = torque - FECD - BECD * w
    w(t)     = w_ss * (1 - exp(-t / tau)),   tau = J / BECD,  w_ss = (torque - FECD) / BECD
    theta(t) = w_ss * (t - lag),             lag = tau * (1 - exp(-t / tau))

so the steady speed is ``theta / (t - lag)``, not ``theta / t``. Because ``lag`` depends
on BECD, the line and the correction are fitted together by non-linear least squares:
the model torque of a point is ``FECD + BECD * theta / (t - lag(BECD))``. The fit starts
from the plain line of the steady-state speeds and reports each point's speed correction.
The inertia used is the ``rig_inertia_kg_m2`` column plus ``m r**2``; the damper's own
rotor inertia (reflected: J_rotor * N**2) is unknown before the test and belongs in that
column when known. Without the column no correction is made (the paper's steady-state
reading), and a warning says how large the falling mass alone would make it.

Where the scatter lies is a choice (:data:`NOISE_MODELS`, docs/characterize.md section 1):

* ``torque`` (the default): the torque carries independent, equal-variance errors (the
  rig's friction varying from drop to drop, a mass known to a few grams) and the speeds
  are exact: the line above, by (non-linear) least squares in torque;
* ``timing``: the masses and the radius are known precisely and the recorded time carries
  a relative error (a stopwatch or a light gate triggered with a delay proportional to
  the drop). Then ``log t`` carries equal-variance errors and the torque is exact, so the
  fit is least squares of ``log t_i`` against the model's drop time
  ``t(torque_i; FECD, BECD, J_i)`` (:func:`drop_time`): the residuals are the drops'
  relative timing errors, the speed errors neither dilute the slope nor make the
  torque-space scatter grow with speed, and the intervals hold for that noise.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, as_float
from ecdsim._version import __version__
from ecdsim.characterize import leastsq
from ecdsim.characterize.csvdata import (
    INERTIA,
    LENGTH,
    MASS,
    TIME,
    Column,
    Table,
    above_absolute_zero,
    non_negative,
    positive,
    read_table,
    temperature_groups,
)
from ecdsim.characterize.findings import FitWarning
from ecdsim.characterize.linefit import (
    LineFit,
    LineFitError,
    check_line_data,
    fit_line,
    summarise_line,
)
from ecdsim.characterize.noisecheck import Group, NoiseCheck, check_noise_model
from ecdsim.characterize.stats import Estimate, linearised
from ecdsim.characterize.templaws import (
    MISFIT_LEVEL,
    LawFit,
    TemperatureLaws,
    fit_temperature_laws,
)
from ecdsim.config.units import ANGLE, TEMPERATURE, TORQUE
from ecdsim.jsonrows import RowTable

STANDARD_GRAVITY = 9.80665  # m/s**2, the conventional value (3rd CGPM, 1901)
# A start-up correction above this fraction of a speed makes the result lean on the
# inertia being right: say so.
LARGE_CORRECTION = 0.05
# Below this the falling mass's own start-up transient is not worth a warning.
NOTABLE_CORRECTION = 0.01
# The timing-noise fit keeps FECD below every drive torque by this fraction of the largest
# (the model's drop time is infinite at FECD = torque).
FRICTION_CEILING = 1e-9

DROP_TEST_COLUMNS = (
    Column("temperature", TEMPERATURE, "temperature_C", check=above_absolute_zero),
    Column("mass", MASS, "mass_kg", check=positive("kg")),
    Column("radius", LENGTH, "radius_m", check=positive("m")),
    Column("angle", ANGLE, "angle_rad", check=positive("rad")),
    Column("time", TIME, "time_s", check=positive("s")),
    Column("rig_friction", TORQUE, "rig_friction_Nm", required=False, check=non_negative("N*m")),
    Column(
        "rig_inertia",
        INERTIA,
        "rig_inertia_kg_m2",
        required=False,
        check=non_negative("kg*m^2"),
    ),
)


def drive_torque(
    mass: ArrayLike,
    radius: ArrayLike,
    rig_friction: ArrayLike = 0.0,
    gravity: float = STANDARD_GRAVITY,
) -> FloatArray:
    """Torque a falling mass applies to the damper (paper section 7): ``m g r - F_rig``.

    Parameters
    ----------
    mass : the falling mass m [kg]
    radius : flywheel (string) radius r [m]
    rig_friction : the rig's own Coulomb friction F_rig [N*m]
    gravity : acceleration of gravity g [m/s**2]

    >>> round(float(drive_torque(2.0, 0.05, 0.01)), 12)  # 2 * 9.80665 * 0.05 - 0.01
    0.970665
    """
    return as_float(
        np.asarray(mass, dtype=float) * gravity * np.asarray(radius, dtype=float)
        - np.asarray(rig_friction, dtype=float)
    )


def falling_mass_inertia(mass: ArrayLike, radius: ArrayLike) -> FloatArray:
    """Inertia of the falling mass seen at the shaft: ``m r**2`` (start-up, section 1 of
    docs/characterize.md).

    Parameters
    ----------
    mass : the falling mass m [kg]
    radius : flywheel (string) radius r [m]
    """
    r = np.asarray(radius, dtype=float)
    return as_float(np.asarray(mass, dtype=float) * r * r)


def steady_speed(angle: ArrayLike, time: ArrayLike) -> FloatArray:
    """The paper's steady-state speed reading: ``theta / t``.

    Parameters
    ----------
    angle : angle turned theta [rad]
    time : time taken t [s]
    """
    return as_float(np.asarray(angle, dtype=float) / np.asarray(time, dtype=float))


def _time_constant(damping_rate: ArrayLike, inertia: ArrayLike) -> FloatArray:
    return as_float(np.asarray(inertia, dtype=float) / np.asarray(damping_rate, dtype=float))


def transient_lag(time: ArrayLike, damping_rate: ArrayLike, inertia: ArrayLike) -> FloatArray:
    """Time lost to the start-up transient: ``lag = tau (1 - exp(-t / tau))``, tau = J / B.

    From ``J dw/dt = T - FECD - BECD w`` (Eq. 5 with inertia; docs/characterize.md
    section 1).

    A shaft released from rest under constant torque reaches ``theta = w_ss (t - lag)``;
    lag = 0 for J = 0 (steady state from the start).

    Parameters
    ----------
    time : time since release t [s]
    damping_rate : BECD [N*m*s/rad], > 0
    inertia : total inertia at the shaft J [kg*m**2]

    >>> round(float(transient_lag(10.0, 2.0, 4.0)), 12)  # tau = 2 s: 2 * (1 - e**-5)
    1.986524106002
    """
    t = np.asarray(time, dtype=float)
    tau = _time_constant(damping_rate, inertia)
    moving = tau > 0.0
    safe_tau = np.where(moving, tau, 1.0)
    return as_float(np.where(moving, -safe_tau * np.expm1(-t / safe_tau), 0.0))


# Below this x = t / tau the differences x - (1 - e**-x) and (1 - e**-x) - x e**-x lose
# digits to cancellation (relative error about 2 eps / x) and are summed as series; the
# series' terms up to x**21 leave a relative error below 1e-19 there.
_SERIES_BELOW = 1.0
_SERIES_TERMS = 20


def _series(x: FloatArray, coefficient: Callable[[int], float]) -> FloatArray:
    """``sum over n = 2 .. 21 of coefficient(n) * (-x)**n / n!``, by Horner's rule."""
    total = np.zeros_like(x)
    for n in range(_SERIES_TERMS + 1, 1, -1):
        total = total * -x + coefficient(n) / math.factorial(n)
    return as_float(total * x * x)


def _span(t: FloatArray, tau: FloatArray) -> FloatArray:
    """``t - lag = t - tau (1 - e**-x)``, x = t / tau > 0, without cancellation for small
    x (there ``tau (x - (1 - e**-x))`` summed as a series)."""
    x = t / tau
    small = x < _SERIES_BELOW
    direct = t + tau * np.expm1(-np.where(small, 0.0, x))
    ramp = _series(np.where(small, x, 0.0), lambda n: 1.0)
    return as_float(np.where(small, tau * ramp, direct))


def _ramp_bracket(x: FloatArray) -> FloatArray:
    """``(1 - e**-x) - x e**-x`` (>= 0) without cancellation for small x."""
    small = x < _SERIES_BELOW
    big = np.where(small, 1.0, x)
    direct = -np.expm1(-big) - big * np.exp(-big)
    return as_float(np.where(small, _series(np.where(small, x, 0.0), lambda n: n - 1.0), direct))


def steady_span(time: ArrayLike, damping_rate: ArrayLike, inertia: ArrayLike) -> FloatArray:
    """``t - lag = tau (x - (1 - e**-x))``, x = t / tau: the time the drop would have taken
    at its steady speed (``theta = w_ss (t - lag)``, :func:`transient_lag`).

    Computed without cancellation: where the inertia is so large that the shaft is far
    from its steady speed (x small), ``t - lag`` is about ``t**2 / (2 tau)``, which
    ``t - transient_lag(t)`` rounded to 0 (rig_inertia 1e20 kg*m^2 made the fit's
    residuals infinite).

    >>> round(float(steady_span(10.0, 2.0, 4.0)), 12)  # 10 - transient_lag's example
    8.013475893998
    >>> float(steady_span(1.0, 1.0, 1e20))  # t**2 / (2 tau) = 1 / 2e20
    5e-21
    """
    t, tau = np.broadcast_arrays(
        np.asarray(time, dtype=float), _time_constant(damping_rate, inertia)
    )
    moving = tau > 0.0
    return as_float(np.where(moving, _span(t, np.where(moving, tau, 1.0)), t))


def _lag_derivative(time: FloatArray, damping_rate: float, inertia: FloatArray) -> FloatArray:
    """``d lag / d BECD = -(J / B**2) * ((1 - e**-x) - x e**-x)``, x = t B / J."""
    tau = _time_constant(damping_rate, inertia)
    moving = tau > 0.0
    x = time / np.where(moving, tau, 1.0)
    bracket = _ramp_bracket(np.where(moving, x, 1.0))
    return as_float(np.where(moving, -(inertia / damping_rate**2) * bracket, 0.0))


def startup_angle(
    time: ArrayLike, steady: ArrayLike, damping_rate: ArrayLike, inertia: ArrayLike
) -> FloatArray:
    """Angle turned after release from rest: ``theta(t) = w_ss (t - lag)`` (Eq. 5 with
    inertia, integrated; docs/characterize.md section 1).

    Parameters
    ----------
    time : time since release t [s]
    steady : steady speed w_ss = (torque - FECD) / BECD [rad/s]
    damping_rate : BECD [N*m*s/rad]
    inertia : total inertia at the shaft J [kg*m**2]
    """
    return as_float(np.asarray(steady, dtype=float) * steady_span(time, damping_rate, inertia))


def drop_time(
    angle: ArrayLike, steady: ArrayLike, damping_rate: ArrayLike, inertia: ArrayLike
) -> FloatArray:
    """Time a drop released from rest takes to turn ``theta``: the root t of
    ``theta = w_ss (t - lag(t))`` (:func:`startup_angle` inverted; docs/characterize.md
    section 1).

    ``g(t) = t - lag(t)`` rises (``g' = 1 - exp(-t / tau) > 0``), is convex, and
    ``t - tau < g(t) <= t``; so Newton's method started at ``theta / w_ss + tau``, right of
    the root, descends onto it monotonically. Without inertia t = theta / w_ss.

    Parameters
    ----------
    angle : angle turned theta [rad]
    steady : steady speed w_ss = (torque - FECD) / BECD [rad/s], > 0
    damping_rate : BECD [N*m*s/rad], > 0
    inertia : total inertia at the shaft J [kg*m**2]

    >>> round(float(drop_time(8.013475893998, 1.0, 2.0, 4.0)), 9)  # transient_lag's example
    10.0
    """
    pace = np.asarray(angle, dtype=float) / np.asarray(steady, dtype=float)
    tau = np.broadcast_to(_time_constant(damping_rate, inertia), pace.shape)
    moving = tau > 0.0
    safe_tau = np.where(moving, tau, 1.0)
    t = pace + np.where(moving, tau, 0.0)
    for _ in range(200):
        excess = np.where(moving, _span(t, safe_tau), t) - pace
        rate = np.where(moving, -np.expm1(-t / safe_tau), 1.0)
        step = excess / rate
        t = t - step
        if np.all(np.abs(step) <= 4.0 * np.finfo(float).eps * np.abs(t)):
            break
    return as_float(t)


def corrected_speed(
    angle: ArrayLike, time: ArrayLike, damping_rate: ArrayLike, inertia: ArrayLike
) -> FloatArray:
    """Steady speed from a drop released from rest: ``theta / (t - lag)`` (the paper's
    section 7 reading, corrected for the start-up transient).

    Parameters
    ----------
    angle : angle turned theta [rad]
    time : time taken t [s]
    damping_rate : BECD [N*m*s/rad], > 0
    inertia : total inertia at the shaft J [kg*m**2]
    """
    return as_float(np.asarray(angle, dtype=float) / steady_span(time, damping_rate, inertia))


@dataclass(frozen=True)
class TemperatureFit:
    """The torque-speed line of one test temperature.

    Attributes
    ----------
    temperature : T [degC]
    rows : file row of each point
    torque : drive torque of each point [N*m]
    speed : steady-state reading theta / t of each point [rad/s]
    corrected : steady speed after the start-up correction [rad/s] (= speed without it)
    inertia : total inertia used for each point [kg*m**2] (0: no correction)
    line : the fitted line and its statistics
    noise : the noise model it was fitted under (a :data:`NOISE_MODELS` name)
    """

    temperature: float
    rows: np.ndarray[Any, np.dtype[np.int64]]
    torque: FloatArray
    speed: FloatArray
    corrected: FloatArray
    inertia: FloatArray
    line: LineFit
    noise: str = "torque"

    @property
    def correction(self) -> FloatArray:
        """Relative speed correction of each point, ``corrected / speed - 1`` [-]."""
        return as_float(self.corrected / self.speed - 1.0)

    @property
    def speed_noise_bias(self) -> float | None:
        """How low BECD would be if all the scatter were speed (timing) error [-].

        The line treats speeds as exact. If instead the torques are exact and the speeds
        carry independent errors of variance ``sigma_w**2``, the residual variance is
        about ``BECD**2 sigma_w**2`` and the fitted slope is low by the fraction
        ``sigma_w**2 / var(speed)`` (regression dilution; Draper and Smith, section
        3.4). None without residual degrees of freedom, and under the timing-noise
        model, which fits the speed error and so has no such bias; 0 for an exact fit.
        """
        stats = self.line.statistics
        if stats.residual_std is None or not NOISE_MODELS[self.noise].dilutes:
            return None
        if stats.exact:
            return 0.0
        sigma_w = stats.residual_std / self.line.slope.value
        return float(sigma_w**2 / np.var(self.corrected))

    @property
    def corrected_for_inertia(self) -> bool:
        """True where the start-up transient was corrected for."""
        return bool(np.any(self.inertia > 0.0))

    def to_dict(self, *, points_as_table: bool = False) -> dict[str, Any]:
        """One entry of the ``temperatures`` list of the JSON document.

        ``points_as_table`` keeps the points as columns (a :class:`RowTable` for
        :func:`ecdsim.jsonrows.write_json`, which streams them) instead of a list of
        dicts: the form for large files.
        """
        line = self.line
        curvature = line.curvature
        # Whole columns first (the correction is a property computed over all points:
        # once per point made this quadratic in the number of drops).
        studentized = np.asarray(line.studentized, dtype=float)
        points = RowTable(
            {
                "row": self.rows,
                "torque_Nm": self.torque,
                "speed_rad_s": self.speed,
                "corrected_speed_rad_s": self.corrected,
                "relative_speed_correction": self.correction,
                "inertia_kg_m2": np.broadcast_to(self.inertia, self.rows.shape),
                "residual_Nm": self.torque - line.fitted,
                # null where undefined (a point with leverage 1), as finite_or_none does
                "studentized_residual": np.where(np.isfinite(studentized), studentized, np.nan),
                "outlier": np.asarray(line.outliers, dtype=bool),
            }
        )
        return {
            "temperature_C": self.temperature,
            "n_points": line.n_points,
            **line.slope.to_dict("damping_rate", "_Nms_per_rad"),
            **line.intercept.to_dict("friction", "_Nm"),
            "r_squared": line.r_squared,
            "noise_model": self.noise,
            "residual_std_Nm": None,
            "relative_time_std": None,
            NOISE_MODELS[self.noise].scatter_key: line.statistics.residual_std,
            "dof": line.statistics.dof,
            "roll_off": bool(curvature.roll_off) if curvature else False,
            "bending": bool(curvature.bending) if curvature else False,
            "curvature_p_value": curvature.p_value if curvature else None,
            "outlier_rows": [int(r) for r in self.rows[line.outliers]],
            "speed_noise_bias": self.speed_noise_bias,
            "inertia_correction": {
                "applied": self.corrected_for_inertia,
                "max_relative_speed_correction": float(np.max(np.abs(self.correction))),
            },
            "points": points if points_as_table else points.records(),
        }


@dataclass(frozen=True)
class FailedTemperature:
    """A temperature whose points could not be fitted.

    Attributes
    ----------
    temperature : T [degC]
    rows : file rows of its points
    reason : why
    """

    temperature: float
    rows: tuple[int, ...]
    reason: str

    def message(self) -> str:
        """One readable line."""
        return f"{self.temperature:g} degC (rows {_row_list(self.rows)}): {self.reason}"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "temperature_C": self.temperature,
            "n_points": len(self.rows),
            "rows": list(self.rows),
            "error": self.reason,
        }


def _row_list(rows: tuple[int, ...] | list[int]) -> str:
    """Row numbers with runs of consecutive rows shown as ranges, for one readable line.

    >>> _row_list([2, 3, 4, 5, 9, 11, 12])
    '2-5, 9, 11-12'
    """
    parts: list[str] = []
    ordered = sorted(rows)
    start = 0
    for i in range(1, len(ordered) + 1):
        if i == len(ordered) or ordered[i] != ordered[i - 1] + 1:
            first, last = ordered[start], ordered[i - 1]
            parts.append(str(first) if first == last else f"{first}-{last}")
            start = i
    return ", ".join(parts)


@dataclass(frozen=True)
class DropTestResult:
    """Everything a drop-test reduction found.

    Attributes
    ----------
    table : the data read (usable rows, bad-row report, notes)
    fits : one line per temperature that could be fitted, coldest first
    failed : the temperatures that could not be fitted
    laws : BECD(T) and FECD(T) laws; None with fewer than two fitted temperatures
    reference_temperature : T_ref of the damping laws [degC]
    gravity : g used [m/s**2]
    warnings : flags raised (roll-off, outliers, start-up correction, ...)
    noise : the noise model of the lines (a :data:`NOISE_MODELS` name)
    noise_check : whether the residuals support that model rather than the other
        (:mod:`ecdsim.characterize.noisecheck`); None where no line has residual scatter
    """

    table: Table
    fits: tuple[TemperatureFit, ...]
    failed: tuple[FailedTemperature, ...]
    laws: TemperatureLaws | None
    reference_temperature: float
    gravity: float
    warnings: tuple[FitWarning, ...] = field(default=())
    noise: str = "torque"
    noise_check: NoiseCheck | None = None

    def to_dict(self, *, points_as_table: bool = False) -> dict[str, Any]:
        """The JSON document of ``ecdsim fit drop-test --json`` (docs/characterize.md).

        ``points_as_table``: see :meth:`TemperatureFit.to_dict`.
        """
        return {
            "ecdsim_version": __version__,
            "kind": "drop_test",
            "source": self.table.source,
            "source_sha256": self.table.sha256,
            "gravity_m_s2": self.gravity,
            "reference_temperature_C": self.reference_temperature,
            "noise_model": self.noise,
            "noise_check": self.noise_check.to_dict() if self.noise_check else None,
            "temperatures": [fit.to_dict(points_as_table=points_as_table) for fit in self.fits],
            "failed_temperatures": [f.to_dict() for f in self.failed],
            "temperature_laws": self.laws.to_dict() if self.laws else None,
            "bad_rows": [b.to_dict() for b in self.table.bad_rows],
            "excluded_rows": self.table.excluded_rows,
            "warnings": [w.to_dict() for w in self.warnings],
        }


def fit_temperature(
    temperature: float,
    rows: ArrayLike,
    torque: ArrayLike,
    angle: ArrayLike,
    time: ArrayLike,
    inertia: ArrayLike,
    *,
    noise: str = "torque",
) -> TemperatureFit:
    """Fit the torque-speed line of one temperature, correcting the start-up if J > 0.

    Raises :class:`~ecdsim.characterize.linefit.LineFitError` where the points cannot
    define a line or the fitted damping rate is not positive, and ValueError for an
    unknown ``noise``.

    Parameters
    ----------
    temperature : T [degC]
    rows : file row of each point
    torque : drive torque of each point [N*m]
    angle : angle turned theta [rad]
    time : time taken t [s]
    inertia : total inertia at the shaft per point J [kg*m**2]; zeros for no correction
    noise : where the scatter lies, a :data:`NOISE_MODELS` name (module docstring)
    """
    model = noise_model(noise)
    y = as_float(torque)
    theta = as_float(angle)
    t = as_float(time)
    j = np.broadcast_to(as_float(inertia), y.shape).astype(float)
    speed = steady_speed(theta, t)
    check_line_data(speed, y)
    # The least-squares line of the steady-state readings: the paper's answer, and the
    # start of every fit.
    design = np.column_stack([np.ones_like(speed), speed - np.mean(speed)])
    centred = np.linalg.lstsq(design, y, rcond=None)[0]
    plain = (float(centred[0] - centred[1] * np.mean(speed)), float(centred[1]))
    if plain[1] <= 0.0:
        raise LineFitError(
            f"the fitted damping rate {plain[1]:.4g} N*m*s/rad is not positive: "
            "torque does not rise with speed"
        )
    line = model.fit(y, theta, t, j, plain)
    corrected = corrected_speed(theta, t, line.slope.value, j)
    row_array = np.asarray(rows, dtype=np.int64)
    return TemperatureFit(temperature, row_array, y, speed, corrected, j, line, model.name)


def _torque_line(
    torque: FloatArray,
    angle: FloatArray,
    time: FloatArray,
    inertia: FloatArray,
    start: tuple[float, float],
) -> LineFit:
    """The torque-noise line: the plain line, or the start-up-corrected fit where J > 0."""
    if not np.any(inertia > 0.0):
        return fit_line(steady_speed(angle, time), torque)
    friction, damping = _fit_with_startup(torque, angle, time, inertia, start)
    corrected = corrected_speed(angle, time, damping, inertia)
    # d torque_model / d B = w_c + B * w_c**2 / theta * d lag / d B
    derivative = corrected + damping * corrected**2 / angle * _lag_derivative(
        time, damping, inertia
    )
    design = np.column_stack([np.ones_like(torque), derivative])
    return summarise_line(corrected, torque, friction, damping, design)


def _log_drop_time(
    torque: FloatArray, angle: FloatArray, friction: float, damping: float, inertia: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """``log t`` of each drop under (FECD, BECD), and ``d log t / d (FECD, BECD)``.

    With ``P = theta * BECD / (torque - FECD)`` the drop time solves
    ``g(t) = t - lag(t; BECD) = P``; implicit differentiation gives
    ``g'(t) dt = dP + d lag / d BECD * dBECD``, ``g'(t) = 1 - exp(-t / tau)`` (1 for
    J = 0, where ``log t = log theta + log BECD - log(torque - FECD)``).
    """
    drive = torque - friction
    t = drop_time(angle, drive / damping, damping, inertia)
    tau = _time_constant(damping, inertia)
    moving = tau > 0.0
    rate = np.where(moving, -np.expm1(-t / np.where(moving, tau, 1.0)), 1.0)
    pace = angle * damping / drive
    d_friction = pace / drive / rate / t
    d_damping = (pace / damping + _lag_derivative(t, damping, inertia)) / rate / t
    return as_float(np.log(t)), np.column_stack([d_friction, d_damping])


def _timing_line(
    torque: FloatArray,
    angle: FloatArray,
    time: FloatArray,
    inertia: FloatArray,
    start: tuple[float, float],
) -> LineFit:
    """The timing-noise line: least squares of ``log t`` (module docstring).

    Its statistics are those of the log-time fit (residuals: relative timing errors,
    ``s``: the relative timing scatter), so the intervals, the outlier test and the
    scatter the laws pool hold for timing noise. The bending test weights the torque
    residuals by ``1 / speed**2``: a relative speed error ``eps`` puts ``BECD * speed *
    eps`` into the torque.
    """
    log_time = np.log(time)
    scale = float(np.max(np.abs(torque)))
    ceiling = float(np.min(torque)) - FRICTION_CEILING * scale
    b0 = start[1]

    # Searched as FECD = ceiling - scale * exp(q), BECD = b0 * exp(b): every trial point
    # keeps FECD below the torques and BECD > 0, so the unbounded Levenberg-Marquardt
    # solver applies (1000 campaigns of the coverage tests: 15 s against 21.5 s with the
    # bounded trust-region solver, measured).
    def parameters(p: FloatArray) -> tuple[float, float]:
        return ceiling - scale * math.exp(p[0]), b0 * math.exp(p[1])

    # The solver asks for the Jacobian where it last evaluated the residuals: keep that
    # point's model rather than solve for the drop times twice.
    last: dict[tuple[float, float], tuple[FloatArray, FloatArray]] = {}

    def model(p: FloatArray) -> tuple[FloatArray, FloatArray]:
        key = (float(p[0]), float(p[1]))
        if key not in last:
            last.clear()
            last[key] = _log_drop_time(torque, angle, *parameters(p), inertia)
        return last[key]

    def residual(p: FloatArray) -> FloatArray:
        return as_float(log_time - model(p)[0])

    def jacobian(p: FloatArray) -> FloatArray:
        friction, damping = parameters(p)
        return as_float(-model(p)[1] * np.array([friction - ceiling, damping]))

    friction_start = min(start[0], ceiling - 0.01 * scale)
    result = _solve(
        "timing-noise",
        residual,
        jacobian,
        np.array([math.log((ceiling - friction_start) / scale), 0.0]),
    )
    if not result.success:
        raise LineFitError(f"the timing-noise fit did not converge ({result.message})")
    friction, damping = parameters(result.x)
    log_model, design = _log_drop_time(torque, angle, friction, damping, inertia)
    # Residuals are relative: round-off is judged against 1.
    statistics = linearised(design, log_time - log_model, np.ones_like(log_time))
    corrected = corrected_speed(angle, time, damping, inertia)
    return summarise_line(
        corrected,
        torque,
        friction,
        damping,
        design,
        statistics=statistics,
        curvature_weights=1.0 / corrected**2,
    )


LineFitter = Callable[
    [FloatArray, FloatArray, FloatArray, FloatArray, tuple[float, float]], LineFit
]


@dataclass(frozen=True)
class NoiseModel:
    """Where a drop test's scatter lies, and how its line is fitted under it.

    Attributes
    ----------
    name : registry name (``--noise``)
    description : what it assumes, for humans
    fit : ``(torque, angle, time, inertia, (FECD, BECD) to start from) -> LineFit``,
        units as in :func:`fit_temperature`
    scatter_key : JSON key of the residual standard deviation (it carries the unit)
    dilutes : True where speed errors would bias the slope low (``speed_noise_bias``)
    """

    name: str
    description: str
    fit: LineFitter
    scatter_key: str
    dilutes: bool


NOISE_MODELS: dict[str, NoiseModel] = {
    "torque": NoiseModel(
        name="torque",
        description="scatter in the torque, speeds exact",
        fit=_torque_line,
        scatter_key="residual_std_Nm",
        dilutes=True,
    ),
    "timing": NoiseModel(
        name="timing",
        description="relative scatter in the drop time, torques exact",
        fit=_timing_line,
        scatter_key="relative_time_std",
        dilutes=False,
    ),
}
DEFAULT_NOISE = "torque"


def noise_model(name: str) -> NoiseModel:
    """The registered noise model ``name``; ValueError naming the choices otherwise."""
    try:
        return NOISE_MODELS[name]
    except KeyError:
        choices = ", ".join(NOISE_MODELS)
        raise ValueError(f"unknown noise model {name!r}; choose one of: {choices}") from None


def _fit_with_startup(
    torque: FloatArray,
    angle: FloatArray,
    time: FloatArray,
    inertia: FloatArray,
    start: tuple[float, float],
) -> tuple[float, float]:
    """Least-squares (FECD, BECD) of ``torque = F + B * theta / (t - lag(B))``."""

    def residual(p: FloatArray) -> FloatArray:
        return as_float(torque - p[0] - p[1] * corrected_speed(angle, time, p[1], inertia))

    def jacobian(p: FloatArray) -> FloatArray:
        w = corrected_speed(angle, time, p[1], inertia)
        dw = w + p[1] * w * w / angle * _lag_derivative(time, p[1], inertia)
        return np.column_stack([-np.ones_like(w), -dw])

    b0 = start[1]
    result = _solve(
        "start-up-corrected",
        residual,
        jacobian,
        np.array([start[0], b0]),
        lower=np.array([-np.inf, 1e-9 * b0]),
        max_evaluations=200,
    )
    if not result.success:
        raise LineFitError(f"the start-up-corrected fit did not converge ({result.message})")
    return float(result.x[0]), float(result.x[1])


def _solve(
    what: str,
    residual: Callable[[FloatArray], FloatArray],
    jacobian: Callable[[FloatArray], FloatArray],
    x0: FloatArray,
    **options: Any,
) -> leastsq.Solution:
    """:func:`leastsq.solve`; a fit that cannot start (residuals not finite at its first
    point) is this temperature's LineFitError, reported with the others, never a crash."""
    try:
        return leastsq.solve(residual, jacobian, x0, **options)
    except ValueError as exc:
        raise LineFitError(f"the {what} fit cannot start ({exc})") from None


def read_drop_test(path: str | Path, gravity: float = STANDARD_GRAVITY) -> Table:
    """Read a drop-test CSV file; rows whose drive torque is not positive are excluded, and
    so are rows that turn further than their inertia allows (:func:`_exclude_unreachable`)."""
    table = read_table(path, DROP_TEST_COLUMNS)
    torque = _drive_torques(table, gravity)
    bad = torque <= 0.0
    if np.any(bad):
        key = "rig_friction" if table.has("rig_friction") else "mass"
        reasons = [
            f"gives a drive torque m*g*r - rig_friction = {value:.4g} N*m <= 0: the mass "
            "cannot turn the damper"
            for value in torque[bad]
        ]
        table = _checked_exclusion(table.exclude(bad, key, reasons))
    return _exclude_unreachable(table, gravity)


def _exclude_unreachable(table: Table, gravity: float) -> Table:
    """The table without the rows whose inertia forbids the recorded drop.

    Released from rest, the shaft turns at most ``torque t**2 / (2 J)`` in a time t,
    its free acceleration: damping and friction only slow it. A row that turns further
    cannot be a drop of that inertia (rig_inertia 1e20 kg*m^2 with a 3 kg mass: 1e-16 rad
    in two minutes, not half a turn); it is excluded with a line saying so, rather than
    handed to a fit no parameters can satisfy.
    """
    if not table.has("rig_inertia"):
        return table
    v = table.values
    torque = _drive_torques(table, gravity)
    inertia = v["rig_inertia"] + falling_mass_inertia(v["mass"], v["radius"])
    reach = torque * v["time"] ** 2 / (2.0 * inertia)
    bad = v["angle"] > reach
    if not np.any(bad):
        return table
    reasons = [
        f"kg*m^2 is too large for the drop: even undamped, its drive torque {t:.4g} N*m turns "
        f"J = {j:.4g} kg*m^2 (with the falling mass) only {r:.4g} rad in {s:.4g} s, not "
        f"{a:.4g} rad"
        for t, j, r, s, a in zip(
            torque[bad], inertia[bad], reach[bad], v["time"][bad], v["angle"][bad], strict=True
        )
    ]
    return _checked_exclusion(table.exclude(bad, "rig_inertia", reasons))


def _checked_exclusion(table: Table) -> Table:
    """``table``, or a ConfigError listing every bad row if no usable row remains."""
    if table.rows.size == 0:
        from ecdsim.config.errors import ConfigError

        lines = [b.message() for b in table.bad_rows]
        raise ConfigError([*lines, "no usable data row remains"], table.source)
    return table


def _drive_torques(table: Table, gravity: float) -> FloatArray:
    v = table.values
    rig = v["rig_friction"] if table.has("rig_friction") else 0.0
    return drive_torque(v["mass"], v["radius"], rig, gravity)


def fit_drop_test(
    path: str | Path,
    reference_temperature: float = 25.0,
    gravity: float = STANDARD_GRAVITY,
    *,
    noise: str = DEFAULT_NOISE,
) -> DropTestResult:
    """Read a drop-test CSV file and fit every temperature and the temperature laws.

    Raises :class:`~ecdsim.config.ConfigError` for an unreadable file or one with no
    usable row, ValueError for an unknown ``noise``; a temperature that cannot be fitted
    is reported in ``failed``.

    Parameters
    ----------
    path : the CSV file (columns in docs/characterize.md)
    reference_temperature : T_ref of the damping laws [degC]
    gravity : acceleration of gravity [m/s**2]
    noise : where the scatter lies, a :data:`NOISE_MODELS` name (module docstring)
    """
    model = noise_model(noise)
    table = read_drop_test(path, gravity)
    return reduce_drop_test(table, reference_temperature, gravity, noise=model.name)


def reduce_drop_test(
    table: Table,
    reference_temperature: float = 25.0,
    gravity: float = STANDARD_GRAVITY,
    *,
    noise: str = DEFAULT_NOISE,
) -> DropTestResult:
    """Fit every temperature of a drop-test table and the laws over temperature.

    Parameters
    ----------
    table : drop-test data (from :func:`read_drop_test`)
    reference_temperature : T_ref of the damping laws [degC]
    gravity : acceleration of gravity [m/s**2]
    noise : where the scatter lies, a :data:`NOISE_MODELS` name (module docstring)
    """
    model = noise_model(noise)
    v = table.values
    torque = _drive_torques(table, gravity)
    has_inertia = table.has("rig_inertia")
    inertia = (
        v["rig_inertia"] + falling_mass_inertia(v["mass"], v["radius"])
        if has_inertia
        else np.zeros_like(torque)
    )
    fits: list[TemperatureFit] = []
    failed: list[FailedTemperature] = []
    warnings: list[FitWarning] = [FitWarning("ignored_column", note) for note in table.notes]
    groups: list[Group] = []  # the lines' residuals, for the noise model's check
    for temperature, members in temperature_groups(v["temperature"]):
        rows = table.rows[members]
        try:
            fit = fit_temperature(
                temperature,
                rows,
                torque[members],
                v["angle"][members],
                v["time"][members],
                inertia[members],
                noise=model.name,
            )
        except LineFitError as exc:
            failed.append(FailedTemperature(temperature, tuple(int(r) for r in rows), str(exc)))
            continue
        fits.append(fit)
        group = _check_group(fit, v["angle"][members], v["time"][members])
        if group is not None:
            groups.append(group)
        warnings.extend(_flags(fit))
        if not has_inertia:
            warnings.extend(_uncorrected_transient(fit, v, members))
    laws = None
    if len(fits) >= 2:
        laws = fit_temperature_laws(
            [f.temperature for f in fits],
            [law_input(f.line.slope, f.line) for f in fits],
            [law_input(f.line.intercept, f.line) for f in fits],
            reference_temperature,
            scatter=[f.line.statistics.scatter for f in fits],
        )
        warnings.extend(law_warnings(laws))
    elif len(fits) == 1:
        warnings.append(
            FitWarning(
                "single_temperature",
                "only one temperature could be fitted: no law over temperature",
            )
        )
    other = next(name for name in NOISE_MODELS if name != model.name)
    check = check_noise_model(model.name, other, groups)
    finding = check.warning() if check is not None else None
    if finding is not None:
        warnings.append(finding)
    return DropTestResult(
        table=table,
        fits=tuple(fits),
        failed=tuple(failed),
        laws=laws,
        reference_temperature=reference_temperature,
        gravity=gravity,
        warnings=tuple(warnings),
        noise=model.name,
        noise_check=check,
    )


def _check_group(fit: TemperatureFit, angle: FloatArray, time: FloatArray) -> Group | None:
    """One line's residuals, linearised design and the other model's scatter pattern, for
    :func:`~ecdsim.characterize.noisecheck.check_noise_model`; None for an exact line or one
    without residual degrees of freedom.

    The patterns come from ``d torque_model / d log t = BECD w t (1 - e**-(t/tau)) / (t -
    lag)`` (``BECD w`` without inertia): a relative timing error moves a point's torque by
    it, and a torque error moves ``log t`` by its inverse.
    """
    stats = fit.line.statistics
    if stats.dof < 1 or stats.exact:
        return None
    damping = fit.line.slope.value
    inertia = fit.inertia
    corrected = fit.corrected
    tau = _time_constant(damping, inertia)
    moving = tau > 0.0
    rate = np.where(moving, -np.expm1(-time / np.where(moving, tau, 1.0)), 1.0)
    sensitivity = corrected * time * rate / steady_span(time, damping, inertia)
    if fit.noise == "timing":
        design = _log_drop_time(fit.torque, angle, fit.line.intercept.value, damping, inertia)[1]
        exponent = -np.log(sensitivity)
    else:
        slope_column = corrected
        if np.any(inertia > 0.0):
            slope_column = corrected + damping * corrected**2 / angle * _lag_derivative(
                time, damping, inertia
            )
        design = np.column_stack([np.ones_like(corrected), slope_column])
        exponent = np.log(sensitivity)
    return Group(stats.residuals, design, as_float(exponent))


def law_input(estimate: Estimate, line: LineFit) -> Estimate:
    """The estimate a law over temperature is fitted to.

    Where the line is exact (noise-free data) its standard errors are float64 round-off,
    not uncertainty: they are dropped so that the law is fitted unweighted.
    """
    if line.statistics.exact:
        return Estimate(estimate.value, None, None)
    return estimate


def _flags(fit: TemperatureFit) -> list[FitWarning]:
    """The warnings one temperature's line raises."""
    t = fit.temperature
    line = fit.line
    out = []
    if line.statistics.dof == 0:
        out.append(
            FitWarning(
                "no_uncertainty",
                f"{t:g} degC: two points define the line exactly; no uncertainty can be given",
                t,
            )
        )
    if line.curvature is not None and line.curvature.bending:
        kind = "roll_off" if line.curvature.roll_off else "bending"
        what = "bends down (roll-off)" if line.curvature.roll_off else "bends up"
        out.append(
            FitWarning(
                kind,
                f"{t:g} degC: the torque-speed line {what} "
                f"(quadratic term p = {line.curvature.p_value:.2g}); "
                "points beyond the linear range bias BECD",
                t,
            )
        )
    for row, p in zip(fit.rows[line.outliers], line.outlier_p[line.outliers], strict=True):
        out.append(
            FitWarning(
                "outlier",
                f"{t:g} degC: row {int(row)} is an outlier (Bonferroni p = {p:.2g}); "
                "it is kept in the fit, check it",
                t,
            )
        )
    if line.intercept.value < 0.0:
        out.append(
            FitWarning(
                "negative_friction",
                f"{t:g} degC: the fitted friction {line.intercept.value:.4g} N*m is negative "
                "(rig friction over-subtracted, or the line bends)",
                t,
            )
        )
    bias = fit.speed_noise_bias
    se = line.slope.standard_error
    if bias is not None and se is not None and bias * line.slope.value > 0.5 * se:
        out.append(
            FitWarning(
                "speed_noise_bias",
                f"{t:g} degC: if the scatter is timing error, BECD is low by about "
                f"{100 * bias:.2g} %, not small against its standard error; spread the loads "
                "wider or time longer drops",
                t,
            )
        )
    largest = float(np.max(np.abs(fit.correction)))
    if largest > LARGE_CORRECTION:
        out.append(
            FitWarning(
                "inertia_correction",
                f"{t:g} degC: the start-up correction changes a speed by {100 * largest:.1f} %; "
                "the result depends on the inertia given (include the damper's reflected "
                "rotor inertia)",
                t,
            )
        )
    return out


def _uncorrected_transient(
    fit: TemperatureFit, values: dict[str, FloatArray], members: np.ndarray[Any, Any]
) -> list[FitWarning]:
    """Warn where the falling mass alone would change the speeds noticeably."""
    mass_inertia = falling_mass_inertia(values["mass"][members], values["radius"][members])
    t = values["time"][members]
    lag = transient_lag(t, fit.line.slope.value, mass_inertia)
    largest = float(np.max(lag / (t - lag)))
    if largest <= NOTABLE_CORRECTION or not math.isfinite(largest):
        return []
    return [
        FitWarning(
            "inertia_not_given",
            f"{fit.temperature:g} degC: no rig_inertia column, so the speeds are read as "
            f"steady; the falling mass alone (m*r**2) would raise a speed by "
            f"{100 * largest:.1f} %. Give rig_inertia_kg_m2 (0 if negligible) to correct",
            fit.temperature,
        )
    ]


def _misfit_test(fit: LawFit) -> str:
    """The name of the law's misfit test: F with pooled scatter, chi-square else."""
    return "F" if fit.scatter_dof is not None else "chi-square"


def law_warnings(laws: TemperatureLaws) -> list[FitWarning]:
    """Warnings about the laws over temperature (misfit, failures)."""
    out = []
    for name, fit in laws.damping.items():
        if fit.p_value is not None and fit.p_value < MISFIT_LEVEL:
            out.append(
                FitWarning(
                    "law_misfit",
                    f"the {name} damping law misses the per-temperature values by more than "
                    f"their errors ({_misfit_test(fit)} p = {fit.p_value:.2g}); its intervals are "
                    "widened by the scatter",
                )
            )
    for name, why in laws.damping_failures.items():
        out.append(FitWarning("law_failed", f"the {name} damping law could not be fitted: {why}"))
    if laws.friction_failure:
        out.append(
            FitWarning(
                "law_failed", f"the friction line could not be fitted: {laws.friction_failure}"
            )
        )
    return out
