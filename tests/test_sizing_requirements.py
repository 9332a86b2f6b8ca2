"""Each requirement filter and the torque margin on hand-built cases, hand-calculated.

The hand system: BD = 0.01 N*m*s/rad, no temperature change, BG = 0, N = 10 -> BECD =
1.0 N*m*s/rad; FD = 0.01 N*m, FG = 0 -> FECD = 0.1 N*m; FS = 0.1 N*m; spring 1.2 -> 0.7
N*m over 1 rad. Net torque a = 1.0 at the start, b = 0.5 at the end, slope k = 0.5 N*m/rad.
Exact time t = (B/k) ln(a/b) = 2 ln 2 s; start speed 1.0, end speed 0.5 rad/s; peak ECD
input torque FECD + B * 1.0 = 1.1 N*m (= Ts - FS); stall margin (Te - F)/F = 0.5/0.2.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ecdsim.config import ConfigError, parse_config
from ecdsim.model import Ecd, Gearbox, HighSpeedDamper, LinearSpring, LinearTemperatureLaw, Load
from ecdsim.sizing.margin import MarginSettings, margin_over_travel, torque_margin
from ecdsim.sizing.requirements import (
    Requirements,
    max_time_margin,
    min_time_margin,
    stall_margin,
    upper_limit_margin,
)
from ecdsim.sizing.search import Evaluation, Limits, evaluate
from tests.conftest import PAPER_CONFIG

T_HAND = 2.0 * math.log(2.0)  # exact deployment time of the hand system [s]
TEMPS = (0.0, 50.0)  # the hand system does not depend on temperature


def hand_ecd(end_torque: float = 0.7) -> tuple[Ecd, Load]:
    damper = HighSpeedDamper(damping_rate=0.01, coulomb_friction=0.01,
                             damping_temperature_coefficient=0.0)  # fmt: skip
    gearbox = Gearbox(ratio=np.array([[10.0]]), coulomb_friction=0.0, damping_rate=0.0)
    load = Load(LinearSpring(1.2, end_torque), 1.0, LinearTemperatureLaw(0.0, 0.1))
    return Ecd(damper, gearbox), load


def run(
    requirements: Requirements, end_torque: float = 0.7, limits: Limits | None = None
) -> Evaluation:
    ecd, load = hand_ecd(end_torque)
    return evaluate(ecd, load, requirements, limits)


def outcome(requirements: Requirements, name: str) -> float:
    return float(run(requirements).check(name).worst()[0])


# Every margin below is compared at rel 1e-12: the code and the hand formula do the same
# few float operations on O(1) numbers, so they agree to rounding.
TIGHT = 1e-12


def test_time_window_filters() -> None:
    r = Requirements(TEMPS, min_deployment_time=1.0, max_deployment_time=1.5)
    evaluation = run(r)
    assert evaluation.prediction.solutions["exact"].deployment_time[0, 0] == pytest.approx(
        T_HAND, rel=TIGHT
    )
    assert float(evaluation.check("min_deployment_time").worst()[0]) == pytest.approx(
        1.0 - 1.0 / T_HAND, rel=TIGHT
    )
    assert float(evaluation.check("max_deployment_time").worst()[0]) == pytest.approx(
        1.5 / T_HAND - 1.0, rel=TIGHT
    )
    assert bool(evaluation.passed()[0])
    too_slow = Requirements(TEMPS, max_deployment_time=1.3)  # 1.3 s < 1.386 s: fails
    assert outcome(too_slow, "max_deployment_time") == pytest.approx(1.3 / T_HAND - 1.0, rel=TIGHT)
    assert not bool(run(too_slow).passed()[0])
    too_fast = Requirements(TEMPS, min_deployment_time=1.5)  # 1.386 s < 1.5 s: fails
    assert outcome(too_fast, "min_deployment_time") == pytest.approx(1.0 - 1.5 / T_HAND, rel=TIGHT)
    assert not bool(run(too_fast).passed()[0])


def test_end_speed_and_input_torque_filters() -> None:
    ok = Requirements(TEMPS, max_end_speed=0.6, max_input_torque=1.2)
    assert outcome(ok, "max_end_speed") == pytest.approx((0.6 - 0.5) / 0.6, rel=TIGHT)
    assert outcome(ok, "max_input_torque") == pytest.approx((1.2 - 1.1) / 1.2, rel=TIGHT)
    assert bool(run(ok).passed()[0])
    bad = Requirements(TEMPS, max_end_speed=0.4, max_input_torque=1.0)
    assert outcome(bad, "max_end_speed") == pytest.approx((0.4 - 0.5) / 0.4, rel=TIGHT)
    assert outcome(bad, "max_input_torque") == pytest.approx((1.0 - 1.1) / 1.0, rel=TIGHT)
    assert not bool(run(bad).passed()[0])


def test_stall_filter() -> None:
    r = Requirements(TEMPS, max_deployment_time=10.0)
    assert outcome(r, "no_stall") == pytest.approx(0.5 / 0.2, rel=TIGHT)
    # End torque 0.15 N*m below the friction 0.2 N*m: stalls; margin (0.15 - 0.2)/0.2.
    stalled = run(r, end_torque=0.15)
    assert float(stalled.check("no_stall").worst()[0]) == pytest.approx(-0.25, rel=TIGHT)
    # A stalled deployment never arrives: the time margin is t_max/inf - 1 = -1 exactly.
    assert float(stalled.check("max_deployment_time").worst()[0]) == -1.0
    assert not bool(stalled.passed()[0])
    free = Requirements(TEMPS, no_stall=False)
    assert [c.name for c in run(free, end_torque=0.15).checks] == []


def test_torque_margin_at_a_fixed_speed() -> None:
    # Damping at 0.2 rad/s: R = F + B*0.2 = 0.2 + 0.2 = 0.4 N*m; the minimum is at the end
    # of travel (Te = 0.7): 0.7/0.4 - 1 = 0.75 (at the start 1.2/0.4 - 1 = 2).
    r = Requirements(TEMPS, min_torque_margin=0.5, margin=MarginSettings(damping_speed=0.2))
    evaluation = run(r)
    assert float(evaluation.torque_margin[0, 0]) == pytest.approx(0.75, rel=TIGHT)
    assert float(evaluation.torque_margin_angle[0, 0]) == pytest.approx(1.0, rel=TIGHT)
    assert outcome(r, "min_torque_margin") == pytest.approx(0.75 - 0.5, rel=TIGHT)
    # Friction factor 2: R = 0.4 + 0.2 = 0.6 -> 0.7/0.6 - 1.
    factored = MarginSettings(factors={"friction": 2.0}, damping_speed=0.2)
    evaluation = run(Requirements(TEMPS, min_torque_margin=0.5, margin=factored))
    assert float(evaluation.torque_margin[0, 0]) == pytest.approx(0.7 / 0.6 - 1.0, rel=TIGHT)
    assert not bool(evaluation.passed()[0])
    # A harness allowance of 0.1 N*m with factor 3 adds 0.3: R = 0.7 -> margin 0.
    harness = MarginSettings(
        factors={"harness": 3.0}, allowances={"harness": 0.1}, damping_speed=0.2
    )
    evaluation = run(Requirements(TEMPS, margin=harness))
    assert float(evaluation.torque_margin[0, 0]) == pytest.approx(0.0, abs=1e-15)


def test_torque_margin_at_the_deployment_speed() -> None:
    # Damping at the deployment's own speed (damping_speed None): B*omega = T - F, so with
    # unit factors the resistance equals the drive everywhere the mechanism moves: margin
    # 0 exactly.
    evaluation = run(Requirements(TEMPS, margin=MarginSettings(damping_speed=None)))
    assert np.all(evaluation.torque_margin == 0.0)
    # Friction factor 2: margin = T/(2F + T - F) - 1 = -F/(T + F), lowest where T is lowest
    # (the end of travel): -0.2/0.9.
    factored = Requirements(
        TEMPS, margin=MarginSettings(factors={"friction": 2.0}, damping_speed=None)
    )
    evaluation = run(factored)
    assert float(evaluation.torque_margin[0, 0]) == pytest.approx(-0.2 / 0.9, rel=TIGHT)
    assert float(evaluation.torque_margin_angle[0, 0]) == pytest.approx(1.0, rel=TIGHT)


def test_margin_over_travel_minimum_is_exact_between_breakpoints() -> None:
    # A three-point spring table with a stall: the minimum found at breakpoints and the
    # stall point equals a brute-force minimum over 20001 angles of the hand formula.
    angles = np.array([0.0, 0.4, 1.0])
    torques = np.array([1.0, 0.9, 0.1])
    friction, damping, speed = 0.3, 2.0, None
    factors = {"friction": 1.5, "damping": 1.2}
    stall = 0.4 + 0.6 * (0.9 - 0.3) / (0.9 - 0.1)
    result = margin_over_travel(
        angles, torques, ecd_friction=friction, system_friction=0.0, damping_rate=damping,
        stalled=True, stall_angle=stall, settings=MarginSettings(factors, {}, speed),
    )  # fmt: skip
    low, where = result.minimum()
    phi = np.linspace(0.0, 1.0, 20001)
    spring = np.interp(phi, angles, torques)
    omega = np.maximum(spring - friction, 0.0) / damping
    brute = spring / (1.5 * friction + 1.2 * damping * omega) - 1.0
    # The minimum is at the end of travel (T = 0.1 < F): 0.1/0.45 - 1, a grid point.
    assert float(low) == pytest.approx(brute.min(), rel=TIGHT)
    assert float(low) == pytest.approx(0.1 / 0.45 - 1.0, rel=TIGHT)
    assert float(where) == 1.0  # the table's last breakpoint itself


def test_margin_functions_by_hand() -> None:
    assert float(torque_margin(2.0, {"ecd_friction": 0.5, "damping": 0.5}, {})) == 1.0
    assert float(torque_margin(1.0, {"system_friction": 0.0}, {})) == np.inf  # nothing resists
    with pytest.raises(KeyError, match="unknown resistive torque"):
        torque_margin(1.0, {"wind": 1.0}, {})
    assert float(min_time_margin(np.inf, 5.0)) == 1.0
    assert float(max_time_margin(np.inf, 5.0)) == -1.0
    assert float(upper_limit_margin(3.0, np.nan)) == np.inf  # no limit given
    # Friction <= 0 (a law outside its range): +inf if the spring stays above it.
    assert float(stall_margin(np.array([1.0, 0.5]), 0.0)) == np.inf
    assert float(stall_margin(np.array([1.0, 0.5]), 0.25)) == pytest.approx(1.0, rel=TIGHT)


def test_catalogue_limits() -> None:
    # Peak input speed 1.0 rad/s -> damper shaft 10 rad/s; eddy torque BD*10 = 0.1 N*m;
    # damper shaft torque 0.1 + FD = 0.11 N*m; ECD input torque 1.1 N*m.
    limits = Limits(
        damper_max_torque=np.array([0.1]),
        damper_max_linear_speed=np.array([12.0]),
        damper_max_linear_torque=np.array([0.08]),
        gearbox_max_output_torque=np.array([1.0]),
    )
    evaluation = run(Requirements(TEMPS, no_stall=False), limits=limits)
    expected = {
        "damper_max_torque": (0.1 - 0.11) / 0.1,
        "damper_linear_speed": (12.0 - 10.0) / 12.0,
        "damper_linear_torque": (0.08 - 0.1) / 0.08,
        "gearbox_max_output_torque": (1.0 - 1.1) / 1.0,
    }
    for name, margin in expected.items():
        assert float(evaluation.check(name).worst()[0]) == pytest.approx(margin, rel=1e-9)
    none = Limits(*(np.array([np.nan]) for _ in range(4)))
    assert run(Requirements(TEMPS, no_stall=False), limits=none).checks == ()


def test_worst_temperature_is_found() -> None:
    # FS = 0.1 - 0.001 T: 0.15 N*m at -50 degC, 0.05 at +50. Colder is slower:
    # t(T) = (B/k) ln(a/(a - k L)) with a = 1.2 - 0.1 - FS(T).
    ecd, _ = hand_ecd()
    load = Load(LinearSpring(1.2, 0.7), 1.0, LinearTemperatureLaw(-0.001, 0.1))
    r = Requirements((-50.0, 50.0), max_deployment_time=2.0)
    evaluation = evaluate(ecd, load, r, None)
    check = evaluation.check("max_deployment_time")
    a = 1.2 - 0.1 - 0.15
    t_cold = (1.0 / 0.5) * math.log(a / (a - 0.5))
    assert int(check.worst_index()[0]) == 0
    assert float(check.values[0, 0]) == pytest.approx(t_cold, rel=TIGHT)
    assert float(check.worst()[0]) == pytest.approx(2.0 / t_cold - 1.0, rel=TIGHT)


REQUIREMENTS = """
[requirements]
min_deployment_time = "10 s"
max_deployment_time = "1 min"
temperature_range = ["-40 degC", "100 degC"]
temperatures = ["25 degC", "-40 degC"]
max_end_speed = "6 deg/s"
min_torque_margin = 0.1
[requirements.torque_margin]
damping_speed = "0.005 rad/s"
factors = { friction = 2 }
allowances = { harness = "10 N*mm" }
"""


def test_requirements_section_parses_to_si() -> None:
    config = parse_config(PAPER_CONFIG.read_text() + REQUIREMENTS)
    assert config.spec.requirements is not None
    r = Requirements.from_spec(config.spec.requirements)
    assert r.temperatures == (-40.0, 25.0, 100.0)  # ends + listed, sorted, no repeats
    assert r.max_deployment_time == 60.0
    assert r.max_end_speed == pytest.approx(math.radians(6.0), rel=TIGHT)
    # `friction` is the factor of both Coulomb kinds (neither is given on its own).
    assert r.margin.factors["ecd_friction"] == r.margin.factors["system_friction"] == 2.0
    assert r.margin.factors["damping"] == 1.0
    assert r.margin.allowances == {"harness": pytest.approx(0.01)}
    assert r.margin.damping_speed == 0.005
    assert r.no_stall


@pytest.mark.parametrize(
    ("section", "fragment"),
    [
        ('min_deployment_time = "2 min"\nmax_deployment_time = "1 min"\n'
         'temperatures = ["25 degC"]', "must be below max_deployment_time"),
        ("no_stall = true", "give temperature_range"),
        ('temperatures = ["25 degC"]\nmax_end_speed = "3 N*m"', "requirements.max_end_speed"),
        ('temperatures = ["25 degC"]\n[requirements.torque_margin]\nfactors = { friction = 0.5 }',
         "must be >= 1"),
        ('temperatures = ["25 degC"]\n[requirements.torque_margin]\ndamping_speed = "fast"',
         'or "deployment"'),
        ('temperatures = ["25 degC"]\n[requirements.torque_margin]\n'
         'factors = { system_friction = 0.9 }', "system_friction: 0.9 must be >= 1"),
        ('temperature_range = ["100 degC", "-40 degC"]', "cold < hot"),
    ],
)  # fmt: skip
def test_bad_requirements_are_one_line_errors(section: str, fragment: str) -> None:
    with pytest.raises(ConfigError) as raised:
        parse_config(PAPER_CONFIG.read_text() + "\n[requirements]\n" + section + "\n")
    assert any(fragment in line for line in raised.value.problems), raised.value.problems
