"""A segment integrated by RODAS4 to its first event, located on the dense output.

Steps of :mod:`ecdsim.dynamics.kernel.rodas` are accepted when the embedded error, in
the max norm over ``atol + rtol |y|``, is at most 1. After each accepted step every event
slot the segment arms is evaluated at the step's end; those that crossed are located on
the step's cubic Hermite interpolant (:mod:`ecdsim.dynamics.kernel.dense`, one locator
for all) and the earliest ends the segment, the state set to the interpolant there. The
largest speed, the damper's peak temperature and (compliant mesh) the largest mesh torque
are tracked at the step ends, at the event and at the interpolant's interior maxima.
"""

from __future__ import annotations

import math

from ecdsim._types import FloatArray
from ecdsim.dynamics.kernel import layout as L
from ecdsim.dynamics.kernel.dense import (
    LOCATE_ITERATIONS,
    LOCATE_TOLERANCE,
    crossed,
    illinois,
    interior_peak,
    interpolate,
    next_trial,
)
from ecdsim.dynamics.kernel.events import (
    accept_creep,
    active_slots,
    compliant_creeping,
    event_value,
)
from ecdsim.dynamics.kernel.hinge import derivatives, mesh_now
from ecdsim.dynamics.kernel.record import Buffers, add_point, open_span
from ecdsim.dynamics.kernel.rodas import error_norm, rodas_step, step_factor

MAX_STEPS = 200_000  # step attempts per segment before the run is cut short (horizon)


def locate(
    cw: FloatArray, slot: int, y: FloatArray, f: FloatArray, y1: FloatArray, f1: FloatArray,
    h: float, g0: float, g1: float, trial: FloatArray, scratch: FloatArray, column: FloatArray,
    m: int, na: int, n: int,
) -> float:  # fmt: skip
    """The fraction of the step where event ``slot`` occurs (g0 > 0 >= g1): Illinois on
    the event function of the interpolated state, to 2^-50 of the step."""
    if g0 <= 0.0:
        return 0.0
    a = 0.0
    b = 1.0
    ga = g0
    gb = g1
    side = 0
    for _ in range(LOCATE_ITERATIONS):
        if b - a <= LOCATE_TOLERANCE or gb == 0.0:
            break
        s = next_trial(ga, gb, a, b)
        interpolate(y, f, y1, f1, h, s, trial, n)
        gs = event_value(cw, slot, trial, scratch, column, m, na)
        ga, gb, a, b, side = illinois(ga, gb, a, b, gs, s, side)
    return b


def _mesh_peak(
    cw: FloatArray,
    y: FloatArray,
    f: FloatArray,
    y1: FloatArray,
    f1: FloatArray,
    h: float,
    stop: float,
) -> float:
    """The pressing mesh's largest |torque| inside the step (its interpolant's interior
    maximum, the torque being linear in the relative angle and speed)."""
    par = md = cw
    if md[L.MD_MESH] != L.PRESS:
        return 0.0
    side = md[L.MD_SIDE]
    c = side * par[L.MC]
    d = side * par[L.MD]
    offset = -side * c * 0.5 * par[L.GAP]
    peak = interior_peak(
        c * y[1] + d * y[3] + offset, c * f[1] + d * f[3], c * y1[1] + d * y1[3] + offset,
        c * f1[1] + d * f1[3], h, stop,
    )  # fmt: skip
    return max(peak, 0.0)


def track_mesh(cw: FloatArray, out: FloatArray, torque: float) -> None:
    """Count a mesh torque in the run's largest, and once the load is held at the end
    of travel in the largest at the latch (issue 23 item 8: at the event instants too)."""
    value = abs(torque)
    out[L.OUT_MAX_MESH_TORQUE] = max(out[L.OUT_MAX_MESH_TORQUE], value)
    if cw[L.MD_HELD] != 0:
        out[L.OUT_LATCH_MESH_TORQUE] = max(out[L.OUT_LATCH_MESH_TORQUE], value)


def _extremes(
    cw: FloatArray, y: FloatArray, f: FloatArray, y1: FloatArray, f1: FloatArray, h: float,
    stop: float, ex: FloatArray, out: FloatArray, m: int, na: int,
) -> None:  # fmt: skip
    """The step's interior maxima of the forward speed, the damper's log state and
    (compliant) the mesh torque, before the fraction ``stop``."""
    sigma = cw[L.MD_SLIDE0]
    if sigma != 0:
        peak = interior_peak(sigma * y[m], sigma * f[m], sigma * y1[m], sigma * f1[m], h, stop)
        ex[0] = max(ex[0], peak)
    if na > 0:
        row = 2 * m
        ex[1] = max(ex[1], interior_peak(y[row], f[row], y1[row], f1[row], h, stop))
    if m == 2:
        track_mesh(cw, out, _mesh_peak(cw, y, f, y1, f1, h, stop))


def _endpoint(
    cw: FloatArray, y: FloatArray, ex: FloatArray, out: FloatArray, m: int, na: int
) -> None:
    """The extremes at a step's end or at the event."""
    sigma = cw[L.MD_SLIDE0]
    if sigma != 0:
        ex[0] = max(ex[0], sigma * y[m])
    if na > 0:
        ex[1] = max(ex[1], y[2 * m])
    if m == 2:
        track_mesh(cw, out, mesh_now(cw, cw, y[1], y[3]))


def _point(
    cw: FloatArray, buffers: Buffers, counts: FloatArray, span: int, t: float, y: FloatArray,
    f: FloatArray, m: int, na: int,
) -> None:  # fmt: skip
    """Record the state at time t (absolute) in the span."""
    sg = cw
    s = y[2 * m] if na > 0 else 0.0
    ds = f[2 * m] if na > 0 else 0.0
    add_point(buffers, counts, span, t, sg[L.SG_PHI] + y[0], y[m], s, f[0], f[m], ds)


def start_stepper(
    cw: FloatArray, y: FloatArray, span: float, rtol: float, atol: FloatArray, h: float,
    method: int, dm: tuple[int, ...], da: tuple[int, ...], dq: tuple[int, ...],
) -> float:  # fmt: skip
    """The stepper's state for a segment: RODAS4 keeps none (its step size is ``h``).
    (:mod:`ecdsim.dynamics.scipy_steppers` replaces this and :func:`attempt` by scipy's
    Radau, BDF and LSODA, stepping the same equations.)"""
    return h


def attempt(
    stepper: float, cw: FloatArray, y: FloatArray, f: FloatArray, h: float, t: float, limit: float,
    rtol: float, atol: FloatArray, ws: tuple[FloatArray, ...], dm: tuple[int, ...],
    da: tuple[int, ...], dq: tuple[int, ...],
) -> tuple[float, float]:  # fmt: skip
    """One accepted RODAS4 step from ``y`` at t (rejected ones retried smaller): its state
    in ``ws[0][8]``; returns (the step's size, the next one's), or (0, 0) after
    MAX_STEPS rejections."""
    n = 2 * len(dm) + len(da) + len(dq)
    work, jac, lu, pivot = ws[0], ws[1], ws[2], ws[3]
    for _ in range(MAX_STEPS):
        h = min(h, limit - t)
        sound = rodas_step(cw, y, f, h, work, jac, lu, pivot, dm, da, dq)
        norm = error_norm(y, work[8], work[5], rtol, atol, n)
        factor = step_factor(norm) if sound else 0.25
        if sound and norm <= 1.0:
            return h, h * factor
        h *= factor
    return 0.0, 0.0


def _earliest(
    cw: FloatArray, y: FloatArray, f: FloatArray, y1: FloatArray, f1: FloatArray, h: float,
    rows: FloatArray, scratch: FloatArray, column: FloatArray, m: int, na: int, n: int,
) -> tuple[int, float]:  # fmt: skip
    """The first event within the step (its slot and fraction), or (-1, inf): every armed
    slot evaluated at the step's end, those that crossed located on the interpolant."""
    g0, g1, active, trial = rows[2], rows[3], rows[4], rows[5]
    best = math.inf
    hit = -1
    for slot in range(L.SLOTS):
        if active[slot] == 0.0:
            continue
        g1[slot] = event_value(cw, slot, y1, scratch, column, m, na)
        if not crossed(g0[slot], g1[slot]):
            continue
        s = locate(cw, slot, y, f, y1, f1, h, g0[slot], g1[slot], trial, scratch, column, m, na, n)
        if s >= best:
            continue
        if slot == L.SLOT_CREEP:
            interpolate(y, f, y1, f1, h, s, trial, n)
            if not accept_creep(cw, trial):
                continue
        best = s
        hit = slot
    return hit, best


def _begin(
    cw: FloatArray, y: FloatArray, start: float, ws: tuple[FloatArray, ...], record: bool,
    buffers: Buffers, counts: FloatArray, index: int,
    dm: tuple[int, ...], da: tuple[int, ...], dq: tuple[int, ...],
) -> int:  # fmt: skip
    """A segment's start: the rates, the active events' values, its span (-1 if none)."""
    m = len(dm)
    na = len(da)
    rows, scratch, column = ws[4], ws[5], ws[6]
    f, g0, active = rows[0], rows[2], rows[4]
    derivatives(cw, y, f, dm, da, dq)
    active_slots(cw, active, m)
    for slot in range(L.SLOTS):
        if active[slot] != 0.0:
            g0[slot] = event_value(cw, slot, y, scratch, column, m, na)
    if not record:
        return -1
    span = open_span(buffers, counts, index, L.SPAN_STEPS, start, cw[L.SG_ENG])
    _point(cw, buffers, counts, span, start, y, f, m, na)
    return span


def advance_integrated(
    cw: FloatArray, y: FloatArray, start: float, end: float, cap_slot: int, settings: FloatArray,
    atol: FloatArray, h: float, ws: tuple[FloatArray, ...], ex: FloatArray, out: FloatArray,
    buffers: Buffers, counts: FloatArray, index: int, creep: FloatArray,
    dm: tuple[int, ...], da: tuple[int, ...], dq: tuple[int, ...],
) -> tuple[int, float, float]:  # fmt: skip
    """Integrate the segment from ``y`` at time ``start`` to its first event or ``end``.

    ``y`` is updated to the state at the end. Returns (the event's slot, or CAP_SLOT /
    HORIZON_SLOT at ``end`` as ``cap_slot`` says, or after MAX_STEPS; the duration; the
    next step size). ``creep`` = (threshold, torque scale) of a compliant mesh's check.
    """
    m = len(dm)
    na = len(da)
    n = 2 * m + na + len(dq)
    rows, scratch, column = ws[4], ws[5], ws[6]
    f, f1, g0, trial = rows[0], rows[1], rows[2], rows[5]
    rtol = settings[L.RTOL]
    record = settings[L.RECORD] != 0.0
    span = _begin(cw, y, start, ws, record, buffers, counts, index, dm, da, dq)
    t = 0.0
    limit = end - start
    _endpoint(cw, y, ex, out, m, na)
    stepper = start_stepper(cw, y, limit, rtol, atol, h, int(settings[L.METHOD]), dm, da, dq)
    for _ in range(MAX_STEPS):
        h, h_next = attempt(stepper, cw, y, f, h, t, limit, rtol, atol, ws, dm, da, dq)
        if h <= 0.0:
            break
        y1 = ws[0][8]
        cw[L.MD_STEPS] += 1
        derivatives(cw, y1, f1, dm, da, dq)
        hit, best = _earliest(cw, y, f, y1, f1, h, rows, scratch, column, m, na, n)
        _extremes(cw, y, f, y1, f1, h, min(best, 1.0), ex, out, m, na)
        if hit >= 0:
            interpolate(y, f, y1, f1, h, best, trial, n)
            for i in range(n):
                y[i] = trial[i]
            t += best * h
            _endpoint(cw, y, ex, out, m, na)
            if record:
                derivatives(cw, y, f, dm, da, dq)
                _point(cw, buffers, counts, span, start + t, y, f, m, na)
            return hit, t, h_next
        t += h
        for i in range(n):
            y[i] = y1[i]
            f[i] = f1[i]
        for slot in range(L.SLOTS):
            g0[slot] = rows[3, slot]
        _endpoint(cw, y, ex, out, m, na)
        if record:
            _point(cw, buffers, counts, span, start + t, y, f, m, na)
        if m == 2 and compliant_creeping(cw, y, creep[0], creep[1], scratch, column, na):
            return L.SLOT_CREEP, t, h_next
        if t >= limit * (1.0 - 1e-15):
            return cap_slot, t, h_next
        h = h_next
    return L.HORIZON_SLOT, t, h
