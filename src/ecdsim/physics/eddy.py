"""The ECD's damping torque at the slow shaft, by eddy-current law, with its derivatives.

One function per quantity, each written once for floats, NumPy arrays and numba's
compiled dynamic kernel (:mod:`ecdsim.dynamics.kernel`), which compiles these very
functions: the dynamic method, its time series, the FMU's damper and the result's
findings all evaluate the law here. Two laws, chosen by a code (an ``int``, the same for
every element of an array):

* :data:`LINEAR` (paper Eq. 1 and 3): ``T_eddy = BD f omega_d`` with ``f = 1 + c (T -
  T_ref)`` Eq. 1's temperature factor; parameters ``a = BD`` (at T_ref), ``b`` unused;
* :data:`KLOSS` (the roll-off of :mod:`ecdsim.physics.rolloff`, Wouterse 1991,
  doi:10.1049/ip-b.1991.0019): ``T_eddy = 2 T_peak omega_d p / (omega_d^2 + p^2)`` with
  the peak speed ``p = omega_peak_ref f`` and ``f = 1 + alpha (T - T_ref)``; parameters
  ``a = T_peak``, ``b = omega_peak_ref``.

Both scale with the affine temperature factor f, which the dynamic method carries as
its logarithm (:mod:`ecdsim.physics.thermal`); the heating power is returned over f,
``p = T_eddy omega_d / f``, which stays finite where f vanishes. At the slow (input)
shaft the damper side's torque is ``M_d = N (T_eddy(N w, f) + BG N w)`` (Eq. 3 with the
law in place of BD_T; BG, the gearbox's damping, stays linear and does not heat the
damper's conductor).
"""

from ecdsim._types import Real
from ecdsim.physics.rolloff import (
    kloss_peak_speed_derivative,
    kloss_power_per_peak_speed,
    kloss_power_per_peak_speed_derivatives,
    kloss_speed_derivative,
    kloss_torque,
)

LINEAR = 0  # Eq. 1: BD_T omega_d
KLOSS = 1  # the Kloss roll-off


def eddy_torque(law: int, a: Real, b: Real, speed: Real, factor: Real) -> Real:
    """The eddy-current torque at the high-speed shaft [N*m] (Eq. 1, or the Kloss law).

    Parameters
    ----------
    law : :data:`LINEAR` or :data:`KLOSS` [-]
    a : BD at T_ref [N*m*s/rad] (linear), or T_peak [N*m] (Kloss)
    b : unused [-] (linear), or omega_peak at T_ref [rad/s] (Kloss)
    speed : omega_d, the high-speed shaft's speed [rad/s]
    factor : f, the law's temperature factor [-]

    >>> round(float(eddy_torque(LINEAR, 1.3e-4, 0.0, 1000.0, 0.5)), 12)  # BD f w
    0.065
    >>> float(eddy_torque(KLOSS, 0.13, 2000.0, 2000.0, 1.0))  # at the peak: T_peak
    0.13
    """
    if law == LINEAR:
        return a * factor * speed
    return kloss_torque(speed, a, b * factor)


def eddy_torque_parts(
    law: int, a: Real, b: Real, speed: Real, factor: Real
) -> tuple[Real, Real, Real, Real, Real, Real]:
    """Torque, its derivatives, and the heating power over f with its derivatives.

    ``(T, dT/dw, dT/df, p, dp/dw, dp/df)`` with ``p = T w / f`` [W] (module notes; Eq. 1
    of the ECD paper, or the Kloss law of Wouterse 1991): the terms of the dynamic
    method's right-hand side and Jacobian.

    Parameters
    ----------
    law : :data:`LINEAR` or :data:`KLOSS` [-]
    a : BD at T_ref [N*m*s/rad] (linear), or T_peak [N*m] (Kloss)
    b : unused [-] (linear), or omega_peak at T_ref [rad/s] (Kloss)
    speed : omega_d [rad/s]
    factor : f [-]
    """
    if law == LINEAR:
        rate = a * factor
        return rate * speed, rate, a * speed, a * speed * speed, 2.0 * a * speed, 0.0 * speed
    peak = b * factor
    by_speed, by_peak = kloss_power_per_peak_speed_derivatives(speed, a, peak)
    return (
        kloss_torque(speed, a, peak),
        kloss_speed_derivative(speed, a, peak),
        kloss_peak_speed_derivative(speed, a, peak) * b,
        kloss_power_per_peak_speed(speed, a, peak) * b,
        by_speed * b,
        by_peak * b * b,
    )


def damper_side_torque(
    law: int, a: Real, b: Real, ratio: Real, gearbox_damping: Real, speed: Real, factor: Real
) -> tuple[Real, Real]:
    """``M_d = N (T_eddy(N w, f) + BG N w)`` at the slow shaft [N*m], and ``p`` [W].

    The ECD's damping torque referred to the input shaft (paper Eq. 3 with the eddy law
    in place of the linear BD_T) and the eddy-current heating power over the factor f
    (BG's power heats the gearbox, not the damper's conductor).

    Parameters
    ----------
    law : :data:`LINEAR` or :data:`KLOSS` [-]
    a : BD at T_ref [N*m*s/rad] (linear), or T_peak [N*m] (Kloss)
    b : unused [-] (linear), or omega_peak at T_ref [rad/s] (Kloss)
    ratio : N, the gear ratio [-]
    gearbox_damping : BG at the high-speed shaft [N*m*s/rad]
    speed : w, the slow shaft's speed [rad/s]
    factor : f [-]

    >>> torque, power = damper_side_torque(LINEAR, 1.3e-4, 0.0, 380.0, 3.38e-5, 0.1, 1.0)
    >>> round(float(torque), 9), round(float(power), 9)  # (BD + BG) N^2 w, BD (N w)^2
    (2.365272, 0.18772)
    """
    shaft = ratio * speed
    if law == LINEAR:
        power = a * shaft * shaft
        return ratio * (a * factor * shaft + gearbox_damping * shaft), power
    peak = b * factor
    eddy = kloss_torque(shaft, a, peak)
    return ratio * (eddy + gearbox_damping * shaft), kloss_power_per_peak_speed(shaft, a, peak) * b


def damper_side_parts(
    law: int, a: Real, b: Real, ratio: Real, gearbox_damping: Real, speed: Real, factor: Real
) -> tuple[Real, Real, Real, Real, Real, Real]:
    """:func:`damper_side_torque` with the derivatives a Jacobian needs.

    ``(M_d, dM_d/dw, dM_d/df, p, dp/dw, dp/df)`` at the slow shaft (w its speed; paper
    Eq. 3 with the law of :func:`eddy_torque_parts` at ``N w``).

    Parameters
    ----------
    law : :data:`LINEAR` or :data:`KLOSS` [-]
    a : BD at T_ref [N*m*s/rad] (linear), or T_peak [N*m] (Kloss)
    b : unused [-] (linear), or omega_peak at T_ref [rad/s] (Kloss)
    ratio : N [-]
    gearbox_damping : BG at the high-speed shaft [N*m*s/rad]
    speed : w [rad/s]
    factor : f [-]
    """
    shaft = ratio * speed
    torque, by_speed, by_factor, power, power_speed, power_factor = eddy_torque_parts(
        law, a, b, shaft, factor
    )
    return (
        ratio * (torque + gearbox_damping * shaft),
        ratio * ratio * (by_speed + gearbox_damping),
        ratio * by_factor,
        power,
        ratio * power_speed,
        power_factor,
    )
