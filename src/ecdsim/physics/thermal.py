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
