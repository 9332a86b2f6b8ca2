"""The explorer's bench fit, ``POST /api/fit/drop-test``: the CLI's fit, curves, 422s.

Independent derivations: the CLI run on the same file (``ecdsim fit drop-test --json``
and ``-o FILE --config CONFIG``), and the laws re-evaluated by hand from the parameters
that JSON prints.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from typer.testing import CliRunner

from ecdsim.cli.app import app as cli
from ecdsim.webapp.server import create_app
from tests.conftest import PAPER_CONFIG, ROOT

DROP_TEST = ROOT / "examples" / "drop_test.csv"
client = TestClient(create_app(), base_url="http://localhost")
runner = CliRunner()
# Keys of the CLI's JSON that name files on disk, not results.
FILE_KEYS = ("source", "parameter_file", "plots")


def _fit(**extra: Any) -> Any:
    body = {"csv": DROP_TEST.read_text(encoding="utf-8"), "filename": "drop_test.csv", **extra}
    return client.post("/api/fit/drop-test", json=body)


def _cli_json(*args: str) -> dict[str, Any]:
    result = runner.invoke(cli, ["fit", "drop-test", str(DROP_TEST), "--json", *args])
    assert result.exit_code == 0, result.output
    document: dict[str, Any] = json.loads(result.stdout)
    return document


def _without_files(document: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in document.items() if k not in FILE_KEYS}


@pytest.mark.parametrize("noise", ["torque", "timing"])
def test_fit_equals_the_cli(noise: str) -> None:
    response = _fit(noise=noise)
    assert response.status_code == 200, response.text
    body = response.json()
    # The same library call on the same bytes: the same document, exactly.
    assert _without_files(body["fit"]) == _without_files(_cli_json("--noise", noise))
    assert body["fit"]["source"] == "drop_test.csv"


def test_display_units_are_recorded_as_the_cli_records_them() -> None:
    us = _fit(units="us").json()["fit"]
    assert _without_files(us) == _without_files(_cli_json("--units", "us"))
    assert us["display_units"] == "us"
    # Without units, the config's [output] units (as --config's for the CLI).
    config = tomllib.loads(PAPER_CONFIG.read_text(encoding="utf-8"))
    config["output"] = {"units": "us"}
    assert _fit(config=config).json()["fit"]["display_units"] == "us"


def test_parameter_file_equals_the_cli_file(tmp_path: Path) -> None:
    from ecdsim.webapp.fitapi import CONFIG_NAME

    config = tomllib.loads(PAPER_CONFIG.read_text(encoding="utf-8"))
    body = _fit(config=config).json()
    # The config as the page exports it, given to the CLI as --config under that name.
    exported = client.post("/api/config.toml", json={"config": config}).text
    (tmp_path / CONFIG_NAME).write_text(exported, encoding="utf-8")
    out = tmp_path / "fitted.toml"
    result = runner.invoke(
        cli,
        [
            "fit",
            "drop-test",
            str(DROP_TEST),
            "-o",
            str(out),
            "--config",
            str(tmp_path / CONFIG_NAME),
        ],
    )
    assert result.exit_code == 0, result.output
    # The CLI's -o file with the same --config, byte for byte.
    assert body["toml"] == out.read_text(encoding="utf-8")
    assert body["config"] == tomllib.loads(body["toml"])
    assert body["export_error"] is None
    # The fitted ECD is referred to the input shaft: N = 1; the rest of the case is kept.
    assert body["config"]["gearbox"]["ratio"] == 1
    assert body["config"]["load"] == config["load"]
    assert body["config"]["analysis"] == config["analysis"]
    assert body["config"]["title"] == config["title"]


def test_without_a_config_the_load_is_the_cli_placeholder() -> None:
    body = _fit().json()
    assert "PLACEHOLDER" in body["toml"]


def test_curves_are_the_fit() -> None:
    body = _fit().json()
    fit, curves = body["fit"], body["curves"]
    lines = curves["torque_speed"]
    assert [line["temperature_C"] for line in lines] == [-40.0, 25.0, 100.0]
    for line, temperature in zip(lines, fit["temperatures"], strict=True):
        points = temperature["points"]
        assert line["speed_rad_s"] == [p["corrected_speed_rad_s"] for p in points]
        assert line["torque_Nm"] == [p["torque_Nm"] for p in points]
        # The drawn line is FECD + BECD * speed at its two ends (rounding only).
        b = temperature["damping_rate_Nms_per_rad"]
        f = temperature["friction_Nm"]
        top = line["line_speed_rad_s"][1]
        assert line["line_torque_Nm"] == pytest.approx([f, f + b * top], rel=1e-12)
        assert (
            line["damping_rate_Nms_per_rad"]["ci95"] == temperature["damping_rate_ci95_Nms_per_rad"]
        )
    laws = fit["temperature_laws"]
    grid = curves["laws"]["temperature_C"]
    # Grid: 10 % beyond the tested range (-40 to 100 degC: span 140 K) on both sides.
    assert grid[0] == pytest.approx(-54.0, abs=1e-12)
    assert grid[-1] == pytest.approx(114.0, abs=1e-12)
    linear = laws["damping_rate"]["linear"]
    b_ref = linear["damping_rate_ref_Nms_per_rad"]
    c = linear["temperature_coefficient_per_K"]
    # BECD(T) = B_ref * (1 + c (T - 25)), typed from the printed parameters: rounding only.
    expected = [b_ref * (1.0 + c * (t - 25.0)) for t in grid]
    drawn = curves["laws"]["damping_rate"]["linear"]
    assert drawn["value"] == pytest.approx(expected, rel=1e-12)
    assert all(
        lo < v < hi for lo, v, hi in zip(drawn["low"], drawn["value"], drawn["high"], strict=True)
    )
    friction = laws["friction"]
    line_values = [friction["at_0C_Nm"] + friction["slope_Nm_per_K"] * t for t in grid]
    assert curves["laws"]["friction"]["value"] == pytest.approx(line_values, rel=1e-12)


def _errors(response: Any) -> list[str]:
    assert response.status_code == 422, response.text
    errors = response.json()["errors"]
    assert isinstance(errors, list)
    assert errors
    return [str(e) for e in errors]


@pytest.mark.parametrize(
    ("csv", "expected"),
    [
        ("", "empty"),
        ("temperature [degC],mass [g]\n-40,3000\n", "csv: "),
        ("a,b,c\n1,2,3\n", "csv: "),
        # One row per temperature: no line can be fitted.
        (
            "temperature [degC],mass [g],radius [mm],angle [deg],time [s]\n"
            "-40,3000,50,180,100\n25,3000,50,180,80\n",
            "no temperature could be fitted",
        ),
    ],
)
def test_unusable_csv_is_422(csv: str, expected: str) -> None:
    errors = _errors(client.post("/api/fit/drop-test", json={"csv": csv}))
    assert any(expected in e for e in errors), errors
    assert all("\n" not in e for e in errors)


@pytest.mark.parametrize(
    ("extra", "field"),
    [
        ({"noise": "loud"}, "noise"),
        ({"reference_temperature": -300}, "reference_temperature"),
        ({"reference_temperature": "hot"}, "reference_temperature"),
        ({"filename": ""}, "filename"),
        ({"unknown": 1}, "unknown"),
        ({"config": {"load": {"travel": "1 N*m"}}}, "config"),
    ],
)
def test_bad_parameters_are_422_naming_the_field(extra: dict[str, Any], field: str) -> None:
    errors = _errors(_fit(**extra))
    assert any(field in e for e in errors), errors


def test_csv_over_the_length_limit_is_refused() -> None:
    from ecdsim.webapp.fitapi import MAX_CSV_CHARS

    response = client.post("/api/fit/drop-test", json={"csv": "x" * (MAX_CSV_CHARS + 1)})
    assert response.status_code in (413, 422)
    assert response.json()["errors"]


def test_endpoint_is_in_the_openapi_document() -> None:
    schema = client.get("/openapi.json").json()
    operation = schema["paths"]["/api/fit/drop-test"]["post"]
    assert {"200", "413", "422", "503"} <= set(operation["responses"])


def test_a_deeply_nested_config_is_refused_before_it_is_walked() -> None:
    from ecdsim.config.loader import MAX_NESTING

    nested: Any = 1
    for _ in range(MAX_NESTING + 5):
        nested = {"x": nested}
    config = tomllib.loads(PAPER_CONFIG.read_text(encoding="utf-8"))
    config["extra"] = nested
    (message,) = _errors(_fit(config=config))
    assert "nested too deeply" in message


def test_a_file_name_is_only_a_name() -> None:
    # A path in the name cannot point anywhere: only its last part, made safe, is used.
    body = _fit(filename="../../etc/pass wd;.csv").json()
    assert body["fit"]["source"] == "pass_wd_.csv"
    assert "data: pass_wd_.csv" in body["toml"]
