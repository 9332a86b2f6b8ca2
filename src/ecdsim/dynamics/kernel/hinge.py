"""The hinge's equations of motion from its components, with their Jacobian.

A hinge is the load (spring, resistive table, a ground test's gravity, the system
friction, the stops) and the damper side (the ECD's eddy law and heating, its friction,
the gear train's inertia) joined by the gear mesh. Each effect is a law of
:mod:`ecdsim.physics` (written once, compiled from the same source); this module only
adds them up, in the generalised coordinates of the mesh:

* a **rigid mesh** (m = 1): one coordinate, the load angle phi; the damper side turns
  with it (once the lost motion has closed), its inertia, damping and friction seen
  through the gear's mesh factor (1, or a lossy gear's 1/eta_f forward and eta_b
  back-driven: :mod:`ecdsim.physics.gearing`);
* a **compliant mesh** (m = 2): coordinates ``q = (phi_L, delta)`` with the mesh's
  relative angle ``delta = phi_L - phi_D`` a coordinate of its own, so that the mesh's
  deflection (of order T / c, small for a stiff mesh) keeps its own accuracy. The bodies'
  inertias give the mass matrix ``M = J_L g_L^T g_L + J_D g_D^T g_D`` with the body
  directions ``g_L = (1, 0)`` and ``g_D = (1, -1)``, and each body's force enters the
  generalised forces as ``g^T F``.

The accelerations are ``P_S Q``: ``P_S = Z (Z^T M Z)^-1 Z^T`` is the mass matrix's
inverse on the motions the stuck friction elements allow (``Z`` spans them; for one
body ``1 / J``, or 0 when it is stuck: :mod:`ecdsim.dynamics.kernel.friction`). The state
is ``[q, v, z, e]`` (:mod:`ecdsim.dynamics.kernel.rodas`): ``z`` the damper's log
temperature state (and the housing's rise with two nodes), ``e`` the damper's dissipation
(and the mesh's with a compliant mesh).
"""

from __future__ import annotations

import math

from ecdsim._types import FloatArray
from ecdsim.dynamics.kernel import layout as L
from ecdsim.dynamics.kernel.effects import registered_terms, registered_torque
from ecdsim.physics.eddy import damper_side_parts, damper_side_torque
from ecdsim.physics.friction import stribeck_excess
from ecdsim.physics.mechanics import mesh_torque
from ecdsim.physics.thermal import (
    damping_factor_from_log,
    factor_log_cooling,
    factor_log_cooling_slope,
    factor_log_heating,
    factor_log_heating_slope,
    housing_rate,
    housing_return,
    temperature_from_factor_log,
)


def load_spring(sg: FloatArray, x: float) -> float:
    """The spring's net torque on its current piece, x from the segment's start [N*m]
    (Eq. 7, or the table's linear interpolation, less the resistive table)."""
    value: float = sg[L.SG_T0] + sg[L.SG_SLOPE] * x
    return value


def factor_at(par: FloatArray, y: FloatArray, m: int, na: int) -> float:
    """The damping law's temperature factor f: from the log state s with heating, else
    the ambient one (Eq. 1's bracket, or the Kloss law's resistivity factor)."""
    if na == 0:
        ambient: float = par[L.FA]
        return ambient
    return float(damping_factor_from_log(y[2 * m], par[L.FA], par[L.COEF]))


def excess_at(speed: float, excess: float, stribeck_speed: float) -> tuple[float, float]:
    """The Stribeck excess of a friction element and its slope at its sliding speed
    (:func:`ecdsim.physics.friction.stribeck_excess`); 0 without one, without its exp."""
    if excess > 0.0:
        g, slope = stribeck_excess(speed, excess, stribeck_speed)
        return float(g), float(slope)
    return 0.0, 0.0


def mesh_now(par: FloatArray, md: FloatArray, delta: float, speed: float) -> float:
    """The compliant mesh's torque in its mode: MSL ElastoBacklash2 while pressing
    (:func:`ecdsim.physics.mechanics.mesh_torque`), 0 in the gap or released."""
    if md[L.MD_MESH] != L.PRESS:
        return 0.0
    return float(mesh_torque(delta, speed, 0.5 * par[L.GAP], par[L.MC], par[L.MD]))


def aux_rates(
    par: FloatArray, y: FloatArray, dy: FloatArray, power: float, f: float, m: int, na: int
) -> None:
    """The heating states' rates: the damper's log state (Incropera Eq. 5.2 in the log
    form of :mod:`ecdsim.physics.thermal`) and the housing's rise with two nodes."""
    s = y[2 * m]
    rate = float(factor_log_heating(power, par[L.HC]))
    if par[L.HR] < math.inf:  # the cooling term; 0 (and skipped) where adiabatic
        rate -= float(factor_log_cooling(s, par[L.HC], par[L.HR], par[L.COEF]))
    if na == 2:
        h = y[2 * m + 1]
        rate += float(housing_return(h, f, par[L.HR], par[L.HC]))
        rise = temperature_from_factor_log(s, 0.0, par[L.FA], par[L.COEF])
        dy[2 * m + 1] = housing_rate(rise, h, par[L.HCH], par[L.HR], par[L.HRHE])
    dy[2 * m] = rate


def hinge_forces(
    cw: FloatArray, y: FloatArray, m: int, na: int
) -> tuple[float, float, float, float, float, float, float]:
    """The generalised forces and what the rates need, at state y in the case's modes.

    Returns ``(Q0, Q1, M_d, p, power, tau, f)``: the generalised forces (Q1 = 0 for one
    coordinate), the damper side's torque at the input and its eddy-current power over
    f, the dissipated power into the damper's account (damping and the Stribeck excesses),
    the compliant mesh's torque (0 for a rigid mesh) and the law's temperature factor.
    """
    par = md = sg = cw
    f = factor_at(par, y, m, na)
    law = int(par[L.LAW])
    phi = y[0]
    w = y[m]
    sigma = md[L.MD_SLIDE0]
    g = excess_at(sigma * w, sg[L.SG_EX0], par[L.WST])[0]
    extra, lost = registered_torque(cw, sg[L.SG_PHI] + phi, w)  # kernel/effects.py
    load = load_spring(sg, phi) - sigma * (sg[L.SG_FC0] + g) + extra
    if m == 1:
        eng = sg[L.SG_ENG]
        torque_, power = damper_side_torque(
            law, par[L.LA], par[L.LB], par[L.LC], par[L.RATIO], par[L.BG], w, f
        )
        torque = eng * float(torque_)
        q0 = load - sg[L.SG_MESH] * torque
        return q0, 0.0, torque, eng * float(power), torque * w + sigma * g * w + lost, 0.0, f
    # A compliant mesh: q = (phi_L, delta), the damper side's speed w_L - delta'.
    speed = y[m + 1]
    wd = w - speed
    sigma_d = md[L.MD_SLIDE1]
    tau = mesh_now(par, md, y[1], speed)
    g_d = excess_at(sigma_d * wd, sg[L.SG_EX1], par[L.WST])[0]
    torque_, power = damper_side_torque(
        law, par[L.LA], par[L.LB], par[L.LC], par[L.RATIO], par[L.BG], wd, f
    )
    torque = float(torque_)
    damper = tau - sigma_d * (sg[L.SG_FC1] + g_d) - torque
    dissipated = torque * wd + sigma * g * w + sigma_d * g_d * wd + lost
    return load - tau + damper, -damper, torque, float(power), dissipated, tau, f


def derivatives(
    cw: FloatArray, y: FloatArray, dy: FloatArray, dm: tuple[int, ...], da: tuple[int, ...],
    dq: tuple[int, ...],
) -> None:  # fmt: skip
    """``dy/dt`` of the hinge at state y (the model of the module notes)."""
    m = len(dm)
    na = len(da)
    par = md = cw
    q0, q1, _, power, dissipated, tau, f = hinge_forces(cw, y, m, na)
    e = 2 * m + na
    if m == 1:
        dy[0] = y[1]
        dy[1] = cw[L.PINV] * q0
    else:
        dy[0] = y[2]
        dy[1] = y[3]
        dy[2] = cw[L.PINV] * q0 + cw[L.PINV + 1] * q1
        dy[3] = cw[L.PINV + 2] * q0 + cw[L.PINV + 3] * q1
        dy[e + 1] = mesh_dissipation(par, md, y[1], y[3], tau)
    if na > 0:
        aux_rates(par, y, dy, power, f, m, na)
    dy[e] = dissipated


def mesh_dissipation(
    par: FloatArray, md: FloatArray, delta: float, speed: float, tau: float
) -> float:
    """The compliant mesh's dissipated power [W]: ``d delta'^2`` while pressing; while
    released, the stored energy ``c (delta -+ b/2)^2 / 2`` it loses as it relaxes at no
    torque (the power into it is 0); 0 in the gap (docs/dynamics.md)."""
    mode = md[L.MD_MESH]
    if mode == L.PRESS:
        if tau != 0.0:
            value: float = par[L.MD] * speed * speed
            return value
        return 0.0
    if mode == L.RELEASED:
        side = md[L.MD_SIDE]
        deflection = delta - side * 0.5 * par[L.GAP]
        if side * deflection > 0.0:
            released: float = -par[L.MC] * deflection * speed
            return released
    return 0.0


def aux_jacobian(
    par: FloatArray, y: FloatArray, jac: FloatArray, power_speed: float, power_factor: float,
    f: float, m: int, na: int,
) -> None:  # fmt: skip
    """The heating rows of the Jacobian. ``power_speed`` is d(power over f)/dw_D; the
    damper side's speed is w (one coordinate) or w_L - delta' (a compliant mesh)."""
    s = y[2 * m]
    c = par[L.COEF]
    row = 2 * m
    jac[row, m] = power_speed / par[L.HC]
    if m == 2:
        jac[row, m + 1] = -power_speed / par[L.HC]
    slope = factor_log_heating_slope(power_factor, f, par[L.HC], c)
    if par[L.HR] < math.inf:
        slope -= factor_log_cooling_slope(s, par[L.HC], par[L.HR], c)
    if na == 2:
        h = y[2 * m + 1]
        slope -= c * housing_return(h, f, par[L.HR], par[L.HC])
        jac[row, row + 1] = housing_return(1.0, f, par[L.HR], par[L.HC])
        coupling = 1.0 / par[L.HR]
        jac[row + 1, row] = f * coupling / par[L.HCH]
        jac[row + 1, row + 1] = -(coupling + 1.0 / par[L.HRHE]) / par[L.HCH]
    jac[row, row] = slope


def jacobian(
    cw: FloatArray, y: FloatArray, jac: FloatArray, dm: tuple[int, ...], da: tuple[int, ...],
    dq: tuple[int, ...],
) -> None:  # fmt: skip
    """``d(dy/dt)/dy`` of :func:`derivatives`: the rows of the speeds, the heating and the
    quadratures (the coordinates' rows are ``q' = v``, which the stepper knows)."""
    m = len(dm)
    na = len(da)
    n = 2 * m + na + len(dq)
    par = md = sg = cw
    for r in range(m, n):
        for c in range(n):
            jac[r, c] = 0.0
    f = factor_at(par, y, m, na)
    c_f = par[L.COEF] * f  # df/ds
    law = int(par[L.LAW])
    e = 2 * m + na
    if m == 1:
        phi = y[0]
        w = y[1]
        sigma = md[L.MD_SLIDE0]
        g, g_slope = excess_at(sigma * w, sg[L.SG_EX0], par[L.WST])
        eng = sg[L.SG_ENG]
        mesh = sg[L.SG_MESH] * eng
        torque, d_speed, d_factor, _, p_speed, p_factor = damper_side_parts(
            law, par[L.LA], par[L.LB], par[L.LC], par[L.RATIO], par[L.BG], w, f
        )
        _, x_angle, x_speed, _, p_angle, p_speed_ = registered_terms(cw, sg[L.SG_PHI] + phi, w)
        stiffness = sg[L.SG_SLOPE] + x_angle
        inv = cw[L.PINV]
        jac[1, 0] = inv * stiffness
        jac[1, 1] = -inv * (g_slope + mesh * d_speed - x_speed)
        if na > 0:
            jac[1, 2] = -inv * mesh * d_factor * c_f
            aux_jacobian(par, y, jac, eng * p_speed, eng * p_factor, f, m, na)
            jac[e, 2] = eng * d_factor * c_f * w
        jac[e, 0] = p_angle
        jac[e, 1] = eng * (d_speed * w + torque) + g_slope * w + sigma * g + p_speed_
        return
    compliant_jacobian(cw, y, jac, f, c_f, law, m, na)


def compliant_jacobian(
    cw: FloatArray, y: FloatArray, jac: FloatArray, f: float, c_f: float, law: int, m: int, na: int
) -> None:
    """The Jacobian rows of a compliant mesh (m = 2; :func:`jacobian`)."""
    par = md = sg = cw
    phi = y[0]
    delta = y[1]
    w = y[2]
    speed = y[3]
    wd = w - speed
    sigma = md[L.MD_SLIDE0]
    sigma_d = md[L.MD_SLIDE1]
    tau = mesh_now(par, md, delta, speed)
    k_mesh = par[L.MC] if tau != 0.0 else 0.0
    d_mesh = par[L.MD] if tau != 0.0 else 0.0
    g, g_slope = excess_at(sigma * w, sg[L.SG_EX0], par[L.WST])
    g_d, gd_slope = excess_at(sigma_d * wd, sg[L.SG_EX1], par[L.WST])
    torque, d_speed, d_factor, _, p_speed, p_factor = damper_side_parts(
        law, par[L.LA], par[L.LB], par[L.LC], par[L.RATIO], par[L.BG], wd, f
    )
    _, x_angle, x_speed, _, p_angle, p_speed_ = registered_terms(cw, sg[L.SG_PHI] + phi, w)
    stiffness = sg[L.SG_SLOPE] + x_angle
    damper_speed = gd_slope + d_speed  # d(damper friction and damping)/d(w_D)
    # d(load force)/d(phi, delta, w, speed) and d(damper force)/d(same), then Q = (L + D, -D).
    load = (stiffness, -k_mesh, x_speed - g_slope, -d_mesh)
    damper = (0.0, k_mesh, -damper_speed, d_mesh + damper_speed)
    for j in range(4):
        q0 = load[j] + damper[j]
        q1 = -damper[j]
        jac[2, j] = cw[L.PINV] * q0 + cw[L.PINV + 1] * q1
        jac[3, j] = cw[L.PINV + 2] * q0 + cw[L.PINV + 3] * q1
    e = 2 * m + na
    if na > 0:
        q0 = -d_factor * c_f
        jac[2, 4] = cw[L.PINV] * q0 - cw[L.PINV + 1] * q0
        jac[3, 4] = cw[L.PINV + 2] * q0 - cw[L.PINV + 3] * q0
        aux_jacobian(par, y, jac, float(p_speed), float(p_factor), f, m, na)
        jac[e, 4] = d_factor * c_f * wd
    power_wd = d_speed * wd + torque + gd_slope * wd + sigma_d * g_d
    jac[e, 0] = p_angle
    jac[e, 2] = power_wd + g_slope * w + sigma * g + p_speed_
    jac[e, 3] = -power_wd
    mode = md[L.MD_MESH]
    if mode == L.PRESS and tau != 0.0:
        jac[e + 1, 3] = 2.0 * par[L.MD] * speed
    elif mode == L.RELEASED:
        side = md[L.MD_SIDE]
        deflection = delta - side * 0.5 * par[L.GAP]
        if side * deflection > 0.0:
            jac[e + 1, 1] = -par[L.MC] * speed
            jac[e + 1, 3] = -par[L.MC] * deflection
