"""The event loop: one case from release to the end of its run, and a batch of cases.

One loop for every hinge model (a rigid mesh of one coordinate, a compliant mesh of
two): each pass resolves the friction elements at rest (the state machine of
:mod:`ecdsim.dynamics.kernel.friction`: stick or break away), starts a segment
(:mod:`ecdsim.dynamics.kernel.segment`), advances it to its first event, in closed form
where the segment is linear (:mod:`ecdsim.dynamics.kernel.closed`) or by RODAS4
(:mod:`ecdsim.dynamics.kernel.integrate`), books its energy and extremes and applies the
event (:mod:`ecdsim.dynamics.kernel.outcome`). A run ends latched or settled at the end
of travel, stuck, creeping, at the stop time, or cut short (event limit, horizon).
"""

from __future__ import annotations

import math

import numpy as np

from ecdsim._types import FloatArray
from ecdsim.dynamics.kernel import layout as L
from ecdsim.dynamics.kernel.closed import (
    REACH,
    REST,
    ZERO,
    Segment,
    advance,
    prepare,
    rest_time,
    switch_time,
)
from ecdsim.dynamics.kernel.friction import drives, holds_at_rest, scratch_rows, stuck_flags
from ecdsim.dynamics.kernel.hinge import load_spring
from ecdsim.dynamics.kernel.integrate import advance_integrated
from ecdsim.dynamics.kernel.layout import case_words
from ecdsim.dynamics.kernel.outcome import apply_event, book, finish, peak_temperature
from ecdsim.dynamics.kernel.record import OVERFLOW, Buffers, begin_case, log_event, open_span
from ecdsim.dynamics.kernel.segment import (
    Tables,
    at_rest,
    compliant_scales,
    first_piece,
    rigid_scales,
    start_segment,
)
from ecdsim.physics.mechanics import kinetic_energy, mesh_elastic_energy
from ecdsim.physics.thermal import damping_factor_from_log, temperature_from_factor_log

HORIZON_TIME = 1e9  # [s] a segment's integration horizon when there is no stop time
# A plot of a case that ends approaching rest asymptotically (creep) stops after this many
# of the motion's slow time constants (its remaining motion is then below e^-10 of it).
DISPLAY_TIME_CONSTANTS = 10.0
_LATCHED, _STOP_TIME, _EVENT_LIMIT, _HORIZON = 1, 5, 6, 7  # statuses that keep their speed


def temperature(par: FloatArray, s: float) -> float:
    """The damper temperature of the log state s, clipped to the law's zero [degC]."""
    value = float(temperature_from_factor_log(s, par[L.AMB], par[L.FA], par[L.COEF]))
    return min(value, float(par[L.TZERO]))


def new_workspace(m: int, na: int, nq: int) -> tuple[FloatArray, ...]:
    """The work arrays of one case: RODAS4's (stages, Jacobian, LU, pivots), event
    values and scratch rows, the friction machine's (constraint systems)."""
    n = 2 * m + na + nq
    size = m + na
    return (
        np.zeros((9, n)),
        np.zeros((n, n)),
        np.zeros((size, size)),
        np.zeros(size),
        np.zeros((6, max(n, L.SLOTS))),
        np.zeros(scratch_rows(m)),
        np.zeros(2 * m),
    )


def _sign(value: float) -> float:
    if value > 0.0:
        return 1.0
    if value < 0.0:
        return -1.0
    return 0.0


def initial_state(
    cw: FloatArray, tables: Tables, y: FloatArray, out: FloatArray, m: int, na: int
) -> None:
    """The state at release: the load at its start angle and speed, the damper side at
    rest behind a lost motion (else turning with the load), the heating's start."""
    par = md = cw
    angles = tables[0]
    for i in range(y.shape[0]):
        y[i] = 0.0
    for i in range(L.COLUMNS, case_words(m)):
        md[i] = 0.0
    for i in range(L.OUT_FIELDS):
        out[i] = 0.0
    md[L.MD_PIECE] = first_piece(angles, par[L.PHI0])
    w0 = par[L.W0]
    y[m] = w0
    if na > 0:
        y[2 * m] = par[L.S0]
        if na == 2:
            y[2 * m + 1] = par[L.H0]
    engaged = par[L.GAP] <= 0.0
    if m == 1:
        md[L.MD_ENGAGED] = 1.0 if engaged else 0.0
        md[L.MD_SLIDE0] = _sign(w0)
        out[L.OUT_INITIAL_KE] = kinetic_energy(par[L.JL] + md[L.MD_ENGAGED] * par[L.JD], w0)
    else:
        _initial_mesh(cw, tables, y, out, engaged)
    out[L.OUT_ARRIVAL_TIME] = math.inf
    out[L.OUT_STUCK_ANGLE] = math.nan
    out[L.OUT_STUCK_TIME] = math.nan
    out[L.OUT_ENGAGEMENT_TIME] = 0.0 if engaged else math.inf
    out[L.OUT_MAX_SPEED] = max(w0, 0.0)
    out[L.OUT_MAX_TEMPERATURE] = temperature(par, par[L.S0]) if na > 0 else par[L.AMB]


def _initial_mesh(
    cw: FloatArray, tables: Tables, y: FloatArray, out: FloatArray, engaged: bool
) -> None:
    """A compliant mesh at release: the whole gap open with the load against the
    backward flank; without lost motion the flanks touch and the damper side turns with
    the load, pressed on the side the spring drives; a backward start presses the
    backward flank at once."""
    par = md = sg = cw
    w0 = par[L.W0]
    wd = w0 if engaged else 0.0
    y[1] = -0.5 * par[L.GAP]
    y[3] = w0 - wd
    if engaged:
        at_rest(cw, tables, par[L.PHI0], 2)
        md[L.MD_MESH] = L.PRESS
        md[L.MD_SIDE] = 1.0 if load_spring(sg, 0.0) >= 0.0 else -1.0
    elif w0 < 0.0:
        md[L.MD_MESH] = L.PRESS
        md[L.MD_SIDE] = -1.0
    else:
        md[L.MD_SIDE] = 1.0
    md[L.MD_SLIDE0] = _sign(w0)
    md[L.MD_SLIDE1] = _sign(wd)
    out[L.OUT_INITIAL_KE] = kinetic_energy(par[L.JL], w0) + kinetic_energy(par[L.JD], wd)


def resolve_rest(
    cw: FloatArray, tables: Tables, y: FloatArray, t: float, phi: float,
    ws: tuple[FloatArray, ...], out: FloatArray, buffers: Buffers, counts: FloatArray,
    index: int, m: int, na: int,
) -> bool:  # fmt: skip
    """The friction machine at rest: every element at rest is taken as stuck, the one
    held least breaks away in the direction it is pushed, the others are solved again,
    until every stuck one holds (an active-set pass; module notes of
    :mod:`ecdsim.dynamics.kernel.friction`). True when every element stays stuck."""
    md = cw
    scratch, column = ws[5], ws[6]
    if md[L.MD_SLIDE0] == 0 and md[L.MD_HELD] == 0:
        md[L.MD_START] = 1.0 if phi <= 0.0 else 0.0
    at_rest(cw, tables, phi, m)
    for _ in range(m):
        stuck_flags(cw, scratch, m)
        drives(cw, y, scratch, column, m, na)
        worst = -1
        excess = -1.0
        for k in range(m):
            drive = column[m + k]
            held = scratch[3 * m + 1, k] != 0.0
            if held and not holds_at_rest(cw, k, drive, m) and abs(drive) > excess:
                worst = k
                excess = abs(drive)
        if worst < 0:
            break
        md[L.MD_SLIDE0 + worst] = _sign(column[m + worst])
        if worst == 0:
            md[L.MD_START] = 0.0
            log_event(buffers, counts, index, t, L.EV_BREAKAWAY, phi, y[m])
    sliding = 0
    for k in range(m):
        sliding += md[L.MD_SLIDE0 + k] != 0
    return sliding == 0


def _stick(
    cw: FloatArray,
    t: float,
    phi: float,
    out: FloatArray,
    buffers: Buffers,
    counts: FloatArray,
    index: int,
) -> None:
    """Every element stuck: at rest for good, or, a compliant mesh's load held at the
    end of travel, the run ends with the held load's status."""
    md = cw
    if md[L.MD_HELD] != 0:
        finish(cw, out, int(md[L.MD_HELD]))
        return
    finish(cw, out, L.ST_STUCK)
    out[L.OUT_STUCK] = 1.0
    out[L.OUT_STUCK_ANGLE] = phi
    out[L.OUT_STUCK_TIME] = t
    log_event(buffers, counts, index, t, L.EV_STICK, phi, 0.0)


def segment_effects(cw: FloatArray, m: int) -> int:
    """The effects that act on the segment: the case's, less those of the damper side
    while the lost motion is open (its law and heating) and a Stribeck excess of zero."""
    par = sg = cw
    effects = int(par[L.EFFECTS])
    if m == 1 and sg[L.SG_ENG] == 0.0:
        effects &= ~L.ENGAGED_EFFECTS
    if sg[L.SG_EX0] <= 0.0 and (m == 1 or sg[L.SG_EX1] <= 0.0):
        effects &= ~L.EFFECT_STRIBECK
    return effects


def closed_form_applies(cw: FloatArray, m: int) -> bool:
    """A segment takes the closed form when it is linear: one coordinate and only the
    effects the closed form models (``layout.CLOSED_FORM_EFFECTS``); any other effect,
    a new one included, is integrated."""
    return m == 1 and (segment_effects(cw, m) & ~L.CLOSED_FORM_EFFECTS) == 0


def advance_closed(
    cw: FloatArray, y: FloatArray, t: float, stop: float, out: FloatArray, ex: FloatArray,
    buffers: Buffers, counts: FloatArray, index: int, record: bool, na: int,
) -> tuple[int, float]:  # fmt: skip
    """A rigid mesh's linear segment in closed form, to its first event (a lossy gear's
    power-flow switch included); the state's displacement, speed and damper dissipation
    are set. Returns (the event's slot, the duration)."""
    par = md = sg = cw
    sigma = md[L.MD_SLIDE0]
    eng = sg[L.SG_ENG]
    ideal = eng * par[L.BLIN] * par[L.ETAF]  # BT_T N^2 through an ideal gear
    damping = sg[L.SG_MESH] * ideal
    w0 = sigma * y[1] + 0.0  # + 0.0: -0.0's atan2 would give a negative time
    seg = prepare(
        1.0 / cw[L.PINV], damping, -sg[L.SG_SLOPE], sigma * sg[L.SG_T0] - sg[L.SG_FC0], w0
    )
    length = sigma * sg[L.SG_TARGET]
    cap = max(stop - t, 0.0)
    kind, duration, x, v, v2, top = advance(seg, length, cap)
    slot = (
        L.SLOT_REACH
        if kind == REACH
        else L.SLOT_ZERO0
        if kind == ZERO
        else L.SLOT_CREEP
        if kind == REST
        else L.CAP_SLOT
    )
    if md[L.MD_FLOW] != 0:
        horizon = duration if math.isfinite(duration) else rest_time(seg, 800.0)
        switch = switch_time(
            seg, ideal, sg[L.SG_FQ], par[L.JL], par[L.JD], sg[L.SG_LOAD], md[L.MD_FLOW], horizon
        )
        if math.isfinite(switch) and switch < cap:
            kind, duration, x, v, v2, top = advance(seg, length, switch)
            slot = L.SLOT_SWITCH
        own = 0.5 * par[L.JD] * (v * v - w0 * w0) + ideal * v2 + sg[L.SG_FQ] * abs(x)
        out[L.OUT_GEAR_LOSS] += (sg[L.SG_MESH] - 1.0) * own
    if record:
        _closed_span(cw, seg, t, duration, y, buffers, counts, index, na)
    if kind == REST:
        out[L.OUT_DISPLAY_END] = t + rest_time(seg, DISPLAY_TIME_CONSTANTS)
    y[0] = sigma * x
    y[1] = sigma * v
    y[2 + na] = ideal * v2
    ex[0] = max(ex[0], top)
    return slot, duration


def _closed_span(
    cw: FloatArray, seg: Segment, t: float, duration: float, y: FloatArray, buffers: Buffers,
    counts: FloatArray, index: int, na: int,
) -> None:  # fmt: skip
    """Record a closed-form segment's constants (its time series are re-evaluated)."""
    par = md = sg = cw
    row = open_span(buffers, counts, index, L.SPAN_CLOSED, t, sg[L.SG_ENG])
    if row < 0:
        return
    spans = buffers[1]
    spans[row, L.SPAN_T1] = t + duration
    spans[row, L.SPAN_PHI0] = sg[L.SG_PHI]
    spans[row, L.SPAN_DIR] = md[L.MD_SLIDE0]
    spans[row, L.SPAN_J] = seg[0]
    spans[row, L.SPAN_B] = seg[1]
    spans[row, L.SPAN_K] = seg[2]
    spans[row, L.SPAN_A] = seg[3]
    spans[row, L.SPAN_W0] = seg[4]
    spans[row, L.SPAN_TEMP] = temperature(par, y[2]) if na > 0 else par[L.AMB]


def _pass(
    cw: FloatArray, tables: Tables, y: FloatArray, t: float, phi: float,
    settings: FloatArray, h: float, ws: tuple[FloatArray, ...], arrays: tuple[FloatArray, ...],
    out: FloatArray,
    buffers: Buffers, counts: FloatArray, index: int, dm: tuple[int, ...],
    da: tuple[int, ...], dq: tuple[int, ...],
) -> tuple[int, float, float, bool]:  # fmt: skip
    """One segment from the state at time t (load angle phi) to its first event.

    Returns (its slot, its duration, the next step size, whether it was integrated).
    """
    m = len(dm)
    na = len(da)
    n = 2 * m + na + len(dq)
    par = cw
    atol, ex, start, creep = arrays[0], arrays[1], arrays[2], arrays[3]
    factor = float(par[L.FA])
    if na > 0:
        factor = float(damping_factor_from_log(y[2 * m], par[L.FA], par[L.COEF]))
    start_segment(cw, tables, y, phi, factor, ws[5], ws[6], m)
    for i in range(2 * m + na, n):
        y[i] = 0.0
    for i in range(n):
        start[i] = y[i]
    ex[0] = cw[L.MD_SLIDE0] * y[m]
    ex[1] = y[2 * m] if na > 0 else 0.0
    stop = settings[L.STOP]
    record = settings[L.RECORD] != 0.0
    if closed_form_applies(cw, m):
        slot, duration = advance_closed(cw, y, t, stop, out, ex, buffers, counts, index, record, na)
        return slot, duration, h, False
    if m == 1:
        h = rigid_scales(cw, y, settings[L.RTOL], atol, na)[0]
    left = stop - t
    end = t + min(left, HORIZON_TIME)
    cap_slot = L.CAP_SLOT if left <= HORIZON_TIME else L.HORIZON_SLOT
    slot, duration, h = advance_integrated(
        cw, y, t, end, cap_slot, settings, atol, h, ws, ex, out, buffers, counts, index,
        creep, dm, da, dq,
    )  # fmt: skip
    return slot, duration, h, True


def run_case(
    index: int, cw: FloatArray, tables: Tables, settings: FloatArray, out: FloatArray,
    ws: tuple[FloatArray, ...], arrays: tuple[FloatArray, ...], y: FloatArray,
    buffers: Buffers, counts: FloatArray,
    dm: tuple[int, ...], da: tuple[int, ...], dq: tuple[int, ...],
) -> None:  # fmt: skip
    """Run one case from release to the end of its run; its summary goes to ``out``."""
    m = len(dm)
    na = len(da)
    par = md = cw
    begin_case(counts)
    initial_state(cw, tables, y, out, m, na)
    t = 0.0
    phi = par[L.PHI0]
    log_event(buffers, counts, index, t, L.EV_RELEASE, phi, y[m])
    h = 0.0
    if m == 2:
        h, speed = compliant_scales(cw, tables, settings[L.RTOL], arrays[0], na)
        arrays[3][0] = 1e-9 * speed
        arrays[3][1] = _largest(tables[1])
    while md[L.MD_DONE] == 0:
        if counts[OVERFLOW] != 0.0:
            return
        if md[L.MD_PASSES] >= settings[L.MAX_EVENTS]:
            finish(cw, out, L.ST_EVENT_LIMIT)
            log_event(buffers, counts, index, t, L.EV_EVENT_LIMIT, phi, y[m])
            break
        if m == 1:
            md[L.MD_SLIDE0] = _sign(y[1])
        resting = md[L.MD_SLIDE0] == 0 or (m == 2 and md[L.MD_SLIDE1] == 0)
        if resting and resolve_rest(cw, tables, y, t, phi, ws, out, buffers, counts, index, m, na):
            _stick(cw, t, phi, out, buffers, counts, index)
            break
        slot, duration, h, integrated = _pass(
            cw, tables, y, t, phi, settings, h, ws, arrays, out, buffers, counts, index, dm, da, dq
        )
        x = book(cw, y, arrays[2], slot, arrays[1][0], out, integrated, m, na)
        if na > 0:
            peak_temperature(out, temperature(par, max(arrays[1][1], y[2 * m])))
        phi = cw[L.SG_PHI] + x
        y[0] = 0.0
        t += duration
        out[L.OUT_HOLD_FROM] = t
        if not (slot == L.SLOT_CREEP and not integrated):
            out[L.OUT_DISPLAY_END] = t
        counted, t = apply_event(
            cw, slot, t, phi, y, ws[0][8], out, ws, buffers, counts, index, m, na
        )
        md[L.MD_PASSES] += counted
    _final(cw, y, t, phi, out, m, na)


def _largest(values: FloatArray) -> float:
    """The largest magnitude of a table, at least 1e-300 (a scale for its tolerance)."""
    largest = 1e-300
    for value in values:
        largest = max(largest, abs(value))
    return largest


def _final(
    cw: FloatArray, y: FloatArray, t: float, phi: float, out: FloatArray, m: int, na: int
) -> None:
    """The run's final state and kinetic energy (the elastic energy of a compliant mesh)."""
    par = md = cw
    status = int(md[L.MD_DONE])
    keeps = status in (_LATCHED, _STOP_TIME, _EVENT_LIMIT, _HORIZON)
    speed = y[m] if keeps else 0.0
    if m == 1:
        out[L.OUT_FINAL_KE] = kinetic_energy(par[L.JL] + md[L.MD_ENGAGED] * par[L.JD], speed)
        out[L.OUT_ENGAGED] = md[L.MD_ENGAGED]
    else:
        damper = y[2] - y[3]
        load = kinetic_energy(par[L.JL], y[2]) if keeps else 0.0
        out[L.OUT_FINAL_KE] = load + kinetic_energy(par[L.JD], damper)
        out[L.OUT_ELASTIC] = mesh_elastic_energy(y[1], 0.5 * par[L.GAP], par[L.MC])
        out[L.OUT_ENGAGED] = 1.0
    out[L.OUT_TIME] = t
    out[L.OUT_ANGLE] = phi
    out[L.OUT_SPEED] = speed
    out[L.OUT_STATUS] = status
    out[L.OUT_IMPACTS] = md[L.MD_IMPACTS]
    out[L.OUT_TEMPERATURE] = temperature(par, y[2 * m]) if na > 0 else par[L.AMB]
    out[L.OUT_HOUSING] = par[L.AMB] + y[2 * m + 1] if na == 2 else par[L.AMB]


def solve_cases(
    first: int, last: int, table: FloatArray, angles: FloatArray, torques: FloatArray,
    resist: FloatArray, settings: FloatArray, out: FloatArray, buffers: Buffers,
    counts: FloatArray, dm: tuple[int, ...], da: tuple[int, ...], dq: tuple[int, ...],
) -> int:  # fmt: skip
    """Run cases ``first`` to ``last - 1`` of the table (one row each, with their spring
    tables' rows); their summaries go to the rows of ``out``. Returns -1, or the case at
    which an output table was full (:mod:`ecdsim.dynamics.kernel.record`): the caller
    enlarges it, resets ``counts`` to that case's start and runs again from it."""
    m = len(dm)
    na = len(da)
    n = 2 * m + na + len(dq)
    ws = new_workspace(m, na, len(dq))
    arrays = (np.zeros(n), np.zeros(2), np.zeros(n), np.zeros(2))
    y = np.zeros(n)
    cw = np.zeros(case_words(m))
    for i in range(first, last):
        for j in range(L.COLUMNS):
            cw[j] = table[i, j]
        tables = (angles[i], torques[i], resist[i])
        run_case(i, cw, tables, settings, out[i], ws, arrays, y, buffers, counts, dm, da, dq)
        if counts[OVERFLOW] != 0.0:
            return i
    return -1
