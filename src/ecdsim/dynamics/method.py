"""The ``dynamic`` deployment method: the registry entry and its solution type.

:class:`DynamicMethod` satisfies the :class:`~ecdsim.solvers.Solver` protocol. It needs a
:class:`~ecdsim.dynamics.problem.DynamicProblem` (a quasi-static problem extended with
inertia and the other dynamic parameters): :func:`ecdsim.deployment.predict` builds one
when it is given ``dynamics=``. Its solution, :class:`DynamicSolution`, is a
:class:`~ecdsim.solvers.DeploymentSolution` (same fields, same meaning, so reports and
plots treat every method alike) that also carries the full :class:`DynamicResult`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import ArrayLike, BoolArray, FloatArray, any_true, broadcast
from ecdsim.dynamics.damping import KlossEddy
from ecdsim.dynamics.problem import DynamicProblem
from ecdsim.dynamics.result import STATUSES, DynamicResult
from ecdsim.dynamics.solver import solve_dynamic
from ecdsim.physics import rolloff
from ecdsim.solvers.base import DeploymentSolution, QuasiStaticProblem, Trajectory


@dataclass(frozen=True, kw_only=True)
class DynamicSolution(DeploymentSolution):
    """The dynamic method's answer: the common fields plus the full result.

    Common fields: ``deployment_time`` is the first arrival at the end of travel (inf if
    never), ``start_speed`` the speed at release, ``end_speed`` the arrival speed (0 if
    never), ``stalled`` True where the mechanism stops for good short of the end of
    travel, ``stall_angle`` where.

    Attributes
    ----------
    end_kinetic_energy : kinetic energy at arrival [J]
    max_damper_temperature : [degC]
    stuck : came to rest for good (also after arriving, e.g. after a rebound)
    stuck_angle : where [rad]; NaN if not stuck
    stuck_time : when [s]; inf for an asymptotic approach; NaN if not stuck
    energy_balance_error : relative energy imbalance [-]
    result : the full :class:`DynamicResult` (events, energy terms, time series)
    problem : the problem solved (to recompute time series that were not recorded)
    notes : noteworthy outcomes, (code, message, flat case index), for warnings
    """

    end_kinetic_energy: FloatArray
    max_damper_temperature: FloatArray
    stuck: BoolArray
    stuck_angle: FloatArray
    stuck_time: FloatArray
    energy_balance_error: FloatArray
    result: DynamicResult
    problem: DynamicProblem
    notes: tuple[tuple[str, str, int], ...] = ()

    def trajectory(self, times: ArrayLike) -> Trajectory:
        """Angle and speed at shared times [s]; shape (n_times, *batch_shape).

        A large nonlinear batch is solved without recording its segments (memory); they
        are then recomputed here, once, with recording.
        """
        t = np.asarray(times, dtype=float).reshape(-1)
        result = self.result
        if result.trajectory is None:
            result = solve_dynamic(self.problem, record=True)
        series = result.sample(t)
        return Trajectory(method=self.method, time=t, angle=series.angle, speed=series.speed)

    def case_fields(self, index: int) -> dict[str, Any]:
        """The dynamic-only JSON fields of one case (flat index)."""
        summary = self.result.case_summary(index)
        keys = (
            "end_kinetic_energy_J",
            "max_damper_temperature_C",
            "stuck",
            "stuck_angle_rad",
            "stuck_time_s",
            "energy_balance_error",
            "status",
            "final_angle_rad",
            "final_time_s",
            "engagement_time_s",
            "rebound_speed_rad_s",
            "impacts",
            "energy_J",
        )
        fields = {key: summary[key] for key in keys}
        if "final_housing_temperature_C" in summary:  # two-node heating
            fields["final_housing_temperature_C"] = summary["final_housing_temperature_C"]
        for key in ("max_mesh_torque_Nm", "latch_mesh_torque_Nm"):  # compliant backlash only
            if key in summary:
                fields[key] = summary[key]
        return fields

    def time_series_csv(self) -> str:
        """The time series, one block per case (:meth:`DynamicResult.timeseries_csv`)."""
        return self.result.timeseries_csv()

    def findings(self) -> list[tuple[str, str, int]]:
        """Noteworthy outcomes as (code, message, flat case index)."""
        return list(self.notes)


# Nonlinear batches larger than this are solved without recording their time series.
RECORD_LIMIT = 2000


@dataclass(frozen=True)
class DynamicMethod:
    """Full deployment dynamics: inertia, stick-slip, lost motion, end stop, roll-off, heat."""

    name: str = "dynamic"
    label: str = "dynamic (inertia, stiction, end stop)"
    needs_dynamics: bool = True

    def solve(self, problem: QuasiStaticProblem) -> DynamicSolution:
        """Solve every case; ``problem`` must be a :class:`DynamicProblem`."""
        dynamic = _require_dynamic(problem)
        size = math.prod(dynamic.batch_shape)
        # Closed-form records are small; integrated ones hold every step of every case.
        record = (
            not (dynamic.nonlinear or dynamic.stribeck or dynamic.compliant) or size <= RECORD_LIMIT
        )
        return solution_from_result(self.name, dynamic, solve_dynamic(dynamic, record=record))

    def trajectory(self, problem: QuasiStaticProblem, times: ArrayLike) -> Trajectory:
        """Angle and speed at the given times [s] for every case of the batch."""
        return self.solve(problem).trajectory(times)


def _require_dynamic(problem: QuasiStaticProblem) -> DynamicProblem:
    if not isinstance(problem, DynamicProblem):
        raise ValueError(
            "the dynamic method needs inertia and the other dynamic parameters: pass "
            "dynamics=DynamicParameters(...) to ecdsim.deployment.predict, or build the "
            "problem with ecdsim.dynamics.dynamic_problem"
        )
    return problem


def solution_from_result(
    name: str, problem: DynamicProblem, result: DynamicResult
) -> DynamicSolution:
    """Wrap a :class:`DynamicResult` as the common :class:`DeploymentSolution` fields."""
    shape = result.batch_shape
    arrived = result.arrived
    stalled = np.asarray(result.stuck & ~arrived)
    error = result.energy_balance_error  # computed once: the findings read it too
    solution = object.__new__(DynamicSolution)
    # DynamicSolution(**these) without the frozen dataclass's __init__ (a field at a time
    # through object.__setattr__, some 3 us of a single deployment; issue 13): a frozen
    # dataclass without slots keeps its fields in the instance __dict__, and every field
    # is given, ``solved`` as DeploymentSolution.__post_init__ fills it in (every case
    # solved). tests/test_fast_paths.py fails when a field is added and not set here.
    vars(solution).update(
        method=name,
        deployment_time=result.deployment_time,
        start_speed=broadcast(problem.initial_speed, shape).astype(float),
        end_speed=result.arrival_speed,
        max_speed=result.max_speed,
        stalled=stalled,
        stall_angle=np.where(stalled, result.stuck_angle, np.nan),
        solved=np.ones(stalled.shape, dtype=bool),
        end_kinetic_energy=result.arrival_kinetic_energy,
        max_damper_temperature=result.max_damper_temperature,
        stuck=result.stuck,
        stuck_angle=result.stuck_angle,
        stuck_time=result.stuck_time,
        energy_balance_error=error,
        result=result,
        problem=problem,
        notes=tuple(_findings(problem, result, error)),
    )
    return solution


# No case flagged: the usual answer, without NumPy's search for the indices.
_NONE = np.empty(0, dtype=np.intp)
_STOP_TIME = STATUSES.index("stop_time")
_CUT_SHORT = {code: STATUSES.index(code) for code in ("event_limit", "horizon")}
# The statuses reported as findings are the last of STATUSES (tests/test_fast_paths.py
# checks it): one comparison tells whether any case has one.
REPORTED_FROM = min(_STOP_TIME, *_CUT_SHORT.values())


def _findings(
    problem: DynamicProblem, result: DynamicResult, energy_error: FloatArray
) -> list[tuple[str, str, int]]:
    """Outcomes a user must hear about, as (code, message, flat case index)."""
    if result.status.size == 1:
        return _one_case_findings(problem, result, energy_error)
    return _batch_findings(problem, result, energy_error)


def _batch_findings(
    problem: DynamicProblem, result: DynamicResult, energy_error: FloatArray
) -> list[tuple[str, str, int]]:
    """:func:`_findings` of any batch (the general path)."""
    out: list[tuple[str, str, int]] = []
    status = result.status.ravel()
    if any_true(status >= REPORTED_FROM):
        out.extend(_status_findings(result, status))
    error = energy_error.ravel()
    unbalanced = np.abs(error) > 1e-6
    if any_true(unbalanced):
        for i in np.flatnonzero(unbalanced):
            out.append(("energy_balance", _energy_message(error[i]), int(i)))
    eddy = problem.eddy
    if isinstance(eddy, KlossEddy):
        shape = result.batch_shape
        n = broadcast(problem.gear_ratio, shape)
        ambient = broadcast(problem.ambient_temperature, shape)
        peak = eddy.peak_speed(ambient)
        slope = rolloff.kloss_speed_derivative(0.0, eddy.peak_torque, peak)
        kloss_becd = (n * n * (slope + problem.gearbox_damping_rate)).ravel()
        eq1_becd = broadcast(problem.damping_rate, shape).ravel()
        mismatch = kloss_becd / eq1_becd - 1.0
        # A batch can hold thousands of these findings: the values are formatted as Python
        # floats (NumPy scalars format several times slower; the same text).
        mismatched = np.abs(mismatch) > 0.01
        off = np.flatnonzero(mismatched) if any_true(mismatched) else _NONE
        for case, becd, eq1, ratio in zip(
            off.tolist(),
            kloss_becd[off].tolist(),
            eq1_becd[off].tolist(),
            (100 * mismatch[off]).tolist(),
            strict=True,
        ):
            out.append(("rolloff_temperature_law", _rolloff_law_message(becd, eq1, ratio), case))
        shaft = (result.max_speed * n).ravel()
        peaks = broadcast(peak, shape).ravel()
        past = shaft > peaks
        beyond = np.flatnonzero(past) if any_true(past) else _NONE
        for case, reached, limit in zip(
            beyond.tolist(), shaft[beyond].tolist(), peaks[beyond].tolist(), strict=True
        ):
            out.append(("rolloff_beyond_peak", _beyond_peak_message(reached, limit), case))
    return out


def _status_findings(result: DynamicResult, status: NDArray[np.int8]) -> list[tuple[str, str, int]]:
    """The cases that ended at the stop time, then those cut short, each in case order."""
    out: list[tuple[str, str, int]] = []
    flagged = np.flatnonzero(status >= REPORTED_FROM)
    cases = list(zip(flagged.tolist(), status[flagged].tolist(), strict=True))
    final_time = result.final_time.ravel()
    final_angle = result.final_angle.ravel()
    for i, status_of_i in cases:
        if status_of_i == _STOP_TIME:
            out.append(("stop_time", _stop_time_message(final_time[i], final_angle[i]), i))
    for code, value in _CUT_SHORT.items():
        for i, status_of_i in cases:
            if status_of_i == value:
                out.append((code, _cut_short_message(code, final_time[i]), i))
    return out


def _stop_time_message(time: float, angle: float) -> str:
    return (
        f"the end of travel was not reached by the stop time ({time:.4g} s; angle {angle:.4g} rad)"
    )


def _cut_short_message(code: str, time: float) -> str:
    return (
        f"the dynamic run was cut short ({code.replace('_', ' ')}) at {time:.4g} s; its "
        "result is incomplete"
    )


def _energy_message(error: float) -> str:
    return f"the energy balance closes only to {error:.2g} (relative); tighten rtol"


def _rolloff_law_message(becd: float, eq1: float, ratio: float) -> str:
    return (
        f"at low speed the roll-off law gives BECD {becd:.4g} N*m*s/rad, "
        f"{ratio:+.1f} % from Eq. 1's {eq1:.4g}: with roll-off "
        "the damper's temperature law is resistivity_coefficient's, not Eq. 1's"
    )


def _beyond_peak_message(reached: float, limit: float) -> str:
    return (
        f"the damper reached {reached:.4g} rad/s, beyond its peak-torque speed "
        f"{limit:.4g} rad/s, where its torque falls with speed"
    )


def _one_case_findings(
    problem: DynamicProblem, result: DynamicResult, energy_error: FloatArray
) -> list[tuple[str, str, int]]:
    """:func:`_findings` of a result holding one case, in Python floats.

    The same findings in the same order with the same text (NumPy scalars format as
    Python floats) and the same arithmetic (the elementwise +, -, *, / of IEEE doubles),
    without the general path's broadcasts, flattenings and index searches, which cost a
    single deployment some 10 us (issue 13, single cases). The physics functions are
    called with floats; every per-case array of a one-case problem holds one number.
    """
    out: list[tuple[str, str, int]] = []
    status = result.status.item()
    if status >= REPORTED_FROM:
        time = result.final_time.item()
        if status == _STOP_TIME:
            out.append(("stop_time", _stop_time_message(time, result.final_angle.item()), 0))
        else:  # the statuses from REPORTED_FROM on are stop_time and the cut-short ones
            code = STATUSES[status]
            out.append((code, _cut_short_message(code, time), 0))
    error = energy_error.item()
    if abs(error) > 1e-6:
        out.append(("energy_balance", _energy_message(error), 0))
    eddy = problem.eddy
    if isinstance(eddy, KlossEddy):
        n = problem.gear_ratio.item()
        kloss = _kloss_low_speed(eddy, problem.ambient_temperature.item())
        if kloss is None:
            return _batch_findings(problem, result, energy_error)
        peak, slope = kloss
        becd = n * n * (slope + problem.gearbox_damping_rate.item())
        eq1 = problem.damping_rate.item()
        shaft = result.max_speed.item() * n
        if eq1 == 0.0 or not math.isfinite(becd / eq1 + shaft):
            # NumPy's answer and warnings (a division by 0, an overflow): the general path.
            return _batch_findings(problem, result, energy_error)
        mismatch = becd / eq1 - 1.0
        if abs(mismatch) > 0.01:
            out.append(
                ("rolloff_temperature_law", _rolloff_law_message(becd, eq1, 100 * mismatch), 0)
            )
        if shaft > peak:
            out.append(("rolloff_beyond_peak", _beyond_peak_message(shaft, peak), 0))
    return out


def _kloss_low_speed(eddy: KlossEddy, temperature: float) -> tuple[float, float] | None:
    """The peak speed at ``temperature`` and the Kloss law's slope at zero speed, in floats.

    ``rolloff.peak_speed_at`` and ``rolloff.kloss_speed_derivative(0, T_peak, p)`` called
    on Python floats (the functions take floats as they take arrays: the same bits,
    without some ten NumPy calls on one number; issue 13, single cases). Each parameter of
    a one-case law holds one number. None, for the general path (NumPy's answer and
    warnings), where a value is not finite or ``p`` is 0.
    """
    t_peak, p_ref, alpha, t_ref = (
        value if type(value) is float else float(np.asarray(value, dtype=float).item())
        for value in (
            eddy.peak_torque,
            eddy.reference_peak_speed,
            eddy.resistivity_coefficient,
            eddy.reference_temperature,
        )
    )
    p = rolloff.peak_speed_at(temperature, p_ref, alpha, t_ref)
    if not (p != 0.0 and math.isfinite(p) and math.isfinite(p * p)):
        return None
    slope = rolloff.kloss_speed_derivative(0.0, t_peak, p)
    if not math.isfinite(slope):
        return None
    return float(p), float(slope)


DYNAMIC = DynamicMethod()
