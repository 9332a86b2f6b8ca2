"""The event-driven solver of the dynamic deployment, vectorised over a batch of cases.

Every loop iteration takes all cases still running, decides for those at rest whether
they stick for good or break away, builds each case's current segment (constant inertia,
damping, friction direction and spring slope), advances it to its first event (closed
form for linear segments, :mod:`ecdsim.dynamics.integrate` for roll-off and heating) and
applies the events: lost motion closing, spring breakpoints, end of travel (latch or
rebound), zero speed, stop time, asymptotic rest. See ``docs/dynamics.md``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import BoolArray, FloatArray
from ecdsim.dynamics import integrate, linear
from ecdsim.dynamics.damping import EddyLaw
from ecdsim.dynamics.problem import DynamicProblem
from ecdsim.dynamics.records import ClosedFormRecord, IntegratedRecord
from ecdsim.dynamics.result import (
    EVENT_KINDS,
    STATUSES,
    DynamicResult,
    EnergyBalance,
    EventLog,
    TrajectoryData,
)
from ecdsim.physics import mechanics

# A breakaway needs the drive to exceed static friction by more than this relative margin;
# at the boundary (a forward motion that stops where drive = kinetic friction = static
# friction) rounding must not restart the motion: that would be numerical chatter.
_STICK_MARGIN = 1e-12
# After an impact, a rebound whose kinetic energy is below this fraction of the first
# arrival's is taken as coming to rest against the stop (the remaining bounces form a
# convergent geometric series of vanishing energy).
_SETTLE_FRACTION = 1e-12

_EV = {name: code for code, name in enumerate(EVENT_KINDS)}
_ST = {name: code for code, name in enumerate(STATUSES)}


@dataclass
class _Cases:
    """The problem's per-case arrays, flattened to 1-D (n cases)."""

    n: int
    angles: FloatArray  # (points, n)
    torques: FloatArray  # (points, n)
    travel: FloatArray
    load_inertia: FloatArray
    total_inertia: FloatArray
    damper_inertia: FloatArray
    damping: FloatArray
    ecd_friction: FloatArray
    system_friction: FloatArray
    factor: FloatArray
    system_factor: FloatArray
    restitution: FloatArray
    gap: FloatArray
    angle0: FloatArray
    speed0: FloatArray
    ambient: FloatArray
    ratio: FloatArray
    gearbox_damping: FloatArray
    heat_capacity: FloatArray
    thermal_resistance: FloatArray
    eddy: EddyLaw


def _flatten(problem: DynamicProblem) -> _Cases:
    shape = problem.batch_shape
    n = int(np.prod(shape)) if shape else 1
    points = problem.angles.shape[0]

    def flat(a: FloatArray) -> FloatArray:
        return np.ascontiguousarray(np.broadcast_to(a, shape).reshape(n), dtype=float)

    return _Cases(
        n=n,
        angles=np.ascontiguousarray(problem.angles.reshape(points, n), dtype=float),
        torques=np.ascontiguousarray(problem.torques.reshape(points, n), dtype=float),
        travel=flat(problem.travel),
        load_inertia=flat(problem.load_inertia),
        total_inertia=flat(problem.total_inertia),
        damper_inertia=flat(problem.damper_inertia),
        damping=flat(problem.damping_rate),
        ecd_friction=flat(problem.ecd_friction),
        system_friction=flat(problem.system_friction),
        factor=flat(problem.static_friction_factor),
        system_factor=flat(problem.system_static_friction_factor),
        restitution=flat(problem.restitution),
        gap=flat(problem.lost_motion),
        angle0=flat(problem.initial_angle),
        speed0=flat(problem.initial_speed),
        ambient=flat(problem.ambient_temperature),
        ratio=flat(problem.gear_ratio),
        gearbox_damping=flat(problem.gearbox_damping_rate),
        heat_capacity=flat(problem.heat_capacity),
        thermal_resistance=flat(problem.thermal_resistance),
        eddy=problem.eddy.flattened(shape),
    )


@dataclass(frozen=True)
class _Piece:
    """The spring piece each case is on, for its direction of motion."""

    lower: FloatArray  # angle of the piece's start [rad]
    upper: FloatArray  # angle of the piece's end [rad]
    torque: FloatArray  # spring torque at the current angle [N*m]
    stiffness: FloatArray  # k = -dT/dphi on the piece [N*m/rad]


def _piece(c: _Cases, idx: NDArray[np.intp], phi: FloatArray, forward: BoolArray) -> _Piece:
    """Piecewise-linear spring lookup per case (each case has its own breakpoints)."""
    angles = c.angles[:, idx]
    torques = c.torques[:, idx]
    interior = angles[1:-1]
    at_or_below = np.sum(interior <= phi, axis=0)
    below = np.sum(interior < phi, axis=0)
    i = np.where(forward, at_or_below, below).astype(np.intp)
    cols = np.arange(idx.size)
    a0, a1 = angles[i, cols], angles[i + 1, cols]
    t0, t1 = torques[i, cols], torques[i + 1, cols]
    width = a1 - a0
    slope = np.where(width > 0.0, (t1 - t0) / np.where(width > 0.0, width, 1.0), 0.0)
    return _Piece(lower=a0, upper=a1, torque=t0 + slope * (phi - a0), stiffness=-slope)


class _Log:
    """Accumulates events as flat arrays."""

    def __init__(self) -> None:
        self.parts: list[tuple[NDArray[np.intp], FloatArray, int, FloatArray, FloatArray]] = []

    def add(
        self,
        case: NDArray[np.intp],
        time: FloatArray,
        kind: str,
        angle: FloatArray,
        speed: FloatArray,
    ) -> None:
        if case.size:
            self.parts.append((case.copy(), time.copy(), _EV[kind], angle.copy(), speed.copy()))

    def build(self) -> EventLog:
        if not self.parts:
            empty = np.zeros(0)
            return EventLog(np.zeros(0, np.intp), empty, np.zeros(0, np.int8), empty, empty)
        case = np.concatenate([p[0] for p in self.parts])
        time = np.concatenate([p[1] for p in self.parts])
        kind = np.concatenate([np.full(p[0].size, p[2], np.int8) for p in self.parts])
        angle = np.concatenate([p[3] for p in self.parts])
        speed = np.concatenate([p[4] for p in self.parts])
        order = np.lexsort((np.arange(case.size), case))
        return EventLog(case[order], time[order], kind[order], angle[order], speed[order])


@dataclass
class _State:
    """The running state of every case (flat arrays, updated in place)."""

    t: FloatArray
    phi: FloatArray
    w: FloatArray
    temp: FloatArray
    heat: FloatArray  # the damper's temperature state s (its damping law's log factor)
    engaged: BoolArray
    engage_angle: FloatArray
    done: BoolArray
    status: NDArray[np.int8]
    hold_from: FloatArray  # when the final state begins (for time series)
    display_end: FloatArray  # where a plot of the case should end
    arrival_time: FloatArray
    arrival_speed: FloatArray
    arrival_ke: FloatArray
    stuck: BoolArray
    stuck_angle: FloatArray
    stuck_time: FloatArray
    engagement_time: FloatArray
    rebound_speed: FloatArray
    impacts: NDArray[np.int64]
    max_speed: FloatArray
    max_temp: FloatArray
    spring_work: FloatArray
    friction_work: FloatArray
    damper_work: FloatArray
    engagement_loss: FloatArray
    impact_loss: FloatArray

    @classmethod
    def initial(cls, c: _Cases) -> _State:
        n = c.n
        engaged = c.gap <= 0.0
        return cls(
            t=np.zeros(n),
            phi=c.angle0.copy(),
            w=c.speed0.copy(),
            temp=c.ambient.copy(),
            heat=np.zeros(n),
            engaged=engaged,
            engage_angle=c.angle0 + c.gap,
            done=np.zeros(n, dtype=bool),
            status=np.zeros(n, dtype=np.int8),
            hold_from=np.zeros(n),
            display_end=np.zeros(n),
            arrival_time=np.full(n, np.inf),
            arrival_speed=np.zeros(n),
            arrival_ke=np.zeros(n),
            stuck=np.zeros(n, dtype=bool),
            stuck_angle=np.full(n, np.nan),
            stuck_time=np.full(n, np.nan),
            engagement_time=np.where(engaged, 0.0, np.inf),
            rebound_speed=np.zeros(n),
            impacts=np.zeros(n, dtype=np.int64),
            max_speed=np.maximum(c.speed0, 0.0),
            max_temp=c.ambient.copy(),
            spring_work=np.zeros(n),
            friction_work=np.zeros(n),
            damper_work=np.zeros(n),
            engagement_loss=np.zeros(n),
            impact_loss=np.zeros(n),
        )

    def finish(self, idx: NDArray[np.intp], status: str) -> None:
        """Mark cases as finished with a status."""
        self.done[idx] = True
        self.status[idx] = _ST[status]


def solve_dynamic(problem: DynamicProblem, record: bool = True) -> DynamicResult:
    """Solve every case of ``problem``; ``record`` keeps the segments for time series."""
    c = _flatten(problem)
    s = _State.initial(c)
    ke0 = mechanics.kinetic_energy(np.where(s.engaged, c.total_inertia, c.load_inertia), s.w)
    log = _Log()
    records: _Records | None = _Records([], []) if record else None
    log.add(np.arange(c.n), s.t, "release", s.phi, s.w)

    for iteration in range(problem.max_events + 1):
        active = np.flatnonzero(~s.done)
        if active.size == 0:
            break
        if iteration == problem.max_events:
            s.finish(active, "event_limit")
            log.add(active, s.t[active], "event_limit", s.phi[active], s.w[active])
            break
        direction = np.zeros(c.n)
        resting = active[s.w[active] == 0.0]
        if resting.size:
            _stick_or_break(c, s, resting, direction, log)
        moving = active[s.w[active] != 0.0]
        direction[moving] = np.sign(s.w[moving])
        run = np.flatnonzero(~s.done & (direction != 0.0))
        if run.size:
            _advance_cases(c, s, run, direction[run], problem, log, records)

    final_inertia = np.where(s.engaged, c.total_inertia, c.load_inertia)
    keeps_speed = np.isin(
        s.status, [_ST[k] for k in ("latched", "stop_time", "event_limit", "horizon")]
    )
    final_speed = np.where(keeps_speed, s.w, 0.0)
    energy = EnergyBalance(
        spring_work=s.spring_work,
        initial_kinetic_energy=ke0,
        damper_dissipation=s.damper_work,
        friction_dissipation=s.friction_work,
        engagement_loss=s.engagement_loss,
        impact_loss=s.impact_loss,
        final_kinetic_energy=mechanics.kinetic_energy(final_inertia, final_speed),
    )
    shape = problem.batch_shape
    trajectory = None
    if records is not None:
        display = np.where(np.isfinite(s.t), s.t, s.display_end)
        trajectory = TrajectoryData(
            closed=records.closed,
            integrated=records.integrated,
            initial=(c.angle0, c.speed0, c.ambient, c.gap <= 0.0),
            final=(s.phi.copy(), final_speed, s.temp.copy(), s.engaged.copy(), s.hold_from),
            display_end=display,
            angles=c.angles,
            torques=c.torques,
            ecd_friction=c.ecd_friction,
            system_friction=c.system_friction,
            factor=c.factor,
            system_factor=c.system_factor,
            ratio=c.ratio,
            gearbox_damping=c.gearbox_damping,
            eddy=c.eddy,
        )

    def shaped(a: NDArray[Any]) -> NDArray[Any]:
        return a.reshape(shape)

    return DynamicResult(
        batch_shape=shape,
        temperature=shaped(c.ambient),
        deployment_time=shaped(s.arrival_time),
        arrival_speed=shaped(s.arrival_speed),
        arrival_kinetic_energy=shaped(s.arrival_ke),
        final_time=shaped(s.t),
        final_angle=shaped(s.phi),
        final_speed=shaped(final_speed),
        final_temperature=shaped(s.temp),
        stuck=shaped(s.stuck),
        stuck_angle=shaped(s.stuck_angle),
        stuck_time=shaped(s.stuck_time),
        max_speed=shaped(s.max_speed),
        max_damper_temperature=shaped(s.max_temp),
        engagement_time=shaped(s.engagement_time),
        rebound_speed=shaped(s.rebound_speed),
        impacts=shaped(s.impacts),
        status=shaped(s.status),
        energy=energy.reshaped(shape),
        events=log.build(),
        trajectory=trajectory,
    )


@dataclass(frozen=True)
class _Records:
    closed: list[ClosedFormRecord]
    integrated: list[IntegratedRecord]


def _stick_or_break(
    c: _Cases, s: _State, resting: NDArray[np.intp], direction: FloatArray, log: _Log
) -> None:
    """At rest: stick for good if the spring cannot beat static friction, else break away."""
    piece = _piece(c, resting, s.phi[resting], np.ones(resting.size, dtype=bool))
    # Each friction breaks away at its own factor: the ECD's (when engaged) and the
    # system's FS_T (hinge, harness), which is not the damper's breakaway.
    static = mechanics.static_friction(
        c.system_friction[resting], c.system_factor[resting]
    ) + np.where(
        s.engaged[resting],
        mechanics.static_friction(c.ecd_friction[resting], c.factor[resting]),
        0.0,
    )
    drive = piece.torque
    holds = np.abs(drive) <= static + _STICK_MARGIN * np.maximum(np.abs(drive), static)
    sticking = resting[holds]
    s.finish(sticking, "stuck")
    s.stuck[sticking] = True
    s.stuck_angle[sticking] = s.phi[sticking]
    s.stuck_time[sticking] = s.t[sticking]
    log.add(sticking, s.t[sticking], "stick", s.phi[sticking], s.w[sticking])
    moving_off = resting[~holds]
    direction[moving_off] = np.sign(drive[~holds])
    log.add(moving_off, s.t[moving_off], "breakaway", s.phi[moving_off], s.w[moving_off])


def _advance_cases(
    c: _Cases,
    s: _State,
    run: NDArray[np.intp],
    direction: FloatArray,
    problem: DynamicProblem,
    log: _Log,
    records: _Records | None,
) -> None:
    """Advance the cases ``run`` through one segment each and apply their events."""
    forward = direction > 0.0
    phi_r = s.phi[run]
    t_r = s.t[run]
    piece = _piece(c, run, phi_r, forward)
    eng = s.engaged[run]
    # Distance to the first geometric event and its kind, in the direction of motion.
    up_length = piece.upper - phi_r
    up_kind = np.where(piece.upper >= c.travel[run], _EV["arrive"], _EV["breakpoint"])
    gap_length = s.engage_angle[run] - phi_r
    gap_first = forward & ~eng & (gap_length <= up_length)
    down_kind = np.where(piece.lower <= 0.0, _EV["start_stop"], _EV["breakpoint"])
    length = np.maximum(
        np.where(forward, np.where(gap_first, gap_length, up_length), phi_r - piece.lower), 0.0
    )
    reach_kind = np.where(forward, np.where(gap_first, _EV["engage"], up_kind), down_kind)

    inertia = np.where(eng, c.total_inertia[run], c.load_inertia[run])
    damping = np.where(eng, c.damping[run], 0.0)
    kinetic = np.where(eng, c.ecd_friction[run] + c.system_friction[run], c.system_friction[run])
    # Forward frame: J x'' + B x' + k x = a with x = direction * (phi - phi_start).
    drive = np.where(forward, piece.torque - kinetic, -(piece.torque + kinetic))
    speed0 = direction * s.w[run]
    cap = np.maximum(problem.stop_time - t_r, 0.0)

    m = run.size
    kind = np.zeros(m, dtype=np.int8)
    duration = np.zeros(m)
    x = np.zeros(m)
    v = np.zeros(m)
    work_damper = np.zeros(m)
    peak_speed = np.zeros(m)
    temp_end = s.temp[run].copy()
    temp_peak = s.temp[run].copy()
    display = np.zeros(m)

    integrate_mask = eng & problem.nonlinear
    closed_idx = np.flatnonzero(~integrate_mask)
    if closed_idx.size:
        seg = linear.segment(
            inertia[closed_idx],
            damping[closed_idx],
            piece.stiffness[closed_idx],
            drive[closed_idx],
            speed0[closed_idx],
        )
        adv = linear.advance(seg, length[closed_idx], cap[closed_idx])
        kind[closed_idx] = adv.kind
        duration[closed_idx] = adv.duration
        x[closed_idx] = adv.x
        v[closed_idx] = adv.v
        work_damper[closed_idx] = damping[closed_idx] * adv.speed_squared_integral
        peak_speed[closed_idx] = adv.max_speed
        # A plot of an asymptotic approach to rest ends after 10 slow time constants.
        display[closed_idx] = t_r[closed_idx] + linear.rest_time(seg) / 80.0
        if records is not None:
            records.closed.append(
                ClosedFormRecord(
                    case=run[closed_idx],
                    start_time=t_r[closed_idx],
                    duration=adv.duration,
                    start_angle=phi_r[closed_idx],
                    direction=direction[closed_idx],
                    engaged=eng[closed_idx],
                    temperature=s.temp[run[closed_idx]],
                    segment=seg,
                )
            )
    nl_idx = np.flatnonzero(integrate_mask)
    if nl_idx.size:
        cases = run[nl_idx]
        out = integrate.advance_nonlinear(
            integrate.NonlinearSegments(
                inertia=inertia[nl_idx],
                stiffness=piece.stiffness[nl_idx],
                drive=drive[nl_idx],
                speed0=speed0[nl_idx],
                length=length[nl_idx],
                cap=cap[nl_idx],
                state0=s.heat[cases],
                ambient=c.ambient[cases],
                ratio=c.ratio[cases],
                gearbox_damping=c.gearbox_damping[cases],
                heat_capacity=c.heat_capacity[cases],
                thermal_resistance=c.thermal_resistance[cases],
                linear_damping=c.damping[cases],
                eddy=c.eddy,
                case=cases,
                thermal=problem.thermal,
            ),
            rtol=problem.rtol,
            method=problem.integrator,
            record=records is not None,
        )
        kind[nl_idx] = out.kind
        duration[nl_idx] = out.duration
        x[nl_idx] = out.x
        v[nl_idx] = out.v
        work_damper[nl_idx] = out.damper_work
        peak_speed[nl_idx] = out.max_speed
        temp_end[nl_idx] = out.temperature
        temp_peak[nl_idx] = out.max_temperature
        s.heat[cases] = out.state
        display[nl_idx] = t_r[nl_idx] + out.duration
        if records is not None:
            for j, sol in enumerate(out.solutions):
                if sol is not None:
                    i = int(nl_idx[j])
                    records.integrated.append(
                        IntegratedRecord(
                            case=int(run[i]),
                            start_time=float(t_r[i]),
                            duration=float(out.duration[j]),
                            start_angle=float(phi_r[i]),
                            direction=float(direction[i]),
                            solution=sol,
                        )
                    )

    # Energy of the segment (spring work exact for the linear spring piece).
    displacement = direction * x
    s.spring_work[run] += (
        piece.torque * displacement - 0.5 * piece.stiffness * displacement * displacement
    )
    s.friction_work[run] += kinetic * np.abs(x)
    s.damper_work[run] += work_damper
    before_arrival = ~np.isfinite(s.arrival_time[run]) & forward
    s.max_speed[run] = np.where(
        before_arrival, np.maximum(s.max_speed[run], peak_speed), s.max_speed[run]
    )
    s.max_temp[run] = np.maximum(s.max_temp[run], temp_peak)
    s.temp[run] = temp_end

    reached = kind == linear.REACH
    # Geometric events land exactly on their angle.
    target = phi_r + direction * length
    t_new = t_r + duration
    s.hold_from[run] = t_new
    s.display_end[run] = display
    s.t[run] = t_new
    s.phi[run] = np.where(reached, target, phi_r + displacement)
    s.w[run] = direction * v

    zero = run[kind == linear.ZERO]
    s.w[zero] = 0.0  # the next iteration decides stick or breakaway
    log.add(zero, s.t[zero], "zero_speed", s.phi[zero], s.w[zero])

    capped = run[kind == linear.CAP]
    s.finish(capped, "stop_time")
    log.add(capped, s.t[capped], "stop_time", s.phi[capped], s.w[capped])

    creeping = run[kind == linear.REST]
    s.finish(creeping, "creep")
    s.stuck[creeping] = True
    s.stuck_angle[creeping] = s.phi[creeping]
    s.stuck_time[creeping] = np.inf
    s.t[creeping] = np.inf
    s.w[creeping] = 0.0
    log.add(creeping, s.t[creeping], "creep", s.phi[creeping], s.w[creeping])

    cut = run[kind == integrate.HORIZON]
    s.finish(cut, "horizon")
    log.add(cut, s.t[cut], "horizon", s.phi[cut], s.w[cut])

    engaging = run[reached & (reach_kind == _EV["engage"])]
    if engaging.size:
        log.add(engaging, s.t[engaging], "engage", s.phi[engaging], s.w[engaging])
        w_after, loss = mechanics.plastic_engagement(
            c.load_inertia[engaging], s.w[engaging], c.damper_inertia[engaging]
        )
        s.w[engaging] = w_after
        s.engagement_loss[engaging] += loss
        s.engaged[engaging] = True
        s.engagement_time[engaging] = s.t[engaging]
    passing = run[reached & (reach_kind == _EV["breakpoint"])]
    log.add(passing, s.t[passing], "breakpoint", s.phi[passing], s.w[passing])
    for name in ("arrive", "start_stop"):
        hit = run[reached & (reach_kind == _EV[name])]
        if hit.size:
            _impact(c, s, hit, name, log)


def _impact(c: _Cases, s: _State, hit: NDArray[np.intp], name: str, log: _Log) -> None:
    """End of travel (latch or rebound) or the start stop."""
    inertia = np.where(s.engaged[hit], c.total_inertia[hit], c.load_inertia[hit])
    ke = mechanics.kinetic_energy(inertia, s.w[hit])
    log.add(hit, s.t[hit], name, s.phi[hit], s.w[hit])
    arriving = name == "arrive"
    if arriving:
        first = ~np.isfinite(s.arrival_time[hit])
        s.arrival_time[hit] = np.where(first, s.t[hit], s.arrival_time[hit])
        s.arrival_speed[hit] = np.where(first, s.w[hit], s.arrival_speed[hit])
        s.arrival_ke[hit] = np.where(first, ke, s.arrival_ke[hit])
    e = c.restitution[hit]
    latch = e <= 0.0
    if arriving:
        latched = hit[latch]
        s.finish(latched, "latched")
        log.add(latched, s.t[latched], "latch", s.phi[latched], s.w[latched])
    else:
        stopped = hit[latch]
        s.impact_loss[stopped] += ke[latch]
        s.w[stopped] = 0.0
    if np.all(latch):
        return
    bouncing = ~latch
    idx = hit[bouncing]
    w_after, loss = mechanics.rebound(s.w[idx], e[bouncing], inertia[bouncing])
    rebound_ke = ke[bouncing] - loss
    reference = np.maximum(np.maximum(s.arrival_ke[idx], ke[bouncing]), np.finfo(float).tiny)
    settle = rebound_ke <= _SETTLE_FRACTION * reference
    if arriving:
        first_rebound = s.impacts[idx] == 0
        s.rebound_speed[idx] = np.where(first_rebound & ~settle, w_after, s.rebound_speed[idx])
    s.impacts[idx] += 1
    s.impact_loss[idx] += np.where(settle, ke[bouncing], loss)
    s.w[idx] = np.where(settle, 0.0, w_after)
    if arriving:
        settled = idx[settle]
        s.finish(settled, "settled")
        log.add(settled, s.t[settled], "settle", s.phi[settled], s.w[settled])
