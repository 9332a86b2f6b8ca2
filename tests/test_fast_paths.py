"""The shortcuts of a single deployment's fixed cost give the general path's answers.

``predict`` of one case pays every NumPy call's dispatch in full (issue 13, single
cases), so a few helpers answer the common question directly: one-element masks read
off their element, two breakpoint rows filled into one array, the findings' status test
done once. Each is checked here against the general NumPy expression it replaces, on
the shapes a batch can have (empty, one element with 0, 1 or 2 axes, many).
"""

from __future__ import annotations

import math
from dataclasses import fields, replace
from typing import Any

import numpy as np
import pytest

import ecdsim.deployment as deployment_module
import ecdsim.dynamics.problem as problem_module
from ecdsim._types import all_true, any_true, one_case_views
from ecdsim.deployment import (
    ModelDomainError,
    ModelWarning,
    _check_damping_positive,
    build_problem,
    predict,
)
from ecdsim.dynamics import DynamicParameters, DynamicProblem, Rolloff, Thermal
from ecdsim.dynamics.damping import KlossEddy
from ecdsim.dynamics.method import (
    REPORTED_FROM,
    DynamicSolution,
    _batch_findings,
    _findings,
    _kloss_low_speed,
)
from ecdsim.dynamics.problem import (
    _BASE_FIELDS,
    _CASE_FIELDS,
    _REGISTERED_FIELDS,
    _SETTING_FIELDS,
    dynamic_problem,
)
from ecdsim.dynamics.result import _TERMS, STATUSES, EnergyBalance
from ecdsim.model import (
    Ecd,
    EcdState,
    Gearbox,
    GearEfficiency,
    LinearSpring,
    LinearTemperatureLaw,
    TabulatedTemperatureLaw,
    _pair,
)
from ecdsim.physics import mechanics, rolloff
from ecdsim.solvers.base import ONE_CASE_FIELDS, QuasiStaticProblem, one_case_problem
from tests.conftest import paper_system

MASKS = [
    np.zeros(0, dtype=bool),
    np.asarray(True),
    np.asarray(False),
    np.bool_(True),
    np.bool_(False),
    np.array([True]),
    np.array([False]),
    np.array([[True]]),
    np.array([[False]]),
    np.array([False, False, True]),
    np.array([True, True, False]),
    np.array([[True, True], [True, True]]),
    np.array([[False, False], [False, False]]),
]


@pytest.mark.parametrize("mask", MASKS, ids=lambda m: f"{np.shape(m)}-{np.ravel(m).tolist()}")
def test_any_true_and_all_true_are_np_any_and_np_all(mask: np.ndarray) -> None:
    assert any_true(mask) is bool(np.any(mask))
    assert all_true(mask) is bool(np.all(mask))


SHAPES = [(), (1,), (3,), (1, 1), (2, 3), (1, 3), (2, 1)]


@pytest.mark.parametrize("first", SHAPES)
@pytest.mark.parametrize("second", SHAPES)
def test_pair_is_stack_of_broadcast_arrays(first: tuple[int, ...], second: tuple[int, ...]) -> None:
    rng = np.random.default_rng(7)
    a = rng.normal(size=first)
    b = rng.normal(size=second)
    try:
        expected = np.stack(np.broadcast_arrays(a, b))
    except ValueError:
        with pytest.raises(ValueError, match="broadcast"):
            _pair(np.asarray(a), np.asarray(b))
        return
    got = _pair(np.asarray(a), np.asarray(b))
    assert got.shape == expected.shape
    assert got.dtype == expected.dtype
    assert got.tobytes() == expected.tobytes()  # bit for bit, NaN-free random values


def test_linear_spring_breakpoints_are_the_stacked_rows() -> None:
    # Eq. 7's two breakpoints, (0, Ts f) and (travel, Te f), f = 1 + k (T - T_ref), by hand.
    spring = LinearSpring(np.array([3.7, 3.8]), 1.6, 0.01, 25.0)
    temps = np.array([[-40.0], [25.0], [100.0]])
    angles, torques = spring.breakpoints(1.57, temps)
    factor = 1.0 + 0.01 * (temps - 25.0)
    assert angles.shape == (2,)
    np.testing.assert_array_equal(angles, [0.0, 1.57])
    assert torques.shape == (2, 3, 2)
    # Same operations in the same order as the spring: equal bit for bit.
    np.testing.assert_array_equal(torques[0], np.array([3.7, 3.8]) * factor)
    np.testing.assert_array_equal(torques[1], np.broadcast_to(1.6 * factor, (3, 2)))


def test_reported_statuses_are_the_last_ones() -> None:
    # The findings test status >= REPORTED_FROM once: that must be exactly the statuses
    # they report (a new status appended after them would be reported by mistake).
    assert set(STATUSES[REPORTED_FROM:]) == {"stop_time", "event_limit", "horizon"}


@pytest.mark.parametrize("bad", ["damper", "ecd", "both"])
@pytest.mark.parametrize("value", [math.nan, -1e-4])
@pytest.mark.parametrize("temps", [[25.0], [-40.0, 25.0, 100.0]])
def test_a_bad_damping_rate_is_refused_at_one_or_many_temperatures(
    bad: str, value: float, temps: list[float]
) -> None:
    # The one-test shortcut of _check_damping_positive must still catch a NaN or a
    # negative BD_T or BECD_T in any case, as the element-wise test after it does.
    state = paper_system().ecd.at(np.asarray(temps))
    last = len(temps) - 1
    changes: dict[str, Any] = {}
    if bad in ("damper", "both"):
        damper = np.array(np.broadcast_to(state.damper_damping_rate, (len(temps),)))
        damper[last] = value
        changes["damper_damping_rate"] = damper
    if bad in ("ecd", "both"):
        ecd = np.array(state.ecd_damping_rate)
        ecd[last] = value
        changes["ecd_damping_rate"] = ecd
    with pytest.raises(ModelDomainError) as caught:
        _check_damping_positive(replace(state, **changes))
    assert caught.value.key == "damper.damping_temperature_coefficient"
    assert f"at {temps[last]:g} degC" in str(caught.value)


def test_good_damping_rates_pass() -> None:
    state = paper_system().ecd.at(np.array([-40.0, 25.0, 100.0]))
    _check_damping_positive(state)  # raises if the shortcut refused a valid state
    zero = np.zeros(3)  # zero is a real case (an undamped coast)
    _check_damping_positive(replace(state, damper_damping_rate=zero, ecd_damping_rate=zero))


@pytest.mark.parametrize("shape", [(), (1,), (1, 1), (1, 1, 1)])
def test_one_case_views_are_the_broadcast_values(shape: tuple[int, ...]) -> None:
    values = [
        np.asarray(1.5),
        np.array([-0.0]),
        np.array([[math.inf]]),
        np.asarray(math.nan),
        np.array([2.0]),
    ]
    got = one_case_views(values, shape)
    assert len(got) == len(values)
    for value, view in zip(values, got, strict=True):
        expected = np.broadcast_to(value.reshape(()), shape)
        assert type(view) is np.ndarray  # a 0-d array, not a NumPy scalar, for shape ()
        assert view.shape == expected.shape
        assert view.dtype == np.float64
        assert not view.flags.writeable  # read-only, as broadcast() returns
        assert view.tobytes() == expected.tobytes()  # -0.0, inf and NaN kept bit for bit


def test_a_one_case_dynamic_problem_is_the_broadcast_one() -> None:
    # The one-case path of DynamicProblem.__post_init__ against the general one: the same
    # problem built for two cases and for one gives the first case's values, shapes and
    # read-only fields for every per-case field.
    system = paper_system()
    params = DynamicParameters(load_inertia=np.array([5.0, 6.0]), rolloff=Rolloff(60.0, 0.0039))
    one = replace(params, load_inertia=np.array([5.0]))
    two_cases = predict(system, [25.0, 25.0], ["dynamic"], dynamics=params)
    one_case = predict(system, [25.0], ["dynamic"], dynamics=one)
    p2 = two_cases.solutions["dynamic"].problem  # type: ignore[attr-defined]
    p1 = one_case.solutions["dynamic"].problem  # type: ignore[attr-defined]
    assert isinstance(p1, DynamicProblem)
    assert isinstance(p2, DynamicProblem)
    for name in (*_CASE_FIELDS, "friction", "damping_rate"):
        general, single = getattr(p2, name), getattr(p1, name)
        assert single.shape == (1,)
        assert not single.flags.writeable
        assert single.dtype == general.dtype == np.float64
        assert single.tobytes() == general[:1].tobytes(), name
    assert p1.angles.tobytes() == p2.angles[:, :1].tobytes()
    assert p1.torques.tobytes() == p2.torques[:, :1].tobytes()


def test_a_problem_built_from_a_normalized_one_is_the_same() -> None:
    # QuasiStaticProblem keeps fields that are already aligned, read-only float64 arrays
    # (the early return of __post_init__): the result equals the general path's.
    general = QuasiStaticProblem(
        angles=np.array([0.0, 1.57]),
        torques=np.array([[3.7, 3.8], [1.6, 1.5]]),
        friction=np.array([1.0, 1.1]),
        damping_rate=np.asarray(20.0),
    )
    again = QuasiStaticProblem(
        general.angles, general.torques, general.friction, general.damping_rate
    )
    assert again.angles is general.angles  # kept as it is
    for name in ("angles", "torques", "friction", "damping_rate"):
        a, b = getattr(general, name), getattr(again, name)
        assert a.shape == b.shape == ((2, 2) if name in ("angles", "torques") else (2,))
        assert not b.flags.writeable
        assert a.tobytes() == b.tobytes()
    # A writeable field, or gravity, takes the general path (which makes it read-only).
    writeable = QuasiStaticProblem(
        np.array(general.angles), general.torques, general.friction, general.damping_rate
    )
    assert not writeable.angles.flags.writeable
    with_gravity = QuasiStaticProblem(
        general.angles,
        general.torques,
        general.friction,
        general.damping_rate,
        gravity_amplitude=np.asarray(0.5),
    )
    assert with_gravity.gravity_amplitude is not None
    assert with_gravity.gravity_amplitude.shape == (2,)
    assert with_gravity.gravity_angle is not None
    assert with_gravity.gravity_angle.shape == (2,)


def _findings_as_before(result: Any, error: np.ndarray) -> list[tuple[str, str, int]]:
    """The status and energy findings as they were written before the shortcuts: one
    search per status, then the energy balance (the texts of dynamics/method.py)."""
    out: list[tuple[str, str, int]] = []
    status = np.ravel(result.status)
    final_time = np.ravel(result.final_time)
    final_angle = np.ravel(result.final_angle)
    for i in np.flatnonzero(status == STATUSES.index("stop_time")):
        out.append(
            (
                "stop_time",
                f"the end of travel was not reached by the stop time ({final_time[i]:.4g} s; "
                f"angle {final_angle[i]:.4g} rad)",
                int(i),
            )
        )
    for code in ("event_limit", "horizon"):
        for i in np.flatnonzero(status == STATUSES.index(code)):
            out.append(
                (
                    code,
                    f"the dynamic run was cut short ({code.replace('_', ' ')}) at "
                    f"{final_time[i]:.4g} s; its result is incomplete",
                    int(i),
                )
            )
    flat = np.ravel(error)
    for i in np.flatnonzero(np.abs(flat) > 1e-6):
        out.append(
            (
                "energy_balance",
                f"the energy balance closes only to {flat[i]:.2g} (relative); tighten rtol",
                int(i),
            )
        )
    return out


@pytest.mark.parametrize(
    "statuses",
    [
        ["latched"] * 6,  # nothing to report: the one comparison answers
        ["stop_time", "event_limit", "horizon", "latched", "stop_time", "horizon"],
        ["horizon", "horizon", "event_limit", "stuck", "creep", "stop_time"],
    ],
)
def test_status_and_energy_findings_are_the_per_status_searches(statuses: list[str]) -> None:
    # A real six-case result (linear law: no Kloss findings) with its statuses and
    # energy errors replaced: the findings, in order and word for word, are those of a
    # search per status.
    system = paper_system()
    temps = [-40.0, 25.0, 100.0, -40.0, 25.0, 100.0]
    prediction = predict(system, temps, ["dynamic"], dynamics=DynamicParameters(load_inertia=5.0))
    solution = prediction.solutions["dynamic"]
    result = replace(
        solution.result,  # type: ignore[attr-defined]
        status=np.array([STATUSES.index(s) for s in statuses], dtype=np.int8),
    )
    error = np.array([0.0, 2e-6, -1e-9, -3e-6, 1e-6, 0.5])
    got = _findings(solution.problem, result, error)  # type: ignore[attr-defined]
    assert got == _findings_as_before(result, error)
    assert sum(code == "energy_balance" for code, _, _ in got) == 3  # 2e-6, -3e-6, 0.5


def _same_field(name: str, fast: object, general: object) -> None:
    """Asserts ``fast`` is ``general``'s value bit for bit: type, shape, dtype, read-only
    flag and bytes for an array; equality (and type) for everything else."""
    assert type(fast) is type(general), name
    if isinstance(general, np.ndarray):
        assert isinstance(fast, np.ndarray)
        assert fast.shape == general.shape, name
        assert fast.dtype == general.dtype, name
        assert fast.flags.writeable == general.flags.writeable, name
        assert fast.tobytes() == general.tobytes(), name  # -0.0, inf and NaN kept
    else:
        assert fast == general, name


def test_the_one_case_problem_covers_every_field() -> None:
    # _one_case_problem sets the fields it lists and nothing else: a field added to
    # DynamicProblem (or QuasiStaticProblem) without adding it there fails here.
    listed = (*_BASE_FIELDS, *_REGISTERED_FIELDS, *_CASE_FIELDS, *_SETTING_FIELDS)
    names = [f.name for f in fields(DynamicProblem)]
    assert sorted(listed) == sorted(names)
    system = paper_system()
    problem = predict(system, [25.0], ["dynamic"], dynamics=DynamicParameters(5.0)).problem
    assert type(problem) is DynamicProblem
    assert sorted(vars(problem)) == sorted(names)


ONE_CASE_INPUTS: list[tuple[str, Any, DynamicParameters]] = [
    ("linear", [25.0], DynamicParameters(5.0, initial_speed=0.3)),
    ("scalar temperature", 25.0, DynamicParameters(5.0, rotor_inertia=1e-6)),
    ("two axes", [[-40.0]], DynamicParameters(5.0, restitution=0.4)),
    ("rolloff", [60.0], DynamicParameters(5.0, rolloff=Rolloff(60.0, 0.0039))),
    (
        "two-node heating",
        [25.0],
        DynamicParameters(
            5.0,
            rolloff=Rolloff(60.0, 0.0039),
            thermal=Thermal(2.0, 50.0, housing_heat_capacity=20.0, initial_rotor_rise=3.0),
        ),
    ),
    ("stribeck", [25.0], DynamicParameters(5.0, stribeck_speed=0.05, static_friction_factor=1.5)),
    ("compliant", [25.0], DynamicParameters(5.0, rotor_inertia=1e-6, gear_stiffness=1e3)),
    # A one-element array parameter: one case at a scalar temperature, (1,) at [25.0] and
    # (1, 1) at [[25.0]] (the general path, the parameter widening the batch).
    ("array parameter", 25.0, DynamicParameters(np.array([5.0]))),
    ("array parameter (1,)", [25.0], DynamicParameters(np.array([5.0]))),
    ("array parameter (1, 1)", [25.0], DynamicParameters(np.array([[5.0]]))),
    ("integer parameter", [25.0], DynamicParameters(np.array([5]), initial_speed=np.array(1))),
    ("two cases", [25.0, 80.0], DynamicParameters(5.0)),
]


@pytest.mark.parametrize(
    ("temperatures", "params"),
    [case[1:] for case in ONE_CASE_INPUTS],
    ids=[case[0] for case in ONE_CASE_INPUTS],
)
def test_the_one_case_problem_is_the_dataclass_one(
    temperatures: Any, params: DynamicParameters, monkeypatch: pytest.MonkeyPatch
) -> None:
    # dynamic_problem's one-case construction against DynamicProblem(...) (its __init__
    # and __post_init__), on the same inputs: every field bit for bit, read-only flags
    # included. Where it declines (several cases, a widening parameter) the general path
    # answers, so both sides agree there too.
    system = paper_system()
    temps = np.asarray(temperatures, dtype=float)
    ecd = system.ecd.at(temps)
    base, fs = build_problem(system, ecd, temps)
    taken: list[bool] = []
    one_case = problem_module._one_case_problem

    def spy(*args: Any) -> DynamicProblem | None:
        answer = one_case(*args)
        taken.append(answer is not None)
        return answer

    monkeypatch.setattr(problem_module, "_one_case_problem", spy)
    fast = dynamic_problem(system, ecd, temps, base, fs, params)
    # The shortcut answers one case that keeps the temperatures' shape, and only that.
    widened = np.shape(params.load_inertia) != () and temps.ndim == 0
    assert taken == [temps.size == 1 and not widened and np.ndim(params.load_inertia) < 2]
    monkeypatch.setattr(problem_module, "_one_case_problem", lambda *args: None)
    general = dynamic_problem(system, ecd, temps, base, fs, params)
    assert type(fast) is type(general) is DynamicProblem
    for f in fields(DynamicProblem):
        _same_field(f.name, getattr(fast, f.name), getattr(general, f.name))


def test_one_case_findings_are_the_batch_findings() -> None:
    # _findings of one case (Python floats) against the general path's on the same
    # one-case results: a roll-off damper at three temperatures (its temperature law off
    # Eq. 1's away from T_ref) with a low and a high peak speed (the damper beyond its
    # peak or not), each with every status and energy errors on both sides of 1e-6.
    system = paper_system()
    seen: set[str] = set()
    for peak_speed in (0.5, 1e4):
        params = DynamicParameters(load_inertia=5.0, rolloff=Rolloff(peak_speed, 0.0039))
        for temperature in (-40.0, 25.0, 100.0):
            prediction = predict(system, [temperature], ["dynamic"], dynamics=params)
            solution = prediction.solutions["dynamic"]
            problem = solution.problem  # type: ignore[attr-defined]
            for status in range(len(STATUSES)):
                result = replace(
                    solution.result,  # type: ignore[attr-defined]
                    status=np.array([status], dtype=np.int8),
                )
                for value in (0.0, 2e-6, -3e-6, -1e-9, math.nan):
                    error = np.array([value])
                    got = _findings(problem, result, error)
                    assert got == _batch_findings(problem, result, error)
                    assert all(type(i) is int for _, _, i in got)
                    seen.update(code for code, _, _ in got)
    # Every finding was produced (and so compared) at least once.
    assert seen == {
        "stop_time",
        "event_limit",
        "horizon",
        "energy_balance",
        "rolloff_temperature_law",
        "rolloff_beyond_peak",
    }


_PAPER_ECD = paper_system().ecd
ONE_TEMPERATURE_ECDS: list[tuple[str, Ecd, Any, bool]] = [
    # (label, assembly, temperature, the float path answers)
    ("paper, cold", _PAPER_ECD, [-40.0], True),
    ("paper, scalar", _PAPER_ECD, 25.0, True),
    ("paper, two axes", _PAPER_ECD, [[100.0]], True),
    (
        "given BG",
        replace(_PAPER_ECD, gearbox=Gearbox(120.0, 1e-3, damping_rate=3e-5)),
        [60.0],
        True,
    ),
    ("NaN temperature", _PAPER_ECD, [math.nan], False),
    ("overflow", replace(_PAPER_ECD, gearbox=Gearbox(1e200, damping_rate=0.0)), [25.0], False),
    (
        "lossy gear",
        replace(_PAPER_ECD, gearbox=Gearbox(380.0, 0.0, 0.0, efficiency=GearEfficiency(0.9, 0.8))),
        [25.0],
        False,
    ),
    (
        "table law",
        replace(
            _PAPER_ECD,
            damper=replace(
                _PAPER_ECD.damper,
                lubrication_friction=TabulatedTemperatureLaw((-50.0, 50.0), (4e-4, 1e-4)),
            ),
        ),
        [25.0],
        False,
    ),
    (
        "array parameter",
        replace(_PAPER_ECD, damper=replace(_PAPER_ECD.damper, damping_rate=np.array([1.3e-4]))),
        [25.0],
        False,
    ),
    ("two temperatures", _PAPER_ECD, [-40.0, 100.0], False),
]


@pytest.mark.parametrize(
    ("ecd", "temperature", "fast"),
    [case[1:] for case in ONE_TEMPERATURE_ECDS],
    ids=[case[0] for case in ONE_TEMPERATURE_ECDS],
)
def test_ecd_at_one_temperature_is_the_general_path(
    ecd: Ecd, temperature: Any, fast: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Ecd.at's float path (Eq. 1-4 written out) against the NumPy path on the same
    # inputs: every field bit for bit, shapes and writeable flags included. It declines
    # (None) where it does not apply, and the general path answers.
    t = np.asarray(temperature, dtype=float)
    assert (ecd._one_case_at(t) is not None if t.size == 1 else False) is fast
    with np.errstate(over="ignore"):  # the overflow case, as predict evaluates it
        got = ecd.at(t)
        monkeypatch.setattr(Ecd, "_one_case_at", lambda self, t: None)
        general = ecd.at(t)
    for f in fields(EcdState):
        _same_field(f.name, getattr(got, f.name), getattr(general, f.name))
    # The two efficiencies are one array in both (the ideal gear's 1).
    assert (got.forward_efficiency is got.backward_efficiency) is (
        general.forward_efficiency is general.backward_efficiency
    )


def test_ecd_at_one_temperature_sets_every_field() -> None:
    # The float path fills the EcdState's __dict__ itself: one field added to the class
    # (with a default, so that the constructor would not complain) fails here until set.
    state = _PAPER_ECD._one_case_at(np.array([25.0]))
    assert type(state) is EcdState
    assert sorted(vars(state)) == sorted(f.name for f in fields(EcdState))


def test_the_one_case_quasi_static_problem_covers_every_field() -> None:
    # one_case_problem sets the fields it lists, which are the class's: a field added to
    # QuasiStaticProblem without adding it there fails here.
    assert sorted(ONE_CASE_FIELDS) == sorted(f.name for f in fields(QuasiStaticProblem))
    problem = one_case_problem(np.array([0.0, 1.5]), np.array([[2.0], [1.0]]), *np.ones((2, 1)))
    assert problem is not None
    assert sorted(vars(problem)) == sorted(ONE_CASE_FIELDS)


QUASI_STATIC_ONE_CASE: list[tuple[str, tuple[Any, ...], bool]] = [
    # (label, (angles, torques, friction, damping_rate), the shortcut answers)
    ("linear spring", ([0.0, 1.57], [[3.7], [1.6]], [0.5], [20.0]), True),
    ("scalar batch", ([0.0, 1.57], [3.7, 1.6], 0.5, 20.0), True),
    ("two axes", ([0.0, 1.0, 1.57], [[[3.7]], [[2.0]], [[1.6]]], [[0.5]], 20.0), True),
    ("aligned angles", ([[0.0], [1.57]], [[3.7], [1.6]], [-0.0], [math.inf]), True),
    ("NaN damping", ([0.0, 1.57], [[3.7], [1.6]], [0.5], [math.nan]), True),
    ("two cases", ([0.0, 1.57], [[3.7, 3.8], [1.6, 1.5]], [0.5, 0.6], [20.0]), False),
    ("widening", ([0.0, 1.57], [[3.7], [1.6]], [[0.5]], [20.0]), True),
    ("integer angles", (np.array([0, 2]), [[3.7], [1.6]], [0.5], [20.0]), False),
]


@pytest.mark.parametrize(
    ("arrays", "fast"),
    [case[1:] for case in QUASI_STATIC_ONE_CASE],
    ids=[case[0] for case in QUASI_STATIC_ONE_CASE],
)
def test_the_one_case_quasi_static_problem_is_the_dataclass_one(
    arrays: tuple[Any, ...], fast: bool
) -> None:
    # one_case_problem against QuasiStaticProblem(...) on the same arrays: every field
    # bit for bit, read-only flags included; None where it does not apply.
    angles, torques, friction, damping = (
        value if isinstance(value, np.ndarray) else np.asarray(value, dtype=float)
        for value in arrays
    )
    general = QuasiStaticProblem(angles, torques, friction, damping)
    got = one_case_problem(angles, torques, friction, damping)
    assert (got is not None) is fast
    if got is not None:
        for name in ONE_CASE_FIELDS:
            _same_field(name, getattr(got, name), getattr(general, name))


def test_a_linear_law_is_never_out_of_range() -> None:
    # collect_warnings skips LinearTemperatureLaw.out_of_range: it holds no True anywhere.
    law = LinearTemperatureLaw(slope=-0.0044, at_0c=0.58)
    temps = np.array([-1e300, -273.15, -40.0, 0.0, 25.0, 1e300, math.inf, -math.inf, math.nan])
    assert not np.any(law.out_of_range(temps))
    assert not np.any(law.out_of_range(temps.reshape(3, 3)))


@pytest.mark.parametrize("load_inertia", [5.0, np.array([5.0, 80.0])])
def test_one_temperature_findings_carry_the_broadcast_temperature(load_inertia: Any) -> None:
    # The method's findings at one temperature (one case, or a batch of parameters at one
    # temperature) carry the temperature as the general path's broadcast and flat index
    # give it. A short stop time makes every case report one (stop_time).
    params = DynamicParameters(load_inertia, stop_time=1e-3, rolloff=Rolloff(0.5, 0.0039))
    prediction = predict(paper_system(), [-40.0], ["dynamic"], dynamics=params)
    solution = prediction.solutions["dynamic"]
    own = solution.findings()
    assert len(own) >= np.size(load_inertia)  # at least a stop_time finding per case
    flat = np.broadcast_to(prediction.temperatures, solution.deployment_time.shape).ravel()
    expected = [ModelWarning(code, message, float(flat[i]), "dynamic") for code, message, i in own]
    got = [w for w in prediction.warnings if w.method == "dynamic"]
    assert got == expected
    assert all(type(w.temperature_C) is float for w in got)


@pytest.mark.parametrize(
    "value",
    [
        np.asarray(1.0),
        np.array([0.9]),
        np.array([[math.nan]]),
        np.array([1.0, 1.0]),
        np.array([1.0, 0.8]),
        np.zeros(0),
    ],
    ids=str,
)
def test_differs_is_any_not_equal(value: np.ndarray) -> None:
    assert problem_module._differs(value, 1.0) is bool(np.any(value != 1.0))


@pytest.mark.parametrize("angle", [-1e-12, 0.0, 1.0, 1.57, 2.0, math.nan])
def test_one_case_initial_angle_check_is_the_array_test(angle: float) -> None:
    # dynamic_problem's start-angle test, on the numbers for one case, refuses exactly
    # where the array test any(start < 0) or any(start >= travel) does (travel 1.57 rad;
    # NaN passes both).
    system = paper_system()
    refused = bool(np.any(np.asarray(angle) < 0.0) or np.any(np.asarray(angle) >= 1.57))
    params = DynamicParameters(5.0, initial_angle=angle, stop_time=1e-3)
    if refused:
        with pytest.raises(ModelDomainError, match="initial.angle"):
            predict(system, [25.0], ["dynamic"], dynamics=params)
    else:
        temps = np.array([25.0])
        ecd = system.ecd.at(temps)
        base, fs = build_problem(system, ecd, temps)
        problem = dynamic_problem(system, ecd, temps, base, fs, params)
        assert problem.initial_angle.tobytes() == np.array([angle]).tobytes()


def _with_load(**changes: Any) -> Any:
    system = paper_system()
    return replace(system, load=replace(system.load, **changes))


BUILD_ONE_CASE: list[tuple[str, Any, Any]] = [
    ("paper", paper_system(), [-40.0]),
    ("scalar temperature", paper_system(), 25.0),
    ("two axes", paper_system(), [[100.0]]),
    (
        "warm spring",
        _with_load(spring=LinearSpring(3.7, 1.6, temperature_coefficient=-2e-3)),
        [80.0],
    ),
    ("array travel", _with_load(travel=np.array([1.57])), [25.0]),
    ("overflowing torque", _with_load(spring=LinearSpring(1e308, 1.6, 0.01)), [100.0]),
    ("NaN temperature", paper_system(), [math.nan]),
    ("two temperatures", paper_system(), [-40.0, 100.0]),
    # FS_T: a table law, an array parameter (the array paths), a negative value, and an
    # overflowing law (the array path, with NumPy's warning).
    (
        "friction table",
        _with_load(system_friction=TabulatedTemperatureLaw((-20.0, 60.0), (0.6, 0.3))),
        [25.0],
    ),
    (
        "friction law array",
        _with_load(system_friction=LinearTemperatureLaw(np.array([-0.0044]), 0.58)),
        25.0,
    ),
    ("negative friction", _with_load(system_friction=LinearTemperatureLaw(-0.0044, 0.3)), [100.0]),
    ("overflowing friction", _with_load(system_friction=LinearTemperatureLaw(1e308, 0.0)), [100.0]),
]


@pytest.mark.parametrize(
    ("system", "temperature"),
    [case[1:] for case in BUILD_ONE_CASE],
    ids=[case[0] for case in BUILD_ONE_CASE],
)
def test_one_case_build_problem_is_the_general_one(
    system: Any, temperature: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    # build_problem's one-case shortcuts (a linear spring's breakpoints in floats packed
    # into one array; any spring's arrays packed) against QuasiStaticProblem(...) on the
    # same inputs: the problem and FS_T bit for bit, read-only flags included.
    temps = np.asarray(temperature, dtype=float)
    with np.errstate(over="ignore"):  # the overflowing case (the array path's warning)
        ecd = system.ecd.at(temps)
        got, got_fs = build_problem(system, ecd, temps)
        monkeypatch.setattr(LinearSpring, "one_case_breakpoints", lambda *args: None)
        half, half_fs = build_problem(system, ecd, temps)  # the arrays packed
        monkeypatch.setattr(deployment_module, "one_case_problem", lambda *args: None)
        general, general_fs = build_problem(system, ecd, temps)
    for problem, fs in ((got, got_fs), (half, half_fs)):
        _same_field("system_friction", fs, general_fs)
        assert type(problem) is QuasiStaticProblem
        for name in ONE_CASE_FIELDS:
            _same_field(name, getattr(problem, name), getattr(general, name))


def test_linear_spring_one_case_breakpoints_decline() -> None:
    # Floats only, finite torques only: anything else is the array path's.
    spring = LinearSpring(3.7, 1.6)
    assert spring.one_case_breakpoints(1.57, 25.0) == ([0.0, 1.57], [3.7, 1.6])
    assert spring.one_case_breakpoints(np.float64(1.57), 25.0) is None
    assert LinearSpring(np.array(3.7), 1.6).one_case_breakpoints(1.57, 25.0) is None
    assert LinearSpring(1e308, 1.6, 0.01).one_case_breakpoints(1.57, 125.0) is None


def _balance(values: list[float | None], shape: tuple[int, ...]) -> EnergyBalance:
    arrays = [None if v is None else np.full(shape, v, dtype=float) for v in values]
    return EnergyBalance(*arrays)  # type: ignore[arg-type]


ENERGY_CASES: list[tuple[str, list[float | None]]] = [
    # (label, the eleven terms in field order)
    ("closed", [2.0, 0.5, 1.5, 0.7, 0.0, 0.1, 0.2, 0.0, None, None, None]),
    ("open", [2.0, 0.5, 1.2, 0.7, 0.0, 0.1, 0.2, 3e-3, None, None, None]),
    ("gravity and mesh", [2.0, 0.5, 1.2, 0.7, 0.0, 0.1, 0.2, 0.0, 0.3, 0.05, 1e-3]),
    ("nothing moved", [0.0, 0.0, 0.0, -0.0, 0.0, 0.0, 0.0, 0.0, None, None, None]),
    ("infinite", [math.inf, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, None, None, None]),
    ("inf - inf", [math.inf, 0.0, math.inf, 0.0, 0.0, 0.0, 0.0, 0.0, None, None, None]),
    ("NaN", [math.nan, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, None, None, None]),
    ("negative", [-1.0, 0.25, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, None, None]),
]


@pytest.mark.parametrize("shape", [(), (1,), (1, 1), (2,)])
@pytest.mark.parametrize(
    "terms",
    [case[1] for case in ENERGY_CASES],
    ids=[case[0] for case in ENERGY_CASES],
)
def test_one_case_energy_error_is_the_array_one(
    terms: list[float | None], shape: tuple[int, ...]
) -> None:
    # EnergyBalance.error (one case summed in floats) against the NumPy expressions on
    # the terms' arrays: the same bits, shape, dtype and writeable array, for one case or
    # a batch, finite sums or not.
    balance = _balance(terms, shape)
    with np.errstate(invalid="ignore"):  # inf - inf, as in the general path
        got = balance.error
        supplied, accounted = balance.supplied, balance.accounted
        scale = np.maximum(np.abs(supplied), np.abs(accounted))
        moved = scale > 0.0
        general = np.where(moved, (supplied - accounted) / np.where(moved, scale, 1.0), 0.0)
    _same_field("error", got, general)


def test_energy_terms_are_the_balance_fields() -> None:
    # The float path sums the terms it names: a field added to EnergyBalance fails here.
    assert list(_TERMS) == [f.name for f in fields(EnergyBalance)]


@pytest.mark.parametrize("damping", [0.0, math.inf, math.nan])
def test_one_case_kloss_findings_leave_a_zero_or_odd_damping_to_numpy(damping: float) -> None:
    # Eq. 1's BECD of 0 (a division by zero), inf or NaN: the one-case findings hand the
    # case to the general path, whose answer (and NumPy's warnings) they give.
    params = DynamicParameters(load_inertia=5.0, rolloff=Rolloff(60.0, 0.0039))
    solution = predict(paper_system(), [25.0], ["dynamic"], dynamics=params).solutions["dynamic"]
    problem = replace(solution.problem, damping_rate=np.array([damping]))  # type: ignore[attr-defined]
    result = solution.result  # type: ignore[attr-defined]
    error = np.array([0.0])
    with np.errstate(divide="ignore", invalid="ignore"):
        assert _findings(problem, result, error) == _batch_findings(problem, result, error)


KLOSS_LAWS: list[tuple[Any, Any, Any, Any, float]] = [
    # (T_peak, omega_peak_ref, alpha, T_ref, T): floats, 0-d, one-element and integer arrays
    (0.13, 2000.0, 0.0039, 25.0, 125.0),
    (np.asarray(6.5e-4), 10.0, 0.00392, 25.0, 20.0),
    (np.array([1e-3]), np.array([[60.0]]), np.array([0.0039]), 20.0, -40.0),
    (np.array([2]), np.array(7), 0.0, np.array([25]), 80.0),
    (1e300, 1e300, 0.0039, 25.0, 25.0),  # p**2 overflows: NumPy's answer (inf, warned)
    (0.13, 0.0, 0.0039, 25.0, 25.0),  # p = 0: the derivative's guard gives 0
    (0.13, 2000.0, 0.0039, 25.0, math.nan),
    (0.13, 2000.0, -0.01, 25.0, 125.0),  # p = 0 at T (alpha (T - T_ref) = -1)
]


@pytest.mark.parametrize(("t_peak", "p_ref", "alpha", "t_ref", "temperature"), KLOSS_LAWS)
def test_kloss_low_speed_floats_are_the_physics_functions(
    t_peak: Any, p_ref: Any, alpha: Any, t_ref: Any, temperature: float
) -> None:
    # The one-case findings' peak speed and zero-speed slope (the physics functions on
    # floats) against KlossEddy.peak_speed and rolloff.kloss_speed_derivative on arrays:
    # bit for bit where the floats answer; None (the NumPy path) where a value is not
    # finite or the peak speed is 0.
    eddy = KlossEddy(t_peak, p_ref, alpha, t_ref)
    with np.errstate(all="ignore"):
        peak = float(eddy.peak_speed(temperature).item())
        slope = np.asarray(rolloff.kloss_speed_derivative(0.0, eddy.peak_torque, peak)).item()
    got = _kloss_low_speed(eddy, temperature)
    finite = math.isfinite(peak) and math.isfinite(slope) and peak != 0.0
    assert (got is not None) is finite
    if got is not None:
        assert type(got[0]) is float
        assert type(got[1]) is float
        assert np.float64(got[0]).tobytes() == np.float64(peak).tobytes()
        assert np.float64(got[1]).tobytes() == np.float64(slope).tobytes()


@pytest.mark.parametrize("temperatures", [[20.0], [-40.0, 25.0, 100.0]])
def test_the_dynamic_solution_is_the_dataclass_one(temperatures: list[float]) -> None:
    # solution_from_result fills the DynamicSolution's __dict__ itself: every field of the
    # class is set (a field added to it and not there fails here), with the values the
    # dataclass's __init__ and __post_init__ make of the same arguments.
    params = DynamicParameters(load_inertia=5.0, rolloff=Rolloff(60.0, 0.0039))
    prediction = predict(paper_system(), temperatures, ["dynamic"], dynamics=params)
    fast = prediction.solutions["dynamic"]
    assert type(fast) is DynamicSolution
    names = [f.name for f in fields(DynamicSolution)]
    assert sorted(vars(fast)) == sorted(names)
    given = {name: getattr(fast, name) for name in names if name != "solved"}
    general = DynamicSolution(**given)
    for name in names:
        _same_field(name, getattr(fast, name), getattr(general, name))


@pytest.mark.parametrize(
    ("rotor", "gearbox", "ratio"),
    [
        (2e-7, 0.0, np.asarray(380.0)),
        (1e-6, 3e-7, np.asarray(120.0)),
        (0.0, 0.0, np.asarray(1.0)),
        (1e-6, 0.0, np.array([380.0])),  # the ratio's axis: the NumPy path
        (np.array([1e-6]), 0.0, np.asarray(380.0)),  # an array inertia: the NumPy path
        (1e300, 0.0, np.asarray(1e10)),  # overflows: NumPy's answer (and warning)
    ],
)
def test_one_case_reflected_inertia_is_the_physics_function(
    rotor: Any, gearbox: Any, ratio: np.ndarray
) -> None:
    # dynamic_problem's float J N N against mechanics.reflect_inertia_to_input on the same
    # inputs: the same number (bit for bit), which DynamicProblem reads as the same 0-d
    # array; None where the answer would have another shape or is not finite.
    params = DynamicParameters(5.0, rotor_inertia=rotor, gearbox_inertia=gearbox)
    with np.errstate(over="ignore"):
        general = mechanics.reflect_inertia_to_input(
            np.asarray(rotor, float) + np.asarray(gearbox, float), ratio
        )
    got = problem_module._one_case_reflected(params, ratio)
    fast = type(rotor) is float and ratio.shape == () and bool(np.isfinite(general))
    assert (got is not None) is fast
    if got is not None:
        assert type(got) is float
        assert general.shape == ()
        assert np.asarray(got, dtype=float).tobytes() == general.tobytes()


@pytest.mark.parametrize(
    ("temperatures", "peak_speed", "alpha"),
    [
        ([25.0], 60.0, 0.0039),
        ([-300.0], 60.0, 0.0039),  # 1 + alpha (T - T_ref) < 0: refused
        ([25.0 - 1.0 / 0.0039], 60.0, 0.0039),  # about 0 at T
        (25.0, 60.0, -0.01),
        ([125.0], 60.0, -0.01),  # exactly 0 at T: refused
        ([math.nan], 60.0, 0.0039),  # NaN is not <= 0
        ([100.0], 1e308, 1e10),  # overflows: the array test
        ([25.0], np.array([60.0]), 0.0039),  # an array parameter: the array test
        ([-300.0, 25.0], 60.0, 0.0039),  # two temperatures: the array test
    ],
)
def test_one_case_peak_speed_check_is_the_array_test(
    temperatures: Any, peak_speed: Any, alpha: float
) -> None:
    # The roll-off domain check against the array test it replaces.
    temps = np.asarray(temperatures, dtype=float)
    with np.errstate(over="ignore"):
        peaks = rolloff.peak_speed_at(temps, peak_speed, alpha, 25.0)
        expected = bool(np.any(peaks <= 0.0))
        assert problem_module._peak_speed_not_positive(temps, peak_speed, alpha, 25.0) is expected


def test_one_case_build_problem_leaves_an_overflowing_total_friction_to_numpy() -> None:
    # FECD_T + FS_T = inf: the float path declines, and the array path answers with
    # NumPy's overflow warning, as before the shortcut.
    temps = np.array([25.0])
    spring = paper_system().load.spring
    assert isinstance(spring, LinearSpring)
    paper = paper_system()  # the usual case: the float path answers
    one = deployment_module._one_case_linear_problem(paper, spring, paper.ecd.at(temps), temps)
    assert one is not None
    system = _with_load(system_friction=LinearTemperatureLaw(0.0, 1e308))
    ecd = replace(system.ecd.at(temps), ecd_friction=np.array([1e308]))
    assert deployment_module._one_case_linear_problem(system, spring, ecd, temps) is None
    with pytest.warns(RuntimeWarning, match="overflow"):
        problem, _ = build_problem(system, ecd, temps)
    assert problem.friction.tolist() == [math.inf]


@pytest.mark.parametrize(
    ("slope", "at_0c", "temperature"),
    [(-0.0044, 0.58, 25.0), (1e-5, 4e-4, -40.0), (0.0, 0.0, 100.0), (2.5, -0.1, math.nan)],
)
def test_linear_law_at_one_temperature_is_the_array_law(
    slope: float, at_0c: float, temperature: float
) -> None:
    # LinearTemperatureLaw.one_case against its NumPy evaluation: bit for bit where
    # finite, None (the array path) where not or for an array parameter.
    law = LinearTemperatureLaw(slope, at_0c)
    general = law(np.asarray(temperature))
    got = law.one_case(temperature)
    assert (got is not None) is bool(np.isfinite(general))
    if got is not None:
        assert np.float64(got).tobytes() == general.tobytes()
    assert LinearTemperatureLaw(np.asarray(slope), at_0c).one_case(temperature) is None


@pytest.mark.parametrize("temperature", [-40.0, 25.0, 68.0, 100.0])
def test_one_case_negative_friction_warning_is_the_batch_one(temperature: float) -> None:
    # FS_T = 0.3 - 0.0044 T is negative above 68 degC: a one-case prediction reports the
    # negative_friction findings the same as that case in a batch (its one-number test
    # skips the array test only where the value is not negative).
    system = _with_load(system_friction=LinearTemperatureLaw(-0.0044, 0.3))
    one = predict(system, [temperature], ["paper"]).warnings
    batch = predict(system, [temperature, 20.0], ["paper"]).warnings
    expected = [w for w in batch if w.code == "negative_friction"]
    assert [w for w in one if w.code == "negative_friction"] == expected
    assert bool(expected) is (temperature > 0.3 / 0.0044)


SMALL_VALUES: list[Any] = [
    0.0,
    -0.0,
    3.0,
    -0.004,
    math.nan,
    math.inf,
    np.asarray(0.0),
    np.array([-1.0]),
    np.array([[2.0]]),
    np.array([0.0, -1.0]),
    np.array([1, 0]),  # integers, as asarray(dtype=float) reads them
    np.array([math.nan, 1.0]),
]


@pytest.mark.parametrize("value", SMALL_VALUES, ids=repr)
def test_problem_value_tests_are_the_array_tests(value: Any) -> None:
    # dynamic_problem's one-number tests against the array expressions they replace.
    assert problem_module._differs(value, 0.0) is bool(np.any(np.asarray(value) != 0.0))
    assert problem_module._below_zero(value) is bool(np.any(np.asarray(value, float) < 0.0))
