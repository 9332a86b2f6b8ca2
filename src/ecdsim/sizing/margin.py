"""Torque margin in the motorisation-ratio form of ECSS-E-ST-33-01C (docs/sizing.md).

The margin at one point of the travel and one temperature is ::

    TM = drive / sum_k(f_k * R_k) - 1

where ``drive`` is the spring torque (the motorisation torque of a spring-driven
deployment), ``R_k`` are the resistive torques by kind and ``f_k`` their uncertainty
factors. Every torque is referred to the ECD's input (slow) shaft, the hinge axis, at the
same angle and temperature. This is the form of ECSS-E-ST-33-01C (motorisation ratio
minus one). ecdsim ships **no** factor values from any standard: every factor defaults to
1 ("no factors applied") and must be taken from the standard the project applies
(docs/sizing.md explains why).

The resistive torques of an ECD deployment, by kind (:data:`RESISTIVE_TYPES`):

* ``ecd_friction``: the ECD's Coulomb friction FECD_T (Eq. 2, 4 of the ECD paper);
* ``system_friction``: the load's friction FS_T (hinge, harness, as measured; section 5);
* ``damping``: BECD_T * omega (Eq. 3) at a required speed, or at the deployment's own
  speed, or nothing (speed 0, the default);
* ``inertia``, ``spring`` (a *resisting* spring) and ``harness``: user allowances that
  the quasi-static model does not contain;
* ``resistive_table``: the config's ``[load] resistive_table`` at the angle (harness,
  blanket torque against angle), which the deployment does contain: the drive is then
  the spring torque alone, and this its own kind with its own factor;
* ``gravity``: a ground test's gravity torque ``m g r (1 - offload) sin(theta_0 + phi)``
  where it opposes deployment (``[load.gravity]``; an aiding gravity torque is not
  credited to the drive), its own kind with its own factor.
* ``gear_loss``: with ``[gearbox] efficiency``, the mesh loss ``(1 - eta_f) (FECD_T +
  BECD_T omega)`` (issue 16 item 5): FECD_T and BECD_T include 1/eta_f, so the
  ``ecd_friction`` and ``damping`` kinds keep their ideal-gear parts ``eta_f`` times them
  and the loss is its own kind with its own factor.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import ArrayLike, BoolArray, FloatArray, as_float
from ecdsim.physics.assembly import input_speed
from ecdsim.physics.gravity import gravity_torque
from ecdsim.sizing.factored import factored_sum, margin_over

RESISTIVE_TYPES = (
    "ecd_friction",
    "system_friction",
    "damping",
    "inertia",
    "spring",
    "harness",
    "resistive_table",
    "gravity",
    "gear_loss",
)
# ECSS-E-ST-33-01C has one kind for friction; ``friction`` is the factor of both Coulomb
# kinds unless ``ecd_friction`` or ``system_friction`` is given on its own.
FRICTION_TYPES = ("ecd_friction", "system_friction")
FACTOR_KEYS = ("friction", *RESISTIVE_TYPES)


def factor_of(kind: str, factors: Mapping[str, float]) -> float:
    """The uncertainty factor of one resistive kind [-]: its own, else ``friction`` for
    the two Coulomb kinds, else 1 ("no factor applied").

    Parameters
    ----------
    kind : resistive kind, one of RESISTIVE_TYPES
    factors : uncertainty factors by key of FACTOR_KEYS [-]

    >>> factor_of("system_friction", {"friction": 1.5})
    1.5
    >>> factor_of("ecd_friction", {"friction": 1.5, "ecd_friction": 2.0})
    2.0
    """
    unknown = set(factors) - set(FACTOR_KEYS)
    if unknown:
        raise KeyError(f"unknown uncertainty factor(s) {sorted(unknown)}; known: {FACTOR_KEYS}")
    if kind in factors:
        return float(factors[kind])
    if kind in FRICTION_TYPES:
        return float(factors.get("friction", 1.0))
    return 1.0


def factored_resistance(
    resistive: Mapping[str, ArrayLike], factors: Mapping[str, float]
) -> FloatArray:
    """``sum_k(f_k * R_k)``, the factored resistive torque [N*m].

    Parameters
    ----------
    resistive : resistive torque by kind, keys from RESISTIVE_TYPES [N*m]
    factors : uncertainty factors by key of FACTOR_KEYS, missing ones count 1 [-]
    """
    unknown = set(resistive) - set(RESISTIVE_TYPES)
    if unknown:
        raise KeyError(f"unknown resistive torque type(s) {sorted(unknown)}")
    # The same arithmetic as a torque budget's (ecdsim.sizing.factored).
    return factored_sum((factor_of(kind, factors), torque) for kind, torque in resistive.items())


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
    resistive : resistive torque by kind, keys from RESISTIVE_TYPES [N*m]
    factors : uncertainty factors by key of FACTOR_KEYS, missing ones count 1 [-]

    >>> torque = {"ecd_friction": 0.5, "system_friction": 0.5, "damping": 0.5}
    >>> round(float(torque_margin(3.0, torque, {"friction": 2.0})), 12)
    0.2
    """
    return margin_over(drive, factored_resistance(resistive, factors))


@dataclass(frozen=True)
class MarginSettings:
    """How the torque margin is evaluated.

    Attributes
    ----------
    factors : uncertainty factor by key of FACTOR_KEYS [-]; 1 = no factor applied
    allowances : margin-only resistive torques (inertia, spring, harness) [N*m]
    damping_speed : speed at which the damping torque is taken [rad/s]; 0 (the default)
        = no damping torque (the margin of a mechanism that must just move); None = the
        deployment's own speed at each angle (then, with unit factors, the margin is 0 by
        quasi-static equilibrium wherever the mechanism moves)
    """

    factors: Mapping[str, float] = field(default_factory=dict)
    allowances: Mapping[str, float] = field(default_factory=dict)
    damping_speed: float | None = 0.0

    @property
    def factors_applied(self) -> bool:
        """False when every factor is 1 (the default: "no factors applied")."""
        return any(v != 1.0 for v in self.factors.values())

    @property
    def damping_mode(self) -> str:
        """``"none"`` (speed 0), ``"fixed"`` (a required speed) or ``"deployment"``."""
        if self.damping_speed is None:
            return "deployment"
        return "fixed" if self.damping_speed > 0.0 else "none"


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
    drive : spring torque at each point [N*m]
    resistive : unfactored resistive torque by kind at each point [N*m]
    factored : sum of the factored resistive torques at each point [N*m]
    margin : torque margin at each point [-]
    valid : False for the padding point where a case does not stall
    """

    angle: FloatArray
    drive: FloatArray
    resistive: dict[str, FloatArray]
    factored: FloatArray
    margin: FloatArray
    valid: BoolArray

    def _lowest(self) -> NDArray[np.intp]:
        lowest: NDArray[np.intp] = np.argmin(np.where(self.valid, self.margin, np.inf), axis=0)
        return lowest[np.newaxis]

    def minimum(self) -> tuple[FloatArray, FloatArray]:
        """Minimum margin over the travel and the angle [rad] where it occurs."""
        index = self._lowest()
        masked = np.where(self.valid, self.margin, np.inf)
        low = np.take_along_axis(masked, index, axis=0)[0]
        where = np.take_along_axis(self.angle, index, axis=0)[0]
        return as_float(low), as_float(where)

    def at_minimum(self) -> TorqueMarginTerms:
        """Every term of the margin at the point of the travel where it is smallest."""
        index = self._lowest()

        def pick(values: FloatArray) -> FloatArray:
            full = np.broadcast_to(values, self.margin.shape)
            return as_float(np.take_along_axis(full, index, axis=0)[0])

        low, where = self.minimum()
        return TorqueMarginTerms(
            margin=low,
            angle=where,
            drive=pick(self.drive),
            resistive={kind: pick(torque) for kind, torque in self.resistive.items()},
            factored=pick(self.factored),
        )


@dataclass(frozen=True)
class TorqueMarginTerms:
    """The torque margin and its terms at one point of the travel, per case.

    Attributes
    ----------
    margin : TM = drive / factored - 1 [-]
    angle : deployed angle of the point [rad]
    drive : spring torque there [N*m]
    resistive : unfactored resistive torque by kind there, at the ECD input [N*m]
    factored : sum of the factored resistive torques there [N*m]
    """

    margin: FloatArray
    angle: FloatArray
    drive: FloatArray
    resistive: dict[str, FloatArray]
    factored: FloatArray


def margin_over_travel(
    breakpoint_angles: ArrayLike,
    spring_torques: ArrayLike,
    *,
    ecd_friction: ArrayLike,
    system_friction: ArrayLike,
    damping_rate: ArrayLike,
    stalled: ArrayLike,
    stall_angle: ArrayLike,
    settings: MarginSettings,
    resistance: ArrayLike | None = None,
    gravity_amplitude: ArrayLike | None = None,
    gravity_angle: ArrayLike | None = None,
    forward_efficiency: ArrayLike | None = None,
) -> MarginOverTravel:
    """Torque margin at every spring breakpoint and at the stall point (docs/sizing.md).

    Resistive torques at a point, at the ECD input: ``ecd_friction`` = FECD_T,
    ``system_friction`` = FS_T, ``damping`` = BECD_T * omega with omega
    ``settings.damping_speed`` (0 by default: no damping torque) or, if that is None, the
    quasi-static speed there (Eq. 5, zero where the spring torque does not exceed the
    friction); plus the settings' allowances.

    Parameters
    ----------
    breakpoint_angles : deployed angles of the spring breakpoints, along axis 0 [rad]
    spring_torques : spring torque at each breakpoint, the drive [N*m]
    ecd_friction : FECD_T at the input shaft [N*m]
    system_friction : FS_T at the input shaft [N*m]
    damping_rate : BECD_T at the input shaft [N*m*s/rad]
    stalled : True where the deployment stalls [-]
    stall_angle : angle of the stall [rad], ignored where not stalled
    settings : factors, allowances and damping speed
    resistance : the resistive table's torque at each breakpoint [N*m], where
        ``spring_torques`` is the net drive (spring less resistance); None without one
    gravity_amplitude : W = m g r (1 - offload) of a ground test [N*m], None without
        gravity; the margin is then also taken on :data:`GRAVITY_GRID` equal steps of the
        travel (the sine is not piecewise linear), the spring interpolated there
    gravity_angle : theta_0, the gravity term's release angle [rad]
    forward_efficiency : eta_f of a lossy mesh, which FECD_T and BECD_T include [-];
        None for an ideal gear (no ``gear_loss`` kind)
    """
    angles = as_float(breakpoint_angles)
    torques = as_float(spring_torques)
    if gravity_amplitude is not None:
        angles, torques, resistance = _gravity_grid(angles, torques, resistance)
    fecd = as_float(ecd_friction)
    fs = as_float(system_friction)
    f = as_float(fecd + fs)
    b = as_float(damping_rate)
    stop = np.asarray(stalled, dtype=bool)
    # The stall point: net drive torque equal to the friction, at the stall angle.
    stop_angle = np.nan_to_num(as_float(stall_angle))
    resist: FloatArray | None = None
    if resistance is not None:
        points, resist_at = np.broadcast_arrays(angles, as_float(resistance))
        batch = np.broadcast_shapes(points.shape[1:], stop_angle.shape)
        points = np.broadcast_to(points, (points.shape[0], *batch))
        resist_at = np.broadcast_to(resist_at, points.shape)
        at_stop = _interpolate_axis0(np.broadcast_to(stop_angle, batch), points, resist_at)
        resist = as_float(np.concatenate([resist_at, at_stop[None]]))
    angles = np.concatenate([angles, np.broadcast_to(stop_angle, angles.shape[1:])[None]])
    weight = as_float(0.0)
    at_stall = f
    if gravity_amplitude is not None:
        # T_g at every point (physics.gravity); at the stall the net drive less gravity
        # equals the friction, so there the spring less resistance is F + T_g.
        theta0 = as_float(0.0 if gravity_angle is None else gravity_angle)
        weight = as_float(gravity_torque(angles, as_float(gravity_amplitude), theta0))
        at_stall = as_float(f + weight[-1])
    drive = np.concatenate([torques, np.broadcast_to(at_stall, torques.shape[1:])[None]])
    if resist is not None:
        drive = drive + resist  # the spring torque: net drive plus the resistance
    angles, drive = np.broadcast_arrays(angles, drive)
    if settings.damping_speed is None:
        speed = input_speed(drive - weight, f, b)
    else:
        speed = as_float(np.full(drive.shape, settings.damping_speed))
    resistive: dict[str, FloatArray] = {
        "ecd_friction": as_float(np.broadcast_to(fecd, drive.shape)),
        "system_friction": as_float(np.broadcast_to(fs, drive.shape)),
        "damping": as_float(np.broadcast_to(b * speed, drive.shape)),
    }
    if resist is not None:
        resistive["resistive_table"] = as_float(np.broadcast_to(resist, drive.shape))
    if gravity_amplitude is not None:
        resistive["gravity"] = as_float(np.broadcast_to(np.maximum(weight, 0.0), drive.shape))
    if forward_efficiency is not None:
        # The mesh loss apart: (1 - eta_f) of the ECD's torque at the input.
        eta = as_float(forward_efficiency)
        ecd_torque = resistive["ecd_friction"] + resistive["damping"]
        resistive["ecd_friction"] = as_float(resistive["ecd_friction"] * eta)
        resistive["damping"] = as_float(resistive["damping"] * eta)
        resistive["gear_loss"] = as_float(np.broadcast_to((1.0 - eta) * ecd_torque, drive.shape))
    for kind, torque in settings.allowances.items():
        resistive[kind] = as_float(np.full(drive.shape, torque))
    margin = torque_margin(drive, resistive, settings.factors)
    valid = np.ones(margin.shape, dtype=bool)
    valid[-1] = np.broadcast_to(stop, margin.shape[1:])
    return MarginOverTravel(
        angle=as_float(angles),
        drive=as_float(drive),
        resistive=resistive,
        factored=as_float(
            np.broadcast_to(factored_resistance(resistive, settings.factors), drive.shape)
        ),
        margin=margin,
        valid=valid,
    )


# Equal steps of the travel at which the margin is also taken under gravity.
GRAVITY_GRID = 128


def _gravity_grid(
    angles: FloatArray, torques: FloatArray, resistance: ArrayLike | None
) -> tuple[FloatArray, FloatArray, FloatArray | None]:
    """The breakpoints and GRAVITY_GRID + 1 equal steps of the travel, in order of angle,
    with the (piecewise-linear) drive and resistance interpolated there."""
    resist = None if resistance is None else as_float(resistance)
    shapes = [angles.shape[1:], torques.shape[1:]]
    if resist is not None:
        shapes.append(resist.shape[1:])
    batch = np.broadcast_shapes(*shapes)
    points = np.broadcast_to(angles, (angles.shape[0], *batch))
    travel = points[-1]
    steps = [travel * (k / GRAVITY_GRID) for k in range(GRAVITY_GRID + 1)]

    def extended(values: FloatArray) -> FloatArray:
        full = np.broadcast_to(values, points.shape)
        grid = [_interpolate_axis0(x, points, full) for x in steps]
        return as_float(np.concatenate([full, np.stack(grid)]))

    all_angles = as_float(np.concatenate([points, np.stack(steps)]))
    order = np.argsort(all_angles, axis=0, kind="stable")
    new_torques = np.take_along_axis(extended(torques), order, axis=0)
    new_resist = None if resist is None else np.take_along_axis(extended(resist), order, axis=0)
    return np.take_along_axis(all_angles, order, axis=0), new_torques, new_resist


def _interpolate_axis0(x: ArrayLike, xp: ArrayLike, fp: ArrayLike) -> FloatArray:
    """Linear interpolation at ``x`` (batch shape) in tables ``xp``, ``fp`` along axis 0.

    ``xp`` ascends along axis 0 (repeated values allowed: zero-length segments); outside
    the table the end values are taken, as ``numpy.interp`` does.
    """
    table_x = as_float(xp)
    table_f = as_float(fp)
    query = as_float(x)
    last = table_x.shape[0] - 1
    k = np.clip(np.sum(table_x <= query[None], axis=0) - 1, 0, max(last - 1, 0))[None]
    x0 = np.take_along_axis(table_x, k, axis=0)[0]
    x1 = np.take_along_axis(table_x, np.minimum(k + 1, last), axis=0)[0]
    f0 = np.take_along_axis(table_f, k, axis=0)[0]
    f1 = np.take_along_axis(table_f, np.minimum(k + 1, last), axis=0)[0]
    width = x1 - x0
    weight = np.clip(
        np.where(width > 0.0, (query - x0) / np.where(width > 0.0, width, 1.0), 0.0), 0.0, 1.0
    )
    return as_float(f0 + weight * (f1 - f0))
