"""The paper's closed-form method, Eq. 8 to 13, exactly as printed.

Eq. 12 is missing from the paper's text; the deceleration that makes Eq. 13 reach the end
of travel at Eq. 11's time is ``alpha = (omega_e - omega_s) / delta_t`` (negative for a
falling spring torque), and ecdsim uses that. With it, Eq. 13 in ecdsim's deployed angle
phi = theta_s - theta reads ``phi(t) = omega_s t + alpha t**2 / 2``.

The method only looks at the torques at the start and the end of travel (for a tabulated
spring, the first and last points). Where the spring torque falls to the friction before
the end of travel, Eq. 8-11 are invalid: the method then reports the same stall as the
exact solver (the stall is a property of load and friction, not of the method).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, as_float
from ecdsim.physics.gravity import gravity_torque
from ecdsim.physics.quasistatic import locate_stall
from ecdsim.solvers import exact_gravity
from ecdsim.solvers.base import (
    DeploymentSolution,
    QuasiStaticProblem,
    Trajectory,
    mark_unsolved,
    times_against_batch,
    undamped_cases,
)


def start_speed(
    start_torque: ArrayLike, friction: ArrayLike, damping_rate: ArrayLike
) -> FloatArray:
    """Speed at the start of deployment (Eq. 8): ``omega_s = (Ts - (FECD_T + FS_T)) / BECD_T``.

    Parameters
    ----------
    start_torque : Ts [N*m]
    friction : FECD_T + FS_T [N*m]
    damping_rate : BECD_T [N*m*s/rad]
    """
    return as_float((as_float(start_torque) - as_float(friction)) / as_float(damping_rate))


def end_speed(end_torque: ArrayLike, friction: ArrayLike, damping_rate: ArrayLike) -> FloatArray:
    """Speed at the end of deployment (Eq. 9): ``omega_e = (Te - (FECD_T + FS_T)) / BECD_T``.

    Parameters
    ----------
    end_torque : Te [N*m]
    friction : FECD_T + FS_T [N*m]
    damping_rate : BECD_T [N*m*s/rad]
    """
    return start_speed(end_torque, friction, damping_rate)


def mean_speed(omega_s: ArrayLike, omega_e: ArrayLike) -> FloatArray:
    """Average velocity (Eq. 10): ``(omega_s + omega_e) / 2``.

    Parameters
    ----------
    omega_s : start speed [rad/s]
    omega_e : end speed [rad/s]
    """
    return as_float((as_float(omega_s) + as_float(omega_e)) / 2.0)


def deployment_time(travel: ArrayLike, omega_mean: ArrayLike) -> FloatArray:
    """Deployment time (Eq. 11): ``delta_t = delta_theta / omega_mean``.

    Parameters
    ----------
    travel : deployment angle delta_theta [rad]
    omega_mean : average velocity [rad/s], > 0

    >>> round(float(deployment_time(1.57, 0.0785)), 6)
    20.0
    """
    return as_float(as_float(travel) / as_float(omega_mean))


def deceleration(omega_s: ArrayLike, omega_e: ArrayLike, delta_t: ArrayLike) -> FloatArray:
    """Constant acceleration (the missing Eq. 12): ``alpha = (omega_e - omega_s) / delta_t``.

    Parameters
    ----------
    omega_s : start speed [rad/s]
    omega_e : end speed [rad/s]
    delta_t : deployment time [s]
    """
    return as_float((as_float(omega_e) - as_float(omega_s)) / as_float(delta_t))


def position_eq13(
    time: ArrayLike, start_angle: ArrayLike, omega_s: ArrayLike, alpha: ArrayLike
) -> FloatArray:
    """Angle to the end of travel at time t (Eq. 13): ``theta_s - omega_s t - alpha t**2 / 2``.

    Written with the sign that makes theta reach 0 at Eq. 11's time when alpha is the
    (negative) value of Eq. 12.

    Parameters
    ----------
    time : t since release [s]
    start_angle : theta_s, the deployment angle [rad]
    omega_s : start speed [rad/s]
    alpha : acceleration from Eq. 12 [rad/s**2]
    """
    t = as_float(time)
    return as_float(as_float(start_angle) - as_float(omega_s) * t - 0.5 * as_float(alpha) * t * t)


@dataclass(frozen=True)
class PaperMethod:
    """The paper's mean-velocity, constant-deceleration method (Eq. 8-13)."""

    name: str = "paper"
    label: str = "paper (Eq. 8-13)"
    needs_dynamics: bool = False

    def solve(self, problem: QuasiStaticProblem) -> DeploymentSolution:
        """Eq. 8-11 for every case; stalled cases get +inf and the stall angle.

        Cases with no damping (BECD_T = 0: Eq. 8-9 divide by it) are returned as not
        solved.
        """
        problem, undamped = undamped_cases(problem)
        return mark_unsolved(self._solve(problem), undamped)

    def _solve(self, problem: QuasiStaticProblem) -> DeploymentSolution:
        shape = problem.batch_shape
        start_torque, end_torque = problem.torques[0], problem.torques[-1]
        if problem.has_gravity:
            # Eq. 8-9 with the end-point torques less gravity there; the stall and the
            # peak are the load's, found as the exact method finds them (docs/model.md).
            assert problem.gravity_amplitude is not None
            assert problem.gravity_angle is not None
            start_torque = start_torque - gravity_torque(
                0.0, problem.gravity_amplitude, problem.gravity_angle
            )
            end_torque = end_torque - gravity_torque(
                problem.travel, problem.gravity_amplitude, problem.gravity_angle
            )
            stalled, stall_angle, peak = exact_gravity.stall_and_peak(problem)
        else:
            stalled, stall_angle = locate_stall(problem.angles, problem.net_torques)
            peak = problem.peak_speed_reached(stalled, stall_angle)
        omega_s = start_speed(start_torque, problem.friction, problem.damping_rate)
        omega_e = end_speed(end_torque, problem.friction, problem.damping_rate)
        omega_bar = mean_speed(omega_s, omega_e)
        safe_mean = np.where(stalled | (omega_bar <= 0.0), 1.0, omega_bar)
        delta_t = np.where(stalled, np.inf, deployment_time(problem.travel, safe_mean))
        return DeploymentSolution(
            method=self.name,
            deployment_time=np.broadcast_to(delta_t, shape).astype(float),
            start_speed=np.broadcast_to(np.maximum(omega_s, 0.0), shape).astype(float),
            end_speed=np.broadcast_to(np.where(stalled, 0.0, omega_e), shape).astype(float),
            # The linear-range check is physical, not the method's: the peak speed is taken
            # over every breakpoint (a tabulated spring may peak mid-travel), as in exact.
            max_speed=peak,
            stalled=np.broadcast_to(stalled, shape).copy(),
            stall_angle=np.broadcast_to(stall_angle, shape).astype(float),
        )

    def trajectory(self, problem: QuasiStaticProblem, times: ArrayLike) -> Trajectory:
        """Eq. 13 up to the end of travel, then held at the latch.

        A stalled case has no Eq. 11 time; the same constant-deceleration idea is applied
        up to the stall angle (uniform deceleration from omega_s to rest over the angle to
        the stall), so that the curve stays defined and ends where the exact one does.
        """
        solution = self.solve(problem)
        t = times_against_batch(times, len(solution.deployment_time.shape))
        omega_s = solution.start_speed
        stalled = solution.stalled
        target = np.where(stalled, np.nan_to_num(solution.stall_angle), problem.travel)
        final = np.where(stalled, 0.0, solution.end_speed)
        omega_bar = mean_speed(omega_s, final)  # Eq. 10
        moving = omega_bar > 0.0
        duration = np.where(moving, deployment_time(target, np.where(moving, omega_bar, 1.0)), 0.0)
        alpha = deceleration(omega_s, final, np.where(moving, duration, 1.0))  # Eq. 12
        tc = np.minimum(t, duration)
        angle = target - position_eq13(tc, target, omega_s, np.where(moving, alpha, 0.0))  # Eq. 13
        speed = np.where(moving & (t < duration), omega_s + alpha * tc, 0.0)
        return Trajectory(
            method=self.name,
            time=as_float(times).reshape(-1),
            angle=np.asarray(angle),
            speed=np.asarray(speed),
        )


PAPER = PaperMethod()
