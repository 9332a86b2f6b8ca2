"""Rigid-body mechanics of the deployment: reflected inertia, engagement and end-stop impact.

Textbook relations (Meriam and Kraige, *Engineering Mechanics: Dynamics*, 7th ed.,
sections 6/8 "impulse-momentum" and 3/12 "impact" for the coefficient of restitution;
Wittenburg, *Dynamics of Multibody Systems*, 2nd ed., 2008, section 3.3 for inertia
reflected through a gear pair). The paper neglects inertia (section 4, end) and notes gear
lost motion (section 3.4) without modelling it.
"""

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, as_float


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


def kinetic_energy(inertia: ArrayLike, speed: ArrayLike) -> FloatArray:
    """Rotational kinetic energy ``J omega**2 / 2``.

    Meriam and Kraige, *Engineering Mechanics: Dynamics*, 7th ed., 2012, section 6/6
    (kinetic energy of a body rotating about a fixed axis). The paper neglects it
    (section 4, end).

    Parameters
    ----------
    inertia : J [kg*m^2]
    speed : omega [rad/s]
    """
    w = np.asarray(speed, dtype=float)
    return as_float(0.5 * np.asarray(inertia, dtype=float) * w * w)


def plastic_engagement(
    load_inertia: ArrayLike, load_speed: ArrayLike, damper_inertia: ArrayLike
) -> tuple[FloatArray, FloatArray]:
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
    jl = np.asarray(load_inertia, dtype=float)
    jd = np.asarray(damper_inertia, dtype=float)
    w = np.asarray(load_speed, dtype=float)
    total = jl + jd
    return as_float(jl * w / total), as_float(0.5 * jl * jd * w * w / total)


def rebound(
    speed: ArrayLike, restitution: ArrayLike, inertia: ArrayLike
) -> tuple[FloatArray, FloatArray]:
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
    e = np.asarray(restitution, dtype=float)
    w = np.asarray(speed, dtype=float)
    return as_float(-e * w), as_float((1.0 - e * e) * kinetic_energy(inertia, w))


def static_friction(kinetic_friction: ArrayLike, static_factor: ArrayLike) -> FloatArray:
    """Breakaway (static) friction torque: ``factor * kinetic``, factor >= 1.

    The static coefficient of friction is at least the kinetic one (Meriam and Kraige,
    *Engineering Mechanics: Statics*, 7th ed., 2012, section 6/3); the paper calls the
    damper's and gearbox's friction "coulomb (or static)" (section 2.2) and gives one value.

    Parameters
    ----------
    kinetic_friction : Coulomb (kinetic) friction torque [N*m]
    static_factor : static over kinetic friction [-], >= 1
    """
    return as_float(
        np.asarray(kinetic_friction, dtype=float) * np.asarray(static_factor, dtype=float)
    )


def elasto_backlash_torque(
    relative_angle: ArrayLike,
    relative_speed: ArrayLike,
    gap: ArrayLike,
    stiffness: ArrayLike,
    damping: ArrayLike,
) -> FloatArray:
    """Torque through a compliant gear mesh with lost motion (an elastic backlash).

    The Modelica Standard Library's ``Modelica.Mechanics.Rotational.Components.
    ElastoBacklash`` (MSL 4.0, documentation of the component): a spring-damper in
    series with a backlash of total width b; with ``phi_rel`` the relative angle between
    the driving and the driven flange and ``w_rel`` its rate,

        tau = c (phi_rel - b/2) + d w_rel     phi_rel >  b/2, limited to tau >= 0
        tau = 0                               |phi_rel| <= b/2
        tau = c (phi_rel + b/2) + d w_rel     phi_rel < -b/2, limited to tau <= 0

    The limit is Modelica's: the damping term cannot make the contact pull the flanks
    together (the teeth only push), so the contact torque never changes sign through d.
    A torque limited to zero while ``|phi_rel| > b/2`` means the flanks have separated
    faster than the compressed mesh relaxes (its stored energy is then dissipated, see
    docs/dynamics.md). The lost motion b is the gearbox's, which the paper notes in its
    section 3.4 without modelling it.

    Parameters
    ----------
    relative_angle : phi_rel, driving minus driven angle at the input shaft [rad]
    relative_speed : w_rel = phi_rel' [rad/s]
    gap : b, total lost motion [rad], >= 0
    stiffness : c [N*m/rad], > 0
    damping : d [N*m*s/rad], >= 0

    >>> [round(float(t), 12) for t in elasto_backlash_torque(
    ...     [0.0, 0.02, 0.02, -0.03], [1.0, 0.1, -1.0, 0.0], 0.02, 100.0, 1.0)]
    [0.0, 1.1, 0.0, -2.0]
    """
    phi = np.asarray(relative_angle, dtype=float)
    w = np.asarray(relative_speed, dtype=float)
    half = 0.5 * np.asarray(gap, dtype=float)
    c = np.asarray(stiffness, dtype=float)
    d = np.asarray(damping, dtype=float)
    ahead = np.maximum(c * (phi - half) + d * w, 0.0)
    behind = np.minimum(c * (phi + half) + d * w, 0.0)
    return as_float(np.where(phi > half, ahead, np.where(phi < -half, behind, 0.0)))
