"""What the load's geometric events and the compliant mesh's events do to the state.

The end of travel latches the load or bounces it back (Newton's restitution,
:func:`ecdsim.physics.mechanics.rebound`), the rebounds settling once they carry less
than 1e-12 of the reference impact's kinetic energy; the start stop likewise. The rigid
mesh's lost motion closes with a plastic impact that conserves angular momentum
(:func:`ecdsim.physics.mechanics.plastic_engagement`; through a lossy gear driven
forward). A compliant mesh's flanks meet, part, and meet again (MSL ElastoBacklash2's
modes: gap, pressing, released). With a compliant mesh the load held at the end of
travel (latched, or its rebounds settled) stays held while the damper side turns on.
"""

from __future__ import annotations

import math

from ecdsim._types import FloatArray
from ecdsim.dynamics.kernel import layout as L
from ecdsim.dynamics.kernel.record import Buffers, log_event
from ecdsim.physics.mechanics import kinetic_energy, plastic_engagement, rebound

# After an impact, a rebound whose kinetic energy is below this fraction of the reference
# impact's is taken as coming to rest against the stop (the remaining bounces form a
# convergent geometric series of vanishing energy).
SETTLE_FRACTION = 1e-12
_TINY = 2.2250738585072014e-308


def set_load_speed(y: FloatArray, speed: float, m: int) -> None:
    """The load's speed jumps (an impact, a latch) while the damper side's is kept (a
    compliant mesh's relative speed changes with it)."""
    if m == 2:
        y[3] += speed - y[2]
        y[2] = speed
    else:
        y[1] = speed


def engage(
    cw: FloatArray, y: FloatArray, t: float, phi: float, out: FloatArray, buffers: Buffers,
    counts: FloatArray, index: int,
) -> None:  # fmt: skip
    """The rigid mesh's lost motion closes: a plastic tooth impact (through a lossy gear
    driven forward, the damper side's inertia seen as J_D / eta_f)."""
    par = md = cw
    log_event(buffers, counts, index, t, L.EV_ENGAGE, phi, y[1])
    w = y[1]
    after, loss = plastic_engagement(par[L.JL], w, par[L.JD])
    if par[L.ETAF] != 1.0:
        after = par[L.JL] * w / (par[L.JL] + par[L.JD] / par[L.ETAF])
        loss = kinetic_energy(par[L.JL], w) - kinetic_energy(par[L.JL] + par[L.JD], after)
    y[1] = after
    out[L.OUT_ENGAGEMENT_LOSS] += loss
    md[L.MD_ENGAGED] = 1.0
    out[L.OUT_ENGAGEMENT_TIME] = t


def _arrival(cw: FloatArray, y: FloatArray, t: float, out: FloatArray, m: int) -> float:
    """Book the first arrival at the end of travel; the kinetic energy arriving."""
    par = md = cw
    if m == 1:
        inertia = par[L.JL] + par[L.JD] if md[L.MD_ENGAGED] != 0 else par[L.JL]
        ke = float(kinetic_energy(inertia, y[1]))
    else:
        ke = float(kinetic_energy(par[L.JL], y[2]) + kinetic_energy(par[L.JD], y[2] - y[3]))
    if not math.isfinite(out[L.OUT_ARRIVAL_TIME]):
        out[L.OUT_ARRIVAL_TIME] = t
        out[L.OUT_ARRIVAL_SPEED] = y[m]
        out[L.OUT_ARRIVAL_KE] = ke
    return ke


def hold(cw: FloatArray, y: FloatArray, out: FloatArray, status: int, m: int) -> None:
    """A compliant mesh's load held at the end of travel (its kinetic energy taken by
    the latch); the damper side turns on until it comes to rest."""
    md = cw
    out[L.OUT_IMPACT_LOSS] += kinetic_energy(cw[L.JL], y[2])
    set_load_speed(y, 0.0, m)
    md[L.MD_SLIDE0] = 0.0
    md[L.MD_START] = 0.0
    md[L.MD_HELD] = status


def stop_impact(
    cw: FloatArray, y: FloatArray, t: float, phi: float, arriving: bool, out: FloatArray,
    buffers: Buffers, counts: FloatArray, index: int, m: int,
) -> int:  # fmt: skip
    """The load on a stop: the end of travel (``arriving``) or the start stop. Returns
    the status the run ends with (a rigid latch or settle), else 0."""
    par = md = cw
    w = y[m]
    log_event(buffers, counts, index, t, L.EV_ARRIVE if arriving else L.EV_START_STOP, phi, w)
    engaged = m == 1 and md[L.MD_ENGAGED] != 0
    inertia = par[L.JL] + par[L.JD] if engaged else par[L.JL]
    ke = float(kinetic_energy(inertia, w))
    if arriving:
        _arrival(cw, y, t, out, m)
    e = par[L.REST]
    if e <= 0.0:
        if arriving:
            log_event(buffers, counts, index, t, L.EV_LATCH, phi, w)
            if m == 1:
                return L.ST_LATCHED
            hold(cw, y, out, L.ST_LATCHED, m)
            return 0
        out[L.OUT_IMPACT_LOSS] += ke
        set_load_speed(y, 0.0, m)
        md[L.MD_SLIDE0] = 0.0
        return 0
    return _bounce(cw, y, t, phi, arriving, ke, inertia, out, buffers, counts, index, m)


def _bounce(
    cw: FloatArray, y: FloatArray, t: float, phi: float, arriving: bool, ke: float,
    inertia: float, out: FloatArray, buffers: Buffers, counts: FloatArray, index: int, m: int,
) -> int:  # fmt: skip
    """A rebound off a stop, or its settling when the rebound would carry less than
    SETTLE_FRACTION of the reference impact (the first arrival's, or the largest on the
    start stop)."""
    par = md = cw
    w = y[m]
    after_, loss_ = rebound(w, par[L.REST], inertia)
    after, loss = float(after_), float(loss_)
    largest = ke
    if not arriving:
        largest = max(out[L.OUT_START_KE], ke)
        out[L.OUT_START_KE] = largest
    reference = max(max(out[L.OUT_ARRIVAL_KE], largest), _TINY)
    settle = ke - loss <= SETTLE_FRACTION * reference
    if arriving and md[L.MD_IMPACTS] == 0 and not settle:
        out[L.OUT_REBOUND_SPEED] = after
    md[L.MD_IMPACTS] += 1.0
    out[L.OUT_IMPACT_LOSS] += ke if settle else loss
    if not settle:
        set_load_speed(y, after, m)
        md[L.MD_SLIDE0] = 1.0 if after > 0.0 else -1.0
        return 0
    set_load_speed(y, 0.0, m)
    md[L.MD_SLIDE0] = 0.0
    if not arriving:
        return 0
    log_event(buffers, counts, index, t, L.EV_SETTLE, phi, 0.0)
    if m == 1:
        return L.ST_SETTLED
    hold(cw, y, out, L.ST_SETTLED, m)
    return 0


def _enter_gap(
    cw: FloatArray, y: FloatArray, t: float, phi: float, buffers: Buffers, counts: FloatArray,
    index: int, logged: bool,
) -> None:  # fmt: skip
    """Back inside the gap; without lost motion the other flank is met at once."""
    par = md = cw
    if md[L.MD_MESH] == L.PRESS and not logged:
        log_event(buffers, counts, index, t, L.EV_SEPARATE, phi, y[2])
    md[L.MD_MESH] = L.MESH_GAP
    if par[L.GAP] <= 0.0 and y[3] != 0.0:
        md[L.MD_MESH] = L.PRESS
        md[L.MD_SIDE] = 1.0 if y[3] > 0.0 else -1.0
        log_event(buffers, counts, index, t, L.EV_CONTACT, phi, y[2])


def mesh_event(
    cw: FloatArray, y: FloatArray, t: float, phi: float, forward_flank: bool, out: FloatArray,
    buffers: Buffers, counts: FloatArray, index: int,
) -> None:  # fmt: skip
    """A compliant mesh's event: the flanks meet (engage the first time, contact after),
    the limited torque reaches zero (released while deflected and damped, else back in
    the gap), a released mesh presses again or re-enters the gap."""
    par = md = cw
    mode = md[L.MD_MESH]
    if mode == L.MESH_GAP:
        md[L.MD_MESH] = L.PRESS
        md[L.MD_SIDE] = 1.0 if forward_flank else -1.0
        if not math.isfinite(out[L.OUT_ENGAGEMENT_TIME]):
            out[L.OUT_ENGAGEMENT_TIME] = t
            log_event(buffers, counts, index, t, L.EV_ENGAGE, phi, y[2])
        else:
            log_event(buffers, counts, index, t, L.EV_CONTACT, phi, y[2])
        return
    side = md[L.MD_SIDE]
    deflection = side * (y[1] - side * 0.5 * par[L.GAP])
    if mode == L.PRESS:
        if deflection > 0.0 and par[L.MD] > 0.0:
            md[L.MD_MESH] = L.RELEASED
            log_event(buffers, counts, index, t, L.EV_SEPARATE, phi, y[2])
        else:
            _enter_gap(cw, y, t, phi, buffers, counts, index, False)
        return
    if forward_flank:
        md[L.MD_MESH] = L.PRESS
        log_event(buffers, counts, index, t, L.EV_CONTACT, phi, y[2])
    else:
        _enter_gap(cw, y, t, phi, buffers, counts, index, True)


def resolve_mesh(
    cw: FloatArray, y: FloatArray, t: float, phi: float, buffers: Buffers, counts: FloatArray,
    index: int,
) -> None:  # fmt: skip
    """The mesh's mode after a jump of the speeds (an impact on a stop, a settle): a jump
    of the relative speed changes the limited torque at once."""
    par = md = cw
    mode = md[L.MD_MESH]
    if mode == L.MESH_GAP:
        return
    side = md[L.MD_SIDE]
    deflection = side * (y[1] - side * 0.5 * par[L.GAP])
    raw = side * (par[L.MC] * (deflection * side) + par[L.MD] * y[3])
    if mode == L.PRESS and raw <= 0.0:
        if deflection > 0.0 and par[L.MD] > 0.0:
            md[L.MD_MESH] = L.RELEASED
            log_event(buffers, counts, index, t, L.EV_SEPARATE, phi, y[2])
        else:
            _enter_gap(cw, y, t, phi, buffers, counts, index, False)
    elif mode == L.RELEASED and deflection <= 0.0:
        _enter_gap(cw, y, t, phi, buffers, counts, index, True)
    elif mode == L.RELEASED and raw > 0.0:
        md[L.MD_MESH] = L.PRESS
        log_event(buffers, counts, index, t, L.EV_CONTACT, phi, y[2])
