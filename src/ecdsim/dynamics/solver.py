"""Solve a dynamic problem on the kernel: pack its cases, run them, build the result.

:func:`solve_dynamic` is the dynamic method's one path: every case of every problem (a
single deployment, a Monte Carlo batch, a compliant mesh) runs through the same compiled
event loop (:mod:`ecdsim.dynamics.kernel`), one case at a time; a large batch is split
over two threads (the compiled kernel releases the GIL). Cases of different state layouts
(a rigid or a compliant mesh) are run as separate groups.
"""

from __future__ import annotations

import math
import os
import threading
from collections.abc import Callable
from dataclasses import fields
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import FloatArray
from ecdsim.dynamics.assemble import Packed, Run, result_of
from ecdsim.dynamics.damping import KlossEddy, LinearEddy, PowerLawDamper
from ecdsim.dynamics.kernel import effects as registry
from ecdsim.dynamics.kernel import layout as L
from ecdsim.dynamics.kernel.build import Backend, backend
from ecdsim.dynamics.kernel.record import COUNTS, OVERFLOW, START
from ecdsim.dynamics.problem import DynamicProblem
from ecdsim.dynamics.result import DynamicResult
from ecdsim.physics import eddy as eddy_laws
from ecdsim.physics.thermal import factor_log_from_rise

# A batch of at least PARALLEL_MIN cases runs on THREADS threads (the compiled kernel
# releases the GIL), each over a contiguous part; every case depends on its own row only,
# so the results are the same for any split.
THREADS = max(1, min(2, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1))
PARALLEL_MIN = 256


# Columns of the case table read straight off the problem's per-case fields.
_FIELDS = (
    (L.JL, "load_inertia"),
    (L.JD, "damper_inertia"),
    (L.FS, "system_friction"),
    (L.FE, "ecd_friction"),
    (L.WST, "stribeck_speed"),
    (L.REST, "restitution"),
    (L.GAP, "lost_motion"),
    (L.PHI0, "initial_angle"),
    (L.W0, "initial_speed"),
    (L.AMB, "ambient_temperature"),
    (L.RATIO, "gear_ratio"),
    (L.BG, "gearbox_damping_rate"),
    (L.BLIN, "damping_rate"),
    (L.ETAF, "forward_efficiency"),
    (L.ETAB, "backward_efficiency"),
    (L.MC, "gear_stiffness"),
    (L.MD, "gear_mesh_damping"),
    (L.HC, "heat_capacity"),
    (L.HR, "thermal_resistance"),
    (L.HCH, "housing_heat_capacity"),
    (L.HRHE, "housing_thermal_resistance"),
)
Column = float | FloatArray


def _law(problem: DynamicProblem) -> dict[int, Column]:
    """The eddy law's code and parameters, its temperature factor at ambient (Eq. 1's
    bracket, or the Kloss law's resistivity factor), reference and zero temperature."""
    law = problem.eddy
    columns: dict[int, Column] = {}
    if isinstance(law, LinearEddy):
        columns[L.LAW] = float(eddy_laws.LINEAR)
        columns[L.LA] = np.asarray(law.damping_rate, float)
        columns[L.LB] = 0.0
    elif isinstance(law, KlossEddy):
        columns[L.LAW] = float(eddy_laws.KLOSS)
        columns[L.LA] = np.asarray(law.peak_torque, float)
        columns[L.LB] = np.asarray(law.reference_peak_speed, float)
    elif isinstance(law, PowerLawDamper):
        if problem.thermal:
            # The fluid's c(T) and n(T) are packed at ambient: the law has no factor
            # for the kernel's heating state to act on (docs/dynamics.md).
            raise TypeError("the dynamic kernel does not model self-heating of a fluid damper")
        columns[L.LAW] = float(eddy_laws.POWER_LAW)
        columns[L.LA], columns[L.LB], columns[L.LC] = law.parameters
    else:
        raise TypeError(f"the dynamic kernel has no eddy law {law.name!r}")
    coefficient = np.asarray(law.coefficient, float)
    reference = np.asarray(law.reference_temperature, float)
    columns[L.COEF] = coefficient
    columns[L.TREF] = reference
    # The problem's domain checks keep f_a >= 0; the clip removes rounding at the zero.
    ambient = np.asarray(law.factor(problem.ambient_temperature), float)
    if coefficient.size == 1 and reference.size == 1 and ambient.size == 1:
        # One value each (one deployment): the same arithmetic on floats, without the
        # array calls (a few microseconds each, a tenth of a deployment's Python).
        c = float(coefficient.reshape(-1)[0])
        columns[L.FA] = max(float(ambient.reshape(-1)[0]), 0.0)
        columns[L.TZERO] = float(reference.reshape(-1)[0]) - 1.0 / c if c < 0.0 else math.inf
        return columns
    columns[L.FA] = np.maximum(ambient, 0.0)
    falling = coefficient < 0.0
    columns[L.TZERO] = np.where(
        falling, reference - 1.0 / np.where(falling, coefficient, -1.0), np.inf
    )
    return columns


def _derived(problem: DynamicProblem, law: dict[int, Column], nodes: int) -> dict[int, Column]:
    """The breakaway frictions, the travel and the heating's start states."""
    columns: dict[int, Column] = {
        L.FSB: problem.system_friction * problem.system_static_friction_factor,
        L.FEB: problem.ecd_friction * problem.static_friction_factor,
        L.TRAVEL: problem.angles[-1],
        L.NODES: float(nodes),
        L.S0: 0.0,
        L.H0: problem.initial_housing_rise if nodes == 2 else 0.0,
    }
    rise = np.asarray(problem.initial_rotor_rise, float)
    if nodes and np.any(rise != 0.0):
        with np.errstate(divide="ignore", invalid="ignore"):
            columns[L.S0] = np.asarray(factor_log_from_rise(rise, law[L.FA], law[L.COEF]))
    return columns


# Every field of DynamicProblem, each taken by the packer above (its columns, the law,
# the derived columns, the spring tables, the settings). A field not listed here is
# refused (tests/test_dynamics_kernel.py holds the list to the dataclass), so that a new
# input is never silently ignored by the kernel.
KNOWN_FIELDS = frozenset(
    {name for _, name in _FIELDS}
    | {
        "angles",
        "torques",
        "resistance",
        "friction",  # FECD_T + FS_T: the quasi-static methods' (the kernel takes both)
        "eddy",
        "static_friction_factor",
        "system_static_friction_factor",
        "initial_rotor_rise",
        "initial_housing_rise",
        "thermal",
        "two_node",
        "stop_time",
        "rtol",
        "integrator",
        "max_events",
        "effects",  # the registered effects' parameters (kernel/effects.py)
    }
    # and the registered parameters set as fields (gravity's: effects.problem_values)
    | {p.name for p in registry.PARAMETERS if p.config is None}
)


def _effects(problem: DynamicProblem, table: FloatArray) -> FloatArray:
    """Each case's effects (``layout.EFFECT_*`` bits): what each path of the kernel must
    model to take it (``layout.KERNEL_EFFECTS``, ``layout.CLOSED_FORM_EFFECTS``)."""
    if table.shape[0] == 1:  # one deployment: its numbers as floats (no array calls)
        return np.array([float(_case_effects(problem, table[0].tolist()))])
    effects = np.zeros(table.shape[0])
    for bit, present in _presence(problem, table.T):
        effects += np.where(present, float(bit), 0.0)
    return effects


def _case_effects(problem: DynamicProblem, row: list[float]) -> int:
    """:func:`_effects` of one case, from its row as floats (the same tests)."""
    return sum(bit for bit, found in _presence(problem, row) if found)


def _presence(problem: DynamicProblem, c: Any) -> list[tuple[int, Any]]:
    """Each effect's bit and whether it is present, from one case's row of floats or
    the table's columns (``table.T``): the same tests on either (``<`` for isfinite:
    the columns tested are never NaN; ``|`` for ``or``); the registered effects' from
    their declarations (:func:`ecdsim.dynamics.kernel.effects.presence`)."""
    inf = math.inf
    return [
        (L.EFFECT_ROLLOFF, c[L.LAW] == eddy_laws.KLOSS),
        (L.EFFECT_HEATING, c[L.NODES] > 0),
        (L.EFFECT_TWO_NODE, c[L.NODES] == 2),
        (L.EFFECT_STRIBECK, c[L.WST] < inf),
        (L.EFFECT_LOSSY, (c[L.ETAF] != 1.0) | (c[L.ETAB] != 1.0)),
        (L.EFFECT_LOST_MOTION, c[L.GAP] > 0.0),
        (L.EFFECT_COMPLIANT, c[L.MC] < inf),
        (L.EFFECT_RESISTANCE, problem.resistance is not None),
        (L.EFFECT_REBOUND, c[L.REST] > 0.0),
        (L.EFFECT_WARM_START, (c[L.S0] != 0.0) | (c[L.H0] != 0.0)),
        (L.EFFECT_STOP_TIME, math.isfinite(problem.stop_time)),
        (L.EFFECT_POWER_LAW, c[L.LAW] == eddy_laws.POWER_LAW),
        *registry.presence(c),
    ]


@cache
def _unknown_fields(kind: type, known: frozenset[str]) -> frozenset[str]:
    """The fields of a problem class not in ``known`` (worked out once per class)."""
    return frozenset({f.name for f in fields(kind)} - known)


def _check_known(problem: DynamicProblem, effects: FloatArray) -> None:
    """Refuse a problem with an input or an effect the kernel does not know."""
    kind: type = type(problem)
    unknown = _unknown_fields(kind, KNOWN_FIELDS)
    if problem.effects:  # a parameter no registered effect declares
        unknown |= {f"effects[{k!r}]" for k in problem.effects if k not in registry.COLUMN}
    if unknown:
        raise TypeError(
            f"the dynamic kernel does not take DynamicProblem field(s) {sorted(unknown)}"
        )
    if effects.size == 1:  # one case: its bits as an int
        outside = int(effects[0]) & ~L.KERNEL_EFFECTS
    else:
        masked = effects.astype(np.int64) & ~L.KERNEL_EFFECTS
        outside = int(masked.max()) if masked.size else 0
    if outside:
        raise TypeError(f"the dynamic kernel does not model effect(s) {outside}")


def _table(columns: dict[int, Column], shape: tuple[int, ...], n: int) -> FloatArray:
    """The case table from its columns (floats, or arrays broadcasting to the batch)."""
    if n == 1:  # one case: one array from its numbers
        row = [0.0] * L.COLUMNS
        for column, value in columns.items():
            row[column] = value if type(value) is float else float(np.asarray(value).item())
        return np.array([row])
    table = np.zeros((n, L.COLUMNS))
    for column, value in columns.items():
        table[:, column] = np.broadcast_to(value, shape).reshape(n)
    return table


def pack(problem: DynamicProblem, record: bool) -> Packed:
    """The kernel's view of ``problem`` (see :class:`Packed`)."""
    shape = problem.batch_shape
    n = math.prod(shape)
    points = problem.angles.shape[0]
    nodes = 0 if not problem.thermal else 2 if problem.two_node else 1
    columns: dict[int, Column] = {column: getattr(problem, name) for column, name in _FIELDS}
    law = _law(problem)
    columns.update(law)
    columns.update(_derived(problem, law, nodes))
    columns.update(registry.columns(registry.problem_values(problem)))
    table = _table(columns, shape, n)
    table[:, L.EFFECTS] = _effects(problem, table)
    _check_known(problem, table[:, L.EFFECTS])
    resistance = np.zeros((n, points))
    if problem.resistance is not None:
        full = np.broadcast_to(problem.resistance, problem.angles.shape)
        resistance = np.array(full.reshape(points, n).T, order="C")
    settings = np.array(
        [
            problem.stop_time,
            problem.rtol,
            float(problem.max_events),
            1.0 if record else 0.0,
            float(L.INTEGRATOR_CODES[problem.integrator]),
        ]
    )
    # Copies, always writable: a read-only view (one case's spring table is one) is
    # another type to numba, which would compile the whole kernel again for it.
    return Packed(
        table=table,
        angles=np.array(problem.angles.reshape(points, n).T, order="C"),
        torques=np.array(problem.torques.reshape(points, n).T, order="C"),
        resistance=resistance,
        compliant=np.isfinite(table[:, L.MC]),
        nodes=nodes,
        settings=settings,
    )


# Rows of the event and span tables allocated up front at most (they grow when needed).
TABLE_ROWS = 1 << 20


def _tables(cases: int, record: bool, points: int) -> list[FloatArray]:
    """The kernel's output tables, a row per spring breakpoint (an event and a segment
    each) and case: a full table reruns the case (14 runs of one with P = 1,000)."""
    rows = min(cases * (points + 8), TABLE_ROWS)
    spans = rows if record else 1
    return [
        np.zeros((rows + 8, L.EVENT_FIELDS)),
        np.zeros((spans, L.SPAN_FIELDS)),
        np.zeros((min(64 * spans, 8 * TABLE_ROWS), L.POINT_FIELDS)),
    ]


def _run_part(
    kernel: Backend,
    packed: Packed,
    cases: NDArray[np.intp],
    lo: int,
    hi: int,
    dims: tuple[Any, ...],
) -> Run:
    """Cases ``cases[lo:hi]`` of ``packed``, in kernel calls that resume after a full
    output table has been enlarged (:mod:`ecdsim.dynamics.kernel.record`)."""
    record = packed.settings[L.RECORD] != 0.0
    index = cases[lo:hi]
    n = hi - lo
    tables = _tables(n, record, packed.angles.shape[1])
    counts = np.zeros(COUNTS)
    out = np.zeros((n, L.OUT_FIELDS))
    whole = (packed.table, packed.angles, packed.torques, packed.resistance)
    if n == packed.table.shape[0]:  # every case, in order (one group, one part)
        arrays = whole
    else:
        arrays = (
            np.ascontiguousarray(packed.table[index]),
            np.ascontiguousarray(packed.angles[index]),
            np.ascontiguousarray(packed.torques[index]),
            np.ascontiguousarray(packed.resistance[index]),
        )
    first = 0
    while True:
        stopped = kernel.solve_cases(
            first, n, *arrays, packed.settings, out, tuple(tables), counts, *dims
        )
        if stopped < 0:
            break
        full = int(counts[OVERFLOW]) - 1
        for table in range(3):
            counts[table] = counts[START + table]
        filled = int(counts[full])
        bigger = np.zeros((2 * tables[full].shape[0], tables[full].shape[1]))
        bigger[:filled] = tables[full][:filled]
        tables[full] = bigger
        counts[OVERFLOW] = 0.0
        first = int(stopped)
    events = tables[0][: int(counts[0])]
    spans = tables[1][: int(counts[1])]
    if n != packed.table.shape[0]:  # the group's case numbers back to the problem's
        events[:, 0] = index[events[:, 0].astype(np.intp)]
        spans[:, L.SPAN_CASE] = index[spans[:, L.SPAN_CASE].astype(np.intp)]
    return Run(index, out, events, spans, tables[2][: int(counts[2])])


def _in_threads(run: Callable[[int, int], Run], parts: list[tuple[int, int]]) -> list[Run]:
    """``run(lo, hi)`` for each part: the first in this thread, the others in new ones."""
    results: list[Run | None] = [None] * len(parts)
    errors: list[BaseException] = []

    def guarded(k: int) -> None:
        try:
            results[k] = run(*parts[k])
        except BaseException as exc:  # re-raised in the calling thread
            errors.append(exc)

    workers = [threading.Thread(target=guarded, args=(k,)) for k in range(1, len(parts))]
    for worker in workers:
        worker.start()
    try:
        guarded(0)
    finally:
        for worker in workers:
            worker.join()
    if errors:
        raise errors[0]
    return [r for r in results if r is not None]


def _group(kernel: Backend, packed: Packed, cases: NDArray[np.intp], compliant: bool) -> list[Run]:
    """One state layout's cases, split over threads when the batch is large."""
    m = 2 if compliant else 1
    dims = ((0,) * m, (0,) * packed.nodes, (0,) * m)
    n = cases.size
    parts_count = THREADS if n >= PARALLEL_MIN and kernel.name == "numba" else 1
    edges = [n * i // parts_count for i in range(parts_count + 1)]
    parts = [(lo, hi) for lo, hi in zip(edges[:-1], edges[1:], strict=True) if hi > lo]
    if len(parts) == 1:
        return [_run_part(kernel, packed, cases, 0, n, dims)]
    return _in_threads(lambda lo, hi: _run_part(kernel, packed, cases, lo, hi, dims), parts)


def solve_dynamic(
    problem: DynamicProblem, record: bool = True, kernel: Backend | None = None
) -> DynamicResult:
    """Solve every case of ``problem``; ``record`` keeps what time series need.

    ``kernel`` picks the kernel's form (:func:`ecdsim.dynamics.kernel.build.backend`):
    compiled by default, plain Python with ``backend("python")`` or ``ECDSIM_NUMBA=0``.
    """
    if kernel is None:
        kernel = backend() if problem.integrator == "RODAS4" else backend("scipy")
    packed = pack(problem, record)
    runs: list[Run] = []
    if packed.compliant.size == 1:  # one case: one group of one
        one = np.zeros(1, dtype=np.intp)
        runs.extend(_group(kernel, packed, one, bool(packed.compliant[0])))
        return result_of(problem, packed, runs, record)
    for compliant in (False, True):
        cases = np.flatnonzero(packed.compliant == compliant)
        if cases.size:
            runs.extend(_group(kernel, packed, cases, compliant))
    return result_of(problem, packed, runs, record)
