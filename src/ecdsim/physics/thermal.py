"""Self-heating of the damper: one lumped heat capacity, optionally cooled to ambient.

The paper rates the damping at +25 degC and gives its temperature law (Eq. 1) but treats
the damper's temperature as the ambient one. The energy a deployment dissipates in the
damper's conductor heats it; ecdsim models the damper as a single isothermal body (the
lumped-capacitance model, valid for Biot numbers well below 0.1; Incropera, DeWitt,
Bergman and Lavine, *Fundamentals of Heat and Mass Transfer*, 6th ed., section 5.1,
Eq. 5.2 with a heat source):

    C * dT/dt = P - (T - T_ambient) / R

with C the heat capacity, P the dissipated power and R the thermal resistance to the
ambient (``R = inf``: adiabatic, the conservative choice for a deployment lasting
seconds to minutes).
"""

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, as_float


def heat_loss(
    temperature: ArrayLike, ambient_temperature: ArrayLike, thermal_resistance: ArrayLike
) -> FloatArray:
    """Heat flow from the damper to ambient: ``(T - T_ambient) / R``; 0 where R is inf.

    The loss term of the lumped-capacitance balance (Incropera, DeWitt, Bergman and
    Lavine 2007, section 5.1, Eq. 5.2), written with a thermal resistance (their
    section 3.1.3).

    Parameters
    ----------
    temperature : damper temperature T [degC]
    ambient_temperature : T_ambient [degC]
    thermal_resistance : R, damper to ambient [K/W], > 0; ``inf`` for adiabatic

    >>> float(heat_loss(30.0, 25.0, 2.5))
    2.0
    >>> float(heat_loss(30.0, 25.0, float("inf")))
    0.0
    """
    r = np.asarray(thermal_resistance, dtype=float)
    dt = np.asarray(temperature, dtype=float) - np.asarray(ambient_temperature, dtype=float)
    finite = np.isfinite(r)
    return np.where(finite, dt / np.where(finite, r, 1.0), 0.0)


def temperature_rate(
    power: ArrayLike,
    temperature: ArrayLike,
    ambient_temperature: ArrayLike,
    heat_capacity: ArrayLike,
    thermal_resistance: ArrayLike,
) -> FloatArray:
    """``dT/dt = (P - (T - T_ambient) / R) / C`` of the lumped damper (Incropera Eq. 5.2).

    Parameters
    ----------
    power : heat dissipated in the damper P [W]
    temperature : damper temperature T [degC]
    ambient_temperature : T_ambient [degC]
    heat_capacity : C, the damper's heat capacity [J/K], > 0
    thermal_resistance : R, damper to ambient [K/W]; ``inf`` for adiabatic

    >>> float(temperature_rate(10.0, 25.0, 25.0, 5.0, float("inf")))
    2.0
    """
    loss = heat_loss(temperature, ambient_temperature, thermal_resistance)
    return as_float(
        (np.asarray(power, dtype=float) - loss) / np.asarray(heat_capacity, dtype=float)
    )


def adiabatic_temperature_rise(energy: ArrayLike, heat_capacity: ArrayLike) -> FloatArray:
    """Temperature rise of an adiabatic lumped body: ``dT = E / C``.

    Incropera, DeWitt, Bergman and Lavine 2007, section 5.1, Eq. 5.2 integrated with no
    loss to ambient (R = inf): the energy a deployment dissipates in the damper (paper
    Eq. 5's damping torque times the speed, integrated over the deployment).

    Parameters
    ----------
    energy : heat put into the body E [J]
    heat_capacity : C [J/K], > 0

    >>> round(float(adiabatic_temperature_rise(4.2, 90.0)), 6)  # ~4 J into a 90 J/K damper
    0.046667
    """
    return as_float(np.asarray(energy, dtype=float) / np.asarray(heat_capacity, dtype=float))


# Heating towards the zero of the damping law
# ------------------------------------------
# Both damping laws scale with an affine temperature factor f(T) = 1 + c (T - T_ref): the
# paper's Eq. 1 (BD_T = BD f, c = -0.004/K) and the Kloss law's peak speed
# (omega_peak = omega_peak_ref f, c = alpha). With c < 0 the factor reaches zero at
# T_zero = T_ref - 1/c (275 degC for the paper's damper), and so does the heating power
# P = f p (p = P / f stays finite there). Adiabatically, C dT/dt = f p gives
# df/dt = c f p / C: f decays exponentially at most and never reaches zero, so T_zero is
# approached, never crossed. Integrated as T, the approach ends at T_zero within the
# integrator's error (and within one rounding of T), where Eq. 1 gives BD_T <= 0. The
# state s = ln(f / f_a) / c (f_a = f(T_ambient)), the damping factor's logarithm in
# kelvin, keeps the invariant exactly: f = f_a exp(c s) > 0 for every finite s. With
# dT/ds = f, the heat balance becomes ds/dt = (p - (T - T_ambient) / (R f)) / C, smooth
# and bounded up to T_zero; (T - T_ambient) / f = s E(-c s) with E(z) = (e^z - 1) / z
# needs no division by the vanishing f. At c = 0 the state is (T - T_ambient) / f_a.


def temperature_from_factor_log(
    state: ArrayLike,
    ambient_temperature: ArrayLike,
    ambient_factor: ArrayLike,
    coefficient: ArrayLike,
) -> FloatArray:
    """Damper temperature from the damping factor's log: ``T_amb + f_a s E(c s)``.

    ``s = ln(f(T) / f_a) / c`` for a damping law scaled by ``f(T) = 1 + c (T - T_ref)``
    (Eq. 1 of the ECD paper; the Kloss law's resistivity factor), ``E(z) = (e^z - 1)/z``.
    Where c < 0, T tends to the law's zero ``T_ref - 1/c`` as s grows and never reaches
    it; the factor itself is :func:`damping_factor_from_log`.

    Parameters
    ----------
    state : s, the damping factor's logarithm over c [K]
    ambient_temperature : T_ambient, where s = 0 [degC]
    ambient_factor : f_a, the damping factor at T_ambient [-], >= 0
    coefficient : c, the factor's fractional change per kelvin [1/K]

    >>> round(float(temperature_from_factor_log(0.0, 25.0, 1.0, -0.004)), 12)
    25.0
    >>> round(float(temperature_from_factor_log(1e4, 25.0, 1.0, -0.004)), 9)  # f = e^-40
    275.0
    >>> float(temperature_from_factor_log(2.0, 25.0, 0.5, 0.0))  # c = 0: T = T_amb + f_a s
    26.0
    """
    s = as_float(state)
    shift = as_float(ambient_factor) * s * _exprel(as_float(coefficient) * s)
    return as_float(as_float(ambient_temperature) + shift)


def damping_factor_from_log(
    state: ArrayLike, ambient_factor: ArrayLike, coefficient: ArrayLike
) -> FloatArray:
    """The damping law's temperature factor ``f = f_a exp(c s)``, > 0 where f_a > 0.

    The factor of Eq. 1 of the ECD paper (c = -0.004 / K) or of the Kloss law's peak
    speed (c = alpha), from the log state of the module notes.

    Parameters
    ----------
    state : s, the damping factor's logarithm over c [K]
    ambient_factor : f_a, the factor at the ambient temperature [-], >= 0
    coefficient : c [1/K]

    >>> round(float(damping_factor_from_log(250.0 * np.log(2.0), 1.0, -0.004)), 12)
    0.5
    """
    return as_float(as_float(ambient_factor) * np.exp(as_float(coefficient) * as_float(state)))


def factor_log_rate(
    power_per_factor: ArrayLike,
    state: ArrayLike,
    heat_capacity: ArrayLike,
    thermal_resistance: ArrayLike,
    coefficient: ArrayLike,
) -> FloatArray:
    """``ds/dt = (p - (T - T_amb) / (R f)) / C``: the lumped heat balance in the log state.

    Incropera Eq. 5.2, ``C dT/dt = P - (T - T_amb) / R``, divided by ``dT/ds = f``, with
    ``P = f p`` and ``(T - T_amb) / f = s E(-c s)`` (see the module notes), so that
    nothing is divided by the vanishing factor.

    Parameters
    ----------
    power_per_factor : p, the heating power over the damping factor [W]
    state : s, the damping factor's logarithm over c [K]
    heat_capacity : C [J/K], > 0
    thermal_resistance : R, damper to ambient [K/W]; ``inf`` for adiabatic
    coefficient : c [1/K]

    >>> float(factor_log_rate(2.0, 30.0, 0.5, float("inf"), -0.004))  # adiabatic: p / C
    4.0
    >>> float(factor_log_rate(2.0, 5.0, 0.5, 2.5, 0.0))  # c = 0: (P - (T - T_amb) / R) / C
    0.0
    """
    power = as_float(power_per_factor)
    r = as_float(thermal_resistance)
    finite = np.isfinite(r)
    if not np.any(finite):  # adiabatic (the usual case): no loss term to evaluate
        return as_float(power / as_float(heat_capacity))
    s = as_float(state)
    if np.all(finite):
        loss = s * _exprel(-as_float(coefficient) * s) / r
    else:
        # E(-c s) grows as f shrinks; it is only evaluated where a resistance cools.
        growth = _exprel(-as_float(coefficient) * np.where(finite, s, 0.0))
        loss = np.where(finite, s * growth / np.where(finite, r, 1.0), 0.0)
    return as_float((power - loss) / as_float(heat_capacity))


def _exprel(z: FloatArray) -> FloatArray:
    """``E(z) = (e^z - 1) / z``, 1 at z = 0; inf (no warning) where e^z overflows.

    NumPy's expm1 over z is three times faster than ``scipy.special.exprel``, and this
    runs in the integrator's right-hand side.
    """
    with np.errstate(over="ignore"):
        grown = np.expm1(z)
    return np.divide(grown, z, out=np.ones_like(grown), where=z != 0.0)


def factor_log_rate_slope(
    power_per_factor_slope: ArrayLike,
    factor: ArrayLike,
    state: ArrayLike,
    heat_capacity: ArrayLike,
    thermal_resistance: ArrayLike,
    coefficient: ArrayLike,
) -> FloatArray:
    """``d(ds/dt)/ds = (c f dp/df - exp(-c s) / R) / C``: :func:`factor_log_rate`'s slope.

    The Jacobian entry of the temperature state. Uses ``df/ds = c f`` and
    ``d(s E(-c s))/ds = exp(-c s)``; the heat balance is Incropera Eq. 5.2 in the log
    state (:func:`factor_log_rate`).

    Parameters
    ----------
    power_per_factor_slope : dp/df at fixed speed [W]
    factor : f, the damping factor [-]
    state : s [K]
    heat_capacity : C [J/K], > 0
    thermal_resistance : R [K/W]; ``inf`` for adiabatic
    coefficient : c [1/K]

    >>> float(factor_log_rate_slope(0.0, 1.0, 0.0, 2.0, 0.5, -0.004))  # -1 / (R C)
    -1.0
    """
    c = as_float(coefficient)
    slope = c * as_float(factor) * as_float(power_per_factor_slope)
    r = as_float(thermal_resistance)
    finite = np.isfinite(r)
    if np.any(finite):
        cooling = np.where(finite, np.exp(-c * np.where(finite, as_float(state), 0.0)), 0.0)
        slope = slope - cooling / np.where(finite, r, 1.0)
    return as_float(slope / as_float(heat_capacity))
