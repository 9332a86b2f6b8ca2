"""Temperatures at or below absolute zero are refused everywhere a temperature comes in.

The config file refused them, but the command line's ``-T -300`` and ``-T -500degF``
ran ``deploy``, ``report`` and ``montecarlo`` and printed results. Every command with a
temperature option is checked here (deploy, report, montecarlo, repeat, sweep, fit). Every
temperature option now reads through the config's rule (``ecdsim.config.units.parse_temperature``):
exit code 2 and one ``error:`` line naming the option, the value and the expected unit.
The explorer's API reads configs, so it answers 422 naming the field.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.cli.common import parse_temperature
from ecdsim.config.units import QuantityError
from ecdsim.webapp.server import create_app
from tests.conftest import PAPER_CONFIG, ROOT

runner = CliRunner()
TOLERANCES = ROOT / "examples" / "paper_cc16_tolerances.toml"
DROP_TEST = ROOT / "examples" / "drop_test.csv"
TRACE = ROOT / "examples" / "deployment_trace.csv"
DYNAMIC_CONFIG = ROOT / "examples" / "paper_cc16_dynamic.toml"
EXPECTED = "expected a temperature in degC or compatible units, e.g. '25 degC'"


def _command(name: str, option: str, value: str, tmp_path: Path) -> list[str]:
    config = str(TOLERANCES if name == "montecarlo" else PAPER_CONFIG)
    dynamic = str(DYNAMIC_CONFIG)
    return {
        "deploy": ["deploy", config, option, value],
        "report": ["report", config, option, value, "-o", str(tmp_path / "r.html")],
        "montecarlo": ["montecarlo", config, "-n", "8", option, value, "--out", str(tmp_path)],
        "repeat": ["repeat", dynamic, "--cool-down", "10", "-n", "2", option, value],
        "sweep": [
            "sweep",
            config,
            "--vary",
            "gearbox.ratio=300,380",
            option,
            value,
            "-o",
            str(tmp_path / "s.csv"),
        ],
        "fit drop-test": ["fit", "drop-test", str(DROP_TEST), option, value],
        "fit trace": ["fit", "trace", str(TRACE), "--config", str(PAPER_CONFIG), option, value],
    }[name]


CASES = [
    # (command, option as typed, value, the value as the message quotes it)
    ("deploy", "-T", "-300", "'-300 degC'"),
    ("deploy", "-T", "-500degF", "'-500degF'"),
    ("deploy", "--temperature", "0 K", "'0 K'"),
    ("report", "-T", "-300", "'-300 degC'"),
    ("report", "-T", "-500degF", "'-500degF'"),
    ("montecarlo", "-T", "-300", "'-300 degC'"),
    ("montecarlo", "-T", "-500degF", "'-500degF'"),
    ("repeat", "-T", "-300", "'-300 degC'"),
    ("repeat", "--temperature", "-500degF", "'-500degF'"),
    ("sweep", "-T", "-300", "'-300 degC'"),
    ("sweep", "-T", "-500degF", "'-500degF'"),
    ("fit drop-test", "--reference-temperature", "-500degF", "'-500degF'"),
    ("fit drop-test", "--reference-temperature", "-273.15", "'-273.15 degC'"),
    ("fit trace", "-T", "-500degF", "'-500degF'"),
    ("fit trace", "--reference-temperature", "-300", "'-300 degC'"),
]


@pytest.mark.parametrize(("command", "option", "value", "quoted"), CASES)
def test_below_absolute_zero_exits_2_with_one_line(
    command: str, option: str, value: str, quoted: str, tmp_path: Path
) -> None:
    result = runner.invoke(app, _command(command, option, value, tmp_path))
    long_name = "--temperature" if option == "-T" else option
    assert result.exit_code == 2, result.output
    assert result.stderr.splitlines() == [
        f"error: {long_name}: {quoted} is below absolute zero; {EXPECTED}"
    ]
    assert result.stdout == ""
    assert result.exception is None or isinstance(result.exception, SystemExit)
    assert not (tmp_path / "r.html").exists()
    assert not (tmp_path / "s.csv").exists()


def test_a_swept_temperature_key_below_absolute_zero_is_refused(tmp_path: Path) -> None:
    # sweep takes temperatures through --vary too (here a config key in degF); the value
    # goes through the same reader, so the same words, naming the key and the point.
    out = tmp_path / "s.csv"
    result = runner.invoke(
        app,
        [
            "sweep",
            str(PAPER_CONFIG),
            "--vary",
            "damper.reference_temperature=-500 degF,77 degF",
            "-o",
            str(out),
        ],
    )
    assert result.exit_code == 2, result.output
    assert result.stderr.splitlines() == [
        "error: --vary: damper.reference_temperature: '-500 degF' is below absolute zero; "
        f"{EXPECTED} (at damper.reference_temperature=-500 degF)"
    ]
    assert not out.exists()


def test_every_bad_temperature_is_reported_at_once() -> None:
    result = runner.invoke(app, ["deploy", str(PAPER_CONFIG), "-T", "-300", "-T", "25", "-T", "x"])
    assert result.exit_code == 2
    lines = result.stderr.splitlines()
    assert lines[0] == f"error: --temperature: '-300 degC' is below absolute zero; {EXPECTED}"
    assert lines[1].startswith("error: --temperature: 'x' does not start with a finite number")
    assert len(lines) == 2


@pytest.mark.parametrize("command", [["deploy"], ["report", "-o", "unused.html"]])
def test_a_wing_files_bad_temperatures_are_reported_at_once(command: list[str]) -> None:
    # The wing's loader (cli/wing.load_wing_run) reads -T with the hinge's helper.
    wing = ROOT / "examples" / "wing_cc16_three_panel.toml"
    result = runner.invoke(app, [command[0], str(wing), *command[1:], "-T", "-300", "-T", "x"])
    assert result.exit_code == 2
    lines = result.stderr.splitlines()
    assert lines[0] == f"error: --temperature: '-300 degC' is below absolute zero; {EXPECTED}"
    assert lines[1].startswith("error: --temperature: 'x' does not start with a finite number")
    assert len(lines) == 2


@pytest.mark.parametrize(
    ("text", "celsius"),
    [("-40", -40.0), ("233.15 K", -40.0), ("-40 degF", -40.0), ("-273.14", -273.14)],
)
def test_valid_temperatures_in_any_unit(text: str, celsius: float) -> None:
    assert parse_temperature(text) == pytest.approx(celsius, abs=1e-9)


def test_a_kelvin_option_runs_as_the_same_degc_case() -> None:
    kelvin = runner.invoke(app, ["deploy", str(PAPER_CONFIG), "-T", "233.15 K", "--json"])
    celsius = runner.invoke(app, ["deploy", str(PAPER_CONFIG), "-T", "-40", "--json"])
    assert kelvin.exit_code == 0, kelvin.output
    assert celsius.exit_code == 0, celsius.output
    case_k = json.loads(kelvin.stdout)["cases"][0]
    case_c = json.loads(celsius.stdout)["cases"][0]
    assert case_k["temperature_C"] == pytest.approx(-40.0, abs=1e-9)
    for method in ("paper", "exact"):
        time_k = case_k[method]["deployment_time_s"]
        assert time_k == pytest.approx(case_c[method]["deployment_time_s"], rel=1e-9)


@pytest.mark.parametrize("text", ["-273.15", "0 K", "-459.67 degF", "-300", "-1e6 degC"])
def test_the_shared_reader_refuses_absolute_zero_and_below(text: str) -> None:
    with pytest.raises(QuantityError, match="is below absolute zero; expected a temperature"):
        parse_temperature(text)


# The explorer's API: a config with such a temperature is refused with 422 naming the
# field, on every endpoint that takes a config, and never computed.
client = TestClient(create_app(), base_url="http://localhost")


def _paper() -> dict[str, Any]:
    return tomllib.loads(PAPER_CONFIG.read_text(encoding="utf-8"))


def _with(where: str, value: str) -> dict[str, Any]:
    config = _paper()
    if where == "analysis.temperatures":
        config["analysis"]["temperatures"] = ["25 degC", value]
    elif where == "damper.reference_temperature":
        config["damper"]["reference_temperature"] = value
    else:
        config["load"]["reference_temperature"] = value
    return config


@pytest.mark.parametrize("endpoint", ["/api/deploy", "/api/report", "/api/config.toml"])
@pytest.mark.parametrize(
    ("where", "value"),
    [
        ("analysis.temperatures", "-300 degC"),
        ("analysis.temperatures", "-500 degF"),
        ("analysis.temperatures", "0 K"),
        ("damper.reference_temperature", "-300 degC"),
        ("load.reference_temperature", "-500 degF"),
    ],
)
def test_api_refuses_below_absolute_zero_with_422(endpoint: str, where: str, value: str) -> None:
    response = client.post(endpoint, json={"config": _with(where, value)})
    assert response.status_code == 422, response.text
    errors = response.json()["errors"]
    field = f"{where}[1]" if where == "analysis.temperatures" else where
    assert errors == [f"config: {field}: {value!r} is below absolute zero; {EXPECTED}"]
