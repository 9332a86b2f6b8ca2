"""A segment's outcome: its energy and extremes booked, its event applied.

Each term of the energy account is computed on its own, so that the balance is a check
(docs/dynamics.md, the energy balance): the spring's work and the resistive table's
exactly on the linear piece from the angles, the Coulomb friction's from each element's
path, the damper's (and the compliant mesh's) dissipation from the integrated
quadratures or the closed form, a lossy gear's mesh loss from the damper side's own
energy (:mod:`ecdsim.physics.gearing`); gravity's from the end angles at the end.
"""

from __future__ import annotations

import math

from ecdsim._types import FloatArray
from ecdsim.dynamics.kernel import layout as L
from ecdsim.dynamics.kernel.friction import drives, stuck_flags
from ecdsim.dynamics.kernel.hinge import mesh_now
from ecdsim.dynamics.kernel.impacts import (
    engage,
    mesh_event,
    resolve_mesh,
    set_load_speed,
    stop_impact,
)
from ecdsim.dynamics.kernel.integrate import track_mesh
from ecdsim.dynamics.kernel.record import Buffers, log_event


def book(
    cw: FloatArray, y: FloatArray, start: FloatArray, slot: int, ex_speed: float, out: FloatArray,
    integrated: bool, m: int, na: int,
) -> float:  # fmt: skip
    """Book the segment's energy terms and the largest forward speed; returns the load's
    displacement (exactly the event's for a geometric one). ``start`` holds the state at
    the segment's start."""
    par = md = sg = cw
    x = sg[L.SG_TARGET] if slot == L.SLOT_REACH else y[0]
    net = sg[L.SG_T0] * x + 0.5 * sg[L.SG_SLOPE] * x * x
    resist = sg[L.SG_R0] * x + 0.5 * sg[L.SG_RSLOPE] * x * x
    out[L.OUT_SPRING_WORK] += net + resist
    out[L.OUT_RESISTIVE_WORK] += resist
    e = 2 * m + na
    out[L.OUT_DAMPER_WORK] += y[e]
    if m == 1:
        ideal = par[L.FS] + sg[L.SG_ENG] * sg[L.SG_FQ]
        out[L.OUT_FRICTION_WORK] += ideal * abs(x)
        if md[L.MD_FLOW] != 0 and integrated:
            kinetic = 0.5 * par[L.JD] * (y[1] * y[1] - start[1] * start[1])
            own = kinetic + y[e] + sg[L.SG_FQ] * abs(x)
            out[L.OUT_GEAR_LOSS] += (sg[L.SG_MESH] - 1.0) * own
    else:
        if md[L.MD_SLIDE0] != 0:
            out[L.OUT_FRICTION_WORK] += par[L.FS] * abs(x)
        if md[L.MD_SLIDE1] != 0:
            out[L.OUT_FRICTION_WORK] += par[L.FE] * abs(x - (y[1] - start[1]))
        out[L.OUT_MESH_WORK] += y[e + 1]
    if md[L.MD_SLIDE0] > 0 and not math.isfinite(out[L.OUT_ARRIVAL_TIME]):
        out[L.OUT_MAX_SPEED] = max(out[L.OUT_MAX_SPEED], ex_speed)
    return float(x)


def _breakaway_direction(
    cw: FloatArray, y: FloatArray, hint: FloatArray, k: int, ws: tuple[FloatArray, ...], m: int,
    na: int,
) -> float:  # fmt: skip
    """The direction a stuck element breaks away in: that of its drive at the event, or
    a little later (the step's end) where the drive there is still about zero (an
    element with next to no friction, loaded from zero)."""
    scratch, column = ws[5], ws[6]
    stuck_flags(cw, scratch, m)
    drives(cw, y, scratch, column, m, na)
    drive = column[m + k]
    static = cw[L.FSB] if k == 0 else cw[L.FEB]
    if abs(drive) <= 0.5 * static or drive == 0.0:
        drives(cw, hint, scratch, column, m, na)
        drive = column[m + k]
    return 1.0 if drive > 0.0 else -1.0


def finish(cw: FloatArray, out: FloatArray, status: int) -> None:
    """End the run with ``status``."""
    cw[L.MD_DONE] = status
    out[L.OUT_STATUS] = status


def _end(
    cw: FloatArray, slot: int, t: float, phi: float, y: FloatArray, out: FloatArray,
    buffers: Buffers, counts: FloatArray, index: int, m: int,
) -> float:  # fmt: skip
    """The slots that end the run: stop time, horizon, creep. Returns the run's time."""
    if slot == L.CAP_SLOT:
        finish(cw, out, L.ST_STOP_TIME)
        log_event(buffers, counts, index, t, L.EV_STOP_TIME, phi, y[m])
        return t
    if slot == L.HORIZON_SLOT:
        finish(cw, out, L.ST_HORIZON)
        log_event(buffers, counts, index, t, L.EV_HORIZON, phi, y[m])
        return t
    md = cw
    if md[L.MD_HELD] != 0:  # the load held at the end, the damper side coming to rest
        y[3] = y[2]
        finish(cw, out, int(md[L.MD_HELD]))
        return t
    finish(cw, out, L.ST_CREEP)
    out[L.OUT_STUCK] = 1.0
    out[L.OUT_STUCK_ANGLE] = phi
    out[L.OUT_STUCK_TIME] = math.inf
    set_load_speed(y, 0.0, m)
    if m == 2:
        y[3] = 0.0
    log_event(buffers, counts, index, math.inf, L.EV_CREEP, phi, 0.0)
    return math.inf


def _reach(
    cw: FloatArray, y: FloatArray, t: float, phi: float, out: FloatArray, buffers: Buffers,
    counts: FloatArray, index: int, m: int,
) -> int:  # fmt: skip
    """The load's geometric event: engagement, a breakpoint (0 returned: not counted
    against the event limit), a stop."""
    sg = cw
    kind = int(sg[L.SG_REACH])
    if kind == L.EV_BREAKPOINT:
        log_event(buffers, counts, index, t, L.EV_BREAKPOINT, phi, y[m])
        return 0
    if kind == L.EV_ENGAGE:
        engage(cw, y, t, phi, out, buffers, counts, index)
        return 1
    before = y[m]
    status = stop_impact(cw, y, t, phi, kind == L.EV_ARRIVE, out, buffers, counts, index, m)
    if status != 0:
        finish(cw, out, status)
    elif m == 2 and y[m] != before:
        resolve_mesh(cw, y, t, phi, buffers, counts, index)
    return 1


def apply_event(
    cw: FloatArray, slot: int, t: float, phi: float, y: FloatArray, hint: FloatArray,
    out: FloatArray, ws: tuple[FloatArray, ...], buffers: Buffers, counts: FloatArray,
    index: int, m: int, na: int,
) -> tuple[int, float]:  # fmt: skip
    """Apply the segment's event at time t (load angle phi, state y); returns (1 if it
    counts against the event limit else 0, the run's time)."""
    md = cw
    counted = 1
    if slot in (L.CAP_SLOT, L.HORIZON_SLOT, L.SLOT_CREEP):
        return counted, _end(cw, slot, t, phi, y, out, buffers, counts, index, m)
    if slot == L.SLOT_REACH:
        counted = _reach(cw, y, t, phi, out, buffers, counts, index, m)
    elif slot == L.SLOT_ZERO0:
        log_event(buffers, counts, index, t, L.EV_ZERO, phi, 0.0)
        set_load_speed(y, 0.0, m)
        md[L.MD_SLIDE0] = 0.0
    elif slot == L.SLOT_ZERO1:
        y[3] = y[2]  # the damper side at rest: delta' = w_L
        md[L.MD_SLIDE1] = 0.0
    elif slot == L.SLOT_BREAK0:
        md[L.MD_SLIDE0] = _breakaway_direction(cw, y, hint, 0, ws, m, na)
        md[L.MD_START] = 0.0
        log_event(buffers, counts, index, t, L.EV_BREAKAWAY, phi, y[m])
    elif slot == L.SLOT_BREAK1:
        md[L.MD_SLIDE1] = _breakaway_direction(cw, y, hint, 1, ws, m, na)
    elif slot in (L.SLOT_MESH_A, L.SLOT_MESH_B):
        mesh_event(cw, y, t, phi, slot == L.SLOT_MESH_A, out, buffers, counts, index)
    elif slot == L.SLOT_SWITCH:
        log_event(buffers, counts, index, t, L.EV_POWER_FLOW, phi, y[m])
        md[L.MD_HINT] = -md[L.MD_FLOW]
    if m == 2:
        track_mesh(cw, out, mesh_now(cw, md, y[1], y[3]))
    return counted, t


def peak_temperature(out: FloatArray, value: float) -> None:
    """Count a damper temperature in the run's highest."""
    out[L.OUT_MAX_TEMPERATURE] = max(out[L.OUT_MAX_TEMPERATURE], value)
