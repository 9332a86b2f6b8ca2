"""A wing's equations of motion on the kernel: the planar chain in its groups' coordinates.

Lagrange's equations of the panel chain (:mod:`ecdsim.physics.chain`: ``M(q)``, the
velocity terms ``h(q, q')``, the ground test's gravity), in each hinge's deployed angle
``phi = s (q - q_stowed)`` (docs/wing.md):

    M_phi = S M(q) S + diag(J_D)
    F_j = T_j(phi_j) - B_j phi_j' - latch_j + cables_j - s_j h_j + s_j Q_g,j

and in the groups' coordinates psi (hinges joined by rigid cables share one,
``phi = P psi``): ``M_psi = P^T M_phi P``, ``Q_psi = P^T F - d F_k`` with each sliding
group's kinetic friction F_k against its direction d (with a Stribeck speed, each
hinge's friction falls from its breakaway at rest to its kinetic value with speed). A
held group (stuck, or latched) is a constraint ``psi_g'' = 0``; its holding torque, what
its friction or latch supplies, is the constraint force
(:mod:`ecdsim.dynamics.kernel.friction`'s constraint system, solved by its
:func:`~ecdsim.dynamics.kernel.friction.solve_small`). The hinge laws are the single
hinge's: the spring table, the ECD as ``BECD_T`` (Eq. 3) with its Coulomb ``FECD_T``
(Eq. 4), its heating (one node, or rotor and housing), the compliant latch's spring and
damper, the cable's two strands (:func:`ecdsim.physics.cable.cable_torque`).

The functions have the hinge's signatures (``derivatives(cw, y, dy, dm, da, dq)`` ...),
so the kernel's RODAS4 step, its step control and its event locator run a wing unchanged
(:mod:`ecdsim.dynamics.kernel.build` substitutes these for the hinge's). The Jacobian is
taken by forward differences (the chain's ``dM/dq`` is not worth an analytic form; the
stage matrix only needs it to the step's accuracy).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import FloatArray
from ecdsim.dynamics.kernel.friction import solve_small
from ecdsim.physics.cable import cable_torque
from ecdsim.physics.chain import gravity_forces, mass_matrix, velocity_terms
from ecdsim.physics.eddy import damper_side_torque
from ecdsim.physics.friction import stribeck_curve
from ecdsim.physics.gearing import mesh_factor, power_flow_mode
from ecdsim.physics.thermal import (
    damping_factor_from_log,
    factor_log_cooling,
    factor_log_heating,
    housing_rate,
    housing_return,
    temperature_from_factor_log,
)
from ecdsim.wing.kernel import layout as W
from ecdsim.wing.kernel.layout import cable as cable_at
from ecdsim.wing.kernel.layout import group as group_at
from ecdsim.wing.kernel.layout import hinge as hinge_at
from ecdsim.wing.kernel.layout import table_angle, table_torque

# Forward-difference steps of the Jacobian: sqrt(eps) relative, at least this much.
FD_RELATIVE = 1.4901161193847656e-08
FD_FLOOR = 1e-6
# Relative rounding of a holding torque: below it, a holding torque is zero.
ROUNDING = 1e-13


def drive_torque(cw: FloatArray, j: int, phi: float) -> float:
    """Hinge j's net drive at phi: its table (spring less resistive torque), linear
    between breakpoints and continued with its end slopes beyond them [N*m]. Pieces of
    no width (a breakpoint repeated where the spring's and the resistive table's
    breakpoints meet, e.g. at 0 and at the travel) are stepped over."""
    k = int(cw[W.W_K])
    last = int(cw[hinge_at(W.H_POINTS, j)]) - 1
    p = 0
    while p < last - 1 and (
        phi > cw[table_angle(k, j, p + 1)]
        or cw[table_angle(k, j, p + 1)] <= cw[table_angle(k, j, p)]
    ):
        p += 1
    while p > 0 and cw[table_angle(k, j, p + 1)] <= cw[table_angle(k, j, p)]:
        p -= 1  # the end's piece of no width: continue the last real piece
    a0 = cw[table_angle(k, j, p)]
    a1 = cw[table_angle(k, j, p + 1)]
    t0 = cw[table_torque(k, j, p)]
    if a1 <= a0:
        return float(t0)
    t1 = cw[table_torque(k, j, p + 1)]
    value: float = t0 + (t1 - t0) * (phi - a0) / (a1 - a0)
    return value


def drive_work(cw: FloatArray, j: int, phi: float) -> float:
    """The drive's work from 0 to phi [J] (exact for the piecewise-linear table)."""
    k = int(cw[W.W_K])
    last = int(cw[hinge_at(W.H_POINTS, j)]) - 1
    total = 0.0
    start = 0.0
    for p in range(last):
        a1 = cw[table_angle(k, j, p + 1)]
        end = min(phi, a1) if p < last - 1 else phi
        if end > start:
            total += 0.5 * (drive_torque(cw, j, start) + drive_torque(cw, j, end)) * (end - start)
            start = end
    return total


def hinge_angles(cw: FloatArray, y: FloatArray, m: int) -> tuple[FloatArray, FloatArray]:
    """Each hinge's deployed angle and speed at state y (``phi = P psi``)."""
    n = int(cw[W.W_N])
    phi = np.empty(n)
    rate = np.empty(n)
    for j in range(n):
        g = int(cw[hinge_at(W.H_GROUP, j)])
        factor = cw[hinge_at(W.H_FACTOR, j)]
        phi[j] = factor * y[g]
        rate[j] = factor * y[m + g]
    return phi, rate


def _panels(cw: FloatArray, field: int, n: int) -> FloatArray:
    start = hinge_at(field, 0)
    return cw[start : start + n]


def relative(cw: FloatArray, phi: FloatArray, rate: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The relative angles q and their rates q' of deployed angles and speeds."""
    n = phi.shape[0]
    q = np.empty(n)
    dq = np.empty(n)
    for j in range(n):
        s = cw[hinge_at(W.H_SIGN, j)]
        q[j] = cw[hinge_at(W.H_STOWED, j)] + s * phi[j]
        dq[j] = s * rate[j]
    return q, dq


def damper_torque(cw: FloatArray, j: int, rate: float, y: FloatArray) -> tuple[float, float]:
    """Hinge j's ECD torque at the hinge and its eddy-current power over the factor f:
    :func:`ecdsim.physics.eddy.damper_side_torque` (Eq. 3 with the linear or Kloss law,
    BG), at the factor of the damper's temperature (its log state when heated)."""
    aux = int(cw[hinge_at(W.H_AUX, j)])
    factor = cw[hinge_at(W.H_FA, j)]
    if aux >= 0:
        factor = damping_factor_from_log(y[aux], factor, cw[hinge_at(W.H_COEF, j)])
    torque, power = damper_side_torque(
        int(cw[hinge_at(W.H_LAW, j)]),
        cw[hinge_at(W.H_LA, j)],
        cw[hinge_at(W.H_LB, j)],
        0.0,  # the power law's core speed: a wing's dampers are ECDs (linear or Kloss)
        cw[hinge_at(W.H_RATIO, j)],
        cw[hinge_at(W.H_BG, j)],
        rate,
        factor,
    )
    meshed = cw[hinge_at(W.H_MESHED, j)]  # 0 in the lost motion: the damper side idles
    return meshed * float(torque), meshed * float(power)


def latch_torque(cw: FloatArray, j: int, phi: float, rate: float) -> float:
    """Hinge j's engaged compliant latch: ``k (phi - travel) + c phi'`` [N*m] (0 if not)."""
    if cw[hinge_at(W.H_ENGAGED, j)] == 0.0:
        return 0.0
    overshoot = phi - cw[hinge_at(W.H_TRAVEL, j)]
    value: float = cw[hinge_at(W.H_LATCH_K, j)] * overshoot + cw[hinge_at(W.H_LATCH_C, j)] * rate
    return value


def cable_deflection(cw: FloatArray, c: int, phi: FloatArray) -> float:
    """Elastic cable c's ``delta = phi_out - r phi_in`` [rad]."""
    inboard = int(cw[cable_at(W.C_IN, c)])
    value: float = phi[inboard + 1] - cw[cable_at(W.C_RATIO, c)] * phi[inboard]
    return value


def mesh_of(cw: FloatArray, j: int) -> float:
    """Hinge j's lossy gear's factor m on its damper side in its power flow
    (:func:`ecdsim.physics.gearing.mesh_factor`; 1 for an ideal gear or at rest)."""
    flow = int(cw[hinge_at(W.H_FLOW, j)])
    if flow == 0:
        return 1.0
    return float(mesh_factor(flow, cw[hinge_at(W.H_ETAF, j)], cw[hinge_at(W.H_ETAB, j)]))


def hinge_forces(
    cw: FloatArray, y: FloatArray, m: int, lossy: bool
) -> tuple[FloatArray, FloatArray]:
    """The mass matrix in deployed angles and the forces on them at state y, without
    friction: ``(M_phi, F)`` (module notes); with ``lossy`` each lossy gear's factor m
    on its damper side's torque and inertia (else the ideal gears: the kinetic energy,
    the latches' impulses)."""
    n = int(cw[W.W_N])
    phi, rate = hinge_angles(cw, y, m)
    q, dq = relative(cw, phi, rate)
    mass = _panels(cw, W.H_MASS, n)
    cga = _panels(cw, W.H_CGA, n)
    cgb = _panels(cw, W.H_CGB, n)
    length = _panels(cw, W.H_LENGTH, n)
    matrix = mass_matrix(q, mass, cga, cgb, _panels(cw, W.H_INERTIA, n), length)
    velocity = velocity_terms(q, dq, mass, cga, cgb, length)
    forces = np.empty(n)
    for j in range(n):
        s = cw[hinge_at(W.H_SIGN, j)]
        mesh = mesh_of(cw, j) if lossy else 1.0
        forces[j] = (
            drive_torque(cw, j, phi[j])
            - mesh * damper_torque(cw, j, rate[j], y)[0]
            - latch_torque(cw, j, phi[j], rate[j])
            - s * velocity[j]
        )
        for k in range(n):
            matrix[j, k] *= s * cw[hinge_at(W.H_SIGN, k)]
        matrix[j, j] += mesh * cw[hinge_at(W.H_MESHED, j)] * cw[hinge_at(W.H_JD, j)]
    if cw[W.W_GX] != 0.0 or cw[W.W_GY] != 0.0:
        weight = gravity_forces(
            q, mass, cga, cgb, length, _panels(cw, W.H_OFFLOAD, n), cw[W.W_GX], cw[W.W_GY]
        )
        for j in range(n):
            forces[j] += cw[hinge_at(W.H_SIGN, j)] * weight[j]
    for c in range(int(cw[W.W_C])):
        torque = cable_torque(
            cable_deflection(cw, c, phi), cw[cable_at(W.C_K, c)], cw[cable_at(W.C_SLACK, c)]
        )
        inboard = int(cw[cable_at(W.C_IN, c)])
        forces[inboard + 1] += torque
        forces[inboard] -= cw[cable_at(W.C_RATIO, c)] * torque
    return matrix, forces


def group_system(
    cw: FloatArray, y: FloatArray, m: int, lossy: bool
) -> tuple[FloatArray, FloatArray]:
    """``M_psi`` and ``Q_psi`` (with the sliding groups' kinetic friction) at state y;
    ``lossy`` as :func:`hinge_forces`."""
    n = int(cw[W.W_N])
    matrix, forces = hinge_forces(cw, y, m, lossy)
    mass = np.zeros((m, m))
    rhs = np.zeros(m)
    for j in range(n):
        gj = int(cw[hinge_at(W.H_GROUP, j)])
        fj = cw[hinge_at(W.H_FACTOR, j)]
        rhs[gj] += fj * forces[j]
        for k in range(n):
            gk = int(cw[hinge_at(W.H_GROUP, k)])
            mass[gj, gk] += fj * cw[hinge_at(W.H_FACTOR, k)] * matrix[j, k]
    for g in range(m):
        rhs[g] -= cw[group_at(W.G_DIR, g)] * cw[group_at(W.G_FRICTION, g)]
    for j in range(n):  # the Stribeck excesses and the mesh factors of sliding hinges
        g = int(cw[hinge_at(W.H_GROUP, j)])
        direction = cw[group_at(W.G_DIR, g)]
        factor = cw[hinge_at(W.H_FACTOR, j)]
        if direction != 0.0 and cw[hinge_at(W.H_EXCESS, j)] > 0.0:
            rhs[g] -= direction * factor * stribeck_part(cw, j, factor * y[m + g])
        if lossy and direction != 0.0 and cw[hinge_at(W.H_FLOW, j)] != 0.0:
            rhs[g] -= direction * factor * mesh_friction(cw, j)
    return mass, rhs


def mesh_friction(cw: FloatArray, j: int) -> float:
    """Hinge j's friction in its lossy gear's power flow less its kinetic friction
    ``FECD_T + FS_T`` (which holds FT N / eta_f): ``(m - 1 / eta_f) FT N`` [N*m]."""
    value: float = (mesh_of(cw, j) - 1.0 / cw[hinge_at(W.H_ETAF, j)]) * cw[hinge_at(W.H_FQ, j)]
    return value


def ideal_friction(cw: FloatArray, j: int) -> float:
    """Hinge j's kinetic friction through an ideal gear, ``FS_T + FT N`` [N*m] (the
    mesh's share, ``(m - 1) FT N``, is its gear loss)."""
    value: float = cw[hinge_at(W.H_FRICTION, j)] - cw[hinge_at(W.H_MESHED, j)] * cw[
        hinge_at(W.H_FQ, j)
    ] * (1.0 / cw[hinge_at(W.H_ETAF, j)] - 1.0)
    return value


def mesh_torque(cw: FloatArray, j: int, y: FloatArray, acc: FloatArray, m: int) -> float:
    """The torque hinge j's damper side takes through its gear along the motion, as an
    ideal gear passes it: ``d (D + J_D phi'') + FT N`` [N*m] (its damping, its rotor's
    inertia at the accelerations ``acc``, its friction; d the direction of motion). Its
    sign is the power flow's (> 0: the load drives the damper); it is continuous in the
    state, and at its zero the flow does not change the motion (the mesh factor m
    multiplies it): the wing's form of
    :func:`ecdsim.physics.gearing.power_flow_indicator`, whose ``J_L D + J_D A`` is it
    times ``J_L + m J_D`` on a single hinge."""
    g = int(cw[hinge_at(W.H_GROUP, j)])
    direction = cw[group_at(W.G_DIR, g)]
    factor = cw[hinge_at(W.H_FACTOR, j)]
    rate = factor * y[m + g]
    torque = damper_torque(cw, j, rate, y)[0] + cw[hinge_at(W.H_JD, j)] * factor * acc[g]
    value: float = direction * torque + cw[hinge_at(W.H_FQ, j)]
    return value


def lossy_gear(cw: FloatArray, j: int) -> bool:
    """Hinge j has a lossy gear (an efficiency below 1 either way)."""
    return bool(cw[hinge_at(W.H_ETAF, j)] != 1.0 or cw[hinge_at(W.H_ETAB, j)] != 1.0)


def decide_flows(cw: FloatArray, y: FloatArray, m: int) -> None:
    """Each lossy gear's power flow for the segment about to start: 0 at rest; else
    :func:`ecdsim.physics.gearing.power_flow_mode` of its mesh torque under the flows
    so far (or the flow a power_flow event switched it to), repeated until no flow
    changes (one pass with one lossy hinge: its torque's sign does not depend on its
    own flow), at most once per hinge and once more."""
    n = int(cw[W.W_N])
    acc = np.empty(m)
    holding = np.empty(m)
    flowing = 0
    for j in range(n):
        g = int(cw[hinge_at(W.H_GROUP, j)])
        meshed = cw[hinge_at(W.H_MESHED, j)] != 0.0
        if not lossy_gear(cw, j) or not meshed or cw[group_at(W.G_DIR, g)] == 0.0:
            cw[hinge_at(W.H_FLOW, j)] = 0.0
            cw[hinge_at(W.H_HINT, j)] = 0.0
            continue
        flowing += 1
        if cw[hinge_at(W.H_FLOW, j)] == 0.0:
            cw[hinge_at(W.H_FLOW, j)] = 1.0  # from rest the load drives the damper
    for _ in range(n + 1 if flowing > 0 else 0):
        accelerations(cw, y, acc, holding, m)
        changed = False
        for j in range(n):
            flow = int(cw[hinge_at(W.H_FLOW, j)])
            if flow == 0:
                continue
            hint = int(cw[hinge_at(W.H_HINT, j)])
            wanted = power_flow_mode(mesh_torque(cw, j, y, acc, m), hint)
            if wanted != flow:
                cw[hinge_at(W.H_FLOW, j)] = wanted
                changed = True
        if not changed:
            break
    for j in range(n):
        cw[hinge_at(W.H_HINT, j)] = 0.0


def stribeck_part(cw: FloatArray, j: int, rate: float) -> float:
    """Hinge j's sliding friction above its kinetic one at its speed ``rate``: the
    single hinge's Stribeck curve :func:`ecdsim.physics.friction.stribeck_curve` of its
    excess ``F_brk - F_C`` at its ECD's Stribeck speed (docs/dynamics.md, "Stribeck
    friction"); 0 without one."""
    excess = cw[hinge_at(W.H_EXCESS, j)]
    if excess <= 0.0:
        return 0.0
    return float(stribeck_curve(rate, excess, cw[hinge_at(W.H_WST, j)]))


def solve_on(matrix: FloatArray, rhs: FloatArray, index: NDArray[np.int64]) -> FloatArray:
    """``x`` of ``matrix[index][:, index] x = rhs[index]``: a system restricted to some
    groups (the moving ones, the held ones, the unlocked ones), solved by the kernel's
    :func:`~ecdsim.dynamics.kernel.friction.solve_small`; ``x[r]`` belongs to group
    ``index[r]``."""
    count = index.shape[0]
    system = np.empty((count, count + 1))
    for r in range(count):
        for c in range(count):
            system[r, c] = matrix[index[r], index[c]]
        system[r, count] = rhs[index[r]]
    solution = np.empty(count)
    solve_small(system, solution, count)
    return solution


def accelerations(
    cw: FloatArray, y: FloatArray, acc: FloatArray, holding: FloatArray, m: int
) -> None:
    """The groups' accelerations (held ones 0) and the held groups' holding torques
    (``(M a)_g - Q_g``, what their friction or latch supplies; 0 for sliding ones)."""
    mass, rhs = group_system(cw, y, m, True)
    free = 0
    for g in range(m):
        if cw[group_at(W.G_DIR, g)] != 0.0:
            free += 1
    index = np.empty(free, dtype=np.int64)
    i = 0
    for g in range(m):
        acc[g] = 0.0
        if cw[group_at(W.G_DIR, g)] != 0.0:
            index[i] = g
            i += 1
    if free > 0:
        solution = solve_on(mass, rhs, index)
        for r in range(free):
            acc[index[r]] = solution[r]
    scale = 0.0
    for g in range(m):
        scale = max(scale, abs(rhs[g]))
    for g in range(m):
        holding[g] = 0.0
        if cw[group_at(W.G_DIR, g)] == 0.0:
            value = -rhs[g]
            for k in range(m):
                value += mass[g, k] * acc[k]
            holding[g] = value if abs(value) > ROUNDING * scale else 0.0


def heating_rates(cw: FloatArray, j: int, y: FloatArray, dy: FloatArray, power: float) -> None:
    """Hinge j's heating states' rates (the single hinge's ``aux_rates`` on the wing's
    words): the damper's log state, Incropera Eq. 5.2 in the log form of
    :mod:`ecdsim.physics.thermal`, and with two nodes the heat its housing returns and
    the housing's own rise (:func:`~ecdsim.physics.thermal.housing_return`,
    :func:`~ecdsim.physics.thermal.housing_rate`)."""
    aux = int(cw[hinge_at(W.H_AUX, j)])
    capacity = cw[hinge_at(W.H_HC, j)]
    resistance = cw[hinge_at(W.H_HR, j)]
    coefficient = cw[hinge_at(W.H_COEF, j)]
    s = y[aux]
    rate = float(factor_log_heating(power, capacity))
    if resistance < math.inf:  # the cooling term; 0 (and skipped) where adiabatic
        rate -= float(factor_log_cooling(s, capacity, resistance, coefficient))
    housing = int(cw[hinge_at(W.H_HOUSING, j)])
    if housing >= 0:
        ambient = cw[hinge_at(W.H_FA, j)]
        factor = float(damping_factor_from_log(s, ambient, coefficient))
        h = y[housing]
        rate += float(housing_return(h, factor, resistance, capacity))
        rise = float(temperature_from_factor_log(s, 0.0, ambient, coefficient))
        dy[housing] = float(
            housing_rate(rise, h, cw[hinge_at(W.H_HCH, j)], resistance, cw[hinge_at(W.H_HRHE, j)])
        )
    dy[aux] = rate


def chain_derivatives(
    cw: FloatArray, y: FloatArray, dy: FloatArray, dm: tuple[int, ...], da: tuple[int, ...],
    dq: tuple[int, ...],
) -> None:  # fmt: skip
    """``dy/dt`` of the wing at state y: ``[psi', psi'', heating, dissipated powers]``
    (each hinge's damper, friction through an ideal gear, latch damper, gear mesh)."""
    m = len(dm)
    n = int(cw[W.W_N])
    acc = np.empty(m)
    holding = np.empty(m)
    accelerations(cw, y, acc, holding, m)
    for g in range(m):
        moving = cw[group_at(W.G_DIR, g)] != 0.0
        dy[g] = y[m + g] if moving else 0.0
        dy[m + g] = acc[g]
    e = 2 * m + len(da)
    for j in range(n):
        g = int(cw[hinge_at(W.H_GROUP, j)])
        rate = cw[hinge_at(W.H_FACTOR, j)] * y[m + g]
        torque, power = damper_torque(cw, j, rate, y)
        dy[e + j] = torque * rate
        if int(cw[hinge_at(W.H_AUX, j)]) >= 0:
            heating_rates(cw, j, y, dy, power)
        sliding = ideal_friction(cw, j) + stribeck_part(cw, j, rate)
        dy[e + n + j] = cw[group_at(W.G_DIR, g)] * sliding * rate
        latch = cw[hinge_at(W.H_ENGAGED, j)] * cw[hinge_at(W.H_LATCH_C, j)]
        dy[e + 2 * n + j] = latch * rate * rate
        dy[e + 3 * n + j] = 0.0
        if cw[hinge_at(W.H_FLOW, j)] != 0.0:  # (m - 1) times the mesh's power, >= 0
            own = mesh_torque(cw, j, y, acc, m) * abs(rate)
            dy[e + 3 * n + j] = (mesh_of(cw, j) - 1.0) * own


def chain_jacobian(
    cw: FloatArray, y: FloatArray, jac: FloatArray, dm: tuple[int, ...], da: tuple[int, ...],
    dq: tuple[int, ...],
) -> None:  # fmt: skip
    """``d(dy/dt)/dy`` by forward differences over the coordinates and speeds (the
    quadratures' columns are zero; the coordinates' rows ``q' = v`` the stepper knows)."""
    m = len(dm)
    size = 2 * m + len(da) + len(dq)
    base = np.empty(size)
    moved = np.empty(size)
    chain_derivatives(cw, y, base, dm, da, dq)
    trial = y.copy()
    for c in range(size):
        for r in range(m, size):
            jac[r, c] = 0.0
    for c in range(2 * m + len(da)):
        step = FD_RELATIVE * max(abs(y[c]), FD_FLOOR)
        trial[c] = y[c] + step
        step = trial[c] - y[c]
        chain_derivatives(cw, trial, moved, dm, da, dq)
        trial[c] = y[c]
        for r in range(m, size):
            jac[r, c] = (moved[r] - base[r]) / step


def kinetic(cw: FloatArray, y: FloatArray, m: int) -> float:
    """The wing's kinetic energy ``psi'^T M_psi psi' / 2`` [J] (the rotors' included,
    through ideal gears: a lossy gear's factor is a loss, not an inertia)."""
    mass, _ = group_system(cw, y, m, False)
    total = 0.0
    for g in range(m):
        for k in range(m):
            total += 0.5 * y[m + g] * mass[g, k] * y[m + k]
    return total


def holding_margin(cw: FloatArray, g: int, holding: float, psi: float) -> float:
    """How far stuck group g's holding torque is from its breakaway (> 0 holds); on its
    stowed stop the stop holds any push back."""
    limit = cw[group_at(W.G_BREAKAWAY, g)] * (1.0 + 1e-12)
    if psi == 0.0:
        value: float = holding + limit
        return value
    margin: float = limit - abs(holding)
    return margin


def chain_event_value(
    cw: FloatArray, slot: int, y: FloatArray, scratch: FloatArray, column: FloatArray, m: int,
    na: int,
) -> float:  # fmt: skip
    """Event ``slot``'s function at state y: > 0 inside the segment's mode, 0 at the event
    (slots: :mod:`ecdsim.wing.kernel.layout`)."""
    if slot < W.NMAX:
        g = slot
        direction = cw[group_at(W.G_DIR, g)]
        if direction != 0.0:
            speed: float = direction * y[m + g]
            return speed
        acc = np.empty(m)
        holding = np.empty(m)
        accelerations(cw, y, acc, holding, m)
        return holding_margin(cw, g, holding[g], y[g])
    if slot < 2 * W.NMAX:
        g = slot - W.NMAX
        if cw[group_at(W.G_DIR, g)] > 0.0:
            ahead: float = cw[group_at(W.G_TRAVEL, g)] - y[g]
            return ahead
        behind: float = y[g]
        return behind
    if slot >= W.GAP_SLOTS:  # the lost motion ahead: gap - phi
        j = slot - W.GAP_SLOTS
        g = int(cw[hinge_at(W.H_GROUP, j)])
        gap: float = cw[hinge_at(W.H_GAP, j)] - cw[hinge_at(W.H_FACTOR, j)] * y[g]
        return gap
    if slot >= W.FLOW_SLOTS:
        return flow_value(cw, slot - W.FLOW_SLOTS, y, m)
    c = (slot - 2 * W.NMAX) // 2
    phi, _ = hinge_angles(cw, y, m)
    limit = cw[cable_at(W.C_SLACK, c)] / cw[cable_at(W.C_K, c)]
    delta = cable_deflection(cw, c, phi)
    if (slot - 2 * W.NMAX) % 2 == 0:
        value: float = cw[cable_at(W.C_SIDE_A, c)] * (delta - limit)
        return value
    other: float = cw[cable_at(W.C_SIDE_B, c)] * (delta + limit)
    return other


def flow_value(cw: FloatArray, j: int, y: FloatArray, m: int) -> float:
    """Hinge j's power_flow event: its mesh torque times its flow (> 0 while the flow is
    the segment's; :func:`mesh_torque`)."""
    acc = np.empty(m)
    holding = np.empty(m)
    accelerations(cw, y, acc, holding, m)
    value: float = cw[hinge_at(W.H_FLOW, j)] * mesh_torque(cw, j, y, acc, m)
    return value


def active_slots(cw: FloatArray, y: FloatArray, active: FloatArray, m: int) -> None:
    """The slots a segment arms: each unlocked group's motion; each sliding group's latch
    ahead (a rigid latch, or a compliant one not yet engaged) or stowed stop behind; both
    slack points of each elastic cable, oriented to the side the cable starts on; each
    lossy gear's power flow while its hinge moves; each lost motion ahead of a hinge
    moving forward in it."""
    for slot in range(W.SLOTS):
        active[slot] = 0.0
    for j in range(int(cw[W.W_N])):
        if cw[hinge_at(W.H_FLOW, j)] != 0.0:
            active[W.FLOW_SLOTS + j] = 1.0
        forward = cw[group_at(W.G_DIR, int(cw[hinge_at(W.H_GROUP, j)]))] > 0.0
        if cw[hinge_at(W.H_MESHED, j)] == 0.0 and forward:
            active[W.GAP_SLOTS + j] = 1.0
    for g in range(m):
        direction = cw[group_at(W.G_DIR, g)]
        if cw[group_at(W.G_LOCKED, g)] == 0.0:
            active[g] = 1.0
        first = int(cw[group_at(W.G_FIRST, g)])
        engaged = cw[hinge_at(W.H_ENGAGED, first)] != 0.0
        if direction > 0.0 and not engaged or direction < 0.0:
            active[W.NMAX + g] = 1.0
    phi, rate = hinge_angles(cw, y, m)
    for c in range(int(cw[W.W_C])):
        limit = cw[cable_at(W.C_SLACK, c)] / cw[cable_at(W.C_K, c)]
        delta = cable_deflection(cw, c, phi)
        inboard = int(cw[cable_at(W.C_IN, c)])
        moving = rate[inboard + 1] - cw[cable_at(W.C_RATIO, c)] * rate[inboard]
        cw[cable_at(W.C_SIDE_A, c)] = _side(delta - limit, moving)
        cw[cable_at(W.C_SIDE_B, c)] = _side(delta + limit, moving)
        active[2 * W.NMAX + 2 * c] = 1.0
        active[2 * W.NMAX + 2 * c + 1] = 1.0


def _side(value: float, moving: float) -> float:
    """The orientation that makes an event function positive where it starts: its sign,
    or at a crossing just taken (|value| at rounding) the way it moves."""
    if abs(value) > 1e-12:
        return 1.0 if value > 0.0 else -1.0
    return 1.0 if moving >= 0.0 else -1.0
