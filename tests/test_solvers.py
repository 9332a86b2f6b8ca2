"""The paper method (Eq. 8-13) and the exact quasi-static solution.

References: hand calculations (tests/hand.py) and a tight solve_ivp integration
(tests/reference.py, rtol 1e-10) of the same ODE.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ecdsim.deployment import predict
from ecdsim.model import (
    DeploymentSystem,
    LinearSpring,
    LinearTemperatureLaw,
    Load,
    TabulatedSpring,
)
from ecdsim.solvers import EXACT, PAPER, QuasiStaticProblem
from ecdsim.solvers import paper as paper_eqs
from tests import hand, reference
from tests.conftest import paper_system

TEMPS = [-40.0, 25.0, 100.0]


@pytest.mark.parametrize("temperature", TEMPS)
def test_paper_method_matches_hand_calculation(paper: DeploymentSystem, temperature: float) -> None:
    result = predict(paper, [temperature], methods=["paper"]).solutions["paper"]
    # Same formulas evaluated in another order: a few ulp.
    assert result.deployment_time[0] == pytest.approx(hand.paper_time(temperature), rel=1e-12)


def test_paper_method_at_25c_by_hand() -> None:
    """Eq. 8-11 with numbers: F = 0.53466 + 0.47; B = 23.65272."""
    ws = (3.73 - 1.00466) / 23.65272  # Eq. 8: 0.115223 rad/s
    we = (1.58 - 1.00466) / 23.65272  # Eq. 9: 0.024324 rad/s
    dt = 1.57 / ((ws + we) / 2.0)  # Eq. 10-11: 22.50 s
    result = predict(paper_system(), [25.0], methods=["paper"]).solutions["paper"]
    assert result.start_speed[0] == pytest.approx(ws, rel=1e-12)
    assert result.end_speed[0] == pytest.approx(we, rel=1e-12)
    assert result.deployment_time[0] == pytest.approx(dt, rel=1e-12)
    assert dt == pytest.approx(22.50, abs=0.01)  # the figure quoted in docs/model.md


def test_eq13_reaches_the_end_at_eq11_time() -> None:
    ws, we, travel = 0.115, 0.024, 1.57
    dt = float(paper_eqs.deployment_time(travel, paper_eqs.mean_speed(ws, we)))
    alpha = paper_eqs.deceleration(ws, we, dt)
    assert float(alpha) < 0.0  # the missing Eq. 12 gives a deceleration
    theta_end = paper_eqs.position_eq13(dt, travel, ws, alpha)
    # theta = theta_s - ws t - alpha t^2/2 = travel - dt (ws + we)/2 = 0 by construction.
    assert float(theta_end) == pytest.approx(0.0, abs=1e-12)
    # Half time by hand: 1.57 - 0.115 t - 0.5 alpha t^2.
    half = dt / 2.0
    expected = travel - ws * half - 0.5 * (we - ws) / dt * half**2
    # Eq. 13 by hand with the same numbers: rounding only on O(1) values.
    assert float(paper_eqs.position_eq13(half, travel, ws, alpha)) == pytest.approx(
        expected, rel=1e-12
    )


@pytest.mark.parametrize("temperature", TEMPS)
def test_exact_matches_closed_form_by_hand(paper: DeploymentSystem, temperature: float) -> None:
    result = predict(paper, [temperature], methods=["exact"]).solutions["exact"]
    # ecdsim uses the log-mean form; hand.exact_time uses (B/k) ln(a/(a - k L)).
    assert result.deployment_time[0] == pytest.approx(hand.exact_time(temperature), rel=1e-12)


@pytest.mark.parametrize("temperature", TEMPS)
def test_exact_matches_solve_ivp(paper: DeploymentSystem, temperature: float) -> None:
    friction = hand.fecd(temperature) + hand.fs(temperature)
    damping = hand.becd(temperature)

    def spring(phi: float) -> float:
        return 3.73 - (3.73 - 1.58) * phi / 1.57

    t_ref, _ = reference.deploy(spring, friction, damping, 1.57)
    assert t_ref is not None
    result = predict(paper, [temperature], methods=["exact"]).solutions["exact"]
    # The reference integrates at rtol 1e-10; its event time is good to ~1e-9 relative.
    assert result.deployment_time[0] == pytest.approx(t_ref, rel=1e-8)


def test_exact_trajectory_matches_solve_ivp(paper: DeploymentSystem) -> None:
    friction = hand.fecd(-40.0) + hand.fs(-40.0)

    def spring(phi: float) -> float:
        return 3.73 - 2.15 * phi / 1.57

    t_ref, sol = reference.deploy(spring, friction, hand.becd(-40.0), 1.57)
    assert t_ref is not None
    times = np.linspace(0.0, t_ref * 0.999, 9)
    trajectory = predict(paper, [-40.0]).trajectory("exact", times)
    ref_angle = sol.sol(times)[0]  # type: ignore[attr-defined]
    # Dense output of DOP853 at rtol 1e-10 interpolates to ~1e-9.
    np.testing.assert_allclose(trajectory.angle[:, 0], ref_angle, rtol=1e-8, atol=1e-10)
    speed_ref = (spring(ref_angle[3]) - friction) / hand.becd(-40.0)
    assert trajectory.speed[3, 0] == pytest.approx(speed_ref, rel=1e-8)
    # After arrival the mechanism is latched at the travel.
    after = predict(paper, [-40.0]).trajectory("exact", [t_ref * 1.01])
    assert after.angle[0, 0] == 1.57  # held at the travel itself, not computed
    assert after.speed[0, 0] == 0.0


def test_paper_method_underestimates(paper: DeploymentSystem) -> None:
    prediction = predict(paper, TEMPS)
    paper_t = prediction.solutions["paper"].deployment_time
    exact_t = prediction.solutions["exact"].deployment_time
    assert np.all(paper_t < exact_t)  # arithmetic mean >= log mean (docs/model.md)
    # Leading-order bias: exact/paper = g(x) (1 - x/2), g(x) = -ln(1-x)/x, x = 1 - b/a.
    for i, t in enumerate(TEMPS):
        friction = hand.fecd(t) + hand.fs(t)
        x = 1.0 - (1.58 - friction) / (3.73 - friction)
        ratio = -math.log1p(-x) / x * (1.0 - x / 2.0)
        assert exact_t[i] / paper_t[i] == pytest.approx(ratio, rel=1e-12)
    # By hand: 34.1 s - 48.1 s; both times good to 1e-12, so the difference to 1e-11.
    difference = hand.paper_time(-40.0) - hand.exact_time(-40.0)
    assert prediction.time_difference()[0] == pytest.approx(difference, rel=1e-11)


def test_stall_reported_by_both_methods() -> None:
    # End torque 0.7 N*m < F_25 = 1.00466 N*m: net torque a - k phi reaches 0 at
    # phi* = (3.73 - 1.00466) / ((3.73 - 0.7) / 1.57) = 1.41213 rad, before 1.57 rad.
    system = paper_system(end_torque=0.7)
    prediction = predict(system, [25.0])
    stall = (3.73 - 1.00466) / ((3.73 - 0.7) / 1.57)
    for name in ("paper", "exact"):
        solution = prediction.solutions[name]
        assert bool(solution.stalled[0])
        assert math.isinf(solution.deployment_time[0])
        assert solution.stall_angle[0] == pytest.approx(stall, rel=1e-12)
        assert solution.end_speed[0] == 0.0
    codes = [w.code for w in prediction.warnings]
    assert codes.count("stall") == 2
    case = prediction.to_dict()["cases"][0]
    assert case["exact"]["deployment_time_s"] is None
    assert case["paper"]["stall_angle_rad"] == pytest.approx(stall, rel=1e-12)
    assert case["difference"]["deployment_time_s"] is None
    # The exact trajectory creeps towards the stall angle and never passes it.
    late = prediction.trajectory("exact", [1e3, 1e5]).angle[:, 0]
    assert np.all(late <= stall)
    assert late[-1] == pytest.approx(stall, rel=1e-9)


def test_stall_at_release_when_start_torque_below_friction() -> None:
    system = paper_system(start_torque=0.9, end_torque=0.5)  # 0.9 < F_25 = 1.00466
    prediction = predict(system, [25.0])
    for solution in prediction.solutions.values():
        assert bool(solution.stalled[0])
        assert solution.stall_angle[0] == 0.0
        assert solution.start_speed[0] == 0.0
    trajectory = prediction.trajectory("exact", [0.0, 10.0])
    np.testing.assert_array_equal(trajectory.angle[:, 0], [0.0, 0.0])
    paper_traj = prediction.trajectory("paper", [0.0, 10.0])
    np.testing.assert_array_equal(paper_traj.angle[:, 0], [0.0, 0.0])


def test_constant_torque_spring_has_no_method_difference() -> None:
    # Ts == Te: both methods give B L / (T - F) exactly (log mean of equal values).
    system = paper_system(start_torque=2.0, end_torque=2.0)
    prediction = predict(system, [25.0])
    expected = 23.65272 * 1.57 / (2.0 - 1.00466)
    for solution in prediction.solutions.values():
        assert solution.deployment_time[0] == pytest.approx(expected, rel=1e-12)


def test_rising_spring_torque() -> None:
    # Torque rising along the travel (k < 0): the same closed form holds.
    system = paper_system(start_torque=1.58, end_torque=3.73)
    t_exact = predict(system, [25.0]).solutions["exact"].deployment_time[0]
    assert t_exact == pytest.approx(hand.exact_time(25.0, ts=1.58, te=3.73), rel=1e-12)


def tabulated_system() -> tuple[DeploymentSystem, list[float], list[float]]:
    angles = [0.0, 0.5, 1.2, 1.57]
    torques = [3.9, 3.0, 2.4, 1.6]
    base = paper_system()
    load = Load(
        TabulatedSpring(tuple(angles), tuple(torques)),
        1.57,
        LinearTemperatureLaw(-0.0044, 0.58),
    )
    return DeploymentSystem(base.ecd, load), angles, torques


def test_tabulated_spring_sum_of_segments_by_hand() -> None:
    system, angles, torques = tabulated_system()
    friction = hand.fecd(25.0) + hand.fs(25.0)
    b = hand.becd(25.0)
    expected = 0.0
    for i in range(3):
        a_i, b_i = torques[i] - friction, torques[i + 1] - friction
        length = angles[i + 1] - angles[i]
        expected += b * length * math.log(a_i / b_i) / (a_i - b_i)  # B L / logmean
    result = predict(system, [25.0]).solutions["exact"]
    assert result.deployment_time[0] == pytest.approx(expected, rel=1e-12)


def test_tabulated_spring_matches_solve_ivp() -> None:
    system, angles, torques = tabulated_system()
    friction = hand.fecd(100.0) + hand.fs(100.0)

    def spring(phi: float) -> float:
        return float(np.interp(phi, angles, torques))

    t_ref, _ = reference.deploy(spring, friction, hand.becd(100.0), 1.57)
    assert t_ref is not None
    result = predict(system, [100.0]).solutions["exact"]
    # The kinks at the breakpoints cost the reference a little accuracy: 1e-7.
    assert result.deployment_time[0] == pytest.approx(t_ref, rel=1e-7)


def test_tabulated_spring_stall_inside_a_segment() -> None:
    # Net torque at 25 degC: 2.9 at 0, 1.4 at 1.0, -0.4 at 1.57: crosses zero in segment 2.
    friction = hand.fecd(25.0) + hand.fs(25.0)
    base = paper_system()
    angles, torques = (0.0, 1.0, 1.57), (3.9, 2.4, 0.6)
    load = Load(TabulatedSpring(angles, torques), 1.57, LinearTemperatureLaw(-0.0044, 0.58))
    result = predict(DeploymentSystem(base.ecd, load), [25.0]).solutions["exact"]
    a, b = 2.4 - friction, 0.6 - friction
    expected = 1.0 + a / (a - b) * 0.57
    assert bool(result.stalled[0])
    assert result.stall_angle[0] == pytest.approx(expected, rel=1e-12)


def test_table_longer_than_travel_is_cut_at_the_travel() -> None:
    base = paper_system()
    # A linear table that runs past the travel is the linear spring of Eq. 7.
    slope = (3.73 - 1.58) / 1.57
    load = Load(
        TabulatedSpring((0.0, 2.0), (3.73, 3.73 - 2.0 * slope)),
        1.57,
        LinearTemperatureLaw(-0.0044, 0.58),
    )
    result = predict(DeploymentSystem(base.ecd, load), [25.0]).solutions["exact"]
    assert result.deployment_time[0] == pytest.approx(hand.exact_time(25.0), rel=1e-12)


def test_batch_2d_temperatures_by_samples() -> None:
    # 3 temperatures x 4 samples of the start torque, against the scalar closed form.
    starts = np.array([3.5, 3.73, 4.0, 4.5])
    system = paper_system()
    load = Load(LinearSpring(starts, 1.58), 1.57, system.load.system_friction)
    batch = DeploymentSystem(system.ecd, load)
    temps = np.array(TEMPS)[:, None]
    prediction = predict(batch, temps)
    times = prediction.solutions["exact"].deployment_time
    assert times.shape == (3, 4)
    for i, t in enumerate(TEMPS):
        for j, ts in enumerate(starts):
            assert times[i, j] == pytest.approx(hand.exact_time(t, ts=float(ts)), rel=1e-12)
    trajectory = prediction.trajectory("exact", np.linspace(0.0, 10.0, 5))
    assert trajectory.angle.shape == (5, 3, 4)
    paper_times = prediction.solutions["paper"].deployment_time
    assert paper_times[2, 1] == pytest.approx(hand.paper_time(100.0), rel=1e-12)


def test_problem_aligns_batch_axes() -> None:
    # Breakpoints (2,) with friction (3,): the batch axes broadcast to (2, 3).
    problem = QuasiStaticProblem(
        angles=np.array([0.0, 1.0]),
        torques=np.array([[2.0, 2.0, 2.0], [1.0, 1.0, 1.0]]),
        friction=np.array([0.1, 0.2, 0.3]),
        damping_rate=np.array(10.0),
    )
    assert problem.angles.shape == (2, 3)
    solution = EXACT.solve(problem)
    # B L ln(a/b)/(a - b) with a = 2 - F, b = 1 - F, L = 1, B = 10.
    for j, f in enumerate([0.1, 0.2, 0.3]):
        a, b = 2.0 - f, 1.0 - f
        assert solution.deployment_time[j] == pytest.approx(10.0 * math.log(a / b), rel=1e-12)
    # Eq. 8-11 by hand, B L / ((a + b)/2): rounding only.
    paper_time = PAPER.solve(problem).deployment_time[0]
    assert paper_time == pytest.approx(10.0 / ((1.9 + 0.9) / 2), rel=1e-12)
    with pytest.raises(ValueError, match="breakpoints"):
        QuasiStaticProblem(np.array([0.0, 1.0]), np.array([1.0]), np.array(0.0), np.array(1.0))


def test_tabulated_spring_over_several_temperatures() -> None:
    # Regression: a spring table with a temperature coefficient, solved at three
    # temperatures at once (1-D) and against samples (2-D), equals the scalar solutions.
    base = paper_system()
    spring = TabulatedSpring((0.0, 0.8, 1.57), (3.73, 2.6, 1.58), temperature_coefficient=-3e-4)
    system = DeploymentSystem(base.ecd, Load(spring, 1.57, base.load.system_friction))
    sweep = predict(system, TEMPS).solutions["exact"].deployment_time
    for i, t in enumerate(TEMPS):
        single = predict(system, t).solutions["exact"].deployment_time
        assert sweep[i] == pytest.approx(float(single), rel=1e-14)
    # Hand: torques scale by 1 - 3e-4 (T - 25); two segments of B L / logmean.
    factor = 1.0 - 3e-4 * (-40.0 - 25.0)
    friction = hand.fecd(-40.0) + hand.fs(-40.0)
    nets = [3.73 * factor - friction, 2.6 * factor - friction, 1.58 * factor - friction]
    lengths = [0.8, 0.77]
    expected = sum(
        hand.becd(-40.0) * length * math.log(a / b) / (a - b)
        for length, a, b in zip(lengths, nets[:-1], nets[1:], strict=True)
    )
    assert sweep[0] == pytest.approx(expected, rel=1e-12)
    travels = np.array([1.2, 1.57])
    batch = DeploymentSystem(base.ecd, Load(spring, travels, base.load.system_friction))
    grid = predict(batch, np.array(TEMPS)[:, None]).solutions["exact"].deployment_time
    assert grid.shape == (3, 2)
    assert grid[0, 1] == pytest.approx(sweep[0], rel=1e-14)


def test_paper_peak_speed_sees_a_mid_travel_peak() -> None:
    # A spring whose torque peaks mid-travel: both methods report the same physical
    # peak speed, (5.0 - F) / B at the middle breakpoint, for the linear-range check.
    base = paper_system()
    spring = TabulatedSpring((0.0, 0.8, 1.57), (3.0, 5.0, 2.0))
    system = DeploymentSystem(base.ecd, Load(spring, 1.57, base.load.system_friction))
    prediction = predict(system, [25.0])
    expected = (5.0 - hand.fecd(25.0) - hand.fs(25.0)) / hand.becd(25.0)
    for solution in prediction.solutions.values():
        assert solution.max_speed[0] == pytest.approx(expected, rel=1e-12)


def test_paper_trajectory_follows_eq13() -> None:
    prediction = predict(paper_system(), [25.0])
    dt = hand.paper_time(25.0)
    friction = hand.fecd(25.0) + hand.fs(25.0)
    ws = (3.73 - friction) / hand.becd(25.0)
    we = (1.58 - friction) / hand.becd(25.0)
    t = np.array([0.0, dt / 3.0, dt, 2.0 * dt])
    trajectory = prediction.trajectory("paper", t)
    expected = ws * t[:3] + 0.5 * (we - ws) / dt * t[:3] ** 2  # phi = travel - theta (Eq. 13)
    np.testing.assert_allclose(trajectory.angle[:3, 0], expected, rtol=1e-12)
    assert trajectory.angle[3, 0] == pytest.approx(1.57)  # latched
    assert trajectory.speed[1, 0] == pytest.approx(ws + (we - ws) / dt * dt / 3.0, rel=1e-12)
    assert trajectory.speed[3, 0] == 0.0
