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
kernel (:mod:`ecdsim.dynamics.kernel`), which compiles these very functions; the damper
FMU translates the same functions to C (:mod:`ecdsim.fmu.ctranslate`, whose subset
takes ``np.exp`` as C's ``exp``): :func:`stribeck_friction` and
:func:`input_coulomb_friction` are its plain-float compositions of them.
"""

import math

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
    g = stribeck_curve(speed, excess, stribeck_speed)
    return g, -2.0 * (speed / stribeck_speed) / stribeck_speed * g


def stribeck_curve(speed: Real, excess: Real, stribeck_speed: Real) -> Real:
    """``g(u) = (F_brk - F_C) exp(-(u / w_St)^2)``, the friction above Coulomb [N*m]
    (:func:`stribeck_excess` without its slope: the LuGre model's steady-state Stribeck
    curve, Canudas de Wit et al. 1995, section 2; paper section 2.2's friction is its
    Coulomb part).

    Parameters
    ----------
    speed : u, sliding speed at the input shaft [rad/s]
    excess : F_brk - F_C, breakaway over Coulomb friction [N*m], >= 0
    stribeck_speed : w_St [rad/s], > 0

    >>> round(float(stribeck_curve(2.0, 1.0, 2.0)), 12)
    0.367879441171
    """
    ratio = speed / stribeck_speed
    return excess * np.exp(-ratio * ratio)


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


def stribeck_friction(
    speed: float, kinetic: float, static_factor: float, stribeck_speed: float
) -> float:
    """Sliding friction opposing ``speed``: ``sign(u) [F_C + (f F_C - F_C) exp(-(u/w_St)^2)]``.

    The Stribeck curve of :func:`stribeck_excess` (docs/dynamics.md, "Stribeck
    friction") over the kinetic ``F_C``, with the excess ``(f - 1) F_C`` of
    :func:`breakaway`: from the breakaway ``f F_C`` near rest to the kinetic ``F_C`` as
    speed grows; ``F_C`` at every speed without a Stribeck speed (w_St = inf). 0 at
    rest (u = 0) and for a NaN speed: the holding torque at rest depends on the rest of
    the mechanism. The damper FMU's friction (F_C its FECD_T, Eq. 2, 4).

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
    excess = breakaway(kinetic, static_factor) - kinetic
    if excess != 0.0 and math.isfinite(stribeck_speed):
        friction = kinetic + float(stribeck_curve(speed, excess, stribeck_speed))
    return math.copysign(friction, speed)


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
