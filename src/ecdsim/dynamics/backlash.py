"""Compliant backlash: the load and the damper side as two bodies coupled by an elastic mesh.

With ``[gearbox] stiffness`` the gear mesh is a spring-damper (c, d) in series with the
lost motion b, as the Modelica Standard Library's ElastoBacklash
(:func:`ecdsim.physics.mechanics.elasto_backlash_torque`). The load and the damper side
(rotor and gear train reflected to the input shaft) are then two degrees of freedom:

    J_L phi_L'' = T_s(phi_L) - F_L(w_L) - tau
    J_D phi_D'' = tau - F_D(w_D) - M_d(w_D)
    tau = tau_mesh(delta, delta'),   delta = phi_L - phi_D

with ``F_L`` the system friction FS_T (hinge, harness: on the load) and ``F_D`` the
ECD's FECD_T (on the damper side), each Coulomb with its own stiction, and ``M_d`` the
damping torque of :mod:`ecdsim.dynamics.equations` at ambient temperature. See
docs/dynamics.md, "Compliant backlash".

The state ``y = [phi_L, w_L, delta, w_D, E_d, E_m]`` (load angle and speed, the relative
angle, the damper side's speed, and the dissipations of the damper and of the mesh) is
integrated by RODAS4 (the tableau of :mod:`ecdsim.dynamics.rosenbrock`, here for one case
with a dense 6 x 6 Jacobian) between events, case by case. The relative angle is a state
of its own so that the mesh's deflection (T / c, small for a stiff mesh) keeps its own
accuracy. Within a segment every term is smooth; the events change the mode:

- the mesh: gap (no torque), pressing (``tau = c (delta -+ b/2) + d delta'``, its sign
  that of the flank), released (past the flank, but the limited torque is zero: the
  flanks separate faster than the mesh relaxes);
- each body: sliding forward, backward, or stuck (friction holds up to its breakaway);
- the load's spring piece: breakpoints, the end of travel, the start of travel (a latch
  holds the load and the run goes on until the damper side, overrunning it through the
  backlash, has come to rest).

Contact changes follow Modelica's rule with no extra threshold: a linear spring-damper
contact lasts about half a period of the two-inertia mode whatever the impact speed, so
bounces cannot accumulate in finite time, and once the drive presses the flanks together
by more than the remaining vibration the contact stays closed by itself (no chatter).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import FloatArray
from ecdsim.dynamics.damping import EddyLaw
from ecdsim.dynamics.problem import DynamicProblem
from ecdsim.dynamics.records import IntegratedRecord
from ecdsim.dynamics.result import (
    EVENT_KINDS,
    STATUSES,
    DynamicResult,
    EnergyBalance,
    EventLog,
    TrajectoryData,
)
from ecdsim.dynamics.rosenbrock import GAMMA, A, C, Trajectory

GAP, PRESS, RELEASED = 0, 1, 2  # mesh modes (PRESS and RELEASED with a flank side +-1)
_STICK_MARGIN = 1e-12  # as the rigid solver's: no restart by rounding at the boundary
_SETTLE_FRACTION = 1e-12  # rebounds below this fraction of the arrival's KE settle
CREEP_FRACTION = 1e-9  # speeds below this fraction of the scale, in equilibrium: at rest
HORIZON_TIME = 1e9  # [s] integration horizon without a stop time
MAX_STEPS = 200_000  # step attempts per case before the run is cut short (horizon)
_GC = tuple(tuple(GAMMA * c for c in row) for row in C)
_EV = {name: code for code, name in enumerate(EVENT_KINDS)}
_ST = {name: code for code, name in enumerate(STATUSES)}


@dataclass
class _Case:
    """One case's constants, at the input shaft (SI)."""

    index: int
    angles: FloatArray  # spring breakpoints [rad]
    torques: FloatArray  # spring torque at them [N*m]
    travel: float
    load_inertia: float
    damper_inertia: float
    load_friction: float  # FS_T, kinetic [N*m]
    load_static: float  # f_S FS_T [N*m]
    damper_friction: float  # FECD_T, kinetic [N*m]
    damper_static: float  # f_D FECD_T [N*m]
    stiffness: float  # c [N*m/rad]
    mesh_damping: float  # d [N*m*s/rad]
    half: float  # b / 2 [rad]
    restitution: float
    angle0: float
    speed0: float
    ambient: float
    damping: Callable[[float], tuple[float, float]]  # w_D -> (M_d, dM_d/dw_D)
    speed_scale: float
    torque_scale: float  # largest spring torque [N*m]
    stop_time: float
    rtol: float
    max_events: int


@dataclass
class _Mode:
    """The smooth regime of a segment."""

    load: int  # +1 / -1 sliding, 0 stuck
    damper: int
    mesh: int  # GAP, PRESS, RELEASED
    side: int  # flank of PRESS / RELEASED: +1 forward (load drives), -1 backward
    piece: int  # the load's spring piece
    at_start: bool = False  # load held against the start stop
    held: str = ""  # "latched" or "settled": the load is held at the end of travel


@dataclass
class _Run:
    """One case's outcome."""

    t: float = 0.0
    y: FloatArray = field(default_factory=lambda: np.zeros(6))
    status: str = "running"
    arrival_time: float = math.inf
    arrival_speed: float = 0.0
    arrival_ke: float = 0.0
    stuck: bool = False
    stuck_angle: float = math.nan
    stuck_time: float = math.nan
    engagement_time: float = math.inf
    rebound_speed: float = 0.0
    impacts: int = 0
    max_speed: float = 0.0
    spring_work: float = 0.0
    friction_work: float = 0.0
    impact_loss: float = 0.0
    max_mesh_torque: float = 0.0  # largest |tau| at the steps and events [N*m]
    latch_mesh_torque: float = 0.0  # the same once the load is held at the end [N*m]
    events: list[tuple[float, int, float, float]] = field(default_factory=list)
    times: list[float] = field(default_factory=list)
    states: list[FloatArray] = field(default_factory=list)
    slopes: list[FloatArray] = field(default_factory=list)

    def log(self, kind: str) -> None:
        self.events.append((self.t, _EV[kind], float(self.y[0]), float(self.y[1])))


# ---------------------------------------------------------------------------------------
# The equations of a mode


def _spring(case: _Case, piece: int, phi: float) -> tuple[float, float]:
    """Spring torque at phi on the piece, and its slope dT/dphi."""
    a0, a1 = case.angles[piece], case.angles[piece + 1]
    t0, t1 = case.torques[piece], case.torques[piece + 1]
    slope = (t1 - t0) / (a1 - a0) if a1 > a0 else 0.0
    return float(t0 + slope * (phi - a0)), float(slope)


def _mesh(case: _Case, mode: _Mode, delta: float, w_rel: float) -> tuple[float, float, float]:
    """Mesh torque and its derivatives in delta and w_rel, in the mode."""
    if mode.mesh != PRESS:
        return 0.0, 0.0, 0.0
    c, d = case.stiffness, case.mesh_damping
    raw = c * (delta - mode.side * case.half) + d * w_rel
    if raw * mode.side <= 0.0:  # rounding at the mode's boundary: the limit holds
        return 0.0, 0.0, 0.0
    return raw, c, d


def _rhs(case: _Case, mode: _Mode, y: FloatArray) -> FloatArray:
    phi, w_l, delta, w_d = float(y[0]), float(y[1]), float(y[2]), float(y[3])
    w_rel = w_l - w_d
    tau = _mesh(case, mode, delta, w_rel)[0]
    dy = np.zeros(6)
    if mode.load:
        spring = _spring(case, mode.piece, phi)[0]
        dy[0] = w_l
        dy[1] = (spring - mode.load * case.load_friction - tau) / case.load_inertia
    damping = case.damping(w_d)[0]
    if mode.damper:
        dy[3] = (tau - mode.damper * case.damper_friction - damping) / case.damper_inertia
    dy[2] = w_rel
    dy[4] = damping * w_d
    if mode.mesh == PRESS and tau != 0.0:
        dy[5] = case.mesh_damping * w_rel * w_rel
    elif mode.mesh != GAP and mode.side * (delta - mode.side * case.half) > 0.0:
        # The limited torque is zero: the mesh's elastic energy c (delta -+ b/2)^2 / 2
        # is lost as the flanks separate (power into the mesh 0 = dE_el/dt + loss).
        dy[5] = -case.stiffness * (delta - mode.side * case.half) * w_rel
    return dy


def _jacobian(case: _Case, mode: _Mode, y: FloatArray) -> FloatArray:
    phi, w_l, delta, w_d = float(y[0]), float(y[1]), float(y[2]), float(y[3])
    w_rel = w_l - w_d
    tau, dt_dq, dt_dw = _mesh(case, mode, delta, w_rel)
    jac = np.zeros((6, 6))
    if mode.load:
        slope = _spring(case, mode.piece, phi)[1]
        jl = case.load_inertia
        jac[0, 1] = 1.0
        jac[1, 0] = slope / jl
        jac[1, 1] = -dt_dw / jl
        jac[1, 2] = -dt_dq / jl
        jac[1, 3] = dt_dw / jl
    jac[2, 1] = 1.0
    jac[2, 3] = -1.0
    damping, d_damping = case.damping(w_d)
    if mode.damper:
        jd = case.damper_inertia
        jac[3, 1] = dt_dw / jd
        jac[3, 2] = dt_dq / jd
        jac[3, 3] = (-dt_dw - d_damping) / jd
    jac[4, 3] = d_damping * w_d + damping
    pressing = mode.mesh == PRESS and tau != 0.0
    if pressing:
        d = case.mesh_damping
        jac[5, 1] = 2.0 * d * w_rel
        jac[5, 3] = -2.0 * d * w_rel
    elif mode.mesh != GAP and mode.side * (delta - mode.side * case.half) > 0.0:
        c, deflection = case.stiffness, delta - mode.side * case.half
        jac[5, 1] = -c * deflection
        jac[5, 3] = c * deflection
        jac[5, 2] = -c * w_rel
    return jac


# Event codes of a segment
_END, _LOAD_ZERO, _LOAD_BREAK, _DAMPER_ZERO, _DAMPER_BREAK = 0, 1, 2, 3, 4
_MESH_A, _MESH_B = 5, 6


def _events(case: _Case, mode: _Mode, y: FloatArray) -> FloatArray:
    """The mode's event functions: each is > 0 inside the mode and reaches 0 at its event.

    Unused entries are +inf.
    """
    phi, w_l, delta, w_d = float(y[0]), float(y[1]), float(y[2]), float(y[3])
    w_rel = w_l - w_d
    g = np.full(7, np.inf)
    tau = _mesh(case, mode, delta, w_rel)[0]
    if mode.load > 0:
        g[_END] = case.angles[mode.piece + 1] - phi
    elif mode.load < 0:
        g[_END] = phi - case.angles[mode.piece]
    if mode.load:
        g[_LOAD_ZERO] = mode.load * w_l
    elif not mode.held:
        net = _spring(case, mode.piece, phi)[0] - tau
        limit = case.load_static * (1.0 + _STICK_MARGIN)
        g[_LOAD_BREAK] = limit - (net if mode.at_start else abs(net))
    if mode.damper:
        g[_DAMPER_ZERO] = mode.damper * w_d
    else:
        g[_DAMPER_BREAK] = case.damper_static * (1.0 + _STICK_MARGIN) - abs(tau)
    c, d, half = case.stiffness, case.mesh_damping, case.half
    if mode.mesh == GAP:
        g[_MESH_A] = half - delta  # reaches the forward flank
        g[_MESH_B] = delta + half  # reaches the backward flank
    elif mode.mesh == PRESS:
        g[_MESH_A] = mode.side * (c * (delta - mode.side * half) + d * w_rel)
    else:
        g[_MESH_A] = -mode.side * (c * (delta - mode.side * half) + d * w_rel)  # presses again
        g[_MESH_B] = mode.side * (delta - mode.side * half)  # back at the flank: the gap
    return g


# ---------------------------------------------------------------------------------------
# RODAS4 for one case


def _step(
    case: _Case, mode: _Mode, y: FloatArray, f0: FloatArray, h: float
) -> tuple[FloatArray, FloatArray]:
    """One RODAS4 step (the transformed form of :mod:`ecdsim.dynamics.rosenbrock`)."""
    hg = h * GAMMA
    try:
        inverse = np.linalg.inv(np.eye(6) - hg * _jacobian(case, mode, y))
    except np.linalg.LinAlgError:  # a singular stage matrix: the caller rejects the step
        nan = np.full(6, np.nan)
        return nan, nan
    k = [inverse @ (hg * f0)]
    last = y.copy()
    for i in range(1, 6):
        if i < 5:
            stage = y.copy()
            for a, kj in zip(A[i], k, strict=False):
                stage = stage + a * kj
            if i == 4:
                last = stage
        else:
            last = last + k[4]
            stage = last
        coupling = sum((gc * kj for gc, kj in zip(_GC[i], k, strict=False)), np.zeros(6))
        k.append(inverse @ (hg * _rhs(case, mode, stage) + coupling))
    return last + k[5], k[5]


# ---------------------------------------------------------------------------------------
# Decisions at events


def _decide(net: float, static: float) -> int:
    """A body at rest: stuck (0) if friction holds, else the direction it breaks away."""
    if abs(net) <= static * (1.0 + _STICK_MARGIN):
        return 0
    return 1 if net > 0.0 else -1


def _piece_for(case: _Case, phi: float, direction: int, start: int) -> int:
    """The spring piece ahead of phi in the direction of motion (walked from ``start``)."""
    last = case.angles.size - 2
    i = start
    while True:
        if i < last and (case.angles[i + 1] <= phi if direction >= 0 else case.angles[i + 1] < phi):
            i += 1
        elif i > 0 and (case.angles[i] > phi if direction >= 0 else case.angles[i] >= phi):
            i -= 1
        else:
            return i


def _load_net(case: _Case, mode: _Mode, y: FloatArray) -> float:
    tau = _mesh(case, mode, float(y[2]), float(y[1] - y[3]))[0]
    return _spring(case, mode.piece, float(y[0]))[0] - tau


def _set_load_mode(case: _Case, mode: _Mode, y: FloatArray, run: _Run) -> None:
    """The load at rest (speed 0): stick or break away."""
    y[1] = 0.0
    mode.piece = _piece_for(case, float(y[0]), 1, mode.piece)
    net = _load_net(case, mode, y)
    at_start = float(y[0]) <= 0.0
    if at_start and net < 0.0:
        mode.load, mode.at_start = 0, True
        return
    mode.load = _decide(net, case.load_static)
    mode.at_start = at_start and mode.load == 0
    if mode.load:
        mode.piece = _piece_for(case, float(y[0]), mode.load, mode.piece)
        run.log("breakaway")


def _set_damper_mode(case: _Case, mode: _Mode, y: FloatArray) -> None:
    y[3] = 0.0
    tau = _mesh(case, mode, float(y[2]), float(y[1]))[0]
    mode.damper = _decide(tau, case.damper_static)


def _enter_gap(case: _Case, mode: _Mode, y: FloatArray, run: _Run) -> None:
    """Back inside the gap; without lost motion the other flank is met at once."""
    if mode.mesh == PRESS:
        run.log("separate")  # (from RELEASED the parting was logged already)
    mode.mesh = GAP
    if case.half <= 0.0:
        w_rel = float(y[1] - y[3])
        if w_rel != 0.0:
            mode.mesh, mode.side = PRESS, (1 if w_rel > 0.0 else -1)
            run.log("contact")


def _mesh_event(case: _Case, mode: _Mode, y: FloatArray, code: int, run: _Run) -> None:
    if mode.mesh == GAP:
        mode.mesh, mode.side = PRESS, (1 if code == _MESH_A else -1)
        if not math.isfinite(run.engagement_time):
            run.engagement_time = run.t
            run.log("engage")
        else:
            run.log("contact")
    elif mode.mesh == PRESS:
        deflection = mode.side * (float(y[2]) - mode.side * case.half)
        if deflection > 0.0 and case.mesh_damping > 0.0:
            mode.mesh = RELEASED
            run.log("separate")
        else:
            _enter_gap(case, mode, y, run)
    elif code == _MESH_A:
        mode.mesh = PRESS
        run.log("contact")
    else:
        _enter_gap(case, mode, y, run)


# ---------------------------------------------------------------------------------------
# One case


def _kinetic(case: _Case, y: FloatArray) -> float:
    return 0.5 * (case.load_inertia * float(y[1]) ** 2 + case.damper_inertia * float(y[3]) ** 2)


def elastic_energy(stiffness: float, half: float, delta: float) -> float:
    """Energy stored in the mesh's spring, ``c (|delta| - b/2)^2 / 2`` past a flank [J]."""
    deflection = max(abs(delta) - half, 0.0)
    return 0.5 * stiffness * deflection * deflection


def _initial_mode(case: _Case, y: FloatArray, run: _Run) -> _Mode:
    mode = _Mode(load=0, damper=0, mesh=GAP, side=1, piece=0)
    mode.piece = _piece_for(case, case.angle0, 1, 0)
    if case.half <= 0.0:
        # No lost motion: the flanks touch with no torque; the mesh's side is the one
        # the relative motion will press (the bodies' accelerations, mesh torque 0).
        run.engagement_time = 0.0
        mode.mesh = PRESS
        accel_l = (_spring(case, mode.piece, case.angle0)[0]) / case.load_inertia
        mode.side = 1 if accel_l >= 0.0 else -1
    elif case.speed0 < 0.0:
        mode.mesh, mode.side = PRESS, -1  # the load starts against the backward flank
    if case.speed0 != 0.0:
        mode.load = 1 if case.speed0 > 0.0 else -1
        mode.piece = _piece_for(case, case.angle0, mode.load, mode.piece)
    else:
        _set_load_mode(case, mode, y, run)
    if y[3] != 0.0:
        mode.damper = 1 if y[3] > 0.0 else -1
    else:
        _set_damper_mode(case, mode, y)
    _recheck(case, mode, y, run)
    return mode


def _locate(
    case: _Case, mode: _Mode, y: FloatArray, f0: FloatArray, h: float, code: int, g0: float
) -> tuple[float, FloatArray]:
    """Time into the step where event ``code`` occurs, and the state just past it.

    The Illinois variant of regula falsi on ``g(step(y, s))``: every trial is a full
    RODAS4 step from the step's start, so the event state has the integrator's accuracy.
    """
    return _root(case, mode, y, f0, h, lambda ys: float(_events(case, mode, ys)[code]), g0)


def _root(
    case: _Case,
    mode: _Mode,
    y: FloatArray,
    f0: FloatArray,
    h: float,
    g: Callable[[FloatArray], float],
    g0: float,
) -> tuple[float, FloatArray]:
    """Where ``g`` (> 0 at the step's start) reaches 0 within the step (see _locate)."""
    if g0 <= 0.0:
        return 0.0, y.copy()
    a, ga = 0.0, g0
    b = h
    yb = _step(case, mode, y, f0, h)[0]
    gb = g(yb)
    side = 0
    for _ in range(100):
        s = (a * gb - b * ga) / (gb - ga) if gb != ga else 0.5 * (a + b)
        if not a < s < b:
            s = 0.5 * (a + b)
        ys = _step(case, mode, y, f0, s)[0]
        gs = g(ys)
        if gs > 0.0:
            a, ga = s, gs
            if side == 1:
                gb *= 0.5
            side = 1
        else:
            b, gb, yb = s, gs, ys
            if side == -1:
                ga *= 0.5
            side = -1
        if b - a <= 1e-13 * h or gs == 0.0:
            break
    return b, yb


def _solve_case(case: _Case, record: bool) -> _Run:
    run = _Run()
    y = np.array(
        [case.angle0, case.speed0, -case.half, case.speed0 if case.half <= 0 else 0.0, 0.0, 0.0]
    )
    run.y = y
    run.max_speed = max(case.speed0, 0.0)
    run.log("release")
    mode = _initial_mode(case, y, run)
    atol = (
        case.rtol
        * 1e-3
        * np.array(
            [
                case.travel,
                case.speed_scale,
                0.0,
                case.speed_scale,
                max(case.speed_scale * case.speed_scale * case.load_inertia, 1e-300),
                max(case.speed_scale * case.speed_scale * case.load_inertia, 1e-300),
            ]
        )
    )
    # The mesh's deflection is of order drive / c, small for a stiff mesh: its own scale.
    atol[2] = case.rtol * 1e-3 * max(min(case.travel, case.torque_scale / case.stiffness), 1e-300)
    atol[1] = atol[3] = min(case.rtol * 1e-3, 1e-12) * case.speed_scale
    h = 1e-3 * min(
        case.travel / case.speed_scale,
        math.sqrt(
            case.load_inertia
            * case.damper_inertia
            / ((case.load_inertia + case.damper_inertia) * case.stiffness)
        ),
    )
    f = _rhs(case, mode, y)
    events = 0
    attempts = 0
    if record:
        run.times.append(0.0)
        run.states.append(y.copy())
        run.slopes.append(f.copy())
    while run.status == "running":
        if mode.load == 0 and mode.damper == 0:
            if mode.held:
                run.status = mode.held  # the damper side has come to rest too
            else:
                _finish_stuck(case, run, y)
            break
        if events >= case.max_events:
            run.status = "event_limit"
            run.log("event_limit")
            break
        if run.t >= case.stop_time:
            run.status = "stop_time"
            run.log("stop_time")
            break
        if run.t >= HORIZON_TIME or attempts >= MAX_STEPS:
            run.status = "horizon"
            run.log("horizon")
            break
        attempts += 1
        h = min(h, case.stop_time - run.t, HORIZON_TIME)
        y1, err = _step(case, mode, y, f, h)
        scale = atol + case.rtol * np.maximum(np.abs(y), np.abs(y1))
        norm = float(np.max(np.abs(err) / scale))
        if not math.isfinite(norm) or norm > 1.0:
            h *= max(0.2, 0.9 * norm**-0.25) if math.isfinite(norm) else 0.2
            continue
        g0 = _events(case, mode, y)
        g1 = _events(case, mode, y1)
        fired = np.flatnonzero(((g0 > 0.0) & (g1 <= 0.0)) | ((g0 == 0.0) & (g1 < 0.0)))
        code = -1
        hint = y1.copy()
        if fired.size:
            # The earliest: locate each (few fire together) and keep the first.
            best = (math.inf, y1, -1)
            for j in fired:
                s, ys = _locate(case, mode, y, f, h, int(j), float(g0[j]))
                if s < best[0]:
                    best = (s, ys, int(j))
            h_taken, y1, code = best
        else:
            h_taken = h
        # Energy of the segment part: the spring (exact on the piece) and friction.
        run.t += h_taken
        f1 = _rhs(case, mode, y1)
        if record:
            run.times.append(run.t)
            run.states.append(y1.copy())
            run.slopes.append(f1.copy())
        _account_part(case, mode, run, y, y1)
        _torque_peak(case, mode, y, f, h_taken, f1, run)
        y[:] = y1
        run.y = y
        f = f1
        _track_torque(case, mode, y, run)
        if not math.isfinite(run.arrival_time):
            run.max_speed = max(run.max_speed, float(y[1]))
        if code < 0:
            h *= min(5.0, max(0.2, 0.9 * max(norm, 1e-10) ** -0.25))
            if _creeping(case, mode, y):
                if mode.held:
                    y[3] = 0.0
                    run.status = mode.held
                else:
                    _finish_creep(case, run, y)
            continue
        events += 1
        _apply(case, mode, y, code, run, hint)
        _recheck(case, mode, y, run)
        if run.status == "running":
            f = _rhs(case, mode, y)
            if record:
                run.times.append(run.t)
                run.states.append(y.copy())
                run.slopes.append(f.copy())
    return run


def _torque_rate(case: _Case, mode: _Mode, f: FloatArray) -> float:
    """d tau / dt of a pressing mesh, from the state's derivative f, times the flank side."""
    return mode.side * (case.stiffness * float(f[2]) + case.mesh_damping * float(f[1] - f[3]))


def _torque_peak(
    case: _Case,
    mode: _Mode,
    y: FloatArray,
    f0: FloatArray,
    h: float,
    f1: FloatArray,
    run: _Run,
) -> None:
    """A peak of the pressing mesh's torque inside the step: located (its rate's zero, by
    re-stepping as the events are) and counted in the maxima."""
    if mode.mesh != PRESS or h <= 0.0:
        return
    rate0, rate1 = _torque_rate(case, mode, f0), _torque_rate(case, mode, f1)
    if not (rate0 > 0.0 and rate1 < 0.0):
        return
    _, ys = _root(
        case, mode, y, f0, h, lambda yy: _torque_rate(case, mode, _rhs(case, mode, yy)), rate0
    )
    _track_torque(case, mode, ys, run)


def _track_torque(case: _Case, mode: _Mode, y: FloatArray, run: _Run) -> None:
    """The largest mesh torque, at the accepted steps and the events (where the peak of
    an undamped contact lies: the damper side's zero speed)."""
    torque = abs(_mesh(case, mode, float(y[2]), float(y[1] - y[3]))[0])
    run.max_mesh_torque = max(run.max_mesh_torque, torque)
    if mode.held:
        run.latch_mesh_torque = max(run.latch_mesh_torque, torque)


def _account_part(case: _Case, mode: _Mode, run: _Run, y0: FloatArray, y1: FloatArray) -> None:
    """Spring work (exact on the linear piece) and Coulomb friction work of a part step."""
    dphi = float(y1[0] - y0[0])
    if mode.load:
        torque, slope = _spring(case, mode.piece, float(y0[0]))
        run.spring_work += torque * dphi + 0.5 * slope * dphi * dphi
        run.friction_work += case.load_friction * abs(dphi)
    if mode.damper:
        # phi_D = phi_L - delta
        run.friction_work += case.damper_friction * abs(dphi - float(y1[2] - y0[2]))


def _creeping(case: _Case, mode: _Mode, y: FloatArray) -> bool:
    """Both speeds negligible and both bodies within their breakaway: at rest for good."""
    threshold = CREEP_FRACTION * case.speed_scale
    if abs(y[1]) > threshold or abs(y[3]) > threshold:
        return False
    tau = _mesh(case, mode, float(y[2]), 0.0)[0]
    net = 0.0 if mode.held else _spring(case, mode.piece, float(y[0]))[0] - tau
    # A sliding body creeps towards where its torques balance its kinetic friction, at
    # most its breakaway; at these speeds the damping is CREEP_FRACTION of the drive.
    slack = 1e3 * CREEP_FRACTION * case.torque_scale
    return abs(net) <= case.load_static + slack and abs(tau) <= case.damper_static + slack


def _finish_stuck(case: _Case, run: _Run, y: FloatArray) -> None:
    run.status = "stuck"
    run.stuck, run.stuck_angle, run.stuck_time = True, float(y[0]), run.t
    run.log("stick")


def _finish_creep(case: _Case, run: _Run, y: FloatArray) -> None:
    y[1] = y[3] = 0.0
    run.status = "creep"
    run.stuck, run.stuck_angle, run.stuck_time = True, float(y[0]), math.inf
    run.t = math.inf
    run.log("creep")


def _apply(case: _Case, mode: _Mode, y: FloatArray, code: int, run: _Run, hint: FloatArray) -> None:
    """Apply event ``code`` at state y; ``hint`` is a state a little later (the trial
    step's end), whose torques give the direction of a breakaway from a zero-friction
    rest, where the torque at the event itself is still zero."""
    if code == _END:
        before = float(y[1])
        _load_end(case, mode, y, run)
        if run.status == "running" and float(y[1]) != before:
            _resolve_mesh(case, mode, y, run)  # the load's speed jumped at a stop
    elif code == _LOAD_ZERO:
        run.log("zero_speed")
        _set_load_mode(case, mode, y, run)
    elif code == _LOAD_BREAK:
        net = _load_net(case, mode, y)
        if abs(net) <= 0.5 * case.load_static or net == 0.0:
            net = _load_net(case, mode, hint)
        mode.load = 1 if net > 0.0 else -1
        mode.at_start = False
        mode.piece = _piece_for(case, float(y[0]), mode.load, mode.piece)
        run.log("breakaway")
    elif code == _DAMPER_ZERO:
        _set_damper_mode(case, mode, y)
    elif code == _DAMPER_BREAK:
        tau = _mesh(case, mode, float(y[2]), float(y[1]))[0]
        if abs(tau) <= 0.5 * case.damper_static or tau == 0.0:
            tau = _mesh(case, mode, float(hint[2]), float(hint[1]))[0]
        mode.damper = 1 if tau > 0.0 else -1
    else:
        _mesh_event(case, mode, y, code, run)


def _resolve_mesh(case: _Case, mode: _Mode, y: FloatArray, run: _Run) -> None:
    """The mesh's mode after a jump of the speeds (an impact on a stop, a settle).

    A jump of w_rel changes the limited torque at once: a pressing mesh whose torque the
    jump turns to zero is released (or back in the gap), a released one that it loads
    presses again.
    """
    if mode.mesh == GAP:
        return
    side = mode.side
    deflection = side * (float(y[2]) - side * case.half)
    raw = side * (case.stiffness * (deflection * side) + case.mesh_damping * float(y[1] - y[3]))
    if mode.mesh == PRESS and raw <= 0.0:
        if deflection > 0.0 and case.mesh_damping > 0.0:
            mode.mesh = RELEASED
            run.log("separate")
        else:
            _enter_gap(case, mode, y, run)
    elif mode.mesh == RELEASED and deflection <= 0.0:
        _enter_gap(case, mode, y, run)
    elif mode.mesh == RELEASED and raw > 0.0:
        mode.mesh = PRESS
        run.log("contact")


def _recheck(case: _Case, mode: _Mode, y: FloatArray, run: _Run) -> None:
    """A stuck body whose holding torque a mode change has just exceeded breaks away now.

    (Its breakaway event function would start already negative, which no root finder
    sees: e.g. the mesh's damping torque d w_rel acting at once when the flanks meet.)
    """
    if mode.load == 0 and not mode.held:
        net = _load_net(case, mode, y)
        beyond = (net if mode.at_start else abs(net)) > case.load_static * (1.0 + _STICK_MARGIN)
        if beyond:
            mode.load = 1 if net > 0.0 else -1
            mode.at_start = False
            mode.piece = _piece_for(case, float(y[0]), mode.load, mode.piece)
            run.log("breakaway")
    if mode.damper == 0:
        tau = _mesh(case, mode, float(y[2]), float(y[1]))[0]
        if abs(tau) > case.damper_static * (1.0 + _STICK_MARGIN):
            mode.damper = 1 if tau > 0.0 else -1


def _load_end(case: _Case, mode: _Mode, y: FloatArray, run: _Run) -> None:
    """A breakpoint, the end of travel or the start stop (the load's angle lands on it)."""
    if mode.load > 0:
        y[0] = case.angles[mode.piece + 1]
        if y[0] >= case.travel:
            _arrive(case, mode, y, run)
            return
        mode.piece += 1
        run.log("breakpoint")
        return
    y[0] = case.angles[mode.piece]
    if y[0] > 0.0:
        mode.piece -= 1
        run.log("breakpoint")
        return
    run.log("start_stop")
    ke = 0.5 * case.load_inertia * y[1] ** 2
    if case.restitution <= 0.0:
        run.impact_loss += ke
        _set_load_mode(case, mode, y, run)
        return
    _rebound(case, mode, y, run, ke, arriving=False)


def _arrive(case: _Case, mode: _Mode, y: FloatArray, run: _Run) -> None:
    ke = _kinetic(case, y)
    run.log("arrive")
    if not math.isfinite(run.arrival_time):
        run.arrival_time, run.arrival_speed, run.arrival_ke = run.t, float(y[1]), ke
    if case.restitution <= 0.0:
        run.log("latch")
        _hold(case, mode, y, run, "latched")
        return
    _rebound(case, mode, y, run, 0.5 * case.load_inertia * y[1] ** 2, arriving=True)


def _hold(case: _Case, mode: _Mode, y: FloatArray, run: _Run, how: str) -> None:
    """The load is held at the end of travel (latch, or rebounds settled); the damper side
    turns on through the mesh until it comes to rest, overrunning the load across the gap
    (the latch takes the load's kinetic energy, booked as impact loss)."""
    run.impact_loss += 0.5 * case.load_inertia * float(y[1]) ** 2
    y[1] = 0.0
    mode.load, mode.at_start, mode.held = 0, False, how


def _rebound(case: _Case, mode: _Mode, y: FloatArray, run: _Run, ke: float, arriving: bool) -> None:
    """The load bounces off a stop (Newton's law); the damper side goes on through the mesh."""
    e = case.restitution
    after = -e * float(y[1])
    rebound_ke = e * e * ke
    reference = max(run.arrival_ke, ke, np.finfo(float).tiny)
    settle = rebound_ke <= _SETTLE_FRACTION * reference
    if arriving and run.impacts == 0 and not settle:
        run.rebound_speed = after
    run.impacts += 1
    run.impact_loss += ke if settle else ke - rebound_ke
    if settle:
        y[1] = 0.0
        if arriving:
            run.log("settle")
            _hold(case, mode, y, run, "settled")
        else:
            _set_load_mode(case, mode, y, run)
        return
    y[1] = after
    mode.load = 1 if after > 0.0 else -1
    mode.piece = _piece_for(case, float(y[0]), mode.load, mode.piece)


# ---------------------------------------------------------------------------------------
# The batch


def _damping_law(
    eddy: EddyLaw, case: int, ambient: float, ratio: float, gearbox_damping: float, rate: float
) -> Callable[[float], tuple[float, float]]:
    """``w_D -> (M_d, dM_d/dw_D)`` at the ambient temperature."""
    if eddy.name == "linear":
        return lambda w: (rate * w, rate)
    one = eddy.take(np.array([case]))
    factor = np.maximum(one.factor(np.array([ambient])), 0.0)

    def law(w: float) -> tuple[float, float]:
        shaft = np.array([ratio * w])
        torque = float(one.torque_at_factor(shaft, factor)[0])
        slope = float(one.speed_derivative_at_factor(shaft, factor)[0])
        return (
            ratio * (torque + gearbox_damping * ratio * w),
            ratio * ratio * (slope + gearbox_damping),
        )

    return law


def _cases(problem: DynamicProblem) -> list[_Case]:
    shape = problem.batch_shape
    n = int(np.prod(shape)) if shape else 1
    points = problem.angles.shape[0]

    def flat(a: FloatArray) -> FloatArray:
        return np.reshape(np.broadcast_to(np.asarray(a, float), shape), n)

    angles = np.reshape(problem.angles, (points, n))
    torques = np.reshape(problem.torques, (points, n))
    eddy = problem.eddy.flattened(shape)
    arrays = {
        name: flat(getattr(problem, name))
        for name in (
            "travel",
            "load_inertia",
            "damper_inertia",
            "system_friction",
            "ecd_friction",
            "system_static_friction_factor",
            "static_friction_factor",
            "gear_stiffness",
            "gear_mesh_damping",
            "lost_motion",
            "restitution",
            "initial_angle",
            "initial_speed",
            "ambient_temperature",
            "gear_ratio",
            "gearbox_damping_rate",
            "damping_rate",
        )
    }
    out = []
    for i in range(n):
        v = {k: float(a[i]) for k, a in arrays.items()}
        drive = float(np.max(np.abs(torques[:, i])))
        total = v["load_inertia"] + v["damper_inertia"]
        rate = v["damping_rate"]
        # Speeds scale as the quasi-static speed drive / B, or the free one
        # sqrt(drive travel / J) without damping, or the initial speed.
        scale = max(
            abs(v["initial_speed"]),
            drive / rate if rate > 0.0 else 0.0,
            math.sqrt(drive * v["travel"] / total),
            1e-300,
        )
        out.append(
            _Case(
                index=i,
                angles=np.ascontiguousarray(angles[:, i], dtype=float),
                torques=np.ascontiguousarray(torques[:, i], dtype=float),
                travel=v["travel"],
                load_inertia=v["load_inertia"],
                damper_inertia=v["damper_inertia"],
                load_friction=v["system_friction"],
                load_static=v["system_friction"] * v["system_static_friction_factor"],
                damper_friction=v["ecd_friction"],
                damper_static=v["ecd_friction"] * v["static_friction_factor"],
                stiffness=v["gear_stiffness"],
                mesh_damping=v["gear_mesh_damping"],
                half=0.5 * v["lost_motion"],
                restitution=v["restitution"],
                angle0=v["initial_angle"],
                speed0=v["initial_speed"],
                ambient=v["ambient_temperature"],
                damping=_damping_law(
                    eddy,
                    i,
                    v["ambient_temperature"],
                    v["gear_ratio"],
                    v["gearbox_damping_rate"],
                    rate,
                ),
                speed_scale=scale,
                torque_scale=max(drive, 1e-300),
                stop_time=problem.stop_time,
                rtol=problem.rtol,
                max_events=problem.max_events,
            )
        )
    return out


class _Dense:
    """A case's whole run as a callable ``t -> [phi_L, w_L, T_d, E_d]`` (Hermite steps).

    The steps are evaluated by :class:`ecdsim.dynamics.rosenbrock.Trajectory`; the damper
    side's rows are dropped and the damper stays at the ambient temperature.
    """

    def __init__(self, times: FloatArray, states: FloatArray, slopes: FloatArray, ambient: float):
        self.steps = Trajectory(times, states, slopes)
        self.ambient = ambient

    def __call__(self, t: FloatArray) -> FloatArray:
        y = self.steps(t)
        return np.stack([y[0], y[1], np.full(y[0].shape, self.ambient), y[4]])


def solve_compliant(problem: DynamicProblem, record: bool = True) -> DynamicResult:
    """Solve every case of ``problem`` with the compliant mesh (one case at a time)."""
    cases = _cases(problem)
    runs = [_solve_case(case, record) for case in cases]
    shape = problem.batch_shape

    def arr(values: list[float] | list[int] | list[bool], dtype: type = float) -> NDArray:  # type: ignore[type-arg]
        return np.asarray(values, dtype=dtype).reshape(shape)

    keeps = ("latched", "stop_time", "event_limit", "horizon")
    final_speed = [float(r.y[1]) if r.status in keeps else 0.0 for r in runs]
    final_ke = [
        _kinetic(c, r.y) if r.status in keeps else 0.5 * c.damper_inertia * float(r.y[3]) ** 2
        for c, r in zip(cases, runs, strict=True)
    ]
    ke0 = [_kinetic(c, np.array([0, c.speed0, 0, c.speed0 if c.half <= 0 else 0.0])) for c in cases]
    energy = EnergyBalance(
        spring_work=arr([r.spring_work for r in runs]),
        initial_kinetic_energy=arr(ke0),
        damper_dissipation=arr([float(r.y[4]) for r in runs]),
        friction_dissipation=arr([r.friction_work for r in runs]),
        engagement_loss=arr([0.0] * len(runs)),
        impact_loss=arr([r.impact_loss for r in runs]),
        final_kinetic_energy=arr(final_ke),
        gear_loss=arr([0.0] * len(runs)),
        mesh_dissipation=arr([float(r.y[5]) for r in runs]),
        elastic_energy=arr(
            [
                elastic_energy(c.stiffness, c.half, float(r.y[2]))
                for c, r in zip(cases, runs, strict=True)
            ]
        ),
    )
    log = _event_log(runs)
    trajectory = None
    if record:
        integrated = [
            IntegratedRecord(
                case=c.index,
                start_time=0.0,
                duration=r.times[-1],
                start_angle=0.0,
                direction=1.0,
                solution=_Dense(
                    np.asarray(r.times),
                    np.stack(r.states, axis=1),
                    np.stack(r.slopes, axis=1),
                    c.ambient,
                ),
            )
            for c, r in zip(cases, runs, strict=True)
            if len(r.times) > 1
        ]
        n = len(cases)
        flat = {
            name: np.reshape(np.broadcast_to(np.asarray(getattr(problem, name), float), shape), n)
            for name in (
                "ecd_friction",
                "system_friction",
                "static_friction_factor",
                "system_static_friction_factor",
                "gear_ratio",
                "gearbox_damping_rate",
            )
        }
        ends = np.array(
            [r.t if math.isfinite(r.t) else (r.times[-1] if r.times else 0.0) for r in runs]
        )
        angle0 = np.array([c.angle0 for c in cases])
        trajectory = TrajectoryData(
            closed=[],
            integrated=integrated,
            initial=(
                angle0,
                np.array([c.speed0 for c in cases]),
                np.array([c.ambient for c in cases]),
                np.array([c.half <= 0 for c in cases]),
            ),
            final=(
                np.array([float(r.y[0]) for r in runs]),
                np.asarray(final_speed),
                np.array([c.ambient for c in cases]),
                np.ones(n, dtype=bool),
                ends,
            ),
            display_end=ends,
            angles=np.stack([c.angles for c in cases], axis=1),
            torques=np.stack([c.torques for c in cases], axis=1),
            ecd_friction=flat["ecd_friction"],
            system_friction=flat["system_friction"],
            factor=flat["static_friction_factor"],
            system_factor=flat["system_static_friction_factor"],
            ratio=flat["gear_ratio"],
            gearbox_damping=flat["gearbox_damping_rate"],
            eddy=problem.eddy.flattened(shape),
        )
    ambient = [c.ambient for c in cases]
    return DynamicResult(
        batch_shape=shape,
        temperature=arr(ambient),
        deployment_time=arr([r.arrival_time for r in runs]),
        arrival_speed=arr([r.arrival_speed for r in runs]),
        arrival_kinetic_energy=arr([r.arrival_ke for r in runs]),
        final_time=arr([r.t for r in runs]),
        final_angle=arr([float(r.y[0]) for r in runs]),
        final_speed=arr(final_speed),
        final_temperature=arr(ambient),
        stuck=arr([r.stuck for r in runs], bool),
        stuck_angle=arr([r.stuck_angle for r in runs]),
        stuck_time=arr([r.stuck_time for r in runs]),
        max_speed=arr([r.max_speed for r in runs]),
        max_damper_temperature=arr(ambient),
        engagement_time=arr([r.engagement_time for r in runs]),
        rebound_speed=arr([r.rebound_speed for r in runs]),
        impacts=arr([r.impacts for r in runs], np.int64),
        status=arr([_ST[r.status] for r in runs], np.int8),
        energy=energy,
        events=log,
        trajectory=trajectory,
        max_mesh_torque=arr([r.max_mesh_torque for r in runs]),
        latch_mesh_torque=arr([r.latch_mesh_torque for r in runs]),
    )


def _event_log(runs: list[_Run]) -> EventLog:
    rows = [(i, *e) for i, r in enumerate(runs) for e in r.events]
    if not rows:
        empty = np.zeros(0)
        return EventLog(np.zeros(0, np.intp), empty, np.zeros(0, np.int8), empty, empty)
    return EventLog(
        np.array([r[0] for r in rows], np.intp),
        np.array([r[1] for r in rows]),
        np.array([r[2] for r in rows], np.int8),
        np.array([r[3] for r in rows]),
        np.array([r[4] for r in rows]),
    )
