"""The exact solution of the quasi-static equation ``B * dphi/dt = T(phi) - F``.

The spring torque is piecewise linear in angle (two breakpoints for the linear spring of
Eq. 7, more for a table), so on each segment the equation is linear and first order and
its solution is an exponential (see :mod:`ecdsim.physics.quasistatic` and
``docs/model.md``). The time across a segment is ``B * L / logmean(a, b)`` where a and b
are the net torques at its ends; a stall is where the net torque first reaches zero, and
the mechanism approaches it asymptotically (infinite deployment time).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ecdsim._types import ArrayLike, FloatArray
from ecdsim.physics.quasistatic import (
    locate_stall,
    segment_angle,
    segment_duration,
    segment_speed,
)
from ecdsim.solvers import exact_gravity, exact_kernel
from ecdsim.solvers.base import (
    DeploymentSolution,
    QuasiStaticProblem,
    Trajectory,
    mark_unsolved,
    times_against_batch,
    undamped_cases,
)


def segment_start_times(problem: QuasiStaticProblem) -> FloatArray:
    """Time at which each breakpoint is reached, shape (n_breakpoints, *batch) [s].

    +inf for every breakpoint beyond a stall.
    """
    net = problem.net_torques
    angles = problem.angles
    b = problem.damping_rate
    durations = [
        segment_duration(angles[i + 1] - angles[i], b, net[i], net[i + 1])
        for i in range(angles.shape[0] - 1)
    ]
    zero = np.zeros(problem.batch_shape)
    # A case that cannot start (net torque <= 0 at release) never reaches breakpoint 1.
    return np.stack([zero, *np.cumsum(np.broadcast_arrays(*durations), axis=0)])


@dataclass(frozen=True)
class ExactMethod:
    """Exact piecewise-exponential solution of the quasi-static deployment."""

    name: str = "exact"
    label: str = "exact quasi-static"
    needs_dynamics: bool = False

    def solve(self, problem: QuasiStaticProblem, kernel: str | None = None) -> DeploymentSolution:
        """Deployment time, start, end and peak speed for every case of the batch.

        Cases with no damping (BECD_T = 0) are returned as not solved. ``kernel`` is one
        of :data:`ecdsim.solvers.exact_kernel.KERNELS`; None chooses by batch size and
        what is installed (:func:`ecdsim.solvers.exact_kernel.choose`). The fast kernels
        compute the same function as :meth:`solve_reference` (tests/test_exact_kernel.py).
        """
        if problem.has_gravity:  # not piecewise linear: the quadrature path (docs/model.md)
            return exact_gravity.solve(problem, self.name)
        chosen = kernel or exact_kernel.choose(int(np.prod(problem.batch_shape, dtype=np.int64)))
        if chosen == "reference":
            return self.solve_reference(problem)
        if chosen not in exact_kernel.KERNELS:
            raise ValueError(f"kernel {chosen!r}: expected one of {list(exact_kernel.KERNELS)}")
        found = exact_kernel.solve_fast(problem, chosen, self.solve_reference)
        return DeploymentSolution(
            method=self.name,
            deployment_time=found.deployment_time,
            start_speed=found.start_speed,
            end_speed=found.end_speed,
            max_speed=found.max_speed,
            stalled=found.stalled,
            stall_angle=found.stall_angle,
            solved=found.solved,
        )

    def solve_reference(self, problem: QuasiStaticProblem) -> DeploymentSolution:
        """:meth:`solve` by the reference implementation: whole-batch NumPy, for clarity."""
        if problem.has_gravity:
            return exact_gravity.solve(problem, self.name)
        problem, undamped = undamped_cases(problem)
        return mark_unsolved(self._solve(problem), undamped)

    def _solve(self, problem: QuasiStaticProblem) -> DeploymentSolution:
        shape = problem.batch_shape
        net = np.broadcast_to(problem.net_torques, (problem.angles.shape[0], *shape))
        b = problem.damping_rate
        stalled, stall_angle = locate_stall(problem.angles, net)
        arrival = segment_start_times(problem)[-1]
        moving_net = np.maximum(net, 0.0)
        return DeploymentSolution(
            method=self.name,
            deployment_time=np.where(stalled, np.inf, arrival),
            start_speed=np.broadcast_to(moving_net[0] / b, shape).astype(float),
            end_speed=np.broadcast_to(np.where(stalled, 0.0, net[-1] / b), shape).astype(float),
            max_speed=problem.peak_speed_reached(stalled, stall_angle),
            stalled=np.broadcast_to(stalled, shape).copy(),
            stall_angle=np.broadcast_to(stall_angle, shape).astype(float),
        )

    def trajectory(self, problem: QuasiStaticProblem, times: ArrayLike) -> Trajectory:
        """Angle and speed at the given times; held at the latch after arrival.

        A case with no damping (not solved, see :meth:`solve`) stays at 0.
        """
        if problem.has_gravity:
            return exact_gravity.trajectory(problem, times, self.name)
        problem, undamped = undamped_cases(problem)
        path = self._trajectory(problem, times)
        if not np.any(undamped):
            return path
        return Trajectory(
            method=path.method,
            time=path.time,
            angle=np.where(undamped, 0.0, path.angle),
            speed=np.where(undamped, 0.0, path.speed),
        )

    def _trajectory(self, problem: QuasiStaticProblem, times: ArrayLike) -> Trajectory:
        shape = problem.batch_shape
        n_points = problem.angles.shape[0]
        t = times_against_batch(times, len(shape))
        starts = segment_start_times(problem)
        net = np.broadcast_to(problem.net_torques, (n_points, *shape))
        angles = np.broadcast_to(problem.angles, (n_points, *shape))
        b = problem.damping_rate
        angle = np.zeros(np.broadcast_shapes(t.shape, shape))
        speed = np.zeros_like(angle)
        for i in range(n_points - 1):
            length = angles[i + 1] - angles[i]
            slope = (net[i] - net[i + 1]) / np.where(length > 0.0, length, 1.0)
            in_segment = (t >= starts[i]) & (t < starts[i + 1]) & (net[i] > 0.0)
            elapsed = np.where(
                in_segment, t - np.where(np.isfinite(starts[i]), starts[i], 0.0), 0.0
            )
            phi = angles[i] + segment_angle(elapsed, b, net[i], slope)
            omega = segment_speed(elapsed, b, net[i], slope)
            angle = np.where(in_segment, phi, angle)
            speed = np.where(in_segment, omega, speed)
        arrived = t >= starts[-1]
        angle = np.where(arrived, angles[-1], angle)
        speed = np.where(arrived, 0.0, speed)
        return Trajectory(
            method=self.name,
            time=np.asarray(times, dtype=float).reshape(-1),
            angle=angle,
            speed=speed,
        )


EXACT = ExactMethod()
