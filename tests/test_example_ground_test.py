"""The shipped ground-test example (issue 16): resistive table, gravity and two-node heating.

``examples/paper_cc16_ground_test.toml`` is the paper's Cc-16 example with a harness table,
a 1 g test partly offloaded, and a rotor/housing network. Its exact deployment times in
the ground test and in flight are checked here against the quasi-static time integral
typed from the paper's equations and integrated by ``scipy.integrate.quad``:

    t = integral over phi of BECD_T / (T_spring - T_resist - T_gravity - FS_T - FECD_T)

(paper Eq. 1-4 and 12: the load turns at omega = net torque / BECD_T), with the
example's constants written out below rather than read from ecdsim.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "paper_cc16_ground_test.toml"

N = 380.0
TRAVEL = 1.57  # rad
G = 9.80665  # m/s^2, standard gravity
TABLE_ANGLE = np.radians([0.0, 45.0, 90.0])
TABLE_TORQUE = np.array([0.06, 0.08, 0.10])  # N*m, opposing deployment


def _terms(temp: float) -> tuple[float, float, float]:
    """BECD_T, FECD_T and FS_T of the example at ``temp`` degC (paper Eq. 1-6)."""
    bd = 1.3e-4 * (1.0 - 0.004 * (temp - 25.0))  # Eq. 1
    bg = 0.26 * 1.3e-4  # the gearbox damping fraction of the reference BD
    fl = -2.12e-6 * temp + 2.2e-4  # lubrication
    becd = N**2 * (bd + bg)  # Eq. 3
    fecd = N * (7.9e-4 + 4.5e-4 + fl)  # Eq. 4: FD + FG + FL_T
    fs = -0.0044 * temp + 0.58
    return becd, fecd, fs


def _time(temp: float, gravity: bool) -> float:
    becd, fecd, fs = _terms(temp)
    # 1.2 kg at 0.3 m, 95 % offloaded, released at -60 deg from the downward vertical.
    amplitude = 1.2 * G * 0.3 * (1.0 - 0.95) if gravity else 0.0

    def rate(phi: float) -> float:
        spring = 3.73 + (1.58 - 3.73) * phi / TRAVEL
        resist = float(np.interp(phi, TABLE_ANGLE, TABLE_TORQUE))
        weight = amplitude * math.sin(math.radians(-60.0) + phi)
        return becd / (spring - resist - weight - fs - fecd)

    # The table's kink at 45 deg is a break point of the integrand's derivative.
    value, _ = quad(rate, 0.0, TRAVEL, points=[math.radians(45.0)], epsabs=0.0, epsrel=1e-13)
    return float(value)


@pytest.fixture(scope="module")
def document() -> dict[str, object]:
    done = subprocess.run(
        [sys.executable, "-m", "ecdsim", "deploy", str(EXAMPLE), "--json"],
        capture_output=True,
        text=True,
        check=False,
        cwd=ROOT,
    )
    assert done.returncode == 0, done.stderr
    result: dict[str, object] = json.loads(done.stdout)
    return result


@pytest.mark.parametrize(("index", "temp"), [(0, -40.0), (1, 25.0), (2, 100.0)])
def test_exact_times_in_test_and_flight_match_the_integral(
    document: dict[str, object], index: int, temp: float
) -> None:
    ground = document["ground_test"]
    assert isinstance(ground, dict)
    row = ground["cases"][index]
    assert row["temperature_C"] == temp
    exact = row["exact"]
    # The exact method with gravity integrates to a stated 1e-9 (docs/model.md); flight
    # is piecewise linear and exact to round-off; quad runs at 1e-13.
    assert exact["test_deployment_time_s"] == pytest.approx(_time(temp, True), rel=1e-9)
    assert exact["flight_deployment_time_s"] == pytest.approx(_time(temp, False), rel=1e-12)


def test_the_ground_test_is_slower_than_flight_at_every_temperature(
    document: dict[str, object],
) -> None:
    # Gravity aids at release (-60 deg) and opposes at the latch (+30 deg), where the net
    # torque is smallest: the integral weights the end, so the test is slower. The
    # hand-typed integrals say the same at each temperature.
    ground = document["ground_test"]
    assert isinstance(ground, dict)
    for row in ground["cases"]:
        temp = row["temperature_C"]
        assert _time(temp, True) > _time(temp, False)
        assert row["exact"]["test_minus_flight_s"] > 0.0
        assert row["dynamic"]["test_minus_flight_s"] > 0.0


def test_repeated_deployments_of_the_example_settle_and_heat_the_rotor() -> None:
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "ecdsim",
            "repeat",
            str(EXAMPLE),
            "--count",
            "30",
            "--cool-down",
            "60 s",
            "--stow-time",
            "30 s",
            "-T",
            "25",
            "--json",
        ],
        capture_output=True,
        text=True,
        check=False,
        cwd=ROOT,
    )
    assert done.returncode == 0, done.stderr
    case = json.loads(done.stdout)["cases"][0]
    runs = case["deployments"]
    times = np.array(runs["deployment_time_s"])
    start = np.array(runs["start_rotor_temperature_C"])
    end = np.array(runs["end_rotor_temperature_C"])
    # Deployment 1 starts cold: it is the single deployment of `ecdsim deploy` (the same
    # dynamic method on the same system; the integrator's rtol 1e-8 bounds the rest).
    single = document_at_25c()
    assert times[0] == pytest.approx(single, rel=1e-9)
    assert start[0] == 25.0
    # Each later one starts between the environment and where the last one ended (the
    # network only relaxes during cool-down and stow), and a warmer rotor damps less
    # (Eq. 1 with a < 0): the times never grow.
    assert np.all((start[1:] > 25.0) & (start[1:] < end[:-1]))
    assert np.all(np.diff(times) <= 0.0)
    assert case["drift"]["deployment_time_s"] == pytest.approx(times[-1] - times[0], abs=1e-12)


def document_at_25c() -> float:
    """The dynamic deployment time of the example at +25 degC from `ecdsim deploy -T 25`."""
    done = subprocess.run(
        [sys.executable, "-m", "ecdsim", "deploy", str(EXAMPLE), "-T", "25", "--json"],
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
    )
    return float(json.loads(done.stdout)["cases"][0]["dynamic"]["deployment_time_s"])


def test_the_notebook_api_gives_the_ground_test_and_its_flight_twin() -> None:
    import ecdsim

    result = ecdsim.deploy(EXAMPLE, temperatures=[25], methods="exact")
    # The same hand-typed integrals as the command line's (rel 1e-9: the quadrature path).
    assert result.deployment_time()[25.0] == pytest.approx(_time(25.0, True), rel=1e-9)
    flight = result.flight_deployment_time()
    assert flight is not None
    assert flight[25.0] == pytest.approx(_time(25.0, False), rel=1e-12)
    assert ecdsim.deploy(ROOT / "examples" / "paper_cc16.toml").flight_deployment_time() is None
