"""The kernel's outputs as a :class:`~ecdsim.dynamics.result.DynamicResult`.

Summaries per case (the kernel's output rows, reshaped to the batch), the energy
account, the event log sorted by case, and what time series need: the recorded spans
and points, the cases' constants and spring tables.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import FloatArray, as_float
from ecdsim.dynamics.kernel import effects as registry
from ecdsim.dynamics.kernel import layout as L
from ecdsim.dynamics.problem import DynamicProblem
from ecdsim.dynamics.result import DynamicResult, EnergyBalance, EventLog, TrajectoryData


@dataclass(frozen=True)
class Packed:
    """A problem's cases as the kernel reads them (flat, one row per case).

    Attributes
    ----------
    table : the cases' constants, (n, ``layout.COLUMNS``)
    angles, torques, resistance : the spring's breakpoints, net torque (spring less the
        resistive table) and resistive torque there, (n, points)
    compliant : per case, a compliant mesh (two coordinates)
    nodes : heating nodes (0, 1 or 2), the same for every case
    settings : the run's settings (``layout.STOP`` ..)
    """

    table: FloatArray
    angles: FloatArray
    torques: FloatArray
    resistance: FloatArray
    compliant: NDArray[np.bool_]
    nodes: int
    settings: FloatArray


@dataclass
class Run:
    """The kernel's outputs for a group of cases."""

    cases: NDArray[np.intp]
    out: FloatArray
    events: FloatArray
    spans: FloatArray
    points: FloatArray


def _gather(runs: list[Run], n: int) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """The groups' outputs in case order: summaries, events, spans, points."""
    if len(runs) == 1:
        run = runs[0]
        return run.out, run.events, run.spans, run.points
    out = np.zeros((n, L.OUT_FIELDS))
    events: list[FloatArray] = []
    spans: list[FloatArray] = []
    points: list[FloatArray] = []
    offset = 0
    for run in runs:
        out[run.cases] = run.out
        events.append(run.events)
        if run.spans.size:
            shifted = run.spans.copy()
            steps = shifted[:, L.SPAN_KIND] == L.SPAN_STEPS
            shifted[steps, L.SPAN_FIRST] += offset
            spans.append(shifted)
        offset += run.points.shape[0]
        points.append(run.points)

    def joined(parts: list[FloatArray], width: int) -> FloatArray:
        return np.concatenate(parts) if parts else np.zeros((0, width))

    return (
        out,
        joined(events, L.EVENT_FIELDS),
        joined(spans, L.SPAN_FIELDS),
        joined(points, L.POINT_FIELDS),
    )


def _event_log(events: FloatArray, single: bool) -> EventLog:
    """The events sorted by case, in the order logged within each case."""
    if not single and events.shape[0]:
        order = np.argsort(events[:, 0], kind="stable")
        events = events[order]
    return EventLog(
        events[:, 0].astype(np.intp),
        np.ascontiguousarray(events[:, 1]),
        events[:, 2].astype(np.int8),
        np.ascontiguousarray(events[:, 3]),
        np.ascontiguousarray(events[:, 4]),
    )


def _energy(
    problem: DynamicProblem, packed: Packed, rows: FloatArray, shape: tuple[int, ...]
) -> EnergyBalance:
    """The energy account per case (``rows``: the summaries by field, batch-shaped)."""
    table = packed.table
    end = rows[L.OUT_ANGLE].reshape(-1)
    stored = registry.stored_work(table, table[:, L.EFFECTS], table[:, L.PHI0], end)
    compliant = bool(np.any(packed.compliant))
    return EnergyBalance(
        spring_work=rows[L.OUT_SPRING_WORK],
        initial_kinetic_energy=rows[L.OUT_INITIAL_KE],
        damper_dissipation=rows[L.OUT_DAMPER_WORK],
        friction_dissipation=rows[L.OUT_FRICTION_WORK],
        engagement_loss=rows[L.OUT_ENGAGEMENT_LOSS],
        impact_loss=rows[L.OUT_IMPACT_LOSS],
        final_kinetic_energy=rows[L.OUT_FINAL_KE],
        gear_loss=rows[L.OUT_GEAR_LOSS],
        **{line: np.asarray(work).reshape(shape) for line, work in stored.items()},
        mesh_dissipation=rows[L.OUT_MESH_WORK] if compliant else None,
        elastic_energy=rows[L.OUT_ELASTIC] if compliant else None,
        resistive_work=rows[L.OUT_RESISTIVE_WORK] if problem.resistance is not None else None,
    )


_INITIAL = (L.PHI0, L.W0, L.AMB)
_FINAL = (L.OUT_ANGLE, L.OUT_SPEED, L.OUT_TEMPERATURE, L.OUT_ENGAGED, L.OUT_HOLD_FROM)


def _trajectory(
    packed: Packed, out: FloatArray, spans: FloatArray, points: FloatArray, single: bool
) -> TrajectoryData:
    """What :meth:`DynamicResult.sample` needs: the spans (sorted by case and time: one
    run's are already) and points, the cases' initial and final states and constants."""
    n = out.shape[0]
    table = packed.table
    if not single and spans.size:
        spans = spans[np.lexsort((spans[:, L.SPAN_T0], spans[:, L.SPAN_CASE]))]
    start = np.searchsorted(spans[:, L.SPAN_CASE], np.arange(n + 1), side="left")
    time = out[:, L.OUT_TIME]
    display = np.where(np.isfinite(time), time, out[:, L.OUT_DISPLAY_END])
    initial = np.zeros((n, 5))
    initial[:, :3] = table[:, _INITIAL]
    initial[:, 3] = np.where(packed.compliant, 1.0, table[:, L.GAP] <= 0.0)
    return TrajectoryData(
        spans=np.ascontiguousarray(spans),
        points=np.ascontiguousarray(points),
        span_start=start.astype(float),
        initial=initial,
        final=out[:, _FINAL],
        display_end=display,
        table=table,
        angles=packed.angles,
        torques=packed.torques,
    )


def result_of(
    problem: DynamicProblem, packed: Packed, runs: list[Run], record: bool
) -> DynamicResult:
    """The :class:`DynamicResult` of the kernel's runs of ``problem``."""
    shape = problem.batch_shape
    n = math.prod(shape)
    out, events, spans, points = _gather(runs, n)
    compliant = bool(np.any(packed.compliant))

    rows = np.ascontiguousarray(out.T).reshape((L.OUT_FIELDS, *shape))

    def shaped(column: int) -> FloatArray:
        return as_float(rows[column])

    energy = _energy(problem, packed, rows, shape)
    status: NDArray[np.int8] = rows[L.OUT_STATUS].astype(np.int8)
    fields: dict[str, Any] = {
        "batch_shape": shape,
        "temperature": packed.table[:, L.AMB].reshape(shape),
        "deployment_time": shaped(L.OUT_ARRIVAL_TIME),
        "arrival_speed": shaped(L.OUT_ARRIVAL_SPEED),
        "arrival_kinetic_energy": shaped(L.OUT_ARRIVAL_KE),
        "final_time": shaped(L.OUT_TIME),
        "final_angle": shaped(L.OUT_ANGLE),
        "final_speed": shaped(L.OUT_SPEED),
        "final_temperature": shaped(L.OUT_TEMPERATURE),
        "stuck": rows[L.OUT_STUCK] != 0.0,
        "stuck_angle": shaped(L.OUT_STUCK_ANGLE),
        "stuck_time": shaped(L.OUT_STUCK_TIME),
        "max_speed": shaped(L.OUT_MAX_SPEED),
        "max_damper_temperature": shaped(L.OUT_MAX_TEMPERATURE),
        "engagement_time": shaped(L.OUT_ENGAGEMENT_TIME),
        "rebound_speed": shaped(L.OUT_REBOUND_SPEED),
        "impacts": rows[L.OUT_IMPACTS].astype(np.int64),
        "status": status,
        "energy": energy,
        "events": _event_log(events, len(runs) == 1),
        "trajectory": _trajectory(packed, out, spans, points, len(runs) == 1) if record else None,
        "final_housing_temperature": shaped(L.OUT_HOUSING) if packed.nodes == 2 else None,
        "max_mesh_torque": shaped(L.OUT_MAX_MESH_TORQUE) if compliant else None,
        "latch_mesh_torque": shaped(L.OUT_LATCH_MESH_TORQUE) if compliant else None,
    }
    return DynamicResult(**fields)
