"""Repeated deployments: a life test's N deployments with cool-down and stow between them.

The paper's mechanism was deployed 500 times in its life test. Each deployment heats the
damper (the eddy-current energy, :mod:`ecdsim.physics.thermal`); between deployments the
damper cools towards the environment, and the next deployment starts warmer than the
first if the interval is short against the thermal time constants. The damping falls
with temperature (Eq. 1), so the deployment time drifts.

One cycle: deployment k (the dynamic method, from release to the end of its run, with
the rotor and housing temperatures carried over), then the cool-down (the deployed
mechanism at rest), then the stow (re-arming the spring), then release k + 1. The two
intervals generate no heat in the damper: both are relaxation of the thermal network
towards the environment, in closed form (the matrix exponential of the two-node network,
:func:`ecdsim.physics.thermal.two_node_relaxation`; ``exp(-t / (R C))`` for one node),
no integration. Stowing back-drives the damper if it stays engaged; at a constant stow
speed ``travel / t_stow`` that adds about ``BECD travel^2 / t_stow`` of heat (docs/dynamics.md),
which is not modelled: the stow is taken as slow, or with the damper disengaged.

The deployments are solved by a caller-supplied function (``predict`` in the system
layer, or :func:`ecdsim.dynamics.solver.solve_dynamic` on a problem), so this module
stays in the dynamics layer. Every analysis temperature runs as one batch per deployment.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ecdsim._types import ArrayLike, BoolArray, FloatArray
from ecdsim.dynamics.params import DynamicParameters, Thermal
from ecdsim.dynamics.result import DynamicResult
from ecdsim.physics import thermal as heat

Solve = Callable[[DynamicParameters], DynamicResult]

# Start temperatures within this of the previous deployment's count as periodic [K]:
# a thousandth of a kelvin changes Eq. 1's damping by 4e-6 of itself.
PERIODIC_TOLERANCE = 1e-3


@dataclass(frozen=True)
class Cycle:
    """The life-test schedule.

    Attributes
    ----------
    count : N, the number of deployments, >= 1
    cool_down : time from the end of one deployment to the start of its stow [s], >= 0
    stow_time : time to re-arm the spring, up to the next release [s], >= 0
    """

    count: int
    cool_down: float
    stow_time: float = 0.0

    def __post_init__(self) -> None:
        if self.count < 1:
            raise ValueError(f"count must be >= 1, got {self.count}")
        for name in ("cool_down", "stow_time"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name} must be finite and >= 0 s, got {value}")

    @property
    def interval(self) -> float:
        """Time between the end of a deployment and the next release [s]."""
        return self.cool_down + self.stow_time


@dataclass(frozen=True)
class SequenceResult:
    """Per deployment (rows, 1 to N) and analysis temperature (columns).

    Attributes
    ----------
    temperatures : the deployment (environment) temperatures T [degC], shape (m,)
    cycle : the schedule
    start_rotor_temperature : damper (rotor) temperature at release [degC], (N, m)
    start_housing_temperature : housing temperature at release [degC] (two nodes), or None
    deployment_time : first arrival at the end of travel [s] (inf if never), (N, m)
    peak_rotor_temperature : highest damper temperature in the deployment [degC]
    end_rotor_temperature : damper temperature at the end of the run [degC]
    end_housing_temperature : housing temperature at the end of the run [degC], or None
    damper_dissipation : energy dissipated by the damping in the deployment [J]
    periodic_after : per temperature, the first deployment (1-based) from which every
        start temperature is within ``tolerance`` of the one before; None if not reached
    tolerance : the periodic-state tolerance [K]
    """

    temperatures: FloatArray
    cycle: Cycle
    start_rotor_temperature: FloatArray
    start_housing_temperature: FloatArray | None
    deployment_time: FloatArray
    peak_rotor_temperature: FloatArray
    end_rotor_temperature: FloatArray
    end_housing_temperature: FloatArray | None
    damper_dissipation: FloatArray
    periodic_after: list[int | None]
    tolerance: float

    @property
    def stalled(self) -> BoolArray:
        """True where a deployment never reaches the end of travel (its time is inf), (N, m)."""
        return ~np.isfinite(self.deployment_time)

    def drift(self) -> dict[str, FloatArray]:
        """Deployment N minus deployment 1, per temperature: time [s], peak and start [K].

        The time's drift is NaN where deployment 1 or N stalls (no time to compare; see
        :attr:`stalled`), computed without inf - inf.
        """
        first, last = self.deployment_time[0], self.deployment_time[-1]
        with np.errstate(invalid="ignore"):  # inf - inf where both stall: NaN below anyway
            change = last - first
        return {
            "deployment_time_s": np.where(np.isfinite(first) & np.isfinite(last), change, math.nan),
            "peak_rotor_temperature_K": self.peak_rotor_temperature[-1]
            - self.peak_rotor_temperature[0],
            "start_rotor_temperature_K": self.start_rotor_temperature[-1]
            - self.start_rotor_temperature[0],
        }

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready document (SI units, temperatures in degC; inf as null)."""

        def column(values: FloatArray | None, j: int) -> list[float | None] | None:
            if values is None:
                return None
            return [float(v) if math.isfinite(v) else None for v in values[:, j]]

        drift = self.drift()
        stalled = self.stalled
        cases = []
        for j, temp in enumerate(self.temperatures):
            cases.append(
                {
                    "temperature_C": float(temp),
                    "periodic_after": self.periodic_after[j],
                    # Deployments that never reach the end of travel: their time and the
                    # time's drift (if deployment 1 or N is among them) are null.
                    "stalled_deployments": int(np.count_nonzero(stalled[:, j])),
                    "drift": {
                        key: float(v[j]) if math.isfinite(v[j]) else None
                        for key, v in drift.items()
                    },
                    "deployments": {
                        "start_rotor_temperature_C": column(self.start_rotor_temperature, j),
                        "start_housing_temperature_C": column(self.start_housing_temperature, j),
                        "deployment_time_s": column(self.deployment_time, j),
                        "stalled": [bool(v) for v in stalled[:, j]],
                        "peak_rotor_temperature_C": column(self.peak_rotor_temperature, j),
                        "end_rotor_temperature_C": column(self.end_rotor_temperature, j),
                        "end_housing_temperature_C": column(self.end_housing_temperature, j),
                        "damper_dissipation_J": column(self.damper_dissipation, j),
                    },
                }
            )
        return {
            "count": self.cycle.count,
            "cool_down_s": self.cycle.cool_down,
            "stow_time_s": self.cycle.stow_time,
            "periodic_tolerance_K": self.tolerance,
            "cases": cases,
        }


def relax(
    thermal: Thermal, rotor_rise: FloatArray, housing_rise: FloatArray, time: float
) -> tuple[FloatArray, FloatArray]:
    """Rotor and housing rises after ``time`` without heat input (closed form).

    Two nodes: :func:`ecdsim.physics.thermal.two_node_relaxation`; one node (the rotor to
    the environment through R): ``theta exp(-t / (R C))``, unchanged when adiabatic.
    Rounding below zero is clipped (the exact relaxation of rises >= 0 stays >= 0: the
    network's matrix has non-negative off-diagonal entries).
    """
    if thermal.housing_heat_capacity is not None:
        rotor, housing = heat.two_node_relaxation(
            rotor_rise,
            housing_rise,
            time,
            thermal.heat_capacity,
            thermal.housing_heat_capacity,
            thermal.thermal_resistance,
            thermal.housing_thermal_resistance,
        )
        return np.maximum(rotor, 0.0), np.maximum(housing, 0.0)
    rate = 1.0 / (np.asarray(thermal.thermal_resistance, float) * thermal.heat_capacity)
    return np.maximum(rotor_rise * np.exp(-rate * time), 0.0), np.zeros_like(housing_rise)


def run_sequence(
    solve: Solve,
    params: DynamicParameters,
    temperatures: ArrayLike,
    cycle: Cycle,
    tolerance: float = PERIODIC_TOLERANCE,
) -> SequenceResult:
    """N deployments at each temperature, each starting from the last one's heat.

    ``solve(params)`` runs one deployment of every temperature (a batch over
    ``temperatures``) with ``params.thermal``'s start rises. Without ``params.thermal``
    nothing carries over: one deployment is solved and repeated N times. When a
    deployment starts from exactly the state of the one before, the rest repeat it.
    """
    temps = np.atleast_1d(np.asarray(temperatures, dtype=float))
    n, m = cycle.count, temps.size
    rows: dict[str, FloatArray] = {
        name: np.empty((n, m))
        for name in ("start_r", "start_h", "time", "peak", "end_r", "end_h", "work")
    }
    base = params.thermal
    rotor = np.zeros(m)
    housing = np.zeros(m)
    two_node = base is not None and base.housing_heat_capacity is not None
    k = 0
    while k < n:
        run = params
        if base is not None:
            run = replace(
                params,
                thermal=replace(
                    base,
                    initial_rotor_rise=rotor.copy(),
                    initial_housing_rise=housing.copy() if two_node else 0.0,
                ),
            )
        result = solve(run)
        rows["start_r"][k] = temps + rotor
        rows["start_h"][k] = temps + housing
        rows["time"][k] = np.ravel(result.deployment_time)
        rows["peak"][k] = np.ravel(result.max_damper_temperature)
        rows["end_r"][k] = np.ravel(result.final_temperature)
        end_h = result.final_housing_temperature
        rows["end_h"][k] = temps if end_h is None else np.ravel(end_h)
        rows["work"][k] = np.ravel(result.energy.damper_dissipation)
        k += 1
        if base is None:
            break
        next_rotor, next_housing = relax(
            base,
            np.maximum(rows["end_r"][k - 1] - temps, 0.0),
            np.maximum(rows["end_h"][k - 1] - temps, 0.0),
            cycle.interval,
        )
        if np.array_equal(next_rotor, rotor) and np.array_equal(next_housing, housing):
            break  # the same start state: every later deployment is this one again
        rotor, housing = next_rotor, next_housing
    for values in rows.values():
        values[k:] = values[k - 1]
    return SequenceResult(
        temperatures=temps,
        cycle=cycle,
        start_rotor_temperature=rows["start_r"],
        start_housing_temperature=rows["start_h"] if two_node else None,
        deployment_time=rows["time"],
        peak_rotor_temperature=rows["peak"],
        end_rotor_temperature=rows["end_r"],
        end_housing_temperature=rows["end_h"] if two_node else None,
        damper_dissipation=rows["work"],
        periodic_after=_periodic_after(rows["start_r"], rows["start_h"], tolerance),
        tolerance=tolerance,
    )


def _periodic_after(rotor: FloatArray, housing: FloatArray, tolerance: float) -> list[int | None]:
    """Per column, the first row (1-based) from which every step changes by <= tolerance."""
    n = rotor.shape[0]
    step = np.zeros_like(rotor)
    if n > 1:
        step[1:] = np.maximum(np.abs(np.diff(rotor, axis=0)), np.abs(np.diff(housing, axis=0)))
    out: list[int | None] = []
    for j in range(rotor.shape[1]):
        moving = np.flatnonzero(step[:, j] > tolerance)
        first = 1 if moving.size == 0 else int(moving[-1]) + 2  # the row after the last move
        out.append(first if first <= n else None)
    return out


def stow_heat(damping_rate: ArrayLike, travel: ArrayLike, stow_time: float) -> FloatArray:
    """Heat a stow would put into the damper if it back-drove it [J] (not modelled).

    Re-arming at the constant speed ``w = travel / t_stow`` against the eddy damping
    ``B`` (BD_T N^2 at the input shaft, Eq. 1 and 3) dissipates ``P = B w^2`` for
    ``t_stow``: ``E = B travel^2 / t_stow`` (inf for an instant stow).

    >>> float(stow_heat(20.0, 1.5, 45.0))
    1.0
    """
    b = np.asarray(damping_rate, dtype=float)
    theta = np.asarray(travel, dtype=float)
    if stow_time <= 0.0:
        return np.full(np.broadcast(b, theta).shape, math.inf)
    return np.asarray(b * theta * theta / stow_time)
