"""The ECD's laws at one operating point, as plain functions of Python floats.

The damper and its gearbox referred to the slow shaft, one case at a time: the
eddy-current torque (the paper's linear law, Eq. 1, or the Kloss roll-off of
:mod:`ecdsim.physics.rolloff`) at the damper temperature, the gearbox damping and the
Coulomb friction of Eq. 2-4 referred through the gear ratio, the Stribeck curve of the
dynamic method, and the lumped heat balance of :mod:`ecdsim.physics.thermal` (one node,
or rotor and housing).

Why plain floats: these functions are written once and used as they are by the
Python side, and translated to C for the damper FMU (:mod:`ecdsim.fmu.ctranslate`,
docs/fmu.md), which needs no Python. So each body uses only float arithmetic,
comparisons, ``if``/``else``, ``for`` over ``range``, :mod:`math` and calls of other
such functions; an argument is a float, an int, a bool, or (for a table) a sequence of
floats with its length. No NumPy: the vectorised laws of :mod:`ecdsim.physics.assembly`,
:mod:`ecdsim.physics.rolloff` and :mod:`ecdsim.physics.thermal` are the batched forms,
and tests hold the two equal (tests/test_fmu.py). Temperatures in degC, SI otherwise.
"""

import math
from collections.abc import Sequence


def temperature_factor(
    temperature: float, reference_temperature: float, coefficient: float
) -> float:
    """The damping law's temperature factor ``f = 1 + c (T - T_ref)``, never below 0.

    Eq. 1's bracket (``BD_T = BD f``, c = -0.004/K for the paper's damper), or the
    Kloss law's resistivity factor (``omega_peak = omega_peak_ref f``, c = alpha;
    Wouterse 1991, doi:10.1049/ip-b.1991.0019). Held at 0 beyond the law's zero
    ``T_ref - 1/c``, which heating approaches and never crosses (docs/dynamics.md,
    "The zero of the damping law is never crossed"): there the eddy damping has faded.

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


def linear_eddy_torque(shaft_speed: float, damping_rate: float, factor: float) -> float:
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


def kloss_eddy_torque(shaft_speed: float, peak_torque: float, peak_speed: float) -> float:
    """Kloss-form eddy-current torque ``2 T_peak x / (1 + x^2)``, ``x = omega_d / omega_peak``.

    Evaluated as ``2 T_peak omega_d omega_peak / (omega_d^2 + omega_peak^2)``, finite (0)
    where the peak speed is 0 and 0 where both speeds are (Wouterse 1991,
    doi:10.1049/ip-b.1991.0019; :func:`ecdsim.physics.rolloff.kloss_torque`): the
    roll-off beyond the linear range of paper section 2.1.

    Parameters
    ----------
    shaft_speed : high-speed shaft speed omega_d [rad/s]
    peak_torque : T_peak [N*m]
    peak_speed : omega_peak at the damper temperature [rad/s], >= 0

    >>> kloss_eddy_torque(2000.0, 0.13, 2000.0)  # at the peak
    0.13
    """
    denominator = shaft_speed * shaft_speed + peak_speed * peak_speed
    if denominator > 0.0:
        return 2.0 * peak_torque * shaft_speed * peak_speed / denominator
    return 0.0


def eddy_torque(
    shaft_speed: float,
    factor: float,
    damping_rate: float,
    reference_peak_speed: float,
    rolloff: bool,
) -> float:
    """The damper's eddy-current torque at its own shaft, by its law [N*m].

    Linear (Eq. 1): ``BD f omega_d``. With roll-off, the Kloss law with
    ``omega_peak = omega_peak_ref f`` and ``T_peak = BD omega_peak_ref / 2``, the peak
    torque whose slope at zero speed is the rated BD (Wouterse 1991,
    doi:10.1049/ip-b.1991.0019; :func:`ecdsim.physics.rolloff.peak_torque_from_damping`).

    Parameters
    ----------
    shaft_speed : high-speed shaft speed omega_d [rad/s]
    factor : f, the law's temperature factor at the damper temperature [-]
    damping_rate : BD at the reference temperature [N*m*s/rad]
    reference_peak_speed : omega_peak_ref [rad/s] (used with roll-off only)
    rolloff : the Kloss law (True) or the linear one (False) [bool]

    >>> round(eddy_torque(2000.0, 1.0, 1.3e-4, 2000.0, True), 12)  # T_peak at the peak speed
    0.13
    """
    if rolloff:
        peak_torque = damping_rate * reference_peak_speed / 2.0
        return kloss_eddy_torque(shaft_speed, peak_torque, reference_peak_speed * factor)
    return linear_eddy_torque(shaft_speed, damping_rate, factor)


def slow_shaft_damping_torque(
    speed: float,
    gear_ratio: float,
    shaft_eddy_torque: float,
    gearbox_damping_rate: float,
    forward_efficiency: float,
) -> float:
    """Damping torque of the ECD at its slow (input) shaft: ``N (T_eddy + BG N u) / eta_f``.

    The damper's eddy torque and the gearbox damping at the high-speed shaft (Eq. 1),
    referred to the input through the gear ratio (Eq. 3: with the linear law at
    temperature T this is ``BECD_T u``), divided by the forward efficiency of a lossy
    mesh driven from the input (Modelica's LossyGear; ``ecdsim.physics.gearing``; 1 for
    an ideal mesh). It opposes the speed.

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


def linear_in_temperature(temperature: float, slope: float, at_0c: float) -> float:
    """``slope T + value_at_0C``: the paper's FL_T and FS_T (sections 2.3 and 5).

    :func:`ecdsim.physics.laws.linear_in_temperature` for one temperature.

    Parameters
    ----------
    temperature : T [degC]
    slope : change per kelvin [unit of the quantity / K]
    at_0c : value at 0 degC [unit of the quantity]

    >>> round(linear_in_temperature(25.0, -0.0044, 0.58), 12)
    0.47
    """
    return slope * temperature + at_0c


def table_in_temperature(
    temperature: float, temperatures: Sequence[float], values: Sequence[float], count: int
) -> float:
    """Piecewise-linear interpolation in a (T, value) table, held at its end values.

    :func:`ecdsim.physics.laws.interpolate_table` (NumPy's ``interp``) for one
    temperature: a measured FL_T (paper section 2.3).

    Parameters
    ----------
    temperature : T [degC]
    temperatures : strictly increasing table temperatures [degC]
    values : the quantity at those temperatures [unit of the quantity]
    count : number of table points, >= 1 [-]

    >>> table_in_temperature(10.0, [0.0, 20.0], [1.0, 3.0], 2)
    2.0
    """
    if temperature <= temperatures[0]:
        return values[0]
    last = count - 1
    if temperature >= temperatures[last]:
        return values[last]
    for i in range(1, count):
        if temperature < temperatures[i]:
            below = i - 1
            slope = (values[i] - values[below]) / (temperatures[i] - temperatures[below])
            return slope * (temperature - temperatures[below]) + values[below]
    return values[last]


def input_coulomb_friction(
    damper_friction: float,
    lubrication_friction: float,
    gearbox_friction: float,
    gear_ratio: float,
    forward_efficiency: float,
) -> float:
    """FECD_T, the ECD's Coulomb friction at the slow shaft: ``(FD + FL_T + FG) N / eta_f``.

    Eq. 2 (``FT_T = FD + FL_T + FG``) referred to the input (Eq. 4), through a lossy
    mesh driven forward (``ecdsim.physics.gearing``; eta_f = 1 for an ideal mesh).

    Parameters
    ----------
    damper_friction : FD at the high-speed shaft [N*m]
    lubrication_friction : FL_T at the high-speed shaft [N*m]
    gearbox_friction : FG at the high-speed shaft [N*m]
    gear_ratio : N [-]
    forward_efficiency : eta_f, in (0, 1] [-]

    >>> round(input_coulomb_friction(7.9e-4, 1.67e-4, 4.5e-4, 380.0, 1.0), 12)
    0.53466
    """
    total = damper_friction + lubrication_friction + gearbox_friction
    return total * gear_ratio / forward_efficiency


def stribeck_friction(
    speed: float, kinetic: float, static_factor: float, stribeck_speed: float
) -> float:
    """Sliding friction opposing ``speed``: ``sign(u) [F_C + (f F_C - F_C) exp(-(u/w_St)^2)]``.

    The Stribeck curve of the dynamic method (docs/dynamics.md, "Stribeck friction"; the
    LuGre model's steady curve, Canudas de Wit et al. 1995): from the breakaway
    ``f F_C`` near rest to the kinetic ``F_C`` as speed grows; ``F_C`` at every speed
    without a Stribeck speed (w_St = inf). 0 at rest (u = 0) and for a NaN speed: the
    holding torque at rest depends on the rest of the mechanism. F_C is the ECD's FECD_T
    (Eq. 2, 4).

    Parameters
    ----------
    speed : u [rad/s]
    kinetic : F_C, the kinetic (Coulomb) friction [N*m], >= 0
    static_factor : f, breakaway over kinetic [-], >= 1
    stribeck_speed : w_St [rad/s], > 0; inf for none

    >>> stribeck_friction(-0.5, 2.0, 1.5, math.inf)
    -2.0
    """
    if speed == 0.0 or math.isnan(speed):
        return 0.0
    friction = kinetic
    excess = (static_factor - 1.0) * kinetic
    if excess != 0.0 and math.isfinite(stribeck_speed):
        ratio = speed / stribeck_speed
        friction = kinetic + excess * math.exp(-(ratio * ratio))
    return math.copysign(friction, speed)


def heat_flow(temperature: float, sink_temperature: float, thermal_resistance: float) -> float:
    """Heat flow through a thermal resistance: ``(T - T_sink) / R`` [W]; 0 where R is inf.

    The resistance form of conduction (Incropera, DeWitt, Bergman and Lavine 2007,
    section 3.1.3); :func:`ecdsim.physics.thermal.heat_loss` for one case: the loss term
    of the damper's lumped self-heating (the ECD's eddy-current power heats it).

    Parameters
    ----------
    temperature : the hot side's temperature T [degC]
    sink_temperature : T_sink [degC]
    thermal_resistance : R [K/W], > 0; inf for none (adiabatic)

    >>> heat_flow(30.0, 25.0, 2.5)
    2.0
    >>> heat_flow(30.0, 25.0, math.inf)
    0.0
    """
    if math.isinf(thermal_resistance):
        return 0.0
    return (temperature - sink_temperature) / thermal_resistance


def heat_rate(
    power: float,
    temperature: float,
    sink_temperature: float,
    heat_capacity: float,
    thermal_resistance: float,
) -> float:
    """``dT/dt = (P - (T - T_sink) / R) / C`` of one lumped body [K/s].

    The lumped-capacitance balance with a heat source (Incropera et al. 2007, section
    5.1, Eq. 5.2); :func:`ecdsim.physics.thermal.temperature_rate` for one case. The
    damper (or the rotor of a two-node damper) takes the eddy-current power and sinks
    into the ambient (or its housing); a housing takes the rotor's heat flow as P.

    Parameters
    ----------
    power : heat put into the body P [W]
    temperature : its temperature T [degC]
    sink_temperature : the temperature it loses heat to [degC]
    heat_capacity : C [J/K], > 0
    thermal_resistance : R to the sink [K/W]; inf for adiabatic

    >>> heat_rate(10.0, 25.0, 25.0, 5.0, math.inf)
    2.0
    """
    return (power - heat_flow(temperature, sink_temperature, thermal_resistance)) / heat_capacity
