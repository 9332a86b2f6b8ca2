"""Monte Carlo tolerances on the damper's heating and roll-off (issue 16, item 6).

The sampled values must reach the dynamic model: checked against the heat balance of an
adiabatic one-node damper (with BG = 0 every joule the eddy currents dissipate stays in
the rotor, so each case's rise is E / C, by hand), against scalar predictions run with
each sample's own values, and, with a spread too small to matter, against the nominal
deterministic prediction. Keys the config cannot centre a tolerance on (an adiabatic,
omitted resistance; a section the config does not give) are refused in one line naming
the key, exit 2.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.config import parse_config
from ecdsim.config.errors import ConfigError
from ecdsim.deployment import predict
from ecdsim.dynamics import DynamicParameters
from ecdsim.dynamics.method import DynamicSolution
from ecdsim.model import DeploymentSystem
from ecdsim.montecarlo import build_plan
from ecdsim.montecarlo.apply import Parameters, apply, nominal
from ecdsim.montecarlo.run import evaluate_chunk, output_column
from ecdsim.montecarlo.tolerances import resolve

TEMPS = [-40.0, 25.0, 100.0]

# The paper's Cc-16 example (section 6) with inertia, as examples/paper_cc16_dynamic.toml.
BASE = """
title = "thermal tolerances"
[damper]
damping_rate = "1.3e-4 N*m*s/rad"
reference_temperature = "25 degC"
damping_temperature_coefficient = "-0.004 / K"
coulomb_friction = "7.9e-4 N*m"
lubrication_friction = {{ slope = "-2.12e-6 N*m/K", at_0C = "2.2e-4 N*m" }}
rotor_inertia = "2e-7 kg*m^2"
{thermal}
[gearbox]
ratio = 380
damping_fraction = {fraction}
coulomb_friction = "4.5e-4 N*m"
[load]
start_torque = "3.73 N*m"
end_torque = "1.58 N*m"
travel = "1.57 rad"
system_friction = {{ slope = "-0.0044 N*m/K", at_0C = "0.58 N*m" }}
inertia = "5 kg*m^2"
[analysis]
temperatures = ["-40 degC", "25 degC", "100 degC"]
methods = ["dynamic"]
{tolerances}
"""

TWO_NODE = """[damper.thermal]
heat_capacity = "4 J/K"
thermal_resistance = "20 K/W"
housing_heat_capacity = "55 J/K"
housing_thermal_resistance = "5 K/W"
"""
# A small rotor, so that it heats by tens of kelvin and its capacity matters.
ADIABATIC = '[damper.thermal]\nheat_capacity = "0.5 J/K"\n'
ROLLOFF = '[damper.rolloff]\npeak_speed = "2000 rad/s"\nresistivity_coefficient = "0.0039 / K"\n'


def _text(thermal: str = TWO_NODE, tolerances: str = "", fraction: float = 0.26) -> str:
    return BASE.format(thermal=thermal, tolerances=tolerances, fraction=fraction)


def _quantities(**specs: str) -> str:
    lines = "\n".join(f'"{key}" = {{ {spec} }}' for key, spec in specs.items())
    return "[tolerances.quantities]\n" + lines + "\n"


def _dynamic(params: DynamicParameters, system: DeploymentSystem) -> DynamicSolution:
    solution = predict(system, TEMPS, ["dynamic"], dynamics=params).solutions["dynamic"]
    assert isinstance(solution, DynamicSolution)
    return solution


def test_sampled_rotor_capacities_set_the_end_temperature_by_the_heat_balance() -> None:
    # Adiabatic rotor, BG = 0: the eddy energy E of each case heats only the rotor, so
    # its end temperature is T + E / C (by hand). The spread of C reaches the model: the
    # end temperatures spread, the smallest capacity the hottest.
    config = parse_config(_text(ADIABATIC, fraction=0.0))
    base = Parameters(config.system, config.spec.dynamics())
    assert nominal(base, "damper.thermal.heat_capacity") == 0.5
    capacities = np.array([0.25, 0.5, 1.0, 2.0])
    varied = apply(base, {"damper.thermal.heat_capacity": capacities})
    assert varied.dynamics is not None
    temps = np.array(TEMPS)[:, np.newaxis]
    solution = predict(varied.system, temps, ["dynamic"], dynamics=varied.dynamics)
    result = solution.solutions["dynamic"]
    assert isinstance(result, DynamicSolution)
    rise = result.result.final_temperature - temps
    stored = rise * capacities
    # The integrated dissipation and temperature each carry the integrator's rtol 1e-8.
    np.testing.assert_allclose(stored, result.result.energy.damper_dissipation, rtol=1e-6)
    assert np.all(np.diff(rise, axis=1) < 0.0)  # larger capacity, smaller rise
    assert np.all(rise[:, 0] > 2.0 * rise[:, -1])  # C x 8: the rise falls by more than 2


def test_a_monte_carlo_chunk_solves_each_sample_as_its_own_scalar_case() -> None:
    tolerances = _quantities(
        **{
            "damper.thermal.heat_capacity": 'distribution = "normal", sigma = "10 %"',
            "damper.thermal.thermal_resistance": 'distribution = "uniform", plus_minus = "20 %"',
            "damper.thermal.housing_heat_capacity": (
                'distribution = "triangular", plus_minus = "10 J/K"'
            ),
            "damper.thermal.housing_thermal_resistance": (
                'distribution = "normal", three_sigma = "1 K/W"'
            ),
        }
    )
    config = parse_config(_text(TWO_NODE, tolerances))
    plan = build_plan(config, 6, "dynamic", seed=7, chunk_size=6)
    columns = evaluate_chunk(plan, 0).columns
    nominal_params = config.spec.dynamics()
    assert nominal_params is not None
    assert nominal_params.thermal is not None
    times = {t: columns[output_column("deployment_time_s", t)] for t in TEMPS}
    spreads = {t: float(np.ptp(times[t])) for t in TEMPS}
    assert all(s > 1e-4 for s in spreads.values())  # the samples do differ
    for j in range(6):
        thermal = dataclasses.replace(
            nominal_params.thermal,
            heat_capacity=float(columns["damper.thermal.heat_capacity"][j]),
            thermal_resistance=float(columns["damper.thermal.thermal_resistance"][j]),
            housing_heat_capacity=float(columns["damper.thermal.housing_heat_capacity"][j]),
            housing_thermal_resistance=float(
                columns["damper.thermal.housing_thermal_resistance"][j]
            ),
        )
        one = _dynamic(dataclasses.replace(nominal_params, thermal=thermal), config.system)
        found = np.array([times[t][j] for t in TEMPS])
        # Each case is integrated to rtol 1e-8 with its own step control, alone or in a
        # batch: agreement to 1e-7 of the time (10 rtol), far below the spread (> 1e-4 s
        # of ~15-48 s).
        np.testing.assert_allclose(found, one.deployment_time, rtol=1e-7)


def test_a_vanishing_spread_gives_the_nominal_deterministic_prediction() -> None:
    # Spreads must be > 0; at 1e-10 % of the capacity the samples move the time by
    # ~1e-12 of itself, far below the tolerance below.
    tolerances = _quantities(
        **{"damper.thermal.heat_capacity": 'distribution = "uniform", plus_minus = "1e-10 %"'}
    )
    config = parse_config(_text(TWO_NODE, tolerances))
    plan = build_plan(config, 4, "dynamic", seed=1, chunk_size=4)
    columns = evaluate_chunk(plan, 0).columns
    params = config.spec.dynamics()
    assert params is not None
    expected = _dynamic(params, config.system).deployment_time
    for i, t in enumerate(TEMPS):
        # 1e-7: the batch and the scalar run each integrate to rtol 1e-8 (see above).
        np.testing.assert_allclose(
            columns[output_column("deployment_time_s", t)], expected[i], rtol=1e-7
        )


def test_sampled_rolloff_peak_speeds_reach_the_model() -> None:
    config = parse_config(_text(TWO_NODE.replace("[damper.thermal]", ROLLOFF + "[damper.thermal]")))
    base = Parameters(config.system, config.spec.dynamics())
    assert nominal(base, "damper.rolloff.peak_speed") == 2000.0
    assert nominal(base, "damper.rolloff.resistivity_coefficient") == 0.0039
    speeds = np.array([1000.0, 2000.0, 8000.0])
    varied = apply(base, {"damper.rolloff.peak_speed": speeds})
    assert varied.dynamics is not None
    assert base.dynamics is not None
    batch = predict(
        varied.system, np.array(TEMPS)[:, np.newaxis], ["dynamic"], dynamics=varied.dynamics
    ).solutions["dynamic"]
    assert isinstance(batch, DynamicSolution)
    for j, speed in enumerate(speeds):
        assert base.dynamics.rolloff is not None
        rolloff = dataclasses.replace(base.dynamics.rolloff, peak_speed=speed)
        one = _dynamic(dataclasses.replace(base.dynamics, rolloff=rolloff), config.system)
        # 1e-7: the same rtol 1e-8 integration, alone or in a batch.
        np.testing.assert_allclose(batch.deployment_time[:, j], one.deployment_time, rtol=1e-7)
    # A lower peak speed rolls the torque off sooner: less damping, a faster deployment.
    assert np.all(np.diff(batch.deployment_time, axis=1) > 0.0)


@pytest.mark.parametrize(
    ("thermal", "key", "message"),
    [
        (
            ADIABATIC,
            "damper.thermal.thermal_resistance",
            "infinite here: [damper.thermal] gives no thermal_resistance (adiabatic)",
        ),
        (
            TWO_NODE.replace('housing_thermal_resistance = "5 K/W"\n', ""),
            "damper.thermal.housing_thermal_resistance",
            "infinite here: [damper.thermal] gives no housing_thermal_resistance",
        ),
        (
            '[damper.thermal]\nheat_capacity = "4 J/K"\nthermal_resistance = "20 K/W"\n',
            "damper.thermal.housing_heat_capacity",
            "gives no housing_heat_capacity (one-node heating)",
        ),
        ("", "damper.thermal.heat_capacity", "[damper.thermal], which this config does not"),
        ("", "damper.rolloff.peak_speed", "[damper.rolloff], which this config does not"),
    ],
)
def test_a_tolerance_the_config_cannot_centre_is_refused_by_name(
    thermal: str, key: str, message: str, tmp_path: Path
) -> None:
    spec = 'distribution = "normal", sigma = "5 %"'
    text = _text(thermal, _quantities(**{key: spec}))
    with pytest.raises(ConfigError, match=f"tolerances.quantities.{key}: .*") as info:
        resolve(parse_config(text))
    assert message in str(info.value)
    path = tmp_path / "c.toml"
    path.write_text(text)
    run = CliRunner().invoke(
        app, ["montecarlo", str(path), "-n", "8", "-m", "dynamic", "--out", str(tmp_path / "o")]
    )
    assert run.exit_code == 2
    lines = [line for line in run.output.splitlines() if line.strip()]
    assert len(lines) == 1
    assert key in lines[0]
    assert message in lines[0]
    assert "Traceback" not in run.output


def test_a_spread_that_takes_a_capacity_to_zero_is_refused() -> None:
    # sigma 20 %: the truncated normal reaches nominal - 6 sigma = -0.2 C < 0.
    text = _text(
        TWO_NODE,
        _quantities(**{"damper.thermal.heat_capacity": 'distribution = "normal", sigma = "20 %"'}),
    )
    with pytest.raises(ConfigError, match=r"heat_capacity.*must stay > 0 J/K"):
        resolve(parse_config(text))


def test_the_montecarlo_command_runs_with_thermal_tolerances(tmp_path: Path) -> None:
    tolerances = _quantities(
        **{"damper.thermal.heat_capacity": 'distribution = "normal", sigma = "10 %"'}
    )
    path = tmp_path / "c.toml"
    path.write_text(_text(TWO_NODE, tolerances))
    run = CliRunner().invoke(
        app,
        ["montecarlo", str(path), "-n", "64", "-m", "dynamic", "--out", str(tmp_path / "o")],
        env={"COLUMNS": "80"},
    )
    assert run.exit_code == 0, run.output
    assert "damper.thermal.heat_capacity" in run.output
    assert "nan" not in run.output.lower()


def test_heating_without_inertia_is_refused_for_the_inertia() -> None:
    # The config gives [damper.thermal] but no [load] inertia (quasi-static methods only):
    # the message names what is missing, not the section it has.
    text = _text(
        TWO_NODE,
        _quantities(**{"damper.thermal.heat_capacity": 'distribution = "normal", sigma = "5 %"'}),
    )
    text = text.replace('inertia = "5 kg*m^2"\n', "").replace('["dynamic"]', '["exact"]')
    with pytest.raises(ConfigError, match=r"heat_capacity: .*need \[load\] inertia") as info:
        resolve(parse_config(text))
    assert "which this config does not give" not in str(info.value)


def test_a_quasi_static_study_says_which_tolerances_it_cannot_see() -> None:
    # The exact method has no inertia or heat balance: a tolerance on the rotor's heat
    # capacity changes nothing there, and the summary says so instead of letting a
    # sensitivity of 0 read as "does not matter". With the dynamic method: no such note.
    from ecdsim.montecarlo.stats import _notes

    tolerances = _quantities(
        **{"damper.thermal.heat_capacity": 'distribution = "normal", sigma = "10 %"'}
    )
    config = parse_config(_text(TWO_NODE, tolerances))
    exact = [n for n in _notes(build_plan(config, 6, "exact", seed=7)) if "dynamic" in n]
    assert exact == [
        "damper.thermal.heat_capacity: only the dynamic method models this; with "
        "--method exact the results do not depend on it (sensitivity 0); use "
        "--method dynamic"
    ]
    dynamic = _notes(build_plan(config, 6, "dynamic", seed=7))
    assert not [n for n in dynamic if "only the dynamic method" in n]
