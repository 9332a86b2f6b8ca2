"""A segment's constants: the spring piece, the event ahead, the frictions, the gear.

Between two events every term of the equations is smooth: the load is on one spring
piece, each friction element slides one way or is stuck, the lost motion is open or
closed, a lossy gear's power flows one way. :func:`start_segment` fixes these for the
segment about to start (in ``sg``, the segment's float array, and the case's modes) and
the load's first geometric event ahead: a spring breakpoint, the lost motion closing,
the end of travel, the start stop.
"""

from __future__ import annotations

import math

from ecdsim._types import FloatArray
from ecdsim.dynamics.kernel import layout as L
from ecdsim.dynamics.kernel.effects import registered_torque
from ecdsim.dynamics.kernel.friction import projected_inverse, stuck_flags
from ecdsim.physics.eddy import damper_side_torque
from ecdsim.physics.gearing import mesh_factor, power_flow_indicator, power_flow_mode

Tables = tuple[
    FloatArray, FloatArray, FloatArray
]  # a case's spring: angles, net torque, resistance
# Speed, relative to its scale, taken as "at rest" while approaching rest asymptotically.
CREEP_FRACTION = 1e-9


def piece_walk(angles: FloatArray, phi: float, forward: bool, start: int) -> int:
    """The spring piece the motion is about to run along, walked from ``start``.

    Moving forward from a breakpoint, the piece above it; backward, the piece below. A
    motion is continuous, so it moves by one piece per event: a deployment over P
    breakpoints costs O(P), not O(P^2).
    """
    last = angles.shape[0] - 2
    i = start
    while last > 0:
        up = i < last and (angles[i + 1] <= phi if forward else angles[i + 1] < phi)
        down = i > 0 and (angles[i] > phi if forward else angles[i] >= phi)
        if up:
            i += 1
        elif down:
            i -= 1
        else:
            break
    return i


def first_piece(angles: FloatArray, phi: float) -> int:
    """The piece at the release angle (interior breakpoints at or below it)."""
    count = 0
    for i in range(1, angles.shape[0] - 1):
        if angles[i] <= phi:
            count += 1
    return count


def _slope(angles: FloatArray, values: FloatArray, piece: int) -> float:
    """dT/dphi of a table on a piece (0 on a piece of no width)."""
    width = angles[piece + 1] - angles[piece]
    if width > 0.0:
        slope: float = (values[piece + 1] - values[piece]) / width
        return slope
    return 0.0


def _spring_piece(cw: FloatArray, tables: Tables, phi: float, sigma: int) -> None:
    """The net spring's and the resistive table's torque and slope at phi (``sg``)."""
    md = sg = cw
    angles, torques, resist = tables[0], tables[1], tables[2]
    piece = piece_walk(angles, phi, sigma >= 0, int(md[L.MD_PIECE]))
    md[L.MD_PIECE] = piece
    a0 = angles[piece]
    slope = _slope(angles, torques, piece)
    sg[L.SG_PHI] = phi
    sg[L.SG_T0] = torques[piece] + slope * (phi - a0)
    sg[L.SG_SLOPE] = slope
    r_slope = _slope(angles, resist, piece)
    sg[L.SG_R0] = resist[piece] + r_slope * (phi - a0)
    sg[L.SG_RSLOPE] = r_slope


def _target(cw: FloatArray, tables: Tables, phi: float, sigma: int, m: int) -> None:
    """The load's first geometric event ahead, from phi, and its kind (``sg``)."""
    par = md = sg = cw
    angles = tables[0]
    piece = int(md[L.MD_PIECE])
    if sigma > 0:
        upper = angles[piece + 1]
        length = upper - phi
        reach = L.EV_ARRIVE if upper >= par[L.TRAVEL] else L.EV_BREAKPOINT
        if m == 1 and md[L.MD_ENGAGED] == 0:
            gap = par[L.PHI0] + par[L.GAP] - phi  # the lost motion closes at release + b
            if gap <= length:
                length = gap
                reach = L.EV_ENGAGE
        sg[L.SG_TARGET] = max(length, 0.0)
    else:
        lower = angles[piece]
        reach = L.EV_START_STOP if lower <= 0.0 else L.EV_BREAKPOINT
        sg[L.SG_TARGET] = -max(phi - lower, 0.0)
    sg[L.SG_REACH] = reach


def _frictions(cw: FloatArray, m: int) -> None:
    """Kinetic friction and Stribeck excess (breakaway less kinetic, where a Stribeck
    speed is given) of each element in the segment, with a lossy gear's mesh factor."""
    par = md = sg = cw
    stribeck = math.isfinite(par[L.WST])
    if m == 1:
        eng = float(md[L.MD_ENGAGED])
        sg[L.SG_FC0] = par[L.FS] + eng * sg[L.SG_MESH] * par[L.FE] * par[L.ETAF]
        excess = eng * (par[L.FEB] - par[L.FE]) + (par[L.FSB] - par[L.FS])
        sg[L.SG_EX0] = max(excess, 0.0) if stribeck else 0.0
        return
    sg[L.SG_FC0] = par[L.FS]
    sg[L.SG_EX0] = max(par[L.FSB] - par[L.FS], 0.0) if stribeck else 0.0
    sg[L.SG_FC1] = par[L.FE]
    sg[L.SG_EX1] = max(par[L.FEB] - par[L.FE], 0.0) if stribeck else 0.0


def flow_indicator(cw: FloatArray, x: float, speed: float, factor: float, sigma: int) -> float:
    """A lossy gear's power-flow indicator ``J_L (M_d + F_q) + J_D A`` along the motion
    (:func:`ecdsim.physics.gearing.power_flow_indicator`; > 0 forward) at displacement x
    from the segment's start, load speed and law factor: the segment's choice of flow
    and the power_flow event's value (:func:`ecdsim.dynamics.kernel.events.indicator`)."""
    par = sg = cw
    torque = damper_side_torque(
        int(par[L.LAW]), par[L.LA], par[L.LB], par[L.LC], par[L.RATIO], par[L.BG],
        sigma * speed + 0.0, factor,
    )[0]  # fmt: skip
    spring = sg[L.SG_T0] + sg[L.SG_SLOPE] * x + registered_torque(cw, sg[L.SG_PHI] + x, speed)[0]
    load = sigma * spring - par[L.FS]
    return float(power_flow_indicator(par[L.JL], par[L.JD], torque + sg[L.SG_FQ], load))


def _flow(cw: FloatArray, y: FloatArray, factor: float, sigma: int) -> None:
    """A lossy gear's power flow for the segment and its mesh factor m (``sg``): the
    sign of the mesh torque's indicator at the start (:mod:`ecdsim.physics.gearing`),
    or the flow a power_flow event has just switched to. An ideal gear, or the free
    play of the lost motion, has m = 1 and no flow."""
    par = md = sg = cw
    sg[L.SG_MESH] = 1.0
    sg[L.SG_FQ] = par[L.FE] * par[L.ETAF]
    hint = int(md[L.MD_HINT])
    md[L.MD_HINT] = 0
    md[L.MD_FLOW] = 0
    if md[L.MD_ENGAGED] == 0 or (par[L.ETAF] == 1.0 and par[L.ETAB] == 1.0):
        return
    indicator = flow_indicator(cw, 0.0, y[1], factor, sigma)
    flow = power_flow_mode(indicator, hint)
    md[L.MD_FLOW] = flow
    sg[L.SG_MESH] = mesh_factor(flow, par[L.ETAF], par[L.ETAB])


def start_segment(
    cw: FloatArray, tables: Tables, y: FloatArray, phi: float, factor: float,
    scratch: FloatArray, column: FloatArray, m: int,
) -> None:  # fmt: skip
    """Fix the segment's constants (``sg``), its spring piece and its gear's power flow,
    for the load at angle phi with the speeds of y, in the case's friction modes."""
    par = md = sg = cw
    for i in range(L.MD_END, L.SG_END):
        sg[i] = 0.0
    sigma = int(md[L.MD_SLIDE0])
    sg[L.SG_ENG] = float(md[L.MD_ENGAGED]) if m == 1 else 1.0
    _spring_piece(cw, tables, phi, sigma)
    sg[L.SG_REACH] = -1.0
    if sigma != 0:
        _target(cw, tables, phi, sigma, m)
    sg[L.SG_MESH] = 1.0
    if m == 1:
        _flow(cw, y, factor, sigma)
    _frictions(cw, m)
    stuck_flags(cw, scratch, m)
    projected_inverse(cw, scratch, column, m)
    sg[L.SG_DRIVE] = sigma * sg[L.SG_T0] - sg[L.SG_FC0]
    sg[L.SG_LOAD] = sigma * sg[L.SG_T0] - par[L.FS]


def rigid_scales(
    cw: FloatArray, y: FloatArray, rtol: float, atol: FloatArray, na: int
) -> tuple[float, float]:
    """A rigid hinge's segment: the integrator's absolute tolerances (``atol``: the
    displacement on the segment's length, the speed finely enough to resolve the creep
    threshold, the log state in kelvin, the dissipation on the energy moved), its first
    step and the creep speed (1e-9 of the speed scale)."""
    par = sg = cw
    drive = abs(sg[L.SG_DRIVE])
    speed0 = abs(y[1])
    damping0 = max(par[L.BLIN], 1e-300)
    inertia = par[L.JL] + sg[L.SG_ENG] * sg[L.SG_MESH] * par[L.JD]
    speed = max(max(speed0, drive / damping0), 1e-300)
    length = max(abs(sg[L.SG_TARGET]), 1e-9)
    energy = max(max(drive * abs(sg[L.SG_TARGET]), 0.5 * inertia * speed0 * speed0), 1e-300)
    atol[0] = rtol * 1e-3 * length
    atol[1] = min(rtol * 1e-3, 1e-12) * speed
    for i in range(na):
        atol[2 + i] = rtol * 1e-3
    atol[2 + na] = rtol * 1e-3 * energy
    sg[L.SG_CREEP] = CREEP_FRACTION * speed
    return 1e-3 * min(inertia / damping0, length / speed), speed


def compliant_scales(
    cw: FloatArray, tables: Tables, rtol: float, atol: FloatArray, na: int
) -> tuple[float, float]:
    """A compliant mesh's tolerances, for the whole run: speeds scale as the quasi-static
    speed drive / B, the free one sqrt(drive travel / J) or the initial speed; the mesh's
    deflection as drive / c. Returns the first step and the speed scale."""
    par = cw
    torques = tables[1]
    drive = 0.0
    for i in range(torques.shape[0]):
        drive = max(drive, abs(torques[i]))
    total = par[L.JL] + par[L.JD]
    rate = par[L.BLIN]
    speed = max(
        max(abs(par[L.W0]), drive / rate if rate > 0.0 else 0.0),
        max(math.sqrt(drive * par[L.TRAVEL] / total), 1e-300),
    )
    energy = max(speed * speed * par[L.JL], 1e-300)
    fine = rtol * 1e-3
    atol[0] = fine * par[L.TRAVEL]
    atol[1] = fine * max(min(par[L.TRAVEL], max(drive, 1e-300) / par[L.MC]), 1e-300)
    atol[2] = min(fine, 1e-12) * speed
    atol[3] = min(fine, 1e-12) * speed
    for i in range(na):
        atol[4 + i] = fine
    atol[4 + na] = fine * energy
    # The mesh's dissipation on what one contact can take, the relative motion's energy
    # J_L J_D / (J_L + J_D) speed^2 / 2: a small term of the balance, compared on its own
    # (validation, compliant backlash).
    atol[5 + na] = fine * 0.5 * (par[L.JL] * par[L.JD] / total) * speed * speed
    contact = math.sqrt(par[L.JL] * par[L.JD] / (total * par[L.MC]))
    return 1e-3 * min(par[L.TRAVEL] / speed, contact), speed


def at_rest(cw: FloatArray, tables: Tables, phi: float, m: int) -> None:
    """The segment constants that the friction machine reads at rest at phi: the spring
    piece ahead (forward), the engagement, an ideal mesh factor."""
    md = sg = cw
    _spring_piece(cw, tables, phi, 1)
    sg[L.SG_ENG] = float(md[L.MD_ENGAGED]) if m == 1 else 1.0
    sg[L.SG_MESH] = 1.0
