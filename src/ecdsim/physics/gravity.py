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

import math

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


# --- gravity as an effect of the hinge's registry (dynamics/kernel/effects.py) ---------
# The registry's convention: T along deployment, a function of the deployed angle and
# speed, with its slopes; the laws above, signed.


def gravity_load_torque(angle: float, speed: float, amplitude: float, release: float) -> float:
    """Gravity's torque along deployment, ``-W sin(theta_0 + phi)`` [N*m]: the
    :func:`gravity_torque` of rigid-body statics (Meriam & Kraige, Statics, section on the
    moment of a force), counted along deployment.

    Parameters
    ----------
    angle : deployed angle phi [rad]
    speed : the load's speed [rad/s] (gravity does not depend on it)
    amplitude : W [N*m]
    release : theta_0 [rad]
    """
    return -float(gravity_torque(angle, amplitude, release))


def gravity_load_slopes(
    angle: float, speed: float, amplitude: float, release: float
) -> tuple[float, float]:
    """``(dT/dphi, dT/domega) = (-W cos(theta_0 + phi), 0)`` of
    :func:`gravity_load_torque` (:func:`gravity_torque_slope`; Statics, section on the
    moment of a force) [N*m/rad, N*m*s/rad].

    Parameters
    ----------
    angle : deployed angle phi [rad]
    speed : the load's speed [rad/s]
    amplitude : W [N*m]
    release : theta_0 [rad]
    """
    return -float(gravity_torque_slope(angle, amplitude, release)), 0.0


def gravity_level_count(
    slope: float, lo: float, hi: float, amplitude: float, release: float
) -> int:
    """How many candidates :func:`gravity_level_angle` lists for ``[lo, hi]``: the angles
    where gravity's stiffness ``-W cos(theta_0 + phi)`` (section on the moment of a
    force, as :func:`gravity_torque_slope`) is ``-slope``; none where ``|slope| > |W|``.

    Parameters
    ----------
    slope : the stiffness sought, negated [N*m/rad] (the spring piece's slope)
    lo : the interval's least deployed angle [rad]
    hi : its greatest [rad]
    amplitude : W [N*m]
    release : theta_0 [rad]
    """
    if amplitude == 0.0 or abs(slope) > abs(amplitude):
        return 0
    first = math.floor((lo + release - math.pi) / (2.0 * math.pi))
    last = math.ceil((hi + release + math.pi) / (2.0 * math.pi))
    return 2 * (int(last) - int(first) + 1)


def gravity_level_angle(
    slope: float, lo: float, hi: float, i: int, amplitude: float, release: float
) -> float:
    """Candidate ``i`` of :func:`gravity_level_count` [rad]: ``cos(theta_0 + phi) =
    slope / W`` (section on the moment of a force), ``theta = +-acos(slope / W)`` plus
    whole turns; the caller keeps those inside ``[lo, hi]``.

    Parameters
    ----------
    slope : the stiffness sought, negated [N*m/rad]
    lo : the interval's least deployed angle [rad]
    hi : its greatest [rad]
    i : the candidate's index [-], from 0
    amplitude : W [N*m]
    release : theta_0 [rad]
    """
    first = math.floor((lo + release - math.pi) / (2.0 * math.pi))
    root = math.acos(slope / amplitude) * (1.0 if i % 2 == 0 else -1.0)
    return root + 2.0 * math.pi * (int(first) + i // 2) - release
