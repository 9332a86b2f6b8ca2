"""The ECD assembly: high-speed damper + gearbox, referred to the slow input shaft.

Source: "Eddy Current Damper Simulation and Modeling", CDA InterCorp (``shared/paper``),
sections 2 to 4, Eq. 1 to 6. All damping rates and frictions named "high-speed" are
referred to the high-speed damper shaft, as in the paper; the ``ecd_*`` quantities are
referred to the slow (input) shaft through the gear ratio N.
"""

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, as_float


def damper_damping_rate(
    reference_damping_rate: ArrayLike,
    temperature: ArrayLike,
    reference_temperature: ArrayLike = 25.0,
    temperature_coefficient: ArrayLike = -0.004,
) -> FloatArray:
    """Damping rate BD_T of the high-speed damper at temperature T (first term of Eq. 1).

    ``BD_T = BD * (1 + c * (T - T_ref))``; the paper's CDA value is c = -0.004 per K
    (0.4 % decrease per degC) with T_ref = +25 degC.

    Parameters
    ----------
    reference_damping_rate : BD at the reference temperature [N*m*s/rad]
    temperature : damper temperature T [degC]
    reference_temperature : temperature at which BD is rated [degC]
    temperature_coefficient : fractional change of BD per kelvin, c [1/K]

    >>> round(float(damper_damping_rate(1.3e-4, -40.0)), 10)
    0.0001638
    """
    bd = as_float(reference_damping_rate)
    dt = as_float(temperature) - as_float(reference_temperature)
    return as_float(bd * (1.0 + as_float(temperature_coefficient) * dt))


def total_damping_rate(damper_rate: ArrayLike, gearbox_rate: ArrayLike) -> FloatArray:
    """Total damping rate BT_T at the high-speed shaft (Eq. 1): ``BT_T = BD_T + BG``.

    Parameters
    ----------
    damper_rate : BD_T, the high-speed damper's rate at T [N*m*s/rad]
    gearbox_rate : BG, the gearbox damping referred to the high-speed shaft [N*m*s/rad]
    """
    return as_float(as_float(damper_rate) + as_float(gearbox_rate))


def total_friction(
    damper_friction: ArrayLike, lubrication_friction: ArrayLike, gearbox_friction: ArrayLike
) -> FloatArray:
    """Total Coulomb friction FT_T at the high-speed shaft (Eq. 2): ``FD + FL_T + FG``.

    Parameters
    ----------
    damper_friction : FD, the high-speed damper's Coulomb friction [N*m]
    lubrication_friction : FL_T, the lubrication friction at T [N*m]
    gearbox_friction : FG, the gearbox friction referred to the high-speed shaft [N*m]
    """
    return as_float(
        as_float(damper_friction) + as_float(lubrication_friction) + as_float(gearbox_friction)
    )


def refer_damping_to_input(high_speed_rate: ArrayLike, gear_ratio: ArrayLike) -> FloatArray:
    """Damping rate of the ECD at the slow input shaft (Eq. 3): ``BECD_T = BT_T * N**2``.

    Parameters
    ----------
    high_speed_rate : BT_T, total damping at the high-speed shaft [N*m*s/rad]
    gear_ratio : N, high-speed shaft turns per input shaft turn [-]

    >>> round(float(refer_damping_to_input(1.638e-4, 380)), 4)
    23.6527
    """
    n = as_float(gear_ratio)
    return as_float(as_float(high_speed_rate) * n * n)


def refer_friction_to_input(high_speed_friction: ArrayLike, gear_ratio: ArrayLike) -> FloatArray:
    """Coulomb friction of the ECD at the slow input shaft (Eq. 4): ``FECD_T = FT_T * N``.

    Parameters
    ----------
    high_speed_friction : FT_T, total friction at the high-speed shaft [N*m]
    gear_ratio : N, high-speed shaft turns per input shaft turn [-]
    """
    return as_float(as_float(high_speed_friction) * as_float(gear_ratio))


def input_speed(torque: ArrayLike, friction: ArrayLike, damping_rate: ArrayLike) -> FloatArray:
    """Steady speed of the ECD input shaft under a constant torque (Eq. 5).

    ``omega_I = (T_I - FECD) / BECD``, and zero where the torque does not exceed the
    friction (the damper does not turn; Eq. 5 alone would give a negative speed).

    Parameters
    ----------
    torque : input torque T_I [N*m]
    friction : FECD_T, Coulomb friction referred to the input [N*m]
    damping_rate : BECD_T, damping rate referred to the input [N*m*s/rad]
    """
    excess = as_float(torque) - as_float(friction)
    return as_float(np.maximum(excess, 0.0) / as_float(damping_rate))


def dynamic_damping_rate(torque: ArrayLike, speed: ArrayLike) -> FloatArray:
    """CDA's "Dynamic Damping Rate" at one operating point (Eq. 6): ``DBECD = T_I / omega_I``.

    Where the speed is zero (torque at or below friction) the ratio is +inf: the damper
    holds the torque without moving. It is never NaN.

    Parameters
    ----------
    torque : input torque T_I [N*m]
    speed : input speed omega_I at that torque [rad/s]
    """
    t = as_float(torque)
    w = as_float(speed)
    moving = w > 0.0
    safe_speed = np.where(moving, w, 1.0)
    return np.where(moving, t / safe_speed, np.inf)


def damper_torque(damping_rate: ArrayLike, speed: ArrayLike) -> FloatArray:
    """Eddy-current torque of the high-speed damper in its linear range: ``BD_T * omega_d``.

    Used to check the damper's linear-range torque limit (paper section 2.1).

    Parameters
    ----------
    damping_rate : BD_T, the high-speed damper's damping rate [N*m*s/rad]
    speed : high-speed shaft speed omega_d [rad/s]
    """
    return as_float(as_float(damping_rate) * as_float(speed))
