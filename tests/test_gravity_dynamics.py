"""Gravity in the dynamic method's equations (issue 16 item 2): Model and the integrators.

The engaged equations of :mod:`ecdsim.dynamics.equations` carry the ground test's gravity
torque ``W sin(theta_0 + phi)`` (opposing deployment positive) when a segment is given
one. Checked against scipy Radau at rtol 1e-12 of the equation of motion written here in
the absolute angle phi (independent of the forward-frame bookkeeping), and the Jacobian
against central differences of the right-hand side.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ecdsim.config import parse_config
from ecdsim.deployment import predict
from ecdsim.dynamics import integrate
from ecdsim.dynamics.damping import LinearEddy
from ecdsim.dynamics.equations import Model
from ecdsim.dynamics.method import DynamicSolution
from tests import hand

BD, N = 1.3e-4, 380.0  # the paper's damper and gear ratio; B = N^2 BD at factor 1
B = N * N * BD
INTEGRATORS = ("RODAS4", "Radau")


def _segment(
    drive: float,
    stiffness: float,
    speed0: float,
    length: float,
    amplitude: float,
    phase: float,
    direction: float,
) -> integrate.NonlinearSegments:
    one = np.ones(1)
    return integrate.NonlinearSegments(
        inertia=5.0 * one,
        stiffness=stiffness * one,
        drive=drive * one,
        speed0=speed0 * one,
        length=length * one,
        cap=np.full(1, np.inf),
        state0=0.0 * one,
        ambient=25.0 * one,
        ratio=N * one,
        gearbox_damping=0.0 * one,
        heat_capacity=np.full(1, np.inf),
        thermal_resistance=np.full(1, np.inf),
        linear_damping=B * one,
        eddy=LinearEddy(BD * one, 25.0 * one, 0.0 * one),
        case=np.zeros(1, dtype=np.intp),
        thermal=False,
        gravity_amplitude=amplitude * one,
        gravity_phase=phase * one,
        gravity_direction=direction * one,
    )


def _reference(
    torque: float, slope: float, friction: float, w: float, theta0: float, direction: float,
    speed0: float, length: float,
) -> tuple[float, float]:  # fmt: skip
    """Time to move ``length`` and the speed there, from J phi'' = T(phi) - sign F - B phi'
    - W sin(theta_0 + phi) with phi from 0 and T(phi) = torque + slope phi."""

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        phi, w_phi = y
        accel = torque + slope * phi - direction * friction - B * w_phi - w * math.sin(theta0 + phi)
        return [w_phi, accel / 5.0]

    def arrive(_t: float, y: np.ndarray) -> float:
        return direction * float(y[0]) - length

    arrive.terminal = True  # type: ignore[attr-defined]
    sol = solve_ivp(
        rhs, (0.0, 1e4), [0.0, direction * speed0], method="Radau", events=arrive,
        rtol=1e-12, atol=1e-14,
    )  # fmt: skip
    return float(sol.t_events[0][0]), float(direction * sol.y_events[0][0][1])


@pytest.mark.parametrize("method", INTEGRATORS)
def test_a_forward_segment_under_gravity_matches_radau(method: str) -> None:
    # The paper's falling spring (3.73 -> 1.58 N*m over 1.57 rad), friction 1.2 N*m,
    # gravity W = 0.35 N*m from theta_0 = -60 deg: aiding, then opposing.
    torque, slope, friction, w, theta0 = 3.73, -2.15 / 1.57, 1.2, 0.35, -math.pi / 3
    segs = _segment(torque - friction, -slope, 0.0, 1.57, w, theta0, 1.0)
    out = integrate.advance_nonlinear(segs, 1e-10, method, False)
    time, speed = _reference(torque, slope, friction, w, theta0, 1.0, 0.0, 1.57)
    # 1e-7: the integrator runs at rtol 1e-10 (event located on its dense output), the
    # reference at 1e-12
    assert float(out.duration[0]) == pytest.approx(time, rel=1e-7)
    assert float(out.v[0]) == pytest.approx(speed, rel=1e-7)


@pytest.mark.parametrize("method", INTEGRATORS)
def test_a_backward_segment_is_pulled_by_gravity(method: str) -> None:
    # Moving backward (a rebound) with a constant spring 0.5 N*m and friction 0.2 N*m:
    # in the forward frame of the motion the drive is -(T + F); gravity W = 1 N*m at
    # theta_0 + phi_0 = 90 deg pulls the load back, harder than spring and friction.
    torque, friction, w, theta0 = 0.5, 0.2, 1.0, math.pi / 2
    segs = _segment(-(torque + friction), 0.0, 0.01, 0.3, w, theta0, -1.0)
    out = integrate.advance_nonlinear(segs, 1e-10, method, False)
    time, speed = _reference(torque, 0.0, friction, w, theta0, -1.0, 0.01, 0.3)
    # 1e-7: as above
    assert float(out.duration[0]) == pytest.approx(time, rel=1e-7)
    assert float(out.v[0]) == pytest.approx(speed, rel=1e-7)


def test_the_jacobian_with_gravity_matches_central_differences() -> None:
    segs = _segment(2.5, 1.37, 0.02, 1.57, 0.35, -math.pi / 3, 1.0)
    model = Model(
        inertia=segs.inertia,
        stiffness=segs.stiffness,
        drive=segs.drive,
        ratio=segs.ratio,
        gearbox_damping=segs.gearbox_damping,
        heat_capacity=segs.heat_capacity,
        thermal_resistance=segs.thermal_resistance,
        ambient=segs.ambient,
        eddy=segs.eddy,
        heating=False,
        gravity_amplitude=segs.gravity_amplitude,
        gravity_phase=segs.gravity_phase,
        gravity_direction=segs.gravity_direction,
    )
    y = np.array([[0.7], [0.05], [0.0], [0.0]])
    j10, j11 = (float(j[0]) for j in model.jacobian(y)[:2])
    h = 1e-6
    for row, expected in ((0, j10), (1, j11)):
        up, down = y.copy(), y.copy()
        up[row] += h
        down[row] -= h
        numeric = float((model.rhs(up)[1] - model.rhs(down)[1])[0]) / (2 * h)
        # 1e-7 relative: the central difference's truncation (h^2 terms) and rounding
        assert expected == pytest.approx(numeric, rel=1e-7)
    # The gravity term itself: -(k + W cos(theta_0 + x)) / J by hand
    assert j10 == pytest.approx(-(1.37 + 0.35 * math.cos(-math.pi / 3 + 0.7)) / 5.0, rel=1e-14)


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


def test_the_compiled_kernel_carries_gravity_as_numpy_does(monkeypatch: pytest.MonkeyPatch) -> None:
    # The same ground-test deployment by the compiled RODAS4 (numba) and the NumPy one:
    # one algorithm in two implementations (docs/architecture.md), with the gravity
    # columns of the compiled parameter table.
    assert integrate.compiled_kernel() is not None, "numba is part of the test extra"
    config = parse_config(DYNAMIC.read_text() + GROUND)
    temps = np.array([-40.0, 25.0, 100.0])
    compiled = predict(config.system, temps, ("dynamic",), dynamics=config.spec.dynamics())
    monkeypatch.setenv("ECDSIM_NUMBA", "0")
    assert integrate.compiled_kernel() is None
    plain = predict(config.system, temps, ("dynamic",), dynamics=config.spec.dynamics())
    for field in ("deployment_time", "end_speed", "max_speed"):
        # 1e-10: the two implementations agree to about 1e-12 (tests/test_dynamics_compiled)
        np.testing.assert_allclose(
            getattr(compiled.solutions["dynamic"], field),
            getattr(plain.solutions["dynamic"], field),
            rtol=1e-10,
            err_msg=field,
        )


def test_the_compiled_right_hand_side_and_jacobian_hold_the_gravity_term() -> None:
    # compiled._rhs and _jacobian against Model.rhs and jacobian at a state, gravity on:
    # the parameter table's gravity columns reach the kernels (a backward segment, so
    # that the direction's sign matters too).
    from ecdsim.dynamics import compiled

    segs = _segment(-0.7, 0.4, 0.01, 0.3, 1.0, math.pi / 2, -1.0)
    model = integrate._model(segs)
    par, law = compiled._parameters(model)
    # The factor _segment stores from the start state (s = 0: the ambient factor).
    par[0, compiled._FIXED] = par[0, compiled._FA]
    y = np.array([0.2, 0.05, 0.0, 0.0])
    out = np.empty(4)
    compiled._rhs(par[0], law, False, y, out)
    expected = model.rhs(y.reshape(4, 1))[:, 0]
    # 1e-14: the same arithmetic, compiled (sin from the C library)
    np.testing.assert_allclose(out, expected, rtol=1e-14, atol=1e-300)
    j10 = compiled._jacobian(par[0], law, False, y)[0]
    assert j10 == pytest.approx(float(model.jacobian(y.reshape(4, 1))[0][0]), rel=1e-14)
    # and the gravity term is in both: -(k + W cos(pi/2 - 0.2)) / J by hand
    assert j10 == pytest.approx(-(0.4 + math.cos(math.pi / 2 - 0.2)) / 5.0, rel=1e-14)
