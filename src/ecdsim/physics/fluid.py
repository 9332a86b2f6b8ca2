"""A shear-thinning (power-law) fluid damper: its torque, and the quasi-static time with it.

Silicone fluids thin with shear: a rotary shear damper's torque grows slower than its
speed. The power-law (Ostwald-de Waele) fluid has shear stress ``K * rate**n``, so a
narrow-gap rotary damper of fixed geometry gives (docs/qualification.md, section 3)::

    T(omega, T) = T_r(T) * (omega / omega_r)**n(T)          (sign of omega)
    T_r(T)      = T_r(T_ref) * exp(B * (1/T_K - 1/T_ref,K))  (Arrhenius-Andrade consistency)
    n(T)        = n_ref + s * (T - T_ref)

W. Ostwald, Kolloid-Z. 36 (1925) 99-117; A. de Waele, J. Oil Colour Chem. Assoc. 6 (1923)
33-88; E. N. da C. Andrade, Nature 125 (1930) 309-310. Flight boom-hinge dampers were
reported (issue 28) with n = 0.43 to 0.47 and 3 to 5 times the damping at -15 degC of
that at +40 degC. The coefficient of ``T = c * omega**n`` is ``c = T_r / omega_r**n``.

For a dynamic model the torque is given with a linear core below a small speed
``omega_l`` (``c * omega_l**(n-1) * omega``, continuous at omega_l), since the power law's
slope is infinite at rest for n < 1; :func:`power_law_torque_slope` is its derivative.
The dynamic kernel (:mod:`ecdsim.dynamics.kernel`, through :mod:`ecdsim.physics.eddy`)
compiles :func:`power_law_parts`, the same law with its slope in one branch-free
expression for floats, arrays and numba.
"""

from __future__ import annotations

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, Real, as_float

KELVIN_OFFSET = 273.15


def arrhenius_factor(
    temperature: ArrayLike, activation: ArrayLike, reference_temperature: ArrayLike
) -> FloatArray:
    """``exp(B * (1/T_K - 1/T_ref,K))``: a viscosity's (or consistency's) change from T_ref.

    Andrade (1930), the form of :func:`ecdsim.sizing.fluid.andrade_viscosity`;
    docs/qualification.md section 3.

    Parameters
    ----------
    temperature : T [degC]
    activation : B [K], > 0 for a fluid that thickens in the cold
    reference_temperature : T_ref [degC]

    >>> round(float(arrhenius_factor(-15.0, 2037.3, 40.0)), 2)  # about 4: cold is stiffer
    4.0
    """
    t = as_float(temperature) + KELVIN_OFFSET
    ref = as_float(reference_temperature) + KELVIN_OFFSET
    return as_float(np.exp(as_float(activation) * (1.0 / t - 1.0 / ref)))


def power_law_exponent(
    temperature: ArrayLike, exponent: ArrayLike, slope: ArrayLike, reference_temperature: ArrayLike
) -> FloatArray:
    """``n(T) = n_ref + s * (T - T_ref)`` [-], the power-law index over temperature
    (docs/qualification.md section 3, fitted by ``ecdsim fit fluid-damper``).

    Parameters
    ----------
    temperature : T [degC]
    exponent : n_ref at T_ref [-]
    slope : s, change of n per kelvin [1/K]
    reference_temperature : T_ref [degC]
    """
    dt = as_float(temperature) - as_float(reference_temperature)
    return as_float(as_float(exponent) + as_float(slope) * dt)


def power_law_coefficient(
    reference_torque: ArrayLike, reference_speed: ArrayLike, exponent: ArrayLike
) -> FloatArray:
    """``c = T_r / omega_r**n``, the coefficient of ``T = c * omega**n`` [N*m*(s/rad)**n]
    (docs/qualification.md section 3).

    Parameters
    ----------
    reference_torque : T_r, the torque at omega_r [N*m]
    reference_speed : omega_r [rad/s]
    exponent : n [-]
    """
    return as_float(as_float(reference_torque) / np.power(as_float(reference_speed), exponent))


def power_law_torque(
    speed: ArrayLike, coefficient: ArrayLike, exponent: ArrayLike, linear_speed: ArrayLike = 0.0
) -> FloatArray:
    """Damping torque ``c * sign(omega) * |omega|**n`` [N*m], linear below ``omega_l``:
    the power-law (Ostwald-de Waele) fluid damper of docs/qualification.md section 3.

    Below ``linear_speed`` the torque is ``c * omega_l**(n-1) * omega`` (continuous at
    omega_l, finite slope at rest); ``linear_speed = 0`` is the pure power law.

    Parameters
    ----------
    speed : omega [rad/s], either sign
    coefficient : c [N*m*(s/rad)**n]
    exponent : n [-]
    linear_speed : omega_l >= 0 [rad/s]

    >>> round(float(power_law_torque(0.4, 2.0, 0.5)), 12)
    1.264911064067
    """
    w = as_float(speed)
    c = as_float(coefficient)
    n = as_float(exponent)
    wl = as_float(linear_speed)
    size = np.abs(w)
    core = size < wl
    safe = np.where(wl > 0.0, wl, 1.0)
    power = np.power(np.where(core, 1.0, size), n)
    linear = np.power(safe, n - 1.0) * size
    return as_float(np.sign(w) * c * np.where(core, linear, power))


def power_law_torque_slope(
    speed: ArrayLike, coefficient: ArrayLike, exponent: ArrayLike, linear_speed: ArrayLike = 0.0
) -> FloatArray:
    """``dT/d omega`` of :func:`power_law_torque` [N*m*s/rad]: ``c n |omega|**(n-1)``,
    ``c omega_l**(n-1)`` in the linear core (+inf at rest without one, for n < 1); the
    Jacobian entry of the effect (docs/qualification.md section 3).

    Parameters
    ----------
    speed : omega [rad/s]
    coefficient : c [N*m*(s/rad)**n]
    exponent : n [-]
    linear_speed : omega_l >= 0 [rad/s]
    """
    w = np.abs(as_float(speed))
    c = as_float(coefficient)
    n = as_float(exponent)
    wl = as_float(linear_speed)
    core = w < wl
    safe = np.where(wl > 0.0, wl, 1.0)
    with np.errstate(divide="ignore"):
        outer = c * n * np.power(np.where(core, 1.0, w), n - 1.0)
    return as_float(np.where(core, c * np.power(safe, n - 1.0), outer))


def power_law_damper_torque(
    speed: Real, coefficient: Real, exponent: Real, linear_speed: Real
) -> Real:
    """The regularised power law's torque ``c max(|omega|, omega_l)**(n-1) omega`` [N*m]
    (:func:`power_law_parts`' first value), written in ``abs`` and ``**`` alone so that
    floats, arrays, numba and the FMU's C translation (:mod:`ecdsim.fmu.ctranslate`,
    which translates the damper laws :mod:`ecdsim.physics.eddy` dispatches) all take it
    (docs/qualification.md section 3).

    Parameters
    ----------
    speed : omega [rad/s], either sign
    coefficient : c [N*m*(s/rad)**n]
    exponent : n [-]
    linear_speed : omega_l > 0 [rad/s]

    >>> round(float(power_law_damper_torque(-0.25, 2.0, 0.5, 1e-6)), 12)  # -c |w|^n
    -1.0
    """
    size: Real = abs(speed)  # type: ignore[assignment]  # abs of a float or an array
    gap: Real = abs(size - linear_speed)  # type: ignore[assignment]
    above = 0.5 * (size + linear_speed + gap)  # max(|w|, w_l)
    torque: Real = coefficient * above ** (exponent - 1.0) * speed
    return torque


def power_law_parts(
    speed: Real, coefficient: Real, exponent: Real, linear_speed: Real
) -> tuple[Real, Real]:
    """The regularised power law's torque and slope, ``(T, dT/d omega)``, for the dynamic
    method (docs/qualification.md section 3, docs/dynamics.md).

    ``T = c * max(|omega|, omega_l)**(n-1) * omega``: ``c sign(omega) |omega|**n`` above
    omega_l, and ``c omega_l**(n-1) omega`` below it (the Newtonian plateau that real
    shear-thinning fluids show at low shear, the Cross model's zero-shear viscosity:
    M. M. Cross, J. Colloid Sci. 20 (1965) 417-437); continuous at omega_l, the values of
    :func:`power_law_torque` and :func:`power_law_torque_slope`. One branch-free
    expression, for floats, arrays and the compiled kernel alike.

    Parameters
    ----------
    speed : omega [rad/s], either sign
    coefficient : c [N*m*(s/rad)**n]
    exponent : n [-]
    linear_speed : omega_l > 0 [rad/s]

    >>> [round(float(v), 12) for v in power_law_parts(0.4, 2.0, 0.5, 1e-6)]  # c w^n, c n w^(n-1)
    [1.264911064067, 1.581138830084]
    >>> [round(float(v), 9) for v in power_law_parts(-1e-8, 2.0, 0.5, 1e-6)]  # the core
    [-2e-05, 2000.0]
    """
    size = np.abs(speed)
    scale = coefficient * np.power(np.maximum(size, linear_speed), exponent - 1.0)
    outer = size >= linear_speed
    return scale * speed, scale * (1.0 + (exponent - 1.0) * outer)


def power_law_segment_duration(
    length: ArrayLike,
    coefficient: ArrayLike,
    exponent: ArrayLike,
    net_start: ArrayLike,
    net_end: ArrayLike,
) -> FloatArray:
    """Quasi-static time across a segment of linear net torque, ``c * omega**n = a - k phi``.

    Speed ``omega = ((a - k phi) / c)**(1/n)`` with k = (a - b) / L, so with p = 1/n::

        t = c**p * integral_0^L (a - k phi)**(-p) dphi
          = c**p * (a**(1-p) - b**(1-p)) / (k (1 - p))            (p != 1)
          = L * c**p * a**(-p) * expm1(q r) / (q expm1(r)),  q = 1 - p, r = ln(b / a)

    the last form stable as b -> a (its limit is ``L c**p a**(-p)``) and as p -> 1
    (``expm1(q r) / q -> r``: the logarithmic mean of the ECD, docs/model.md). n = 1 is
    exact too. +inf where the net torque reaches zero in the segment (a stall); a zero
    length takes no time. Derivation: docs/qualification.md section 3.

    Parameters
    ----------
    length : segment length L [rad]
    coefficient : c [N*m*(s/rad)**n]
    exponent : n > 0 [-]
    net_start : a, net torque at the segment start [N*m]
    net_end : b, net torque at the segment end [N*m]
    """
    p = 1.0 / as_float(exponent)
    q = 1.0 - p
    length_arr = as_float(length)
    a = as_float(net_start)
    b = as_float(net_end)
    valid = (a > 0.0) & (b > 0.0)
    a_safe = np.where(valid, a, 1.0)
    b_safe = np.where(valid, b, 1.0)
    r = np.log(b_safe / a_safe)
    flat_r = r == 0.0
    r_safe = np.where(flat_r, 1.0, r)
    newtonian = q == 0.0
    q_safe = np.where(newtonian, 1.0, q)
    numerator = np.where(newtonian, r_safe, np.expm1(q_safe * r_safe) / q_safe)
    shape_factor = np.where(flat_r, 1.0, numerator / np.expm1(r_safe))
    duration = length_arr * np.power(as_float(coefficient), p) * a_safe ** (-p) * shape_factor
    blocked = ~valid & (length_arr > 0.0)
    return as_float(np.where(blocked, np.inf, np.where(length_arr > 0.0, duration, 0.0)))


def power_law_speed(
    net_torque: ArrayLike, coefficient: ArrayLike, exponent: ArrayLike
) -> FloatArray:
    """Quasi-static speed ``(max(net, 0) / c)**(1/n)`` [rad/s] (Eq. 5 with a power law).

    Parameters
    ----------
    net_torque : spring torque less the Coulomb frictions [N*m]
    coefficient : c [N*m*(s/rad)**n]
    exponent : n [-]
    """
    net = np.maximum(as_float(net_torque), 0.0)
    return as_float(np.power(net / as_float(coefficient), 1.0 / as_float(exponent)))


def power_law_mean_speed_time(
    travel: ArrayLike,
    coefficient: ArrayLike,
    exponent: ArrayLike,
    net_start: ArrayLike,
    net_end: ArrayLike,
) -> FloatArray:
    """The paper's method (Eq. 8-11) with a power-law damper: ``travel / ((w_s + w_e) / 2)``
    with the start and end speeds of :func:`power_law_speed`; +inf where an end speed is
    0 (the paper's method is invalid at a stall; the caller reports the stall).

    Parameters
    ----------
    travel : deployment angle [rad]
    coefficient : c [N*m*(s/rad)**n]
    exponent : n [-]
    net_start : net torque at the start of travel [N*m]
    net_end : net torque at the end of travel [N*m]
    """
    ws = power_law_speed(net_start, coefficient, exponent)
    we = power_law_speed(net_end, coefficient, exponent)
    mean = 0.5 * (ws + we)
    moving = (ws > 0.0) & (we > 0.0)
    return as_float(np.where(moving, as_float(travel) / np.where(moving, mean, 1.0), np.inf))
