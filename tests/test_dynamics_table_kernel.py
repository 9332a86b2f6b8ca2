"""Spring tables crossed in one compiled call (``ecdsim.dynamics.compiled_table``).

A forward engaged segment with at least ``solver.TABLE_PIECES`` pieces ahead is integrated
piece after piece in compiled code, each breakpoint the REACH event of its piece. The
reference is the solver's own per-piece path (one event-loop pass per breakpoint: closed
form for linear damping, the integrator for roll-off and heating), selected here by
raising ``TABLE_PIECES`` beyond the table, and a scipy integration of the equations.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import pytest

from ecdsim.deployment import predict
from ecdsim.dynamics import DynamicParameters, Rolloff, Thermal, solver
from ecdsim.model import DeploymentSystem, TabulatedSpring
from tests import hand
from tests.conftest import paper_system, require
from tests.dynamics_reference import assert_energy_closes

# numba is in the test extra: without it this fails with the install command.
require("ecdsim.dynamics.compiled_table")


def _table(points: int, end_torque: float = hand.TE) -> DeploymentSystem:
    angles = np.linspace(0.0, hand.TRAVEL, points)
    torques = hand.TS - (hand.TS - end_torque) * (angles / hand.TRAVEL) ** 1.5
    base = paper_system()
    spring = TabulatedSpring(tuple(angles.tolist()), tuple(torques.tolist()))
    return DeploymentSystem(base.ecd, replace(base.load, spring=spring), name="table")


def _both(
    system: DeploymentSystem, params: DynamicParameters, monkeypatch: pytest.MonkeyPatch
) -> tuple[Any, Any]:
    """(compiled table path, per-piece path) results at +25 degC."""
    monkeypatch.setenv("ECDSIM_NUMBA", "1")
    fast = predict(system, [25.0], ["dynamic"], dynamics=params).solutions["dynamic"]
    monkeypatch.setattr(solver, "TABLE_PIECES", 10**9)
    slow = predict(system, [25.0], ["dynamic"], dynamics=params).solutions["dynamic"]
    return fast.result, slow.result  # type: ignore[attr-defined]


def _breakpoint_events(result: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    kinds = np.asarray(result.events.names())
    chosen = kinds == "breakpoint"
    return result.events.time[chosen], result.events.angle[chosen], result.events.speed[chosen]


def test_a_linear_table_deployment_matches_the_closed_form_pieces(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # 300 points, linear damping: the per-piece path is exact (closed form), the compiled
    # one integrates at the default rtol 1e-8. RODAS4's error on this smooth motion is
    # about 1e-11 in time and 1e-9 in speed (measured 2e-11 and 6e-10 at P = 1,000):
    # 1e-9 and 1e-7 bound them.
    fast, slow = _both(_table(300), DynamicParameters(load_inertia=5.0), monkeypatch)
    assert fast.status_names() == slow.status_names() == ["latched"]
    assert fast.deployment_time[0] == pytest.approx(slow.deployment_time[0], rel=1e-9)
    assert fast.arrival_speed[0] == pytest.approx(slow.arrival_speed[0], rel=1e-7)
    assert fast.max_speed[0] == pytest.approx(slow.max_speed[0], rel=1e-7)
    # Every breakpoint is logged, at its exact angle, at the same times and speeds.
    t_fast, a_fast, w_fast = _breakpoint_events(fast)
    t_slow, a_slow, w_slow = _breakpoint_events(slow)
    assert t_fast.size == t_slow.size == 298
    assert np.array_equal(a_fast, a_slow)
    assert np.allclose(t_fast, t_slow, rtol=1e-9, atol=0.0)
    assert np.allclose(w_fast, w_slow, rtol=1e-7, atol=0.0)
    # The spring work is that of the table, piece by piece (exact on both paths).
    assert fast.energy.spring_work[0] == pytest.approx(slow.energy.spring_work[0], rel=1e-12)
    assert_energy_closes(fast, 1e-8)
    # Time series from the one recorded multi-piece segment.
    times = np.linspace(0.0, float(slow.deployment_time[0]), 9)
    assert np.allclose(fast.sample(times).angle, slow.sample(times).angle, rtol=0, atol=1e-9)


def test_a_table_that_stalls_midway_creeps_to_the_same_angle(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # The spring falls below the friction before the end (end torque 0.2 N*m): the motion
    # approaches the angle where the table equals FECD + FS and never gets there (creep),
    # on a piece in the middle of the table. Both paths find that angle: the per-piece
    # closed form exactly; the compiled one stops at the creep threshold (1e-9 of the
    # speed scale), the displacement left then being below 1e-9 rad times J/B-scale
    # factors: 1e-8 rad bounds it.
    fast, slow = _both(
        _table(200, end_torque=0.2), DynamicParameters(load_inertia=5.0), monkeypatch
    )
    assert slow.status_names() == fast.status_names() == ["creep"]
    assert fast.final_angle[0] == pytest.approx(slow.final_angle[0], abs=1e-8)
    assert 0.2 < fast.final_angle[0] < hand.TRAVEL - 0.2
    assert _breakpoint_events(fast)[0].size == _breakpoint_events(slow)[0].size
    assert_energy_closes(fast, 1e-8)


def test_a_rebound_crosses_the_table_back_and_forth(monkeypatch: pytest.MonkeyPatch) -> None:
    # Restitution 0.6 on the paper's hinge with a 100-point table: forward passes run
    # compiled, the backward ones after each rebound through the event loop, and the
    # impacts, stops and breakaways as before. Same bounds as the linear deployment.
    params = DynamicParameters(load_inertia=5.0, restitution=0.6)
    fast, slow = _both(_table(100), params, monkeypatch)
    assert fast.status_names() == slow.status_names()
    assert fast.impacts[0] == slow.impacts[0] >= 1
    assert fast.deployment_time[0] == pytest.approx(slow.deployment_time[0], rel=1e-9)
    assert fast.rebound_speed[0] == pytest.approx(slow.rebound_speed[0], rel=1e-7)
    assert fast.final_time[0] == pytest.approx(slow.final_time[0], rel=1e-7)
    assert fast.events.names().count("breakpoint") == slow.events.names().count("breakpoint")
    assert_energy_closes(fast, 1e-8)


def test_rolloff_and_heating_over_a_table_match_the_per_piece_integration(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # Both paths integrate the same pieces with RODAS4 at rtol 1e-9, with the same scales
    # per piece; the compiled one sums the pieces' times and dissipations in another
    # order and restarts each piece from its own first step as the per-piece path does,
    # so they agree to rounding amplified by the step control: 1e-9 relative.
    params = DynamicParameters(
        load_inertia=5.0,
        rolloff=Rolloff(peak_speed=60.0, resistivity_coefficient=0.0039),
        thermal=Thermal(heat_capacity=0.2, thermal_resistance=100.0),
        rtol=1e-9,
    )
    fast, slow = _both(_table(120), params, monkeypatch)
    assert fast.status_names() == slow.status_names() == ["latched"]
    assert fast.deployment_time[0] == pytest.approx(slow.deployment_time[0], rel=1e-9)
    assert fast.arrival_speed[0] == pytest.approx(slow.arrival_speed[0], rel=1e-9)
    assert fast.max_damper_temperature[0] == pytest.approx(slow.max_damper_temperature[0], rel=1e-9)
    assert fast.energy.damper_dissipation[0] == pytest.approx(
        slow.energy.damper_dissipation[0], rel=1e-9
    )
    assert_energy_closes(fast, 1e-8)


def test_without_numba_the_per_piece_path_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    # ECDSIM_NUMBA=0 selects the NumPy integrator: tables then take one pass per
    # breakpoint, with the closed form's exact pieces, bit for bit as with a table
    # shorter than TABLE_PIECES.
    system = _table(60)
    params = DynamicParameters(load_inertia=5.0)
    monkeypatch.setenv("ECDSIM_NUMBA", "0")
    numpy_path = predict(system, [25.0], ["dynamic"], dynamics=params).solutions["dynamic"]
    monkeypatch.setattr(solver, "TABLE_PIECES", 10**9)
    monkeypatch.setenv("ECDSIM_NUMBA", "1")
    per_piece = predict(system, [25.0], ["dynamic"], dynamics=params).solutions["dynamic"]
    assert numpy_path.deployment_time[0] == per_piece.deployment_time[0]
    assert numpy_path.end_speed[0] == per_piece.end_speed[0]


def test_a_larger_batch_keeps_the_vectorised_pass_per_breakpoint(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # Above TABLE_CASES qualifying cases in a pass, one vectorised pass per breakpoint is
    # cheaper than a compiled call per case: three temperatures with TABLE_CASES = 2 must
    # give the per-piece path's results bit for bit (closed form, not integrated).
    system = _table(80)
    params = DynamicParameters(load_inertia=5.0)
    monkeypatch.setattr(solver, "TABLE_CASES", 2)
    batch = predict(system, [-40.0, 25.0, 100.0], ["dynamic"], dynamics=params)
    monkeypatch.setattr(solver, "TABLE_PIECES", 10**9)
    per_piece = predict(system, [-40.0, 25.0, 100.0], ["dynamic"], dynamics=params)
    a, b = batch.solutions["dynamic"], per_piece.solutions["dynamic"]
    assert np.array_equal(a.deployment_time, b.deployment_time)
    assert np.array_equal(a.end_speed, b.end_speed)
