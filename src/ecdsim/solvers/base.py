"""The quasi-static deployment problem and the shape of a solver's answer."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Protocol

import numpy as np

from ecdsim._types import ArrayLike, BoolArray, FloatArray, broadcast, joint_shape


@dataclass(frozen=True)
class QuasiStaticProblem:
    """``B * dphi/dt = T_spring(phi) - F`` with a piecewise-linear spring torque.

    Axis 0 of ``angles`` and ``torques`` runs over the spring's breakpoints (two for a
    linear spring); the remaining axes, and ``friction`` and ``damping_rate``, broadcast
    over the batch (temperatures x samples).

    Attributes
    ----------
    angles : deployed angle of each breakpoint, 0 first, the travel last [rad]
    torques : spring torque at each breakpoint [N*m]
    friction : total resisting Coulomb torque at the input shaft, FECD_T + FS_T [N*m]
    damping_rate : BECD_T at the input shaft [N*m*s/rad]
    gravity_amplitude : W = m g r (1 - offload), the peak gravity torque of a ground test
        [N*m]; None (the default) for none, today's piecewise-linear problem. With it the
        drive is ``T(phi) - W sin(theta_0 + phi)`` (docs/model.md, gravity in ground tests)
    gravity_angle : theta_0, the release angle of the gravity term [rad]; None with no
        ``gravity_amplitude``
    """

    angles: FloatArray
    torques: FloatArray
    friction: FloatArray
    damping_rate: FloatArray
    gravity_amplitude: FloatArray | None = None
    gravity_angle: FloatArray | None = None

    def __post_init__(self) -> None:
        if self._normalized():
            return  # what the code below would leave as it is (a problem built from one)
        # Right-align the batch axes of the breakpoint arrays with the scalar fields and
        # broadcast everything to one shape, so that every solver sees (n_points, *batch).
        angles = np.asarray(self.angles, dtype=float)
        torques = np.asarray(self.torques, dtype=float)
        friction = np.asarray(self.friction, dtype=float)
        damping = np.asarray(self.damping_rate, dtype=float)
        if angles.ndim < 1 or torques.ndim < 1 or angles.shape[0] != torques.shape[0]:
            raise ValueError("angles and torques need the same number of breakpoints on axis 0")
        gravity: tuple[FloatArray, FloatArray] | None = None
        if self.gravity_amplitude is not None:
            gravity = (
                np.asarray(self.gravity_amplitude, dtype=float),
                np.asarray(0.0 if self.gravity_angle is None else self.gravity_angle, dtype=float),
            )
        batch = joint_shape(
            angles.shape[1:],
            torques.shape[1:],
            friction.shape,
            damping.shape,
            *((gravity[0].shape, gravity[1].shape) if gravity is not None else ()),
        )
        points = (angles.shape[0], *batch)
        # Already aligned (the problem of a problem: a DynamicProblem built from one): kept.
        if angles.shape != points:
            angles = angles.reshape(_aligned(angles, batch))
        if torques.shape != points:
            torques = torques.reshape(_aligned(torques, batch))
        object.__setattr__(self, "angles", broadcast(angles, points))
        object.__setattr__(self, "torques", broadcast(torques, points))
        object.__setattr__(self, "friction", broadcast(friction, batch))
        object.__setattr__(self, "damping_rate", broadcast(damping, batch))
        if gravity is not None:
            object.__setattr__(self, "gravity_amplitude", broadcast(gravity[0], batch))
            object.__setattr__(self, "gravity_angle", broadcast(gravity[1], batch))

    def _normalized(self) -> bool:
        """True when the fields are what :meth:`__post_init__` makes of them already.

        Read-only float64 arrays, the breakpoints ``(n_points, *batch)``, friction and
        damping of the batch shape, no gravity: the fields of a problem passed on to a new
        one (``dynamic_problem``), which a single deployment would otherwise align and
        broadcast again for nothing (issue 13, single cases).
        """
        values = (self.angles, self.torques, self.friction, self.damping_rate)
        for value in values:
            if type(value) is not np.ndarray or value.dtype != np.float64:
                return False
            if value.flags.writeable:
                return False
        angles, torques, friction, damping = values
        return (
            self.gravity_amplitude is None
            and angles.ndim >= 1
            and angles.shape == torques.shape
            and angles.shape[1:] == friction.shape == damping.shape
        )

    @property
    def has_gravity(self) -> bool:
        """True when some case has a gravity torque (a ground test, docs/model.md)."""
        return self.gravity_amplitude is not None and bool(np.any(self.gravity_amplitude != 0.0))

    @property
    def travel(self) -> FloatArray:
        """Deployment angle [rad]."""
        return np.asarray(self.angles[-1])

    @property
    def net_torques(self) -> FloatArray:
        """Spring torque minus friction at each breakpoint [N*m]."""
        return np.asarray(self.torques - self.friction)

    @property
    def peak_speed(self) -> FloatArray:
        """Highest Eq. 5 speed over the breakpoints, ``max(T_i - F, 0) / BECD`` [rad/s].

        The net torque is piecewise linear, so its maximum lies on a breakpoint. Both
        methods report it, for the damper's linear-range check (a tabulated spring may
        peak mid-travel, which the paper's Eq. 8-9 do not look at).
        """
        net = np.maximum(self.net_torques, 0.0)
        return np.asarray(net.max(axis=0) / self.damping_rate, dtype=np.float64)

    def peak_speed_reached(self, stalled: BoolArray, stall_angle: FloatArray) -> FloatArray:
        """:attr:`peak_speed` over the part of the travel actually covered [rad/s].

        A stalled case never reaches the breakpoints beyond its stall angle, so their
        speeds are left out: a rising spring that cannot start has a peak speed of 0, not
        the Eq. 5 speed at a breakpoint it never gets to.
        """
        covered = ~stalled | (self.angles <= np.where(stalled, stall_angle, np.inf))
        net = np.where(covered, np.maximum(self.net_torques, 0.0), 0.0)
        return np.asarray(net.max(axis=0) / self.damping_rate, dtype=np.float64)

    @property
    def batch_shape(self) -> tuple[int, ...]:
        """Broadcast shape of one result."""
        return tuple(self.friction.shape)


# Every field of QuasiStaticProblem, as one_case_problem sets it (tests/test_fast_paths.py
# fails when a field is added to the class and not here).
ONE_CASE_FIELDS = (
    "angles",
    "torques",
    "friction",
    "damping_rate",
    "gravity_amplitude",
    "gravity_angle",
)


def one_case_problem(
    angles: FloatArray, torques: FloatArray, friction: FloatArray, damping_rate: FloatArray
) -> QuasiStaticProblem | None:
    """``QuasiStaticProblem(angles, torques, friction, damping_rate)`` of one case, or None.

    The same problem, field for field (values, shapes, read-only float64 views), as
    ``__post_init__`` makes of float64 arrays whose batch (the breakpoints' trailing axes,
    friction's and damping's shapes) holds one case: their numbers read into one
    read-only array and handed out as views of the aligned shapes, without the general
    path's conversions, alignment and broadcasts (some 4 us of a single deployment;
    issue 13, single cases). No gravity. None, for the general path, for anything else.
    """
    values = (angles, torques, friction, damping_rate)
    for value in values:
        if type(value) is not np.ndarray or value.dtype != np.float64:
            return None
    if angles.ndim < 1 or torques.ndim < 1 or angles.shape[0] != torques.shape[0]:
        return None  # the general path raises its error
    batch = joint_shape(angles.shape[1:], torques.shape[1:], friction.shape, damping_rate.shape)
    if math.prod(batch) != 1:
        return None
    return packed_problem(
        angles.ravel().tolist(),
        torques.ravel().tolist(),
        friction.item(),
        damping_rate.item(),
        batch,
    )


def packed_problem(
    angles: list[float],
    torques: list[float],
    friction: float,
    damping_rate: float,
    batch: tuple[int, ...],
) -> QuasiStaticProblem:
    """The one-case problem of these numbers, its batch shape ``batch`` (of size 1).

    What ``QuasiStaticProblem.__post_init__`` makes of the arrays holding them: the
    breakpoints ``(n_points, *batch)``, friction and damping ``batch``, all read-only
    float64 views (here of one array), no gravity (:func:`one_case_problem`).
    """
    n = len(angles)
    packed = np.array([*angles, *torques, friction, damping_rate], dtype=np.float64)
    packed.flags.writeable = False
    points = (n, *batch)
    problem = object.__new__(QuasiStaticProblem)
    # A frozen dataclass without slots: its fields live in the instance __dict__.
    vars(problem).update(
        angles=packed[:n].reshape(points),
        torques=packed[n : 2 * n].reshape(points),
        friction=packed[2 * n : 2 * n + 1].reshape(batch),  # slices: views, read-only
        damping_rate=packed[2 * n + 1 :].reshape(batch),
        gravity_amplitude=None,
        gravity_angle=None,
    )
    return problem


def _aligned(points: FloatArray, batch: tuple[int, ...]) -> tuple[int, ...]:
    """Shape of a (n_points, *own_batch) array with its batch axes right-aligned to batch."""
    own = points.shape[1:]
    return (points.shape[0], *((1,) * (len(batch) - len(own))), *own)


@dataclass(frozen=True)
class DeploymentSolution:
    """One method's deployment prediction; every array has the problem's batch shape.

    Attributes
    ----------
    method : solver name ("paper", "exact", ...)
    deployment_time : time from release to the end of travel [s]; +inf where stalled
    start_speed : input-shaft speed at the start of travel [rad/s]
    end_speed : speed on arrival at the end of travel [rad/s]; 0 where stalled
    max_speed : highest speed over the travel [rad/s]
    stalled : True where the spring torque falls to the friction before the end of travel
    stall_angle : deployed angle at which it stalls [rad]; NaN where not stalled
    solved : False where this method cannot solve the case at all (the quasi-static
        methods with no damping, BECD_T = 0: their equation gives an infinite speed);
        there the time is +inf, the speeds are 0 and the case is not flagged as stalled.
        None (the default) means every case was solved.
    """

    method: str
    deployment_time: FloatArray
    start_speed: FloatArray
    end_speed: FloatArray
    max_speed: FloatArray
    stalled: BoolArray
    stall_angle: FloatArray
    solved: BoolArray | None = None

    def __post_init__(self) -> None:
        if self.solved is None:
            object.__setattr__(self, "solved", np.ones(self.stalled.shape, dtype=bool))

    @property
    def solved_mask(self) -> BoolArray:
        """``solved`` as an array of the batch shape (True where the method has an answer)."""
        assert self.solved is not None  # set in __post_init__
        return broadcast(np.asarray(self.solved), self.stalled.shape)

    # Hooks through which a method adds what only it knows. Callers (predict, the JSON,
    # the CLI) use them for every method alike; a method overrides those it needs.

    def case_fields(self, index: int) -> dict[str, Any]:
        """The method's own JSON fields of one case (flat index), beyond the common ones."""
        return {}

    def findings(self) -> list[tuple[str, str, int]]:
        """The method's own noteworthy outcomes as (code, message, flat case index)."""
        return []

    def trajectory(self, times: ArrayLike) -> Trajectory | None:
        """The solved angle and speed at ``times`` [s], if this solution keeps them.

        None here: the solver recomputes them from the problem
        (:meth:`Solver.trajectory`). A method whose solution keeps its time history
        returns it, so that it is not solved twice.
        """
        return None

    def time_series_csv(self) -> str | None:
        """The method's recorded time series as CSV text; None if it records none."""
        return None


@dataclass(frozen=True)
class Trajectory:
    """Angle and speed against time; arrays have shape (n_times, *batch_shape).

    Attributes
    ----------
    method : solver name
    time : times [s], shape (n_times,)
    angle : deployed angle [rad]
    speed : input-shaft speed [rad/s]
    """

    method: str
    time: FloatArray
    angle: FloatArray
    speed: FloatArray


class Solver(Protocol):
    """A named deployment method."""

    @property
    def name(self) -> str:
        """Registry name of the method."""
        ...

    @property
    def label(self) -> str:
        """Human label for tables and plots."""
        ...

    @property
    def needs_dynamics(self) -> bool:
        """True if the method needs the dynamic parameters (inertia, stiction, end stop).

        :func:`ecdsim.deployment.predict` then builds a
        :class:`~ecdsim.dynamics.DynamicProblem` (from its ``dynamics=`` argument), and
        the config asks for ``[load] inertia``; otherwise a
        :class:`QuasiStaticProblem` is all the method reads.
        """
        ...

    def solve(self, problem: QuasiStaticProblem) -> DeploymentSolution:
        """Deployment time and speeds for every case of the batch."""
        ...

    def trajectory(self, problem: QuasiStaticProblem, times: ArrayLike) -> Trajectory:
        """Angle and speed at the given times [s] for every case of the batch."""
        ...


def undamped_cases(problem: QuasiStaticProblem) -> tuple[QuasiStaticProblem, BoolArray]:
    """Split off the cases a quasi-static method cannot solve: BECD_T = 0 (or tiny).

    ``B * dphi/dt = T(phi) - F`` gives an infinite speed where B = 0 and the net torque is
    positive, so the quasi-static methods have no answer there (the dynamic method, with
    inertia, does). Returns the problem with those damping rates replaced by
    1 N*m*s/rad, so that the solver's arithmetic stays finite, and the mask of the
    replaced cases, which :func:`mark_unsolved` then reports as not solved.
    """
    rate = problem.damping_rate
    # A damping rate so small that the Eq. 5 speed overflows (a gear ratio of 1e-160
    # squares to a subnormal) is no more solvable than zero.
    with np.errstate(over="ignore"):
        speed_bound = np.maximum(problem.net_torques, 0.0).max(axis=0) / np.where(
            rate > 0.0, rate, 1.0
        )
    undamped = ~(rate > 0.0) | ~np.isfinite(speed_bound)
    if not np.any(undamped):
        return problem, undamped
    safe = replace(problem, damping_rate=np.where(undamped, 1.0, problem.damping_rate))
    return safe, undamped


def mark_unsolved(solution: DeploymentSolution, unsolved: BoolArray) -> DeploymentSolution:
    """The solution with the ``unsolved`` cases flagged (``solved`` False, time +inf)."""
    if not np.any(unsolved):
        return solution
    shape = solution.stalled.shape
    unsolved = np.broadcast_to(unsolved, shape)

    def zero_where(values: FloatArray) -> FloatArray:
        return np.where(unsolved, 0.0, np.broadcast_to(values, shape))

    return replace(
        solution,
        deployment_time=np.where(unsolved, np.inf, solution.deployment_time),
        start_speed=zero_where(solution.start_speed),
        end_speed=zero_where(solution.end_speed),
        max_speed=zero_where(solution.max_speed),
        stalled=solution.stalled & ~unsolved,
        stall_angle=np.where(unsolved, np.nan, solution.stall_angle),
        solved=~unsolved,
    )


def times_against_batch(times: ArrayLike, batch_ndim: int) -> FloatArray:
    """Reshape a 1-D time vector to (n_times, 1, ..., 1) so that it broadcasts."""
    t = np.asarray(times, dtype=float).reshape(-1)
    return t.reshape((-1,) + (1,) * batch_ndim)
