"""What the event loop keeps for time series: closed-form and integrated segment records.

A closed-form record holds, for the cases of one loop iteration, the prepared
:class:`~ecdsim.dynamics.linear.Segment` and where and when it started, so the exact
solution can be re-evaluated at any time. An integrated record holds scipy's dense output
of one case's nonlinear segment.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import FloatArray
from ecdsim.dynamics.linear import Segment, evaluate


@dataclass(frozen=True)
class ClosedFormRecord:
    """Closed-form segments of several cases, started in the same loop iteration.

    Attributes
    ----------
    case : flat case index of each segment
    start_time : time at the segment's start [s]
    duration : time spent in the segment [s] (inf for an asymptotic approach to rest)
    start_angle : deployed angle at the start [rad]
    direction : +1 forward, -1 backward (the segment is solved in the forward frame)
    engaged : whether the damper was engaged (False: free lost-motion phase)
    temperature : the damper's (constant) temperature in the segment [degC]
    segment : the prepared closed form
    """

    case: NDArray[np.intp]
    start_time: FloatArray
    duration: FloatArray
    start_angle: FloatArray
    direction: FloatArray
    engaged: NDArray[np.bool_]
    temperature: FloatArray
    segment: Segment


@dataclass(frozen=True)
class IntegratedRecord:
    """One case's nonlinear segment, as scipy's dense output.

    ``solution(t - start_time)`` returns ``[x, u, T_d, E]`` in the forward frame:
    displacement, speed, damper temperature and damper energy.
    """

    case: int
    start_time: float
    duration: float
    start_angle: float
    direction: float
    solution: Callable[[FloatArray], FloatArray]


@dataclass(frozen=True)
class Sampled:
    """States sampled at given times; arrays of shape (n_times, n_cases).

    Attributes
    ----------
    angle : deployed angle [rad]
    speed : load speed [rad/s]
    damper_temperature : [degC]
    engaged : True where the damper is engaged
    """

    angle: FloatArray
    speed: FloatArray
    damper_temperature: FloatArray
    engaged: NDArray[np.bool_]


def sample(
    times: FloatArray,
    closed: list[ClosedFormRecord],
    integrated: list[IntegratedRecord],
    initial: tuple[FloatArray, FloatArray, FloatArray, NDArray[np.bool_]],
    final: tuple[FloatArray, FloatArray, FloatArray, NDArray[np.bool_], FloatArray],
) -> Sampled:
    """Evaluate the recorded segments at ``times`` (shape (n_times, n_cases)).

    Before t = 0 the initial state is returned; after a case's final time its final state
    is held.
    """
    angle0, speed0, temp0, engaged0 = initial
    angle_f, speed_f, temp_f, engaged_f, time_f = final
    shape = times.shape
    angle = np.broadcast_to(angle0, shape).copy()
    speed = np.broadcast_to(speed0, shape).copy()
    temperature = np.broadcast_to(temp0, shape).copy()
    engaged = np.broadcast_to(engaged0, shape).copy()
    for rec in closed:
        t_local = times[:, rec.case] - rec.start_time
        inside = (t_local >= 0.0) & (t_local < rec.duration)
        if not np.any(inside):
            continue
        state = evaluate(rec.segment, np.where(inside, t_local, 0.0), energy=False)
        rows, cols = np.nonzero(inside)
        cases = rec.case[cols]
        angle[rows, cases] = rec.start_angle[cols] + rec.direction[cols] * state.x[rows, cols]
        speed[rows, cases] = rec.direction[cols] * state.v[rows, cols]
        temperature[rows, cases] = rec.temperature[cols]
        engaged[rows, cases] = rec.engaged[cols]
    for irec in integrated:
        t_local = times[:, irec.case] - irec.start_time
        inside = (t_local >= 0.0) & (t_local < irec.duration)
        if not np.any(inside):
            continue
        y = np.asarray(irec.solution(t_local[inside]), dtype=float)
        angle[inside, irec.case] = irec.start_angle + irec.direction * y[0]
        speed[inside, irec.case] = irec.direction * y[1]
        temperature[inside, irec.case] = y[2]
        engaged[inside, irec.case] = True
    after = times >= time_f
    angle = np.where(after, angle_f, angle)
    speed = np.where(after, speed_f, speed)
    temperature = np.where(after, temp_f, temperature)
    engaged = np.where(after, engaged_f, engaged)
    return Sampled(angle=angle, speed=speed, damper_temperature=temperature, engaged=engaged)
