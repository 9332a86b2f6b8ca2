"""The dynamic method end to end: config keys, CLI, JSON, CSV and the result object."""

from __future__ import annotations

import csv
import importlib
import json
import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.config import ConfigError, load_config, parse_config
from ecdsim.deployment import ModelDomainError, predict
from ecdsim.dynamics import (
    DynamicParameters,
    DynamicProblem,
    Rolloff,
    dynamic_problem,
    solve_dynamic,
)
from ecdsim.dynamics.method import DYNAMIC, DynamicSolution
from ecdsim.methods import SOLVERS
from tests import hand
from tests.conftest import PAPER_CONFIG, ROOT, SavedFigures, paper_system
from tests.dynamics_reference import assert_energy_closes, linear_deploy

runner = CliRunner()
DYNAMIC_CONFIG = ROOT / "examples" / "paper_cc16_dynamic.toml"
PAPER_TEXT = PAPER_CONFIG.read_text(encoding="utf-8")
DYNAMIC_FIELDS = {
    "end_speed_rad_s",
    "end_kinetic_energy_J",
    "max_damper_temperature_C",
    "stuck",
    "stuck_angle_rad",
    "energy_balance_error",
}
# The rotor of the example: 2e-7 kg*m^2 at the high-speed shaft, times 380^2.
EXAMPLE_INERTIA = 5.0 + 2e-7 * 380.0**2


def test_example_config_reads_the_dynamic_keys() -> None:
    config = load_config(DYNAMIC_CONFIG)
    assert config.methods == ("paper", "exact", "dynamic")
    params = config.spec.dynamics()
    assert params is not None
    assert params.load_inertia == 5.0
    assert params.rotor_inertia == pytest.approx(2e-7, rel=1e-15)
    assert params.static_friction_factor == 1.0
    assert params.restitution == 0.0
    assert math.isinf(params.stop_time)
    # The quasi-static config has no [load] inertia: no dynamics.
    assert load_config(PAPER_CONFIG).spec.dynamics() is None


def test_every_dynamic_key_parses_with_units() -> None:
    text = (
        PAPER_TEXT.replace(
            'travel = "1.57 rad"',
            'travel = "1.57 rad"\ninertia = "50000 kg*cm^2"\nrestitution = 0.3',
        )
        .replace(
            "[gearbox]",
            '[damper.rolloff]\npeak_speed = "1000 rpm"\nresistivity_coefficient = "0.0039 / K"\n'
            '[damper.thermal]\nheat_capacity = "90 J/K"\nthermal_resistance = "3 K/W"\n\n'
            '[gearbox]\ninertia = "1e-8 kg*m^2"',
        )
        .replace(
            "[analysis]",
            '[initial]\nangle = "10 deg"\nspeed = "-6 deg/s"\n\n[analysis]\nstop_time = "2 min"\n'
            'rtol = 1e-9\nintegrator = "LSODA"',
        )
    )
    params = parse_config(text).spec.dynamics()
    assert params is not None
    # Hand conversions: 50000 kg*cm^2 = 5 kg*m^2; 1000 rpm = 104.72 rad/s; 10 deg and
    # -6 deg/s in radians; 2 min = 120 s.
    assert params.load_inertia == pytest.approx(5.0, rel=1e-12)
    assert params.gearbox_inertia == pytest.approx(1e-8, rel=1e-12)
    assert params.restitution == 0.3
    assert params.rolloff is not None
    assert params.rolloff.peak_speed == pytest.approx(1000 * 2 * math.pi / 60, rel=1e-12)
    assert params.rolloff.resistivity_coefficient == pytest.approx(0.0039, rel=1e-12)
    assert params.thermal is not None
    assert params.thermal.heat_capacity == 90.0
    assert params.thermal.thermal_resistance == 3.0
    assert params.initial_angle == pytest.approx(math.radians(10.0), rel=1e-12)
    assert params.initial_speed == pytest.approx(math.radians(-6.0), rel=1e-12)
    assert params.stop_time == pytest.approx(120.0, rel=1e-12)
    assert (params.rtol, params.integrator) == (1e-9, "LSODA")


@pytest.mark.parametrize(
    ("old", "new", "fragment"),
    [
        ('travel = "1.57 rad"', 'travel = "1.57 rad"\ninertia = "3 kg"', "load.inertia: '3 kg'"),
        ('travel = "1.57 rad"', 'travel = "1.57 rad"\nrestitution = 1.0', "[0, 1)"),
        ("[gearbox]", "static_friction_factor = 0.9\n[gearbox]", "must be >= 1"),
        ("[gearbox]", '[damper.thermal]\nheat_capacity = "5 J"\n[gearbox]', "heat capacity"),
        ("[analysis]", '[initial]\nangle = "2 rad"\n[analysis]', "below the travel"),
        ("[analysis]", '[analysis]\nintegrator = "RK45"', "is not an integrator"),
        ("[analysis]", '[analysis]\nmethods = ["dynamic"]', "needs [load] inertia"),
    ],
)
def test_bad_dynamic_keys_give_one_clear_line(old: str, new: str, fragment: str) -> None:
    with pytest.raises(ConfigError) as info:
        parse_config(PAPER_TEXT.replace(old, new, 1))
    assert len(info.value.problems) == 1
    assert fragment in info.value.problems[0]


def test_deploy_json_has_the_dynamic_fields_and_leaves_the_others_unchanged() -> None:
    result = runner.invoke(app, ["deploy", str(DYNAMIC_CONFIG), "--json"])
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    plain = json.loads(runner.invoke(app, ["deploy", str(PAPER_CONFIG), "--json"]).stdout)
    assert document["methods"] == ["paper", "exact", "dynamic"]
    for case, reference in zip(document["cases"], plain["cases"], strict=True):
        # The quasi-static methods give exactly what they give without the dynamic keys.
        for method in ("paper", "exact", "difference"):
            assert case[method] == reference[method]
        dynamic = case["dynamic"]
        assert set(dynamic) >= DYNAMIC_FIELDS | set(case["exact"])
        temp = case["temperature_C"]
        friction = hand.fecd(temp) + hand.fs(temp)
        ref = linear_deploy(
            EXAMPLE_INERTIA, hand.becd(temp), friction, hand.TS, hand.TE, hand.TRAVEL
        )
        # Radau reference at rtol 1e-10 (see test_dynamics_validation).
        assert dynamic["deployment_time_s"] == pytest.approx(ref.time, rel=1e-8)
        assert dynamic["end_speed_rad_s"] == pytest.approx(ref.speed, rel=1e-7)
        assert dynamic["end_kinetic_energy_J"] == pytest.approx(
            0.5 * EXAMPLE_INERTIA * ref.speed**2, rel=1e-6
        )
        assert dynamic["max_damper_temperature_C"] == temp
        assert dynamic["stuck"] is False
        assert dynamic["stuck_angle_rad"] is None
        assert abs(dynamic["energy_balance_error"]) < 1e-12
    assert document["warnings"] == []


def test_timeseries_csv_per_temperature(tmp_path: Path) -> None:
    target = tmp_path / "series.csv"
    result = runner.invoke(
        app, ["deploy", str(DYNAMIC_CONFIG), "--method", "dynamic", "--timeseries", str(target)]
    )
    assert result.exit_code == 0, result.output
    assert f"wrote {target}" in result.output
    with target.open(newline="") as stream:
        rows = list(csv.DictReader(stream))
    assert list(rows[0]) == [
        "temperature_C",
        "time_s",
        "angle_rad",
        "speed_rad_s",
        "damper_temperature_C",
    ]
    temps = sorted({float(r["temperature_C"]) for r in rows})
    assert temps == [-40.0, 25.0, 100.0]
    for temp in temps:
        block = [r for r in rows if float(r["temperature_C"]) == temp]
        times = [float(r["time_s"]) for r in block]
        assert times[0] == 0.0
        assert all(b >= a for a, b in zip(times, times[1:], strict=False))
        assert float(block[0]["angle_rad"]) == 0.0
        # The last row is the latch: the full travel, at the arrival time.
        assert float(block[-1]["angle_rad"]) == pytest.approx(1.57, rel=1e-11)
        assert all(float(r["damper_temperature_C"]) == temp for r in block)
    assert not list(tmp_path.glob(".series.csv.*"))  # no temporary file left behind


def test_cli_errors_for_the_dynamic_method(tmp_path: Path) -> None:
    result = runner.invoke(app, ["deploy", str(PAPER_CONFIG), "--method", "dynamic"])
    assert result.exit_code == 2
    assert "load.inertia" in result.output
    assert "Traceback" not in result.output
    result = runner.invoke(
        app, ["deploy", str(PAPER_CONFIG), "--timeseries", str(tmp_path / "x.csv")]
    )
    assert result.exit_code == 2
    assert "--timeseries needs the dynamic method" in result.output
    blocked = tmp_path / "file"
    blocked.write_text("not a folder", encoding="utf-8")
    result = runner.invoke(
        app, ["deploy", str(DYNAMIC_CONFIG), "--timeseries", str(blocked / "x.csv")]
    )
    assert result.exit_code == 2
    assert "--timeseries" in result.output


def test_predict_needs_inertia_and_the_method_needs_a_dynamic_problem() -> None:
    with pytest.raises(ModelDomainError, match="load.inertia"):
        predict(paper_system(), [25.0], ["dynamic"])
    plain = predict(paper_system(), [25.0], ["exact"]).problem
    with pytest.raises(ValueError, match="dynamics=DynamicParameters"):
        DYNAMIC.solve(plain)
    with pytest.raises(ModelDomainError, match="initial.angle"):
        predict(
            paper_system(), [25.0], ["dynamic"], dynamics=DynamicParameters(5.0, initial_angle=2.0)
        )
    assert SOLVERS["dynamic"] is DYNAMIC


def test_result_object_outputs(tmp_path: Path) -> None:
    prediction = predict(
        paper_system(), [-40.0, 25.0], ["dynamic"], dynamics=DynamicParameters(5.0)
    )
    solution = prediction.solutions["dynamic"]
    assert isinstance(solution, DynamicSolution)
    result = solution.result
    assert_energy_closes(result)
    document = result.to_dict()
    json.dumps(document, allow_nan=False)  # JSON-safe: no NaN or inf
    assert [e["kind"] for e in document["cases"][1]["events"]] == [
        "release",
        "breakaway",
        "arrive",
        "latch",
    ]
    frame = result.to_pandas()
    assert set(frame["temperature_C"]) == {-40.0, 25.0}
    assert {"spring_torque_Nm", "friction_torque_Nm", "damping_torque_Nm"} <= set(frame.columns)
    assert len(result.to_pandas("summary")) == 2
    assert list(result.to_pandas("events")["kind"])[:4] == [
        "release",
        "breakaway",
        "arrive",
        "latch",
    ]
    with pytest.raises(ValueError, match="table must be"):
        result.to_pandas("nonsense")
    written = result.to_csv(tmp_path / "out.csv", n_points=11)
    assert len(written.read_text(encoding="utf-8").splitlines()) == 1 + 2 * 11
    figure = result.plot()
    angle, speed, heat = figure.axes
    assert angle.get_title() == "dynamic deployment"
    assert [a.get_ylabel() for a in figure.axes] == [
        "deployed angle [deg]",
        "speed [rad/s]",
        "damper temperature [degC]",
    ]
    assert heat.get_xlabel() == "time since release [s]"
    assert [str(line.get_label()) for line in angle.get_lines()] == [
        "case 0, -40 degC",
        "case 1, 25 degC",
    ]
    # No heat capacity configured: the damper stays at each ambient temperature.
    for line, ambient in zip(heat.get_lines(), (-40.0, 25.0), strict=True):
        assert np.all(np.asarray(line.get_ydata(), float) == ambient)
    trajectory = prediction.trajectory("dynamic", np.linspace(0.0, 60.0, 5))
    assert trajectory.angle.shape == (5, 2)
    assert np.all(trajectory.angle[-1] == 1.57)  # latched by 60 s at both temperatures


def test_torques_of_the_time_series_balance_the_inertia_torque() -> None:
    # Newton at the input shaft: J domega/dt = spring + friction + damping torques. The
    # time series gives the torques; the acceleration comes from central differences of
    # the sampled speed (step 1e-4 s, curvature error ~1e-9 of the torques).
    j = 5.0
    prediction = predict(paper_system(), [25.0], ["dynamic"], dynamics=DynamicParameters(j))
    solution = prediction.solutions["dynamic"]
    assert isinstance(solution, DynamicSolution)
    h = 1e-4
    centres = np.array([0.3, 3.0, 12.0, 25.0])
    times = np.concatenate([centres - h, centres, centres + h])
    series = solution.result.sample(times)
    n = centres.size
    acceleration = (series.speed[2 * n :, 0] - series.speed[:n, 0]) / (2 * h)
    net = (
        series.spring_torque[n : 2 * n, 0]
        + series.friction_torque[n : 2 * n, 0]
        + series.damping_torque[n : 2 * n, 0]
    )
    assert np.allclose(j * acceleration, net, rtol=1e-6, atol=1e-8)


def test_to_pandas_without_pandas_says_what_to_do(monkeypatch: pytest.MonkeyPatch) -> None:
    result = solve_dynamic(_problem(DynamicParameters(5.0)))
    real_import = importlib.import_module

    def no_pandas(name: str, package: str | None = None) -> object:
        if name == "pandas":
            raise ImportError("No module named 'pandas'")
        return real_import(name, package)

    monkeypatch.setattr(importlib, "import_module", no_pandas)
    with pytest.raises(ImportError, match="pip install pandas"):
        result.to_pandas()


def _problem(params: DynamicParameters) -> DynamicProblem:
    """The paper example's dynamic problem at 25 degC, built the way predict() builds it."""
    from ecdsim.deployment import build_problem

    system = paper_system()
    temps = np.asarray(25.0)
    ecd = system.ecd.at(temps)
    problem, fs = build_problem(system, ecd, temps)
    return dynamic_problem(system, ecd, temps, problem, fs, params)


def test_unrecorded_results_have_no_time_series() -> None:
    result = solve_dynamic(_problem(DynamicParameters(5.0)), record=False)
    assert result.deployment_time.shape == ()
    with pytest.raises(ValueError, match="record=False"):
        result.sample(np.array([1.0]))


def test_warnings_for_stop_time_and_rolloff() -> None:
    params = DynamicParameters(5.0, stop_time=5.0, rolloff=Rolloff(50.0, 0.0039))
    prediction = predict(paper_system(), [-40.0], ["dynamic"], dynamics=params)
    codes = {w.code for w in prediction.warnings}
    # Stopped at 5 s, long before arrival; the roll-off law's low-speed BECD at -40 degC
    # differs from Eq. 1's by several percent (1/(1 - 0.0039*65) vs 1 + 0.004*65); and at
    # omega_peak = 50 rad/s the damper (N = 380) runs beyond its peak.
    assert codes == {"stop_time", "rolloff_temperature_law", "rolloff_beyond_peak"}
    assert all(w.method == "dynamic" and w.temperature_C == -40.0 for w in prediction.warnings)


def test_plots_accept_the_dynamic_method(tmp_path: Path, saved_figures: SavedFigures) -> None:
    result = runner.invoke(app, ["deploy", str(DYNAMIC_CONFIG), "--plot", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "angle_vs_time.png").read_bytes().startswith(b"\x89PNG")
    (angle,) = saved_figures.axes("angle_vs_time.png")
    assert angle.get_title().replace("\n", " ").endswith("full dynamics: angle against time")
    assert (angle.get_xlabel(), angle.get_ylabel()) == (
        "time since release [s]",
        "deployed angle [deg]",
    )
    label = "dynamic (inertia, stiction, end stop)"
    temperatures = (-40.0, 25.0, 100.0)
    assert saved_figures.legend(angle)[-3:] == [f"{t:g} degC, {label}" for t in temperatures]
    curves = {str(line.get_label()): line for line in angle.get_lines()}
    for t in temperatures:
        times, degrees = (np.asarray(v, float) for v in curves[f"{t:g} degC, {label}"].get_data())
        friction = hand.fecd(t) + hand.fs(t)
        ref = linear_deploy(EXAMPLE_INERTIA, hand.becd(t), friction, hand.TS, hand.TE, hand.TRAVEL)
        moving = times < ref.time
        expected = np.degrees([ref.solution(float(x))[0] for x in times[moving]])
        # Radau's dense output at rtol 1e-10 (tests/dynamics_reference.py): 1e-6 deg is
        # 1e-8 of the travel, the accuracy the deployment times are held to.
        np.testing.assert_allclose(degrees[moving], expected, rtol=0.0, atol=1e-6)
        assert np.all(degrees[~moving] == pytest.approx(math.degrees(hand.TRAVEL), rel=1e-12))
    (torque,) = saved_figures.axes("torque_vs_speed.png")
    assert (torque.get_xlabel(), torque.get_ylabel()) == (
        "input shaft speed [rad/s]",
        "ECD reaction torque [N*m]",
    )


def test_large_nonlinear_batches_recompute_their_time_series(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # Above RECORD_LIMIT cases a nonlinear batch is solved without recording its steps;
    # asking for a trajectory re-solves it once with recording, with the same answer.
    from ecdsim.dynamics import method

    params = DynamicParameters(5.0, rolloff=Rolloff(2000.0, 0.0039))
    times = np.linspace(0.0, 30.0, 4)
    recorded = predict(paper_system(), [25.0, 100.0], ["dynamic"], dynamics=params)
    monkeypatch.setattr(method, "RECORD_LIMIT", 1)
    unrecorded = predict(paper_system(), [25.0, 100.0], ["dynamic"], dynamics=params)
    solution = unrecorded.solutions["dynamic"]
    assert isinstance(solution, DynamicSolution)
    assert solution.result.trajectory is None
    assert np.array_equal(
        unrecorded.trajectory("dynamic", times).angle, recorded.trajectory("dynamic", times).angle
    )
