"""Repeated deployments with cool-down and stow (issue 16, item 6; the paper's life test).

References: the relaxation between deployments as two exponentials written here by hand,
and the second deployment against the Radau rtol 1e-12 reference of
tests/test_two_node_heating.py started from those temperatures.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.config import load_config, parse_config
from ecdsim.deployment import predict
from ecdsim.dynamics import DynamicParameters, DynamicResult, Thermal
from ecdsim.dynamics.method import DynamicSolution
from ecdsim.dynamics.sequence import Cycle, run_sequence
from tests.conftest import ROOT, SavedFigures, paper_system
from tests.helptext import assert_options, read_help, run_example
from tests.test_two_node_heating import two_node_deploy

C_R, R_RH, C_H, R_HE = 0.002, 40.0, 0.2, 200.0  # rotor, rotor-housing, housing, mount
TEMPS = np.array([25.0, -40.0])
runner = CliRunner()


def _solve(params: DynamicParameters) -> DynamicResult:
    solution = predict(paper_system(), TEMPS, ["dynamic"], dynamics=params).solutions["dynamic"]
    assert isinstance(solution, DynamicSolution)
    return solution.result


def _params(thermal: Thermal | None, rtol: float = 1e-8) -> DynamicParameters:
    return DynamicParameters(load_inertia=1.0, thermal=thermal, rtol=rtol)


def relaxed(rotor: float, housing: float, t: float) -> tuple[float, float]:
    """theta(t) = exp(A t) theta0 by hand: A = [[-a, a], [b, -(b + d)]] (the two-node
    network without power), eigenvalues l from l^2 + (a + b + d) l + a d = 0,
    eigenvectors (a, l + a), theta = k1 v1 e^{l1 t} + k2 v2 e^{l2 t}."""
    a, b, d = 1.0 / (R_RH * C_R), 1.0 / (R_RH * C_H), 1.0 / (R_HE * C_H)
    tr = a + b + d
    root = math.sqrt(tr * tr / 4.0 - a * d)
    l1, l2 = -tr / 2.0 + root, -tr / 2.0 - root
    k2 = (housing - rotor * (l1 + a) / a) / (l2 - l1)
    k1 = rotor / a - k2
    e1, e2 = math.exp(l1 * t), math.exp(l2 * t)
    return k1 * a * e1 + k2 * a * e2, k1 * (l1 + a) * e1 + k2 * (l2 + a) * e2


def test_without_heating_there_is_no_drift() -> None:
    result = run_sequence(_solve, _params(None), TEMPS, Cycle(500, 60.0, 30.0))
    assert result.deployment_time.shape == (500, 2)
    assert np.all(result.drift()["deployment_time_s"] == 0.0)
    assert np.all(result.deployment_time == result.deployment_time[0])
    assert np.all(result.start_rotor_temperature == TEMPS)
    assert result.periodic_after == [1, 1]


def test_a_long_cool_down_makes_every_deployment_the_first() -> None:
    # 1e6 s against time constants below 30 s: exp(-1e6 / 30) is 0 in floating point,
    # so each deployment starts exactly at T, as the first did.
    thermal = Thermal(C_R, R_RH, C_H, R_HE)
    result = run_sequence(_solve, _params(thermal), TEMPS, Cycle(20, 1e6, 0.0))
    first = _solve(_params(thermal))
    assert np.array_equal(result.deployment_time, np.tile(first.deployment_time, (20, 1)))
    assert np.array_equal(result.start_rotor_temperature, np.tile(TEMPS, (20, 1)))
    assert np.array_equal(
        result.peak_rotor_temperature, np.tile(first.max_damper_temperature, (20, 1))
    )
    assert np.all(result.drift()["deployment_time_s"] == 0.0)
    assert result.periodic_after == [1, 1]


def test_two_deployments_by_hand() -> None:
    # Deployment 1 from T; the rotor and housing relax for cool-down + stow = 8 s (the
    # two exponentials above); deployment 2 starts there: its start temperatures are the
    # hand relaxation and its course is the Radau reference started from them.
    thermal = Thermal(C_R, R_RH, C_H, R_HE)
    result = run_sequence(_solve, _params(thermal, rtol=1e-10), TEMPS, Cycle(2, 5.0, 3.0))
    assert result.start_housing_temperature is not None
    assert result.end_housing_temperature is not None
    for j, temp in enumerate(TEMPS):
        rotor1 = result.end_rotor_temperature[0, j] - temp
        housing1 = result.end_housing_temperature[0, j] - temp
        rotor2, housing2 = relaxed(rotor1, housing1, 8.0)
        assert housing2 > 0.5  # heat is carried over: the case tests something
        # The closed forms agree to rounding (relative 1e-13 of the ~K rises).
        assert result.start_rotor_temperature[1, j] == pytest.approx(temp + rotor2, abs=1e-11)
        assert result.start_housing_temperature[1, j] == pytest.approx(temp + housing2, abs=1e-11)
        ref = two_node_deploy(temp, 1.0, C_R, R_RH, C_H, R_HE, start=(rotor2, housing2))
        # rtol 1e-10 against the rtol 1e-12 reference: a few 1e-10 of global error.
        assert result.deployment_time[1, j] == pytest.approx(ref.time, rel=1e-8)
        assert result.peak_rotor_temperature[1, j] == pytest.approx(ref.max_rotor, abs=1e-7)
        # The warmer damper damps less (Eq. 1): deployment 2 is faster.
        assert result.deployment_time[1, j] < result.deployment_time[0, j]


def test_a_short_cool_down_drifts_to_a_periodic_state() -> None:
    thermal = Thermal(C_R, R_RH, C_H, R_HE)
    cycle = Cycle(40, 5.0, 3.0)
    result = run_sequence(_solve, _params(thermal), TEMPS, cycle)
    drift = result.drift()
    assert np.all(drift["start_rotor_temperature_K"] > 0.0)
    assert np.all(drift["deployment_time_s"] < 0.0)
    assert all(k is not None and 1 < k < 40 for k in result.periodic_after)
    # In the periodic state the last deployment's end, relaxed over the interval, is its
    # own start again (to the periodic tolerance of 1e-3 K).
    assert result.end_housing_temperature is not None
    assert result.start_housing_temperature is not None
    for j, temp in enumerate(TEMPS):
        rotor, housing = relaxed(
            result.end_rotor_temperature[-1, j] - temp,
            result.end_housing_temperature[-1, j] - temp,
            cycle.interval,
        )
        assert rotor + temp == pytest.approx(result.start_rotor_temperature[-1, j], abs=1e-3)
        assert housing + temp == pytest.approx(result.start_housing_temperature[-1, j], abs=1e-3)
    document = json.loads(json.dumps(result.to_dict()))
    assert document["count"] == 40
    assert len(document["cases"][0]["deployments"]["deployment_time_s"]) == 40


@pytest.mark.parametrize(
    ("count", "cool_down", "stow", "message"),
    [(0, 1.0, 0.0, "count"), (3, -1.0, 0.0, "cool_down"), (3, 1.0, math.inf, "stow_time")],
)
def test_bad_cycle(count: int, cool_down: float, stow: float, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        Cycle(count, cool_down, stow)


# --- the command line ------------------------------------------------------------------


def _two_node_config(folder: Path) -> Path:
    """The paper's dynamic example with the two-node heating of the tests above."""
    text = (ROOT / "examples" / "paper_cc16_dynamic.toml").read_text("utf-8")
    text = text.replace(
        "[gearbox]",
        '[damper.thermal]\nheat_capacity = "0.002 J/K"\nthermal_resistance = "40 K/W"\n'
        'housing_heat_capacity = "0.2 J/K"\nhousing_thermal_resistance = "200 K/W"\n\n'
        "[gearbox]",
    )
    text = text.replace('inertia = "5 kg*m^2"', 'inertia = "1 kg*m^2"')
    path = folder / "life.toml"
    path.write_text(text, "utf-8")
    return path


def test_repeat_command(tmp_path: Path, saved_figures: SavedFigures) -> None:
    config = _two_node_config(tmp_path)
    args = ["repeat", str(config), "-n", "6", "--cool-down", "5", "--stow-time", "3 s"]
    document = runner.invoke(app, [*args, "-T", "25", "-T", "-40", "--json"])
    assert document.exit_code == 0, document.output
    cases = json.loads(document.stdout)["cases"]
    # The same sequence through the library: the command adds nothing of its own.
    loaded = load_config(config)
    params = loaded.spec.dynamics()
    assert params is not None
    assert params.thermal == Thermal(C_R, R_RH, C_H, R_HE)

    def solve(run: DynamicParameters) -> DynamicResult:
        solution = predict(loaded.system, TEMPS, ["dynamic"], dynamics=run).solutions["dynamic"]
        assert isinstance(solution, DynamicSolution)
        return solution.result

    direct = run_sequence(solve, params, TEMPS, Cycle(6, 5.0, 3.0))
    for j in range(2):
        assert cases[j]["deployments"]["deployment_time_s"] == direct.deployment_time[:, j].tolist()
    table = runner.invoke(app, [*args, "-T", "25", "--plot", str(tmp_path / "life.png")])
    assert table.exit_code == 0, table.output
    assert max(len(line) for line in table.stdout.splitlines()) <= 80
    assert "housing" in table.stdout  # the two-node column (its header may wrap)
    assert "[degC]" in table.stdout
    assert "drift 1 to 6" in table.stdout
    assert (tmp_path / "life.png").read_bytes().startswith(b"\x89PNG")
    # What a reader sees (saved_figures): the title, labelled axes, one legend entry per
    # temperature, and the plotted numbers are the JSON's deployments above.
    top, bottom = saved_figures.axes("life.png")
    title = top.get_title().replace("\n", " ")
    assert "6 deployments, cool-down 5 s, stow 3 s" in title
    assert top.get_ylabel() == "deployment time change\nfrom deployment 1 [%]"
    assert bottom.get_xlabel() == "deployment number [-]"
    assert "[K]" in bottom.get_ylabel()
    assert "rotor temperature above T" in bottom.get_ylabel()
    assert saved_figures.legend(top) == ["T = 25 degC"]
    assert saved_figures.legend(bottom) == ["peak, T = 25 degC", "start, T = 25 degC"]
    deployments = cases[0]["deployments"]  # the JSON's first case is +25 degC
    times = np.array(deployments["deployment_time_s"])
    number, change = (np.asarray(v) for v in top.get_lines()[0].get_data())
    assert number.tolist() == [1, 2, 3, 4, 5, 6]
    # Percent change from deployment 1, by hand from the JSON: rounding only.
    np.testing.assert_allclose(change, 100.0 * (times / times[0] - 1.0), rtol=1e-12, atol=1e-12)
    peak, start = (np.asarray(line.get_data()[1]) for line in bottom.get_lines()[:2])
    # The rises above +25 degC, by hand from the JSON: rounding only.
    expected_peak = np.array(deployments["peak_rotor_temperature_C"]) - 25.0
    expected_start = np.array(deployments["start_rotor_temperature_C"]) - 25.0
    np.testing.assert_allclose(peak, expected_peak, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(start, expected_start, rtol=1e-12, atol=1e-12)
    assert expected_peak.min() > 1.0  # a real rise, so that the check can fail


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--cool-down", "5 m"], "--cool-down"),
        (["--cool-down", "-5"], "--cool-down"),
        (["--cool-down", "5", "--stow-time", "x"], "--stow-time"),
        (["--cool-down", "5", "-n", "0"], "--count 0"),
    ],
)
def test_repeat_bad_options(tmp_path: Path, extra: list[str], message: str) -> None:
    result = runner.invoke(app, ["repeat", str(_two_node_config(tmp_path)), *extra])
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("error: ")
    assert message in lines[0]


def test_repeat_help(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    screen = read_help(runner, app, ["repeat"])
    assert_options(
        screen,
        {
            "--cool-down": None,
            "--count": "-n",
            "--stow-time": None,
            "--temperature": "-T",
            "--json": None,
            "--plot": None,
            "--units": None,
            "--wide": None,
            "--plain": None,
            "--help": None,
        },
    )
    run_example(runner, app, screen, tmp_path, monkeypatch)
    # --plot takes a folder, as in every command (issue 26 item 9).
    assert (tmp_path / "plots" / "repeat.png").read_bytes().startswith(b"\x89PNG")


def test_repeat_in_us_units(tmp_path: Path) -> None:
    """--units us: the temperatures in degF (-40 degC is -40 degF; 100 degC is 212), the
    drift in degF (9/5 of a kelvin), the stow heat in in*lbf."""
    config = ROOT / "examples" / "paper_cc16_ground_test.toml"
    args = ["repeat", str(config), "-n", "3", "--cool-down", "60 s", "--stow-time", "30 s"]
    si = runner.invoke(app, [*args, "-T", "100"], env={"COLUMNS": "200"})
    us = runner.invoke(app, [*args, "-T", "100", "--units", "us"], env={"COLUMNS": "200"})
    assert si.exit_code == 0, si.stderr
    assert us.exit_code == 0, us.stderr
    assert "Repeated deployments at T = 100 degC" in si.stdout
    assert "Repeated deployments at T = 212 degF" in us.stdout
    assert "[degF]" in us.stdout
    assert "[degC]" not in us.stdout

    def drift(text: str) -> float:
        return float(text.split("drift 1 to")[1].split("peak rotor ")[1].split()[0])

    # Both printed to 4 significant digits: a difference of 9/5 to that rounding.
    assert drift(us.stdout) == pytest.approx(1.8 * drift(si.stdout), rel=1e-3)
    assert " in*lbf per stow" in us.stdout
    assert " J per stow" in si.stdout


@pytest.mark.parametrize("resistance", [40.0, math.inf])
def test_one_node_cools_by_one_exponential(resistance: float) -> None:
    # One node: the rise decays as exp(-t / (R C)) over cool-down + stow; adiabatic
    # (R = inf) it does not decay at all, and each deployment starts where the last ended.
    thermal = Thermal(0.05, resistance)
    result = run_sequence(_solve, _params(thermal), TEMPS, Cycle(3, 2.0, 1.0))
    assert result.start_housing_temperature is None
    decay = math.exp(-3.0 / (resistance * 0.05))
    for k in (1, 2):
        expected = TEMPS + (result.end_rotor_temperature[k - 1] - TEMPS) * decay
        # exp and one product: rounding of the ~K rises only.
        np.testing.assert_allclose(result.start_rotor_temperature[k], expected, rtol=0, atol=1e-12)
    assert np.all(result.start_rotor_temperature[1] > TEMPS)  # heat carried over


# --- a deployment that never arrives ---------------------------------------------------

# The paper's friction (section 6) with a 600:1 gear instead of 380:1, by hand at -40 degC:
# FS_T = 0.58 + 0.0044 * 40 = 0.756 N*m, FL_T = 2.2e-4 + 2.12e-6 * 40 = 3.048e-4 N*m,
# FECD_T = 600 * (7.9e-4 + 3.048e-4 + 4.5e-4) = 0.92688 N*m: 1.68288 N*m of friction
# against a spring that falls linearly to 1.58 N*m, so the spring meets the friction at
# (3.73 - 1.68288) / ((3.73 - 1.58) / 1.57) = 1.495 rad, short of the 1.57 rad travel.
# At +25 degC: 0.47 + 600 * (7.9e-4 + 1.67e-4 + 4.5e-4) = 1.3142 N*m < 1.58: it arrives.
STALL_FRICTION_M40 = 0.756 + 600 * (7.9e-4 + 2.2e-4 + 2.12e-6 * 40 + 4.5e-4)
ARRIVE_FRICTION_25 = 0.58 - 0.0044 * 25 + 600 * (7.9e-4 + 2.2e-4 - 2.12e-6 * 25 + 4.5e-4)


def _stalling_config(folder: Path) -> Path:
    path = _two_node_config(folder)
    text = path.read_text("utf-8")
    assert "ratio = 380" in text
    path.write_text(text.replace("ratio = 380", "ratio = 600"), "utf-8")
    return path


def test_a_stalled_deployment_shows_a_marker_never_nan(tmp_path: Path) -> None:
    assert STALL_FRICTION_M40 > 1.58 > ARRIVE_FRICTION_25  # the hand calculation above
    config = _stalling_config(tmp_path)
    args = ["repeat", str(config), "-n", "3", "--cool-down", "5", "-T", "-40", "-T", "25"]
    table = runner.invoke(app, args, env={"COLUMNS": "80"})
    assert table.exit_code == 0, table.output
    assert "nan" not in table.output.lower()
    assert "RuntimeWarning" not in table.output
    assert max(len(line) for line in table.stdout.splitlines()) <= 80
    rows = [line for line in table.stdout.splitlines() if line.startswith("│")]
    # Deployments 1, 2, 3 at -40 degC: the time cell and the change cell are markers.
    for row in rows[:3]:
        cells = [cell.strip() for cell in row.strip("│").split("│")]
        assert cells[-2:] == ["stalled", "-"]
    for row in rows[3:]:  # +25 degC arrives: a time and a change from deployment 1
        cells = [cell.strip() for cell in row.strip("│").split("│")]
        assert math.isfinite(float(cells[-2]))
        assert math.isfinite(float(cells[-1]))  # "+0.000", "-0.019": a signed number
    notes = " ".join(table.stdout.split())
    assert "stalled: no deployment reaches the end of travel" in notes
    assert "drift 1 to 3: time - (stalled)" in notes

    document = runner.invoke(app, [*args, "--json"])
    assert document.exit_code == 0, document.output
    cold, warm = json.loads(document.stdout)["cases"]
    assert cold["deployments"]["deployment_time_s"] == [None, None, None]
    assert cold["deployments"]["stalled"] == [True, True, True]
    assert cold["stalled_deployments"] == 3
    assert cold["drift"]["deployment_time_s"] is None
    assert warm["deployments"]["stalled"] == [False, False, False]
    assert warm["stalled_deployments"] == 0
    assert all(t is not None and t > 0.0 for t in warm["deployments"]["deployment_time_s"])


def test_the_drift_of_a_stalled_sequence_is_nan_without_a_warning() -> None:
    import warnings

    from ecdsim.cli.repeat import _time_cells

    text = (ROOT / "examples" / "paper_cc16_dynamic.toml").read_text("utf-8")
    stalling = parse_config(text.replace("ratio = 380", "ratio = 600"))  # as above, no heating
    params = stalling.spec.dynamics()
    assert params is not None

    def solve(run: DynamicParameters) -> DynamicResult:
        found = predict(stalling.system, [-40.0], ["dynamic"], dynamics=run)
        solution = found.solutions["dynamic"]
        assert isinstance(solution, DynamicSolution)
        return solution.result

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # inf - inf must not reach NumPy's RuntimeWarning
        result = run_sequence(solve, params, [-40.0], Cycle(2, 5.0))
        drift = result.drift()["deployment_time_s"]
    assert result.stalled.tolist() == [[True], [True]]
    assert math.isnan(float(drift[0]))
    # A later deployment that arrives after a first that stalled: no change to show.
    assert _time_cells(12.5, math.inf) == ["12.5", "-"]
    assert _time_cells(math.inf, 12.5) == ["stalled", "-"]
    assert _time_cells(12.5, 10.0) == ["12.5", "+25.000"]
