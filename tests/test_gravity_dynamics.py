"""Gravity in the dynamic method's equations (issue 16 item 2).

The hinge's equations (:mod:`ecdsim.dynamics.kernel.hinge`) carry the ground test's
gravity torque ``W sin(theta_0 + phi)`` (opposing deployment positive). Checked against
scipy Radau at rtol 1e-12 of the equation of motion written here in the absolute angle
phi, forward and backward, on the kernel compiled, plain and with scipy's Radau as its
stepper. (The Jacobian against central differences: tests/test_dynamics_kernel.py.)
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ecdsim.config import parse_config
from ecdsim.deployment import build_problem, predict
from ecdsim.dynamics import DynamicParameters
from ecdsim.dynamics.kernel.build import backend
from ecdsim.dynamics.method import DynamicSolution
from ecdsim.dynamics.problem import dynamic_problem
from ecdsim.dynamics.result import DynamicResult
from ecdsim.dynamics.solver import solve_dynamic
from ecdsim.model import DeploymentSystem, HighSpeedDamper
from tests import hand
from tests.dynamics_reference import assert_energy_closes, toy_system

BD, N = 1.3e-4, 380.0  # the paper's damper and gear ratio; B = N^2 BD at factor 1
B = N * N * BD
PATHS = ("compiled", "python", "Radau")


def _ground(
    torque: float, slope: float, friction: float, w: float, theta0: float, phi0: float,
    speed0: float, travel: float, path: str,
) -> DynamicResult:  # fmt: skip
    """J = 5 kg*m^2 on the spring ``torque + slope phi`` (over the travel), friction,
    damping B (the paper's BD behind N = 380, c = 0), gravity W from theta_0, released
    at phi0 with speed0; on ``path``."""
    system = toy_system(B, friction, torque, torque + slope * travel, travel)
    damper = HighSpeedDamper(
        damping_rate=BD, coulomb_friction=0.0, damping_temperature_coefficient=0.0
    )
    system = DeploymentSystem(
        ecd=replace(system.ecd, damper=damper, gearbox=replace(system.ecd.gearbox, ratio=N)),
        load=system.load,
    )
    params = DynamicParameters(
        5.0, initial_angle=phi0, initial_speed=speed0, rtol=1e-10,
        integrator="Radau" if path == "Radau" else "RODAS4",
    )  # fmt: skip
    temps = np.array([25.0])
    ecd = system.ecd.at(temps)
    base, fs = build_problem(system, ecd, temps)
    problem = replace(
        dynamic_problem(system, ecd, temps, base, fs, params),
        gravity_amplitude=np.full(1, w),
        gravity_angle=np.full(1, theta0),
    )
    result = solve_dynamic(problem, kernel=backend("python") if path == "python" else None)
    assert_energy_closes(result)
    return result


def _reference(
    torque: float, slope: float, friction: float, w: float, theta0: float, direction: float,
    phi0: float, speed0: float, end: float,
) -> tuple[float, float]:  # fmt: skip
    """Time to reach ``end`` and the speed there, from J phi'' = T(phi) - sign F - B phi'
    - W sin(theta_0 + phi) with T(phi) = torque + slope phi, from phi0 at speed0."""

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        phi, w_phi = y
        accel = torque + slope * phi - direction * friction - B * w_phi - w * math.sin(theta0 + phi)
        return [w_phi, accel / 5.0]

    def arrive(_t: float, y: np.ndarray) -> float:
        return float(y[0]) - end

    arrive.terminal = True  # type: ignore[attr-defined]
    sol = solve_ivp(
        rhs, (0.0, 1e4), [phi0, speed0], method="Radau", events=arrive, rtol=1e-12, atol=1e-14
    )
    return float(sol.t_events[0][0]), float(sol.y_events[0][0][1])


@pytest.mark.parametrize("path", PATHS)
def test_a_forward_deployment_under_gravity_matches_radau(path: str) -> None:
    # The paper's falling spring (3.73 -> 1.58 N*m over 1.57 rad), friction 1.2 N*m,
    # gravity W = 0.35 N*m from theta_0 = -60 deg: aiding, then opposing.
    torque, slope, friction, w, theta0 = 3.73, -2.15 / 1.57, 1.2, 0.35, -math.pi / 3
    result = _ground(torque, slope, friction, w, theta0, 0.0, 0.0, 1.57, path)
    time, speed = _reference(torque, slope, friction, w, theta0, 1.0, 0.0, 0.0, 1.57)
    # 1e-7: the kernel integrates at rtol 1e-10 (the latch located on its dense output),
    # the reference at 1e-12
    assert float(result.deployment_time[0]) == pytest.approx(time, rel=1e-7)
    assert float(result.arrival_speed[0]) == pytest.approx(speed, rel=1e-7)


@pytest.mark.parametrize("path", PATHS)
def test_a_backward_motion_is_pulled_by_gravity(path: str) -> None:
    # Launched backward at 0.01 rad/s from 0.3 rad with a constant spring 0.5 N*m and
    # friction 0.2 N*m: gravity W = 1 N*m at theta_0 + phi = 90 deg pulls the load back,
    # harder than spring and friction, onto the start stop.
    torque, friction, w, theta0 = 0.5, 0.2, 1.0, math.pi / 2 - 0.3
    result = _ground(torque, 0.0, friction, w, theta0, 0.3, -0.01, 1.57, path)
    time, speed = _reference(torque, 0.0, friction, w, theta0, -1.0, 0.3, -0.01, 0.0)
    names = result.events.names()
    hit = names.index("start_stop")
    # 1e-7: as above
    assert float(result.events.time[hit]) == pytest.approx(time, rel=1e-7)
    assert float(result.events.speed[hit]) == pytest.approx(speed, rel=1e-7)


DYNAMIC = Path(__file__).resolve().parent.parent / "examples" / "paper_cc16_dynamic.toml"
G = 9.80665  # standard gravity, m/s^2, typed here on its own
GROUND = (
    '\n[load.gravity]\nmass = "1.2 kg"\ncg_radius = "0.3 m"\n'
    'release_angle = "-60 deg"\noffload = "0.9"\n'
)


@pytest.mark.parametrize("integrator", ["RODAS4", "Radau"])
def test_a_ground_test_deployment_matches_radau_and_its_energy_closes(integrator: str) -> None:
    # The paper's example with inertia (5 kg*m^2 + 2e-7 * 380^2 reflected), from rest, in
    # a ground test: J phi'' = T(phi) - F - B phi' - W sin(theta_0 + phi) to the latch,
    # W = 1.2 g 0.3 (1 - 0.9), against scipy Radau at rtol 1e-12 written here.
    text = DYNAMIC.read_text() + GROUND
    if integrator != "RODAS4":
        text = text.replace("[analysis]", f'[analysis]\nintegrator = "{integrator}"', 1)
    config = parse_config(text)
    temps = np.array([25.0, 100.0])
    found = predict(config.system, temps, ("dynamic",), dynamics=config.spec.dynamics())
    solution = found.solutions["dynamic"]
    assert isinstance(solution, DynamicSolution)
    inertia = 5.0 + 2e-7 * 380.0**2
    w = 1.2 * G * 0.3 * 0.1
    theta0 = -math.pi / 3
    for i, t in enumerate(temps):
        friction = hand.fecd(t) + hand.fs(t)

        def rhs(
            _t: float, y: np.ndarray, f: float = friction, b: float = hand.becd(t)
        ) -> list[float]:
            phi, speed = y
            spring = hand.TS + (hand.TE - hand.TS) * phi / hand.TRAVEL
            return [speed, (spring - f - b * speed - w * math.sin(theta0 + phi)) / inertia]

        def arrive(_t: float, y: np.ndarray) -> float:
            return float(y[0]) - hand.TRAVEL

        arrive.terminal = True  # type: ignore[attr-defined]
        sol = solve_ivp(
            rhs, (0.0, 1e4), [0.0, 0.0], method="Radau", events=arrive, rtol=1e-12, atol=1e-14
        )
        expected = float(sol.t_events[0][0])
        # 1e-7: ecdsim integrates nonlinear segments at its default rtol 1e-8, the
        # reference at 1e-12 (as validation case paper_example_methods)
        assert float(solution.deployment_time[i]) == pytest.approx(expected, rel=1e-7)
        assert float(solution.end_speed[i]) == pytest.approx(
            float(sol.y_events[0][0][1]),
            rel=1e-6,  # a speed: one digit less than the time
        )
        energy = solution.result.energy
        assert energy.gravity_work is not None
        gravity = float(np.ravel(energy.gravity_work)[i])
        # The work against gravity from release to the latch, by hand
        assert gravity == pytest.approx(
            w * (math.cos(theta0) - math.cos(theta0 + hand.TRAVEL)), rel=1e-12
        )
        # 1e-6: the balance's terms are each integrated at rtol 1e-8
        assert abs(float(np.ravel(energy.error)[i])) < 1e-6


def test_the_dynamic_method_stalls_where_gravity_holds_the_load() -> None:
    # At -40 degC the paper example under W = 0.353 N*m with a resistive table stalls in
    # the quasi-static methods; without a table, a heavier test (offload 0.5) stalls too:
    # the dynamic method creeps to rest at the exact method's stall angle, where the
    # spring less gravity equals the friction (Eq. 5 at rest).
    text = (DYNAMIC.read_text() + GROUND).replace('offload = "0.9"', 'offload = "0.5"')
    config = parse_config(text)
    found = predict(
        config.system, np.array([-40.0]), ("exact", "dynamic"), dynamics=config.spec.dynamics()
    )
    exact = found.solutions["exact"]
    dynamic = found.solutions["dynamic"]
    assert bool(exact.stalled[0])
    assert bool(dynamic.stalled[0])
    # 1e-6 rad: the dynamic method's creep threshold stops it a hair before the
    # asymptote it approaches
    assert float(dynamic.stall_angle[0]) == pytest.approx(float(exact.stall_angle[0]), abs=1e-6)


def test_the_compiled_and_plain_kernels_carry_gravity_alike(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # The same ground-test deployment by the kernel compiled (numba) and run as plain
    # Python: one source (docs/architecture.md), two forms.
    assert backend().name == "numba", "numba is a dependency"
    config = parse_config(DYNAMIC.read_text() + GROUND)
    temps = np.array([-40.0, 25.0, 100.0])
    compiled = predict(config.system, temps, ("dynamic",), dynamics=config.spec.dynamics())
    monkeypatch.setenv("ECDSIM_NUMBA", "0")
    assert backend().name == "python"
    plain = predict(config.system, temps, ("dynamic",), dynamics=config.spec.dynamics())
    for field in ("deployment_time", "end_speed", "max_speed"):
        # 1e-12: the same arithmetic; the compiled code's exp and sin are the C library's
        np.testing.assert_allclose(
            getattr(compiled.solutions["dynamic"], field),
            getattr(plain.solutions["dynamic"], field),
            rtol=1e-12,
            err_msg=field,
        )


def test_a_grazing_bottleneck_is_crossed_not_taken_for_creep() -> None:
    # Issue 23 item 8: a constant drive of 2.5 N*m less 0.5 N*m of friction against
    # gravity W = 2 - 1e-9 N*m whose peak (theta_0 + phi = pi/2) lies mid-travel, at
    # 0.785 rad: the net torque never reaches 0 (its minimum is +1e-9 N*m), so no
    # equilibrium exists and the load crawls through in some 1e6 s. The speed there falls
    # below the creep threshold (1e-9 of the speed scale); the creep rule must find no
    # equilibrium ahead and go on (before, it stopped at 0.785 rad, "creep"). Reference,
    # by hand: overdamped (J/B = 0.27 s against the crawl), t = B int dphi / (a - W
    # sin(theta_0 + phi)) with a = 2 N*m, in closed form 2 B / s [atan((a tan(x/2) - W) /
    # s)] over x = theta_0 + phi, s = sqrt(a^2 - W^2) (x/2 stays below pi/2 here).
    a, gap, peak = 2.0, 1e-9, 0.785
    w, theta0, travel = a - gap, math.pi / 2 - peak, 1.57
    s = math.sqrt(gap * (a + w))  # a^2 - W^2 without the cancellation

    def primitive(x: float) -> float:
        return 2.0 * B / s * math.atan((a * math.tan(x / 2.0) - w) / s)

    time = primitive(theta0 + travel) - primitive(theta0)
    assert time > 1e6
    result = _ground(a + 0.5, 0.0, 0.5, w, theta0, 0.0, 0.0, travel, "compiled")
    assert result.status_names() == ["latched"]
    # The inertia's share of the time is of order J/B out of 1e6 s; the integration's
    # at rtol 1e-10.
    assert float(result.deployment_time[0]) == pytest.approx(time, rel=1e-6)
