"""Nonlinear engaged segments (damping roll-off, self-heating), integrated numerically.

The segment's equations, in its forward frame with the state ``y = [x, u, s, E]``
(displacement, speed, the damping law's log factor standing for the damper temperature,
damper dissipation), are those of :mod:`ecdsim.dynamics.equations`. They are integrated,
with the analytic Jacobian, either by the Rosenbrock method RODAS4 (``"RODAS4"``, the
default: compiled per segment by :mod:`ecdsim.dynamics.compiled` when numba is
installed, else the whole batch at once in NumPy by :mod:`ecdsim.dynamics.rosenbrock`;
see :func:`compiled_kernel`) or case by case with scipy's ``solve_ivp`` (stiff methods
``"Radau"``, ``"BDF"`` or ``"LSODA"``), until the first event: the segment's length is
reached, the speed falls to zero, the speed falls below ``1e-9`` of its scale while the
static equilibrium lies ahead and the load is still short of it (asymptotic approach to
rest, "creep": :meth:`~ecdsim.dynamics.equations.Model.rest_push` > 0), or the time cap.
The damper cannot heat beyond its damping law's zero (Eq. 1's ``BD_T = 0``): the state s
keeps it out of reach.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from dataclasses import dataclass
from types import ModuleType

import numpy as np
from numpy.typing import NDArray

from ecdsim import _numba
from ecdsim._types import FloatArray
from ecdsim.dynamics import linear
from ecdsim.dynamics.damping import EddyLaw
from ecdsim.dynamics.equations import SWITCH, Model

HORIZON = 4  # event kind: the integration horizon passed without an event
HORIZON_TIME = 1e9  # [s] integration horizon when there is no stop time
CREEP_FRACTION = 1e-9  # speed, relative to its scale, taken as "at rest" while creeping
BATCHED = "RODAS4"  # the vectorised integrator's name among the integrator choices


@dataclass(frozen=True)
class NonlinearSegments:
    """Engaged segments to integrate; 1-D arrays over the segments (forward frame).

    Attributes
    ----------
    inertia : J [kg*m^2]
    stiffness : k, fall of the spring torque per radian [N*m/rad]
    drive : a, spring torque minus friction at the start [N*m]
    speed0 : u at the start [rad/s], >= 0
    length : distance to the segment's end [rad]
    cap : time available [s] (inf for none)
    state0 : the damper's temperature state s at the start (the damping law's log
        factor, 0 at ambient; see :mod:`ecdsim.dynamics.equations`) [K]
    ambient : ambient temperature [degC]
    ratio : gear ratio N [-]
    gearbox_damping : BG at the high-speed shaft [N*m*s/rad]
    heat_capacity : C [J/K]
    thermal_resistance : R [K/W] (inf: adiabatic)
    linear_damping : BECD at ambient, to scale speeds [N*m*s/rad]
    eddy : the eddy-current law, flattened over the whole batch
    case : index of each segment's case in the batch (into ``eddy``)
    thermal : whether the damper temperature evolves
    stribeck_excess : F_brk - F_C of the Stribeck friction [N*m], or None for none
    stribeck_speed : w_St [rad/s] (with ``stribeck_excess``)
    housing_state0 : the housing's rise over ambient at the start [K], or None for
        one-node heating (then the next two are None too)
    housing_heat_capacity : C_h [J/K]
    housing_resistance : R_he, housing to ambient [K/W] (inf: adiabatic)
    gravity_amplitude : W of a ground test's gravity torque [N*m], or None for none (then
        the next two are None too; :class:`~ecdsim.dynamics.equations.Model`)
    gravity_phase : theta_0 + phi at the segment's start [rad]
    gravity_direction : +1 forward, -1 backward
    mesh : a lossy gear's factor m on the damper side's torque, or None for an ideal
        gear (then the next five are None too; :class:`~ecdsim.dynamics.equations.Model`)
    flow : the power flow whose reversal ends the segment (equations.SWITCH), 0 for none
    load_inertia : J_L [kg*m^2]
    damper_inertia : J_D at the input [kg*m^2]
    mesh_friction : F_q = FT_T N through an ideal gear [N*m]
    load_drive : spring torque less system friction at the start [N*m]
    """

    inertia: FloatArray
    stiffness: FloatArray
    drive: FloatArray
    speed0: FloatArray
    length: FloatArray
    cap: FloatArray
    state0: FloatArray
    ambient: FloatArray
    ratio: FloatArray
    gearbox_damping: FloatArray
    heat_capacity: FloatArray
    thermal_resistance: FloatArray
    linear_damping: FloatArray
    eddy: EddyLaw
    case: NDArray[np.intp]
    thermal: bool
    stribeck_excess: FloatArray | None = None
    stribeck_speed: FloatArray | None = None
    housing_state0: FloatArray | None = None
    housing_heat_capacity: FloatArray | None = None
    housing_resistance: FloatArray | None = None
    gravity_amplitude: FloatArray | None = None
    gravity_phase: FloatArray | None = None
    gravity_direction: FloatArray | None = None
    mesh: FloatArray | None = None
    flow: FloatArray | None = None
    load_inertia: FloatArray | None = None
    damper_inertia: FloatArray | None = None
    mesh_friction: FloatArray | None = None
    load_drive: FloatArray | None = None


@dataclass(frozen=True)
class NonlinearAdvance:
    """Outcome per segment (see :class:`ecdsim.dynamics.linear.Advance`).

    Attributes
    ----------
    kind : REACH, ZERO, CAP, REST (linear's codes) or HORIZON
    duration : time spent [s]
    x : displacement at the end [rad]
    v : speed at the end [rad/s]
    damper_work : damping dissipation over the segment [J]
    state : the damper's temperature state s at the end [K]
    temperature : damper temperature at the end [degC]
    max_temperature : highest damper temperature in the segment [degC]
    max_speed : highest speed in the segment [rad/s]
    solutions : dense output ``t -> [x, u, T_d, E]`` per segment (None if not recorded)
    housing : the housing's rise over ambient at the end [K] (None for one node)
    """

    kind: NDArray[np.int8]
    duration: FloatArray
    x: FloatArray
    v: FloatArray
    damper_work: FloatArray
    state: FloatArray
    temperature: FloatArray
    max_temperature: FloatArray
    max_speed: FloatArray
    solutions: list[Callable[[FloatArray], FloatArray] | None]
    housing: FloatArray | None = None


@dataclass(frozen=True)
class _One:
    kind: int
    duration: float
    x: float
    v: float
    work: float
    state: float
    max_state: float
    max_speed: float
    solution: Callable[[FloatArray], FloatArray] | None
    housing: float = 0.0


class _Event:
    """A solve_ivp event function with its attributes."""

    def __init__(
        self, func: Callable[[float, FloatArray], float], terminal: bool, direction: float
    ):
        self.func = func
        self.terminal = terminal
        self.direction = direction

    def __call__(self, t: float, y: FloatArray) -> float:
        return self.func(t, y)


@dataclass(frozen=True)
class _Scales:
    """Per-segment scales for tolerances, the first step and the creep threshold."""

    atol: FloatArray  # (4, n): x, u, s, E
    first_step: FloatArray
    creep_speed: FloatArray
    creeps: NDArray[np.bool_]


def _scales(segs: NonlinearSegments, rtol: float) -> _Scales:
    # Pairwise maxima (the same values as np.maximum.reduce over a stacked list, without
    # building the stack: a single deployment pays these calls' fixed cost in full).
    damping0 = np.maximum(segs.linear_damping, 1e-300)
    drive = np.abs(segs.drive)
    speed = np.maximum(np.maximum(np.abs(segs.speed0), drive / damping0), 1e-300)
    length = np.maximum(segs.length, 1e-9)
    energy = np.maximum(
        np.maximum(drive * segs.length, 0.5 * segs.inertia * segs.speed0**2), 1e-300
    )
    # The speed's absolute tolerance resolves the creep threshold (1e-9 of its scale).
    # The temperature state s changes T_d by f ds (f the damping factor, about 1 or
    # less), so its absolute tolerance is one in kelvin.
    atol = np.empty((4, length.size))
    atol[0] = rtol * 1e-3 * length
    atol[1] = min(rtol * 1e-3, 1e-12) * speed
    atol[2] = rtol * 1e-3
    atol[3] = rtol * 1e-3 * energy
    if segs.housing_state0 is not None and segs.thermal:
        atol = np.concatenate([atol, atol[2:3]])  # the housing rise, in kelvin like s
    # At rest the friction is the breakaway one: with Stribeck friction the motion can
    # only come to rest asymptotically where the drive equals it.
    rest_drive = segs.drive if segs.stribeck_excess is None else segs.drive - segs.stribeck_excess
    with np.errstate(divide="ignore", invalid="ignore"):
        equilibrium = np.where(segs.stiffness > 0.0, rest_drive / segs.stiffness, np.inf)
    creeps = (equilibrium > 0.0) & (equilibrium <= segs.length)
    if segs.gravity_amplitude is not None:
        # The sine moves the equilibrium: any segment may come to rest on its way.
        creeps = creeps | (segs.gravity_amplitude > 0.0)
    first = 1e-3 * np.minimum(segs.inertia / damping0, length / speed)
    return _Scales(atol, first, CREEP_FRACTION * speed, creeps)


def _model(segs: NonlinearSegments) -> Model:
    return Model(
        inertia=segs.inertia,
        stiffness=segs.stiffness,
        drive=segs.drive,
        ratio=segs.ratio,
        gearbox_damping=segs.gearbox_damping,
        heat_capacity=segs.heat_capacity,
        thermal_resistance=segs.thermal_resistance,
        ambient=segs.ambient,
        eddy=segs.eddy.take(segs.case),
        heating=segs.thermal,
        stribeck_excess=segs.stribeck_excess,
        stribeck_speed=segs.stribeck_speed,
        housing_heat_capacity=segs.housing_heat_capacity,
        housing_resistance=segs.housing_resistance,
        gravity_amplitude=segs.gravity_amplitude,
        gravity_phase=segs.gravity_phase,
        gravity_direction=segs.gravity_direction,
        mesh=segs.mesh,
        flow=segs.flow,
        load_inertia=segs.load_inertia,
        damper_inertia=segs.damper_inertia,
        mesh_friction=segs.mesh_friction,
        load_drive=segs.load_drive,
    )


def _start(segs: NonlinearSegments, model: Model) -> FloatArray:
    """Start states ``[x, u, s, E]`` (and the housing rise h with two nodes), (rows, n)."""
    y0 = np.zeros((model.rows, segs.speed0.size))
    y0[1] = segs.speed0
    y0[2] = segs.state0
    if model.two_node:
        assert segs.housing_state0 is not None
        y0[4] = segs.housing_state0
    return y0


class _InTemperature:
    """A segment's dense output ``t -> [x, u, s, E]`` with the row s turned into T_d."""

    def __init__(
        self, solution: Callable[[FloatArray], FloatArray], model: Model, index: int
    ) -> None:
        self.solution = solution
        # The segment's own model is taken when the output is first evaluated: most
        # recorded runs are never sampled, and a take builds a model and its law.
        self._batch: Model | None = model
        self._index = index
        self._model: Model | None = None

    @property
    def model(self) -> Model:
        """The model of this segment alone."""
        if self._model is None:
            assert self._batch is not None
            self._model = self._batch.take(np.array([self._index]))
            self._batch = None
        return self._model

    def __call__(self, t: FloatArray) -> FloatArray:
        y = np.array(self.solution(t), dtype=float)
        y[2] = self.model.temperature(y[2])
        if y.shape[0] > 4:
            y[4] += self.model.ambient  # the housing rise as a temperature [degC]
        return y


# The compiled kernels' module (dynamics.single reads it off sys.modules too).
COMPILED_MODULE = "ecdsim.dynamics.compiled"


def compiled_kernel() -> ModuleType | None:
    """:mod:`ecdsim.dynamics.compiled` when numba is installed and not switched off.

    ``ECDSIM_NUMBA=0`` in the environment selects the NumPy integrator (the reference
    implementation); so does a missing numba. numba is imported here, on first use, not
    at start-up.
    """
    if _numba.switched_off():
        return None
    # Once imported, the module is read off sys.modules: a dictionary look-up where the
    # import statement runs importlib's from-list handling (some microseconds, cold, in
    # a single deployment's dispatch: dynamics.single.eligible).
    imported = sys.modules.get(COMPILED_MODULE)
    if imported is not None:
        return imported
    try:
        _numba.load()  # numba with ecdsim's set-up (the compile notice) before any kernel
        from ecdsim.dynamics import compiled
    except ImportError:
        return None
    return compiled


def _advance_batched(
    segs: NonlinearSegments, model: Model, rtol: float, record: bool
) -> NonlinearAdvance:
    """All segments with the RODAS4 integrator: compiled per segment, or NumPy batched."""
    from ecdsim.dynamics import rosenbrock

    scales = _scales(segs, rtol)
    y0 = _start(segs, model)
    segments = rosenbrock.Segments(
        y0=y0,
        length=segs.length,
        cap=segs.cap,
        creep_speed=scales.creep_speed,
        creeps=scales.creeps,
        atol=scales.atol,
        first_step=scales.first_step,
    )
    control = rosenbrock.Control(
        rtol=rtol, horizon=HORIZON_TIME, horizon_kind=HORIZON, record=record
    )
    kernel = compiled_kernel()
    integrate_batch = rosenbrock.integrate_batch if kernel is None else kernel.integrate_batch
    out = integrate_batch(model, segments, control)
    stopped = (out.kind == linear.ZERO) | (out.kind == linear.REST)
    hottest = np.maximum(out.max_thermal_state, out.state[2])
    temperature, max_temperature = model.temperature(np.stack([out.state[2], hottest]))
    return NonlinearAdvance(
        kind=out.kind,
        duration=out.duration,
        x=out.state[0],
        v=np.where(stopped, 0.0, out.state[1]),
        damper_work=out.state[3],
        state=out.state[2],
        temperature=temperature,
        max_temperature=max_temperature,
        max_speed=np.maximum(out.max_speed, segs.speed0),
        solutions=[
            None if sol is None else _InTemperature(sol, model, j)
            for j, sol in enumerate(out.trajectories)
        ],
        housing=out.state[4] if model.two_node else None,
    )


def _integrate_one(
    segs: NonlinearSegments, model: Model, j: int, rtol: float, method: str, record: bool
) -> _One:
    from scipy.integrate import solve_ivp

    one = model.take(np.array([j]))
    u0 = float(segs.speed0[j])
    length = float(segs.length[j])
    cap = float(segs.cap[j])
    state0 = float(segs.state0[j])
    start = _start(segs, model)[:, j]
    housing0 = float(start[4]) if one.two_node else 0.0
    if length <= 0.0:
        return _One(linear.REACH, 0.0, 0.0, u0, 0.0, state0, state0, u0, None, housing0)
    if cap <= 0.0:
        return _One(linear.CAP, 0.0, 0.0, u0, 0.0, state0, state0, u0, None, housing0)
    rows = one.rows

    def rhs(_t: float, y: FloatArray) -> FloatArray:
        return one.rhs(np.reshape(y, (rows, 1))).ravel()

    def jac(_t: float, y: FloatArray) -> FloatArray:
        return one.jacobian_matrix(y)

    scales = _scales(segs, rtol)
    creep_speed = float(scales.creep_speed[j])
    creeps = bool(scales.creeps[j])

    events = [
        _Event(lambda _t, y: float(y[0]) - length, True, 1.0),  # reach the length
        _Event(lambda _t, y: float(y[1]), True, -1.0),  # zero speed
        _Event(lambda t, y: float(rhs(t, y)[1]), False, -1.0),  # speed maxima
        _Event(lambda t, y: float(rhs(t, y)[2]), False, -1.0),  # temperature maxima
    ]
    if creeps:
        # The speed falling through the creep threshold short of the equilibrium (the push
        # at rest forward); past it (a swing's turnaround) the zero-speed event comes
        # instead (rosenbrock._creeping). As one continuous function: the push in speed
        # units over the linear damping, whose sign alone matters.
        damping0 = max(float(segs.linear_damping[j]), 1e-300)

        def creep_event(_t: float, y: FloatArray) -> float:
            push = float(one.rest_push(np.array([float(y[0])]))[0]) / damping0
            return max(float(y[1]) - creep_speed, -push)

        events.append(_Event(creep_event, True, -1.0))
    switches = one.flow is not None and float(one.flow[0]) != 0.0
    if switches:
        # A lossy gear's power flow reverses (equations.SWITCH), last in the list.
        events.append(
            _Event(lambda _t, y: float(one.indicator(np.reshape(y, (rows, 1)))[0]), True, -1.0)
        )
    atol = scales.atol[:, j]
    t_end = cap if math.isfinite(cap) else HORIZON_TIME
    sol = solve_ivp(
        rhs,
        (0.0, t_end),
        start,
        method=method,
        rtol=rtol,
        atol=atol,
        jac=jac,
        events=events,
        dense_output=record,
    )
    y_end = sol.y[:, -1]
    duration = float(sol.t[-1])
    kind = HORIZON
    if sol.status == 1:
        outcomes: list[tuple[int, int]] = [(linear.REACH, 0), (linear.ZERO, 1)]
        if creeps:
            outcomes.append((linear.REST, 4))
        if switches:
            outcomes.append((SWITCH, len(events) - 1))
        for code, index in outcomes:
            if len(sol.t_events[index]):
                kind = code
                duration = float(sol.t_events[index][0])
                y_end = sol.y_events[index][0]
                break
    elif sol.status == 0 and math.isfinite(cap):
        kind = linear.CAP
    x_end = length if kind == linear.REACH else float(y_end[0])
    v_end = 0.0 if kind in (linear.ZERO, linear.REST) else float(y_end[1])
    peaks = [float(p[1]) for p in sol.y_events[2]]
    max_speed = max([u0, v_end, *peaks, *np.asarray(sol.y[1], float).tolist()])
    hot = [float(p[2]) for p in sol.y_events[3]]
    max_state = max([float(np.max(sol.y[2])), float(y_end[2]), *hot])
    solution = sol.sol if record and sol.sol is not None else None
    return _One(
        kind,
        duration,
        x_end,
        v_end,
        float(y_end[3]),
        float(y_end[2]),
        max_state,
        max_speed,
        None if solution is None else _InTemperature(solution, model, j),
        float(y_end[4]) if one.two_node else 0.0,
    )


def advance_nonlinear(
    segs: NonlinearSegments, rtol: float, method: str, record: bool
) -> NonlinearAdvance:
    """Integrate each segment to its first event.

    ``method`` "RODAS4" advances all segments together (:mod:`ecdsim.dynamics.rosenbrock`);
    "Radau", "BDF" or "LSODA" make one scipy ``solve_ivp`` call per segment. Both
    integrate the same :class:`~ecdsim.dynamics.equations.Model`.
    """
    model = _model(segs)
    if method == BATCHED:
        return _advance_batched(segs, model, rtol, record)
    results = [
        _integrate_one(segs, model, j, rtol, method, record) for j in range(segs.inertia.size)
    ]
    state = np.array([r.state for r in results])
    return NonlinearAdvance(
        kind=np.array([r.kind for r in results], dtype=np.int8),
        duration=np.array([r.duration for r in results]),
        x=np.array([r.x for r in results]),
        v=np.array([r.v for r in results]),
        damper_work=np.array([r.work for r in results]),
        state=state,
        temperature=model.temperature(state),
        max_temperature=model.temperature(np.array([r.max_state for r in results])),
        max_speed=np.array([r.max_speed for r in results]),
        solutions=[r.solution for r in results],
        housing=np.array([r.housing for r in results]) if model.two_node else None,
    )
