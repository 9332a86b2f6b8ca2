"""Deployment requirements and their margins (docs/sizing.md, "Requirements").

Every requirement becomes a margin that is >= 0 where it is met and < 0 where it is not,
finite for every finite input and continuous across a stall (so that the gear-ratio
intervals of :mod:`ecdsim.sizing.ratio` can find its roots):

============================  ==========================================  =============
requirement                   margin                                      at a stall
============================  ==========================================  =============
deployment time >= t_min      (t - t_min) / t   = 1 - t_min / t           1
deployment time <= t_max      (t_max - t) / t   = t_max / t - 1           -1
end speed <= v_max            (v_max - v) / v_max                         1 (v = 0)
quantity x <= limit L         (L - x) / L  (input torque, damper limits)
no stall                      (min spring torque - friction) / friction   < 0
torque margin >= m_min        m - m_min
============================  ==========================================  =============
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, as_float
from ecdsim.config.sizing_schema import RequirementsSpec
from ecdsim.sizing.margin import MarginSettings

if TYPE_CHECKING:
    from ecdsim.units_display import UnitSystem


def min_time_margin(deployment_time: ArrayLike, minimum: float) -> FloatArray:
    """Margin of ``t >= t_min``: ``1 - t_min / t``; 1 where stalled (t = +inf).

    Parameters
    ----------
    deployment_time : t, deployment time [s], +inf where stalled
    minimum : t_min, shortest allowed deployment time [s]

    >>> float(min_time_margin(40.0, 30.0))
    0.25
    """
    return as_float(1.0 - minimum / as_float(deployment_time))


def max_time_margin(deployment_time: ArrayLike, maximum: float) -> FloatArray:
    """Margin of ``t <= t_max``: ``t_max / t - 1``; -1 where stalled (t = +inf).

    Parameters
    ----------
    deployment_time : t, deployment time [s], +inf where stalled
    maximum : t_max, longest allowed deployment time [s]

    >>> float(max_time_margin(40.0, 50.0))
    0.25
    """
    return as_float(maximum / as_float(deployment_time) - 1.0)


def upper_limit_margin(value: ArrayLike, limit: ArrayLike) -> FloatArray:
    """Margin of ``x <= L``: ``(L - x) / L``; +inf where no limit is given (L is NaN).

    Parameters
    ----------
    value : x, the quantity (speed [rad/s] or torque [N*m])
    limit : L, its largest allowed value, same unit as x; NaN for "no limit"

    >>> float(upper_limit_margin(3.0, 4.0))
    0.25
    """
    lim = as_float(limit)
    given = np.isfinite(lim)
    safe = np.where(given, lim, 1.0)
    return as_float(np.where(given, (safe - as_float(value)) / safe, np.inf))


def stall_margin(spring_torques: ArrayLike, friction: ArrayLike) -> FloatArray:
    """Margin of "no stall": ``(min over travel of spring torque - F) / F`` (paper Eq. 8-9).

    A quasi-static deployment stalls where the spring torque falls to the total friction
    F = FECD_T + FS_T; the spring torque is piecewise linear, so its minimum is at a
    breakpoint (axis 0). Where F <= 0 (a friction law outside its range) the margin is
    +inf if the spring torque stays above F, else -1.

    Parameters
    ----------
    spring_torques : spring torque at each breakpoint, along axis 0 [N*m]
    friction : total resisting Coulomb torque F [N*m]
    """
    low = as_float(np.min(as_float(spring_torques), axis=0))
    f = as_float(friction)
    low, f = np.broadcast_arrays(low, f)
    positive = f > 0.0
    relative = (low - f) / np.where(positive, f, 1.0)
    return as_float(np.where(positive, relative, np.where(low > f, np.inf, -1.0)))


@dataclass(frozen=True)
class Requirements:
    """What a damper and gear ratio must achieve, in SI units (docs/sizing.md).

    Attributes
    ----------
    temperatures : every temperature at which the requirements must hold [degC]
    min_deployment_time : shortest allowed deployment time [s], None if free
    max_deployment_time : longest allowed deployment time [s], None if free
    max_end_speed : largest allowed speed at the latch [rad/s], None if free
    max_input_torque : largest allowed torque at the ECD's input shaft [N*m], None if free
    min_torque_margin : smallest allowed torque margin [-], None if not required
    no_stall : True if a stall at any listed temperature fails the design
    ratio_range : gear ratios scanned for the exact intervals, (low, high) [-]
    margin : how the torque margin is computed
    """

    temperatures: tuple[float, ...]
    min_deployment_time: float | None = None
    max_deployment_time: float | None = None
    max_end_speed: float | None = None
    max_input_torque: float | None = None
    min_torque_margin: float | None = None
    no_stall: bool = True
    ratio_range: tuple[float, float] = (1.0, 10000.0)
    margin: MarginSettings = field(default_factory=MarginSettings)

    @classmethod
    def from_spec(cls, spec: RequirementsSpec) -> Requirements:
        """The SI requirements of a validated ``[requirements]`` section."""
        tm = spec.torque_margin
        allowances = {k: v for k, v in tm.allowances.model_dump().items() if v != 0.0}
        given = tm.factors
        # `friction` is the factor of both Coulomb kinds unless one is given on its own.
        ecd = given.friction if given.ecd_friction is None else given.ecd_friction
        system = given.friction if given.system_friction is None else given.system_friction
        factors = {
            "friction": given.friction,  # kept for the JSON's keys; the two below override it
            "ecd_friction": ecd,
            "system_friction": system,
            "damping": given.damping,
            "inertia": given.inertia,
            "spring": given.spring,
            "harness": given.harness,
            "resistive_table": given.resistive_table,
            "gravity": given.gravity,
            "gear_loss": given.gear_loss,
        }
        return cls(
            temperatures=spec.all_temperatures(),
            min_deployment_time=spec.min_deployment_time,
            max_deployment_time=spec.max_deployment_time,
            max_end_speed=spec.max_end_speed,
            max_input_torque=spec.max_input_torque,
            min_torque_margin=spec.min_torque_margin,
            no_stall=spec.no_stall,
            ratio_range=(float(spec.ratio_range[0]), float(spec.ratio_range[1])),
            margin=MarginSettings(
                factors=factors,
                allowances=allowances,
                damping_speed=tm.damping_speed,
            ),
        )

    def describe(self, units: UnitSystem = "si") -> list[tuple[str, str]]:
        """(requirement, limit) pairs in words, for reports, in ``units``."""
        from ecdsim.units_display import Shown

        u = Shown(units, digits=6)  # %g's six digits
        rows: list[tuple[str, str]] = []
        temps = ", ".join(u.num(t, "temperature") for t in self.temperatures)
        rows.append((u.head("temperatures", "temperature"), temps))
        if self.min_deployment_time is not None:
            rows.append(("deployment time >=", f"{self.min_deployment_time:g} s"))
        if self.max_deployment_time is not None:
            rows.append(("deployment time <=", f"{self.max_deployment_time:g} s"))
        if self.max_end_speed is not None:
            rows.append(("end (latch) speed <=", f"{self.max_end_speed:g} rad/s"))
        if self.max_input_torque is not None:
            rows.append(("ECD input torque <=", u.text(self.max_input_torque, "torque")))
        if self.min_torque_margin is not None:
            rows.append(("torque margin >=", f"{self.min_torque_margin:g}"))
        rows.append(("no stall", "required" if self.no_stall else "not required"))
        return rows
