"""The worked example of docs/architecture.md, "How to add an effect": a bearing drag.

``[load] bearing_drag = c_b`` adds ``T = -c_b omega`` on the load (the hinge's bearings,
:func:`ecdsim.physics.mechanics.bearing_drag_torque`). With a linear spring, linear
damping B and no friction the equation of motion is linear,
``J x'' + (B + c_b) x' + k x = T_s``, and its solution is written here by hand; the
kernel integrates the drag (the closed form does not declare it) and must agree. The
registry's own checks (Jacobian, compiled and plain, energy, refusals) run on it in
tests/test_effect_registry.py.
"""

from __future__ import annotations

import cmath
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from ecdsim.config import ConfigError
from ecdsim.config.loader import parse_config
from ecdsim.deployment import predict
from ecdsim.dynamics import DynamicParameters
from ecdsim.dynamics.solver import solve_dynamic
from tests.dynamics_reference import assert_energy_closes, toy_system
from tests.test_dynamics_kernel import _problem

ROOT = Path(__file__).resolve().parents[1]
# Overdamped (C^2 = 6.25 > 4 J k = 4) with the equilibrium x_eq = T_s / k = 2 rad beyond
# the travel: the load rises monotonically through 1.5 rad, one crossing to find.
J, B, C_B = 1.0, 1.5, 1.0
TS, TE, TRAVEL = 2.0, 0.5, 1.5


def _hand_arrival() -> tuple[float, float]:
    """Arrival time and speed of ``J x'' + (B + c_b) x' + k x = T_s`` from rest at 0:
    ``x = x_eq + a e^(r1 t) + b e^(r2 t)`` with r the roots of ``J r^2 + C r + k``,
    ``a = x_eq r2 / (r1 - r2)``, ``b = -x_eq r1 / (r1 - r2)`` (x(0) = x'(0) = 0)."""
    k = (TS - TE) / TRAVEL
    c = B + C_B
    root = cmath.sqrt(c * c - 4.0 * J * k)
    r1, r2 = (-c + root) / (2.0 * J), (-c - root) / (2.0 * J)
    x_eq = TS / k
    a, b = x_eq * r2 / (r1 - r2), -x_eq * r1 / (r1 - r2)

    def x(t: float) -> float:
        return (x_eq + a * cmath.exp(r1 * t) + b * cmath.exp(r2 * t)).real - TRAVEL

    time = brentq(x, 0.0, 100.0, xtol=1e-15, rtol=4 * np.finfo(float).eps)
    speed = (a * r1 * cmath.exp(r1 * time) + b * r2 * cmath.exp(r2 * time)).real
    return float(time), float(speed)


def test_the_drag_adds_to_the_damping_as_the_hand_solution_says() -> None:
    system = toy_system(B, 0.0, TS, TE, TRAVEL)
    params = DynamicParameters(J, rtol=1e-11, effects={"bearing_drag": C_B})
    result = solve_dynamic(_problem(system, params, [25.0]))
    time, speed = _hand_arrival()
    # RODAS4 at rtol 1e-11 on a smooth linear motion: the arrival to ~1e-9 relative
    # (the event located on the dense output); 1e-8 leaves a decade of margin.
    np.testing.assert_allclose(result.deployment_time, [time], rtol=1e-8)
    np.testing.assert_allclose(result.arrival_speed, [speed], rtol=1e-8)
    # The closed form of the same motion with the drag folded into the damping (B +
    # c_b, no drag) gives the same arrival: the drag is exactly a damping on the load.
    folded = solve_dynamic(
        _problem(toy_system(B + C_B, 0.0, TS, TE, TRAVEL), DynamicParameters(J), [25.0])
    )
    np.testing.assert_allclose(result.deployment_time, folded.deployment_time, rtol=1e-8)
    # Its dissipation closes the balance: spring work = (B + c_b) int w^2 + final KE.
    assert_energy_closes(result)
    energy = result.energy
    work = TS * TRAVEL - 0.5 * (TS - TE) / TRAVEL * TRAVEL**2  # the linear spring's
    np.testing.assert_allclose(energy.spring_work, [work], rtol=1e-12)
    np.testing.assert_allclose(
        energy.damper_dissipation + energy.final_kinetic_energy, [work], rtol=1e-8
    )


def _config(line: str) -> str:
    text = (ROOT / "examples" / "paper_cc16_dynamic.toml").read_text(encoding="utf-8")
    return text.replace('travel = "1.57 rad"', f'travel = "1.57 rad"\n{line}')


def test_the_config_key_reaches_the_kernel() -> None:
    plain = parse_config(_config(""))
    assert plain.spec.dynamics().effects == {}  # type: ignore[union-attr]
    config = parse_config(_config('bearing_drag = "1 N*m*s/deg"'))
    dynamics = config.spec.dynamics()
    assert dynamics is not None
    # 1 N*m*s/deg = 180/pi N*m*s/rad, parsed once at the edge.
    assert dynamics.effects["bearing_drag"] == pytest.approx(180.0 / math.pi, rel=1e-12)
    with_drag = predict(config.system, [25.0], ["dynamic"], dynamics=dynamics)
    without = predict(plain.system, [25.0], ["dynamic"], dynamics=plain.spec.dynamics())
    slow = with_drag.solutions["dynamic"].deployment_time
    fast = without.solutions["dynamic"].deployment_time
    assert float(np.ravel(slow)[0]) > float(np.ravel(fast)[0])  # more damping, slower


def test_a_negative_drag_is_refused_with_its_key() -> None:
    with pytest.raises(ConfigError, match="bearing_drag"):
        parse_config(_config('bearing_drag = "-0.01 N*m*s/rad"'))
