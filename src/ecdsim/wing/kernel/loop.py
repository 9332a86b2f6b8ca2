"""A wing's event loop: the kernel's friction machine, RODAS4 and locator over N hinges.

One pass per segment, as the hinge's loop (:mod:`ecdsim.dynamics.kernel.loop`): the
groups at rest are resolved by the friction machine (every group at rest taken as stuck,
the one whose holding torque exceeds its breakaway the most breaks away the way it is
pushed, the rest solved again until every stuck one holds: the active-set pass of
:mod:`ecdsim.dynamics.kernel.friction`, its holding torques the constraint forces of
:func:`~ecdsim.wing.kernel.equations.accelerations`); the segment is stepped by
the kernel's RODAS4 (:func:`ecdsim.dynamics.kernel.integrate.attempt`, the wing's
equations substituted for the hinge's by :mod:`ecdsim.dynamics.kernel.build`) to its
first event, located on the step's dense output by the kernel's locator
(:func:`ecdsim.dynamics.kernel.integrate.locate`); the event is applied:

* a sliding group's speed reaches zero, or a stuck one's holding torque its breakaway:
  the friction machine decides again (no chatter: nothing changes while every holding
  torque stays within its breakaway);
* a rigid latch: a generalised impulse ``M dpsi' = E lambda`` sets the arriving group's
  speed to ``-e`` times its arrival speed, the latched groups held, a group resting on
  its stowed stop held only if the impulse pushes it back; rebounds settle below 1e-12
  of the first arrival's kinetic energy (the single hinge's rule, ``impacts.SETTLE_FRACTION``);
* a compliant latch engages (its spring and damper act from then on, both ways);
* the stowed stop: the returning group stops (a plastic impact);
* an elastic cable's strand slackens or tightens again;
* a hinge's lost motion closes while it moves forward: its damper side (rotor, damping,
  ECD friction), idle in the gap, engages in a plastic impact with the chain;
* a lossy gear's mesh torque passes zero (a power_flow event): its flow switches
  (forward: the load drives the damper, the damper side's torque and inertia seen times
  1/eta_f; back-driven: times eta_b), each lossy gear's flow decided at every segment's
  start by :func:`~ecdsim.wing.kernel.equations.decide_flows`.

The run ends when every group is held (latched, or at rest for good), at the stop time
or at the event limit.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import FloatArray
from ecdsim.dynamics.kernel.dense import crossed, interior_peak, interpolate
from ecdsim.dynamics.kernel.friction import solve_small
from ecdsim.dynamics.kernel.impacts import SETTLE_FRACTION
from ecdsim.dynamics.kernel.integrate import attempt, locate, start_stepper
from ecdsim.dynamics.kernel.loop import _sign
from ecdsim.dynamics.kernel.rodas import new_work
from ecdsim.wing.kernel import layout as W
from ecdsim.wing.kernel.equations import (
    accelerations,
    active_slots,
    cable_deflection,
    chain_derivatives,
    chain_event_value,
    decide_flows,
    group_system,
    hinge_angles,
    holding_margin,
    kinetic,
    latch_torque,
    solve_on,
)
from ecdsim.wing.kernel.layout import cable as cable_at
from ecdsim.wing.kernel.layout import group as group_at
from ecdsim.wing.kernel.layout import hinge as hinge_at

HORIZON = 1e4  # [s] a segment's integration horizon without a stop time
CAP = -2  # a segment that reached its end time
FAILED = -3  # the stepper could not take a step (MAX_STEPS rejections)


def log_event(cw: FloatArray, events: FloatArray, t: float, kind: int, hinge: int) -> None:
    """Append an event row (time, kind, hinge); a full buffer marks an overflow."""
    row = int(cw[W.W_EVENTS])
    if row >= events.shape[0]:
        cw[W.W_OVERFLOW] = 1.0
        return
    events[row, 0] = t
    events[row, 1] = kind
    events[row, 2] = hinge
    cw[W.W_EVENTS] = row + 1


def record(cw: FloatArray, points: FloatArray, t: float, y: FloatArray, m: int) -> None:
    """Append a point: time, each hinge's deployed angle and speed; keep each heated
    damper's largest log temperature state (the temperature grows with it)."""
    n = int(cw[W.W_N])
    for j in range(n):
        aux = int(cw[hinge_at(W.H_AUX, j)])
        if aux >= 0:
            word = hinge_at(W.H_PEAK_LOG, j)
            cw[word] = max(cw[word], y[aux])
    row = int(cw[W.W_POINTS])
    if row >= points.shape[0]:
        cw[W.W_OVERFLOW] = 1.0
        return
    phi, rate = hinge_angles(cw, y, m)
    points[row, 0] = t
    for j in range(n):
        points[row, 1 + j] = phi[j]
        points[row, 1 + n + j] = rate[j]
    cw[W.W_POINTS] = row + 1


def _log_group(cw: FloatArray, events: FloatArray, t: float, kind: int, g: int) -> None:
    """An event for every hinge of group g."""
    for j in range(int(cw[W.W_N])):
        if int(cw[hinge_at(W.H_GROUP, j)]) == g:
            log_event(cw, events, t, kind, j)


def resolve_rest(cw: FloatArray, y: FloatArray, t: float, events: FloatArray, m: int) -> None:
    """The friction machine: every unlocked group at rest is stuck unless its holding
    torque exceeds its breakaway; the worst breaks away first, the rest are solved again
    (module notes)."""
    acc = np.empty(m)
    holding = np.empty(m)
    for _ in range(m):
        accelerations(cw, y, acc, holding, m)
        worst = -1
        excess = 0.0
        for g in range(m):
            if cw[group_at(W.G_DIR, g)] != 0.0 or cw[group_at(W.G_LOCKED, g)] != 0.0:
                continue
            margin = holding_margin(cw, g, holding[g], y[g])
            if margin < 0.0 and -margin > excess:
                worst = g
                excess = -margin
        if worst < 0:
            return
        cw[group_at(W.G_DIR, worst)] = -_sign(holding[worst])
        _log_group(cw, events, t, W.EV_BREAKAWAY, worst)


def inverse_mass(cw: FloatArray, y: FloatArray, m: int) -> FloatArray:
    """``M_psi^-1`` at state y, column by column (the friction machine's solver)."""
    mass, _ = group_system(cw, y, m, False)
    inverse = np.empty((m, m))
    system = np.empty((m, m + 1))
    column = np.empty(m)
    for c in range(m):
        for r in range(m):
            for k in range(m):
                system[r, k] = mass[r, k]
            system[r, m] = 1.0 if r == c else 0.0
        solve_small(system, column, m)
        for r in range(m):
            inverse[r, c] = column[r]
    return inverse


def _indices(flags: FloatArray) -> NDArray[np.int64]:
    """The positions of the nonzero flags."""
    count = 0
    for k in range(flags.shape[0]):
        count += flags[k] != 0.0
    index = np.empty(count, dtype=np.int64)
    i = 0
    for k in range(flags.shape[0]):
        if flags[k] != 0.0:
            index[i] = k
            i += 1
    return index


def _impulses(
    inverse: FloatArray, before: FloatArray, held: FloatArray, g: int, target: float
) -> FloatArray:
    """The impulses on the held groups that bring group g's speed to ``target`` and the
    other held groups' to 0: ``(E^T M^-1 E) lambda = v_target - E^T v``."""
    index = _indices(held)
    count = index.shape[0]
    change = np.empty(held.shape[0])
    for k in range(held.shape[0]):
        change[k] = (target if k == g else 0.0) - before[k]
    solution = solve_on(inverse, change, index)
    impulse = np.zeros(held.shape[0])
    for r in range(count):
        impulse[index[r]] = solution[r]
    return impulse


def impact(
    cw: FloatArray, y: FloatArray, before: FloatArray, g: int, target: float, m: int
) -> float:
    """A generalised impulse from the speeds ``before`` setting group g's speed to
    ``target``, the latched groups held and a group on its stowed stop held if pushed
    back; the speeds after go to y. Returns group g's angular impulse [N*m*s]."""
    inverse = inverse_mass(cw, y, m)
    held = np.zeros(m)
    for k in range(m):
        held[k] = cw[group_at(W.G_LOCKED, k)]
    held[g] = 1.0
    impulse = np.zeros(m)
    for _ in range(m):
        impulse = _impulses(inverse, before, held, g, target)
        pushed = False
        for k in range(m):
            after = before[k]
            for c in range(m):
                after += inverse[k, c] * impulse[c]
            y[m + k] = after
            if held[k] == 0.0 and y[k] == 0.0 and after < 0.0:
                held[k] = 1.0
                pushed = True
        if not pushed:
            break
    for k in range(m):
        if held[k] != 0.0:
            y[m + k] = target if k == g else 0.0
    value: float = impulse[g]
    return value


def _latch_rows(
    cw: FloatArray,
    latches: FloatArray,
    t: float,
    y: FloatArray,
    g: int,
    ke: float,
    impulse: float,
    m: int,
) -> None:
    """The first arrival of group g: a latch row per hinge of the group, its first
    hinge's carrying the group's impulse."""
    cw[group_at(W.G_LATCH_ROW, g)] = cw[W.W_LATCHES]
    for j in range(int(cw[W.W_N])):
        if int(cw[hinge_at(W.H_GROUP, j)]) != g:
            continue
        row = int(cw[W.W_LATCHES])
        latches[row, W.LATCH_HINGE] = j
        latches[row, W.LATCH_TIME] = t
        latches[row, W.LATCH_SPEED] = cw[hinge_at(W.H_FACTOR, j)] * y[m + g]
        latches[row, W.LATCH_KE] = ke
        latches[row, W.LATCH_LOSS] = 0.0
        first = j == int(cw[group_at(W.G_FIRST, g)])
        latches[row, W.LATCH_IMPULSE] = impulse if first else math.nan
        cw[W.W_LATCHES] = row + 1


def rigid_latch(
    cw: FloatArray,
    y: FloatArray,
    t: float,
    g: int,
    events: FloatArray,
    latches: FloatArray,
    losses: FloatArray,
    m: int,
) -> None:
    """Group g reaches its rigid latch (module notes)."""
    first = int(cw[group_at(W.G_FIRST, g)])
    y[g] = cw[group_at(W.G_TRAVEL, g)]
    before = y[m : 2 * m].copy()
    ke = kinetic(cw, y, m)
    arriving = cw[group_at(W.G_ARRIVED, g)] == 0.0
    if arriving:
        cw[group_at(W.G_ARRIVED, g)] = 1.0
        cw[group_at(W.G_ARRIVAL_KE, g)] = ke
    e = cw[hinge_at(W.H_RESTITUTION, first)]
    impulse = impact(cw, y, before, g, -e * before[g], m)
    settled = False
    if e > 0.0:
        rebound = 0.5 * y[m + g] * y[m + g] / _free_inverse(cw, y, g, m)
        if rebound < SETTLE_FRACTION * cw[group_at(W.G_ARRIVAL_KE, g)]:
            impact(cw, y, before, g, 0.0, m)
            settled = True
    loss = ke - kinetic(cw, y, m)
    losses[first] += loss
    if arriving:
        _latch_rows(cw, latches, t, _with_speed(y, before, m), g, ke, impulse, m)
    latches[int(cw[group_at(W.G_LATCH_ROW, g)]), W.LATCH_LOSS] += loss
    if e == 0.0 or settled:
        cw[group_at(W.G_LOCKED, g)] = 1.0
        y[m + g] = 0.0
        _log_group(cw, events, t, W.EV_LATCH if e == 0.0 else W.EV_SETTLE, g)
    else:
        log_event(cw, events, t, W.EV_REBOUND, first)
    for k in range(m):
        locked = cw[group_at(W.G_LOCKED, k)] != 0.0
        cw[group_at(W.G_DIR, k)] = 0.0 if locked else _sign(y[m + k])


def _with_speed(y: FloatArray, before: FloatArray, m: int) -> FloatArray:
    """The state with the speeds before an impact (the arrival's)."""
    state = y.copy()
    for k in range(m):
        state[m + k] = before[k]
    return state


def _free_inverse(cw: FloatArray, y: FloatArray, g: int, m: int) -> float:
    """Group g's entry of the inverse mass matrix of the unlocked groups (its effective
    inverse inertia with the latched groups held)."""
    mass, _ = group_system(cw, y, m, False)
    count = 0
    for k in range(m):
        count += cw[group_at(W.G_LOCKED, k)] == 0.0 or k == g
    index = np.empty(count, dtype=np.int64)
    i = 0
    for k in range(m):
        if cw[group_at(W.G_LOCKED, k)] == 0.0 or k == g:
            index[i] = k
            i += 1
    unit = np.zeros(m)
    unit[g] = 1.0
    solution = solve_on(mass, unit, index)
    found = math.inf
    for r in range(count):
        if index[r] == g:
            found = solution[r]
    return found


def start_stop(
    cw: FloatArray, y: FloatArray, t: float, g: int, events: FloatArray, losses: FloatArray, m: int
) -> None:
    """Group g, moving back, reaches its stowed stop: a plastic impact stops it."""
    y[g] = 0.0
    before = y[m : 2 * m].copy()
    ke = kinetic(cw, y, m)
    impact(cw, y, before, g, 0.0, m)
    losses[int(cw[group_at(W.G_FIRST, g)])] += ke - kinetic(cw, y, m)
    cw[group_at(W.G_DIR, g)] = 0.0
    _log_group(cw, events, t, W.EV_START_STOP, g)


def _peaks(
    cw: FloatArray,
    y: FloatArray,
    f: FloatArray,
    y1: FloatArray,
    f1: FloatArray,
    h: float,
    stop: float,
    m: int,
) -> None:
    """The engaged compliant latches' largest |torque| over a step (ends and interior
    maxima of the torque's cubic, both signs), up to the fraction ``stop``."""
    for j in range(int(cw[W.W_N])):
        if cw[hinge_at(W.H_ENGAGED, j)] == 0.0:
            continue
        g = int(cw[hinge_at(W.H_GROUP, j)])
        factor = cw[hinge_at(W.H_FACTOR, j)]
        k = cw[hinge_at(W.H_LATCH_K, j)]
        c = cw[hinge_at(W.H_LATCH_C, j)]
        travel = cw[hinge_at(W.H_TRAVEL, j)]
        a0 = k * (factor * y[g] - travel) + c * factor * y[m + g]
        a1 = k * (factor * y1[g] - travel) + c * factor * y1[m + g]
        d0 = factor * (k * f[g] + c * f[m + g])
        d1 = factor * (k * f1[g] + c * f1[m + g])
        top = max(abs(a0), abs(a1) if stop >= 1.0 else 0.0)
        top = max(top, interior_peak(a0, d0, a1, d1, h, stop))
        top = max(top, interior_peak(-a0, -d0, -a1, -d1, h, stop))
        word = hinge_at(W.H_PEAK, j)
        cw[word] = max(cw[word], top)


def _end_peak(cw: FloatArray, y: FloatArray, m: int) -> None:
    """The engaged latches' |torque| at an event."""
    phi, rate = hinge_angles(cw, y, m)
    for j in range(int(cw[W.W_N])):
        word = hinge_at(W.H_PEAK, j)
        cw[word] = max(cw[word], abs(latch_torque(cw, j, phi[j], rate[j])))


def advance(
    cw: FloatArray, y: FloatArray, start: float, end: float, h: float, settings: FloatArray,
    atol: FloatArray, ws: tuple[FloatArray, ...], points: FloatArray,
    dm: tuple[int, ...], da: tuple[int, ...], dq: tuple[int, ...],
) -> tuple[int, float, float]:  # fmt: skip
    """Step the segment from y at ``start`` to its first event or ``end``; y is set to
    the state there. Returns (the event's slot or CAP, its time, the next step size)."""
    m = len(dm)
    n = y.shape[0]
    rows = ws[4]
    f, f1, g0, g1, active, trial = rows[0], rows[1], rows[2], rows[3], rows[4], rows[5]
    dummy = ws[5]
    rtol = settings[0]
    decide_flows(cw, y, m)
    chain_derivatives(cw, y, f, dm, da, dq)
    active_slots(cw, y, active, m)
    for slot in range(W.SLOTS):
        if active[slot] != 0.0:
            g0[slot] = chain_event_value(cw, slot, y, dummy, dummy, m, 0)
    limit = end - start
    t = 0.0
    stepper = start_stepper(cw, y, limit, rtol, atol, h, int(settings[1]), dm, da, dq)
    while True:
        h, h_next = attempt(stepper, cw, y, f, h, t, limit, rtol, atol, ws, dm, da, dq)
        if h <= 0.0:
            return FAILED, start + t, h_next
        y1 = ws[0][8]
        cw[W.W_STEPS] += 1
        chain_derivatives(cw, y1, f1, dm, da, dq)
        best = math.inf
        hit = -1
        for slot in range(W.SLOTS):
            if active[slot] == 0.0:
                continue
            g1[slot] = chain_event_value(cw, slot, y1, dummy, dummy, m, 0)
            if crossed(g0[slot], g1[slot]):
                s = locate(
                    cw, slot, y, f, y1, f1, h, g0[slot], g1[slot], trial, dummy, dummy, m, 0, n
                )
                if s < best:
                    best = s
                    hit = slot
        _peaks(cw, y, f, y1, f1, h, min(best, 1.0), m)
        if hit >= 0:
            interpolate(y, f, y1, f1, h, best, trial, n)
            for i in range(n):
                y[i] = trial[i]
            t += best * h
            record(cw, points, start + t, y, m)
            _end_peak(cw, y, m)
            return hit, start + t, h_next
        t += h
        for i in range(n):
            y[i] = y1[i]
            f[i] = f1[i]
        for slot in range(W.SLOTS):
            g0[slot] = g1[slot]
        record(cw, points, start + t, y, m)
        if t >= limit * (1.0 - 1e-15):
            return CAP, start + t, h_next
        h = h_next


def _join_friction(cw: FloatArray, j: int) -> None:
    """Hinge j's damper side engaged: its ECD's friction and breakaway join the hinge's
    and its group's (and its Stribeck excess, where it has a Stribeck speed)."""
    g = int(cw[hinge_at(W.H_GROUP, j)])
    factor = cw[hinge_at(W.H_FACTOR, j)]
    fe = cw[hinge_at(W.H_FE, j)]
    feb = cw[hinge_at(W.H_FEB, j)]
    cw[hinge_at(W.H_FRICTION, j)] += fe
    cw[hinge_at(W.H_BREAKAWAY, j)] += feb
    cw[group_at(W.G_FRICTION, g)] += factor * fe
    cw[group_at(W.G_BREAKAWAY, g)] += factor * feb
    if math.isfinite(cw[hinge_at(W.H_WST, j)]):
        excess = cw[hinge_at(W.H_BREAKAWAY, j)] - cw[hinge_at(W.H_FRICTION, j)]
        cw[hinge_at(W.H_EXCESS, j)] = max(excess, 0.0)


def engage_gear(
    cw: FloatArray, y: FloatArray, t: float, j: int, events: FloatArray, losses: FloatArray, m: int
) -> None:
    """Hinge j's lost motion closes: its damper side, idle in the gap, engages in a
    plastic impact with the chain, ``M_after psi'+ = M_before psi'-`` over the unlocked
    groups (the single hinge's engagement, its rotor seen through the gear driven
    forward: ``J_D / eta_f``); the kinetic energy lost goes to ``losses[n + j]``."""
    n = int(cw[W.W_N])
    g = int(cw[hinge_at(W.H_GROUP, j)])
    factor = cw[hinge_at(W.H_FACTOR, j)]
    y[g] = cw[hinge_at(W.H_GAP, j)] / factor
    before = kinetic(cw, y, m)
    mass, _ = group_system(cw, y, m, False)
    momentum = np.zeros(m)
    for r in range(m):
        for c in range(m):
            momentum[r] += mass[r, c] * y[m + c]
    cw[hinge_at(W.H_MESHED, j)] = 1.0
    _join_friction(cw, j)
    after, _ = group_system(cw, y, m, False)
    inertia = cw[hinge_at(W.H_JD, j)] * (1.0 / cw[hinge_at(W.H_ETAF, j)] - 1.0)
    after[g, g] += factor * factor * inertia
    index = _indices(1.0 - _locked(cw, m))
    speeds = solve_on(after, momentum, index)
    for r in range(index.shape[0]):
        k = index[r]
        y[m + k] = speeds[r]
        cw[group_at(W.G_DIR, k)] = 0.0 if speeds[r] == 0.0 else _sign(speeds[r])
    losses[n + j] += before - kinetic(cw, y, m)
    log_event(cw, events, t, W.EV_GEAR_ENGAGE, j)


def _locked(cw: FloatArray, m: int) -> FloatArray:
    """1.0 for each latched group, 0.0 for the rest."""
    flags = np.zeros(m)
    for k in range(m):
        flags[k] = cw[group_at(W.G_LOCKED, k)]
    return flags


def _all_held(cw: FloatArray, m: int) -> bool:
    """Every group at rest (stuck or latched)."""
    moving = 0
    for g in range(m):
        moving += cw[group_at(W.G_DIR, g)] != 0.0
    return moving == 0


def _finish_status(cw: FloatArray, m: int) -> int:
    """latched when every group is latched or held by its engaged compliant latch."""
    for g in range(m):
        if cw[group_at(W.G_LOCKED, g)] != 0.0:
            continue
        first = int(cw[group_at(W.G_FIRST, g)])
        if cw[hinge_at(W.H_ENGAGED, first)] == 0.0:
            return W.ST_STUCK
    return W.ST_LATCHED


def apply_event(
    cw: FloatArray,
    y: FloatArray,
    t: float,
    slot: int,
    events: FloatArray,
    latches: FloatArray,
    losses: FloatArray,
    m: int,
) -> None:
    """Apply the event of ``slot`` at time t (module notes)."""
    if slot < W.NMAX:
        g = slot
        first = int(cw[group_at(W.G_FIRST, g)])
        if cw[group_at(W.G_DIR, g)] != 0.0:
            y[m + g] = 0.0
            cw[group_at(W.G_DIR, g)] = 0.0
            log_event(cw, events, t, W.EV_ZERO, first)
            resolve_rest(cw, y, t, events, m)
            if cw[group_at(W.G_DIR, g)] == 0.0:
                log_event(cw, events, t, W.EV_STICK, first)
            return
        acc = np.empty(m)
        holding = np.empty(m)
        accelerations(cw, y, acc, holding, m)
        cw[group_at(W.G_DIR, g)] = -_sign(holding[g]) if holding[g] != 0.0 else 1.0
        _log_group(cw, events, t, W.EV_BREAKAWAY, g)
        resolve_rest(cw, y, t, events, m)
        return
    if slot < 2 * W.NMAX:
        g = slot - W.NMAX
        if cw[group_at(W.G_DIR, g)] < 0.0:
            start_stop(cw, y, t, g, events, losses, m)
            resolve_rest(cw, y, t, events, m)
        elif cw[group_at(W.G_RIGID, g)] != 0.0:
            rigid_latch(cw, y, t, g, events, latches, losses, m)
            resolve_rest(cw, y, t, events, m)
        else:
            y[g] = cw[group_at(W.G_TRAVEL, g)]
            for j in range(int(cw[W.W_N])):
                if int(cw[hinge_at(W.H_GROUP, j)]) == g:
                    cw[hinge_at(W.H_ENGAGED, j)] = 1.0
            cw[group_at(W.G_ARRIVED, g)] = 1.0
            _latch_rows(cw, latches, t, y, g, kinetic(cw, y, m), math.nan, m)
            _log_group(cw, events, t, W.EV_ENGAGE, g)
        return
    if slot >= W.GAP_SLOTS:  # a hinge's lost motion closes (module notes)
        engage_gear(cw, y, t, slot - W.GAP_SLOTS, events, losses, m)
        resolve_rest(cw, y, t, events, m)
        return
    if slot >= W.FLOW_SLOTS:  # a lossy gear's power flow switches (module notes)
        j = slot - W.FLOW_SLOTS
        cw[hinge_at(W.H_HINT, j)] = -cw[hinge_at(W.H_FLOW, j)]
        log_event(cw, events, t, W.EV_POWER_FLOW, j)
        return
    c = (slot - 2 * W.NMAX) // 2
    phi, rate = hinge_angles(cw, y, m)
    delta = cable_deflection(cw, c, phi)
    inboard = int(cw[cable_at(W.C_IN, c)])
    moving = rate[inboard + 1] - cw[cable_at(W.C_RATIO, c)] * rate[inboard]
    log_event(cw, events, t, W.EV_SLACK if delta * moving > 0.0 else W.EV_TAUT, -1)


def run_wing(
    cw: FloatArray, settings: FloatArray, atol: FloatArray, points: FloatArray,
    events: FloatArray, latches: FloatArray, losses: FloatArray,
    dm: tuple[int, ...], da: tuple[int, ...], dq: tuple[int, ...],
) -> FloatArray:  # fmt: skip
    """Run one wing case from release; returns its final state ``y``. ``settings`` =
    (rtol, integrator code); the status, counts and peaks are in ``cw``."""
    m = len(dm)
    n = 2 * m + len(da) + len(dq)
    y = np.zeros(n)
    for j in range(int(cw[W.W_N])):  # a warm start: the heating states at release
        aux = int(cw[hinge_at(W.H_AUX, j)])
        if aux >= 0:
            y[aux] = cw[hinge_at(W.H_S0, j)]
        housing = int(cw[hinge_at(W.H_HOUSING, j)])
        if housing >= 0:
            y[housing] = cw[hinge_at(W.H_H0, j)]
    work, jac, lu, pivot = new_work(n, m, len(da))
    ws = (work, jac, lu, pivot, np.zeros((6, max(n, W.SLOTS))), np.zeros(2))
    log_event(cw, events, 0.0, W.EV_RELEASE, -1)
    record(cw, points, 0.0, y, m)
    resolve_rest(cw, y, 0.0, events, m)
    t = 0.0
    h = 1e-4
    stop = cw[W.W_STOP]
    passes = 0
    while True:
        if _all_held(cw, m):
            cw[W.W_STATUS] = _finish_status(cw, m)
            if cw[W.W_STATUS] == W.ST_STUCK:
                log_event(cw, events, t, W.EV_STICK, -1)
            break
        if passes >= cw[W.W_MAX_EVENTS]:
            cw[W.W_STATUS] = W.ST_EVENT_LIMIT
            log_event(cw, events, t, W.EV_EVENT_LIMIT, -1)
            break
        end = min(stop, t + HORIZON)
        slot, t, h = advance(cw, y, t, end, h, settings, atol, ws, points, dm, da, dq)
        passes += 1
        if slot == FAILED:  # cut short, as at the event limit (never a wrong answer)
            cw[W.W_STATUS] = W.ST_EVENT_LIMIT
            log_event(cw, events, t, W.EV_EVENT_LIMIT, -1)
            break
        if slot == CAP:
            if t >= stop * (1.0 - 1e-15):
                cw[W.W_STATUS] = W.ST_STOP_TIME
                log_event(cw, events, t, W.EV_STOP_TIME, -1)
                break
            continue
        apply_event(cw, y, t, slot, events, latches, losses, m)
        record(cw, points, t, y, m)
    return y
