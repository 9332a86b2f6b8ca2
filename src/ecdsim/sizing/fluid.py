"""A viscous silicone-fluid rotary damper, and the ECD against it (docs/sizing.md).

The paper (section 3.4, and its reference [2], CDA's "ECD vs. Fluid Damper Simulation
Software") contrasts the ECD with a fluid damper: the fluid's viscosity, hence its damping,
changes strongly with temperature, and it has 15 deg or more of deadband.

Model. A shear-type fluid damper's torque is proportional to the fluid's viscosity times
the speed (Newtonian fluid); optionally ``torque = c * omega**n`` for a shear-thinning
fluid (n < 1). The damping coefficient follows the viscosity:
``c(T) = c(T_match) * visc(T) / visc(T_match)``, and is matched to the ECD at a chosen
temperature: ``c(T_match) = BECD(T_match)`` for n = 1 (equal torque at the matching speed
for n != 1). Viscosity-temperature laws, each fitted through two or more points:

* Andrade / Arrhenius: ``ln(visc) = A + B / T_K`` (least squares in 1/T_K);
* Walther, ASTM D341: ``log10(log10(nu + 0.7)) = A - B log10(T_K)``, nu in mm^2/s.

Deadband. During the deadband the damper is not engaged: the load moves undamped, driven
by the spring against the system friction only. A quasi-static model cannot integrate an
undamped phase, so the deadband is reported separately: the angle lost to it, and (only
if a load inertia is given) the free-motion time and the speed at engagement, from
``J * phi'' = T(phi) - FS``. The damped deployment then runs over the rest of the travel
with the same exact quasi-static solver as the ECD. The ECD's own lost motion (gearbox
backlash) is treated the same way, so both sides are compared alike.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol, Self

import numpy as np

from ecdsim._types import ArrayLike, BoolArray, FloatArray, as_float
from ecdsim._version import __version__
from ecdsim.config.sizing_schema import FluidDamperSpec
from ecdsim.deployment import predict
from ecdsim.dynamics.params import DynamicParameters
from ecdsim.dynamics.result import DynamicResult
from ecdsim.model import DeploymentSystem
from ecdsim.physics.fluid import (
    arrhenius_factor,
    power_law_coefficient,
    power_law_exponent,
    power_law_mean_speed_time,
    power_law_torque,
)

# The power-law time is a physics function; its name is kept here too (re-exported).
from ecdsim.physics.fluid import power_law_segment_duration as power_law_segment_duration
from ecdsim.physics.quasistatic import locate_stall
from ecdsim.sizing import fluid_dynamic as fluid_damper
from ecdsim.solvers import EXACT, PAPER, QuasiStaticProblem

KELVIN_OFFSET = 273.15
# compare_fluid's methods: the quasi-static closed forms, or the dynamic core.
METHODS = ("quasi-static", "dynamic")
_M2S_PER_CST = 1e-6  # 1 mm^2/s (centistokes) = 1e-6 m^2/s
_WALTHER_SHIFT = 0.7  # ASTM D341: Z = nu + 0.7 for nu >= 2 mm^2/s


def _kelvin(temperature: ArrayLike) -> FloatArray:
    return as_float(as_float(temperature) + KELVIN_OFFSET)


def _line_fit(x: FloatArray, y: FloatArray) -> tuple[float, float]:
    """Least-squares (intercept, slope) of y against x; exact through two points."""
    design = np.stack([np.ones_like(x), x], axis=1)
    (intercept, slope), *_ = np.linalg.lstsq(design, y, rcond=None)
    return float(intercept), float(slope)


def andrade_fit(temperatures: ArrayLike, viscosities: ArrayLike) -> tuple[float, float]:
    """Fit Andrade's law ``ln(visc) = A + B / T_K`` by least squares; returns (A, B).

    Andrade (1930), "The viscosity of liquids", Nature 125, 309-310; the same form as an
    Arrhenius law with activation energy B * R. Exact through two points, the least-squares
    line in (1/T_K, ln visc) through more.

    Parameters
    ----------
    temperatures : temperatures of the points [degC]
    viscosities : viscosity at those points, dynamic [Pa*s] or kinematic [m^2/s]

    >>> a, b = andrade_fit([25.0, 100.0], [1.0, 0.5])
    >>> round(float(andrade_viscosity(25.0, a, b)), 12)
    1.0
    """
    x = 1.0 / _kelvin(temperatures)
    return _line_fit(x, as_float(np.log(as_float(viscosities))))


def andrade_viscosity(temperature: ArrayLike, a: float, b: float) -> FloatArray:
    """Viscosity by Andrade's law, ``exp(A + B / T_K)`` (Andrade 1930).

    Parameters
    ----------
    temperature : T [degC]
    a : A, the intercept of ln(visc) [ln of the viscosity's unit]
    b : B, the slope of ln(visc) against 1/T_K [K]
    """
    return as_float(np.exp(a + b / _kelvin(temperature)))


def walther_fit(temperatures: ArrayLike, kinematic_viscosities: ArrayLike) -> tuple[float, float]:
    """Fit Walther's equation (ASTM D341) ``log10(log10(nu + 0.7)) = A - B log10(T_K)``.

    nu in mm^2/s (cSt), valid for nu >= 2 mm^2/s (ASTM D341 adds terms below that).
    Returns (A, B); exact through two points, least squares in (log10 T_K,
    log10 log10(nu + 0.7)) through more.

    Parameters
    ----------
    temperatures : temperatures of the points [degC]
    kinematic_viscosities : kinematic viscosity nu at those points [m^2/s]

    >>> a, b = walther_fit([40.0, 100.0], [32e-6, 5.4e-6])
    >>> round(float(walther_viscosity(40.0, a, b)) * 1e6, 9)
    32.0
    """
    nu_cst = as_float(kinematic_viscosities) / _M2S_PER_CST
    y = as_float(np.log10(np.log10(nu_cst + _WALTHER_SHIFT)))
    intercept, slope = _line_fit(as_float(np.log10(_kelvin(temperatures))), y)
    return intercept, -slope


def walther_viscosity(temperature: ArrayLike, a: float, b: float) -> FloatArray:
    """Kinematic viscosity by Walther's equation (ASTM D341): ``10**10**(A - B log10 T_K) - 0.7``.

    Parameters
    ----------
    temperature : T [degC]
    a : A, Walther constant [-]
    b : B, Walther constant [-]

    Returns nu [m^2/s].
    """
    z = np.power(10.0, np.power(10.0, a - b * np.log10(_kelvin(temperature))))
    return as_float((z - _WALTHER_SHIFT) * _M2S_PER_CST)


class ViscosityLaw(Protocol):
    """A fitted viscosity-temperature law."""

    @property
    def name(self) -> str:
        """Registry name ("andrade", "walther")."""
        ...

    @property
    def points(self) -> tuple[tuple[float, float], ...]:
        """The (T [degC], viscosity [SI]) points it was fitted through."""
        ...

    def __call__(self, temperature: ArrayLike) -> FloatArray:
        """Viscosity at T [degC], in the points' SI unit."""
        ...

    def describe(self) -> str:
        """One-line description with the fitted constants."""
        ...


def _outside(temperature: ArrayLike, points: Sequence[tuple[float, float]]) -> BoolArray:
    temps = [t for t, _ in points]
    t = as_float(temperature)
    return np.asarray((t < min(temps)) | (t > max(temps)))


@dataclass(frozen=True)
class _TwoConstantLaw:
    """A viscosity law with two constants (a, b) fitted through ``points``.

    Each subclass names its law's fit and evaluation functions; ``fit``, ``__call__`` and
    ``out_of_range`` are shared.
    """

    a: float
    b: float
    points: tuple[tuple[float, float], ...]

    _fit_constants: ClassVar[staticmethod[[ArrayLike, ArrayLike], tuple[float, float]]]
    _viscosity: ClassVar[staticmethod[[ArrayLike, float, float], FloatArray]]

    @classmethod
    def fit(cls, points: Sequence[tuple[float, float]]) -> Self:
        """Least-squares fit through two or more (T [degC], viscosity [SI]) points."""
        a, b = cls._fit_constants([t for t, _ in points], [v for _, v in points])
        return cls(a, b, tuple(points))

    def __call__(self, temperature: ArrayLike) -> FloatArray:
        """Viscosity at T [degC], in the points' SI unit."""
        return self._viscosity(temperature, self.a, self.b)

    def out_of_range(self, temperature: ArrayLike) -> BoolArray:
        """True outside the fitted points' temperatures (extrapolation)."""
        return _outside(temperature, self.points)


@dataclass(frozen=True)
class AndradeLaw(_TwoConstantLaw):
    """Andrade / Arrhenius law ``ln(visc) = a + b / T_K`` fitted through ``points``."""

    name: str = "andrade"
    _fit_constants = staticmethod(andrade_fit)
    _viscosity = staticmethod(andrade_viscosity)

    def describe(self) -> str:
        """One-line description."""
        return f"Andrade: ln(visc) = {self.a:.6g} + {self.b:.6g} K / T_K"


@dataclass(frozen=True)
class WaltherLaw(_TwoConstantLaw):
    """Walther (ASTM D341) ``log10 log10(nu + 0.7) = a - b log10 T_K`` through ``points``.

    Fitted through (T [degC], nu [m^2/s]) points; evaluates to nu [m^2/s].
    """

    name: str = "walther"
    _fit_constants = staticmethod(walther_fit)
    _viscosity = staticmethod(walther_viscosity)

    def describe(self) -> str:
        """One-line description."""
        return (
            f"Walther (ASTM D341): log10 log10(nu_cSt + 0.7) = {self.a:.6g} "
            f"- {self.b:.6g} log10 T_K"
        )


VISCOSITY_LAWS: dict[str, Callable[[Sequence[tuple[float, float]]], AndradeLaw | WaltherLaw]] = {
    "andrade": AndradeLaw.fit,
    "walther": WaltherLaw.fit,
}


def fluid_damping(
    matched_coefficient: ArrayLike, viscosity: ArrayLike, matched_viscosity: ArrayLike
) -> FloatArray:
    """Fluid damping coefficient at T: ``c(T) = c_match * visc(T) / visc(T_match)``.

    A Newtonian shear damper's torque is proportional to viscosity times speed (paper
    reference [2]; docs/sizing.md); density changes with temperature are neglected.

    Parameters
    ----------
    matched_coefficient : c at the matching temperature [N*m*(s/rad)**n]
    viscosity : fluid viscosity at T [Pa*s or m^2/s]
    matched_viscosity : fluid viscosity at the matching temperature, same unit
    """
    ratio = as_float(viscosity) / as_float(matched_viscosity)
    return as_float(as_float(matched_coefficient) * ratio)


def matched_coefficient(
    ecd_damping_rate: ArrayLike, speed: ArrayLike, exponent: float
) -> FloatArray:
    """Fluid coefficient giving the ECD's torque at the matching speed: ``B * w**(1 - n)``.

    For n = 1 this is the ECD's damping rate itself (paper Eq. 3 at T_match).

    Parameters
    ----------
    ecd_damping_rate : BECD at the matching temperature [N*m*s/rad]
    speed : matching speed w [rad/s]
    exponent : speed exponent n of ``torque = c * omega**n`` [-]
    """
    return as_float(as_float(ecd_damping_rate) * np.power(as_float(speed), 1.0 - exponent))


def torque_at(angles: ArrayLike, torques: ArrayLike, angle: float) -> FloatArray:
    """Spring torque at one deployed angle, interpolated between breakpoints (axis 0).

    Parameters
    ----------
    angles : deployed angles of the breakpoints, increasing along axis 0 [rad]
    torques : spring torque at the breakpoints [N*m]
    angle : where to evaluate, within the travel [rad]
    """
    phi, torque = np.broadcast_arrays(as_float(angles), as_float(torques))
    value = torque[0].copy()
    for i in range(phi.shape[0] - 1):
        length = phi[i + 1] - phi[i]
        inside = (phi[i] <= angle) & (angle <= phi[i + 1]) & (length > 0.0)
        fraction = (angle - phi[i]) / np.where(length > 0.0, length, 1.0)
        value = np.where(inside, torque[i] + fraction * (torque[i + 1] - torque[i]), value)
    return as_float(value)


def after_deadband(
    angles: ArrayLike, torques: ArrayLike, deadband: float
) -> tuple[FloatArray, FloatArray]:
    """Spring breakpoints of the travel left after the deadband, re-based to start at 0.

    Breakpoints inside the deadband collapse onto its end with the spring torque there
    (linear interpolation, as Eq. 7 or the spring table); zero-length segments take no
    time in the solvers.

    Parameters
    ----------
    angles : deployed angles of the breakpoints, along axis 0 [rad]
    torques : spring torque at the breakpoints [N*m]
    deadband : free angle at the start of travel [rad]
    """
    phi, torque = np.broadcast_arrays(as_float(angles), as_float(torques))
    at_end = torque_at(phi, torque, deadband)
    new_torque = np.where(phi < deadband, at_end, torque)
    return as_float(np.maximum(phi, deadband) - deadband), as_float(new_torque)


def within_deadband(
    angles: ArrayLike, torques: ArrayLike, deadband: float
) -> tuple[FloatArray, FloatArray]:
    """Spring breakpoints of the deadband itself: angles clipped to it, torque there.

    Parameters
    ----------
    angles : deployed angles of the breakpoints, along axis 0 [rad]
    torques : spring torque at the breakpoints [N*m]
    deadband : free angle at the start of travel [rad]
    """
    phi, torque = np.broadcast_arrays(as_float(angles), as_float(torques))
    at_end = torque_at(phi, torque, deadband)
    return as_float(np.minimum(phi, deadband)), as_float(np.where(phi > deadband, at_end, torque))


def free_motion(
    angles: Sequence[float],
    torques: Sequence[float],
    friction: float,
    deadband: float,
    inertia: float,
) -> tuple[float, float]:
    """Undamped motion through the deadband: ``J * phi'' = T(phi) - FS`` from rest.

    Returns (time to cross the deadband [s], speed at its end [rad/s]); (+inf, 0) if the
    work of the net torque falls to zero inside the deadband. The time is
    ``integral_0^d dphi / sqrt(2 W(phi) / J)`` with W the work of the net torque from the
    start (exact for the piecewise-linear spring), integrated with scipy's ``quad`` after
    the substitution phi = u**2, which removes the 1/sqrt singularity at the start.

    Parameters
    ----------
    angles : spring breakpoint angles, 0 first [rad]
    torques : spring torque at the breakpoints [N*m]
    friction : resisting Coulomb torque during the deadband, FS [N*m]
    deadband : free angle [rad]
    inertia : load inertia at the input shaft, J [kg*m^2]
    """
    from scipy.integrate import quad

    phi = np.asarray(angles, dtype=float)
    net = np.asarray(torques, dtype=float) - friction
    # Work of the net torque up to each breakpoint (trapezoid: exact for linear segments).
    starts = np.concatenate([[0.0], np.cumsum(0.5 * (net[1:] + net[:-1]) * np.diff(phi))])

    def work(x: float) -> float:
        i = int(np.clip(np.searchsorted(phi, x, side="right") - 1, 0, len(phi) - 2))
        s = x - phi[i]
        slope = (net[i + 1] - net[i]) / (phi[i + 1] - phi[i])
        return float(starts[i] + net[i] * s + 0.5 * slope * s * s)

    if deadband <= 0.0:
        return 0.0, 0.0
    probe = np.unique(np.concatenate([np.linspace(0.0, deadband, 257)[1:], phi[phi <= deadband]]))
    probe = probe[probe > 0.0]
    if net[0] <= 0.0 or any(work(float(x)) <= 0.0 for x in probe):
        return math.inf, 0.0

    def integrand(u: float) -> float:
        x = u * u
        if x == 0.0:
            return 2.0 / math.sqrt(2.0 * net[0] / inertia)
        return 2.0 * u / math.sqrt(2.0 * work(x) / inertia)

    time, _ = quad(integrand, 0.0, math.sqrt(deadband), epsabs=0.0, epsrel=1e-12, limit=200)
    return float(time), math.sqrt(2.0 * work(deadband) / inertia)


@dataclass(frozen=True)
class DeadbandDeployment:
    """A deployment with a free deadband, then a damped quasi-static phase.

    Arrays have the temperatures' shape.

    Attributes
    ----------
    deadband : free angle at the start [rad]
    damped_time : time of the damped phase, from engagement to the latch [s]; inf if stalled
    free_time : time through the deadband [s]; None without a load inertia
    engage_speed : speed at engagement [rad/s]; None without a load inertia
    total_time : free_time + damped_time [s]; None without a load inertia
    end_speed : quasi-static speed at the latch [rad/s]
    stalled : True if it stalls (in the deadband or after)
    paper_time : the damped phase by the paper's mean-speed method (Eq. 8-11; with a
        power law its start and end speeds are ``(net / c)**(1/n)``) [s]; inf if stalled
    """

    deadband: float
    damped_time: FloatArray
    free_time: FloatArray | None
    engage_speed: FloatArray | None
    total_time: FloatArray | None
    end_speed: FloatArray
    stalled: BoolArray
    paper_time: FloatArray | None = None


def deploy_with_deadband(
    problem: QuasiStaticProblem,
    system_friction: ArrayLike,
    deadband: float,
    exponent: ArrayLike = 1.0,
    inertia: float | None = None,
) -> DeadbandDeployment:
    """Deadband (free) then damped deployment, temperatures along the batch axis (1-D).

    ``problem`` holds the whole travel's spring breakpoints, the damped phase's total
    friction and the damping coefficient; the damped phase uses the exact solver for
    n = 1 and :func:`~ecdsim.physics.fluid.power_law_segment_duration` otherwise (the
    exponent may differ per temperature). During the deadband only the system friction
    acts (the damper is disengaged). The paper's mean-speed method gives ``paper_time``.

    Parameters
    ----------
    problem : spring, damped-phase friction [N*m] and damping coefficient c
    system_friction : FS_T, the friction during the deadband [N*m]
    deadband : free angle at the start [rad]
    exponent : n of ``torque = c * omega**n`` [-], a number or one per temperature
    inertia : load inertia J at the input shaft [kg*m^2], None if unknown
    """
    travel = problem.travel
    if np.any(deadband >= travel):
        raise ValueError(f"the deadband ({deadband:g} rad) is not shorter than the travel")
    angles, torques = after_deadband(problem.angles, problem.torques, deadband)
    damped = QuasiStaticProblem(angles, torques, problem.friction, problem.damping_rate)
    fs = as_float(np.broadcast_to(as_float(system_friction), problem.batch_shape))
    n = as_float(np.broadcast_to(as_float(exponent), problem.batch_shape))
    # Quasi-static stall inside the deadband: spring torque at or below FS there.
    if bool(np.all(n == 1.0)):
        solution = EXACT.solve(damped)
        time = solution.deployment_time
        stalled = solution.stalled
        end_speed = solution.end_speed
        paper = as_float(PAPER.solve(damped).deployment_time)
    else:
        stalled, _ = locate_stall(damped.angles, damped.net_torques)
        net = damped.net_torques
        pieces = [
            power_law_segment_duration(
                damped.angles[i + 1] - damped.angles[i],
                damped.damping_rate,
                n,
                net[i],
                net[i + 1],
            )
            for i in range(damped.angles.shape[0] - 1)
        ]
        time = as_float(np.where(stalled, np.inf, np.sum(np.stack(pieces), axis=0)))
        end_net = np.maximum(net[-1], 0.0)
        end_speed = as_float(np.power(end_net / damped.damping_rate, 1.0 / n))
        paper = power_law_mean_speed_time(damped.travel, damped.damping_rate, n, net[0], net[-1])
    free_time = engage = total = None
    if inertia is None:
        # Quasi-static: the load cannot cross a point of the deadband where the spring
        # torque does not exceed the system friction.
        free_angles, free_torques = within_deadband(problem.angles, problem.torques, deadband)
        stuck, _ = locate_stall(free_angles, free_torques - fs)
        stalled = np.asarray(stalled | stuck)
    else:
        free = np.zeros(problem.batch_shape)
        speed = np.zeros(problem.batch_shape)
        full_angles = np.broadcast_to(problem.angles, problem.torques.shape)
        for index in np.ndindex(problem.batch_shape):
            column = (slice(None), *index)
            free[index], speed[index] = free_motion(
                full_angles[column], problem.torques[column], float(fs[index]), deadband, inertia
            )
        free_time, engage = as_float(free), as_float(speed)
        stalled = np.asarray(stalled | ~np.isfinite(free_time))
        total = as_float(np.where(stalled, np.inf, free_time + time))
    time = as_float(np.where(stalled, np.inf, time))
    end_speed = as_float(np.where(stalled, 0.0, end_speed))
    return DeadbandDeployment(
        deadband=deadband,
        damped_time=time,
        free_time=free_time,
        engage_speed=engage,
        total_time=total,
        end_speed=end_speed,
        stalled=stalled,
        paper_time=as_float(np.where(stalled, np.inf, paper)),
    )


@dataclass(frozen=True)
class PowerLawFluid:
    """A shear-thinning damper's measured torque-speed law over temperature
    (:mod:`ecdsim.physics.fluid`; ``[fluid_damper.power_law]``).

    Attributes
    ----------
    reference_temperature : T_ref [degC]
    reference_speed : omega_r [rad/s]
    torque : T_r at omega_r and T_ref [N*m]
    exponent : n at T_ref [-]
    exponent_slope : dn/dT [1/K]
    activation : B of the Arrhenius-Andrade factor [K]
    temperatures : the bench data's temperatures [degC] (empty if not known)
    """

    reference_temperature: float
    reference_speed: float
    torque: float
    exponent: float
    exponent_slope: float
    activation: float
    temperatures: tuple[float, ...] = ()
    name: str = "power_law"

    def exponent_at(self, temperature: ArrayLike) -> FloatArray:
        """n(T) [-]."""
        return power_law_exponent(
            temperature, self.exponent, self.exponent_slope, self.reference_temperature
        )

    def reference_torque(self, temperature: ArrayLike) -> FloatArray:
        """T_r(T), the torque at omega_r [N*m]."""
        factor = arrhenius_factor(temperature, self.activation, self.reference_temperature)
        return as_float(self.torque * factor)

    def coefficient(self, temperature: ArrayLike) -> FloatArray:
        """c(T) of ``T = c omega**n`` [N*m*(s/rad)**n(T)]."""
        return power_law_coefficient(
            self.reference_torque(temperature), self.reference_speed, self.exponent_at(temperature)
        )

    def torque_at(self, speed: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """The damping torque at a speed [rad/s] and temperature [degC] [N*m]."""
        return power_law_torque(speed, self.coefficient(temperature), self.exponent_at(temperature))

    def out_of_range(self, temperature: ArrayLike) -> BoolArray:
        """True outside the bench data's temperatures (all False if they are not known)."""
        t = as_float(temperature)
        if not self.temperatures:
            return np.zeros(t.shape, dtype=bool)
        return np.asarray((t < min(self.temperatures)) | (t > max(self.temperatures)))

    def describe(self) -> str:
        """One-line description."""
        return (
            f"power law: T = {self.torque:.4g} N*m (w / {self.reference_speed:g} rad/s)^n "
            f"exp({self.activation:.4g} K (1/T_K - 1/T_ref)), n = {self.exponent:.4g}"
            + (f" {self.exponent_slope:+.3g}/K (T - T_ref)" if self.exponent_slope else "")
            + f", T_ref = {self.reference_temperature:g} degC"
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready constants (SI)."""
        return {
            "reference_temperature_C": self.reference_temperature,
            "reference_speed_rad_s": self.reference_speed,
            "torque_Nm": self.torque,
            "exponent": self.exponent,
            "exponent_slope_per_K": self.exponent_slope,
            "activation_K": self.activation,
            "temperatures_C": list(self.temperatures),
        }


def power_law_fluid(spec: FluidDamperSpec) -> PowerLawFluid:
    """The power-law fluid of a ``[fluid_damper]`` that has ``power_law``."""
    law = spec.power_law
    assert law is not None
    return PowerLawFluid(
        reference_temperature=law.reference_temperature,
        reference_speed=law.reference_speed,
        torque=law.torque,
        exponent=law.exponent,
        exponent_slope=law.exponent_slope,
        activation=law.activation,
        temperatures=tuple(law.temperatures),
    )


@dataclass(frozen=True)
class FluidComparison:
    """The ECD and the fluid damper over temperature.

    Attributes
    ----------
    temperatures : T [degC]
    law : the fitted viscosity law, or the measured power law
    source : where the fluid data come from
    name : the fluid damper's name
    match_temperature : T_match [degC]; None for a measured power law (not matched)
    match_speed : speed at which torques are matched [rad/s] (n != 1 only; else None)
    exponent : n (at the reference temperature for a power law) [-]
    matched_coefficient : c(T_match) [N*m*(s/rad)**n]; None for a power law
    ecd_damping_rate : BECD_T [N*m*s/rad]
    fluid_coefficient : c(T) [N*m*(s/rad)**n(T)]
    viscosity : visc(T) [SI unit of the points]; None for a power law
    fluid_friction : FECD_T, or the fluid damper's own friction [N*m]
    ecd : the ECD's deployment (its lost motion as deadband)
    fluid : the fluid damper's deployment
    extrapolated : True where T lies outside the fitted points
    fluid_exponent : n(T) [-]
    reference_speed : the speed at which both dampers' torques are shown [rad/s]
        (the power law's omega_r, else the matching speed, else None)
    method : ``"quasi-static"`` or ``"dynamic"``, how both deployments were computed
    """

    temperatures: FloatArray
    law: AndradeLaw | WaltherLaw | PowerLawFluid
    source: str
    name: str
    match_temperature: float | None
    match_speed: float | None
    exponent: float
    matched_coefficient: float | None
    ecd_damping_rate: FloatArray
    fluid_coefficient: FloatArray
    viscosity: FloatArray | None
    fluid_friction: FloatArray
    ecd: DeadbandDeployment
    fluid: DeadbandDeployment
    extrapolated: BoolArray
    fluid_exponent: FloatArray | None = None
    reference_speed: float | None = None
    method: str = "quasi-static"

    @property
    def exponents(self) -> FloatArray:
        """n at each temperature [-]."""
        if self.fluid_exponent is not None:
            return self.fluid_exponent
        return as_float(np.full(self.temperatures.shape, self.exponent))

    def torques_at_reference(self) -> tuple[FloatArray, FloatArray] | None:
        """The ECD's and the fluid's damping torque at the reference speed [N*m] (no
        Coulomb friction), or None without a reference speed: the spread over
        temperature, speed for speed."""
        w = self.reference_speed
        if w is None:
            return None
        ecd = as_float(self.ecd_damping_rate * w)
        fluid = power_law_torque(w, self.fluid_coefficient, self.exponents)
        return ecd, fluid

    def engagement_torques(self) -> tuple[FloatArray | None, FloatArray | None]:
        """The damping torque at engagement, ECD and fluid damper [N*m]; None without inertia.

        At the end of its deadband the damper engages at the speed the undamped load has
        reached, so its torque jumps at once to ``coefficient * engage_speed**n`` (the
        paper's case for the ECD: a fluid damper's 15 deg or more of deadband against
        the ECD's lost motion of 0.25 deg at most, section 3.4). An ECD without lost
        motion engages at rest: 0. Infinite where the engagement speed is.
        """
        if self.ecd.engage_speed is None or self.fluid.engage_speed is None:
            return None, None
        ecd = as_float(self.ecd_damping_rate * self.ecd.engage_speed)
        fluid = as_float(self.fluid_coefficient * np.power(self.fluid.engage_speed, self.exponents))
        return ecd, fluid

    def _law_block(self) -> dict[str, Any]:
        law = self.law
        if isinstance(law, PowerLawFluid):
            return {
                "law": law.name,
                "law_description": law.describe(),
                "constants": law.to_dict(),
                "points": [],
            }
        return {
            "law": law.name,
            "law_description": law.describe(),
            "constants": {"A": law.a, "B": law.b},
            "points": [{"temperature_C": t, "viscosity_SI": v} for t, v in law.points],
        }

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (infinite times and speeds become null); see docs/sizing.md."""

        def number(x: float) -> float | None:
            return float(x) if math.isfinite(x) else None

        ecd_shock, fluid_shock = self.engagement_torques()
        at_reference = self.torques_at_reference()

        def side(d: DeadbandDeployment, i: int, shock: FloatArray | None) -> dict[str, Any]:
            return {
                "engagement_torque_Nm": None if shock is None else number(float(shock[i])),
                "deadband_rad": d.deadband,
                "damped_time_s": number(float(d.damped_time[i])),
                "damped_time_paper_s": (
                    None if d.paper_time is None else number(float(d.paper_time[i]))
                ),
                "free_time_s": None if d.free_time is None else number(float(d.free_time[i])),
                "engage_speed_rad_s": (
                    None if d.engage_speed is None else number(float(d.engage_speed[i]))
                ),
                "total_time_s": None if d.total_time is None else number(float(d.total_time[i])),
                "end_speed_rad_s": number(float(d.end_speed[i])),
                "stalled": bool(d.stalled[i]),
            }

        exponents = self.exponents
        return {
            "ecdsim_version": __version__,
            "method": self.method,
            "fluid_damper": {
                "name": self.name,
                "source": self.source,
                **self._law_block(),
                "exponent": self.exponent,
                "match_temperature_C": self.match_temperature,
                "match_speed_rad_s": self.match_speed,
                "matched_coefficient": self.matched_coefficient,
                "reference_speed_rad_s": self.reference_speed,
            },
            "cases": [
                {
                    "temperature_C": float(t),
                    "ecd_damping_rate_Nms_per_rad": float(self.ecd_damping_rate[i]),
                    "fluid_coefficient": float(self.fluid_coefficient[i]),
                    "fluid_exponent": float(exponents[i]),
                    "viscosity_SI": None if self.viscosity is None else float(self.viscosity[i]),
                    "fluid_friction_Nm": float(self.fluid_friction[i]),
                    "viscosity_extrapolated": bool(self.extrapolated[i]),
                    "extrapolated": bool(self.extrapolated[i]),
                    "ecd_torque_at_reference_Nm": (
                        None if at_reference is None else float(at_reference[0][i])
                    ),
                    "fluid_torque_at_reference_Nm": (
                        None if at_reference is None else float(at_reference[1][i])
                    ),
                    "ecd": side(self.ecd, i, ecd_shock),
                    "fluid": side(self.fluid, i, fluid_shock),
                }
                for i, t in enumerate(self.temperatures)
            ],
        }


def _integrated_side(result: DynamicResult, deadband: float) -> DeadbandDeployment:
    """An integrated deployment as the comparison's side: free time to the engagement,
    damped time from it to the arrival (inf where the load never arrives)."""
    total = as_float(np.ravel(result.deployment_time))
    arrived = np.isfinite(total)
    free = as_float(np.ravel(result.engagement_time))
    return DeadbandDeployment(
        deadband=deadband,
        damped_time=as_float(np.where(arrived, total - free, np.inf)),
        free_time=free,
        engage_speed=as_float(np.ravel(fluid_damper.engagement_speed(result))),
        total_time=as_float(np.where(arrived, total, np.inf)),
        end_speed=as_float(np.where(arrived, np.ravel(result.arrival_speed), 0.0)),
        stalled=np.asarray(~arrived),
    )


def compare_fluid(
    system: DeploymentSystem,
    spec: FluidDamperSpec,
    temperatures: ArrayLike,
    load_inertia: float | None = None,
    method: str = "quasi-static",
    dynamics: DynamicParameters | None = None,
) -> FluidComparison:
    """The ECD and a fluid damper over the temperatures [degC].

    The fluid damper is either a viscosity law matched to the ECD at T_match (its
    coefficient ``c(T) = c(T_match) visc(T) / visc(T_match)``, docs/sizing.md), or its
    measured power law ``[fluid_damper.power_law]`` (``c(T)`` and ``n(T)`` as fitted, not
    matched: the real spread over temperature, docs/qualification.md). Both deployments
    use the same spring and system friction. The fluid damper's Coulomb friction is the
    ECD's FECD_T at each temperature unless the spec gives its own, so that the
    comparison isolates the damping's temperature law. The load inertia for the free
    motion through a deadband is ``spec.load_inertia``, else ``load_inertia`` [kg*m^2]
    (e.g. the config's ``[load] inertia``), else none (free time not computed). Raises
    :class:`~ecdsim.deployment.ModelDomainError` where BECD <= 0 and ``ValueError`` if a
    deadband is not shorter than the travel or the load has gravity (a ground test).

    ``method`` is ``"quasi-static"`` (the closed-form times above) or ``"dynamic"``: both
    dampers' deployments integrated with inertia on the dynamic core
    (:mod:`ecdsim.sizing.fluid_dynamic`), with ``dynamics`` (the config's dynamic
    parameters, or only the load inertia) and the same load inertia as above (required).
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    gravity = system.load.gravity
    if gravity is not None and bool(np.any(gravity.amplitude > 0.0)):
        # The fluid side's deployment is the piecewise-linear exact solution: with a sine
        # drive the two dampers would not be compared on the same load.
        raise ValueError(
            "load.gravity: the fluid-damper comparison does not model gravity; compare "
            "in flight (a config without [load.gravity], or offload = 1)"
        )
    temps = as_float(temperatures).reshape(-1)
    ecd_run = predict(system, temps, ("exact",))
    law: AndradeLaw | WaltherLaw | PowerLawFluid
    viscosity: FloatArray | None = None
    match_speed: float | None = None
    coefficient: float | None = None
    if spec.power_law is not None:
        law = power_law_fluid(spec)
        fluid_c = law.coefficient(temps)
        exponents = law.exponent_at(temps)
        exponent = law.exponent
        reference_speed: float | None = law.reference_speed
        match_temperature: float | None = None
    else:
        assert spec.law is not None  # the schema requires it without power_law
        law = VISCOSITY_LAWS[spec.law](spec.viscosity_points())
        matching = predict(system, as_float([spec.match_temperature]), ("exact",))
        becd_match = float(np.ravel(matching.ecd.ecd_damping_rate)[0])
        if spec.exponent != 1.0:
            if spec.match_speed is not None:
                match_speed = spec.match_speed
            else:
                time = float(np.ravel(matching.solutions["exact"].deployment_time)[0])
                travel = float(np.ravel(matching.problem.travel)[0])
                if not math.isfinite(time):
                    raise ValueError(
                        "fluid_damper.match_speed: the ECD stalls at the matching "
                        "temperature; give match_speed explicitly"
                    )
                match_speed = travel / time
        coefficient = float(matched_coefficient(becd_match, match_speed or 1.0, spec.exponent))
        viscosity = law(temps)
        fluid_c = fluid_damping(coefficient, viscosity, law(spec.match_temperature))
        exponent = spec.exponent
        exponents = as_float(np.full(temps.shape, exponent))
        reference_speed = match_speed
        match_temperature = spec.match_temperature
    problem = ecd_run.problem
    fs = ecd_run.system_friction
    if spec.coulomb_friction is None:
        fluid_friction = as_float(np.broadcast_to(ecd_run.ecd.ecd_friction, temps.shape))
    else:
        fluid_friction = as_float(np.full(temps.shape, spec.coulomb_friction))
    fluid_problem = QuasiStaticProblem(
        problem.angles, problem.torques, fluid_friction + fs, fluid_c
    )
    inertia = spec.load_inertia if spec.load_inertia is not None else load_inertia
    if method == METHODS[0]:
        ecd_side = deploy_with_deadband(problem, fs, system.ecd.gearbox.lost_motion, 1.0, inertia)
        fluid_side = deploy_with_deadband(fluid_problem, fs, spec.deadband, exponents, inertia)
    else:
        if spec.deadband >= float(np.max(problem.travel)):
            raise ValueError(f"the deadband ({spec.deadband:g} rad) is not shorter than the travel")
        params = fluid_damper.parameters_for(dynamics, inertia)
        hinge = predict(system, temps, (), dynamics=params).problem  # the ECD's, unsolved
        ecd_result, fluid_result = fluid_damper.deployments(
            hinge,
            as_float(np.broadcast_to(fluid_c, temps.shape)),
            as_float(np.broadcast_to(exponents, temps.shape)),
            reference_speed if reference_speed is not None else 1.0,
            fluid_friction,
            spec.deadband,
        )
        ecd_side = _integrated_side(ecd_result, system.ecd.gearbox.lost_motion)
        fluid_side = _integrated_side(fluid_result, spec.deadband)
    return FluidComparison(
        temperatures=temps,
        law=law,
        source=spec.source,
        name=spec.name,
        match_temperature=match_temperature,
        match_speed=match_speed,
        exponent=exponent,
        matched_coefficient=coefficient,
        ecd_damping_rate=as_float(np.broadcast_to(ecd_run.ecd.ecd_damping_rate, temps.shape)),
        fluid_coefficient=as_float(np.broadcast_to(fluid_c, temps.shape)),
        viscosity=None if viscosity is None else as_float(np.broadcast_to(viscosity, temps.shape)),
        fluid_friction=fluid_friction,
        ecd=ecd_side,
        fluid=fluid_side,
        extrapolated=law.out_of_range(temps),
        fluid_exponent=as_float(np.broadcast_to(exponents, temps.shape)),
        reference_speed=reference_speed,
        method=method,
    )
