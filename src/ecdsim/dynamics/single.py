"""One deployment solved with Python floats around the compiled RODAS4 segment.

The vectorised event loop (:mod:`ecdsim.dynamics.solver`) handles a batch with NumPy
arrays; with one case every array holds one number and each operation costs its
dispatch (about a microsecond), some 0.3 ms per deployment beside a compiled
integration of about 0.1 ms (the MSL brake spin-down). This module runs the same loop
for one case with ``float`` arithmetic: the same decisions in the same order, the same
IEEE operations on the same operands, and the same kernel
(:func:`ecdsim.dynamics.compiled._segment`, called directly with a parameter row built
from scalars), so that its :class:`~ecdsim.dynamics.result.DynamicResult` is the
vectorised one bit for bit (``tests/test_dynamics_single.py`` holds the two together).

The subset it takes (:func:`eligible`; anything else stays on the vectorised path):
one case of a rigid mesh (not compliant), without gravity, with an ideal gear (not
lossy), without Stribeck friction, with one-node heating or none, without lost motion
(``lost_motion <= 0``: engaged from the release), with a linear spring (two
breakpoints), and with nonlinear engaged segments (roll-off and/or heating) integrated
by "RODAS4" with the compiled kernel available. In that subset every segment is an
engaged integrated one: no closed form, no engagement, no power-flow switch, no
spring-table run. A warm start (an initial rotor rise) is taken as the vectorised
:func:`~ecdsim.dynamics.solver._thermal_start` takes it.

Each function names the vectorised function it mirrors; the equations are those of
docs/dynamics.md (the segment equations, Eq. 1 and the Kloss law, Incropera's Eq. 5.2 in
the log state of :mod:`ecdsim.physics.thermal`).
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from types import ModuleType
from typing import Any, TypeVar

import numpy as np

from ecdsim._types import FloatArray
from ecdsim.dynamics import integrate, linear
from ecdsim.dynamics.damping import KlossEddy, LinearEddy
from ecdsim.dynamics.equations import Model
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
from ecdsim.dynamics.rosenbrock import Trajectory
from ecdsim.dynamics.rules import KEEPING_SPEED, SETTLE_FRACTION, STICK_MARGIN
from ecdsim.physics import thermal

# Tests switch this off to run the same problem on the vectorised path.
ENABLED = True

_EV = {name: code for code, name in enumerate(EVENT_KINDS)}
_ST = {name: code for code, name in enumerate(STATUSES)}
_KEEPS = frozenset(_ST[name] for name in KEEPING_SPEED)
_REACH, _ZERO, _CAP, _REST = linear.REACH, linear.ZERO, linear.CAP, linear.REST
_TINY = float(np.finfo(float).tiny)
# exp overflows above this argument; NumPy's expm1 then gives inf (with a warning).
_EXP_LIMIT = 709.0
_T = TypeVar("_T")


def eligible(problem: DynamicProblem) -> bool:
    """Whether :func:`solve` takes ``problem`` (the subset of the module notes).

    Cheap: attribute reads and tests of one-element fields (the problem's ``lossy``,
    ``stribeck``, ``compliant`` and ``has_gravity`` for one case), numba's module last.
    """
    if not ENABLED or problem.friction.size != 1 or problem.angles.shape[0] != 2:
        return False
    if problem.integrator != integrate.BATCHED or not problem.nonlinear or problem.two_node:
        return False
    if not isinstance(problem.eddy, (LinearEddy, KlossEddy)):
        return False
    gravity = problem.gravity_amplitude
    if (gravity is not None and gravity.item() != 0.0) or not problem.lost_motion.item() <= 0.0:
        return False
    if problem.forward_efficiency.item() != 1.0 or problem.backward_efficiency.item() != 1.0:
        return False
    if math.isfinite(problem.stribeck_speed.item()):
        return False
    if math.isfinite(problem.gear_stiffness.item()):
        return False
    return integrate.compiled_kernel() is not None


def _item(value: float | FloatArray) -> float:
    """The one number of a one-case field (a float or an array of one element)."""
    return float(value.item()) if isinstance(value, np.ndarray) else float(value)


def _maximum(a: float, b: float) -> float:
    """``np.maximum`` of two floats: NaN if either is, else the larger (b when equal)."""
    return a if a > b or a != a else b


def _minimum(a: float, b: float) -> float:
    """``np.minimum`` of two floats: NaN if either is, else the smaller (b when equal)."""
    return a if a < b or a != a else b


def _sign(value: float) -> float:
    """``np.sign`` of a float."""
    if value > 0.0:
        return 1.0
    if value < 0.0:
        return -1.0
    return 0.0 if value == 0.0 else value  # NaN stays NaN


@dataclass(slots=True)
class _Case:
    """The case's constants (the one-element fields of solver._Cases, as floats)."""

    lower: float  # the spring's first angle [rad]
    upper: float  # its last angle [rad]
    start_torque: float  # its torque at ``lower`` [N*m]
    slope: float  # dT/dphi (solver._piece) [N*m/rad]
    travel: float
    load_inertia: float
    total_inertia: float
    ecd_friction: float
    system_friction: float
    factor: float
    system_factor: float
    restitution: float
    angle0: float
    speed0: float
    ambient: float
    linear_damping: float  # BECD_T at ambient, the integrator's speed scale
    coefficient: float  # c of the damping law's temperature factor [1/K]
    ambient_factor: float  # f_a (Model.ambient_factor)
    zero: float  # the law's zero temperature T_ref - 1/c where c < 0, else inf [degC]
    heating: bool
    law: tuple[float, ...]  # the damping law's parameters in its fields' order (_eddy_values)

    def temperature(self, state: float) -> float:
        """:meth:`Model.temperature` of one state s: ``T_amb + f_a s E(c s)``, clipped.

        ``thermal.temperature_from_factor_log`` with NumPy's expm1 (which differs from
        ``math.expm1`` in the last place for some arguments) where ``c s != 0``.
        """
        z = self.coefficient * state
        if z == 0.0:
            growth = 1.0
        elif z < _EXP_LIMIT:
            growth = float(np.expm1(z)) / z
        else:
            with np.errstate(over="ignore"):  # inf, as thermal._exprel gives it
                growth = float(np.expm1(z)) / z
        return _minimum(self.ambient + self.ambient_factor * state * growth, self.zero)


@dataclass(slots=True)
class _Run:
    """The running state of the case (solver._State, one case, as floats)."""

    t: float
    phi: float
    w: float
    temp: float
    heat: float = 0.0  # the temperature state s
    done: bool = False
    status: int = 0
    hold_from: float = 0.0
    display_end: float = 0.0
    arrival_time: float = math.inf
    arrival_speed: float = 0.0
    arrival_ke: float = 0.0
    stuck: bool = False
    stuck_angle: float = math.nan
    stuck_time: float = math.nan
    rebound_speed: float = 0.0
    impacts: int = 0
    max_speed: float = 0.0
    max_temp: float = 0.0
    spring_work: float = 0.0
    friction_work: float = 0.0
    damper_work: float = 0.0
    impact_loss: float = 0.0
    start_ke: float = 0.0  # the largest impact's kinetic energy on the start stop [J]
    times: list[float] = field(default_factory=list)  # the event log, in order
    kinds: list[int] = field(default_factory=list)
    angles: list[float] = field(default_factory=list)
    speeds: list[float] = field(default_factory=list)
    records: list[IntegratedRecord] | None = None

    def log(self, kind: str, time: float | None = None, speed: float | None = None) -> None:
        """Log an event at the current angle (solver._Log.add), at t and w unless given."""
        self.times.append(self.t if time is None else time)
        self.kinds.append(_EV[kind])
        self.angles.append(self.phi)
        self.speeds.append(self.w if speed is None else speed)

    def finish(self, status: str) -> None:
        """solver._State.finish."""
        self.done = True
        self.status = _ST[status]


@dataclass(slots=True)
class _Kernel:
    """The compiled kernel and the buffers it reads and writes (compiled._parameters)."""

    segment: Callable[..., tuple[int, float, float, float, FloatArray, int]]
    law: int  # the law's code (compiled.LINEAR_LAW, KLOSS_LAW)
    drive: int  # the drive's column in the row
    par: FloatArray  # the parameter row
    y0: FloatArray  # [x, u, s, E] at the segment's start
    atol: FloatArray
    final: FloatArray
    model: Callable[[float], Model]  # a segment's model from its drive (time series)


def _case(problem: DynamicProblem) -> _Case:
    """The constants of the one case (solver._flatten, Model.__post_init__)."""
    angles, torques = problem.angles, problem.torques  # (2, *batch), one case
    a0, a1 = angles.item(0), angles.item(1)
    t0, t1 = torques.item(0), torques.item(1)
    width = a1 - a0
    # The law's parameters, read once as floats (the kernel's row and the result take
    # them too). c: LinearEddy.coefficient and KlossEddy.coefficient (the law's only two
    # classes here: eligible), read as a float rather than through np.asarray.
    law = _eddy_values(problem.eddy)
    if isinstance(problem.eddy, LinearEddy):
        _, reference, coefficient = law  # BD, T_ref, c
    else:
        _, _, coefficient, reference = law  # T_peak, w_peak, alpha, T_ref
    ambient = problem.ambient_temperature.item()
    # max(eddy.factor(T), 0) in floats: both laws' factor is ``1 * (1 + c (T - T_ref))``
    # (assembly.damper_damping_rate at BD = 1, rolloff.peak_speed_at at w_ref = 1), the
    # same IEEE operations on the same operands as NumPy's (solver._thermal_start).
    ambient_factor = _maximum(1.0 * (1.0 + coefficient * (ambient - reference)), 0.0)
    load = problem.load_inertia.item()
    return _Case(
        a0,  # lower
        a1,  # upper
        t0,  # start_torque
        (t1 - t0) / width if width > 0.0 else 0.0,  # slope
        a1,  # travel
        load,  # load_inertia
        load + problem.damper_inertia.item(),  # total_inertia
        problem.ecd_friction.item(),
        problem.system_friction.item(),
        problem.static_friction_factor.item(),  # factor
        problem.system_static_friction_factor.item(),  # system_factor
        problem.restitution.item(),
        problem.initial_angle.item(),  # angle0
        problem.initial_speed.item(),  # speed0
        ambient,
        problem.damping_rate.item(),  # linear_damping
        coefficient,
        ambient_factor,
        reference - 1.0 / coefficient if coefficient < 0.0 else math.inf,  # zero
        problem.thermal,  # heating
        law,
    )


def _kernel(problem: DynamicProblem, case: _Case, module: ModuleType) -> _Kernel:
    """The parameter row of :func:`ecdsim.dynamics.compiled._parameters` for the case.

    J and k are the case's for every segment (engaged, one spring piece); the drive is
    set per segment. The columns of a lossy gear, gravity, Stribeck friction and the
    housing hold their "none" values, as ``_parameters`` writes them.
    """
    row = [0.0] * module._COLUMNS  # zero: no Stribeck excess, gravity, flow, J_L .. a_L
    row[module._J] = case.total_inertia
    row[module._K] = -case.slope
    row[module._DRIVE] = math.nan  # set per segment
    row[module._N] = problem.gear_ratio.item()
    row[module._BG] = problem.gearbox_damping_rate.item()
    row[module._C] = problem.heat_capacity.item()
    row[module._R] = problem.thermal_resistance.item()
    row[module._FA] = case.ambient_factor
    row[module._COEF] = case.coefficient
    row[module._FIXED] = math.nan  # set by _segment from the start state
    row[module._WS] = 1.0  # w_St, unused without Stribeck friction
    row[module._CH] = math.inf  # one node: C_h, R_he unused
    row[module._RHE] = math.inf
    row[module._GD] = 1.0  # the gravity direction, unused without gravity
    row[module._MESH] = 1.0  # an ideal gear: m = 1
    row[module._LAW_A] = case.law[0]  # BD or T_peak
    if isinstance(problem.eddy, LinearEddy):
        law = module.LINEAR_LAW
        row[module._LAW_B] = 0.0
    else:
        law = module.KLOSS_LAW
        row[module._LAW_B] = case.law[1]  # w_peak at T_ref
    par = np.array(row)

    def model(drive: float) -> Model:
        # A recorded segment's own model (integrate._model of the segment), built when
        # its trajectory is first sampled: most recorded runs never are.
        one = np.ones(1)
        return Model(
            inertia=one * case.total_inertia,
            stiffness=one * -case.slope,
            drive=one * drive,
            ratio=problem.gear_ratio.reshape(1),
            gearbox_damping=problem.gearbox_damping_rate.reshape(1),
            heat_capacity=problem.heat_capacity.reshape(1),
            thermal_resistance=problem.thermal_resistance.reshape(1),
            ambient=problem.ambient_temperature.reshape(1),
            eddy=_flat_eddy(problem.eddy, case.law),
            heating=problem.thermal,
            ambient_factor=one * case.ambient_factor,
        )

    return _Kernel(
        module._segment, law, module._DRIVE, par, np.zeros(4), np.empty(4), np.empty(4), model
    )


class _Recorded(integrate._InTemperature):
    """integrate._InTemperature whose one-segment model is built on first evaluation."""

    def __init__(
        self,
        solution: Callable[[FloatArray], FloatArray],
        model: Callable[[float], Model],
        drive: float,
    ):
        self.solution = solution
        self._build = model
        self._drive = drive
        self._model: Model | None = None

    @property
    def model(self) -> Model:
        """The model of this segment alone."""
        if self._model is None:
            self._model = self._build(self._drive)
        return self._model


def _start(problem: DynamicProblem, case: _Case) -> _Run:
    """solver._State.initial and solver._thermal_start for the case (engaged at release)."""
    run = _Run(
        t=0.0,
        phi=case.angle0,
        w=case.speed0,
        temp=case.ambient,
        max_speed=_maximum(case.speed0, 0.0),
        max_temp=case.ambient,
    )
    rise = problem.initial_rotor_rise.item()
    if problem.thermal and rise != 0.0:
        # The rotor's state is the damping law's log factor of its rise (thermal).
        heat = thermal.factor_log_from_rise(
            np.array([rise]), np.array([case.ambient_factor]), case.coefficient
        )
        run.heat = float(heat[0])
        run.temp = case.ambient + rise
        run.max_temp = run.temp
    return run


def _stick_or_break(case: _Case, run: _Run) -> float:
    """solver._stick_or_break: the direction of a breakaway, 0 where the case sticks
    (held by static friction, or by the start stop against a backward drive)."""
    drive = case.start_torque + case.slope * (run.phi - case.lower)
    static = case.system_friction * case.system_factor + case.ecd_friction * case.factor
    holds = abs(drive) <= static + STICK_MARGIN * _maximum(abs(drive), static)
    # On the start stop a backward drive presses the load into the stop, which holds it.
    if holds or (drive < 0.0 and run.phi <= 0.0):
        run.finish("stuck")
        run.stuck = True
        run.stuck_angle = run.phi
        run.stuck_time = run.t
        run.log("stick")
        return 0.0
    run.log("breakaway")
    return _sign(drive)


@dataclass(slots=True)
class _Segment:
    """solver._Segment for the case: the segment's frame, its first geometric event."""

    direction: float
    torque: float  # spring torque at the start [N*m]
    length: float
    reach_kind: int
    kinetic: float
    drive: float
    speed0: float
    cap: float


def _segment(case: _Case, run: _Run, direction: float, stop_time: float) -> _Segment:
    """solver._segments for the engaged case on its one spring piece."""
    phi = run.phi
    torque = case.start_torque + case.slope * (phi - case.lower)
    kinetic = case.ecd_friction + case.system_friction
    if direction > 0.0:
        length = case.upper - phi
        reach = _EV["arrive"] if case.upper >= case.travel else _EV["breakpoint"]
        drive = torque - kinetic
    else:
        length = phi - case.lower
        reach = _EV["start_stop"] if case.lower <= 0.0 else _EV["breakpoint"]
        drive = -(torque + kinetic)
    # Positional (as _Step), in field order.
    return _Segment(
        direction,
        torque,
        _maximum(length, 0.0),  # length
        reach,  # reach_kind
        kinetic,
        drive,
        # + 0.0: a backward breakaway from rest gives -0.0 (solver._segments).
        direction * run.w + 0.0,  # speed0
        _maximum(stop_time - run.t, 0.0),  # cap
    )


@dataclass(slots=True)
class _Step:
    """solver._Step for the case, from integrate._advance_batched."""

    kind: int
    duration: float
    x: float
    v: float
    damper_work: float
    peak_speed: float
    temperature: float
    peak_temperature: float


def _integrate(
    case: _Case, run: _Run, seg: _Segment, kernel: _Kernel, rtol: float, record: bool
) -> _Step:
    """The segment integrated: integrate._scales, _start, compiled.integrate_batch and
    integrate._advance_batched for one segment, then solver._step_integrated's record."""
    inertia = case.total_inertia
    stiffness = -case.slope
    damping0 = _maximum(case.linear_damping, 1e-300)
    drive = abs(seg.drive)
    speed0 = seg.speed0
    speed = _maximum(_maximum(abs(speed0), drive / damping0), 1e-300)
    length = _maximum(seg.length, 1e-9)
    energy = _maximum(_maximum(drive * seg.length, 0.5 * inertia * (speed0 * speed0)), 1e-300)
    atol = kernel.atol
    atol[0] = rtol * 1e-3 * length
    atol[1] = min(rtol * 1e-3, 1e-12) * speed
    atol[2] = rtol * 1e-3
    atol[3] = rtol * 1e-3 * energy
    equilibrium = seg.drive / stiffness if stiffness > 0.0 else math.inf
    creeps = equilibrium > 0.0 and equilibrium <= seg.length
    first = 1e-3 * _minimum(inertia / damping0, length / speed)
    kernel.par[kernel.drive] = seg.drive
    kernel.y0[1] = speed0
    kernel.y0[2] = run.heat
    code, duration, top_speed, top_temp, steps, count = kernel.segment(
        kernel.par,
        kernel.law,
        case.heating,
        kernel.y0,
        seg.length,
        seg.cap,
        integrate.CREEP_FRACTION * speed,
        creeps,
        atol,
        first,
        rtol,
        integrate.HORIZON_TIME,
        integrate.HORIZON,
        record,
        kernel.final,
    )
    x, u, state, work = kernel.final.tolist()
    if run.records is not None and count >= 2:
        # The kernel's buffer is its own (allocated per call), a step a row: the time,
        # state and slope columns are taken as views of it (transposed), not copied.
        solution = _frozen(
            Trajectory,
            {
                "times": steps[:count, 0],
                "states": steps[:count, 1:5].T,
                "slopes": steps[:count, 5:].T,
            },
        )
        run.records.append(
            _frozen(
                IntegratedRecord,
                {
                    "case": 0,
                    "start_time": run.t,
                    "duration": duration,
                    "start_angle": run.phi,
                    "direction": seg.direction,
                    "solution": _Recorded(solution, kernel.model, seg.drive),
                },
            )
        )
    run.heat = state
    temperature = case.temperature(state)
    peak = _maximum(top_temp, state)
    # Positional (a slotted dataclass's keywords cost some 0.3 us a call), in field order.
    return _Step(
        code,  # kind
        duration,
        x,
        0.0 if code in (_ZERO, _REST) else u,  # v
        work,  # damper_work
        _maximum(top_speed, speed0),  # peak_speed
        temperature,
        # The peak is the end state unless the damper cooled: one expm1 fewer.
        temperature if peak == state else case.temperature(peak),  # peak_temperature
    )


def _account(run: _Run, seg: _Segment, step: _Step, stiffness: float) -> None:
    """solver._account: energy, extremes, and the new time, angle and speed."""
    direction = seg.direction
    displacement = direction * step.x
    run.spring_work += seg.torque * displacement - 0.5 * stiffness * displacement * displacement
    run.friction_work += seg.kinetic * abs(step.x)
    run.damper_work += step.damper_work
    if not math.isfinite(run.arrival_time) and direction > 0.0:
        run.max_speed = _maximum(run.max_speed, step.peak_speed)
    run.max_temp = _maximum(run.max_temp, step.peak_temperature)
    run.temp = step.temperature
    t_new = run.t + step.duration
    run.hold_from = t_new
    run.display_end = t_new  # the start plus the duration (solver._step_integrated)
    run.t = t_new
    if step.kind == _REACH:  # geometric events land exactly on their angle
        run.phi = run.phi + direction * seg.length
    else:
        run.phi = run.phi + displacement
    run.w = direction * step.v


def _apply_event(case: _Case, run: _Run, seg: _Segment, kind: int) -> bool:
    """solver._apply_events for the case; True where it passed a spring breakpoint."""
    if kind == _ZERO:
        run.w = 0.0  # the next pass decides stick or breakaway
        run.log("zero_speed")
    elif kind == _CAP:
        run.finish("stop_time")
        run.log("stop_time")
    elif kind == _REST:
        run.finish("creep")
        run.stuck = True
        run.stuck_angle = run.phi
        run.stuck_time = math.inf
        run.t = math.inf
        run.w = 0.0
        run.log("creep")
    elif kind == integrate.HORIZON:
        run.finish("horizon")
        run.log("horizon")
    elif kind == _REACH:
        if seg.reach_kind == _EV["breakpoint"]:
            run.log("breakpoint")
            return True
        _impact(case, run, "arrive" if seg.reach_kind == _EV["arrive"] else "start_stop")
    return False


def _impact(case: _Case, run: _Run, name: str) -> None:
    """solver._impact: end of travel (latch or rebound) or the start stop."""
    inertia = case.total_inertia
    ke = 0.5 * inertia * run.w * run.w  # mechanics.kinetic_energy
    run.log(name)
    arriving = name == "arrive"
    if arriving and not math.isfinite(run.arrival_time):
        run.arrival_time = run.t
        run.arrival_speed = run.w
        run.arrival_ke = ke
    e = case.restitution
    if e <= 0.0:
        if arriving:
            run.finish("latched")
            run.log("latch")
        else:
            run.impact_loss += ke
            run.w = 0.0
        return
    # mechanics.rebound
    w_after = -e * run.w
    loss = (1.0 - e * e) * (0.5 * inertia * run.w * run.w)
    largest = ke
    if not arriving:
        # On the start stop: the largest impact there so far (solver._impact).
        largest = _maximum(run.start_ke, ke)
        run.start_ke = largest
    reference = _maximum(_maximum(run.arrival_ke, largest), _TINY)
    settle = ke - loss <= SETTLE_FRACTION * reference
    if arriving and run.impacts == 0 and not settle:
        run.rebound_speed = w_after
    run.impacts += 1
    run.impact_loss += ke if settle else loss
    run.w = 0.0 if settle else w_after
    if arriving and settle:
        run.finish("settled")
        run.log("settle")


def solve(problem: DynamicProblem, record: bool = True) -> DynamicResult:
    """Solve the one case of ``problem`` (:func:`eligible`) as solver.solve_dynamic does."""
    # numba's kernels: eligible() found the module importable and imported it (read
    # off sys.modules, without asking the environment twice: integrate.compiled_kernel).
    compiled = sys.modules.get(integrate.COMPILED_MODULE) or integrate.compiled_kernel()
    assert compiled is not None
    case = _case(problem)
    kernel = _kernel(problem, case, compiled)
    run = _start(problem, case)
    if record:
        run.records = []
    stiffness = -case.slope
    run.log("release")
    # Passes that ended in an event other than a breakpoint (solve_dynamic's event limit).
    passes = 0
    while not run.done:
        if passes >= problem.max_events:
            run.finish("event_limit")
            run.log("event_limit")
            break
        direction = _stick_or_break(case, run) if run.w == 0.0 else _sign(run.w)
        if direction == 0.0:  # stuck (the loop ends), as no case runs in solve_dynamic
            continue
        seg = _segment(case, run, direction, problem.stop_time)
        step = _integrate(case, run, seg, kernel, problem.rtol, record)
        _account(run, seg, step, stiffness)
        if not _apply_event(case, run, seg, step.kind):
            passes += 1
    return _result(problem, case, run)


def _result(problem: DynamicProblem, case: _Case, run: _Run) -> DynamicResult:
    """solve_dynamic's result for the case: summaries, energy, events and trajectory.

    Every float of the result is a view of one array (one NumPy call, not one per
    field): the 21 summaries, each of the batch's shape, then, when recorded, the
    trajectory's final state and display end and the flattened damping law's
    parameters, each of shape (1,). So are the event log's times, angles and speeds of
    another. The frozen records are built by :func:`_frozen` (every field named here).
    """
    shape = problem.batch_shape
    final_speed = run.w if run.status in _KEEPS else 0.0
    inertia = case.total_inertia
    numbers = [
        run.arrival_time,
        run.arrival_speed,
        run.arrival_ke,
        run.t,
        run.phi,
        final_speed,
        run.temp,
        run.stuck_angle,
        run.stuck_time,
        run.max_speed,
        run.max_temp,
        0.0,  # engagement_time: engaged at release
        run.rebound_speed,
        # The energy balance (mechanics.kinetic_energy for the kinetic energies).
        run.spring_work,
        0.5 * inertia * case.speed0 * case.speed0,
        run.damper_work,
        run.friction_work,
        0.0,  # engagement_loss: no lost motion
        run.impact_loss,
        0.5 * inertia * final_speed * final_speed,
        0.0,  # gear_loss: an ideal gear
    ]
    if run.records is not None:
        # The trajectory's final state and display end (solver._step_integrated), then
        # the law's parameters (_eddy_values).
        end = run.t if math.isfinite(run.t) else run.display_end
        numbers += (run.phi, final_speed, run.temp, run.hold_from, end)
        numbers += case.law
    values = np.array(numbers)
    # Iterating over the first axis gives the views (but scalars for a 0-d batch).
    summary = values[:21].reshape((21, *shape))
    v = list(summary) if shape else [summary[k, ...] for k in range(21)]
    logged = np.array((run.times, run.angles, run.speeds))
    energy = _frozen(
        EnergyBalance,
        {
            "spring_work": v[13],
            "initial_kinetic_energy": v[14],
            "damper_dissipation": v[15],
            "friction_dissipation": v[16],
            "engagement_loss": v[17],
            "impact_loss": v[18],
            "final_kinetic_energy": v[19],
            "gear_loss": v[20],
            "gravity_work": None,
            "mesh_dissipation": None,
            "elastic_energy": None,
        },
    )
    events = _frozen(
        EventLog,
        {
            "case": np.zeros(len(run.kinds), dtype=np.intp),
            "time": logged[0],
            "kind": np.array(run.kinds, dtype=np.int8),
            "angle": logged[1],
            "speed": logged[2],
        },
    )
    trajectory = None
    if run.records is not None:
        trajectory = _trajectory(problem, run.records, list(values[21:].reshape(-1, 1)))
    return _frozen(
        DynamicResult,
        {
            "batch_shape": shape,
            "temperature": problem.ambient_temperature.reshape(shape),
            "deployment_time": v[0],
            "arrival_speed": v[1],
            "arrival_kinetic_energy": v[2],
            "final_time": v[3],
            "final_angle": v[4],
            "final_speed": v[5],
            "final_temperature": v[6],
            "stuck": np.array(run.stuck).reshape(shape),
            "stuck_angle": v[7],
            "stuck_time": v[8],
            "max_speed": v[9],
            "max_damper_temperature": v[10],
            "engagement_time": v[11],
            "rebound_speed": v[12],
            "impacts": np.array(run.impacts, dtype=np.int64).reshape(shape),
            "status": np.array(run.status, dtype=np.int8).reshape(shape),
            "energy": energy,
            "events": events,
            "trajectory": trajectory,
            "final_housing_temperature": None,  # one node
            "max_mesh_torque": None,  # a rigid mesh
            "latch_mesh_torque": None,
        },
    )


def _frozen(cls: type[_T], values: dict[str, Any]) -> _T:
    """``cls(**values)`` for a frozen dataclass, its instance dictionary set at once.

    A frozen dataclass's ``__init__`` sets each field through ``object.__setattr__``
    (some 0.1 us a field; a result has about 50 over its records). ``values`` must name
    every field, defaults included, and ``cls`` must have no ``__post_init__``:
    tests/test_dynamics_single.py asserts both for each class built here, so that a
    field added to one of them fails there until it is filled in.
    """
    built = object.__new__(cls)
    object.__setattr__(built, "__dict__", values)
    return built


def _eddy_values(eddy: object) -> tuple[float, ...]:
    """The law's parameters as floats, in the order of its fields (:func:`_eddy_of`)."""
    if isinstance(eddy, LinearEddy):
        return (
            _item(eddy.damping_rate),
            _item(eddy.reference_temperature),
            _item(eddy.temperature_coefficient),
        )
    assert isinstance(eddy, KlossEddy)
    return (
        _item(eddy.peak_torque),
        _item(eddy.reference_peak_speed),
        _item(eddy.resistivity_coefficient),
        _item(eddy.reference_temperature),
    )


def _eddy_of(eddy: object, rows: list[FloatArray]) -> LinearEddy | KlossEddy:
    """``eddy.flattened(shape)`` for one case from ``rows``, its parameters as (1,)
    arrays in the order of :func:`_eddy_values` (the fields' order); built by
    :func:`_frozen` (tests/test_dynamics_single.py holds the fields to it)."""
    if isinstance(eddy, LinearEddy):
        rate, reference, coefficient = rows
        return _frozen(
            LinearEddy,
            {
                "damping_rate": rate,
                "reference_temperature": reference,
                "temperature_coefficient": coefficient,
            },
        )
    peak, speed, coefficient, reference = rows
    return _frozen(
        KlossEddy,
        {
            "peak_torque": peak,
            "reference_peak_speed": speed,
            "resistivity_coefficient": coefficient,
            "reference_temperature": reference,
        },
    )


def _flat_eddy(eddy: object, law: tuple[float, ...]) -> LinearEddy | KlossEddy:
    """``eddy.flattened(shape)`` for one case from its parameters ``law``: each as a (1,)
    array (rows of one array: one NumPy call)."""
    return _eddy_of(eddy, list(np.array(law).reshape(-1, 1)))


def _trajectory(
    problem: DynamicProblem, records: list[IntegratedRecord], rows: list[FloatArray]
) -> TrajectoryData:
    """solve_dynamic's TrajectoryData for the case (one-element flat arrays: views of the
    problem's fields, as solver._flatten takes them).

    ``rows``: the final angle, speed and temperature, the hold start and the display
    end, then the law's parameters (:func:`_eddy_values`), each of shape (1,).
    """
    p = problem
    flat: tuple[FloatArray, ...] = (
        p.initial_angle,
        p.initial_speed,
        p.ambient_temperature,
        p.ecd_friction,
        p.system_friction,
        p.static_friction_factor,
        p.system_static_friction_factor,
        p.gear_ratio,
        p.gearbox_damping_rate,
        p.stribeck_speed,
    )
    if p.batch_shape != (1,):  # a batch of shape (1,) (predict's one temperature) is flat
        flat = tuple(values.reshape(1) for values in flat)
    angle0, speed0, ambient, ecd_friction, system_friction = flat[:5]
    factor, system_factor, ratio, gearbox_damping, stribeck_speed = flat[5:]
    engaged = np.array([True])  # engaged at release: no lost motion
    return _frozen(
        TrajectoryData,
        {
            "closed": [],
            "integrated": records,
            "initial": (angle0, speed0, ambient, engaged),
            "final": (rows[0], rows[1], rows[2], engaged.copy(), rows[3]),
            "display_end": rows[4],
            "angles": p.angles.reshape(2, 1),
            "torques": p.torques.reshape(2, 1),
            "ecd_friction": ecd_friction,
            "system_friction": system_friction,
            "factor": factor,
            "system_factor": system_factor,
            "ratio": ratio,
            "gearbox_damping": gearbox_damping,
            "eddy": _eddy_of(p.eddy, rows[5:]),  # case.law's rows
            "stribeck_speed": stribeck_speed,
        },
    )
