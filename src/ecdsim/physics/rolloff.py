"""Eddy-current damping beyond the linear range: the Kloss-form torque-speed curve.

The paper (section 2.1) notes that a high-speed magnetic damper is linear only up to a
"maximum torque and speed point ... where the linearity will start to roll off", without
giving the law. ecdsim uses the classical law of a solid-conductor eddy-current brake, the
same form as Kloss's formula for an induction machine's torque against slip:

    T_d = 2 * T_peak * x / (1 + x**2),      x = omega_d / omega_peak

(Wouterse, J. H., "Critical torque and speed of eddy current brake with widely separated
soft iron poles", IEE Proc. B 138(4), p. 153, 1991, doi:10.1049/ip-b.1991.0019). The
torque rises
linearly at low speed with slope ``2 * T_peak / omega_peak``, peaks at ``T_peak`` when
``omega_d = omega_peak`` and falls as ``1/omega_d`` beyond.

Temperature: the peak torque is set by the magnetic circuit and does not depend on the
conductor's resistivity, while the peak speed is proportional to it (Wouterse 1991):
``omega_peak(T) = omega_peak_ref * (1 + alpha * (T - T_ref))``. The low-speed slope,
the damper's BD_T, therefore follows ``BD / (1 + alpha * (T - T_ref))``; for copper
(alpha = 0.0039 / K) this matches the paper's 0.4 % per degC decrease (Eq. 1) to first
order. ``T_peak`` is fixed by requiring the slope at the reference temperature to be the
rated BD: ``T_peak = BD * omega_peak_ref / 2`` (:func:`peak_torque_from_damping`).

All speeds and torques here are at the high-speed damper shaft.
"""

from ecdsim._types import Real


def peak_torque_from_damping(damping_rate: Real, peak_speed: Real) -> Real:
    """Peak eddy-current torque whose Kloss curve has slope BD at zero speed.

    ``T_peak = BD * omega_peak / 2``, from ``dT_d/domega_d (0) = 2 * T_peak / omega_peak``
    of the Kloss-form curve (Wouterse 1991, doi:10.1049/ip-b.1991.0019): the linear range
    keeps the paper's rated BD (section 2.1).

    Parameters
    ----------
    damping_rate : BD, linear damping rate at the reference temperature [N*m*s/rad]
    peak_speed : omega_peak at the reference temperature [rad/s]

    >>> round(float(peak_torque_from_damping(1.3e-4, 2000.0)), 12)
    0.13
    """
    return damping_rate * peak_speed / 2.0


def peak_speed_at(
    temperature: Real,
    reference_peak_speed: Real,
    resistivity_coefficient: Real,
    reference_temperature: Real = 25.0,
) -> Real:
    """Speed of peak eddy-current torque at conductor temperature T.

    ``omega_peak(T) = omega_peak_ref * (1 + alpha * (T - T_ref))``: the peak speed is
    proportional to the conductor's resistivity (Wouterse 1991,
    doi:10.1049/ip-b.1991.0019), linear in temperature; to first order this is the
    paper's 0.4 % per degC fall of BD (Eq. 1).

    Parameters
    ----------
    temperature : conductor (damper) temperature T [degC]
    reference_peak_speed : omega_peak at T_ref [rad/s]
    resistivity_coefficient : alpha, fractional change of resistivity per kelvin [1/K]
    reference_temperature : T_ref [degC]

    >>> round(float(peak_speed_at(125.0, 2000.0, 0.0039)), 6)
    2780.0
    """
    dt = temperature - reference_temperature
    return reference_peak_speed * (1.0 + resistivity_coefficient * dt)


def _denominator(speed: Real, peak_speed: Real) -> Real:
    """``w**2 + p**2`` of the rational Kloss forms, 1 where both speeds vanish.

    Multiplying ``x = w / p`` out of the Kloss formulas gives rational functions of the
    speed w and the peak speed p that stay finite where p vanishes (where x is infinite).
    Only ``w = p = 0`` is left undefined; there every numerator is 0, so a denominator of
    1 returns 0. Written with arithmetic only (no branch, no ``np.where``), so that the
    same code runs on floats, on NumPy arrays and compiled by numba
    (:mod:`ecdsim.dynamics.kernel`).
    """
    den = speed * speed + peak_speed * peak_speed
    return den + (den == 0.0)


def kloss_torque(speed: Real, peak_torque: Real, peak_speed: Real) -> Real:
    """Eddy-current torque against speed, Kloss form: ``2 T_peak x / (1 + x**2)``.

    ``x = omega_d / omega_peak``. Odd in the speed: the torque opposes the motion's
    direction when the sign convention ``damping torque = -T_d`` is used. Evaluated as
    ``2 T_peak omega_d omega_peak / (omega_d**2 + omega_peak**2)``, finite (0) at
    ``omega_peak = 0``. Source: Wouterse 1991 (doi:10.1049/ip-b.1991.0019); linear below
    the peak, the roll-off point of paper section 2.1.

    Parameters
    ----------
    speed : high-speed shaft speed omega_d [rad/s]
    peak_torque : T_peak, the largest eddy-current torque [N*m]
    peak_speed : omega_peak, the speed at which it occurs [rad/s], >= 0

    >>> float(kloss_torque(2000.0, 0.13, 2000.0))  # at the peak
    0.13
    """
    return 2.0 * peak_torque * speed * peak_speed / _denominator(speed, peak_speed)


def kloss_speed_derivative(speed: Real, peak_torque: Real, peak_speed: Real) -> Real:
    """``dT_d / domega_d`` of the Kloss torque: ``(2 T_peak / omega_peak)(1 - x**2)/(1 + x**2)**2``.

    The local damping rate of the damper (the slope definition of paper section 2.1; the
    derivative of the Kloss form of Wouterse 1991, doi:10.1049/ip-b.1991.0019); equal to
    BD at zero speed, zero at the peak and negative beyond it. Evaluated as
    ``2 T_peak p (p**2 - w**2) / (w**2 + p**2)**2``
    (``w = omega_d``, ``p = omega_peak``); 0 where both vanish.

    Parameters
    ----------
    speed : high-speed shaft speed omega_d [rad/s]
    peak_torque : T_peak [N*m]
    peak_speed : omega_peak [rad/s], >= 0
    """
    w, p = speed, peak_speed
    inv = 1.0 / _denominator(w, p)
    return 2.0 * peak_torque * p * (p * p - w * w) * (inv * inv)


def kloss_peak_speed_derivative(speed: Real, peak_torque: Real, peak_speed: Real) -> Real:
    """``dT_d / domega_peak`` of the Kloss torque at fixed speed and peak torque.

    ``-(2 T_peak x / omega_peak)(1 - x**2)/(1 + x**2)**2``, evaluated as
    ``2 T_peak w (w**2 - p**2) / (w**2 + p**2)**2``; with ``domega_peak/dT =
    omega_peak_ref * alpha`` it gives the torque's temperature sensitivity, the roll-off
    counterpart of the paper's Eq. 1 coefficient (Kloss form of Wouterse 1991,
    doi:10.1049/ip-b.1991.0019).

    Parameters
    ----------
    speed : high-speed shaft speed omega_d [rad/s]
    peak_torque : T_peak [N*m]
    peak_speed : omega_peak [rad/s], >= 0
    """
    w, p = speed, peak_speed
    inv = 1.0 / _denominator(w, p)
    return 2.0 * peak_torque * w * (w * w - p * p) * (inv * inv)


def kloss_power_per_peak_speed(speed: Real, peak_torque: Real, peak_speed: Real) -> Real:
    """Eddy-current power over the peak speed: ``T_d omega_d / omega_peak``.

    ``2 T_peak omega_d**2 / (omega_d**2 + omega_peak**2)``: the Kloss torque times the
    speed, divided by omega_peak in closed form, so that it stays finite (``2 T_peak``)
    where omega_peak vanishes. Times ``omega_peak_ref`` it is the heating power over the
    resistivity factor ``omega_peak / omega_peak_ref``, the form the heat balance of
    :mod:`ecdsim.physics.thermal` takes in the damping law's log state. 0 where both
    speeds vanish. Sources: the Kloss
    form of Wouterse 1991 (doi:10.1049/ip-b.1991.0019); power = damping torque times
    speed, as for the linear law of paper Eq. 5.

    Parameters
    ----------
    speed : high-speed shaft speed omega_d [rad/s]
    peak_torque : T_peak [N*m]
    peak_speed : omega_peak [rad/s], >= 0

    >>> float(kloss_power_per_peak_speed(2000.0, 0.13, 2000.0))  # at the peak: T_peak
    0.13
    """
    return 2.0 * peak_torque * speed * speed / _denominator(speed, peak_speed)


def kloss_power_per_peak_speed_derivatives(
    speed: Real, peak_torque: Real, peak_speed: Real
) -> tuple[Real, Real]:
    """Partial derivatives of :func:`kloss_power_per_peak_speed` in omega_d and omega_peak.

    ``(4 T_peak w p**2, -4 T_peak w**2 p) / (w**2 + p**2)**2`` with ``w = omega_d``,
    ``p = omega_peak`` [N*m*s/rad each]; 0 where both vanish. Derivatives of the Kloss
    form of Wouterse 1991 (doi:10.1049/ip-b.1991.0019), for the Jacobian of the heated
    dynamics (paper section 2.1 roll-off with heating).

    Parameters
    ----------
    speed : high-speed shaft speed omega_d [rad/s]
    peak_torque : T_peak [N*m]
    peak_speed : omega_peak [rad/s], >= 0
    """
    w, p = speed, peak_speed
    inv = 1.0 / _denominator(w, p)
    common = 4.0 * peak_torque * w * p * (inv * inv)
    return common * p, -common * w
