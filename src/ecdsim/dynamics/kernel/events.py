"""The events of a segment as functions of the state, and the rest rules that test them.

Each slot (:mod:`ecdsim.dynamics.kernel.layout`, ``SLOT_*``) is a function ``g(y)``
that is positive inside the segment's modes and reaches zero at its event:

* REACH: the load reaches its geometric event ahead (a spring breakpoint, the lost
  motion closing, the end of travel, the start stop);
* ZERO_k: sliding element k's speed falls to zero;
* BREAK_k: stuck element k's holding torque reaches its breakaway;
* MESH_A, MESH_B: the compliant mesh's flanks meet (in the gap), its limited torque
  reaches zero (pressing), the flank is reached again or the torque builds up again
  (released);
* SWITCH: a lossy gear's power flow reverses (the indicator of
  :func:`ecdsim.physics.gearing.power_flow_indicator` changes sign);
* CREEP: the speed falls below 1e-9 of its scale; accepted only short of a static
  equilibrium that exists ahead (an asymptotic approach to rest). Past it the speed
  reaches zero in finite time (a swing's turnaround); with no equilibrium ahead at all
  (a grazing bottleneck whose least push is still positive) the motion goes on.

:mod:`ecdsim.dynamics.kernel.integrate` locates them all on the step's dense output
with one locator; the closed form of :mod:`ecdsim.dynamics.kernel.closed` finds its own.
"""

from __future__ import annotations

import math

from ecdsim._types import FloatArray
from ecdsim.dynamics.kernel import layout as L
from ecdsim.dynamics.kernel.effects import registered_level, registered_torque
from ecdsim.dynamics.kernel.friction import STICK_MARGIN, capacity, drives, stuck_flags
from ecdsim.dynamics.kernel.hinge import factor_at, mesh_now
from ecdsim.dynamics.kernel.segment import flow_indicator


def active_slots(cw: FloatArray, active: FloatArray, m: int) -> None:
    """Which event slots the segment's modes arm (1.0) and which not (0.0)."""
    md = sg = cw
    for i in range(L.SLOTS):
        active[i] = 0.0
    sliding = md[L.MD_SLIDE0] != 0
    if sliding and sg[L.SG_REACH] >= 0.0:
        active[L.SLOT_REACH] = 1.0
    if sliding:
        active[L.SLOT_ZERO0] = 1.0
    elif m == 2 and md[L.MD_HELD] == 0:
        active[L.SLOT_BREAK0] = 1.0
    if m == 1:
        active[L.SLOT_CREEP] = 1.0
        if md[L.MD_FLOW] != 0:
            active[L.SLOT_SWITCH] = 1.0
        return
    if md[L.MD_SLIDE1] != 0:
        active[L.SLOT_ZERO1] = 1.0
    else:
        active[L.SLOT_BREAK1] = 1.0
    active[L.SLOT_MESH_A] = 1.0
    active[L.SLOT_MESH_B] = 1.0


def mesh_event(par: FloatArray, md: FloatArray, slot: int, delta: float, speed: float) -> float:
    """The compliant mesh's event functions in its mode (GAP: the forward flank A, the
    backward flank B; PRESS: the limited torque reaching zero, A; RELEASED: the torque
    building up again, A, or the flank reached, B)."""
    half = 0.5 * par[L.GAP]
    mode = md[L.MD_MESH]
    side = md[L.MD_SIDE]
    if mode == L.PRESS:
        if slot == L.SLOT_MESH_A:
            value: float = side * (par[L.MC] * (delta - side * half) + par[L.MD] * speed)
            return value
        return math.inf
    if mode == L.RELEASED:
        if slot == L.SLOT_MESH_A:
            again: float = -side * (par[L.MC] * (delta - side * half) + par[L.MD] * speed)
            return again
        back: float = side * (delta - side * half)
        return back
    if slot == L.SLOT_MESH_A:
        return float(half - delta)
    return float(delta + half)


def indicator(cw: FloatArray, y: FloatArray, m: int, na: int) -> float:
    """A lossy gear's power-flow indicator times the segment's flow (> 0 while the flow
    is the segment's: :func:`ecdsim.dynamics.kernel.segment.flow_indicator`)."""
    md = cw
    value = flow_indicator(cw, y[0], y[1], factor_at(cw, y, m, na), int(md[L.MD_SLIDE0]))
    flow: float = md[L.MD_FLOW]
    return flow * value


def held_value(
    cw: FloatArray, k: int, y: FloatArray, scratch: FloatArray, column: FloatArray, m: int, na: int
) -> float:
    """Stuck element k's breakaway event: its capacity less the torque it holds (less the
    drive itself where the load is pressed into the start stop, which holds backward)."""
    md = cw
    stuck_flags(cw, scratch, m)
    drives(cw, y, scratch, column, m, na)
    drive = column[m + k]
    limit = capacity(cw, k, drive, m) * (1.0 + STICK_MARGIN)
    at_start = k == 0 and md[L.MD_START] != 0
    value: float = limit - (drive if at_start else abs(drive))
    return value


def event_value(
    cw: FloatArray, slot: int, y: FloatArray, scratch: FloatArray, column: FloatArray, m: int,
    na: int,
) -> float:  # fmt: skip
    """The value of event function ``slot`` at state y (> 0 before its event)."""
    par = md = sg = cw
    if slot == L.SLOT_REACH:
        value: float = md[L.MD_SLIDE0] * (sg[L.SG_TARGET] - y[0])
        return value
    if slot == L.SLOT_ZERO0:
        load: float = md[L.MD_SLIDE0] * y[m]
        return load
    if slot == L.SLOT_CREEP:
        creep: float = md[L.MD_SLIDE0] * y[m] - sg[L.SG_CREEP]
        return creep
    if slot == L.SLOT_ZERO1:
        damper: float = md[L.MD_SLIDE1] * (y[2] - y[3])
        return damper
    if slot in (L.SLOT_MESH_A, L.SLOT_MESH_B):
        return mesh_event(par, md, slot, y[1], y[3])
    if slot == L.SLOT_SWITCH:
        return indicator(cw, y, m, na)
    return held_value(cw, 0 if slot == L.SLOT_BREAK0 else 1, y, scratch, column, m, na)


def rest_push(cw: FloatArray, x: float) -> float:
    """The push at rest on the rigid hinge at displacement x from the segment's start:
    ``sigma (T_s - G) - F_brk`` along the motion, the drive less the breakaway friction
    (kinetic plus the Stribeck excess at rest; the damping vanishes at rest). Positive
    while the load is short of its static equilibrium."""
    md = sg = cw
    sigma = md[L.MD_SLIDE0]
    torque = sg[L.SG_T0] + sg[L.SG_SLOPE] * x + registered_torque(cw, sg[L.SG_PHI] + x, 0.0)[0]
    value: float = sigma * torque - (sg[L.SG_FC0] + sg[L.SG_EX0])
    return value


def equilibrium_ahead(cw: FloatArray, x: float) -> bool:
    """Whether the push at rest vanishes somewhere between x and the segment's geometric
    event ahead: a static equilibrium the load can come to rest at.

    The push is the linear spring piece plus the registered torques: its least value
    over the interval is at an end or where its slope vanishes, the angles each effect
    lists where its stiffness is minus the spring's (``effects.registered_level``: for
    gravity ``W cos(theta_0 + phi) = k``), each of which is examined (issue 23 item 8: a
    grazing bottleneck has none).
    """
    sg = cw
    end = sg[L.SG_TARGET]
    if rest_push(cw, end) <= 0.0:
        return True
    origin = sg[L.SG_PHI]  # the registry's angles are deployed angles: origin + x
    lo = min(x, end) + origin
    hi = max(x, end) + origin
    i = 0
    while True:
        angle = registered_level(cw, sg[L.SG_SLOPE], lo, hi, i)
        if math.isnan(angle):
            return False
        if lo <= angle <= hi and rest_push(cw, angle - origin) <= 0.0:
            return True
        i += 1


def accept_creep(cw: FloatArray, y: FloatArray) -> bool:
    """A creep crossing is an asymptotic approach to rest: short of an equilibrium (the
    push at rest still forward) that exists ahead."""
    x = y[0]
    return rest_push(cw, x) > 0.0 and equilibrium_ahead(cw, x)


def compliant_creeping(
    cw: FloatArray, y: FloatArray, threshold: float, torque_scale: float, scratch: FloatArray,
    column: FloatArray, na: int,
) -> bool:  # fmt: skip
    """Both speeds negligible and both bodies within their breakaway (with a slack of
    1e3 times the creep fraction of the drive, the damping's share at these speeds), a
    static equilibrium at hand: at rest for good (compliant mesh)."""
    md = cw
    if abs(y[2]) > threshold or abs(y[2] - y[3]) > threshold:
        return False
    saved0 = md[L.MD_SLIDE0]
    saved1 = md[L.MD_SLIDE1]
    md[L.MD_SLIDE0] = 0
    md[L.MD_SLIDE1] = 0
    stuck_flags(cw, scratch, 2)
    drives(cw, y, scratch, column, 2, na)
    md[L.MD_SLIDE0] = saved0
    md[L.MD_SLIDE1] = saved1
    slack = 1e3 * 1e-9 * torque_scale
    load = column[2]
    damper = column[3]
    tau = mesh_now(cw, md, y[1], 0.0)
    held = md[L.MD_HELD] != 0
    load_ok = held or abs(load) <= capacity(cw, 0, load, 2) + slack
    return load_ok and abs(tau) <= capacity(cw, 1, damper, 2) + slack
