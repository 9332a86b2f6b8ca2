"""The deployment load: spring torque over the travel (paper section 5).

Angle convention. The paper's Eq. 7 measures theta from the *end* of travel: theta = theta_s
(= the deployment angle) at the start and 0 at the end. ecdsim measures the deployed angle
phi from the *start*: phi = 0 at the start and phi = travel at the latch, so that angle and
time grow together. The two are related by ``theta = travel - phi``.
"""

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, as_float


def spring_torque_eq7(
    theta: ArrayLike, start_torque: ArrayLike, end_torque: ArrayLike, travel: ArrayLike
) -> FloatArray:
    """Linear spring torque in the paper's own angle (Eq. 7): ``T = theta/theta_s*(Ts-Te) + Te``.

    Parameters
    ----------
    theta : angle remaining to the end of travel (paper convention) [rad]
    start_torque : Ts, torque at the start of deployment [N*m]
    end_torque : Te, torque at the end of deployment [N*m]
    travel : theta_s = delta_theta, the deployment angle [rad]

    >>> round(float(spring_torque_eq7(1.57, 3.73, 1.58, 1.57)), 12)
    3.73
    """
    ts = as_float(start_torque)
    te = as_float(end_torque)
    return as_float(as_float(theta) / as_float(travel) * (ts - te) + te)


def spring_torque_linear(
    angle: ArrayLike, start_torque: ArrayLike, end_torque: ArrayLike, travel: ArrayLike
) -> FloatArray:
    """Linear spring torque at deployed angle phi: Eq. 7 with ``theta = travel - phi``.

    Parameters
    ----------
    angle : deployed angle phi, 0 at the start [rad]
    start_torque : Ts [N*m]
    end_torque : Te [N*m]
    travel : deployment angle [rad]
    """
    trav = as_float(travel)
    return spring_torque_eq7(trav - as_float(angle), start_torque, end_torque, trav)


def spring_temperature_factor(
    temperature: ArrayLike, coefficient: ArrayLike, reference_temperature: ArrayLike = 25.0
) -> FloatArray:
    """Scale factor of spring torque with temperature: ``1 + k * (T - T_ref)``.

    The paper asks the engineer not to assume spring torque constant over temperature
    (section 4) without giving a law; ecdsim offers this linear one (k = 0 by default).

    Parameters
    ----------
    temperature : T [degC]
    coefficient : fractional change of spring torque per kelvin, k [1/K]
    reference_temperature : temperature at which the torques are given [degC]
    """
    dt = as_float(temperature) - as_float(reference_temperature)
    return as_float(1.0 + as_float(coefficient) * dt)


def tabulated_torque(
    angle: ArrayLike, table_angles: ArrayLike, table_torques: ArrayLike
) -> FloatArray:
    """Spring torque interpolated linearly in an (angle, torque) table.

    The measured alternative to Eq. 7 for springs that are not linear in angle (the paper,
    section 4, asks for the torque to be characterised over the deployment angle).

    Parameters
    ----------
    angle : deployed angle phi [rad]
    table_angles : strictly increasing table angles, starting at 0 [rad]
    table_torques : torques at the table angles [N*m]
    """
    return np.asarray(
        np.interp(
            as_float(angle),
            as_float(table_angles),
            as_float(table_torques),
        ),
        dtype=float,
    )
