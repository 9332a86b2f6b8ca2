"""The event-driven solver of the dynamic deployment, vectorised over a batch of cases.

Every loop iteration takes all cases still running, decides for those at rest whether
they stick for good or break away, builds each case's current segment (constant inertia,
damping, friction direction and spring slope), advances it to its first event (closed
form for linear segments, :mod:`ecdsim.dynamics.integrate` for roll-off and heating) and
applies the events: lost motion closing, spring breakpoints, end of travel (latch or
rebound), zero speed, stop time, asymptotic rest. See ``docs/dynamics.md``.

One pass over the running cases is :func:`_advance_cases`: event finding
(:func:`_segments`, with the spring piece found by walking from the previous one, O(1)
per event), stepping (:func:`_step_closed_form`, :func:`_step_integrated`) and
bookkeeping (:func:`_account`, :func:`_apply_events`, :func:`_impact`). A single case
in the common subset (:func:`ecdsim.dynamics.single.eligible`) takes the same loop
written for one case in floats, :mod:`ecdsim.dynamics.single`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import BoolArray, FloatArray, broadcast
from ecdsim.dynamics import gearflow, integrate, linear, single
from ecdsim.dynamics.backlash import solve_compliant
from ecdsim.dynamics.damping import EddyLaw
from ecdsim.dynamics.equations import SWITCH
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
from ecdsim.dynamics.rules import KEEPING_SPEED, SETTLE_FRACTION, STICK_MARGIN
from ecdsim.physics import gearing, mechanics, thermal
from ecdsim.physics.gravity import gravity_torque, gravity_work

# The stick margin and the settle fraction (ecdsim.dynamics.rules), shared with the
# single-case path.
_STICK_MARGIN = STICK_MARGIN
_SETTLE_FRACTION = SETTLE_FRACTION
# A plot of a case that ends approaching rest asymptotically (creep) stops after this many
# of the motion's slow time constants (its remaining motion is then below e^-10 of it).
DISPLAY_TIME_CONSTANTS = 10.0

_EV = {name: code for code, name in enumerate(EVENT_KINDS)}
_ST = {name: code for code, name in enumerate(STATUSES)}
# By status code: whether a run that ended so keeps its last speed (else it is at rest).
_KEEPS_SPEED = np.isin(np.arange(len(STATUSES)), [_ST[k] for k in KEEPING_SPEED])


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
    stribeck_speed: FloatArray
    stribeck: bool  # some case has a Stribeck speed
    eddy: EddyLaw
    eta_forward: FloatArray  # lossy gear's forward mesh efficiency (1: ideal)
    eta_backward: FloatArray  # and back-driven
    lossy: bool  # some case has a lossy gear (issue 16 item 5)
    # Two-node heating and the start temperatures (issue 16 item 6); the defaults are
    # the one-node model starting at the deployment temperature.
    two_node: bool = False
    housing_heat_capacity: FloatArray | None = None
    housing_resistance: FloatArray | None = None
    rotor_rise0: FloatArray | None = None
    housing_rise0: FloatArray | None = None
    # A ground test's gravity (issue 16 item 2): W [N*m] and theta_0 [rad]; None in flight.
    gravity_amplitude: FloatArray | None = None
    gravity_angle: FloatArray | None = None


def _flatten(problem: DynamicProblem) -> _Cases:
    shape = problem.batch_shape
    n = math.prod(shape)
    points = problem.angles.shape[0]

    def flat(a: FloatArray) -> FloatArray:
        # The problem's fields already have the batch shape (float, from its
        # __post_init__): a contiguous one is its own 1-D view; broadcast only the others.
        if a.shape == shape and a.flags.c_contiguous and a.dtype == np.float64:
            return a.reshape(n)
        full = a if np.shape(a) == shape else broadcast(np.asarray(a, dtype=float), shape)
        return np.ascontiguousarray(np.reshape(full, n), dtype=float)

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
        stribeck_speed=flat(problem.stribeck_speed),
        stribeck=problem.stribeck,
        eddy=problem.eddy.flattened(shape),
        two_node=problem.two_node,
        housing_heat_capacity=flat(problem.housing_heat_capacity) if problem.two_node else None,
        housing_resistance=flat(problem.housing_thermal_resistance) if problem.two_node else None,
        rotor_rise0=flat(problem.initial_rotor_rise) if problem.thermal else None,
        housing_rise0=flat(problem.initial_housing_rise) if problem.two_node else None,
        gravity_amplitude=_flat_or_none(flat, problem.gravity_amplitude, problem.has_gravity),
        gravity_angle=_flat_or_none(flat, problem.gravity_angle, problem.has_gravity),
        eta_forward=flat(problem.forward_efficiency),
        eta_backward=flat(problem.backward_efficiency),
        lossy=problem.lossy,
    )


def _flat_or_none(
    flat: Callable[[FloatArray], FloatArray], values: FloatArray | None, given: bool
) -> FloatArray | None:
    """``flat(values)`` where the problem gives them (a ground test's gravity), else None."""
    return flat(values) if given and values is not None else None


@dataclass(frozen=True)
class _Piece:
    """The spring piece each case is on, for its direction of motion."""

    index: NDArray[np.intp]  # piece i runs from breakpoint i to i + 1
    lower: FloatArray  # angle of the piece's start [rad]
    upper: FloatArray  # angle of the piece's end [rad]
    torque: FloatArray  # spring torque at the current angle [N*m]
    stiffness: FloatArray  # k = -dT/dphi on the piece [N*m/rad]


def _first_piece(c: _Cases, phi: FloatArray) -> NDArray[np.intp]:
    """The piece of every case at its release angle, counted once: O(P) per case."""
    if c.angles.shape[0] == 2:  # a linear spring: its one piece, without the count
        return np.zeros(c.n, dtype=np.intp)
    interior = c.angles[1:-1]
    return np.asarray(np.sum(interior <= phi, axis=0), dtype=np.intp)


def _piece(
    c: _Cases,
    idx: NDArray[np.intp],
    phi: FloatArray,
    forward: BoolArray,
    start: NDArray[np.intp],
) -> _Piece:
    """Piecewise-linear spring lookup per case (each case has its own breakpoints).

    The piece is the one the motion is about to run along: moving forward from a
    breakpoint, the piece above it; backward, the piece below (equivalently, the number
    of interior breakpoints at or below phi, or below it). The search walks from
    ``start``, the case's previous piece: a motion is continuous, so it moves by at most
    one piece per event, and a deployment over P breakpoints costs O(P), not the O(P^2)
    of counting the breakpoints at every event.
    """
    angles = c.angles
    last = angles.shape[0] - 2  # pieces 0 .. P - 2
    i = start.copy()
    while last > 0:  # a linear spring (P = 2) has the one piece 0
        above = angles[np.minimum(i + 1, last), idx]
        below = angles[i, idx]
        up = (i < last) & np.where(forward, above <= phi, above < phi)
        down = (i > 0) & np.where(forward, below > phi, below >= phi)
        if not (np.any(up) or np.any(down)):
            break
        i += up.astype(np.intp) - down.astype(np.intp)
    a0, a1 = angles[i, idx], angles[i + 1, idx]
    t0, t1 = c.torques[i, idx], c.torques[i + 1, idx]
    width = a1 - a0
    slope = np.where(width > 0.0, (t1 - t0) / np.where(width > 0.0, width, 1.0), 0.0)
    return _Piece(index=i, lower=a0, upper=a1, torque=t0 + slope * (phi - a0), stiffness=-slope)


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

    def build(self, cases: int) -> EventLog:
        """The events sorted by case, then in the order logged (time order per case)."""
        if not self.parts:
            empty = np.zeros(0)
            return EventLog(np.zeros(0, np.intp), empty, np.zeros(0, np.int8), empty, empty)
        case = np.concatenate([p[0] for p in self.parts])
        time = np.concatenate([p[1] for p in self.parts])
        kind = np.concatenate([np.full(p[0].size, p[2], np.int8) for p in self.parts])
        angle = np.concatenate([p[3] for p in self.parts])
        speed = np.concatenate([p[4] for p in self.parts])
        if cases == 1:  # one case: the order logged is the order sought
            return EventLog(case, time, kind, angle, speed)
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
    piece: NDArray[np.intp]  # the spring piece each case was last on
    gear_loss: FloatArray  # energy lost in a lossy gear's mesh
    # The power flow to take on the next segment after a power_flow event (+1 forward,
    # -1 back-driven), 0 to decide from the state: at the switch sigma is 0 to rounding.
    flow_hint: NDArray[np.int8]
    # The largest kinetic energy of an impact on the start stop so far [J]: the reference
    # of a rebound sequence there (the first arrival's is the end stop's).
    start_ke: FloatArray
    housing: FloatArray | None = None  # two nodes: the housing's rise over ambient [K]

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
            piece=_first_piece(c, c.angle0),
            gear_loss=np.zeros(n),
            flow_hint=np.zeros(n, dtype=np.int8),
            start_ke=np.zeros(n),
        )

    def finish(self, idx: NDArray[np.intp], status: str) -> None:
        """Mark cases as finished with a status."""
        self.done[idx] = True
        self.status[idx] = _ST[status]


def _thermal_start(c: _Cases, s: _State) -> None:
    """Start rotor (damper) and housing temperatures other than the deployment's.

    The rotor's state is the damping law's log factor of its rise
    (:func:`ecdsim.physics.thermal.factor_log_from_rise`); nothing changes (s = 0,
    T_d = T) where no rise is given.
    """
    if c.two_node:
        assert c.housing_rise0 is not None
        s.housing = c.housing_rise0.copy()
    rise = c.rotor_rise0
    if rise is None or not np.any(rise != 0.0):
        return
    ambient_factor = np.maximum(c.eddy.factor(c.ambient), 0.0)
    s.heat = thermal.factor_log_from_rise(rise, ambient_factor, c.eddy.coefficient)
    s.temp = c.ambient + rise
    s.max_temp = s.temp.copy()


def solve_dynamic(problem: DynamicProblem, record: bool = True) -> DynamicResult:
    """Solve every case of ``problem``; ``record`` keeps the segments for time series.

    A compliant gear mesh (``gear_stiffness`` finite) makes the load and the damper side
    two bodies: :func:`ecdsim.dynamics.backlash.solve_compliant` solves those problems.
    One case in the subset of :mod:`ecdsim.dynamics.single` (:func:`single.eligible`)
    runs this loop there, in floats around the compiled segment: the same result bit
    for bit, without the NumPy calls' fixed cost on arrays of one element.
    """
    if single.eligible(problem):  # never compliant
        # One case in the single-case subset: the same loop in floats (dynamics.single).
        return single.solve(problem, record=record)
    if problem.compliant:
        return solve_compliant(problem, record=record)
    c = _flatten(problem)
    s = _State.initial(c)
    _thermal_start(c, s)
    ke0 = mechanics.kinetic_energy(np.where(s.engaged, c.total_inertia, c.load_inertia), s.w)
    log = _Log()
    records: _Records | None = _Records([], []) if record else None
    log.add(np.arange(c.n), s.t, "release", s.phi, s.w)

    # Passes of each case that ended in an event other than a spring breakpoint: the
    # event limit counts these, so that a table of any size can be crossed. Between two
    # such events the motion is monotone and passes each breakpoint at most once, so the
    # loop still ends after at most (max_events + 1) P passes.
    passes = np.zeros(c.n, dtype=np.int64)
    while True:
        active = np.flatnonzero(~s.done)
        if active.size == 0:
            break
        over = active[passes[active] >= problem.max_events]
        if over.size:
            s.finish(over, "event_limit")
            log.add(over, s.t[over], "event_limit", s.phi[over], s.w[over])
            active = active[passes[active] < problem.max_events]
            if active.size == 0:
                break
        direction = np.zeros(c.n)
        resting = active[s.w[active] == 0.0]
        if resting.size:
            _stick_or_break(c, s, resting, direction, log)
        moving = active[s.w[active] != 0.0]
        direction[moving] = np.sign(s.w[moving])
        run = np.flatnonzero(~s.done & (direction != 0.0))
        if run.size:
            passing = _advance_cases(c, s, run, direction[run], problem, log, records)
            passes[run] += 1
            passes[passing] -= 1

    final_inertia = np.where(s.engaged, c.total_inertia, c.load_inertia)
    keeps_speed = _KEEPS_SPEED[s.status]
    final_speed = np.where(keeps_speed, s.w, 0.0)
    energy = EnergyBalance(
        spring_work=s.spring_work,
        initial_kinetic_energy=ke0,
        damper_dissipation=s.damper_work,
        friction_dissipation=s.friction_work,
        engagement_loss=s.engagement_loss,
        impact_loss=s.impact_loss,
        final_kinetic_energy=mechanics.kinetic_energy(final_inertia, final_speed),
        # Gravity is conservative: the work against it follows from the end angles.
        gravity_work=None
        if c.gravity_amplitude is None or c.gravity_angle is None
        else gravity_work(c.angle0, s.phi, c.gravity_amplitude, c.gravity_angle),
        gear_loss=s.gear_loss,
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
            stribeck_speed=c.stribeck_speed,
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
        final_housing_temperature=None if s.housing is None else shaped(c.ambient + s.housing),
        engagement_time=shaped(s.engagement_time),
        rebound_speed=shaped(s.rebound_speed),
        impacts=shaped(s.impacts),
        status=shaped(s.status),
        energy=energy.reshaped(shape),
        events=log.build(c.n),
        trajectory=trajectory,
    )


@dataclass(frozen=True)
class _Records:
    closed: list[ClosedFormRecord]
    integrated: list[IntegratedRecord]


def _stick_or_break(
    c: _Cases, s: _State, resting: NDArray[np.intp], direction: FloatArray, log: _Log
) -> None:
    """At rest: stick for good if the spring cannot beat static friction, else break away.

    On the start stop a backward drive is held by the stop: the case sticks there too.
    """
    piece = _piece(c, resting, s.phi[resting], np.ones(resting.size, dtype=bool), s.piece[resting])
    s.piece[resting] = piece.index
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
    if c.gravity_amplitude is not None and c.gravity_angle is not None:
        # At rest gravity acts too: the spring less W sin(theta_0 + phi) (physics.gravity).
        drive = drive - gravity_torque(
            s.phi[resting], c.gravity_amplitude[resting], c.gravity_angle[resting]
        )
    holds = np.abs(drive) <= static + _STICK_MARGIN * np.maximum(np.abs(drive), static)
    # On the start stop (angle 0) a backward drive presses the load into the stop, which
    # holds it: at rest for good as a stick (nothing changes at rest afterwards).
    holds = holds | ((drive < 0.0) & (s.phi[resting] <= 0.0))
    sticking = resting[holds]
    s.finish(sticking, "stuck")
    s.stuck[sticking] = True
    s.stuck_angle[sticking] = s.phi[sticking]
    s.stuck_time[sticking] = s.t[sticking]
    log.add(sticking, s.t[sticking], "stick", s.phi[sticking], s.w[sticking])
    moving_off = resting[~holds]
    direction[moving_off] = np.sign(drive[~holds])
    log.add(moving_off, s.t[moving_off], "breakaway", s.phi[moving_off], s.w[moving_off])


@dataclass(frozen=True)
class _Segment:
    """The segment each running case is on and its first geometric event.

    Every motion is solved in its forward frame: ``J x'' + B x' + k x = a`` with
    ``x = direction * (phi - phi_start)`` (:mod:`ecdsim.dynamics.linear`).
    """

    run: NDArray[np.intp]  # the cases
    direction: FloatArray  # +1 forward, -1 backward
    forward: BoolArray
    piece: _Piece
    engaged: BoolArray
    length: FloatArray  # distance to the first geometric event [rad]
    reach_kind: NDArray[np.int64]  # that event's code (_EV)
    inertia: FloatArray  # J [kg*m^2]
    damping: FloatArray  # B [N*m*s/rad] (linear law at ambient)
    kinetic: FloatArray  # kinetic friction [N*m]
    # Breakaway minus kinetic friction where w_St is given [N*m]; None: no Stribeck speed.
    stribeck_excess: FloatArray | None
    drive: FloatArray  # a, spring torque minus friction, forward frame [N*m]
    speed0: FloatArray  # forward-frame speed at the start [rad/s]
    cap: FloatArray  # time left before the stop time [s]
    # A lossy gear's power flow on engaged segments (None: every gear ideal): +1 forward,
    # -1 back-driven, and its factor m (1/eta_f or eta_b) on the damper side's inertia,
    # damping and friction; the kinetic friction the path dissipates (FECD_T eta_f + FS_T).
    flow: FloatArray | None = None
    factor: FloatArray | None = None
    dissipating: FloatArray | None = None


@dataclass
class _Step:
    """What happened in each case's segment (see :class:`ecdsim.dynamics.linear.Advance`)."""

    kind: NDArray[np.int8]
    duration: FloatArray
    x: FloatArray
    v: FloatArray
    damper_work: FloatArray
    peak_speed: FloatArray
    temperature: FloatArray  # damper temperature at the end [degC]
    peak_temperature: FloatArray
    display_end: FloatArray  # where a plot of the case should end if this is its last
    # Spring work over segments that crossed several pieces (NaN: the one piece's formula).
    spring_work: FloatArray | None = None
    gear_loss: FloatArray | None = None  # mesh loss of a lossy gear [J]
    switched: BoolArray | None = None  # the power flow reversed at the segment's end

    @classmethod
    def empty(cls, temperature: FloatArray) -> _Step:
        m = temperature.size
        return cls(
            kind=np.zeros(m, dtype=np.int8),
            duration=np.zeros(m),
            x=np.zeros(m),
            v=np.zeros(m),
            damper_work=np.zeros(m),
            peak_speed=np.zeros(m),
            temperature=temperature.copy(),
            peak_temperature=temperature.copy(),
            display_end=np.zeros(m),
        )


def _advance_cases(
    c: _Cases,
    s: _State,
    run: NDArray[np.intp],
    direction: FloatArray,
    problem: DynamicProblem,
    log: _Log,
    records: _Records | None,
) -> NDArray[np.intp]:
    """Advance the cases ``run`` through one segment each and apply their events.

    Event finding (:func:`_segments`), stepping (:func:`_step_closed_form`,
    :func:`_step_integrated`) and bookkeeping (:func:`_account`, :func:`_apply_events`).
    Returns the cases whose segment ended at a spring breakpoint.
    """
    seg = _segments(c, s, run, direction, problem.stop_time)
    step = _Step.empty(s.temp[run])
    integrated = seg.engaged & problem.nonlinear
    if seg.stribeck_excess is not None:
        # Stribeck friction makes any sliding segment nonlinear, free play included.
        integrated = integrated | (seg.stribeck_excess > 0.0)
    weighed = None
    if c.gravity_amplitude is not None:
        # Gravity's sine makes every sliding segment nonlinear, free play included.
        weighed = c.gravity_amplitude[run] != 0.0
        integrated = integrated | weighed
    tabled = _table_cases(c, seg, problem)
    if tabled is not None and weighed is not None:
        tabled = tabled & ~weighed  # the compiled table kernel has no gravity term
        tabled = tabled if np.any(tabled) else None
    if tabled is not None:
        _step_table(c, s, seg, np.flatnonzero(tabled), step, problem, log, records)
        integrated = integrated & ~tabled
    closed_idx = np.flatnonzero(~integrated if tabled is None else ~integrated & ~tabled)
    if closed_idx.size:
        _step_closed_form(c, s, seg, closed_idx, step, records)
    nl_idx = np.flatnonzero(integrated)
    if nl_idx.size:
        _step_integrated(c, s, seg, nl_idx, step, problem, records)
    _account(s, seg, step)
    return _apply_events(c, s, seg, step, log)


def _segments(
    c: _Cases, s: _State, run: NDArray[np.intp], direction: FloatArray, stop_time: float
) -> _Segment:
    """Each running case's segment and the distance to its first geometric event."""
    forward = direction > 0.0
    phi_r = s.phi[run]
    piece = _piece(c, run, phi_r, forward, s.piece[run])
    s.piece[run] = piece.index
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
    kinetic = np.where(eng, c.ecd_friction[run] + c.system_friction[run], c.system_friction[run])
    excess = None
    if c.stribeck:
        # Stribeck friction falls from the breakaway (the stiction limit of _stick_or_break)
        # to the kinetic friction with speed; its excess over the kinetic one, where w_St is
        # given.
        system_excess = c.system_friction[run] * (c.system_factor[run] - 1.0)
        excess = np.where(
            eng, c.ecd_friction[run] * (c.factor[run] - 1.0) + system_excess, system_excess
        )
        excess = np.where(np.isfinite(c.stribeck_speed[run]), np.maximum(excess, 0.0), 0.0)
    if c.lossy:
        return _lossy_segment(
            c, s, run, direction, forward, piece, eng, length, reach_kind, stop_time
        )
    return _Segment(
        run=run,
        direction=direction,
        forward=forward,
        piece=piece,
        engaged=eng,
        length=length,
        reach_kind=reach_kind,
        inertia=np.where(eng, c.total_inertia[run], c.load_inertia[run]),
        damping=np.where(eng, c.damping[run], 0.0),
        kinetic=kinetic,
        stribeck_excess=excess,
        drive=np.where(forward, piece.torque - kinetic, -(piece.torque + kinetic)),
        # + 0.0: a backward breakaway from rest gives -0.0, whose atan2 in the zero-speed
        # time of an underdamped segment is -pi (a negative duration, then the event limit).
        speed0=direction * s.w[run] + 0.0,
        cap=np.maximum(stop_time - s.t[run], 0.0),
    )


def _lossy_segment(
    c: _Cases,
    s: _State,
    run: NDArray[np.intp],
    direction: FloatArray,
    forward: BoolArray,
    piece: _Piece,
    eng: BoolArray,
    length: FloatArray,
    reach_kind: NDArray[np.int64],
    stop_time: float,
) -> _Segment:
    """The segments of a batch with a lossy gear: the power flow decides the mesh factor.

    Forward (the load drives the damper) the damper side's inertia J_D, damping and
    friction reach the input divided by eta_f (BECD_T and FECD_T already are),
    back-driven multiplied by eta_b (docs/dynamics.md, lossy gear). The flow is that of
    the sign of ``J_L D + J_D A`` (:func:`ecdsim.physics.gearing.power_flow_indicator`)
    at the segment's start (D with the law's torque where roll-off or heating is
    modelled, A with gravity), or the one a power_flow event has just switched to.
    """
    eta_f, eta_b = c.eta_forward[run], c.eta_backward[run]
    # + 0.0: a backward breakaway from rest would give -0.0, whose atan2 in the zero-speed
    # time of an underdamped segment is -pi (a negative duration).
    speed0 = direction * s.w[run] + 0.0
    fs = c.system_friction[run]
    ideal_damping = c.damping[run] * eta_f  # BT_T N^2, through an ideal gear
    ideal_friction = c.ecd_friction[run] * eta_f  # FT_T N
    load_drive = np.where(forward, piece.torque, -piece.torque) - fs
    needed = ideal_damping * speed0 + ideal_friction
    if c.eddy.name != "linear" or c.rotor_rise0 is not None:
        # Roll-off or heating: the damper side needs its law's torque at the start.
        eddy = c.eddy.take(run)
        factor_now = thermal.damping_factor_from_log(
            s.heat[run], np.maximum(eddy.factor(c.ambient[run]), 0.0), eddy.coefficient
        )
        shaft = c.ratio[run] * speed0
        eddy_torque = eddy.torque_at_factor(shaft, factor_now)
        needed = c.ratio[run] * (eddy_torque + c.gearbox_damping[run] * shaft) + ideal_friction
    felt = load_drive
    if c.gravity_amplitude is not None and c.gravity_angle is not None:
        # A ground test's gravity against the motion at the start (equations.Model.gravity).
        felt = load_drive - direction * gravity_torque(
            0.0, c.gravity_amplitude[run], c.gravity_angle[run] + s.phi[run]
        )
    sigma = gearing.power_flow_indicator(c.load_inertia[run], c.damper_inertia[run], needed, felt)
    hint = s.flow_hint[run]
    flow = np.where(hint != 0, hint, np.where(sigma >= 0.0, 1.0, -1.0))
    s.flow_hint[run] = 0
    ahead = flow > 0.0
    back = np.where(eng, eta_f * eta_b, 1.0)  # forward values -> back-driven ones
    factor = np.where(eng, np.where(ahead, 1.0 / eta_f, eta_b), 1.0)
    damping = np.where(eng, np.where(ahead, c.damping[run], c.damping[run] * back), 0.0)
    ecd = np.where(eng, np.where(ahead, c.ecd_friction[run], c.ecd_friction[run] * back), 0.0)
    kinetic = ecd + fs
    return _Segment(
        run=run,
        direction=direction,
        forward=forward,
        piece=piece,
        engaged=eng,
        length=length,
        reach_kind=reach_kind,
        inertia=c.load_inertia[run] + np.where(eng, factor * c.damper_inertia[run], 0.0),
        damping=damping,
        kinetic=kinetic,
        stribeck_excess=None,
        drive=load_drive - ecd,
        speed0=speed0,
        cap=np.maximum(stop_time - s.t[run], 0.0),
        flow=np.where(eng, flow, 0.0),
        factor=factor,
        dissipating=np.where(eng, ideal_friction, 0.0) + fs,
    )


# A forward engaged segment with at least this many spring pieces ahead crosses them in
# one compiled call (ecdsim.dynamics.compiled_table) instead of one event-loop pass each,
# when at most TABLE_CASES cases of the pass qualify. Each case is its own call (about 10
# microseconds per piece, 0.3 ms per case in Python), while a pass of the loop costs about
# 1 ms plus 2 to 4 microseconds per case: for larger batches the vectorised pass per
# breakpoint is cheaper (measured: 2,000 cases over 100 pieces, 2.3 s compiled per case
# against 0.34 s per pass).
TABLE_PIECES = 32
TABLE_CASES = 64


def _table_cases(c: _Cases, seg: _Segment, problem: DynamicProblem) -> BoolArray | None:
    """The segments (of ``seg``) that run over the spring table compiled; None for none."""
    if c.angles.shape[0] - 1 < TABLE_PIECES or problem.integrator != integrate.BATCHED:
        return None
    if c.two_node or c.lossy:
        # The table kernel carries no mesh factor nor power-flow event (a lossy gear's
        # segments run one pass each: closed form, or integrated with the switch).
        return None
    ahead = (c.angles.shape[0] - 2) - seg.piece.index  # pieces after the current one
    chosen: BoolArray = seg.forward & seg.engaged & (ahead + 1 >= TABLE_PIECES)
    chosen &= seg.reach_kind == _EV["breakpoint"]
    if seg.stribeck_excess is not None:
        chosen &= ~(seg.stribeck_excess > 0.0)
    # numba is imported only when some segment qualifies.
    count = np.count_nonzero(chosen)
    if count == 0 or count > TABLE_CASES or integrate.compiled_kernel() is None:
        return None
    return chosen


def _step_table(
    c: _Cases,
    s: _State,
    seg: _Segment,
    idx: NDArray[np.intp],
    step: _Step,
    problem: DynamicProblem,
    log: _Log,
    records: _Records | None,
) -> None:
    """Segments ``idx`` (of ``seg``) over the spring pieces ahead, compiled, to their
    first event other than a breakpoint; the breakpoints crossed are logged here."""
    from ecdsim.dynamics import compiled, compiled_table, rosenbrock

    cases = seg.run[idx]
    segs = integrate.NonlinearSegments(
        inertia=seg.inertia[idx],
        stiffness=seg.piece.stiffness[idx],
        drive=seg.drive[idx],
        speed0=seg.speed0[idx],
        length=seg.length[idx],
        cap=seg.cap[idx],
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
    )
    model = integrate._model(segs)
    par, law = compiled._parameters(model)
    if step.spring_work is None:
        step.spring_work = np.full(step.kind.size, np.nan)
    end_state = np.empty(idx.size)
    hottest = np.empty(idx.size)
    for j, (k, case) in enumerate(zip(idx.tolist(), cases.tolist(), strict=True)):
        first = int(seg.piece.index[k])
        angles = c.angles[first:, case]
        torques = c.torques[first:, case]
        width = np.diff(angles)
        positive = width > 0.0
        # The pieces' stiffness as _piece computes it; zero-width pieces are skipped.
        slope = np.where(positive, np.diff(torques) / np.where(positive, width, 1.0), 0.0)
        start_torque = torques[:-1].copy()
        start_torque[0] = seg.piece.torque[k]
        length = width.copy()
        length[0] = seg.length[k]
        keep = positive.copy()
        keep[0] = True
        kept = np.flatnonzero(keep)
        final = np.empty(4)
        cross_time = np.empty(kept.size)
        cross_speed = np.empty(kept.size)
        out = compiled_table.table_run(
            par[j], law, bool(model.heating), np.array([0.0, seg.speed0[k], s.heat[case], 0.0]),
            np.ascontiguousarray(start_torque[kept]), np.ascontiguousarray(-slope[kept]),
            np.ascontiguousarray(length[kept]), float(seg.kinetic[k]), float(seg.cap[k]),
            problem.rtol, integrate.HORIZON_TIME, integrate.HORIZON, float(c.damping[case]),
            records is not None, final, cross_time, cross_speed,
        )  # fmt: skip
        code, duration, top_speed, top_temp, spring, crossed, steps, count = out
        start = float(s.t[case])
        step.kind[k] = code
        step.duration[k] = duration
        step.x[k] = final[0]
        step.v[k] = 0.0 if code in (linear.ZERO, linear.REST) else final[1]
        step.damper_work[k] = final[3]
        step.peak_speed[k] = max(top_speed, seg.speed0[k])
        step.spring_work[k] = spring
        step.display_end[k] = start + duration
        end_state[j] = final[2]
        hottest[j] = max(top_temp, final[2])
        # The run's geometric end is the end of travel (the table's last angle).
        seg.length[k] = max(angles[-1] - s.phi[case], 0.0)
        seg.reach_kind[k] = _EV["arrive"]
        s.piece[case] = first + int(kept[crossed])
        if crossed:
            log.add(
                np.full(crossed, case),
                start + cross_time[:crossed],
                "breakpoint",
                angles[kept[:crossed] + 1],
                cross_speed[:crossed],
            )
        if records is not None and count >= 2:
            trajectory = rosenbrock.Trajectory(
                steps[0, :count].copy(), steps[1:5, :count].copy(), steps[5:9, :count].copy()
            )
            records.integrated.append(
                IntegratedRecord(
                    case=case,
                    start_time=start,
                    duration=float(duration),
                    start_angle=float(s.phi[case]),
                    direction=1.0,
                    solution=integrate._InTemperature(trajectory, model, j),
                )
            )
    temperature, peak = model.temperature(np.stack([end_state, hottest]))
    step.temperature[idx] = temperature
    step.peak_temperature[idx] = peak
    s.heat[cases] = end_state


def _step_closed_form(
    c: _Cases,
    s: _State,
    seg: _Segment,
    idx: NDArray[np.intp],
    step: _Step,
    records: _Records | None,
) -> None:
    """Linear segments ``idx`` (of ``seg``) in closed form (:mod:`ecdsim.dynamics.linear`)."""
    closed = linear.segment(
        seg.inertia[idx],
        seg.damping[idx],
        seg.piece.stiffness[idx],
        seg.drive[idx],
        seg.speed0[idx],
    )
    adv = linear.advance(closed, seg.length[idx], seg.cap[idx])
    if seg.flow is not None:
        adv = _lossy_advance(c, seg, idx, closed, adv, step)
    step.kind[idx] = adv.kind
    step.duration[idx] = adv.duration
    step.x[idx] = adv.x
    step.v[idx] = adv.v
    step.damper_work[idx] = seg.damping[idx] * adv.speed_squared_integral
    if seg.factor is not None:
        # The damper's own dissipation, BT_T N^2 int v^2; the mesh's is the gear loss.
        ideal = np.where(
            seg.engaged[idx], c.damping[seg.run[idx]] * c.eta_forward[seg.run[idx]], 0.0
        )
        step.damper_work[idx] = ideal * adv.speed_squared_integral
    step.peak_speed[idx] = adv.max_speed
    start = s.t[seg.run[idx]]
    # A plot of an asymptotic approach to rest ends after a few slow time constants.
    step.display_end[idx] = start + linear.rest_time(closed, DISPLAY_TIME_CONSTANTS)
    if records is not None:
        cases = seg.run[idx]
        records.closed.append(
            ClosedFormRecord(
                case=cases,
                start_time=start,
                duration=adv.duration,
                start_angle=s.phi[cases],
                direction=seg.direction[idx],
                engaged=seg.engaged[idx],
                temperature=s.temp[cases],
                segment=closed,
            )
        )


def _lossy_advance(
    c: _Cases,
    seg: _Segment,
    idx: NDArray[np.intp],
    closed: linear.Segment,
    adv: linear.Advance,
    step: _Step,
) -> linear.Advance:
    """Cut engaged segments of a lossy gear where the power flow reverses; book the loss.

    The switch is an event (:func:`ecdsim.dynamics.gearflow.switch_time`): the segment
    is re-run to it with that time as its cap. The mesh loss of the segment is
    ``(m - 1) (dKE_D + B_q int v^2 + F_q |x|)`` with m = 1/eta_f or eta_b: what the
    effective equation ``(J_L + m J_D) v' = A - m (B_q v + F_q)`` charges the load for
    the damper side beyond its own kinetic energy and dissipation.
    """
    assert seg.flow is not None
    assert seg.factor is not None
    cases = seg.run[idx]
    flow = seg.flow[idx]
    engaged = flow != 0.0
    eta_f = c.eta_forward[cases]
    ideal_damping = c.damping[cases] * eta_f
    ideal_friction = c.ecd_friction[cases] * eta_f
    switched = np.zeros(idx.size, dtype=bool)
    lossy = np.flatnonzero(engaged)
    if lossy.size:
        sub = closed.take(lossy)
        horizon = adv.duration[lossy]
        resting = ~np.isfinite(horizon)
        horizon = np.where(resting, linear.rest_time(sub), horizon)
        load_drive = seg.drive[idx][lossy] + np.where(
            flow[lossy] > 0.0,
            c.ecd_friction[cases][lossy],
            c.ecd_friction[cases][lossy] * eta_f[lossy] * c.eta_backward[cases][lossy],
        )
        t_switch = gearflow.switch_time(
            sub,
            ideal_damping[lossy],
            ideal_friction[lossy],
            c.load_inertia[cases][lossy],
            c.damper_inertia[cases][lossy],
            load_drive,
            flow[lossy],
            horizon,
        )
        cut = np.isfinite(t_switch) & (t_switch < seg.cap[idx][lossy])
        if np.any(cut):
            switched[lossy[cut]] = True
            caps = seg.cap[idx].copy()
            caps[lossy[cut]] = t_switch[cut]
            adv = linear.advance(closed, seg.length[idx], caps)
    factor = seg.factor[idx]
    speed_squared = adv.speed_squared_integral
    kinetic_change = 0.5 * c.damper_inertia[cases] * (adv.v * adv.v - seg.speed0[idx] ** 2)
    own = kinetic_change + ideal_damping * speed_squared + ideal_friction * np.abs(adv.x)
    loss = np.where(engaged, (factor - 1.0) * own, 0.0)
    if step.gear_loss is None:
        step.gear_loss = np.zeros(step.kind.size)
        step.switched = np.zeros(step.kind.size, dtype=bool)
    assert step.switched is not None
    step.gear_loss[idx] = loss
    step.switched[idx] = switched
    return adv


def _step_integrated(
    c: _Cases,
    s: _State,
    seg: _Segment,
    idx: NDArray[np.intp],
    step: _Step,
    problem: DynamicProblem,
    records: _Records | None,
) -> None:
    """Nonlinear segments ``idx`` (roll-off, heating) by :mod:`ecdsim.dynamics.integrate`.

    With a lossy gear the segment's mesh factor and power flow go to the integrators,
    whose SWITCH event ends it like a closed-form segment's power_flow cap.
    """
    cases = seg.run[idx]
    engaged = seg.engaged[idx]
    # Free play (lost motion not yet closed) is integrated only for its Stribeck friction:
    # the damper side is at rest, so no damping torque and no heating (ratio 0).
    ratio = np.where(engaged, c.ratio[cases], 0.0)
    excess = seg.stribeck_excess
    mesh = _mesh_segments(c, seg, idx)
    out = integrate.advance_nonlinear(
        integrate.NonlinearSegments(
            inertia=seg.inertia[idx],
            stiffness=seg.piece.stiffness[idx],
            drive=seg.drive[idx],
            speed0=seg.speed0[idx],
            length=seg.length[idx],
            cap=seg.cap[idx],
            state0=s.heat[cases],
            ambient=c.ambient[cases],
            ratio=ratio,
            gearbox_damping=np.where(engaged, c.gearbox_damping[cases], 0.0),
            heat_capacity=c.heat_capacity[cases],
            thermal_resistance=c.thermal_resistance[cases],
            linear_damping=c.damping[cases],
            eddy=c.eddy,
            case=cases,
            thermal=problem.thermal,
            stribeck_excess=None if excess is None else excess[idx],
            stribeck_speed=None if excess is None else c.stribeck_speed[cases],
            **_housing_segments(c, s, cases),
            **_gravity_segments(c, s, cases, seg.direction[idx]),
            **mesh,
        ),
        rtol=problem.rtol,
        method=problem.integrator,
        record=records is not None,
    )
    if mesh:
        _integrated_mesh_loss(c, seg, idx, out, step)
    step.kind[idx] = np.where(out.kind == SWITCH, linear.CAP, out.kind)
    step.duration[idx] = out.duration
    step.x[idx] = out.x
    step.v[idx] = out.v
    step.damper_work[idx] = out.damper_work
    step.peak_speed[idx] = out.max_speed
    step.temperature[idx] = out.temperature
    step.peak_temperature[idx] = out.max_temperature
    s.heat[cases] = out.state
    if s.housing is not None and out.housing is not None:
        s.housing[cases] = out.housing
    start = s.t[cases]
    step.display_end[idx] = start + out.duration
    if records is not None:
        for j, sol in enumerate(out.solutions):
            if sol is not None:
                case = int(cases[j])
                records.integrated.append(
                    IntegratedRecord(
                        case=case,
                        start_time=float(start[j]),
                        duration=float(out.duration[j]),
                        start_angle=float(s.phi[case]),
                        direction=float(seg.direction[idx[j]]),
                        solution=sol,
                    )
                )


def _mesh_segments(c: _Cases, seg: _Segment, idx: NDArray[np.intp]) -> dict[str, Any]:
    """A lossy gear's arguments of :class:`~ecdsim.dynamics.integrate.NonlinearSegments`:
    the segment's mesh factor m and power flow (1 and 0 in free play), and what the
    power-flow indicator needs; none for ideal gears."""
    if seg.factor is None or seg.flow is None:
        return {}
    cases = seg.run[idx]
    fs = c.system_friction[cases]
    return {
        "mesh": seg.factor[idx],
        "flow": seg.flow[idx],
        "load_inertia": c.load_inertia[cases],
        "damper_inertia": c.damper_inertia[cases],
        "mesh_friction": c.ecd_friction[cases] * c.eta_forward[cases],
        # The drive less the mesh-scaled ECD friction: the spring less FS_T.
        "load_drive": seg.drive[idx] + (seg.kinetic[idx] - fs),
    }


def _integrated_mesh_loss(
    c: _Cases, seg: _Segment, idx: NDArray[np.intp], out: integrate.NonlinearAdvance, step: _Step
) -> None:
    """Book the mesh loss of integrated segments and mark the power-flow switches.

    E (``out.damper_work``) is the damper side's own work ``int M_d u`` (ideal gear), so
    the loss ``(m - 1) int (J_D u' + M_d + F_q) u`` is ``(m - 1) (dKE_D + E + F_q |x|)``
    (docs/model.md, lossy gear), as on the closed-form segments.
    """
    assert seg.factor is not None
    assert seg.flow is not None
    cases = seg.run[idx]
    factor = seg.factor[idx]
    engaged = seg.flow[idx] != 0.0
    kinetic_change = 0.5 * c.damper_inertia[cases] * (out.v * out.v - seg.speed0[idx] ** 2)
    friction = c.ecd_friction[cases] * c.eta_forward[cases] * np.abs(out.x)
    own = kinetic_change + out.damper_work + friction
    if step.gear_loss is None:
        step.gear_loss = np.zeros(step.kind.size)
    if step.switched is None:
        step.switched = np.zeros(step.kind.size, dtype=bool)
    step.gear_loss[idx] = np.where(engaged, (factor - 1.0) * own, 0.0)
    step.switched[idx] = out.kind == SWITCH


def _gravity_segments(
    c: _Cases, s: _State, cases: NDArray[np.intp], direction: FloatArray
) -> dict[str, Any]:
    """The gravity arguments of :class:`~ecdsim.dynamics.integrate.NonlinearSegments`:
    W, theta_0 + phi at the segment's start, and the direction; none without gravity."""
    if c.gravity_amplitude is None or c.gravity_angle is None:
        return {}
    return {
        "gravity_amplitude": c.gravity_amplitude[cases],
        "gravity_phase": c.gravity_angle[cases] + s.phi[cases],
        "gravity_direction": direction,
    }


def _housing_segments(c: _Cases, s: _State, cases: NDArray[np.intp]) -> dict[str, Any]:
    """The housing node's arguments of :class:`~ecdsim.dynamics.integrate.NonlinearSegments`."""
    if s.housing is None or c.housing_heat_capacity is None or c.housing_resistance is None:
        return {}
    return {
        "housing_state0": s.housing[cases],
        "housing_heat_capacity": c.housing_heat_capacity[cases],
        "housing_resistance": c.housing_resistance[cases],
    }


def _account(s: _State, seg: _Segment, step: _Step) -> None:
    """Energy of the segment, extremes, and the new time, angle and speed of each case."""
    run, piece, direction = seg.run, seg.piece, seg.direction
    phi_r = s.phi[run]
    # Spring work exact for the linear spring piece.
    displacement = direction * step.x
    work = piece.torque * displacement - 0.5 * piece.stiffness * displacement * displacement
    if step.spring_work is not None:
        work = np.where(np.isnan(step.spring_work), work, step.spring_work)
    s.spring_work[run] += work
    s.friction_work[run] += (seg.kinetic if seg.dissipating is None else seg.dissipating) * np.abs(
        step.x
    )
    if step.gear_loss is not None:
        s.gear_loss[run] += step.gear_loss
    s.damper_work[run] += step.damper_work
    before_arrival = ~np.isfinite(s.arrival_time[run]) & seg.forward
    s.max_speed[run] = np.where(
        before_arrival, np.maximum(s.max_speed[run], step.peak_speed), s.max_speed[run]
    )
    s.max_temp[run] = np.maximum(s.max_temp[run], step.peak_temperature)
    s.temp[run] = step.temperature
    reached = step.kind == linear.REACH
    # Geometric events land exactly on their angle.
    target = phi_r + direction * seg.length
    t_new = s.t[run] + step.duration
    s.hold_from[run] = t_new
    s.display_end[run] = step.display_end
    s.t[run] = t_new
    s.phi[run] = np.where(reached, target, phi_r + displacement)
    s.w[run] = direction * step.v


def _apply_events(c: _Cases, s: _State, seg: _Segment, step: _Step, log: _Log) -> NDArray[np.intp]:
    """Log each case's event and apply it: stop, cap, creep, engagement, impacts.

    Returns the cases that passed a spring breakpoint.
    """
    run, kind = seg.run, step.kind
    zero = run[kind == linear.ZERO]
    s.w[zero] = 0.0  # the next iteration decides stick or breakaway
    log.add(zero, s.t[zero], "zero_speed", s.phi[zero], s.w[zero])

    if step.switched is not None and seg.flow is not None:
        switching = run[step.switched]
        s.flow_hint[switching] = -seg.flow[step.switched]
        log.add(switching, s.t[switching], "power_flow", s.phi[switching], s.w[switching])
        capped = run[(kind == linear.CAP) & ~step.switched]
    else:
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

    reached = kind == linear.REACH
    engaging = run[reached & (seg.reach_kind == _EV["engage"])]
    if engaging.size:
        log.add(engaging, s.t[engaging], "engage", s.phi[engaging], s.w[engaging])
        w_after, loss = mechanics.plastic_engagement(
            c.load_inertia[engaging], s.w[engaging], c.damper_inertia[engaging]
        )
        if c.lossy:
            # The load drives the damper side through the mesh: its impulse reaches the
            # input divided by eta_f, as J_D / eta_f; the energy lost is the kinetic
            # energy's drop, the mesh's share included.
            j_l, w_before = c.load_inertia[engaging], s.w[engaging]
            j_d = c.damper_inertia[engaging]
            w_after = j_l * w_before / (j_l + j_d / c.eta_forward[engaging])
            loss = mechanics.kinetic_energy(j_l, w_before) - mechanics.kinetic_energy(
                j_l + j_d, w_after
            )
        s.w[engaging] = w_after
        s.engagement_loss[engaging] += loss
        s.engaged[engaging] = True
        s.engagement_time[engaging] = s.t[engaging]
    passing: NDArray[np.intp] = run[reached & (seg.reach_kind == _EV["breakpoint"])]
    log.add(passing, s.t[passing], "breakpoint", s.phi[passing], s.w[passing])
    for name in ("arrive", "start_stop"):
        hit = run[reached & (seg.reach_kind == _EV[name])]
        if hit.size:
            _impact(c, s, hit, name, log)
    return passing


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
    if latch.all():
        return
    bouncing = ~latch
    idx = hit[bouncing]
    w_after, loss = mechanics.rebound(s.w[idx], e[bouncing], inertia[bouncing])
    rebound_ke = ke[bouncing] - loss
    if arriving:
        largest = ke[bouncing]
    else:
        # On the start stop a rebound sequence's reference is the largest impact there
        # so far, as the first arrival is the end stop's.
        largest = np.maximum(s.start_ke[idx], ke[bouncing])
        s.start_ke[idx] = largest
    reference = np.maximum(np.maximum(s.arrival_ke[idx], largest), np.finfo(float).tiny)
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
