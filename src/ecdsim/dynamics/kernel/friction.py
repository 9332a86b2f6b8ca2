"""The friction state machine, once for any number of friction elements.

Each friction element acts along a direction ``g_k`` of the generalised speeds (its
sliding speed is ``u_k = g_k . v``) and is sliding forward, backward, or stuck (the
Modelica Standard Library's ``Rotational.Interfaces.PartialFriction``: forward, backward,
stuck, written once for every friction element). Stuck elements are constraints
``g_k . a = 0`` on the accelerations; the torques they must supply are the constraint
forces of

    M a = Q + sum_{k stuck} g_k lambda_k,      g_k . a = 0 (k stuck)

(Q the generalised forces without the stuck elements' friction), and element k can
hold while ``|lambda_k|`` stays within its breakaway ``f F`` (Coulomb at rest,
:mod:`ecdsim.physics.friction`). Where several elements are at rest at once the set that
sticks is resolved exactly (an active-set pass): all of them are taken as stuck, the
one whose holding torque exceeds its breakaway the most breaks away in the direction it
is pushed (its friction then sliding), and the rest are solved again, until every stuck
element holds. A stuck element breaks away later when its holding torque reaches its
breakaway (an event of the loop); a sliding one comes to rest when its speed reaches
zero (another), and the pass decides again. Nothing depends on time but through the
state, so when every element is stuck the run has ended (stuck, or held at the end of
travel): there is no chatter.

The same constraint solve gives the segment's accelerations, ``a = P_S Q`` with
``P_S = Z (Z^T M Z)^-1 Z^T`` (Z spanning the motions the stuck elements allow), which
:mod:`ecdsim.dynamics.kernel.hinge` uses.

For the hinge's models the elements are the load's friction (FS_T, with the ECD's
FECD_T on a rigid mesh) along ``g_0 = e_0`` and, with a compliant mesh, the damper
side's (FECD_T) along ``g_1 = (1, -1)`` (its angle is ``phi_L - delta``).
"""

from __future__ import annotations

import math

from ecdsim._types import FloatArray
from ecdsim.dynamics.kernel import layout as L
from ecdsim.dynamics.kernel.hinge import hinge_forces
from ecdsim.physics.friction import holds

# A breakaway needs the drive to exceed static friction by more than this relative
# margin; at the boundary (a motion that stops where drive = kinetic friction = static
# friction) rounding must not restart the motion: that would be numerical chatter.
STICK_MARGIN = 1e-12
# Relative rounding of the constraint forces of a constraint solve.
ROUNDING = 1e-13


def element_direction(k: int, j: int) -> float:
    """Component j of friction element k's direction (the hinge's: module notes)."""
    if j == 0:
        return 1.0
    return -1.0 if k == 1 else 0.0


def mass_matrix(cw: FloatArray, mass: FloatArray, m: int) -> None:
    """The mass matrix of the generalised coordinates (the bodies' inertias along their
    directions; a rigid mesh's damper side through its mesh factor once engaged)."""
    par = sg = cw
    if m == 1:
        mass[0, 0] = par[L.JL] + sg[L.SG_ENG] * sg[L.SG_MESH] * par[L.JD]
        return
    mass[0, 0] = par[L.JL] + par[L.JD]
    mass[0, 1] = -par[L.JD]
    mass[1, 0] = -par[L.JD]
    mass[1, 1] = par[L.JD]


def solve_small(a: FloatArray, x: FloatArray, size: int) -> bool:
    """Solve ``a[:, :size] x = a[:, size]`` by Gaussian elimination with partial
    pivoting, in place; False if singular."""
    for k in range(size):
        best = k
        for i in range(k + 1, size):
            if abs(a[i, k]) > abs(a[best, k]):
                best = i
        if a[best, k] == 0.0:
            return False
        if best != k:
            for j in range(size + 1):
                held = a[k, j]
                a[k, j] = a[best, j]
                a[best, j] = held
        for i in range(k + 1, size):
            factor = a[i, k] / a[k, k]
            for j in range(k, size + 1):
                a[i, j] -= factor * a[k, j]
    for i in range(size - 1, -1, -1):
        acc = a[i, size]
        for j in range(i + 1, size):
            acc -= a[i, j] * x[j]
        x[i] = acc / a[i, i]
    return True


def constrained(cw: FloatArray, scratch: FloatArray, out: FloatArray, m: int) -> None:
    """Accelerations (``out[:m]``) and constraint forces (``out[m + k]``, stuck k) of the
    constraint system of the module notes, for the generalised forces and stuck flags in
    the scratch's rows (its layout: :func:`scratch_rows`)."""
    stuck = scratch[3 * m + 1]
    mass = scratch[:m, :m]
    mass_matrix(cw, mass, m)
    forces = scratch[3 * m]
    size = m
    for k in range(m):
        if stuck[k] != 0.0:
            size += 1
    system = scratch[m : 3 * m, :]
    for i in range(size):
        for j in range(size + 1):
            system[i, j] = 0.0
    for i in range(m):
        for j in range(m):
            system[i, j] = mass[i, j]
        system[i, size] = forces[i]
    row = m
    for k in range(m):
        if stuck[k] == 0.0:
            continue
        for j in range(m):
            g = element_direction(k, j)
            system[j, row] = -g  # M a - g lambda = Q
            system[row, j] = g  # g . a = 0
        row += 1
    solve_small(system, out, size)
    # The stuck elements' forces moved to their element indices (last first).
    for k in range(m - 1, -1, -1):
        if stuck[k] != 0.0:
            row -= 1
            out[m + k] = out[row]
        else:
            out[m + k] = 0.0


def scratch_rows(m: int) -> tuple[int, int]:
    """The friction machine's scratch: rows [0, m) the mass matrix, [m, 3m) the
    constraint system, 3m the generalised forces, 3m + 1 the stuck flags; 2m + 1 columns."""
    return 3 * m + 2, 2 * m + 1


def stuck_flags(cw: FloatArray, scratch: FloatArray, m: int) -> None:
    """The scratch's stuck-flags row filled from the case's friction modes."""
    md = cw
    for k in range(m):
        scratch[3 * m + 1, k] = 1.0 if md[L.MD_SLIDE0 + k] == 0 else 0.0


def projected_inverse(cw: FloatArray, scratch: FloatArray, column: FloatArray, m: int) -> None:
    """``P_S`` (into the words from ``PINV``, row-major): the accelerations for unit
    generalised forces, column by column."""
    unit = scratch[3 * m]
    for j in range(m):
        for i in range(m):
            unit[i] = 0.0
        unit[j] = 1.0
        constrained(cw, scratch, column, m)
        for i in range(m):
            cw[L.PINV + i * m + j] = column[i]


def drives(
    cw: FloatArray, y: FloatArray, scratch: FloatArray, out: FloatArray, m: int, na: int
) -> None:
    """The torque each stuck element must hold at state y (``out[m + k]`` = minus its
    constraint force: the drive along its direction, which its friction opposes)."""
    q0, q1, _, _, _, _, _ = hinge_forces(cw, y, m, na)
    forces = scratch[3 * m]
    forces[0] = q0
    if m == 2:
        forces[1] = q1
    constrained(cw, scratch, out, m)
    # The constraint solve mixes the rows: a drive below the solve's rounding of the
    # forces is zero (a frictionless body at rest in the gap holds nothing, exactly).
    scale = 0.0
    for i in range(m):
        scale = max(scale, abs(forces[i]))
    for k in range(m):
        drive = -out[m + k]
        out[m + k] = drive if abs(drive) > ROUNDING * scale else 0.0


def breakaway_of(cw: FloatArray, k: int, m: int) -> float:
    """Element k's breakaway friction [N*m]: the load's system friction f_S FS_T, with the
    ECD's f_D FECD_T on an engaged rigid mesh; the damper side's f_D FECD_T (compliant)."""
    par = sg = cw
    if k == 1:
        damper: float = par[L.FEB]
        return damper
    if m == 1:
        static: float = par[L.FSB] + sg[L.SG_ENG] * par[L.FEB]
        return static
    load: float = par[L.FSB]
    return load


def capacity(cw: FloatArray, k: int, drive: float, m: int) -> float:
    """How much torque element k holds at rest in the direction of ``drive`` [N*m]:
    its breakaway, or without limit where the load is held at the end of travel or
    pressed into the start stop (which holds any backward drive)."""
    md = cw
    if k == 0 and (md[L.MD_HELD] != 0 or (md[L.MD_START] != 0 and drive < 0.0)):
        return math.inf
    return breakaway_of(cw, k, m)


def holds_at_rest(cw: FloatArray, k: int, drive: float, m: int) -> bool:
    """Element k at rest holds ``drive`` (Coulomb at rest with the stick margin)."""
    limit = capacity(cw, k, drive, m)
    if limit == math.inf:
        return True
    return bool(holds(drive, limit, STICK_MARGIN))
