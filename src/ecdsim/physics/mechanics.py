"""Rigid-body mechanics of the deployment: reflected inertia, engagement and end-stop impact.

Textbook relations (Meriam and Kraige, *Engineering Mechanics: Dynamics*, 7th ed.,
sections 6/8 "impulse-momentum" and 3/12 "impact" for the coefficient of restitution;
Wittenburg, *Dynamics of Multibody Systems*, 2nd ed., 2008, section 3.3 for inertia
reflected through a gear pair). The paper neglects inertia (section 4, end) and notes gear
lost motion (section 3.4) without modelling it.
"""

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, Real, as_float


def reflect_inertia_to_input(inertia: ArrayLike, gear_ratio: ArrayLike) -> FloatArray:
    """Inertia of a high-speed part seen at the slow input shaft: ``J * N**2``.

    The kinetic energy ``J (N omega)**2 / 2`` of a part turning N times faster than the
    input equals that of an inertia ``J N**2`` at the input (Wittenburg 2008, 3.3), the
    same N**2 that reflects damping (paper Eq. 3).

    Parameters
    ----------
    inertia : moment of inertia at the high-speed shaft [kg*m^2]
    gear_ratio : N, high-speed turns per input turn [-]

    >>> round(float(reflect_inertia_to_input(1.0e-7, 380.0)), 6)
    0.01444
    """
    n = np.asarray(gear_ratio, dtype=float)
    return as_float(np.asarray(inertia, dtype=float) * n * n)


def kinetic_energy(inertia: Real, speed: Real) -> Real:
    """Rotational kinetic energy ``J omega**2 / 2``.

    Meriam and Kraige, *Engineering Mechanics: Dynamics*, 7th ed., 2012, section 6/6
    (kinetic energy of a body rotating about a fixed axis). The paper neglects it
    (section 4, end).

    Parameters
    ----------
    inertia : J [kg*m^2]
    speed : omega [rad/s]
    """
    return 0.5 * inertia * speed * speed


def plastic_engagement(
    load_inertia: Real, load_speed: Real, damper_inertia: Real
) -> tuple[Real, Real]:
    """Closing of the gear lost motion: the load meets the resting damper side and they lock.

    Angular momentum is conserved through the (short, perfectly plastic) tooth contact
    (Meriam and Kraige 6/8): ``omega_after = J_L omega_L / (J_L + J_D)``, and the kinetic
    energy lost in the engagement is ``J_L J_D omega_L**2 / (2 (J_L + J_D))``. Sources:
    Meriam and Kraige 2012, section 6/8 (angular impulse-momentum); the gear lost motion
    it closes is the paper's section 3.4.

    Parameters
    ----------
    load_inertia : J_L, the load's inertia at the input shaft [kg*m^2]
    load_speed : omega_L, the load's speed when the gap closes [rad/s]
    damper_inertia : J_D, the damper side's inertia reflected to the input [kg*m^2]

    Returns
    -------
    speed_after : common speed after engagement [rad/s]
    energy_lost : kinetic energy dissipated in the engagement [J]

    >>> w, loss = plastic_engagement(3.0, 2.0, 1.0)
    >>> float(w), float(loss)
    (1.5, 1.5)
    """
    total = load_inertia + damper_inertia
    w = load_speed
    return load_inertia * w / total, 0.5 * load_inertia * damper_inertia * w * w / total


def rebound(speed: Real, restitution: Real, inertia: Real) -> tuple[Real, Real]:
    """Impact on a rigid end stop with Newton's coefficient of restitution e.

    ``omega_after = -e * omega_before`` (Meriam and Kraige 3/12); the energy lost in the
    impact is ``(1 - e**2) J omega_before**2 / 2``. e = 0 is a latch (plastic stop).
    Source: Meriam and Kraige 2012, section 3/12 (coefficient of restitution).

    Parameters
    ----------
    speed : speed just before the impact [rad/s]
    restitution : e, 0 <= e < 1 [-]
    inertia : J, the moving inertia [kg*m^2]

    Returns
    -------
    speed_after : speed just after the impact [rad/s]
    energy_lost : kinetic energy dissipated by the impact [J]

    >>> w, loss = rebound(2.0, 0.5, 1.0)
    >>> float(w), float(loss)
    (-1.0, 1.5)
    """
    return -restitution * speed, (1.0 - restitution * restitution) * kinetic_energy(inertia, speed)


def static_friction(kinetic_friction: Real, static_factor: Real) -> Real:
    """Breakaway (static) friction torque: ``factor * kinetic``, factor >= 1.

    The static coefficient of friction is at least the kinetic one (Meriam and Kraige,
    *Engineering Mechanics: Statics*, 7th ed., 2012, section 6/3); the paper calls the
    damper's and gearbox's friction "coulomb (or static)" (section 2.2) and gives one value.

    Parameters
    ----------
    kinetic_friction : Coulomb (kinetic) friction torque [N*m]
    static_factor : static over kinetic friction [-], >= 1
    """
    return kinetic_friction * static_factor


def mesh_torque(
    relative_angle: Real, relative_speed: Real, half_gap: Real, stiffness: Real, damping: Real
) -> Real:
    """Torque through a compliant gear mesh with lost motion, Modelica's ElastoBacklash2.

    The Modelica Standard Library's ``Modelica.Mechanics.Rotational.Components.
    ElastoBacklash2`` (MSL 4.0, documentation of the component): a spring-damper in
    series with a backlash of total width b; with ``phi_rel`` the relative angle between
    the driving and the driven flange and ``w_rel`` its rate,

        tau = max(c (phi_rel - b/2) + d w_rel, 0)     phi_rel >  b/2
        tau = 0                                       |phi_rel| <= b/2
        tau = min(c (phi_rel + b/2) + d w_rel, 0)     phi_rel < -b/2

    The limit is ElastoBacklash2's: the damping term cannot make the contact pull the
    flanks together (the teeth only push), so the contact torque never changes sign
    through d. (MSL's ``ElastoBacklash`` limits the damping differently, ``tau_c +
    min(tau_c, tau_d)`` on the pressed side: a smaller torque at a fast impact.) A torque
    limited to zero while ``|phi_rel| > b/2`` means the flanks have separated faster
    than the compressed mesh relaxes (its stored energy is then dissipated, see
    docs/dynamics.md). The lost motion b is the gearbox's, which the paper notes in its
    section 3.4 without modelling it. Branch-free (floats, arrays, numba alike).

    Parameters
    ----------
    relative_angle : phi_rel, driving minus driven angle at the input shaft [rad]
    relative_speed : w_rel = phi_rel' [rad/s]
    half_gap : b / 2, half the total lost motion [rad], >= 0
    stiffness : c [N*m/rad], > 0
    damping : d [N*m*s/rad], >= 0

    >>> [round(float(mesh_torque(a, w, 0.01, 100.0, 1.0)), 12)
    ...  for a, w in ((0.0, 1.0), (0.02, 0.1), (0.02, -1.0), (-0.03, 0.0))]
    [0.0, 1.1, 0.0, -2.0]
    """
    ahead = np.maximum(stiffness * (relative_angle - half_gap) + damping * relative_speed, 0.0)
    behind = np.minimum(stiffness * (relative_angle + half_gap) + damping * relative_speed, 0.0)
    return (relative_angle > half_gap) * ahead + (relative_angle < -half_gap) * behind


def mesh_elastic_energy(relative_angle: Real, half_gap: Real, stiffness: Real) -> Real:
    """Energy stored in the compliant mesh's spring, ``c (|phi_rel| - b/2)^2 / 2`` [J].

    The potential of the spring in series with the backlash (MSL ElastoBacklash2, see
    :func:`mesh_torque`); 0 inside the gap (the paper's lost motion, section 3.4).

    Parameters
    ----------
    relative_angle : phi_rel [rad]
    half_gap : b / 2 [rad], >= 0
    stiffness : c [N*m/rad]

    >>> round(float(mesh_elastic_energy(-0.03, 0.01, 100.0)), 12)
    0.02
    """
    deflection = np.maximum(np.abs(relative_angle) - half_gap, 0.0)
    return 0.5 * stiffness * deflection * deflection


def bearing_drag_torque(angle: float, speed: float, rate: float) -> float:
    """Viscous drag of the hinge's bearings on the load, ``T = -c_b omega`` [N*m].

    A lubricated journal bearing's friction torque at low speed is linear in speed
    (Petroff's law, e.g. Shigley's *Mechanical Engineering Design*, 10th ed., Eq. 12-6:
    ``T = 4 pi^2 r^3 l mu n / c``), lumped here into one rate c_b at the slow (hinge)
    shaft. The worked example of an effect (docs/architecture.md, "How to add an effect").

    Parameters
    ----------
    angle : the load's deployed angle [rad] (the drag does not depend on it)
    speed : the load's speed omega [rad/s]
    rate : c_b [N*m*s/rad], >= 0

    >>> bearing_drag_torque(0.3, 2.0, 0.01)
    -0.02
    """
    return -rate * speed


def bearing_drag_slopes(angle: float, speed: float, rate: float) -> tuple[float, float]:
    """``(dT/dangle, dT/dspeed)`` of :func:`bearing_drag_torque` (Petroff, Shigley Eq. 12-6:
    see there): ``(0, -c_b)`` [N*m/rad, N*m*s/rad].

    Parameters
    ----------
    angle : the load's deployed angle [rad]
    speed : the load's speed omega [rad/s]
    rate : c_b [N*m*s/rad], >= 0
    """
    return 0.0, -rate
