"""Coulomb friction with an optional Stribeck curve: sliding torque and breakaway.

The paper's frictions (FECD_T, Eq. 2 and 4; the system friction FS_T, section 5) are
Coulomb torques: constant while sliding, opposing the motion. At rest a friction holds
up to its breakaway, the static value ``f F`` (the static coefficient is at least the
kinetic one: Meriam and Kraige, *Engineering Mechanics: Statics*, 7th ed., section 6/3).
With a Stribeck speed w_St the sliding friction falls from the breakaway at rest to the
Coulomb value with speed (the LuGre model's steady-state Stribeck curve, Canudas de Wit,
Olsson, Astrom and Lischinsky, IEEE Trans. Automatic Control 40(3), 419-425, 1995):

    F(u) = F_C + (F_brk - F_C) exp(-(u / w_St)^2)

Each function is written once for floats, NumPy arrays and numba's compiled dynamic
kernel (:mod:`ecdsim.dynamics.kernel`), which compiles these very functions.
"""

import numpy as np

from ecdsim._types import BoolArray, Real


def stribeck_excess(speed: Real, excess: Real, stribeck_speed: Real) -> tuple[Real, Real]:
    """The Stribeck part of the sliding friction above Coulomb, and its slope in speed.

    ``g(u) = (F_brk - F_C) exp(-(u / w_St)^2)``: the steady-state Stribeck curve
    ``g(v) = F_C + (F_s - F_C) exp(-(v / v_s)^2)`` of the LuGre model (Canudas de Wit et
    al. 1995, module notes), one of the forms reviewed by Armstrong-Helouvry, Dupont and
    Canudas de Wit, Automatica 30(7), 1994. The breakaway is at rest (u = 0) and w_St is
    used as given (Simscape's Rotational Friction instead peaks near T_brk at a breakaway
    speed w_brk, with w_St = sqrt(2) w_brk and a sqrt(2 e) scale; docs/model.md). The
    paper's frictions (section 2.2, 3.2) are its Coulomb part.

    Parameters
    ----------
    speed : u, sliding speed at the input shaft [rad/s]
    excess : F_brk - F_C, breakaway over Coulomb friction [N*m], >= 0
    stribeck_speed : w_St [rad/s], > 0 (inf: no Stribeck curve, then g is the excess)

    Returns
    -------
    g : the friction above Coulomb at u [N*m]
    slope : dg/du [N*m*s/rad]

    >>> g, slope = stribeck_excess(np.array([0.0, 2.0]), np.array([1.0, 1.0]), 2.0)
    >>> [round(float(v), 12) for v in g], [round(float(v), 12) for v in slope]
    ([1.0, 0.367879441171], [-0.0, -0.367879441171])
    """
    ratio = speed / stribeck_speed
    g = excess * np.exp(-ratio * ratio)
    return g, -2.0 * ratio / stribeck_speed * g


def breakaway(kinetic: Real, static_factor: Real) -> Real:
    """Breakaway (static) friction torque ``f F`` [N*m] (paper section 2.2's "coulomb (or
    static)" friction; the static factor f >= 1, Meriam and Kraige, Statics, 6/3).

    Parameters
    ----------
    kinetic : F, the Coulomb (kinetic) friction torque [N*m]
    static_factor : f, breakaway over kinetic friction [-], >= 1

    >>> float(breakaway(2.0, 1.25))
    2.5
    """
    return kinetic * static_factor


def holds(drive: Real, static: Real, margin: Real) -> bool | BoolArray:
    """Whether friction at rest holds a drive: ``|drive| <= static (1 + margin)``.

    The stick test of a resting body (Coulomb's law at rest, paper section 2.2's static
    friction): the friction can supply any torque up to its breakaway. The margin (a
    relative 1e-12 in the dynamic method) keeps a motion that stops exactly where the
    drive equals the friction from being restarted by rounding.

    Parameters
    ----------
    drive : the torque the friction must hold [N*m]
    static : the breakaway friction [N*m], >= 0
    margin : relative margin on the comparison [-]

    >>> bool(holds(1.0, 1.0, 1e-12)), bool(holds(-1.1, 1.0, 1e-12))
    (True, False)
    """
    return np.abs(drive) <= static + margin * np.maximum(np.abs(drive), static)
