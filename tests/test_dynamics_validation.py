"""Validation of the dynamic method (issue 3): limits, references and hand analyses.

Every test that solves checks the energy balance too (spring work + initial kinetic
energy = damper and friction dissipation + losses + final kinetic energy, to 1e-6).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from numpy.typing import ArrayLike
from scipy.integrate import quad, solve_ivp

from ecdsim.deployment import predict
from ecdsim.dynamics import DynamicParameters, DynamicResult, Rolloff, Thermal
from ecdsim.dynamics.method import DynamicSolution
from ecdsim.model import DeploymentSystem, Ecd, LinearSpring, TabulatedSpring
from tests import hand
from tests.conftest import paper_system
from tests.dynamics_reference import assert_energy_closes, linear_deploy, toy_system

TEMPS = [-40.0, 25.0, 100.0]


def _dynamic(
    system: DeploymentSystem, temps: ArrayLike, params: DynamicParameters
) -> DynamicResult:
    prediction = predict(system, temps, ["exact", "dynamic"], dynamics=params)
    solution = prediction.solutions["dynamic"]
    assert isinstance(solution, DynamicSolution)
    assert_energy_closes(solution.result)
    return solution.result


def test_zero_inertia_limit_converges_to_exact_solution() -> None:
    system = paper_system()
    exact = predict(system, TEMPS, ["exact"]).solutions["exact"].deployment_time
    errors = []
    for inertia in (1e-1, 1e-2, 1e-3, 1e-4, 1e-5):
        result = _dynamic(system, TEMPS, DynamicParameters(load_inertia=inertia))
        errors.append(np.max(np.abs(result.deployment_time - exact) / exact))
    # The inertia correction is first order in J (a start delay of J/B and a faster slow
    # mode, both O(J k / B^2) relative): each tenfold reduction of J divides the error by
    # about ten. Allow 7..13 for the higher-order terms at the largest J.
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((ratios > 7.0) & (ratios < 13.0)), (errors, ratios)
    # At J = 1e-5 kg*m^2 the dynamic and quasi-static times agree to better than 1e-7.
    assert errors[-1] < 1e-7


@pytest.mark.parametrize("inertia", [5.0, 20.0])
def test_paper_example_against_radau_reference(inertia: float) -> None:
    result = _dynamic(paper_system(), TEMPS, DynamicParameters(load_inertia=inertia))
    for i, temp in enumerate(TEMPS):
        friction = hand.fecd(temp) + hand.fs(temp)
        ref = linear_deploy(inertia, hand.becd(temp), friction, hand.TS, hand.TE, hand.TRAVEL)
        # Reference: Radau, analytic Jacobian, rtol 1e-10 (event located to ~1e-12 s);
        # the closed form is exact, so 1e-8 relative leaves the reference its error.
        assert result.deployment_time[i] == pytest.approx(ref.time, rel=1e-8)
        assert result.arrival_speed[i] == pytest.approx(ref.speed, rel=1e-7)
        assert result.max_speed[i] == pytest.approx(ref.max_speed, rel=1e-7)
        # The time series agrees along the way too (dense output, interpolation ~1e-9).
        times = np.linspace(0.0, ref.time, 7)[1:-1]
        series = result.sample(np.asarray(times))
        expected = np.array([ref.solution(t)[0] for t in times])
        assert np.allclose(series.angle[:, i], expected, rtol=1e-7, atol=1e-10)


def test_sticks_at_the_hand_computed_angle_without_chatter() -> None:
    # Nearly undamped (B = 1e-12): J x'' = a - k x from rest, a = Ts - F = 0.5 N*m,
    # k = 1.5 N*m/rad. The load swings to x* = 2a/k = 2/3 rad at t* = pi sqrt(J/k) and
    # stops; the spring torque there, Ts - k x* = 0.5 N*m, is below static friction
    # (1.0 N*m), so it sticks for good.
    system = toy_system(1e-12, 1.0, 1.5, 0.0, 1.0)
    result = _dynamic(system, [25.0], DynamicParameters(load_inertia=1.0))
    # Damping of 1e-12 changes the hand values by ~1e-12 relative.
    assert bool(result.stuck[0])
    assert result.stuck_angle[0] == pytest.approx(2.0 / 3.0, rel=1e-9)
    assert result.stuck_time[0] == pytest.approx(math.pi / math.sqrt(1.5), rel=1e-9)
    assert math.isinf(result.deployment_time[0])
    assert result.events.names() == ["release", "breakaway", "zero_speed", "stick"]


def test_breaks_away_after_stopping_when_the_drive_beats_static_friction() -> None:
    # Launched backward at 1 rad/s from 0.6 rad (B = 1e-12, J = 1, F = 0.2, Ts = 1.5,
    # Te = 0 over 1 rad: k = 1.5). Backward frame y: y'' + k y = -(T0 + F) with
    # T0 = 1.5 - 1.5 * 0.6 = 0.6, so y = -(0.8/k)(1 - cos wt) + sin(wt)/w, w = sqrt(k).
    # It stops when tan(wt) = k/(0.8 w); the spring torque there exceeds the static
    # friction (1.3 * 0.2), so it breaks away forward at once, then reaches the latch.
    k, t0_torque, friction = 1.5, 0.6, 0.2
    system = toy_system(1e-12, friction, 1.5, 0.0, 1.0)
    params = DynamicParameters(
        load_inertia=1.0, initial_angle=0.6, initial_speed=-1.0, static_friction_factor=1.3
    )
    result = _dynamic(system, [25.0], params)
    w = math.sqrt(k)
    t_stop = math.atan(k / ((t0_torque + friction) * w)) / w
    y_stop = -(t0_torque + friction) / k * (1 - math.cos(w * t_stop)) + math.sin(w * t_stop) / w
    names = result.events.names()
    assert names == ["release", "zero_speed", "breakaway", "arrive", "latch"]
    assert result.events.time[1] == pytest.approx(t_stop, rel=1e-9)
    assert result.events.angle[1] == pytest.approx(0.6 - y_stop, rel=1e-9)
    spring_there = 1.5 - k * (0.6 - y_stop)
    assert spring_there > 1.3 * friction
    assert result.arrived[0]


@pytest.mark.parametrize(("start_torque", "sticks"), [(1.15, True), (1.25, False)])
def test_stiction_at_release(start_torque: float, sticks: bool) -> None:
    # Kinetic friction 1.0 N*m, static 1.2 N*m: 1.15 N*m cannot start it, 1.25 N*m can
    # (and then keeps it moving: Te = 1.2 > kinetic friction).
    system = toy_system(20.0, 1.0, start_torque, 1.2, 1.0)
    params = DynamicParameters(load_inertia=2.0, static_friction_factor=1.2)
    result = _dynamic(system, [25.0], params)
    assert bool(result.stuck[0]) is sticks
    if sticks:
        assert result.events.names() == ["release", "stick"]
        assert result.stuck_time[0] == 0.0
    else:
        assert result.events.names() == ["release", "breakaway", "arrive", "latch"]


def test_creeps_to_the_quasi_static_stall_angle() -> None:
    # Paper example with Te = 0.5 N*m at +25 degC: the spring torque falls to the total
    # friction F = FECD + FS at phi* = (Ts - F) / k (hand), which the overdamped motion
    # approaches asymptotically: stuck there, at t = inf, no zero-speed chatter.
    system = paper_system(end_torque=0.5)
    result = _dynamic(
        system, [25.0], DynamicParameters(load_inertia=5.0, static_friction_factor=1.1)
    )
    friction = hand.fecd(25.0) + hand.fs(25.0)
    k = (hand.TS - 0.5) / hand.TRAVEL
    assert result.stuck_angle[0] == pytest.approx((hand.TS - friction) / k, rel=1e-13)
    assert math.isinf(result.stuck_time[0])
    assert result.events.names() == ["release", "breakaway", "creep"]
    assert result.status_names() == ["creep"]


def test_lost_motion_free_phase_matches_hand_solution() -> None:
    # J_L = 2, J_D = 1 (rotor 1 kg*m^2 at N = 1), gap 0.1 rad, Ts = 3, Te = 1 over 1.5 rad
    # (k = 4/3), FS = 0.5, FECD = 0.3, B = 4. Free phase: J_L x'' = a - k x with
    # a = Ts - FS = 2.5 (no damper): x = (a/k)(1 - cos wt), w = sqrt(k/J_L).
    gap = 0.1
    system = toy_system(4.0, 0.5, 3.0, 1.0, 1.5, ecd_friction=0.3, lost_motion=gap)
    params = DynamicParameters(load_inertia=2.0, rotor_inertia=1.0)
    result = _dynamic(system, [25.0], params)
    k, a, j_l, j_d = 4.0 / 3.0, 2.5, 2.0, 1.0
    w = math.sqrt(k / j_l)
    t_gap = math.acos(1 - k * gap / a) / w
    v_gap = a / k * w * math.sin(w * t_gap)
    assert result.events.names() == ["release", "breakaway", "engage", "arrive", "latch"]
    assert result.engagement_time[0] == pytest.approx(t_gap, rel=1e-12)
    assert result.events.speed[2] == pytest.approx(v_gap, rel=1e-12)
    # Momentum exchange: J_L v = (J_L + J_D) v+, energy lost J_L J_D v^2 / 2 (J_L + J_D).
    loss = j_l * j_d * v_gap**2 / (2 * (j_l + j_d))
    assert result.energy.engagement_loss[0] == pytest.approx(loss, rel=1e-12)
    after = result.sample(np.array([t_gap]))
    assert after.speed[0, 0] == pytest.approx(j_l * v_gap / (j_l + j_d), rel=1e-12)
    before = result.sample(np.array([0.5 * t_gap]))
    assert before.angle[0, 0] == pytest.approx(a / k * (1 - math.cos(w * 0.5 * t_gap)), rel=1e-12)
    assert not bool(before.engaged[0, 0])


def test_rebound_on_the_end_stop() -> None:
    # Restitution 0.5: the first rebound leaves at -0.5 times the arrival speed (Newton),
    # the rebounds die out against the stop, and the energy still balances.
    system = paper_system()
    params = DynamicParameters(load_inertia=5.0, restitution=0.5, initial_speed=0.3)
    result = _dynamic(system, [25.0], params)
    assert result.rebound_speed[0] == pytest.approx(-0.5 * result.arrival_speed[0], rel=1e-15)
    assert result.status_names() == ["settled"]
    assert result.impacts[0] >= 2
    # Every bounce is an arrive, a zero speed and a breakaway; no other events.
    names = result.events.names()
    assert names.count("arrive") == result.impacts[0]
    assert set(names) == {"release", "arrive", "zero_speed", "breakaway", "settle"}
    # Arrival against a reference started at the same speed.
    friction = hand.fecd(25.0) + hand.fs(25.0)
    ref = linear_deploy(5.0, hand.becd(25.0), friction, hand.TS, hand.TE, hand.TRAVEL, 0.3)
    assert result.deployment_time[0] == pytest.approx(ref.time, rel=1e-8)


def test_tabulated_spring_matches_piecewise_reference() -> None:
    # Breakpoints are events: each piece is linear and solved in closed form. The
    # reference integrates piece by piece with Radau, restarting at each breakpoint.
    angles = (0.0, 0.4, 0.9, 1.57)
    torques = (3.73, 3.1, 2.2, 1.58)
    base = paper_system()
    system = DeploymentSystem(
        base.ecd, replace(base.load, spring=TabulatedSpring(angles, torques)), name="table"
    )
    result = _dynamic(system, [25.0], DynamicParameters(load_inertia=5.0))
    friction = hand.fecd(25.0) + hand.fs(25.0)
    b, j = hand.becd(25.0), 5.0
    t, y = 0.0, np.array([0.0, 0.0])
    for start, end, t_start, t_end in zip(angles, angles[1:], torques, torques[1:], strict=False):
        slope = (t_end - t_start) / (end - start)

        def rhs(
            _t: float,
            s: np.ndarray,
            slope: float = slope,
            start: float = start,
            t_start: float = t_start,
        ) -> np.ndarray:
            torque = t_start + slope * (s[0] - start)
            return np.array([s[1], (torque - friction - b * s[1]) / j])

        def reach(_t: float, s: np.ndarray, end: float = end) -> float:
            return float(s[0] - end)

        reach.terminal = True  # type: ignore[attr-defined]
        reach.direction = 1  # type: ignore[attr-defined]
        sol = solve_ivp(rhs, (t, t + 1e4), y, method="Radau", rtol=1e-11, atol=1e-14, events=reach)
        t, y = float(sol.t_events[0][0]), sol.y_events[0][0]
    # Three restarts at rtol 1e-11: ~1e-10 relative on the arrival time.
    assert result.deployment_time[0] == pytest.approx(t, rel=1e-8)
    assert result.arrival_speed[0] == pytest.approx(float(y[1]), rel=1e-7)
    assert result.events.count("breakpoint") == 2


@pytest.mark.parametrize("integrator", ["RODAS4", "Radau", "BDF", "LSODA"])
def test_rolloff_spin_down_with_adiabatic_heating(integrator: str) -> None:
    # A flywheel (J = 0.01 kg*m^2, no spring, no friction) spun at 50 rad/s behind N = 10
    # into a Kloss damper (BD = 1e-3, omega_peak = 200 rad/s at 25 degC, alpha = 0.0039)
    # with BG = 0 and an adiabatic heat capacity of 1 J/K. All the kinetic energy lost
    # heats the damper, so T(w) = T0 + J (w0^2 - w^2) / 2C, and the spin-down time from
    # w0 to w is t = int_w^w0 J dw' / (N T_d(N w', T(w'))): an independent quadrature.
    j, n, bd, peak, alpha, cap, w0 = 0.01, 10.0, 1e-3, 200.0, 0.0039, 1.0, 50.0
    base = toy_system(bd, 0.0, 0.0, 0.0, 1e6)
    system = DeploymentSystem(
        Ecd(base.ecd.damper, replace(base.ecd.gearbox, ratio=n)),
        replace(base.load, spring=LinearSpring(0.0, 0.0)),
    )
    peak_torque = bd * peak / 2.0

    def temperature(w: float) -> float:
        return 25.0 + j * (w0**2 - w**2) / (2 * cap)

    def eddy(w: float) -> float:
        x = n * w / (peak * (1 + alpha * (temperature(w) - 25.0)))
        return 2 * peak_torque * x / (1 + x * x)

    w_half = 0.5 * w0
    t_half, _ = quad(lambda w: j / (n * eddy(w)), w_half, w0, epsabs=0.0, epsrel=1e-13)
    params = DynamicParameters(
        load_inertia=j,
        initial_speed=w0,
        rolloff=Rolloff(peak, alpha),
        thermal=Thermal(cap),
        stop_time=t_half,
        rtol=1e-10,
        integrator=integrator,
    )
    result = _dynamic(system, [25.0], params)
    assert result.status_names() == ["stop_time"]
    # Integrator at rtol 1e-10 against a quadrature at 1e-13: 1e-7 leaves ample margin.
    assert result.final_speed[0] == pytest.approx(w_half, rel=1e-7)
    assert result.final_temperature[0] == pytest.approx(temperature(w_half), rel=1e-9)
    assert result.max_damper_temperature[0] == pytest.approx(temperature(w_half), rel=1e-9)


@pytest.mark.parametrize("integrator", ["RODAS4", "BDF"])
def test_linear_damping_with_heating_against_reference(integrator: str) -> None:
    # The paper example at J = 5 with a small heat capacity (0.2 J/K) and R = 100 K/W, so
    # that the damper warms by several kelvin and its damping (Eq. 1) drops: the reference
    # integrates phi, omega and T with Radau at rtol 1e-11, its RHS typed from Eq. 1-4.
    temp0, j, cap, resistance = 25.0, 5.0, 0.2, 100.0
    params = DynamicParameters(
        load_inertia=j, thermal=Thermal(cap, resistance), integrator=integrator
    )
    result = _dynamic(paper_system(), [temp0], params)
    friction = hand.fecd(temp0) + hand.fs(temp0)
    k = (hand.TS - hand.TE) / hand.TRAVEL

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        phi, w, temp = y
        bd_t = hand.BD * (1 - 0.004 * (temp - 25.0))
        damping = (bd_t + hand.BG_FRACTION * hand.BD) * hand.N**2
        eddy_power = bd_t * (hand.N * w) ** 2
        return np.array(
            [
                w,
                (hand.TS - k * phi - friction - damping * w) / j,
                (eddy_power - (temp - temp0) / resistance) / cap,
            ]
        )

    def arrive(_t: float, y: np.ndarray) -> float:
        return float(y[0] - hand.TRAVEL)

    arrive.terminal = True  # type: ignore[attr-defined]
    sol = solve_ivp(
        rhs, (0, 1e3), [0.0, 0.0, temp0], method="Radau", rtol=1e-11, atol=1e-14, events=arrive
    )
    # Both integrate the same equations; ecdsim at its default rtol 1e-8, whose global
    # error is a few rtol (BDF's more than the Rosenbrock method's).
    assert result.deployment_time[0] == pytest.approx(float(sol.t_events[0][0]), rel=1e-6)
    assert result.final_temperature[0] == pytest.approx(float(sol.y_events[0][0][2]), rel=1e-7)
    assert result.final_temperature[0] > temp0 + 1.0


def test_batches_broadcast_over_temperatures_and_samples() -> None:
    # Three temperatures x four load inertias in one call: every case equals its own
    # single-case solve.
    inertias = np.array([0.5, 2.0, 5.0, 20.0])
    temps = np.array(TEMPS)[:, None]
    result = _dynamic(paper_system(), temps, DynamicParameters(load_inertia=inertias))
    assert result.batch_shape == (3, 4)
    for i, temp in enumerate(TEMPS):
        for jdx, inertia in enumerate(inertias):
            single = _dynamic(
                paper_system(), [temp], DynamicParameters(load_inertia=float(inertia))
            )
            # Same formulas on the same inputs: equal up to vectorised-vs-scalar rounding.
            assert result.deployment_time[i, jdx] == pytest.approx(
                single.deployment_time[0], rel=1e-13
            )


def test_stops_on_the_start_stop_then_breaks_away() -> None:
    # Launched backward hard from 0.05 rad it reaches the start (angle 0) while still
    # moving; the stop (restitution 0) takes its kinetic energy, the spring restarts it.
    system = toy_system(2.0, 0.2, 1.5, 1.0, 1.0)
    params = DynamicParameters(load_inertia=1.0, initial_angle=0.05, initial_speed=-2.0)
    result = _dynamic(system, [25.0], params)
    assert result.events.names() == ["release", "start_stop", "breakaway", "arrive", "latch"]
    hit_speed = result.events.speed[1]
    assert hit_speed < 0.0
    assert result.energy.impact_loss[0] == pytest.approx(0.5 * hit_speed**2, rel=1e-14)
    assert result.events.angle[1] == 0.0


def test_rebounds_cross_spring_breakpoints_both_ways() -> None:
    # A lively rebound (e = 0.9, light damping) on a three-piece spring: the backward
    # motion crosses breakpoints too; each crossing is an event and the energy balances.
    spring = TabulatedSpring((0.0, 0.3, 0.8, 1.0), (2.0, 1.8, 1.2, 1.1))
    system = toy_system(0.5, 0.2, 0.0, 0.0, 1.0, spring=spring)
    params = DynamicParameters(load_inertia=1.0, restitution=0.9)
    result = _dynamic(system, [25.0], params)
    names = result.events.names()
    arrive = names.index("arrive")
    assert "breakpoint" in names[arrive:]  # crossed backward after the first impact
    assert result.status_names() == ["settled"]
    # A spring torque of >= 1.1 N*m against 0.2 N*m of friction cannot hold it off the stop.
    assert result.final_angle[0] == 1.0


def test_sticking_exactly_at_the_static_limit_does_not_chatter() -> None:
    # Ts = 3F with B ~ 0 and a spring that reverses (Te = -2 N*m over 1 rad, k = 5): the
    # swing stops at x* = 2(Ts - F)/k = 0.8 rad where the spring torque is
    # Ts - 2(Ts - F) = -F, exactly the static friction (factor 1). Rounding must not
    # restart it: one zero_speed, one stick, nothing after.
    system = toy_system(1e-12, 1.0, 3.0, -2.0, 1.0)
    result = _dynamic(system, [25.0], DynamicParameters(load_inertia=1.0))
    assert result.events.names() == ["release", "breakaway", "zero_speed", "stick"]
    assert result.stuck_angle[0] == pytest.approx(0.8, rel=1e-9)


def test_heating_approaches_the_zero_of_the_damping_law_without_crossing_it() -> None:
    # A 1e-4 J/K damper absorbing ~2.6 J heats towards 275 degC, where Eq. 1 (-0.4 %/K)
    # reaches BD_T = 0 and its heating power vanishes: the temperature approaches it and
    # never crosses, so the run latches (tests/test_dynamics_heating_limit.py checks the
    # times against references).
    params = DynamicParameters(load_inertia=5.0, thermal=Thermal(1e-4))
    prediction = predict(paper_system(), [25.0], ["dynamic"], dynamics=params)
    solution = prediction.solutions["dynamic"]
    assert isinstance(solution, DynamicSolution)
    result = solution.result
    assert result.status_names() == ["latched"]
    # BD_T = BD (1 - 0.004 (T - 25)) = 0 at T = 275 degC; reached to rounding, not passed.
    assert result.final_temperature[0] == pytest.approx(275.0, rel=1e-6)
    assert result.max_damper_temperature[0] <= 275.0
    assert_energy_closes(result)


def test_batched_integrator_matches_scipy_case_by_case() -> None:
    # Roll-off (into and beyond the peak) with self-heating, 2 temperatures x 2 load
    # inertias: the vectorised Rosenbrock run and one Radau run per case, both at rtol
    # 1e-9, must agree to ~1e-7 (each is within a few rtol of the exact answer); so must
    # their time series (the batched one from its Hermite dense output).
    inertias = np.array([0.5, 20.0])
    temps = np.array([-40.0, 100.0])[:, None]
    runs = {}
    for integrator in ("RODAS4", "Radau"):
        params = DynamicParameters(
            load_inertia=inertias,
            rolloff=Rolloff(60.0, 0.0039),
            thermal=Thermal(0.2, 100.0),
            rtol=1e-9,
            integrator=integrator,
        )
        runs[integrator] = _dynamic(paper_system(), temps, params)
    fast, slow = runs["RODAS4"], runs["Radau"]
    assert np.allclose(fast.deployment_time, slow.deployment_time, rtol=1e-7, atol=0.0)
    assert np.allclose(fast.arrival_speed, slow.arrival_speed, rtol=1e-6, atol=0.0)
    assert np.allclose(fast.max_speed, slow.max_speed, rtol=1e-6, atol=0.0)
    assert np.allclose(fast.max_damper_temperature, slow.max_damper_temperature, rtol=1e-9)
    times = np.linspace(0.0, 10.0, 9)
    a, b = fast.sample(times), slow.sample(times)
    assert np.allclose(a.angle, b.angle, rtol=1e-6, atol=1e-9)
    assert np.allclose(a.damper_temperature, b.damper_temperature, rtol=1e-9, atol=1e-9)
