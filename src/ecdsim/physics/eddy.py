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
  ``a = T_peak``, ``b = omega_peak_ref``;
* :data:`POWER_LAW` (a shear-thinning fluid damper, :mod:`ecdsim.physics.fluid`):
  ``T = c max(|omega_d|, omega_l)^(n-1) omega_d``; parameters ``a = c``, ``b = n`` and
  ``core = omega_l``, each at the case's temperature (the fluid's c(T) and n(T) are
  evaluated when the case is packed; the law takes no temperature factor, so self-heating
  is refused with it: ``ecdsim.dynamics.solver``).

The ECD laws ignore ``core``.

The laws are written once in the subset that numba compiles (the dynamic kernel) and
that :mod:`ecdsim.fmu.ctranslate` turns into C (the damper FMU): arithmetic, ``if`` on
the law's code, calls of other such functions (:mod:`ecdsim.physics.rolloff`'s Kloss
forms). The FMU's plain-float compositions (:mod:`ecdsim.fmu.equations`) call
:func:`temperature_factor`, :func:`rated_eddy_torque` and
:func:`slow_shaft_damping_torque` below, which call the same laws the kernel compiles.

Both scale with the affine temperature factor f, which the dynamic method carries as
its logarithm (:mod:`ecdsim.physics.thermal`); the heating power is returned over f,
``p = T_eddy omega_d / f``, which stays finite where f vanishes. At the slow (input)
shaft the damper side's torque is ``M_d = N (T_eddy(N w, f) + BG N w)`` (Eq. 3 with the
law in place of BD_T; BG, the gearbox's damping, stays linear and does not heat the
damper's conductor).
"""

from ecdsim._types import Real
from ecdsim.physics.fluid import power_law_damper_torque, power_law_parts
from ecdsim.physics.rolloff import (
    kloss_peak_speed_derivative,
    kloss_power_per_peak_speed,
    kloss_power_per_peak_speed_derivatives,
    kloss_speed_derivative,
    kloss_torque,
)

LINEAR = 0  # Eq. 1: BD_T omega_d
KLOSS = 1  # the Kloss roll-off
POWER_LAW = 2  # a shear-thinning fluid damper (physics.fluid)


def temperature_factor(
    temperature: float, reference_temperature: float, coefficient: float
) -> float:
    """The damping law's temperature factor ``f = 1 + c (T - T_ref)``, never below 0.

    Eq. 1's bracket (``BD_T = BD f``, c = -0.004/K for the paper's damper), or the
    Kloss law's resistivity factor (``omega_peak = omega_peak_ref f``, c = alpha;
    Wouterse 1991, doi:10.1049/ip-b.1991.0019). Held at 0 beyond the law's zero
    ``T_ref - 1/c``, which heating approaches and never crosses (docs/dynamics.md,
    "The zero of the damping law is never crossed"): there the eddy damping has faded.
    (The dynamic kernel carries f through its logarithm, :mod:`ecdsim.physics.thermal`.)

    Parameters
    ----------
    temperature : damper temperature T [degC]
    reference_temperature : T_ref [degC]
    coefficient : c [1/K]

    >>> temperature_factor(-40.0, 25.0, -0.004)
    1.26
    >>> temperature_factor(400.0, 25.0, -0.004)
    0.0
    """
    factor = 1.0 + coefficient * (temperature - reference_temperature)
    if factor > 0.0:
        return factor
    return 0.0


def linear_eddy_torque(shaft_speed: Real, damping_rate: Real, factor: Real) -> Real:
    """Eddy-current torque in the linear range: ``BD_T omega_d = (BD f) omega_d`` [N*m].

    Eq. 1's first term (``BD_T = BD f``) times the high-speed shaft's speed (paper
    section 2.1).

    Parameters
    ----------
    shaft_speed : high-speed (damper) shaft speed omega_d [rad/s]
    damping_rate : BD at the reference temperature [N*m*s/rad]
    factor : f, the temperature factor [-]

    >>> linear_eddy_torque(100.0, 1.3e-4, 1.0)
    0.013
    """
    return damping_rate * factor * shaft_speed


def slow_shaft_damping_torque(
    speed: Real,
    gear_ratio: Real,
    shaft_eddy_torque: Real,
    gearbox_damping_rate: Real,
    forward_efficiency: Real,
) -> Real:
    """Damping torque of the ECD at its slow (input) shaft: ``N (T_eddy + BG N u) / eta_f``.

    The damper's eddy torque and the gearbox damping at the high-speed shaft (Eq. 1),
    referred to the input through the gear ratio (Eq. 3: with the linear law at
    temperature T this is ``BECD_T u``), divided by the forward efficiency of a lossy
    mesh driven from the input (Modelica's LossyGear; ``ecdsim.physics.gearing``; 1 for
    an ideal mesh, as the dynamic kernel applies the efficiency itself). It opposes the
    speed.

    Parameters
    ----------
    speed : slow-shaft speed u [rad/s]
    gear_ratio : N [-]
    shaft_eddy_torque : T_eddy at the high-speed shaft speed N u [N*m]
    gearbox_damping_rate : BG at the high-speed shaft [N*m*s/rad]
    forward_efficiency : eta_f, in (0, 1] [-]

    >>> round(slow_shaft_damping_torque(0.1, 380.0, 0.0, 3.38e-5, 1.0), 12)  # BG N^2 u
    0.488072
    """
    shaft_speed = gear_ratio * speed
    return (
        gear_ratio * (shaft_eddy_torque + gearbox_damping_rate * shaft_speed) / forward_efficiency
    )


def eddy_torque(law: int, a: Real, b: Real, core: Real, speed: Real, factor: Real) -> Real:
    """The eddy-current torque at the high-speed shaft [N*m] (Eq. 1, or the Kloss law).

    Parameters
    ----------
    law : :data:`LINEAR`, :data:`KLOSS` or :data:`POWER_LAW` [-]
    a : BD at T_ref [N*m*s/rad] (linear), T_peak [N*m] (Kloss), or c (power law)
    b : unused [-] (linear), omega_peak at T_ref [rad/s] (Kloss), or n (power law)
    core : omega_l [rad/s] (power law); unused otherwise
    speed : omega_d, the high-speed shaft's speed [rad/s]
    factor : f, the law's temperature factor [-] (unused by the power law)

    >>> round(float(eddy_torque(LINEAR, 1.3e-4, 0.0, 0.0, 1000.0, 0.5)), 12)  # BD f w
    0.065
    >>> float(eddy_torque(KLOSS, 0.13, 2000.0, 0.0, 2000.0, 1.0))  # at the peak: T_peak
    0.13
    >>> round(float(eddy_torque(POWER_LAW, 2.0, 0.5, 1e-6, 0.25, 1.0)), 12)  # c w^n
    1.0
    """
    if law == LINEAR:
        return linear_eddy_torque(speed, a, factor)
    if law == POWER_LAW:
        return power_law_damper_torque(speed, a, b, core)
    return kloss_torque(speed, a, b * factor)


def rated_eddy_torque(
    shaft_speed: float,
    factor: float,
    damping_rate: float,
    reference_peak_speed: float,
    rolloff: bool,
) -> float:
    """The damper's eddy-current torque at its own shaft from its rating BD [N*m].

    :func:`eddy_torque` with the parameters a damper is rated by: linear (Eq. 1),
    ``BD f omega_d``; with roll-off, the Kloss law with ``omega_peak = omega_peak_ref f``
    and ``T_peak = BD omega_peak_ref / 2``, the peak torque whose slope at zero speed is
    the rated BD (Wouterse 1991, doi:10.1049/ip-b.1991.0019;
    :func:`ecdsim.physics.rolloff.peak_torque_from_damping`). The damper FMU's law.

    Parameters
    ----------
    shaft_speed : high-speed shaft speed omega_d [rad/s]
    factor : f, the law's temperature factor at the damper temperature [-]
    damping_rate : BD at the reference temperature [N*m*s/rad]
    reference_peak_speed : omega_peak_ref [rad/s] (used with roll-off only)
    rolloff : the Kloss law (True) or the linear one (False) [bool]

    >>> round(rated_eddy_torque(2000.0, 1.0, 1.3e-4, 2000.0, True), 12)  # T_peak at the peak
    0.13
    """
    if rolloff:
        peak_torque = damping_rate * reference_peak_speed / 2.0
        return float(
            eddy_torque(KLOSS, peak_torque, reference_peak_speed, 0.0, shaft_speed, factor)
        )
    return float(eddy_torque(LINEAR, damping_rate, 0.0, 0.0, shaft_speed, factor))


def eddy_torque_parts(
    law: int, a: Real, b: Real, core: Real, speed: Real, factor: Real
) -> tuple[Real, Real, Real, Real, Real, Real]:
    """Torque, its derivatives, and the heating power over f with its derivatives.

    ``(T, dT/dw, dT/df, p, dp/dw, dp/df)`` with ``p = T w / f`` [W] (module notes; Eq. 1
    of the ECD paper, the Kloss law of Wouterse 1991, or the fluid's power law): the
    terms of the dynamic method's right-hand side and Jacobian. The power law has no
    temperature factor (``dT/df = 0``; its power ``T w`` is returned as is, heating being
    refused with it).

    Parameters
    ----------
    law : :data:`LINEAR`, :data:`KLOSS` or :data:`POWER_LAW` [-]
    a : BD at T_ref [N*m*s/rad] (linear), T_peak [N*m] (Kloss), or c (power law)
    b : unused [-] (linear), omega_peak at T_ref [rad/s] (Kloss), or n (power law)
    core : omega_l [rad/s] (power law); unused otherwise
    speed : omega_d [rad/s]
    factor : f [-]
    """
    if law == LINEAR:
        rate = a * factor
        return rate * speed, rate, a * speed, a * speed * speed, 2.0 * a * speed, 0.0 * speed
    if law == POWER_LAW:
        torque, slope = power_law_parts(speed, a, b, core)
        zero = 0.0 * speed
        return torque, slope, zero, torque * speed, slope * speed + torque, zero
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
    law: int, a: Real, b: Real, core: Real, ratio: Real, gearbox_damping: Real, speed: Real,
    factor: Real,
) -> tuple[Real, Real]:  # fmt: skip
    """``M_d = N (T_eddy(N w, f) + BG N w)`` at the slow shaft [N*m], and ``p`` [W].

    The ECD's damping torque referred to the input shaft (paper Eq. 3 with the eddy law
    in place of the linear BD_T) and the eddy-current heating power over the factor f
    (BG's power heats the gearbox, not the damper's conductor).

    Parameters
    ----------
    law : :data:`LINEAR`, :data:`KLOSS` or :data:`POWER_LAW` [-]
    a : BD at T_ref [N*m*s/rad] (linear), T_peak [N*m] (Kloss), or c (power law)
    b : unused [-] (linear), omega_peak at T_ref [rad/s] (Kloss), or n (power law)
    core : omega_l [rad/s] (power law); unused otherwise
    ratio : N, the gear ratio [-]
    gearbox_damping : BG at the high-speed shaft [N*m*s/rad]
    speed : w, the slow shaft's speed [rad/s]
    factor : f [-]

    >>> torque, power = damper_side_torque(LINEAR, 1.3e-4, 0.0, 0.0, 380.0, 3.38e-5, 0.1, 1.0)
    >>> round(float(torque), 9), round(float(power), 9)  # (BD + BG) N^2 w, BD (N w)^2
    (2.365272, 0.18772)
    """
    shaft = ratio * speed
    eddy = eddy_torque(law, a, b, core, shaft, factor)
    torque = slow_shaft_damping_torque(speed, ratio, eddy, gearbox_damping, 1.0)
    if law == LINEAR:
        return torque, a * shaft * shaft
    if law == POWER_LAW:
        return torque, eddy * shaft
    return torque, kloss_power_per_peak_speed(shaft, a, b * factor) * b


def damper_side_parts(
    law: int, a: Real, b: Real, core: Real, ratio: Real, gearbox_damping: Real, speed: Real,
    factor: Real,
) -> tuple[Real, Real, Real, Real, Real, Real]:  # fmt: skip
    """:func:`damper_side_torque` with the derivatives a Jacobian needs.

    ``(M_d, dM_d/dw, dM_d/df, p, dp/dw, dp/df)`` at the slow shaft (w its speed; paper
    Eq. 3 with the law of :func:`eddy_torque_parts` at ``N w``).

    Parameters
    ----------
    law : :data:`LINEAR`, :data:`KLOSS` or :data:`POWER_LAW` [-]
    a : BD at T_ref [N*m*s/rad] (linear), T_peak [N*m] (Kloss), or c (power law)
    b : unused [-] (linear), omega_peak at T_ref [rad/s] (Kloss), or n (power law)
    core : omega_l [rad/s] (power law); unused otherwise
    ratio : N [-]
    gearbox_damping : BG at the high-speed shaft [N*m*s/rad]
    speed : w [rad/s]
    factor : f [-]
    """
    shaft = ratio * speed
    torque, by_speed, by_factor, power, power_speed, power_factor = eddy_torque_parts(
        law, a, b, core, shaft, factor
    )
    return (
        ratio * (torque + gearbox_damping * shaft),
        ratio * ratio * (by_speed + gearbox_damping),
        ratio * by_factor,
        power,
        ratio * power_speed,
        power_factor,
    )
