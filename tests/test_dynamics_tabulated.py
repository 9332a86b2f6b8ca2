"""Tabulated springs of many points: the piece lookup walks from the previous piece.

Each breakpoint is an event of the dynamic solver, so a deployment over a spring table of
P points has about P events; the lookup of the current piece costs O(1) per event (it
moves by one piece at a time), not O(P) (counting the breakpoints below the angle). Long
forward runs over a table are crossed inside the compiled kernel.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ecdsim.deployment import predict
from ecdsim.dynamics import DynamicParameters
from ecdsim.dynamics.kernel.segment import first_piece, piece_walk
from ecdsim.model import DeploymentSystem, TabulatedSpring
from tests import hand
from tests.conftest import paper_system
from tests.dynamics_reference import assert_energy_closes


def _counted(angles: np.ndarray, phi: np.ndarray, forward: np.ndarray) -> np.ndarray:
    """The piece by definition: interior breakpoints at or below phi (forward), below
    phi (backward)."""
    interior = angles[1:-1]
    return np.asarray(
        np.where(forward, np.sum(interior <= phi, axis=0), np.sum(interior < phi, axis=0))
    )


def test_walking_lookup_equals_counting_from_any_start() -> None:
    # Random sorted tables with repeated angles (zero-width pieces), angles on and
    # between breakpoints, both directions, and starting pieces anywhere.
    rng = np.random.default_rng(7)
    points, n = 40, 300
    angles = np.sort(rng.integers(0, 25, size=(points, n)).astype(float), axis=0)
    angles[0], angles[-1] = 0.0, 25.0
    on_breakpoint = angles[rng.integers(0, points, n), np.arange(n)]
    phi = np.where(rng.random(n) < 0.5, on_breakpoint, rng.uniform(0.0, 25.0, n))
    forward = rng.random(n) < 0.5
    start = rng.integers(0, points - 1, n)
    walked = [
        piece_walk(angles[:, k], float(phi[k]), bool(forward[k]), int(start[k])) for k in range(n)
    ]
    assert np.array_equal(walked, _counted(angles, phi, forward))
    first = [first_piece(angles[:, k], float(phi[k])) for k in range(n)]
    assert np.array_equal(first, _counted(angles, phi, np.ones(n, bool)))


def test_ten_thousand_point_spring_against_scipy() -> None:
    # The paper's hinge (J = 5 kg*m^2, +25 degC) with a spring tabulated at P = 10,000
    # points of a curved law. The reference integrates the same piecewise-linear torque
    # (np.interp of the table, typed from the equations of docs/dynamics.md) with
    # solve_ivp Radau at rtol 1e-10 across all the breakpoints.
    points = 10_000
    angles = np.linspace(0.0, hand.TRAVEL, points)
    torques = hand.TS - (hand.TS - hand.TE) * (angles / hand.TRAVEL) ** 1.5
    base = paper_system()
    spring = TabulatedSpring(tuple(angles.tolist()), tuple(torques.tolist()))
    system = DeploymentSystem(base.ecd, replace(base.load, spring=spring), name="table")
    solution = predict(
        system, [25.0], ["dynamic"], dynamics=DynamicParameters(load_inertia=5.0)
    ).solutions["dynamic"]
    result = solution.result  # type: ignore[attr-defined]
    friction = hand.fecd(25.0) + hand.fs(25.0)
    damping, inertia = hand.becd(25.0), 5.0

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        spring_torque = np.interp(y[0], angles, torques)
        return np.array([y[1], (spring_torque - friction - damping * y[1]) / inertia])

    def arrive(_t: float, y: np.ndarray) -> float:
        return float(y[0] - hand.TRAVEL)

    arrive.terminal = True  # type: ignore[attr-defined]
    arrive.direction = 1  # type: ignore[attr-defined]
    sol = solve_ivp(
        rhs, (0.0, 1e3), [0.0, 0.0], method="Radau", rtol=1e-10, atol=1e-13, events=arrive
    )
    assert result.status_names() == ["latched"]
    assert result.events.count("breakpoint") == points - 2
    # With numba the table is crossed in one compiled call (RODAS4 at rtol 1e-8, about
    # 1e-11 on the time); without it every piece is exact (closed form). Radau at rtol
    # 1e-10 over 10,000 kinks of the torque's slope keeps ~1e-9 on the arrival time:
    # 1e-8 bounds the comparison (1e-7 for the speed).
    assert result.deployment_time[0] == pytest.approx(float(sol.t_events[0][0]), rel=1e-8)
    assert result.arrival_speed[0] == pytest.approx(float(sol.y_events[0][0][1]), rel=1e-7)
    assert_energy_closes(result)


def _table_system(points: int) -> DeploymentSystem:
    angles = np.linspace(0.0, hand.TRAVEL, points)
    torques = hand.TS - (hand.TS - hand.TE) * (angles / hand.TRAVEL) ** 1.5
    base = paper_system()
    spring = TabulatedSpring(tuple(angles.tolist()), tuple(torques.tolist()))
    return DeploymentSystem(base.ecd, replace(base.load, spring=spring), name="table")


def _solve(system: DeploymentSystem, **params: float) -> Any:
    dynamics = DynamicParameters(load_inertia=5.0, **params)  # type: ignore[arg-type]
    solution = predict(system, [25.0], ["dynamic"], dynamics=dynamics).solutions["dynamic"]
    return solution.result  # type: ignore[attr-defined]


def test_spring_breakpoints_do_not_count_against_the_event_limit() -> None:
    # A table of 60 points is 58 breakpoint events: with an event limit of 1 the run must
    # still reach the latch (its one pass that is not a breakpoint), and bit for bit as
    # with the default limit, which it never approaches. Before, every breakpoint was a
    # pass of the limit, and a table longer than max_events rows stopped short.
    system = _table_system(60)
    limited = _solve(system, max_events=1)
    free = _solve(system)
    assert limited.status_names() == ["latched"]
    assert limited.events.count("breakpoint") == 58
    assert limited.deployment_time[0] == free.deployment_time[0]
    assert limited.arrival_speed[0] == free.arrival_speed[0]


def test_the_event_limit_still_cuts_rebounds_short() -> None:
    # A rebounding end stop (e = 0.5) needs several impacts to settle: a limit of 3
    # passes ends the run as event_limit, breakpoints crossed on the way back or not.
    result = _solve(_table_system(20), restitution=0.5, max_events=3)
    assert result.status_names() == ["event_limit"]
    assert result.events.count("event_limit") == 1
    assert result.events.count("arrive") >= 1
