"""[load.gravity] (issue 16 item 2): gravity in ground tests, quasi-static methods.

Every expected number comes from a hand calculation written here (the closed form of
int du / (a - W sin u), arcsin for a stall, Eq. 8-11 with the end torques) or from
scipy.integrate.quad at epsabs = epsrel = 1e-13 of the same quasi-static equation
B dphi/dt = T(phi) - F - m g r (1 - offload) sin(theta_0 + phi).
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.config import ConfigError, parse_config
from ecdsim.deployment import predict
from ecdsim.physics.gravity import STANDARD_GRAVITY, gravity_torque
from ecdsim.solvers.exact_gravity import (
    GAUSS_WEIGHTS,
    KRONROD_WEIGHTS,
    NODES,
    solve_flat,
)
from tests import hand

ROOT = Path(__file__).resolve().parent.parent

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "paper_cc16.toml"
TEXT = EXAMPLE.read_text()
TEMPERATURES = (-40.0, 25.0, 100.0)
G = 9.80665  # standard gravity, m/s^2 (CGPM 1901), typed here on its own


def _gravity(mass: str, radius: str, angle: str, offload: str | None = None) -> str:
    lines = ["[load.gravity]", f'mass = "{mass}"', f'cg_radius = "{radius}"']
    lines.append(f'release_angle = "{angle}"')
    if offload is not None:
        lines.append(f'offload = "{offload}"')
    return TEXT + "\n" + "\n".join(lines) + "\n"


def _constant_spring(text: str, torque: str) -> str:
    return text.replace('start_torque = "3.73 N*m"', f'start_torque = "{torque}"').replace(
        'end_torque = "1.58 N*m"', f'end_torque = "{torque}"'
    )


def _quad_time(drive: object, b: float, travel: float) -> float:
    """B * int_0^travel dphi / N(phi), scipy's QUADPACK at 1e-13."""
    value, _ = quad(lambda x: 1.0 / drive(x), 0.0, travel, epsabs=1e-13, epsrel=1e-13, limit=500)  # type: ignore[operator]
    return b * float(value)


def test_standard_gravity_and_the_torque_formula() -> None:
    assert STANDARD_GRAVITY == G
    # m g r sin(theta_0 + phi): 2 kg at 0.5 m, arm horizontal after 60 deg from 30 deg.
    assert float(gravity_torque(math.radians(60.0), 2 * G * 0.5, math.radians(30.0))) == (
        pytest.approx(2 * G * 0.5, rel=1e-15)  # sin(90 deg) = 1: rounding only
    )


def test_the_kronrod_and_gauss_rules_integrate_polynomials_exactly() -> None:
    # K15 is exact to degree 22, G7 to degree 13 (QUADPACK); on [-1, 1], int x^k = 2/(k+1).
    for k in range(0, 23, 2):
        assert float(KRONROD_WEIGHTS @ NODES**k) == pytest.approx(2 / (k + 1), rel=1e-14)
    for k in range(0, 14, 2):
        assert float(GAUSS_WEIGHTS @ NODES**k) == pytest.approx(2 / (k + 1), rel=1e-14)


def test_a_constant_spring_under_gravity_matches_the_closed_form() -> None:
    # Spring 3 N*m everywhere: N(phi) = a - W sin(u), u = theta_0 + phi, a = 3 - F.
    # int du / (a - W sin u) = 2/s atan((a tan(u/2) - W)/s), s = sqrt(a^2 - W^2),
    # continuous for u in (-pi, pi): theta_0 = -30 deg, travel 90 deg keeps u there.
    mass, radius, offload = 3.0, 0.2, 0.9
    w = mass * G * radius * (1 - offload)
    text = _gravity("3 kg", "0.2 m", "-30 deg", "0.9")
    text = _constant_spring(text, "3 N*m").replace('travel = "1.57 rad"', 'travel = "90 deg"')
    config = parse_config(text)
    found = predict(config.system, np.array(TEMPERATURES), ("exact",)).solutions["exact"]
    u0, u1 = math.radians(-30.0), math.radians(60.0)
    for i, t in enumerate(TEMPERATURES):
        a = 3.0 - hand.fecd(t) - hand.fs(t)
        s = math.sqrt(a * a - w * w)

        def primitive(u: float, a: float = a, s: float = s) -> float:
            return 2.0 / s * math.atan((a * math.tan(u / 2.0) - w) / s)

        expected = hand.becd(t) * (primitive(u1) - primitive(u0))
        # 1e-9: the stated accuracy of the adaptive quadrature (solvers/exact_gravity.py)
        assert float(found.deployment_time[i]) == pytest.approx(expected, rel=1e-9)
        assert float(found.start_speed[i]) == pytest.approx(
            (a - w * math.sin(u0)) / hand.becd(t),
            rel=1e-12,  # Eq. 5 at release
        )
        assert float(found.end_speed[i]) == pytest.approx(
            (a - w * math.sin(u1)) / hand.becd(t),
            rel=1e-12,  # Eq. 5 at the latch
        )
        # the slowest point is where sin u = 1, past the travel; the fastest at release
        assert float(found.max_speed[i]) == pytest.approx(float(found.start_speed[i]), rel=1e-12)


@pytest.mark.parametrize("angle", ["30 deg", "-120 deg", "170 deg", "-60 deg"])
def test_the_paper_example_under_gravity_matches_quad(angle: str) -> None:
    # The paper's falling spring with gravity aiding, opposing and changing sign over the
    # travel, against QUADPACK on the same equation written here.
    text = _gravity("1 kg", "0.25 m", angle, "0.9")
    config = parse_config(text)
    found = predict(config.system, np.array(TEMPERATURES), ("exact",)).solutions["exact"]
    w = 1.0 * G * 0.25 * 0.1
    theta0 = math.radians(float(angle.split()[0]))
    for i, t in enumerate(TEMPERATURES):
        f = hand.fecd(t) + hand.fs(t)

        def drive(phi: float, f: float = f) -> float:
            spring = hand.TS + (hand.TE - hand.TS) * phi / hand.TRAVEL
            return spring - f - w * math.sin(theta0 + phi)

        assert not found.stalled[i]
        expected = _quad_time(drive, hand.becd(t), hand.TRAVEL)
        # 1e-9: the stated accuracy (quad at 1e-13 is far tighter)
        assert float(found.deployment_time[i]) == pytest.approx(expected, rel=1e-9)


def test_a_grazing_minimum_is_integrated_to_the_stated_accuracy() -> None:
    # N(phi) = a - W sin(phi) with a just above W: a minimum of depth 1e-6 N*m at
    # phi = pi/2, where 1/N peaks at 1e6. Compared with quad told where the peak is.
    w = 1.0
    a = w + 1e-6
    angles = np.array([[0.0], [2.0]])
    net = np.array([[a], [a]])
    found = solve_flat(angles, net, np.array([w]), np.array([0.0]), np.array([1.0]))
    value, _ = quad(
        lambda x: 1.0 / (a - w * math.sin(x)),
        0.0,
        2.0,
        points=[math.pi / 2],
        epsabs=1e-13,
        epsrel=1e-13,
        limit=1000,
    )
    assert not found.stalled[0]
    assert found.integral.converged[0]
    # 1e-9: the stated accuracy
    assert float(found.time[0]) == pytest.approx(value, rel=1e-9)


def test_a_stall_under_gravity_is_found_where_the_sine_reaches_the_drive() -> None:
    # Constant net drive a against W sin(phi) with W > a: the first zero is at
    # phi = asin(a / W) by hand; the time is infinite there (a simple zero: log).
    a, w = 0.5, 1.0
    found = solve_flat(
        np.array([[0.0], [2.0]]),
        np.array([[a], [a]]),
        np.array([w]),
        np.array([0.0]),
        np.array([1.0]),
    )
    assert found.stalled[0]
    assert math.isinf(float(found.time[0]))
    # 1e-15 relative: the root is refined to the last bits of a double
    assert float(found.stall_angle[0]) == pytest.approx(math.asin(a / w), rel=1e-15)
    assert float(found.end_speed[0]) == 0.0


def test_a_stall_after_a_breakpoint_on_a_falling_piece() -> None:
    # Two pieces: net 1.0 -> 0.6 over [0, 1], then 0.6 -> 0.2 over [1, 2]; W = 0.5 with
    # theta_0 = 0. The zero of 0.6 - 0.4 (x - 1) - 0.5 sin x on the second piece, by
    # bisection written here to 1e-15.
    angles = np.array([[0.0], [1.0], [2.0]])
    net = np.array([[1.0], [0.6], [0.2]])
    found = solve_flat(angles, net, np.array([0.5]), np.array([0.0]), np.array([2.0]))

    def n(x: float) -> float:
        return 1.0 - 0.4 * x - 0.5 * math.sin(x)

    lo, hi = 0.0, 2.0  # n(0) = 1 > 0, n(2) = 0.2 - 0.45 < 0; n decreasing on [0, 2]
    while hi - lo > 1e-15:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if n(mid) > 0 else (lo, mid)
    assert found.stalled[0]
    # 1e-14: the bisection above stops at 1e-15 rad
    assert float(found.stall_angle[0]) == pytest.approx(lo, abs=1e-14)


def test_the_paper_method_uses_the_end_point_torques_less_gravity() -> None:
    # Eq. 8-11 by hand with Ts - W sin(theta_0) and Te - W sin(theta_0 + travel).
    config = parse_config(_gravity("2 kg", "0.3 m", "30 deg", "0.9"))
    found = predict(config.system, np.array(TEMPERATURES), ("paper",)).solutions["paper"]
    w = 2 * G * 0.3 * 0.1
    theta0 = math.radians(30.0)
    for i, t in enumerate(TEMPERATURES):
        ts = hand.TS - w * math.sin(theta0)
        te = hand.TE - w * math.sin(theta0 + hand.TRAVEL)
        if te <= hand.fecd(t) + hand.fs(t):
            continue  # stalls (checked below)
        # 1e-12: the same arithmetic in another order
        assert float(found.deployment_time[i]) == pytest.approx(
            hand.paper_time(t, ts=ts, te=te), rel=1e-12
        )
    # -40 degC: Te - W sin(30 deg + 1.57 rad) = 1.58 - 0.51 = 1.07 against F = 1.34 by
    # hand: the drive reaches the friction before the latch, both methods stall there.
    assert bool(found.stalled[0])
    exact = predict(config.system, np.array(TEMPERATURES), ("exact",)).solutions["exact"]
    assert float(found.stall_angle[0]) == float(exact.stall_angle[0])


@pytest.mark.parametrize("gravity", [("0 kg", "0.3 m", "0"), ("2 kg", "0.3 m", "1")])
def test_no_gravity_torque_gives_exactly_todays_results(gravity: tuple[str, str, str]) -> None:
    # Zero mass or a full offload: no torque, the gravity-free path, bit for bit.
    mass, radius, offload = gravity
    plain = parse_config(TEXT)
    weightless = parse_config(_gravity(mass, radius, "30 deg", offload))
    temps = np.array(TEMPERATURES)
    a = predict(plain.system, temps, ("paper", "exact"))
    b = predict(weightless.system, temps, ("paper", "exact"))
    for method in ("paper", "exact"):
        for name in ("deployment_time", "start_speed", "end_speed", "max_speed"):
            assert np.array_equal(
                getattr(a.solutions[method], name), getattr(b.solutions[method], name)
            )


def test_the_exact_trajectory_under_gravity_follows_the_quadrature() -> None:
    # At half the deployment time the angle is where B int_0^phi dx / N = t_half: the
    # root of that, by quad and bisection here.
    config = parse_config(_gravity("1.5 kg", "0.25 m", "-120 deg", "0.8"))
    prediction = predict(config.system, np.array([25.0]), ("exact",))
    total = float(prediction.solutions["exact"].deployment_time[0])
    path = prediction.trajectory("exact", np.array([0.0, 0.5 * total, 2.0 * total]))
    w = 1.5 * G * 0.25 * 0.2
    theta0 = math.radians(-120.0)
    f = hand.fecd(25.0) + hand.fs(25.0)

    def n(phi: float) -> float:
        spring = hand.TS + (hand.TE - hand.TS) * phi / hand.TRAVEL
        return spring - f - w * math.sin(theta0 + phi)

    def time_to(phi: float) -> float:
        return _quad_time(n, hand.becd(25.0), phi)

    lo, hi = 0.0, hand.TRAVEL
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if time_to(mid) < 0.5 * total else (lo, mid)
    assert float(path.angle[0, 0]) == 0.0
    # 1e-7 rad: cubic Hermite interpolation between 48 cells per monotone piece
    assert float(path.angle[1, 0]) == pytest.approx(lo, abs=1e-7)
    assert float(path.speed[1, 0]) == pytest.approx(n(lo) / hand.becd(25.0), rel=1e-6)
    assert float(path.angle[2, 0]) == pytest.approx(hand.TRAVEL, abs=1e-12)


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("mass", "-1 kg", "must be >= 0"),
        ("mass", "2 m", "mass"),
        ("cg_radius", "-0.1 m", "must be >= 0"),
        ("offload", "1.5", "must be in [0, 1]"),
        ("offload", "-0.1", "must be in [0, 1]"),
        ("mass", "nan kg", "mass"),
        ("release_angle", "nan deg", "release_angle"),
    ],
)
def test_bad_gravity_keys_are_refused_by_name(
    key: str, value: str, message: str, tmp_path: Path
) -> None:
    values = {"mass": "2 kg", "cg_radius": "0.3 m", "release_angle": "30 deg", "offload": "0.5"}
    values[key] = value
    text = _gravity(values["mass"], values["cg_radius"], values["release_angle"], values["offload"])
    with pytest.raises(ConfigError, match=f"load.gravity.{key}") as caught:
        parse_config(text)
    assert message in str(caught.value)
    path = tmp_path / "bad.toml"
    path.write_text(text)
    result = CliRunner().invoke(app, ["deploy", str(path)])
    assert result.exit_code == 2
    assert "Traceback" not in result.output


def test_the_dynamic_method_takes_gravity_and_shows_flight_beside_it(tmp_path: Path) -> None:
    # Flight and test by the dynamic method too: the flight time equals the dynamic
    # method's on the config without [load.gravity].
    import json

    inertia = 'travel = "1.57 rad"\ninertia = "5 kg*m^2"'
    text = _gravity("2 kg", "0.3 m", "30 deg", "0.9").replace('travel = "1.57 rad"', inertia)
    path = tmp_path / "ground.toml"
    path.write_text(text)
    result = CliRunner().invoke(app, ["deploy", str(path), "-m", "dynamic", "--json"])
    assert result.exit_code == 0, result.output
    ground = json.loads(result.stdout)["ground_test"]
    plain = parse_config(TEXT.replace('travel = "1.57 rad"', inertia))
    temps = np.array(plain.temperatures)
    flight = predict(plain.system, temps, ("dynamic",), dynamics=plain.spec.dynamics())
    for i, case in enumerate(ground["cases"]):
        time = float(flight.solutions["dynamic"].deployment_time[i])
        expected = time if math.isfinite(time) else None
        assert case["dynamic"]["flight_deployment_time_s"] == expected


def test_deploy_shows_flight_and_ground_test_side_by_side(tmp_path: Path) -> None:
    # The JSON's ground_test block: flight = the config without [load.gravity], test =
    # the config as given, their difference; the table prints both at 80 columns.
    import json

    text = _gravity("1 kg", "0.25 m", "-60 deg", "0.9")
    path = tmp_path / "ground.toml"
    path.write_text(text)
    runner = CliRunner()
    result = runner.invoke(app, ["deploy", str(path), "--json"])
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    ground = document["ground_test"]
    temps = np.array(parse_config(text).temperatures)
    flight = predict(parse_config(TEXT).system, temps, ("paper", "exact"))
    test = predict(parse_config(text).system, temps, ("paper", "exact"))
    w = 1.0 * G * 0.25 * 0.1
    # 1e-15: W sin(-60 deg) and W sin(-60 deg + 1.57 rad) typed here, rounding only
    assert ground["torque_at_release_Nm"] == pytest.approx(w * math.sin(math.radians(-60)))
    assert ground["torque_at_latch_Nm"] == pytest.approx(
        w * math.sin(math.radians(-60) + 1.57), rel=1e-15
    )
    for i, case in enumerate(ground["cases"]):
        for method in ("paper", "exact"):
            t_flight = float(flight.solutions[method].deployment_time[i])
            t_test = float(test.solutions[method].deployment_time[i])
            block = case[method]
            assert block["flight_deployment_time_s"] == t_flight
            assert block["test_deployment_time_s"] == t_test
            assert block["test_minus_flight_s"] == t_test - t_flight
    wide = runner.invoke(app, ["deploy", str(path)], env={"COLUMNS": "80"})
    assert wide.exit_code == 0
    assert "Flight (0 g) against ground test (1 g, 90 % offloaded)" in wide.stdout
    assert "Deployment (ground test, 1 g)" in wide.stdout
    assert all(len(line) <= 80 for line in wide.stdout.splitlines())
    plain = tmp_path / "flight.toml"
    plain.write_text(TEXT)
    flight_only = json.loads(runner.invoke(app, ["deploy", str(plain), "--json"]).stdout)
    assert "ground_test" not in flight_only


def test_the_report_and_the_explorer_api_carry_flight_and_test() -> None:
    # The report's ground-test table and the explorer's /api/deploy JSON hold the same
    # flight and test times as predict without and with the section.
    from fastapi.testclient import TestClient

    from ecdsim.report.builder import predict_config, render_html
    from ecdsim.webapp.server import create_app

    text = _gravity("1 kg", "0.25 m", "-60 deg", "0.9")
    config = parse_config(text)
    temps = np.array(config.temperatures)
    flight = predict(parse_config(TEXT).system, temps, ("paper", "exact"))
    html = render_html(config, predict_config(config), text)
    assert 'id="ground-test"' in html
    assert "Flight (0 g) against ground test (1 g, 90 % offloaded)" in html
    plain_html = render_html(parse_config(TEXT), predict_config(parse_config(TEXT)), TEXT)
    assert 'id="ground-test"' not in plain_html
    # The figures are the ground test's and say so; without gravity they say nothing.
    assert "Deployed angle against time (paper Fig. 4-6) (ground test, 1 g)" in html
    assert "(ground test, 1 g)" not in plain_html
    client = TestClient(create_app(None), base_url="http://localhost")
    raw = client.post("/api/config/parse", json={"toml": text}).json()["config"]
    body = client.post("/api/deploy", json={"config": raw, "sweep_points": 0}).json()
    ground = body["prediction"]["ground_test"]
    for i, case in enumerate(ground["cases"]):
        expected = float(flight.solutions["exact"].deployment_time[i])
        assert case["exact"]["flight_deployment_time_s"] == expected


def test_monte_carlo_samples_the_gravity_inputs_case_by_case() -> None:
    # A batch of sampled masses, radii and offloads solves as each scalar case does.
    from ecdsim.montecarlo.apply import NotTolerable, Parameters, apply, nominal

    config = parse_config(_gravity("1 kg", "0.25 m", "-60 deg", "0.9"))
    base = Parameters(config.system)
    assert nominal(base, "load.gravity.mass") == 1.0
    assert nominal(base, "load.gravity.offload") == 0.9
    with pytest.raises(NotTolerable, match=r"\[load.gravity\], which this config does not"):
        nominal(Parameters(parse_config(TEXT).system), "load.gravity.mass")
    values = {
        "load.gravity.mass": np.array([0.5, 1.0, 2.0]),
        "load.gravity.cg_radius": np.array([0.2, 0.25, 0.3]),
        "load.gravity.offload": np.array([0.95, 0.9, 0.85]),
    }
    batch = apply(base, values).system
    temps = np.array([[-40.0], [25.0]])
    found = predict(batch, temps, ("exact",)).solutions["exact"].deployment_time
    for j in range(3):
        scalar = parse_config(
            _gravity(
                f"{values['load.gravity.mass'][j]} kg",
                f"{values['load.gravity.cg_radius'][j]} m",
                "-60 deg",
                f"{values['load.gravity.offload'][j]}",
            )
        )
        one = predict(scalar.system, temps[:, 0], ("exact",)).solutions["exact"].deployment_time
        # 1e-12: the same quadrature, in a batch or alone (its tolerance is relative to
        # each case's own integral)
        np.testing.assert_allclose(found[:, j], one, rtol=1e-12)


def test_an_offload_spread_beyond_one_is_refused() -> None:
    from ecdsim.montecarlo.tolerances import resolve

    text = _gravity("1 kg", "0.25 m", "-60 deg", "0.9") + (
        '\n[tolerances.quantities]\n"load.gravity.offload" = '
        '{ distribution = "uniform", plus_minus = "0.2" }\n'
    )
    with pytest.raises(ConfigError, match="must stay <= 1"):
        resolve(parse_config(text))


def test_the_torque_margin_counts_opposing_gravity_as_its_own_kind() -> None:
    # Spring 3 N*m over [0, pi], F = 1 N*m, T_g = sin(phi) (W = 1, theta_0 = 0), factor
    # 2 on gravity, no damping torque: TM = 3 / (1 + 2 sin(phi)) - 1, smallest at
    # phi = pi/2 (a grid point: 64 of 128 steps): 3 / 3 - 1 = 0, by hand.
    from ecdsim.sizing.margin import MarginSettings, margin_over_travel

    settings = MarginSettings(factors={"gravity": 2.0})
    terms = margin_over_travel(
        np.array([0.0, math.pi]),
        np.array([3.0, 3.0]),
        ecd_friction=0.6,
        system_friction=0.4,
        damping_rate=10.0,
        stalled=False,
        stall_angle=math.nan,
        settings=settings,
        gravity_amplitude=1.0,
        gravity_angle=0.0,
    ).at_minimum()
    # 1e-12: sin(pi/2) in floating point
    assert float(terms.margin) == pytest.approx(0.0, abs=1e-12)
    assert float(terms.angle) == pytest.approx(math.pi / 2, rel=1e-15)
    assert float(terms.resistive["gravity"]) == pytest.approx(1.0, rel=1e-15)
    # Gravity aiding everywhere (theta_0 = -pi: T_g = -sin(phi) <= 0) is not credited:
    # TM = 3 / 1 - 1 = 2 at every point.
    aided = margin_over_travel(
        np.array([0.0, math.pi]),
        np.array([3.0, 3.0]),
        ecd_friction=0.6,
        system_friction=0.4,
        damping_rate=10.0,
        stalled=False,
        stall_angle=math.nan,
        settings=settings,
        gravity_amplitude=1.0,
        gravity_angle=-math.pi,
    ).at_minimum()
    assert float(aided.margin) == pytest.approx(2.0, rel=1e-12)
    assert float(aided.resistive["gravity"]) == 0.0


def test_monte_carlo_torque_margin_counts_gravity(tmp_path: Path) -> None:
    # Fixed damping speed 0, factor 2 on gravity; theta_0 = -60 deg, so gravity opposes
    # only past phi = 60 deg and grows to W sin(30 deg) at the latch while the spring
    # falls: the margin is lowest at the end of travel, Te / (F + 2 W sin(30 deg)) - 1 by
    # hand (the sampled mass has a tiny spread; the nominal case is checked).
    from ecdsim.config import load_config
    from ecdsim.montecarlo import build_plan, run
    from ecdsim.montecarlo.stats import summarize
    from tests.test_montecarlo_config import write_config

    requirements = (
        '\n[requirements]\ntemperatures = ["25 degC"]\nmin_torque_margin = 0.1\n'
        '[requirements.torque_margin]\ndamping_speed = "0 rad/s"\n'
        "factors = { gravity = 2.0 }\n"
    )
    base = _gravity("1.2 kg", "0.3 m", "-60 deg", "0.9") + requirements
    config = load_config(
        write_config(
            tmp_path,
            '"load.gravity.mass" = { distribution = "uniform", plus_minus = "0.1 %" }',
            'sampling = "random"\nseed = 7\nchunk_size = 64',
            base=base,
        )
    )
    plan = build_plan(config, 64, temperatures=[25.0])
    run(plan, tmp_path / "run")
    case = summarize(plan, tmp_path / "run")["cases"][0]
    w = 1.2 * G * 0.3 * 0.1
    f = hand.fecd(25.0) + hand.fs(25.0)
    expected = hand.TE / (f + 2.0 * w * math.sin(math.radians(-60.0) + hand.TRAVEL)) - 1.0
    # 1e-12: the same arithmetic at the last breakpoint
    assert case["nominal"]["min_torque_margin"] == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize(
    ("command", "example"),
    [
        (["fit", "trace", "examples/deployment_trace.csv", "--config"], "paper_cc16.toml"),
        (["compare-fluid"], "fluid.toml"),
    ],
)
def test_commands_without_gravity_refuse_a_ground_test(
    command: list[str], example: str, tmp_path: Path
) -> None:
    # Both build their own piecewise-linear problems: with a gravity torque they would
    # fit or compare a load that is not the configured one. They refuse, naming the key.
    text = (ROOT / "examples" / example).read_text(encoding="utf-8")
    at = text.index("[analysis]")
    gravity = (
        '[load.gravity]\nmass = "1.2 kg"\ncg_radius = "0.3 m"\n'
        'release_angle = "-60 deg"\noffload = 0.9\n\n'
    )
    config = tmp_path / "ground.toml"
    config.write_text(text[:at] + gravity + text[at:], encoding="utf-8")
    done = subprocess.run(
        [sys.executable, "-m", "ecdsim", *command, str(config)],
        capture_output=True,
        text=True,
        check=False,
        cwd=ROOT,
    )
    assert done.returncode == 2, done.stdout + done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert "load.gravity" in lines[0], done.stderr
    assert "Traceback" not in done.stderr
