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

from ecdsim._types import ArrayLike, FloatArray, Real, as_float


def heat_loss(temperature: Real, ambient_temperature: Real, thermal_resistance: Real) -> Real:
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
    # A finite difference over an infinite resistance is 0: adiabatic without a branch.
    return (temperature - ambient_temperature) / thermal_resistance


def temperature_rate(
    power: Real,
    temperature: Real,
    ambient_temperature: Real,
    heat_capacity: Real,
    thermal_resistance: Real,
) -> Real:
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
    return (power - loss) / heat_capacity


def adiabatic_temperature_rise(energy: Real, heat_capacity: Real) -> Real:
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
    return energy / heat_capacity


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
    state: Real,
    ambient_temperature: Real,
    ambient_factor: Real,
    coefficient: Real,
) -> Real:
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
    return ambient_temperature + ambient_factor * state * exprel(coefficient * state)


def damping_factor_from_log(state: Real, ambient_factor: Real, coefficient: Real) -> Real:
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
    return ambient_factor * np.exp(coefficient * state)


def factor_log_rate(
    power_per_factor: Real,
    state: Real,
    heat_capacity: Real,
    thermal_resistance: Real,
    coefficient: Real,
) -> Real:
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
    return factor_log_heating(power_per_factor, heat_capacity) - factor_log_cooling(
        state, heat_capacity, thermal_resistance, coefficient
    )


def factor_log_heating(power_per_factor: Real, heat_capacity: Real) -> Real:
    """The heating term of :func:`factor_log_rate`: ``p / C`` (Incropera Eq. 5.2's source
    ``P / C`` over ``dT/ds = f``, with ``P = f p``).

    Parameters
    ----------
    power_per_factor : p, the heating power over the damping factor [W]
    heat_capacity : C [J/K], > 0

    >>> float(factor_log_heating(2.0, 0.5))
    4.0
    """
    return power_per_factor / heat_capacity


def factor_log_cooling(
    state: Real, heat_capacity: Real, thermal_resistance: Real, coefficient: Real
) -> Real:
    """The cooling term of :func:`factor_log_rate`: ``(T - T_amb) / (R f C) = s E(-c s) / (R C)``.

    The loss to ambient of Incropera Eq. 5.2 in the log state (module notes); 0 where the
    damper is adiabatic (R = inf), which the dynamic kernel then skips.

    Parameters
    ----------
    state : s, the damping factor's logarithm over c [K]
    heat_capacity : C [J/K], > 0
    thermal_resistance : R, damper to ambient [K/W]; ``inf`` for adiabatic
    coefficient : c [1/K]

    >>> float(factor_log_cooling(5.0, 0.5, 2.5, 0.0))  # (T - T_amb) / (R C) at c = 0
    4.0
    """
    return state * exprel(-coefficient * state) / (thermal_resistance * heat_capacity)


def exprel(z: Real) -> Real:
    """``E(z) = (e^z - 1) / z``, 1 at z = 0: the relative growth of the damping factor.

    The function that turns the damping law's log state into a temperature
    (:func:`temperature_from_factor_log`, the Eq. 1 factor of the ECD paper in the log
    form of the module notes). Written without a branch (the 1 added to the numerator
    and the denominator at z = 0 only), so that floats, arrays and numba's compiled
    kernel (:mod:`ecdsim.dynamics.kernel`) take the same code; e^z overflows (to inf)
    only beyond z = 709, a rise no damping law reaches.

    Parameters
    ----------
    z : c s, the log state times the factor's coefficient [-]

    >>> float(exprel(0.0)), round(float(exprel(1.0)), 12)
    (1.0, 1.718281828459)
    """
    zero = z == 0.0
    return (np.expm1(z) + zero) / (z + zero)


def factor_log_rate_slope(
    power_per_factor_slope: Real,
    factor: Real,
    state: Real,
    heat_capacity: Real,
    thermal_resistance: Real,
    coefficient: Real,
) -> Real:
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
    heating = factor_log_heating_slope(power_per_factor_slope, factor, heat_capacity, coefficient)
    return heating - factor_log_cooling_slope(state, heat_capacity, thermal_resistance, coefficient)


def factor_log_heating_slope(
    power_per_factor_slope: Real, factor: Real, heat_capacity: Real, coefficient: Real
) -> Real:
    """``d/ds`` of :func:`factor_log_heating` at fixed speed: ``c f (dp/df) / C`` (df/ds =
    c f; Incropera Eq. 5.2 in the log state).

    Parameters
    ----------
    power_per_factor_slope : dp/df at fixed speed [W]
    factor : f [-]
    heat_capacity : C [J/K], > 0
    coefficient : c [1/K]

    >>> float(factor_log_heating_slope(2.0, 0.5, 0.25, -0.004))
    -0.016
    """
    return coefficient * factor * power_per_factor_slope / heat_capacity


def factor_log_cooling_slope(
    state: Real, heat_capacity: Real, thermal_resistance: Real, coefficient: Real
) -> Real:
    """``d/ds`` of :func:`factor_log_cooling`: ``exp(-c s) / (R C)`` (Incropera Eq. 5.2 in
    the log state, ``d(s E(-c s))/ds = exp(-c s)``); 0 where adiabatic.

    Parameters
    ----------
    state : s [K]
    heat_capacity : C [J/K], > 0
    thermal_resistance : R [K/W]; ``inf`` for adiabatic
    coefficient : c [1/K]

    >>> float(factor_log_cooling_slope(0.0, 2.0, 0.5, -0.004))  # 1 / (R C)
    1.0
    """
    return np.exp(-coefficient * state) / (thermal_resistance * heat_capacity)


# Two nodes: the damper's rotor and its housing
# ---------------------------------------------
# The eddy-current power is dissipated in the rotor's conductor; the rotor passes it to
# the housing, which passes it to the mounting interface at the environment (deployment)
# temperature. Two lumped capacitances joined by thermal resistances: the thermal
# circuit of Incropera, DeWitt, Bergman and Lavine 2007 (section 3.1.3) with the lumped
# capacitance balance of their section 5.2 written for each node:
#
#     C_r dT_r/dt = P - (T_r - T_h) / R_rh
#     C_h dT_h/dt = (T_r - T_h) / R_rh - (T_h - T_env) / R_he
#
# In the rotor's log state s (the notes above) the first line becomes
# ds/dt = (p - (T_r - T_env) / (R_rh f) + (T_h - T_env) / (R_rh f)) / C_r: the one-node
# balance with R = R_rh plus the heat the housing returns, :func:`housing_return`.
# Without power the pair relaxes linearly, in closed form (:func:`two_node_relaxation`).


def housing_return(
    housing_rise: Real,
    factor: Real,
    coupling_resistance: Real,
    heat_capacity: Real,
) -> Real:
    """``(T_h - T_env) / (R_rh f C_r)``: the housing's term in the rotor's ``ds/dt``.

    The two-node balance (Incropera et al. 2007, sections 3.1.3 and 5.2; module notes)
    in the rotor's log state: the rotor loses ``(T_r - T_h) / R_rh``, of which
    ``-(T_h - T_env) / R_rh`` is this term times ``f C_r``. 0 where R_rh is inf or the
    factor is 0 (a damping law already at its zero at the environment temperature).

    Parameters
    ----------
    housing_rise : T_h - T_env [K]
    factor : f, the damping law's temperature factor at the rotor temperature [-]
    coupling_resistance : R_rh, rotor to housing [K/W]; ``inf`` for none
    heat_capacity : C_r, the rotor's heat capacity [J/K], > 0

    >>> float(housing_return(2.0, 0.5, 4.0, 0.5))  # 2 / (4 * 0.5 * 0.5)
    2.0
    """
    # f = 0 (the law at its zero) returns 0 rather than dividing by it; an infinite
    # resistance (no coupling) gives 0 by itself.
    positive = factor > 0.0
    den = coupling_resistance * (factor + (factor <= 0.0)) * heat_capacity
    # numpy types a bool mask times a float as a float array of unknown width
    return housing_rise / den * positive  # type: ignore[return-value]


def housing_rate(
    rotor_rise: Real,
    housing_rise: Real,
    heat_capacity: Real,
    coupling_resistance: Real,
    environment_resistance: Real,
) -> Real:
    """``dT_h/dt = ((T_r - T_h) / R_rh - (T_h - T_env) / R_he) / C_h`` (two-node network).

    Incropera et al. 2007, section 5.2's lumped balance of the housing node, with the
    resistances of their section 3.1.3 (module notes).

    Parameters
    ----------
    rotor_rise : T_r - T_env [K]
    housing_rise : T_h - T_env [K]
    heat_capacity : C_h, the housing's heat capacity [J/K], > 0
    coupling_resistance : R_rh, rotor to housing [K/W]; ``inf`` for none
    environment_resistance : R_he, housing to the environment [K/W]; ``inf`` adiabatic

    >>> float(housing_rate(10.0, 4.0, 3.0, 2.0, 4.0))  # (6 / 2 - 4 / 4) / 3
    0.6666666666666666
    """
    gain = heat_loss(rotor_rise, housing_rise, coupling_resistance)
    loss = heat_loss(housing_rise, 0.0, environment_resistance)
    return (gain - loss) / heat_capacity


def factor_log_from_rise(rise: Real, ambient_factor: Real, coefficient: Real) -> Real:
    """The log state ``s = ln(1 + c (T - T_amb) / f_a) / c`` of a temperature rise.

    The inverse of :func:`temperature_from_factor_log` (``f(T) = f_a + c (T - T_amb)``
    for the affine factor of Eq. 1); at c = 0, ``s = (T - T_amb) / f_a``. The rise must
    stay below the law's zero (``1 + c rise / f_a > 0``).

    Parameters
    ----------
    rise : T - T_ambient [K]
    ambient_factor : f_a [-], > 0
    coefficient : c [1/K]

    >>> round(float(factor_log_from_rise(125.0, 1.0, -0.004)), 9)  # f = 1/2: ln 2 / 0.004
    173.28679514
    >>> float(factor_log_from_rise(3.0, 0.5, 0.0))
    6.0
    """
    zero = coefficient == 0.0
    relative = rise / ambient_factor
    # c = 0: log1p(0) = 0, and the rise over f_a over 1; else log1p(c rise / f_a) / c.
    return (np.log1p(coefficient * relative) + zero * relative) / (coefficient + zero)


def two_node_relaxation(
    rotor_rise: ArrayLike,
    housing_rise: ArrayLike,
    time: ArrayLike,
    rotor_heat_capacity: ArrayLike,
    housing_heat_capacity: ArrayLike,
    coupling_resistance: ArrayLike,
    environment_resistance: ArrayLike,
) -> tuple[FloatArray, FloatArray]:
    """Rotor and housing rises after ``time`` without power: ``theta(t) = exp(A t) theta0``.

    The two-node network of the module notes with P = 0 is linear,
    ``theta' = A theta`` with ``A = [[-a, a], [b, -(b + d)]]``, ``a = 1 / (R_rh C_r)``,
    ``b = 1 / (R_rh C_h)``, ``d = 1 / (R_he C_h)`` (Incropera et al. 2007, sections
    3.1.3 and 5.2). Its eigenvalues ``l = m +- q``, ``m = -(a + b + d) / 2``,
    ``q = sqrt((a - b - d)^2 / 4 + a b)``, are real and <= 0, and the matrix exponential
    is ``exp(A t) = e^{m t} (cosh(q t) I + sinh(q t) / q (A - m I))`` (Cayley-Hamilton),
    written with ``e^{l t}`` so that nothing overflows.

    Parameters
    ----------
    rotor_rise : T_r - T_env at the start [K]
    housing_rise : T_h - T_env at the start [K]
    time : t >= 0 [s]
    rotor_heat_capacity : C_r > 0 [J/K]
    housing_heat_capacity : C_h > 0 [J/K]
    coupling_resistance : R_rh [K/W]; ``inf`` for none
    environment_resistance : R_he [K/W]; ``inf`` for an adiabatic housing

    >>> r, h = two_node_relaxation(10.0, 0.0, 1e9, 1.0, 1.0, 1.0, float("inf"))
    >>> round(float(r), 12), round(float(h), 12)  # adiabatic pair: shared to 5 K each
    (5.0, 5.0)
    """
    cond_rh = 1.0 / as_float(coupling_resistance)  # 1 / inf = 0: no coupling
    cond_he = 1.0 / as_float(environment_resistance)
    a = cond_rh / as_float(rotor_heat_capacity)
    b = cond_rh / as_float(housing_heat_capacity)
    d = cond_he / as_float(housing_heat_capacity)
    m = -0.5 * (a + b + d)
    q = np.sqrt(0.25 * (a - b - d) ** 2 + a * b)
    t = as_float(time)
    e1 = np.exp((m + q) * t)
    e2 = np.exp((m - q) * t)
    even = 0.5 * (e1 + e2)  # e^{mt} cosh(qt)
    # e^{mt} sinh(qt) / q, and its limit t e^{mt} as q -> 0
    small = q * t < 1e-8
    odd = np.where(small, t * np.exp(m * t), 0.5 * (e1 - e2) / np.where(small, 1.0, q))
    r0 = as_float(rotor_rise)
    h0 = as_float(housing_rise)
    # (A - m I) = [[-a - m, a], [b, -(b + d) - m]]
    rotor = even * r0 + odd * ((-a - m) * r0 + a * h0)
    housing = even * h0 + odd * (b * r0 + (-(b + d) - m) * h0)
    return as_float(rotor), as_float(housing)
