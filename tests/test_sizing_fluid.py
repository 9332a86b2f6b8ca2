"""Fluid damper: the viscosity laws through their defining points, hand-checked
interpolation, the deadband, the power-law damper, and the ECD comparison by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ecdsim.config import ConfigError, load_config, parse_config
from ecdsim.sizing.fluid import (
    AndradeLaw,
    WaltherLaw,
    andrade_fit,
    compare_fluid,
    deploy_with_deadband,
    free_motion,
    power_law_segment_duration,
    walther_fit,
)
from ecdsim.solvers import QuasiStaticProblem
from tests import hand
from tests.conftest import PAPER_CONFIG, ROOT

K = 273.15
# The fits are linear least squares on O(1) numbers: agreement with a hand formula is at
# float rounding, amplified by exp() or 10**10**() to at most ~1e-12 relative.
FIT = 1e-11


def test_andrade_reproduces_two_points_and_interpolates_by_hand() -> None:
    law = AndradeLaw.fit([(-40.0, 40.0), (100.0, 3.5)])
    assert float(law(-40.0)) == pytest.approx(40.0, rel=FIT)
    assert float(law(100.0)) == pytest.approx(3.5, rel=FIT)
    # By hand: ln(mu) is linear in 1/T_K between the two points.
    x1, x2, x = 1 / (K - 40.0), 1 / (K + 100.0), 1 / (K + 25.0)
    expected = math.exp(math.log(40.0) + (math.log(3.5) - math.log(40.0)) * (x - x1) / (x2 - x1))
    assert float(law(25.0)) == pytest.approx(expected, rel=FIT)


def test_andrade_least_squares_through_three_points() -> None:
    # Points on an exact Andrade curve (A = -3, B = 1500 K) are recovered exactly ...
    temps = np.array([-40.0, 25.0, 100.0])
    on_curve = np.exp(-3.0 + 1500.0 / (temps + K))
    a, b = andrade_fit(temps, on_curve)
    assert a == pytest.approx(-3.0, rel=FIT)
    assert b == pytest.approx(1500.0, rel=FIT)
    # ... and off the curve the residuals meet the normal equations of the line fit in
    # (1/T_K, ln mu): sum(r) = 0 and sum(r * x) = 0 (the definition of least squares).
    off = on_curve * np.array([1.1, 0.95, 1.05])
    a, b = andrade_fit(temps, off)
    x = 1.0 / (temps + K)
    residual = np.log(off) - (a + b * x)
    assert abs(residual.sum()) < 1e-12
    assert abs((residual * x).sum()) < 1e-14  # x ~ 3e-3, so the sum is ~1e-3 smaller
    assert np.max(np.abs(residual)) > 1e-3  # not an exact fit: it is least squares


def test_walther_reproduces_two_points_and_interpolates_by_hand() -> None:
    nu1, nu2 = 32e-6, 5.4e-6  # 32 and 5.4 mm^2/s at 40 and 100 degC
    law = WaltherLaw.fit([(40.0, nu1), (100.0, nu2)])
    assert float(law(40.0)) == pytest.approx(nu1, rel=FIT)
    assert float(law(100.0)) == pytest.approx(nu2, rel=FIT)

    # By hand: log10 log10(nu_cSt + 0.7) is linear in log10 T_K (ASTM D341).
    def w(nu: float) -> float:
        return math.log10(math.log10(nu * 1e6 + 0.7))

    l1, l2, lx = math.log10(K + 40.0), math.log10(K + 100.0), math.log10(K + 80.0)
    wx = w(nu1) + (w(nu2) - w(nu1)) * (lx - l1) / (l2 - l1)
    expected = (10 ** (10**wx) - 0.7) * 1e-6
    assert float(law(80.0)) == pytest.approx(expected, rel=FIT)


def test_walther_least_squares_through_three_points() -> None:
    temps = np.array([0.0, 40.0, 100.0])
    nu = np.array([90e-6, 32e-6, 5.4e-6])
    a, b = walther_fit(temps, nu)
    x = np.log10(temps + K)
    residual = np.log10(np.log10(nu * 1e6 + 0.7)) - (a - b * x)
    assert abs(residual.sum()) < 1e-13
    assert abs((residual * x).sum()) < 1e-12


# A linear spring and constant friction for deadband cases, all numbers by hand.
TS, TE, L, F, FS = 2.0, 1.0, 1.5, 0.4, 0.1  # N*m, N*m, rad, N*m (damped phase), N*m (free)


def problem(c: float) -> QuasiStaticProblem:
    return QuasiStaticProblem(np.array([0.0, L]), np.array([TS, TE]), np.array(F), np.array(c))


def test_deadband_then_exact_damped_phase_by_hand() -> None:
    c, d = 3.0, math.radians(15.0)
    run = deploy_with_deadband(problem(c), FS, d)
    k = (TS - TE) / L
    a = TS - k * d - F  # net torque on engagement
    expected = c / k * math.log(a / (a - k * (L - d)))
    assert float(run.damped_time) == pytest.approx(expected, rel=1e-12)
    assert float(run.end_speed) == pytest.approx((TE - F) / c, rel=1e-12)
    assert run.free_time is None  # no inertia: the deadband time is not computed
    assert run.total_time is None


def test_free_motion_through_a_deadband_by_hand() -> None:
    # J phi'' = a0 - k phi from rest: phi = (a0/k)(1 - cos(wn t)), wn = sqrt(k/J).
    j, d = 0.05, math.radians(15.0)
    a0, k = TS - FS, (TS - TE) / L
    wn = math.sqrt(k / j)
    t_hand = math.acos(1.0 - k * d / a0) / wn
    v_hand = math.sqrt(2.0 * (a0 * d - 0.5 * k * d * d) / j)
    time, speed = free_motion([0.0, L], [TS, TE], FS, d, j)
    assert time == pytest.approx(t_hand, rel=1e-10)  # quad to 1e-12 relative
    assert speed == pytest.approx(v_hand, rel=1e-12)
    run = deploy_with_deadband(problem(3.0), FS, d, inertia=j)
    assert run.free_time is not None
    assert run.total_time is not None
    assert float(run.free_time) == pytest.approx(t_hand, rel=1e-10)
    assert float(run.total_time) == pytest.approx(t_hand + float(run.damped_time), rel=1e-10)


def test_free_motion_across_a_spring_table_breakpoint() -> None:
    # Reference: solve_ivp of J phi'' = T(phi) - FS with a tight tolerance.
    angles, torques, j, d = [0.0, 0.1, 1.0], [2.0, 0.6, 0.5], 0.02, 0.3

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        return [float(y[1]), (float(np.interp(y[0], angles, torques)) - FS) / j]

    def arrive(_t: float, y: np.ndarray) -> float:
        return float(y[0]) - d

    arrive.terminal = True  # type: ignore[attr-defined]
    sol = solve_ivp(rhs, (0.0, 10.0), [0.0, 0.0], rtol=1e-11, atol=1e-13, events=arrive,
                    method="DOP853")  # fmt: skip
    time, speed = free_motion(angles, torques, FS, d, j)
    # The reference integrates across the slope change at 0.1 rad with rtol 1e-11.
    assert time == pytest.approx(float(sol.t_events[0][0]), rel=1e-8)
    assert speed == pytest.approx(float(sol.y_events[0][0][1]), rel=1e-8)


def test_stall_inside_the_deadband() -> None:
    # Spring torque falls below FS = 0.1 at 0.2 rad, inside a 0.3 rad deadband.
    p = QuasiStaticProblem(
        np.array([0.0, 0.2, 1.0]), np.array([0.5, 0.05, 0.05]), np.array(0.01), np.array(1.0)
    )
    assert bool(deploy_with_deadband(p, 0.1, 0.3).stalled)
    # With inertia the work of the net torque decides. It peaks where T = FS and is least
    # at the deadband's end: W(0.3) = 0.2 * (0.4 - 0.05) / 2 - 0.1 * 0.05 = 0.03 > 0, so
    # the load coasts through; after engagement 0.05 N*m exceeds the friction 0.01 N*m.
    inertial = deploy_with_deadband(p, 0.1, 0.3, inertia=1.0)
    assert inertial.free_time is not None
    assert inertial.engage_speed is not None
    assert np.isfinite(float(inertial.free_time))
    assert float(inertial.engage_speed) == pytest.approx(math.sqrt(2 * 0.03 / 1.0), rel=1e-12)
    assert not bool(inertial.stalled)
    # A heavier system friction FS = 0.25: W(0.3) = 0.2 * (0.25 - 0.2) / 2 - 0.1 * 0.2 < 0.
    assert bool(deploy_with_deadband(p, 0.25, 0.3, inertia=1.0).stalled)
    with pytest.raises(ValueError, match="not shorter than the travel"):
        deploy_with_deadband(p, 0.1, 1.0)


def test_power_law_damper_against_hand_integral_and_solve_ivp() -> None:
    c, n = 1.7, 0.8  # torque = c * omega**0.8 (shear thinning)
    k = (TS - TE) / L
    a, b = TS - F, TE - F
    p = 1.0 / n
    hand_time = c**p * (a ** (1 - p) - b ** (1 - p)) / (k * (1 - p))
    run = deploy_with_deadband(problem(c), FS, 0.0, exponent=n)
    assert float(run.damped_time) == pytest.approx(hand_time, rel=1e-12)
    assert float(run.end_speed) == pytest.approx((b / c) ** p, rel=1e-12)

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        return [((TS - k * float(y[0]) - F) / c) ** p]

    def arrive(_t: float, y: np.ndarray) -> float:
        return float(y[0]) - L

    arrive.terminal = True  # type: ignore[attr-defined]
    sol = solve_ivp(rhs, (0.0, 100.0), [0.0], rtol=1e-11, atol=1e-13, events=arrive,
                    method="DOP853")  # fmt: skip
    assert float(run.damped_time) == pytest.approx(float(sol.t_events[0][0]), rel=1e-9)
    # Equal start and end torque: t = L c^p a^(-p) (constant speed).
    flat = power_law_segment_duration(L, c, n, 1.2, 1.2)
    assert float(flat) == pytest.approx(L * c**p * 1.2 ** (-p), rel=1e-14)
    # n -> 1 approaches the exact solver's log-mean time B L / logmean(a, b).
    near = power_law_segment_duration(L, c, 1.0 + 1e-7, a, b)
    assert float(near) == pytest.approx(c * L * math.log(a / b) / (a - b), rel=1e-6)


def test_compare_fluid_on_the_example_by_hand() -> None:
    config = load_config(ROOT / "examples" / "fluid.toml")
    spec = config.spec.fluid_damper
    assert spec is not None
    result = compare_fluid(config.system, spec, (-40.0, 25.0, 100.0))
    # Matched at 25 degC: c(25) = BECD(25) by hand (Eq. 1 and 3).
    assert result.matched_coefficient == pytest.approx(hand.becd(25.0), rel=1e-12)
    assert float(result.fluid_coefficient[1]) == pytest.approx(hand.becd(25.0), rel=1e-12)
    assert result.viscosity is not None  # a viscosity law (not a measured power law)
    for i, t in enumerate((-40.0, 25.0, 100.0)):
        # The ECD has no lost motion in the paper config: its time is the exact one.
        assert float(result.ecd.damped_time[i]) == pytest.approx(hand.exact_time(t), rel=1e-12)
        # Fluid: c(T) = BECD(25) * mu(T)/mu(25), same friction FECD + FS, 15 deg deadband.
        c = hand.becd(25.0) * float(result.viscosity[i]) / float(result.viscosity[1])
        d = math.radians(15.0)
        k = (3.73 - 1.58) / 1.57
        a = 3.73 - k * d - (hand.fecd(t) + hand.fs(t))
        expected = c / k * math.log(a / (a - k * (1.57 - d)))
        assert float(result.fluid.damped_time[i]) == pytest.approx(expected, rel=1e-12)
    # Cold makes the fluid far slower than the ECD, heat far faster (the paper's point).
    assert result.fluid.damped_time[0] > 2 * result.ecd.damped_time[0]
    assert result.fluid.damped_time[2] < result.ecd.damped_time[2]
    document = result.to_dict()
    assert document["fluid_damper"]["law"] == "andrade"
    assert document["fluid_damper"]["source"] == "illustrative, not vendor data"
    assert [c["temperature_C"] for c in document["cases"]] == [-40.0, 25.0, 100.0]


def test_power_law_matching_speed() -> None:
    # n != 1: equal torque at the ECD's mean speed at T_match (travel / exact time).
    text = (
        (ROOT / "examples" / "fluid.toml").read_text().replace("exponent = 1.0", "exponent = 0.7")
    )
    config = parse_config(text)
    spec = config.spec.fluid_damper
    assert spec is not None
    result = compare_fluid(config.system, spec, (25.0,))
    speed = 1.57 / hand.exact_time(25.0)
    assert result.match_speed == pytest.approx(speed, rel=1e-12)
    assert result.matched_coefficient == pytest.approx(
        hand.becd(25.0) * speed ** (1 - 0.7), rel=1e-12
    )


FLUID = """
[fluid_damper]
source = "test"
law = "{law}"
{table}
"""


@pytest.mark.parametrize(
    ("law", "table", "fragment"),
    [
        ("walther", 'dynamic_viscosity = [["25 degC", "1 Pa*s"], ["80 degC", "0.5 Pa*s"]]',
         "defined on kinematic viscosity"),
        ("andrade", 'dynamic_viscosity = [["25 degC", "1 Pa*s"]]', "at least two"),
        ("walther", 'kinematic_viscosity = [["25 degC", "1 mm^2/s"], ["80 degC", "0.5 cSt"]]',
         "below 2 mm^2/s"),
        ("andrade", 'dynamic_viscosity = [["25 degC", "1 Pa*s"], ["25 degC", "2 Pa*s"]]',
         "repeated temperatures"),
        ("andrade", "", "give exactly one of"),
        ("fluid", 'dynamic_viscosity = [["25 degC", "1 Pa*s"], ["80 degC", "0.5 Pa*s"]]',
         "fluid_damper.law"),
        ("andrade", 'dynamic_viscosity = [["25 degC", "1 m^2/s"], ["80 degC", "0.5 Pa*s"]]',
         "wrong dimension"),
    ],
)  # fmt: skip
def test_bad_fluid_section(law: str, table: str, fragment: str) -> None:
    text = PAPER_CONFIG.read_text() + FLUID.format(law=law, table=table)
    with pytest.raises(ConfigError) as raised:
        parse_config(text)
    assert any(fragment in line for line in raised.value.problems), raised.value.problems


def test_deadband_across_spring_table_breakpoints_against_solve_ivp() -> None:
    # A table whose first two breakpoints lie inside a 0.3 rad deadband; the damped phase
    # is checked against tests/reference.py (solve_ivp of B phi' = T(phi + d) - F).
    from tests import reference

    angles, torques = [0.0, 0.1, 0.2, 0.9, 1.2], [3.0, 2.6, 2.5, 1.6, 1.5]
    d, c, friction = 0.3, 4.0, 0.8
    p = QuasiStaticProblem(np.array(angles), np.array(torques), np.array(friction), np.array(c))
    run = deploy_with_deadband(p, 0.2, d)

    def torque(phi: float) -> float:
        return float(np.interp(phi + d, angles, torques))

    expected, _ = reference.deploy(torque, friction, c, 1.2 - d)
    assert expected is not None
    # reference.py integrates with rtol 1e-10.
    assert float(run.damped_time) == pytest.approx(expected, rel=1e-8)
