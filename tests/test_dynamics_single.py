"""The single-case path (ecdsim.dynamics.single) against the vectorised event loop.

Every case is solved twice: by ``solve_dynamic`` as it dispatches (the single-case path,
asserted to have run) and with the path switched off (``single.ENABLED = False``: the
vectorised loop of ecdsim.dynamics.solver, asserted not to have taken it). The two run
the same IEEE operations on the same operands (the same compiled kernel, NumPy's expm1
for the temperature), so every field must agree exactly: integers, booleans, statuses
and event kinds, and floats bit for bit (NaN where NaN). The vectorised loop is the
reference here; its own correctness is held by the other dynamics tests against scipy.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from ecdsim.config import load_config
from ecdsim.deployment import build_problem
from ecdsim.dynamics import DynamicParameters, DynamicProblem, Rolloff, Thermal, single
from ecdsim.dynamics.problem import dynamic_problem
from ecdsim.dynamics.result import STATUSES, DynamicResult
from ecdsim.dynamics.solver import solve_dynamic
from ecdsim.model import (
    DeploymentSystem,
    Ecd,
    Gearbox,
    HighSpeedDamper,
    LinearSpring,
    LinearTemperatureLaw,
    Load,
    TabulatedSpring,
)
from tests.conftest import paper_system

ROOT = Path(__file__).resolve().parent.parent
MSL_BRAKE = ROOT / "validation" / "configs" / "msl_eddy_current_brake.toml"
PAPER_DYNAMIC = ROOT / "examples" / "paper_cc16_dynamic.toml"


def _system(
    damping: float = 1e-3,
    coefficient: float = -0.004,
    ecd_friction: float = 0.0,
    system_friction: float = 0.1,
    start_torque: float = 2.0,
    end_torque: float = 1.0,
    travel: float = 1.5,
    ratio: float = 20.0,
    lost_motion: float = 0.0,
) -> DeploymentSystem:
    damper = HighSpeedDamper(
        damping_rate=damping,
        coulomb_friction=ecd_friction,
        damping_temperature_coefficient=coefficient,
    )
    gearbox = Gearbox(ratio=ratio, coulomb_friction=0.0, damping_rate=0.0, lost_motion=lost_motion)
    load = Load(
        spring=LinearSpring(start_torque, end_torque),
        travel=travel,
        system_friction=LinearTemperatureLaw(0.0, system_friction),
    )
    return DeploymentSystem(Ecd(damper, gearbox), load, name="single")


def _problem(
    system: DeploymentSystem, params: DynamicParameters, temperature: float = 25.0
) -> DynamicProblem:
    """The one-case dynamic problem, built as predict() builds it."""
    temps = np.asarray([temperature])
    ecd = system.ecd.at(temps)
    base, fs = build_problem(system, ecd, temps)
    return dynamic_problem(system, ecd, temps, base, fs, params)


def _solve(
    problem: DynamicProblem, record: bool, fast: bool, monkeypatch: pytest.MonkeyPatch
) -> DynamicResult:
    """solve_dynamic on the path asked for; fails if the dispatch took the other one."""
    calls: list[int] = []
    original = single.solve

    def spy(p: DynamicProblem, record: bool = True) -> DynamicResult:
        calls.append(1)
        return original(p, record=record)

    with monkeypatch.context() as patch:
        patch.setattr(single, "solve", spy)
        patch.setattr(single, "ENABLED", fast)
        result = solve_dynamic(problem, record=record)
    assert calls == ([1] if fast else []), "the single-case path was not taken as asked"
    return result


def _same(a: Any, b: Any, where: str) -> None:
    """Exactly equal: arrays in dtype, shape and every bit (NaN matching NaN)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        assert a.dtype == b.dtype, f"{where}: dtype {a.dtype} != {b.dtype}"
        assert a.shape == b.shape, f"{where}: shape {a.shape} != {b.shape}"
        if a.dtype.kind == "f":
            # Bit for bit: the same operations on the same operands (module docstring).
            assert np.array_equal(a, b, equal_nan=True), f"{where}: {a} != {b}"
        else:
            assert np.array_equal(a, b), f"{where}: {a} != {b}"
    elif isinstance(a, float) and isinstance(b, float) and math.isnan(a):
        assert math.isnan(b), where
    else:
        assert type(a) is type(b), f"{where}: {type(a)} != {type(b)}"
        assert a == b, f"{where}: {a!r} != {b!r}"


def _assert_same_result(fast: DynamicResult, slow: DynamicResult) -> None:
    """Every field of the two results, the energy balance, events and trajectory data."""
    for f in dataclasses.fields(DynamicResult):
        a, b = getattr(fast, f.name), getattr(slow, f.name)
        if f.name in ("energy", "events"):
            for g in dataclasses.fields(a):
                _same(getattr(a, g.name), getattr(b, g.name), f"{f.name}.{g.name}")
        elif f.name == "trajectory":
            assert (a is None) == (b is None)
            if a is not None:
                _assert_same_trajectory(fast, slow)
        else:
            _same(a, b, f.name)


def _assert_same_trajectory(fast: DynamicResult, slow: DynamicResult) -> None:
    a, b = fast.trajectory, slow.trajectory
    assert a is not None
    assert b is not None
    assert a.closed == []  # every segment of the subset is integrated
    assert b.closed == []
    assert len(a.integrated) == len(b.integrated)
    for ra, rb in zip(a.integrated, b.integrated, strict=True):
        for name in ("case", "start_time", "duration", "start_angle", "direction"):
            _same(getattr(ra, name), getattr(rb, name), f"record.{name}")
        local = np.linspace(0.0, ra.duration, 7)
        _same(ra.solution(local), rb.solution(local), "record.solution")
    for name in ("initial", "final"):
        for k, (x, y) in enumerate(zip(getattr(a, name), getattr(b, name), strict=True)):
            _same(x, y, f"trajectory.{name}[{k}]")
    for g in dataclasses.fields(a):
        if g.name not in ("closed", "integrated", "initial", "final", "eddy"):
            _same(getattr(a, g.name), getattr(b, g.name), f"trajectory.{g.name}")
    assert type(a.eddy) is type(b.eddy)
    for g in dataclasses.fields(a.eddy):  # type: ignore[arg-type]
        _same(getattr(a.eddy, g.name), getattr(b.eddy, g.name), f"eddy.{g.name}")
    # The sampled time series (about 50 times over the run) and the CSV and JSON forms.
    ta, tb = fast.sample(n_points=51), slow.sample(n_points=51)
    for g in dataclasses.fields(ta):
        _same(getattr(ta, g.name), getattr(tb, g.name), f"sample.{g.name}")
    assert fast.timeseries_csv(n_points=51) == slow.timeseries_csv(n_points=51)
    assert fast.to_dict() == slow.to_dict()


def _compare(problem: DynamicProblem, monkeypatch: pytest.MonkeyPatch) -> DynamicResult:
    """Both paths, recorded and not; returns the single-case path's recorded result."""
    assert single.eligible(problem)
    fast = _solve(problem, True, True, monkeypatch)
    _assert_same_result(fast, _solve(problem, True, False, monkeypatch))
    _assert_same_result(
        _solve(problem, False, True, monkeypatch), _solve(problem, False, False, monkeypatch)
    )
    return fast


ROLLOFF = Rolloff(60.0, 0.0039)
HEAT = Thermal(0.2, 100.0)
SMALL = Rolloff(5.0, 0.0039)  # a peak speed the toy systems run beyond
WARM = Thermal(0.2, 100.0, initial_rotor_rise=30.0)


def _params(load_inertia: float, **fields: Any) -> DynamicParameters:
    return DynamicParameters(load_inertia, **fields)


def _falling(system_friction: float, ecd_friction: float = 0.0) -> DeploymentSystem:
    """A spring whose torque crosses zero at 0.5 rad (T = 0.5 - phi)."""
    return _system(
        start_torque=0.5,
        end_torque=-1.0,
        system_friction=system_friction,
        ecd_friction=ecd_friction,
    )


def _pushing_back() -> DeploymentSystem:
    """A spring that pulls back everywhere (-0.5 to -1 N*m), against 0.1 N*m friction."""
    return _system(start_torque=-0.5, end_torque=-1.0, system_friction=0.1)


def _pulling_back() -> DeploymentSystem:
    """A spring whose torque crosses zero at 0.375 rad and pulls back beyond it."""
    return _system(start_torque=1.0, end_torque=-3.0, system_friction=0.05)


# name -> (system, params, temperature): each aims at one branch of the event loop.
CASES: dict[str, tuple[Callable[[], DeploymentSystem], DynamicParameters, float]] = {
    "paper roll-off + heating": (paper_system, _params(5.0, rolloff=ROLLOFF, thermal=HEAT), 25.0),
    "paper roll-off only, cold": (paper_system, _params(5.0, rolloff=ROLLOFF), -40.0),
    "paper heating only, hot": (paper_system, _params(5.0, thermal=Thermal(0.05)), 100.0),
    "rebound e=0.3 to settle": (_system, _params(0.2, restitution=0.3, rolloff=SMALL), 25.0),
    "rebound e=0.7 with heating": (
        _system,
        _params(0.2, restitution=0.7, rolloff=SMALL, thermal=Thermal(0.01)),
        25.0,
    ),
    "stall short of the end": (
        lambda: _falling(0.6),
        _params(0.2, initial_angle=0.3, initial_speed=1.0, thermal=Thermal(0.01)),
        25.0,
    ),
    "stick with static friction": (
        lambda: _falling(0.3, ecd_friction=1e-3),
        _params(
            0.2,
            initial_angle=0.3,
            initial_speed=1.7,
            static_friction_factor=1.5,
            system_static_friction_factor=1.6,
            rolloff=SMALL,
        ),
        25.0,
    ),
    "zero speed, breakaway backward": (
        lambda: _falling(0.05),
        _params(0.2, initial_angle=0.5, initial_speed=1.0, rolloff=SMALL, thermal=Thermal(0.01)),
        25.0,
    ),
    "breakaway backward, start stop latch": (
        _pulling_back,
        _params(0.5, initial_angle=1.2, thermal=Thermal(0.02)),
        25.0,
    ),
    "start stop rebound": (
        _pulling_back,
        _params(0.5, initial_angle=1.2, restitution=0.5, rolloff=SMALL),
        25.0,
    ),
    # Lightly damped: the swing passes the equilibrium (0.675 rad) and turns round.
    "swing past the equilibrium": (
        lambda: _system(damping=1e-5, start_torque=1.0, end_torque=-1.0, system_friction=0.1),
        _params(0.2, rolloff=Rolloff(500.0, 0.0039)),
        25.0,
    ),
    "held on the start stop": (_pushing_back, _params(0.5, initial_angle=1.0, rolloff=SMALL), 25.0),
    "start stop rebounds, held": (
        _pushing_back,
        _params(0.5, initial_angle=1.0, restitution=0.5, rolloff=SMALL, thermal=Thermal(0.01)),
        25.0,
    ),
    "backward launch on the start stop": (
        _pushing_back,
        _params(0.5, initial_speed=-1.0, rolloff=SMALL),
        25.0,
    ),
    "creep to equilibrium": (
        lambda: _system(damping=0.05, start_torque=1.0, end_torque=-1.0, system_friction=0.0),
        _params(0.01, rolloff=Rolloff(500.0, 0.0039)),
        25.0,
    ),
    "stop time": (_system, _params(0.2, stop_time=0.05, thermal=HEAT), 25.0),
    # The drive is zero (spring = friction) and the speed decays without end: no event.
    "horizon": (
        lambda: _system(start_torque=0.1, end_torque=0.1, system_friction=0.1),
        _params(0.2, initial_speed=0.5, rolloff=SMALL),
        25.0,
    ),
    "initial speed": (
        _system,
        _params(0.2, initial_speed=3.0, restitution=0.5, rolloff=SMALL, thermal=Thermal(0.01)),
        25.0,
    ),
    "event limit": (_system, _params(0.2, restitution=0.7, max_events=3, rolloff=SMALL), 25.0),
    "warm start": (paper_system, _params(5.0, rolloff=ROLLOFF, thermal=WARM), 25.0),
    "heating, c = 0": (
        lambda: _system(coefficient=0.0),
        _params(0.2, thermal=Thermal(0.01, 50.0)),
        25.0,
    ),
}


@pytest.mark.parametrize("name", list(CASES))
def test_single_case_path_is_the_vectorised_loop(
    name: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    system, params, temperature = CASES[name]
    _compare(_problem(system(), params, temperature), monkeypatch)


def _names(result: DynamicResult) -> set[str]:
    return set(result.events.names())


def test_the_cases_reach_every_branch(monkeypatch: pytest.MonkeyPatch) -> None:
    # The comparisons above mean something only where the branches run: each named case
    # must end as its name says (statuses and events of the vectorised path).
    seen: dict[str, DynamicResult] = {}
    for name, (system, params, temperature) in CASES.items():
        seen[name] = _solve(_problem(system(), params, temperature), False, False, monkeypatch)

    def status(name: str) -> str:
        return STATUSES[int(seen[name].status.ravel()[0])]

    assert status("paper roll-off + heating") == "latched"
    assert status("rebound e=0.3 to settle") == "settled"
    assert int(seen["rebound e=0.3 to settle"].impacts.ravel()[0]) > 3
    assert status("rebound e=0.7 with heating") in ("settled", "stuck")
    assert status("stall short of the end") == "stuck"
    assert _names(seen["stall short of the end"]) >= {"zero_speed", "stick"}
    # Held by static friction only: the spring's torque where it stuck exceeds the kinetic
    # friction (the spring runs 0.5 -> -1 N*m over 1.5 rad: T = 0.5 - phi).
    held = seen["stick with static friction"]
    assert status("stick with static friction") == "stuck"
    kinetic = float(held.energy.friction_dissipation.ravel()[0]) / float(
        held.final_angle.ravel()[0] - 0.3
    )
    assert abs(0.5 - float(held.stuck_angle.ravel()[0])) > kinetic
    assert seen["zero speed, breakaway backward"].events.names()[1:3] == ["zero_speed", "breakaway"]
    assert _names(seen["breakaway backward, start stop latch"]) >= {"breakaway", "start_stop"}
    assert int(seen["breakaway backward, start stop latch"].impacts.ravel()[0]) == 0
    # The rebound off the start stop swings past the equilibrium (T = 1 - 8 phi / 3 = 0.05
    # at 0.356 rad) and turns round at a finite time (zero speed, not creep), then swings
    # on until it sticks where the spring is within the friction of 0.05 N*m.
    rebound = seen["start stop rebound"]
    assert "start_stop" in _names(rebound)
    assert int(rebound.impacts.ravel()[0]) >= 1
    assert status("start stop rebound") == "stuck"
    assert "creep" not in _names(rebound)
    assert abs(1.0 - 8.0 / 3.0 * float(rebound.stuck_angle.ravel()[0])) <= 0.05
    # Past the equilibrium the speed reaches zero in finite time: no creep (the spring
    # there, below -0.1 N*m, sends it back), until it sticks within the friction.
    swing = seen["swing past the equilibrium"]
    assert swing.events.names()[1:4] == ["breakaway", "zero_speed", "breakaway"]
    assert status("swing past the equilibrium") == "stuck"
    # At rest on the start stop with the spring pulling back: the stop holds it.
    for name in ("held on the start stop", "start stop rebounds, held"):
        assert seen[name].events.names()[-2:] == ["start_stop", "stick"]
        assert status(name) == "stuck"
        assert float(seen[name].final_angle.ravel()[0]) == 0.0
        assert float(np.min(seen[name].events.angle)) == 0.0
    assert int(seen["start stop rebounds, held"].impacts.ravel()[0]) >= 2
    launch = seen["backward launch on the start stop"]
    assert launch.events.names() == ["release", "start_stop", "stick"]
    assert status("creep to equilibrium") == "creep"
    assert status("stop time") == "stop_time"
    assert status("horizon") == "horizon"
    assert status("event limit") == "event_limit"
    assert status("warm start") == "latched"
    warm = seen["warm start"]
    assert float(warm.max_damper_temperature.ravel()[0]) >= 25.0 + 30.0  # the warm start


@pytest.mark.parametrize("name", ["zero speed, breakaway backward", "start stop rebound"])
def test_backward_breakaways_move_backward(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    # Where the drive is negative at rest the breakaway runs backward: the angle of the
    # event after it is smaller (on the single-case path itself).
    system, params, temperature = CASES[name]
    result = _solve(_problem(system(), params, temperature), False, True, monkeypatch)
    k = result.events.names().index("breakaway")
    assert result.events.angle[k + 1] < result.events.angle[k]


@pytest.mark.parametrize("seed", range(12))
def test_random_single_cases_agree(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    # Seeded draws across the subset: laws, heating, restitution, friction, start state.
    rng = np.random.default_rng(seed)
    system = _system(
        damping=float(rng.uniform(2e-4, 5e-3)),
        coefficient=float(rng.choice([-0.004, 0.0, 0.002])),
        ecd_friction=float(rng.uniform(0.0, 2e-3)),
        system_friction=float(rng.uniform(0.0, 0.8)),
        start_torque=float(rng.uniform(0.5, 3.0)),
        end_torque=float(rng.uniform(-1.0, 2.0)),
        travel=float(rng.uniform(0.5, 2.0)),
        ratio=float(rng.uniform(5.0, 50.0)),
    )
    law = int(rng.integers(3))  # roll-off, heating, both
    params = DynamicParameters(
        load_inertia=float(rng.uniform(0.05, 1.0)),
        rotor_inertia=float(rng.uniform(0.0, 1e-5)),
        static_friction_factor=float(rng.uniform(1.0, 1.5)),
        restitution=float(rng.choice([0.0, 0.3, 0.7])),
        initial_angle=float(rng.uniform(0.0, 0.3)),
        initial_speed=float(rng.choice([0.0, rng.uniform(-1.0, 3.0)])),
        rolloff=None if law == 1 else Rolloff(float(rng.uniform(2.0, 50.0)), 0.0039),
        thermal=None if law == 0 else Thermal(float(rng.uniform(0.005, 0.5))),
        stop_time=float(rng.choice([math.inf, rng.uniform(0.05, 2.0)])),
        max_events=int(rng.choice([10_000, 4])),
    )
    _compare(_problem(system, params, float(rng.uniform(-40.0, 100.0))), monkeypatch)


def _from_config(path: Path) -> DynamicProblem:
    config = load_config(path)
    params = config.spec.dynamics()
    assert params is not None
    temperature = float(config.temperatures[0])
    return _problem(config.system, params, temperature)


def test_msl_brake_spin_down(monkeypatch: pytest.MonkeyPatch) -> None:
    # Issue 13's single case: roll-off and adiabatic heating, one segment to rest, 1 s.
    result = _compare(_from_config(MSL_BRAKE), monkeypatch)
    assert STATUSES[int(result.status.ravel()[0])] in ("stuck", "stop_time")


def test_paper_dynamic_example_with_rolloff_and_heating(monkeypatch: pytest.MonkeyPatch) -> None:
    # The benchmark's paper case: the dynamic example with roll-off and heating switched on.
    config = load_config(PAPER_DYNAMIC)
    params = config.spec.dynamics()
    assert params is not None
    params = dataclasses.replace(params, rolloff=ROLLOFF, thermal=HEAT)
    _compare(_problem(config.system, params, 25.0), monkeypatch)


def _ineligible() -> dict[str, DynamicProblem]:
    base = DynamicParameters(0.2, rolloff=Rolloff(5.0, 0.0039))
    two = _system()
    temps = np.asarray([25.0, 30.0])
    ecd = two.ecd.at(temps)
    problem, fs = build_problem(two, ecd, temps)
    spring = TabulatedSpring((0.0, 0.7, 1.5), (2.0, 1.6, 1.0))
    table = dataclasses.replace(_system(), load=dataclasses.replace(_system().load, spring=spring))
    return {
        "two cases": dynamic_problem(two, ecd, temps, problem, fs, base),
        "lost motion": _problem(_system(lost_motion=0.01), base),
        "linear law at ambient": _problem(_system(), DynamicParameters(0.2)),
        "Stribeck friction": _problem(_system(), dataclasses.replace(base, stribeck_speed=0.1)),
        "Radau": _problem(_system(), dataclasses.replace(base, integrator="Radau")),
        "tabulated spring": _problem(table, base),
        "two-node heating": _problem(
            _system(),
            DynamicParameters(0.2, thermal=Thermal(0.01, 10.0, housing_heat_capacity=1.0)),
        ),
    }


@pytest.mark.parametrize("name", list(_ineligible()))
def test_outside_the_subset_stays_vectorised(name: str) -> None:
    assert not single.eligible(_ineligible()[name])


def test_without_numba_the_vectorised_path_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    # ECDSIM_NUMBA=0 selects the NumPy integrator: no compiled kernel, no single path.
    problem = _problem(paper_system(), DynamicParameters(5.0, rolloff=ROLLOFF))
    monkeypatch.setenv("ECDSIM_NUMBA", "0")
    assert not single.eligible(problem)


def test_recorded_segments_carry_their_own_model(monkeypatch: pytest.MonkeyPatch) -> None:
    # Each recorded segment's model (built on first use) is the segment's, as the
    # vectorised path's integrate._InTemperature holds it: the same drive, stiffness,
    # inertia and temperature law.
    system, params, temperature = CASES["rebound e=0.3 to settle"]
    problem = _problem(system(), params, temperature)
    fast = _solve(problem, True, True, monkeypatch).trajectory
    slow = _solve(problem, True, False, monkeypatch).trajectory
    assert fast is not None
    assert slow is not None
    assert len(fast.integrated) > 2
    for a, b in zip(fast.integrated, slow.integrated, strict=True):
        ma, mb = a.solution.model, b.solution.model  # type: ignore[attr-defined]
        for name in ("inertia", "stiffness", "drive", "ratio", "ambient", "ambient_factor"):
            _same(getattr(ma, name), getattr(mb, name), f"model.{name}")


@pytest.mark.parametrize("law", ["linear", "kloss"])
def test_frozen_records_carry_every_field(law: str, monkeypatch: pytest.MonkeyPatch) -> None:
    # single._frozen builds the frozen records from their instance dictionaries, past
    # __init__: each must name every field (defaults included), and no class may have a
    # __post_init__ that would be skipped. A field added to one of these classes fails
    # here until the single-case path fills it in.
    rolloff = SMALL if law == "kloss" else None
    params = _params(0.2, restitution=0.3, rolloff=rolloff, thermal=Thermal(0.01))
    result = _solve(_problem(_system(), params), True, True, monkeypatch)
    data = result.trajectory
    assert data is not None
    assert len(data.integrated) > 2  # rebounds: several recorded segments
    steps = [record.solution.solution for record in data.integrated]  # type: ignore[attr-defined]
    laws = [data.eddy, data.integrated[0].solution.model.eddy]  # type: ignore[attr-defined]
    for built in (result, result.energy, result.events, data, *data.integrated, *steps, *laws):
        kind = type(built)
        assert dataclasses.is_dataclass(kind)
        assert kind.__dataclass_params__.frozen  # type: ignore[attr-defined]
        assert not hasattr(kind, "__post_init__"), kind
        assert set(vars(built)) == {f.name for f in dataclasses.fields(built)}, kind
    assert type(data.eddy).__name__ == ("KlossEddy" if law == "kloss" else "LinearEddy")


def test_positionally_built_records_keep_their_field_order() -> None:
    # single._segment and single._integrate build _Segment and _Step positionally (a
    # keyword call costs more): a reordered field would take another field's value.
    segment = [f.name for f in dataclasses.fields(single._Segment)]
    step = [f.name for f in dataclasses.fields(single._Step)]
    assert segment == [
        "direction",
        "torque",
        "length",
        "reach_kind",
        "kinetic",
        "drive",
        "speed0",
        "cap",
    ]
    assert step == [
        "kind",
        "duration",
        "x",
        "v",
        "damper_work",
        "peak_speed",
        "temperature",
        "peak_temperature",
    ]
