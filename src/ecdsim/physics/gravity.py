"""Gravity torque on the hinge in a ground test (issue 16 item 2).

Rigid-body statics (e.g. Meriam & Kraige, Engineering Mechanics: Statics, the moment of
a force about an axis): a deployed mass m with its centre of gravity at radius r from a
horizontal hinge axis feels the moment ``M = m g r sin(beta)`` about the hinge, where
beta is the angle between the downward vertical (the direction of gravity) and the
hinge-to-CG line. Its potential energy is ``U = -m g r cos(beta)`` (height of the CG
below the hinge), and ``M = dU/dbeta`` is the torque that opposes an increase of beta.

ecdsim's convention (sketch and discussion in docs/model.md, "Gravity in ground tests"):
beta grows with the deployed angle phi, one to one, ``beta = theta_0 + phi``, with
theta_0 the angle at release; the gravity torque is counted **positive where it opposes
deployment**, like the resistive table::

    T_g(phi) = m g r (1 - offload) sin(theta_0 + phi)

so that deployment lifting the CG (0 < beta < 180 deg) is opposed, lowering it
(-180 < beta < 0) is aided. The ground-support equipment carries the fraction
``offload`` of the weight (1 = fully offloaded, flight-like: no torque).
"""

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, Real, as_float

# Standard acceleration of gravity (CGPM 1901; ISO 80000-3), m/s^2.
STANDARD_GRAVITY = 9.80665


def gravity_amplitude(
    mass: ArrayLike, cg_radius: ArrayLike, offload: ArrayLike, gravity: float = STANDARD_GRAVITY
) -> FloatArray:
    """Peak gravity torque about the hinge, ``W = m g r (1 - offload)`` [N*m].

    The moment of the offloaded weight at the CG's radius (rigid-body statics, Meriam &
    Kraige, Statics, section on the moment of a force; docs/model.md).

    Parameters
    ----------
    mass : deployed mass m [kg]
    cg_radius : distance r of the centre of gravity from the hinge axis [m]
    offload : fraction of the weight carried by the ground-support equipment [-], 0..1
    gravity : acceleration of gravity g [m/s^2], standard gravity by default

    >>> round(float(gravity_amplitude(2.0, 0.5, 0.75)), 9)  # 2 * 9.80665 * 0.5 * 0.25
    2.4516625
    """
    return as_float(as_float(mass) * gravity * as_float(cg_radius) * (1.0 - as_float(offload)))


def gravity_torque(angle: Real, amplitude: Real, release_angle: Real) -> Real:
    """Gravity torque about the hinge, opposing deployment positive [N*m].

    ``T_g(phi) = W sin(theta_0 + phi)`` (rigid-body statics, Meriam & Kraige, Statics,
    section on the moment of a force; sign convention in the module docstring).

    Parameters
    ----------
    angle : deployed angle phi, 0 at release [rad]
    amplitude : W = m g r (1 - offload) [N*m] (:func:`gravity_amplitude`)
    release_angle : theta_0, from gravity to the hinge-CG line at release [rad]
        (measured from the downward vertical, positive in the direction of deployment)

    >>> round(float(gravity_torque(np.pi / 2, 2.0, 0.0)), 12)  # arm horizontal: full W
    2.0
    """
    return amplitude * np.sin(release_angle + angle)


def gravity_torque_slope(angle: Real, amplitude: Real, release_angle: Real) -> Real:
    """``dT_g/dphi = W cos(theta_0 + phi)`` [N*m/rad], for Jacobians and extremes.

    The derivative of :func:`gravity_torque` (rigid-body statics, section on the moment
    of a force; docs/model.md).

    Parameters
    ----------
    angle : deployed angle phi [rad]
    amplitude : W [N*m]
    release_angle : theta_0 [rad]
    """
    return amplitude * np.cos(release_angle + angle)


def gravity_work(start: Real, end: Real, amplitude: Real, release_angle: Real) -> Real:
    """Work done *against* gravity from phi = start to end, ``int T_g dphi`` [J].

    ``W (cos(theta_0 + start) - cos(theta_0 + end))``: the rise of the CG's potential
    energy ``-m g r (1 - offload) cos(beta)`` (rigid-body mechanics, Meriam & Kraige,
    Dynamics, section on potential energy; docs/model.md).

    Parameters
    ----------
    start : deployed angle at the start [rad]
    end : deployed angle at the end [rad]
    amplitude : W [N*m]
    release_angle : theta_0 [rad]
    """
    return amplitude * (np.cos(release_angle + start) - np.cos(release_angle + end))
