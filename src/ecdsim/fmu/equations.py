"""The damper FMU's equations: the ECD's laws composed at the slow shaft, in plain floats.

Two functions, written once in the plain-float subset of :mod:`ecdsim.fmu.ctranslate`:
:func:`damper_outputs` (the torques, frictions and eddy-current power for a shaft
speed, an ambient temperature and a damper temperature) and :func:`damper_heating`
(the time derivatives of the damper's temperature and its housing's). They call the
laws of :mod:`ecdsim.physics` (``eddy``, ``friction``, ``laws``, ``thermal``: the very
functions the dynamic kernel compiles) and nothing else. The damper FMU is these two
functions translated to C (the FMU variables bear their argument names);
:class:`ecdsim.fmu.model.DamperModel` calls them in Python.

Temperatures in degC, everything else SI; torques at the slow shaft are given with
the sign of the speed (they oppose it).
"""

from collections.abc import Sequence

from ecdsim.physics import eddy as eddy_law
from ecdsim.physics import friction as friction_law
from ecdsim.physics import laws, thermal


def shaft_eddy_torque(
    shaft_speed: float,
    damper_temperature: float,
    damping_rate: float,
    reference_temperature: float,
    damping_temperature_coefficient: float,
    rolloff: bool,
    peak_speed: float,
    resistivity_coefficient: float,
) -> float:
    """T_eddy at the high-speed shaft at the damper temperature [N*m].

    The linear law (Eq. 1, ``BD_T = BD (1 + c (T_d - T_ref))``) or, with roll-off, the
    Kloss law whose peak speed follows the resistivity, ``omega_peak = omega_peak_ref
    (1 + alpha (T_d - T_ref))`` (docs/dynamics.md, "Roll-off"); the factor never below 0.
    """
    coefficient = resistivity_coefficient if rolloff else damping_temperature_coefficient
    factor = eddy_law.temperature_factor(damper_temperature, reference_temperature, coefficient)
    return eddy_law.rated_eddy_torque(shaft_speed, factor, damping_rate, peak_speed, rolloff)


def damper_outputs(
    shaft_speed: float,
    ambient_temperature: float,
    damper_temperature: float,
    gear_ratio: float,
    damping_rate: float,
    reference_temperature: float,
    damping_temperature_coefficient: float,
    rolloff: bool,
    peak_speed: float,
    resistivity_coefficient: float,
    gearbox_damping_rate: float,
    gearbox_damping_fraction: float,
    forward_efficiency: float,
    damper_coulomb_friction: float,
    gearbox_coulomb_friction: float,
    lubrication_friction_slope: float,
    lubrication_friction_at_0c: float,
    lubrication_temperatures: Sequence[float],
    lubrication_frictions: Sequence[float],
    lubrication_points: int,
    static_friction_factor: float,
    stribeck_speed: float,
) -> tuple[float, float, float, float, float]:
    """The ECD at the slow shaft: (damper_torque, friction_torque, coulomb_friction,
    breakaway_friction, eddy_power).

    * damper_torque [N*m]: ``N (T_eddy(N u, T_d) + BG N u) / eta_f`` (Eq. 1, 3), BG the
      gearbox damping (``gearbox_damping_rate``, or ``gearbox_damping_fraction`` of BD;
      the one not configured is 0);
    * coulomb_friction [N*m]: FECD at the ambient temperature (Eq. 2, 4), with FL_T
      linear (``slope T + at_0C``) or from a table of ``lubrication_points`` points;
    * breakaway_friction [N*m]: ``f_D FECD``, what the ECD holds at rest;
    * friction_torque [N*m]: the sliding friction opposing u, on the dynamic method's
      Stribeck curve when a Stribeck speed is given, 0 at rest;
    * eddy_power [W]: ``T_eddy N u``, the power dissipated in the damper (what heats it).
    """
    high_speed = gear_ratio * shaft_speed
    eddy = shaft_eddy_torque(
        high_speed,
        damper_temperature,
        damping_rate,
        reference_temperature,
        damping_temperature_coefficient,
        rolloff,
        peak_speed,
        resistivity_coefficient,
    )
    gearbox_damping = gearbox_damping_rate + gearbox_damping_fraction * damping_rate
    torque = float(
        eddy_law.slow_shaft_damping_torque(
            shaft_speed, gear_ratio, eddy, gearbox_damping, forward_efficiency
        )
    )
    if lubrication_points > 0:
        lubrication = laws.table_in_temperature(
            ambient_temperature, lubrication_temperatures, lubrication_frictions, lubrication_points
        )
    else:
        lubrication = float(
            laws.linear_law(
                ambient_temperature, lubrication_friction_slope, lubrication_friction_at_0c
            )
        )
    coulomb = friction_law.input_coulomb_friction(
        damper_coulomb_friction,
        lubrication,
        gearbox_coulomb_friction,
        gear_ratio,
        forward_efficiency,
    )
    friction = friction_law.stribeck_friction(
        shaft_speed, coulomb, static_friction_factor, stribeck_speed
    )
    breakaway = float(friction_law.breakaway(coulomb, static_friction_factor))
    return torque, friction, coulomb, breakaway, eddy * high_speed


def damper_heating(
    shaft_speed: float,
    ambient_temperature: float,
    damper_temperature: float,
    housing_temperature: float,
    gear_ratio: float,
    damping_rate: float,
    reference_temperature: float,
    damping_temperature_coefficient: float,
    rolloff: bool,
    peak_speed: float,
    resistivity_coefficient: float,
    heat_capacity: float,
    thermal_resistance: float,
    housing: bool,
    housing_heat_capacity: float,
    housing_thermal_resistance: float,
) -> tuple[float, float]:
    """(dT_d/dt, dT_h/dt) [K/s]: the lumped self-heating of the damper.

    One node: ``C dT_d/dt = T_eddy N u - (T_d - T_ambient) / R`` (Incropera et al.,
    Eq. 5.2; only the eddy-current power heats the damper); dT_h/dt is 0. With a housing
    (two nodes, docs/dynamics.md): ``C dT_d/dt = P - (T_d - T_h) / R`` and
    ``C_h dT_h/dt = (T_d - T_h) / R - (T_h - T_ambient) / R_h``.
    """
    high_speed = gear_ratio * shaft_speed
    eddy = shaft_eddy_torque(
        high_speed,
        damper_temperature,
        damping_rate,
        reference_temperature,
        damping_temperature_coefficient,
        rolloff,
        peak_speed,
        resistivity_coefficient,
    )
    power = eddy * high_speed
    if housing:
        rotor = float(
            thermal.temperature_rate(
                power, damper_temperature, housing_temperature, heat_capacity, thermal_resistance
            )
        )
        conducted = float(
            thermal.heat_loss(damper_temperature, housing_temperature, thermal_resistance)
        )
        shell = float(
            thermal.temperature_rate(
                conducted,
                housing_temperature,
                ambient_temperature,
                housing_heat_capacity,
                housing_thermal_resistance,
            )
        )
        return rotor, shell
    rate = float(
        thermal.temperature_rate(
            power, damper_temperature, ambient_temperature, heat_capacity, thermal_resistance
        )
    )
    return rate, 0.0
