"""The explorer's JSON API: same numbers as ``deploy --json``, 422 for bad input, fuzzed."""

from __future__ import annotations

import json
import tomllib
from typing import Any

import pytest
import schemathesis
from fastapi.testclient import TestClient
from hypothesis import HealthCheck, settings
from schemathesis.checks import not_a_server_error
from schemathesis.config import SchemathesisConfig
from typer.testing import CliRunner

from ecdsim.cli.app import app as cli
from ecdsim.config import parse_config
from ecdsim.webapp.server import create_app
from tests import hand
from tests.conftest import PAPER_CONFIG, ROOT

DYNAMIC_CONFIG = ROOT / "examples" / "paper_cc16_dynamic.toml"
APP = create_app(host="testserver")  # the Host schemathesis and TestClient send
client = TestClient(APP)
runner = CliRunner()


def _config(path: Any = PAPER_CONFIG) -> dict[str, Any]:
    return tomllib.loads(path.read_text(encoding="utf-8"))


def _deploy(config: dict[str, Any], **extra: Any) -> Any:
    return client.post("/api/deploy", json={"config": config, **extra})


@pytest.mark.parametrize("path", [PAPER_CONFIG, DYNAMIC_CONFIG], ids=["paper", "dynamic"])
def test_deploy_equals_cli_json(path: Any) -> None:
    response = _deploy(_config(path))
    assert response.status_code == 200, response.text
    cli_result = runner.invoke(cli, ["deploy", str(path), "--json"])
    assert cli_result.exit_code == 0
    # The same library call on the same config: the same document, exactly.
    assert response.json()["prediction"] == json.loads(cli_result.stdout)


def test_curves_reach_the_end_of_travel_and_sweep_the_range() -> None:
    body = _deploy(_config(), time_points=50, sweep_points=5).json()
    times = body["trajectories"]["time_s"]
    assert len(times) == 50
    exact = body["trajectories"]["methods"]["exact"]["angle_rad"]
    assert len(exact) == 3  # one curve per temperature
    # The time axis runs past every deployment, so each curve ends at the travel 1.57 rad.
    assert [curve[-1] for curve in exact] == pytest.approx([1.57] * 3, rel=1e-9)
    sweep = body["sweep"]
    # Five evenly spaced points from -40 to 100 degC; linspace rounding only.
    assert sweep["temperature_C"] == pytest.approx([-40.0, -5.0, 30.0, 65.0, 100.0], abs=1e-12)
    swept = sweep["methods"]["exact"]["deployment_time_s"]
    # The sweep's ends are the configured cold and hot cases: the same numbers.
    cases = body["prediction"]["cases"]
    assert swept[0] == pytest.approx(cases[0]["exact"]["deployment_time_s"], rel=1e-12)
    assert swept[-1] == pytest.approx(cases[-1]["exact"]["deployment_time_s"], rel=1e-12)
    assert body["compute_ms"] > 0.0


def test_example_and_toml_round_trip() -> None:
    example = client.get("/api/example").json()
    assert example["config"] == _config()
    response = client.post("/api/config.toml", json={"config": example["config"]})
    assert response.status_code == 200
    assert "attachment" in response.headers["content-disposition"]
    assert parse_config(response.text).spec == parse_config(PAPER_CONFIG.read_text()).spec


def test_edited_config_downloads_with_the_edit() -> None:
    config = _config()
    config["gearbox"]["ratio"] = 500
    text = client.post("/api/config.toml", json={"config": config}).text
    assert parse_config(text).spec.gearbox.ratio == 500.0


def test_report_endpoint_returns_the_html_report() -> None:
    response = client.post("/api/report", json={"config": _config()})
    assert response.status_code == 200
    assert response.headers["content-type"].startswith("text/html")
    assert 'id="ecdsim-data"' in response.text
    # The report's machine-readable block carries the paper example's numbers, by hand.
    start = response.text.index('id="ecdsim-data">') + len('id="ecdsim-data">')
    block = response.text[start : response.text.index("</script>", start)].replace("<\\/", "</")
    cases = json.loads(block)["prediction"]["cases"]
    assert [c["temperature_C"] for c in cases] == [-40.0, 25.0, 100.0]
    for case in cases:
        t = case["temperature_C"]
        # Eq. 1-4 and 8-11 and the exact solution typed in tests/hand.py: rounding only.
        assert case["exact"]["deployment_time_s"] == pytest.approx(hand.exact_time(t), rel=1e-12)
        assert case["paper"]["deployment_time_s"] == pytest.approx(hand.paper_time(t), rel=1e-12)


def test_parse_endpoint_reads_toml() -> None:
    body = client.post("/api/config/parse", json={"toml": PAPER_CONFIG.read_text()}).json()
    assert body["config"] == _config()


def _errors(response: Any) -> list[str]:
    assert response.status_code == 422, response.text
    errors = response.json()["errors"]
    assert isinstance(errors, list)
    assert errors
    return [str(e) for e in errors]


def test_wrong_unit_is_422_naming_the_field() -> None:
    config = _config()
    config["load"]["travel"] = "1.57 N*m"
    (message,) = _errors(_deploy(config))
    assert "load.travel" in message
    assert "wrong dimension" in message
    assert "rad" in message


def test_missing_section_and_unknown_key_are_422() -> None:
    config = _config()
    del config["gearbox"]
    config["damper"]["dampng_rate"] = "1 N*m*s/rad"
    errors = _errors(_deploy(config))
    assert any("gearbox: missing" in e for e in errors)
    assert any("damper.dampng_rate: unknown key" in e for e in errors)


def test_null_is_422_naming_the_field() -> None:
    config = _config()
    config["load"]["travel"] = None
    (message,) = _errors(_deploy(config))
    assert message.startswith("config.load.travel: null")


def test_model_domain_error_is_422() -> None:
    # BD_T = BD (1 + c (T - 25)) <= 0 at 100 degC when c = -0.02 / K: 1 - 0.02 * 75 < 0.
    config = _config()
    config["damper"]["damping_temperature_coefficient"] = "-0.02 / K"
    (message,) = _errors(_deploy(config))
    assert "damper.damping_temperature_coefficient" in message


@pytest.mark.parametrize(
    ("body", "field"),
    [
        ({}, "config: Field required"),
        ({"config": []}, "config: Input should be a valid dictionary"),
        ({"config": _config(), "time_points": 1}, "time_points"),
        ({"config": _config(), "extra": 1}, "extra"),
    ],
)
def test_malformed_request_is_422(body: dict[str, Any], field: str) -> None:
    errors = _errors(client.post("/api/deploy", json=body))
    assert any(field in e for e in errors), errors


def test_not_json_is_422() -> None:
    response = client.post(
        "/api/deploy", content=b"{not json", headers={"content-type": "application/json"}
    )
    _errors(response)


# schemathesis fails a request after 10 s by default; /api/report takes about 1 s of CPU,
# which a loaded 2-core machine stretched past that. How long a response takes is no
# verdict here (no server error is): the timeout only guards against a hang.
HANG_GUARD = SchemathesisConfig.from_str("request-timeout = 1800.0")
schema = schemathesis.openapi.from_asgi("/openapi.json", APP, config=HANG_GUARD)


@schema.parametrize()
@settings(
    max_examples=25,  # bounded: four operations, a few seconds in all
    deadline=None,
    database=None,
    suppress_health_check=list(HealthCheck),
)
def test_api_fuzz_has_no_server_error(case: Any) -> None:
    case.call_and_validate(checks=[not_a_server_error])
