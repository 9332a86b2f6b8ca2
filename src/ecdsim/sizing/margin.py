"""Torque margin after the space-mechanism motorisation-ratio approach (docs/sizing.md).

The margin at one point of the travel and one temperature is ::

    margin = drive / sum_k(f_k * R_k) - 1

where ``drive`` is the spring torque (the motorisation torque of a spring-driven
deployment), ``R_k`` are the resistive torques by type (friction, damping, inertia,
spring, harness) and ``f_k`` their uncertainty factors. This is the form of the
motorisation ratio of ECSS-E-ST-33-01C (margin = ratio - 1). ecdsim ships **no** factor
values from any standard: every factor defaults to 1 ("no factors applied") and must be
taken from the standard the project applies (docs/sizing.md explains why).

For an ECD deployment the resistive torques at a point are: friction = FECD_T + FS_T,
damping = BECD_T * omega (the deployment's own speed at that angle, or a fixed required
speed), and user allowances for inertia, resisting springs and harness that the
quasi-static model does not contain.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ecdsim._types import ArrayLike, BoolArray, FloatArray, as_float
from ecdsim.physics.assembly import input_speed

RESISTIVE_TYPES = ("friction", "damping", "inertia", "spring", "harness")

# Below this relative size a margin is float rounding of an exact zero: with damping at the
# deployment's own speed and unit factors, drive and resistance are equal by quasi-static
# equilibrium, and their quotient differs from 1 only in the last bits.
_ROUNDING = 1e-12


def torque_margin(
    drive: ArrayLike,
    resistive: Mapping[str, ArrayLike],
    factors: Mapping[str, float],
) -> FloatArray:
    """Torque margin ``drive / sum_k(f_k * R_k) - 1`` (motorisation ratio minus one).

    The form of the motorisation ratio of ECSS-E-ST-33-01C; the factor values are the
    user's (no standard's values are built in). +inf where the factored resistance is
    zero and the drive positive (nothing resists), -1 where both are zero.

    Parameters
    ----------
    drive : driving (motorisation) torque, here the spring torque [N*m]
    resistive : resistive torque by type, keys from RESISTIVE_TYPES [N*m]
    factors : uncertainty factor by type, missing types count 1 [-]

    >>> round(float(torque_margin(3.0, {"friction": 1.0, "damping": 0.5}, {"friction": 2.0})), 12)
    0.2
    """
    unknown = set(resistive) - set(RESISTIVE_TYPES)
    if unknown:
        raise KeyError(f"unknown resistive torque type(s) {sorted(unknown)}")
    total = as_float(0.0)
    for kind, torque in resistive.items():
        total = as_float(total + factors.get(kind, 1.0) * as_float(torque))
    t = as_float(drive)
    total, t = np.broadcast_arrays(total, t)
    positive = total > 0.0
    ratio = t / np.where(positive, total, 1.0)
    margin = np.where(positive, ratio - 1.0, np.where(t > 0.0, np.inf, -1.0))
    return as_float(np.where(np.abs(margin) < _ROUNDING, 0.0, margin))


@dataclass(frozen=True)
class MarginSettings:
    """How the torque margin is evaluated.

    Attributes
    ----------
    factors : uncertainty factor per resistive-torque type [-]; 1 = no factor applied
    allowances : margin-only resistive torques (inertia, spring, harness) [N*m]
    damping_speed : speed at which the damping torque is taken [rad/s]; None = the
        deployment's own speed at each angle (then, with unit factors, the margin is 0 by
        quasi-static equilibrium wherever the mechanism moves)
    """

    factors: Mapping[str, float] = field(default_factory=dict)
    allowances: Mapping[str, float] = field(default_factory=dict)
    damping_speed: float | None = None

    @property
    def factors_applied(self) -> bool:
        """False when every factor is 1 (the default: "no factors applied")."""
        return any(v != 1.0 for v in self.factors.values())


@dataclass(frozen=True)
class MarginOverTravel:
    """Torque margin at the breakpoints of the travel and at the stall point.

    Arrays have shape (n_points, *batch); the margin between points needs no sampling:
    on each segment of a piecewise-linear spring the margin is a monotone function of the
    spring torque, so its extremes lie at breakpoints or where the net torque reaches
    zero (the stall point), which are all included.

    Attributes
    ----------
    angle : deployed angle of each point [rad]
    margin : torque margin at each point [-]
    valid : False for the padding point where a case does not stall
    """

    angle: FloatArray
    margin: FloatArray
    valid: BoolArray

    def minimum(self) -> tuple[FloatArray, FloatArray]:
        """Minimum margin over the travel and the angle [rad] where it occurs."""
        masked = np.where(self.valid, self.margin, np.inf)
        index = np.argmin(masked, axis=0)
        low = np.take_along_axis(masked, index[np.newaxis], axis=0)[0]
        where = np.take_along_axis(self.angle, index[np.newaxis], axis=0)[0]
        return as_float(low), as_float(where)


def margin_over_travel(
    breakpoint_angles: ArrayLike,
    spring_torques: ArrayLike,
    friction: ArrayLike,
    damping_rate: ArrayLike,
    stalled: ArrayLike,
    stall_angle: ArrayLike,
    settings: MarginSettings,
) -> MarginOverTravel:
    """Torque margin at every spring breakpoint and at the stall point (docs/sizing.md).

    Resistive torques at a point: friction = FECD_T + FS_T; damping = BECD_T * omega with
    omega the quasi-static speed there (Eq. 5, zero where the spring torque does not
    exceed the friction) or ``settings.damping_speed``; plus the settings' allowances.

    Parameters
    ----------
    breakpoint_angles : deployed angles of the spring breakpoints, along axis 0 [rad]
    spring_torques : spring torque at each breakpoint, the drive [N*m]
    friction : FECD_T + FS_T at the input shaft [N*m]
    damping_rate : BECD_T at the input shaft [N*m*s/rad]
    stalled : True where the deployment stalls [-]
    stall_angle : angle of the stall [rad], ignored where not stalled
    settings : factors, allowances and damping speed
    """
    angles = as_float(breakpoint_angles)
    torques = as_float(spring_torques)
    f = as_float(friction)
    b = as_float(damping_rate)
    stop = np.asarray(stalled, dtype=bool)
    # The stall point: spring torque equal to the friction, at the stall angle.
    angles = np.concatenate(
        [angles, np.broadcast_to(np.nan_to_num(as_float(stall_angle)), angles.shape[1:])[None]]
    )
    drive = np.concatenate([torques, np.broadcast_to(f, torques.shape[1:])[None]])
    angles, drive = np.broadcast_arrays(angles, drive)
    if settings.damping_speed is None:
        speed = input_speed(drive, f, b)
    else:
        speed = as_float(np.full(drive.shape, settings.damping_speed))
    resistive: dict[str, FloatArray] = {
        "friction": as_float(np.broadcast_to(f, drive.shape)),
        "damping": as_float(b * speed),
    }
    for kind, torque in settings.allowances.items():
        resistive[kind] = as_float(np.full(drive.shape, torque))
    margin = torque_margin(drive, resistive, settings.factors)
    valid = np.ones(margin.shape, dtype=bool)
    valid[-1] = np.broadcast_to(stop, margin.shape[1:])
    return MarginOverTravel(angle=as_float(angles), margin=margin, valid=valid)
