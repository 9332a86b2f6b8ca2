"""The dynamic kernel itself: one source compiled and plain, its layout, its gates.

- The kernel compiled by numba and the same kernel run as plain Python give the same
  results (to the C library's roundings) on every kind of case.
- Its Jacobian against central differences of its right-hand side, for every effect,
  rigid and compliant.
- RODAS4's order 4 and its error estimate's order (the step of
  :mod:`ecdsim.dynamics.kernel.rodas`, fixed steps against a tight DOP853 reference).
- The layout's codes against the result's names; the output tables growing; a batch
  split over threads; an error in a worker reaching the caller.
- Gates closed by default: a problem field or an effect the kernel does not know is
  refused, by the closed form and by the kernel.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ecdsim.deployment import build_problem, predict
from ecdsim.dynamics import DynamicParameters, DynamicProblem, Rolloff, Thermal
from ecdsim.dynamics import solver as solver_module
from ecdsim.dynamics.kernel import effects, hinge, layout, loop, rodas, segment
from ecdsim.dynamics.kernel.build import backend
from ecdsim.dynamics.problem import dynamic_problem
from ecdsim.dynamics.result import EVENT_KINDS, STATUSES, DynamicResult
from ecdsim.dynamics.solver import KNOWN_FIELDS, pack, solve_dynamic
from ecdsim.model import DeploymentSystem
from tests.conftest import paper_system
from tests.dynamics_reference import assert_energy_closes, toy_system

TEMPS = np.array([-40.0, 25.0, 100.0])


def _problem(
    system: DeploymentSystem, params: DynamicParameters, temps: Any = TEMPS
) -> DynamicProblem:
    temps = np.asarray(temps, dtype=float)
    ecd = system.ecd.at(temps)
    base, fs = build_problem(system, ecd, temps)
    return dynamic_problem(system, ecd, temps, base, fs, params)


# --- compiled and plain: one source ------------------------------------------------

CASES = {
    "linear closed form": DynamicParameters(5.0),
    "rolloff and heating": DynamicParameters(
        5.0, rotor_inertia=2e-7, rolloff=Rolloff(60.0, 0.0039), thermal=Thermal(0.2, 100.0)
    ),
    "two nodes": DynamicParameters(
        1.0, thermal=Thermal(0.002, 40.0, 0.02, 100.0, initial_rotor_rise=5.0)
    ),
    "stribeck and rebounds": DynamicParameters(
        5.0, static_friction_factor=1.5, stribeck_speed=0.02, restitution=0.5
    ),
    "compliant mesh": DynamicParameters(
        5.0, rotor_inertia=2e-7, gear_stiffness=2e3, gear_mesh_damping=0.5
    ),
}


@pytest.mark.parametrize("name", list(CASES))
def test_the_compiled_and_plain_kernels_agree(name: str) -> None:
    # The same source twice: compiled (numba) and plain Python. Both run the same
    # operations in the same order; they may differ only where the C library's exp,
    # expm1 or sin round differently from Python's math and NumPy's (1e-12 covers what
    # that does to a deployment at rtol 1e-8).
    problem = _problem(paper_system(), CASES[name])
    compiled = solve_dynamic(problem, kernel=backend("numba"))
    plain = solve_dynamic(problem, kernel=backend("python"))
    assert compiled.events.names() == plain.events.names()
    for field in ("deployment_time", "final_time", "final_angle", "max_speed", "final_temperature"):
        np.testing.assert_allclose(
            getattr(compiled, field), getattr(plain, field), rtol=1e-12, err_msg=field
        )
    np.testing.assert_array_equal(compiled.status, plain.status)
    assert_energy_closes(compiled)
    assert_energy_closes(plain)


# --- the hinge's Jacobian -----------------------------------------------------------


@dataclass
class _Case:
    cw: np.ndarray
    tables: tuple[np.ndarray, np.ndarray, np.ndarray]
    dims: tuple[tuple[int, ...], tuple[int, ...], tuple[int, ...]]


def _case(problem: DynamicProblem, sliding: tuple[float, ...]) -> _Case:
    """The first case of ``problem`` set up as the kernel sets it up (plain Python),
    its friction elements sliding as given."""
    packed = pack(problem, record=False)
    m = 2 if packed.compliant[0] else 1
    cw = np.zeros(layout.case_words(m))
    cw[: layout.COLUMNS] = packed.table[0]
    tables = (packed.angles[0], packed.torques[0], packed.resistance[0])
    y = np.zeros(2 * m + packed.nodes + m)
    loop.initial_state(cw, tables, y, np.zeros(layout.OUT_FIELDS), m, packed.nodes)
    for k, value in enumerate(sliding):
        cw[layout.MD_SLIDE0 + k] = value
    cw[layout.MD_ENGAGED] = 1.0
    if m == 2:
        cw[layout.MD_MESH] = layout.PRESS
    ws = loop.new_workspace(m, packed.nodes, m)
    segment.start_segment(cw, tables, y, 0.3, cw[layout.FA], ws[5], ws[6], m)
    return _Case(cw, tables, ((0,) * m, (0,) * packed.nodes, (0,) * m))


JACOBIAN_CASES = {
    "linear": (DynamicParameters(5.0), (1.0,)),
    "kloss heated": (
        DynamicParameters(
            5.0, rotor_inertia=2e-7, rolloff=Rolloff(60.0, 0.0039), thermal=Thermal(0.2, 100.0)
        ),
        (1.0,),
    ),
    "two nodes": (DynamicParameters(1.0, thermal=Thermal(0.002, 40.0, 0.02, 100.0)), (-1.0,)),
    "stribeck": (DynamicParameters(5.0, static_friction_factor=1.5, stribeck_speed=0.02), (1.0,)),
    "compliant": (
        DynamicParameters(5.0, rotor_inertia=2e-7, gear_stiffness=2e3, gear_mesh_damping=0.5),
        (1.0, 1.0),
    ),
    "compliant, the damper side backward": (
        DynamicParameters(5.0, rotor_inertia=2e-7, gear_stiffness=2e3, gear_mesh_damping=0.5),
        (1.0, -1.0),
    ),
}


@pytest.mark.parametrize("name", list(JACOBIAN_CASES))
def test_the_jacobian_matches_central_differences(name: str) -> None:
    params, sliding = JACOBIAN_CASES[name]
    case = _case(_problem(paper_system(), params, [25.0]), sliding)
    m, na, nq = (len(d) for d in case.dims)
    n = 2 * m + na + nq
    rng = np.random.default_rng(7)
    y = np.zeros(n)
    y[:m] = rng.uniform(0.01, 0.1, m)
    y[m : 2 * m] = rng.uniform(0.02, 0.08, m) * np.array(sliding)
    if m == 2:
        y[1] = 0.001 + 0.5 * float(case.cw[layout.GAP])  # past the forward flank
    y[2 * m : 2 * m + na] = rng.uniform(0.5, 3.0, na)
    jac = np.zeros((n, n))
    hinge.jacobian(case.cw, y, jac, *case.dims)
    for column in range(n):
        step = 1e-6 * max(abs(y[column]), 1e-3)
        up, down = y.copy(), y.copy()
        up[column] += step
        down[column] -= step
        f_up, f_down = np.zeros(n), np.zeros(n)
        hinge.derivatives(case.cw, up, f_up, *case.dims)
        hinge.derivatives(case.cw, down, f_down, *case.dims)
        numeric = (f_up - f_down) / (2.0 * step)
        for row in range(m, n):  # the coordinates' rows are q' = v
            # Central differences: truncation ~ step^2, rounding ~ eps / step relative.
            scale = max(
                abs(numeric[row]), abs(jac[row, column]), 1e-9 * np.max(np.abs(jac[row])), 1e-12
            )
            rounding = 1e-15 * max(abs(f_up[row]), abs(f_down[row])) / step
            error = abs(jac[row, column] - numeric[row])
            assert error <= 1e-6 * scale + rounding, (name, row, column)


# --- RODAS4's order ------------------------------------------------------------------


def _rodas_case() -> _Case:
    # A spring-driven load on a Kloss damper beyond its peak for part of the motion, with
    # adiabatic heating: nonlinear in speed and temperature.
    system = toy_system(0.05 * 2 / 30.0, 0.0, 2.0, 2.0 - 1.5 * 3.0, 3.0)
    params = DynamicParameters(1.0, rolloff=Rolloff(30.0, 0.0039), thermal=Thermal(0.5))
    return _case(_problem(system, params, [25.0]), (1.0,))


def _fixed_steps(case: _Case, y0: np.ndarray, t_end: float, steps: int) -> np.ndarray:
    n = y0.size
    m, na, _ = (len(d) for d in case.dims)
    work, jac, lu, pivot = rodas.new_work(n, m, na)
    y, f = y0.copy(), np.zeros(n)
    for _ in range(steps):
        hinge.derivatives(case.cw, y, f, *case.dims)
        assert rodas.rodas_step(case.cw, y, f, t_end / steps, work, jac, lu, pivot, *case.dims)
        y = work[8].copy()
    return y


def _reference(case: _Case, y0: np.ndarray, t_end: float) -> np.ndarray:
    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        dy = np.zeros(y.size)
        hinge.derivatives(case.cw, y, dy, *case.dims)
        return dy

    sol = solve_ivp(rhs, (0.0, t_end), y0, method="DOP853", rtol=1e-13, atol=1e-15)
    return np.asarray(sol.y[:, -1])


def test_rodas4_converges_with_order_four() -> None:
    case = _rodas_case()
    y0 = np.array([0.0, 0.0, 0.0, 0.0])
    ref = _reference(case, y0, 0.5)
    errors = [np.max(np.abs(_fixed_steps(case, y0, 0.5, n) - ref)) for n in (20, 40, 80)]
    # Order 4: halving the step divides the global error by 16; allow 12..20 for the
    # pre-asymptotic terms (an order-3 method would give 8).
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((ratios > 12.0) & (ratios < 20.0)), (errors, ratios)


def test_the_error_estimate_is_of_local_order_four() -> None:
    case = _rodas_case()
    y0 = np.array([0.0, 0.5, 0.0, 0.0])
    m, na, _ = (len(d) for d in case.dims)
    work, jac, lu, pivot = rodas.new_work(4, m, na)
    f = np.zeros(4)
    hinge.derivatives(case.cw, y0, f, *case.dims)
    estimates = []
    for h in (0.02, 0.01, 0.005):
        rodas.rodas_step(case.cw, y0, f, h, work, jac, lu, pivot, *case.dims)
        estimates.append(np.max(np.abs(work[5])))
    # The embedded solution is order 3: its difference from the order-4 one is O(h^4),
    # so halving h divides the estimate by about 16 (allow 10..22).
    ratios = np.array(estimates[:-1]) / np.array(estimates[1:])
    assert np.all((ratios > 10.0) & (ratios < 22.0)), (estimates, ratios)


# --- layout, outputs, threads ----------------------------------------------------------


def test_the_layout_codes_are_the_result_names() -> None:
    for name, code in (
        ("release", layout.EV_RELEASE),
        ("breakaway", layout.EV_BREAKAWAY),
        ("stick", layout.EV_STICK),
        ("zero_speed", layout.EV_ZERO),
        ("engage", layout.EV_ENGAGE),
        ("breakpoint", layout.EV_BREAKPOINT),
        ("arrive", layout.EV_ARRIVE),
        ("latch", layout.EV_LATCH),
        ("settle", layout.EV_SETTLE),
        ("start_stop", layout.EV_START_STOP),
        ("stop_time", layout.EV_STOP_TIME),
        ("creep", layout.EV_CREEP),
        ("event_limit", layout.EV_EVENT_LIMIT),
        ("horizon", layout.EV_HORIZON),
        ("separate", layout.EV_SEPARATE),
        ("contact", layout.EV_CONTACT),
        ("power_flow", layout.EV_POWER_FLOW),
    ):
        assert EVENT_KINDS[code] == name
    for name, code in (
        ("running", layout.ST_RUNNING),
        ("latched", layout.ST_LATCHED),
        ("settled", layout.ST_SETTLED),
        ("stuck", layout.ST_STUCK),
        ("creep", layout.ST_CREEP),
        ("stop_time", layout.ST_STOP_TIME),
        ("event_limit", layout.ST_EVENT_LIMIT),
        ("horizon", layout.ST_HORIZON),
    ):
        assert STATUSES[code] == name


def _long(result: DynamicResult) -> tuple[Any, ...]:
    return (
        result.events.names(),
        result.deployment_time.tolist(),
        result.final_time.tolist(),
        result.sample(n_points=11).angle.tolist(),
    )


def test_full_output_tables_grow_and_the_case_runs_again(monkeypatch: pytest.MonkeyPatch) -> None:
    # Tables of one row each: every case overflows them, the caller doubles the full one
    # and runs that case again from its start, until the case fits: the same result as
    # with tables large enough at once.
    problem = _problem(paper_system(), CASES["stribeck and rebounds"])
    roomy = solve_dynamic(problem)
    monkeypatch.setattr(
        solver_module,
        "_tables",
        lambda cases, record, points: [
            np.zeros((1, layout.EVENT_FIELDS)),
            np.zeros((1, layout.SPAN_FIELDS)),
            np.zeros((1, layout.POINT_FIELDS)),
        ],
    )
    tight = solve_dynamic(problem)
    assert _long(tight) == _long(roomy)


@pytest.mark.parametrize("threads", [2, 3, 7])
def test_a_batch_split_over_threads_gives_the_same_results(
    threads: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Every case depends on its own row only: any split gives the same bits.
    params = replace(CASES["rolloff and heating"], load_inertia=np.linspace(1.0, 20.0, 300))
    problem = _problem(paper_system(), params, [25.0])
    monkeypatch.setattr(solver_module, "THREADS", 1)
    one = solve_dynamic(problem, record=False)
    monkeypatch.setattr(solver_module, "THREADS", threads)
    split = solve_dynamic(problem, record=False)
    np.testing.assert_array_equal(split.deployment_time, one.deployment_time)
    np.testing.assert_array_equal(split.max_damper_temperature, one.max_damper_temperature)
    assert split.events.names() == one.events.names()


def test_an_error_in_a_worker_thread_reaches_the_caller(monkeypatch: pytest.MonkeyPatch) -> None:
    calls = []

    def failing(*args: Any) -> Any:
        calls.append(1)
        if len(calls) == 2:
            raise RuntimeError("worker failed")
        return original(*args)

    original = solver_module._run_part
    monkeypatch.setattr(solver_module, "THREADS", 2)
    monkeypatch.setattr(solver_module, "_run_part", failing)
    problem = _problem(paper_system(), DynamicParameters(np.linspace(1.0, 2.0, 300)), [25.0])
    with pytest.raises(RuntimeError, match="worker failed"):
        solve_dynamic(problem, record=False)


def test_every_case_of_a_batch_is_its_own_single_solve() -> None:
    inertias = np.array([0.5, 2.0, 5.0, 20.0])
    params = replace(CASES["rolloff and heating"], load_inertia=inertias)
    batch = solve_dynamic(_problem(paper_system(), params, TEMPS[:, None]))
    assert batch.batch_shape == (3, 4)
    for i, temperature in enumerate(TEMPS):
        for j, inertia in enumerate(inertias):
            one = solve_dynamic(
                _problem(
                    paper_system(), replace(params, load_inertia=float(inertia)), [temperature]
                )
            )
            # The same case on its own row: the same operations, the same bits.
            assert batch.deployment_time[i, j] == one.deployment_time[0]
            assert batch.max_damper_temperature[i, j] == one.max_damper_temperature[0]


# --- gates closed by default -----------------------------------------------------------


def test_every_problem_field_is_known_to_the_kernel() -> None:
    # A field added to DynamicProblem is refused until the packer takes it.
    assert {f.name for f in fields(DynamicProblem)} == set(KNOWN_FIELDS)


def test_a_problem_with_an_unknown_field_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(solver_module, "KNOWN_FIELDS", KNOWN_FIELDS - {"restitution"})
    with pytest.raises(TypeError, match="restitution"):
        solve_dynamic(_problem(paper_system(), DynamicParameters(5.0)))


DUMMY = 1 << 20  # an effect no path of the kernel models


def test_an_unknown_effect_is_refused_by_the_kernel(monkeypatch: pytest.MonkeyPatch) -> None:
    original = solver_module._effects

    def with_dummy(problem: DynamicProblem, table: np.ndarray) -> np.ndarray:
        return original(problem, table) + DUMMY

    monkeypatch.setattr(solver_module, "_effects", with_dummy)
    with pytest.raises(TypeError, match="does not model effect"):
        solve_dynamic(_problem(paper_system(), DynamicParameters(5.0)))


@pytest.mark.parametrize("name", sorted(CASES))
def test_one_case_effects_are_the_batch_ones(name: str) -> None:
    # One deployment reads its effects off its row as floats (solver._case_effects); a
    # batch tests its columns: the same bits, case by case.
    problem = _problem(paper_system(), CASES[name], [-40.0, 25.0, 100.0])
    table = pack(problem, record=False).table
    batch = solver_module._effects(problem, table)
    assert np.any(batch != 0.0) or name == "linear closed form"
    for i in range(table.shape[0]):
        assert solver_module._case_effects(problem, table[i].tolist()) == batch[i]


@pytest.mark.parametrize("effect", [DUMMY, layout.EFFECT_ROLLOFF, effects.BIT["gravity"]])
def test_the_closed_form_takes_only_the_effects_it_models(effect: int) -> None:
    # A linear segment takes the closed form; the same segment with any effect outside
    # CLOSED_FORM_EFFECTS (a dummy one included) is integrated instead.
    case = _case(_problem(paper_system(), DynamicParameters(5.0), [25.0]), (1.0,))
    assert loop.closed_form_applies(case.cw, 1)
    case.cw[layout.EFFECTS] += effect
    if effect == effects.BIT["gravity"]:
        case.cw[effects.COLUMN["gravity_amplitude"]] = 1.0  # a registered effect's column
    assert not loop.closed_form_applies(case.cw, 1)
    for known in (layout.EFFECT_LOSSY, layout.EFFECT_REBOUND, layout.EFFECT_STOP_TIME):
        assert known & layout.CLOSED_FORM_EFFECTS


def test_predict_uses_the_kernel_for_one_deployment() -> None:
    # One deployment takes the one kernel as a batch does (no path of its own).
    prediction = predict(paper_system(), 25.0, ["dynamic"], dynamics=CASES["rolloff and heating"])
    result = prediction.solutions["dynamic"].result  # type: ignore[attr-defined]
    batch = solve_dynamic(_problem(paper_system(), CASES["rolloff and heating"], [25.0]))
    assert float(np.ravel(result.deployment_time)[0]) == float(batch.deployment_time[0])
