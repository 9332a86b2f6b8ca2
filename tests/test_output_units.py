"""Display units (issue 14 item 1, issue 15 item 1): SI or US customary on every output.

Every expected number is derived here by hand from the exact definitions
(1 in = 0.0254 m, 1 lbf = 4.4482216152605 N, 1 lbm = 0.45359237 kg, degF = degC*9/5 + 32),
independently of :mod:`ecdsim.units_display`'s own constants.
"""

from __future__ import annotations

import tomllib
from typing import Any

import pytest
from fastapi.testclient import TestClient

from ecdsim.model import LinearTemperatureLaw
from ecdsim.units_display import (
    check_system,
    convert,
    format_quantity,
    format_value,
    key_units,
    kind_of_key,
)
from ecdsim.webapp.server import create_app
from tests.conftest import PAPER_CONFIG, require

# By hand: 1 lbf*in = 4.4482216152605 N * 0.0254 m = 0.112984829027617 N*m
# (4.4482216152605 * 0.0254 = 0.11298482902761670 exactly in decimal).
LBF_IN_NM = 0.1129848290276167


# --- the conversions -------------------------------------------------------------------------


def test_torque_and_damping_in_lbf_in() -> None:
    # The paper's start torque 3.73 N*m = 3.73 / 0.1129848290276167 = 33.01328... lbf*in.
    # rel 1e-13: two float divisions of exact decimal constants.
    assert convert(3.73, "torque", "us") == pytest.approx(3.73 / LBF_IN_NM, rel=1e-13)
    assert convert(3.73, "torque", "us") == pytest.approx(33.01328, abs=5e-6)
    # BECD at 25 degC, 23.65272 N*m*s/rad -> 23.65272 / 0.11298483 = 209.3442 in*lbf*s/rad
    # (the same factor as torque: the rate is per radian).
    assert convert(23.65272, "damping_rate", "us") == pytest.approx(209.3442, abs=5e-5)
    # SI is the identity.
    assert convert(3.73, "torque", "si") == 3.73


def test_temperatures_in_degf() -> None:
    # -40 degC = -40 degF; 25 degC = 77 degF; 100 degC = 212 degF (exact in binary floats).
    assert [convert(t, "temperature", "us") for t in (-40.0, 25.0, 100.0)] == [
        -40.0,
        77.0,
        212.0,
    ]
    # A slope per kelvin: -0.0044 N*m/K is -0.0044 / 1.8 N*m/degF = -0.0024444 N*m/degF,
    # / 0.1129848 N*m per lbf*in = -0.021635 lbf*in/degF.
    got = convert(-0.0044, "torque_per_kelvin", "us")
    assert got == pytest.approx(-0.0044 / 1.8 / LBF_IN_NM, rel=1e-13)


def test_inertia_mass_length() -> None:
    # 1 lbm*in^2 = 0.45359237 kg * 0.0254^2 m^2 = 2.9263965e-4 kg*m^2; 5 kg*m^2 = 17085.86.
    lbm_in2 = 0.45359237 * 0.0254**2
    assert convert(5.0, "inertia", "us") == pytest.approx(5.0 / lbm_in2, rel=1e-13)
    assert convert(5.0, "inertia", "us") == pytest.approx(17085.86, abs=5e-3)
    assert convert(0.185, "mass", "us") == pytest.approx(0.185 / 0.45359237, rel=1e-13)
    # 63 mm = 63 / 25.4 in = 2.480315 in.
    assert convert(0.063, "length", "us") == pytest.approx(2.480315, abs=5e-7)


def test_float_noise_is_not_shown() -> None:
    # pint's -40 degF -> degC is -39.99999999999997; shown back in degF to 4 significant
    # digits it is -40 (and 77, 212), never the noise.
    noisy = (-40.0 - 32.0) * 5.0 / 9.0 + 3e-14
    assert format_quantity(noisy, "temperature", "us") == "-40 degF"
    assert format_value(-39.99999999999997) == "-40"
    assert format_value(77.00000000000001) == "77"
    assert format_value(-0.0) == "0"
    assert format_value(None) == "-"


def test_key_suffixes_name_their_kind() -> None:
    assert kind_of_key("damping_rate_Nms_per_rad") == "damping_rate"
    assert kind_of_key("slope_Nm_per_K") == "torque_per_kelvin"
    assert kind_of_key("start_speed_rad_s") == "angular_speed"
    assert kind_of_key("stall_angle_rad") == "angle"
    assert kind_of_key("deployment_time_s") == "time"
    assert kind_of_key("rig_inertia_kg_m2") == "inertia"
    assert kind_of_key("stalled") is None
    assert key_units({"a": [{"temperature_C": 1.0}]}, "us") == {"temperature_C": "degF"}


def test_unknown_system_is_named() -> None:
    with pytest.raises(ValueError, match=r"^units: 'metric' is not a unit system; expected"):
        check_system("metric")


# --- the explorer's API ----------------------------------------------------------------------

client = TestClient(create_app(), base_url="http://localhost")


def _degf_config() -> dict[str, Any]:
    config = tomllib.loads(PAPER_CONFIG.read_text(encoding="utf-8"))
    config["analysis"]["temperatures"] = ["-40 degF", "77 degF", "212 degF"]
    return config


def test_api_deploy_carries_display_units() -> None:
    body = {"config": _degf_config(), "units": "us", "time_points": 3, "sweep_points": 3}
    response = client.post("/api/deploy", json=body)
    assert response.status_code == 200, response.text
    data = response.json()
    assert data["display_units"] == "us"
    assert data["prediction"]["display_units"] == "us"
    assert data["units"]["torque"] == {"unit": "lbf*in", "scale": 1.0 / LBF_IN_NM, "offset": 0.0}
    assert data["units"]["temperature"] == {"unit": "degF", "scale": 1.8, "offset": 32.0}
    labels = data["key_units"]
    assert labels["temperature_C"] == "degF"
    assert labels["friction_Nm"] == "lbf*in"
    assert labels["damping_rate_Nms_per_rad"] == "in*lbf*s/rad"
    assert labels["angle_rad"] == "rad"  # trajectories are labelled too
    # The numbers stay SI: 77 degF is 25 degC (pint's conversion: rounding only).
    temps = [case["temperature_C"] for case in data["prediction"]["cases"]]
    assert temps == pytest.approx([-40.0, 25.0, 100.0], abs=1e-12)
    # Converted with the response's own table they read back as the config's numbers.
    scale, offset = data["units"]["temperature"]["scale"], data["units"]["temperature"]["offset"]
    assert [format_value(t * scale + offset) for t in temps] == ["-40", "77", "212"]


def test_api_warnings_carry_a_message_in_the_display_units() -> None:
    # A spring of 1.2 N*m cannot start at -40 degC (friction 0.587024 + 0.756 = 1.343024
    # N*m by hand). The message stays SI; display_message is the same sentence in US
    # units: 1.2 N*m = 10.62 lbf*in, 1.343024 N*m = 11.89 lbf*in (4 digits), -40 degF.
    config = tomllib.loads(PAPER_CONFIG.read_text(encoding="utf-8"))
    config["load"]["start_torque"] = "1.2 N*m"
    body = {"config": config, "units": "us", "time_points": 2, "sweep_points": 0}
    warnings = client.post("/api/deploy", json=body).json()["prediction"]["warnings"]
    stall = next(w for w in warnings if w["code"] == "stall")
    assert "drive torque 1.2 N*m < friction 1.343 N*m at -40 degC" in stall["message"]
    assert (
        "drive torque 10.62 lbf*in < friction 11.89 lbf*in at -40 degF"
        in (stall["display_message"])
    )


def test_api_units_default_to_the_config_then_si() -> None:
    config = _degf_config()
    small = {"time_points": 2, "sweep_points": 0}
    assert (
        client.post("/api/deploy", json={"config": config, **small}).json()["display_units"] == "si"
    )
    config["output"] = {"units": "us"}
    data = client.post("/api/deploy", json={"config": config, **small}).json()
    assert data["display_units"] == "us"
    # The request's choice wins over the config's.
    data = client.post("/api/deploy", json={"config": config, "units": "si", **small}).json()
    assert data["display_units"] == "si"
    assert data["key_units"]["temperature_C"] == "degC"


def test_api_refuses_an_unknown_system() -> None:
    response = client.post("/api/deploy", json={"config": _degf_config(), "units": "metric"})
    assert response.status_code == 422
    assert response.json()["errors"][0].startswith("units:")
    config = _degf_config()
    config["output"] = {"units": "imperial"}
    response = client.post("/api/deploy", json={"config": config})
    assert response.status_code == 422
    assert response.json()["errors"] == [
        "config: output.units: 'imperial' is not a unit system; expected 'si' or 'us'"
    ]


def test_api_example_and_parse_say_the_config_system() -> None:
    data = client.get("/api/example").json()
    assert data["display_units"] == "si"
    assert data["units"]["temperature"]["unit"] == "degC"
    text = PAPER_CONFIG.read_text(encoding="utf-8") + '\n[output]\nunits = "us"\n'
    data = client.post("/api/config/parse", json={"toml": text}).json()
    assert data["display_units"] == "us"
    assert data["units"]["torque"]["unit"] == "lbf*in"


# --- friction laws at a reference temperature other than 0 degC --------------------------

_PAPER_TEXT = PAPER_CONFIG.read_text(encoding="utf-8")
_PAPER_FS = 'system_friction = { slope = "-0.0044 N*m/K", at_0C = "0.58 N*m" }'
_PAPER_FL = 'lubrication_friction = { slope = "-2.12e-6 N*m/K", at_0C = "2.2e-4 N*m" }'


def _with_laws(fs: str, fl: str | None = None) -> str:
    assert _PAPER_FS in _PAPER_TEXT
    assert _PAPER_FL in _PAPER_TEXT
    text = _PAPER_TEXT.replace(_PAPER_FS, fs)
    return text.replace(_PAPER_FL, fl) if fl is not None else text


def test_friction_law_at_77f_is_the_paper_law() -> None:
    from ecdsim.config import parse_config
    from ecdsim.deployment import predict

    # By hand: the paper's FS_T = -0.0044 N*m/K * T + 0.58 N*m is 0.58 - 0.0044 * 25 = 0.47 N*m
    # at 25 degC = 77 degF. FL_T = -2.12e-6 * T + 2.2e-4 is 2.2e-4 - 2.12e-6 * 25 = 1.67e-4 N*m.
    # In US units: 0.47 N*m / 0.1129848290276167 N*m per lbf*in = 4.159851 lbf*in and
    # -0.0044 N*m/K = -0.0044 / 1.8 / 0.1129848290276167 = -0.02163516 lbf*in/degF;
    # 1.67e-4 N*m = 1.478075e-3 lbf*in, -2.12e-6 N*m/K = -1.042421e-5 lbf*in/degF.
    us_text = _with_laws(
        'system_friction = { slope = "-0.02163516 lbf*in/degF", at = "77 degF", '
        'value = "4.159851 lbf*in" }',
        'lubrication_friction = { slope = "-1.042421e-5 lbf*in/degF", at = "77 degF", '
        'value = "1.478075e-3 lbf*in" }',
    )
    paper = parse_config(_PAPER_TEXT)
    us = parse_config(us_text)
    temps = (-40.0, 25.0, 100.0)
    a = predict(paper.system, temps, ("paper", "exact")).to_dict()["cases"]
    b = predict(us.system, temps, ("paper", "exact")).to_dict()["cases"]
    # FS at -40 degC by hand: 0.58 + 0.0044 * 40 = 0.756 N*m; the US inputs carry 7 digits,
    # so rel 1e-6 covers their rounding (largest: -0.02163516 of -0.021635156..., 2e-7).
    assert [c["system_friction_Nm"] for c in b] == pytest.approx([0.756, 0.47, 0.14], rel=1e-6)
    for case_a, case_b in zip(a, b, strict=True):
        for method in ("paper", "exact"):
            assert case_b[method]["deployment_time_s"] == pytest.approx(
                case_a[method]["deployment_time_s"], rel=1e-5
            )


def test_friction_law_reference_forms_agree_exactly() -> None:
    from ecdsim.config import parse_config

    # at_0C, at_32F (32 degF is 0 degC) and at = "25 degC" with its value give one law:
    # 0.58 - 0.0044 * 25 = 0.47, so at 0 degC 0.47 + 0.0044 * 25 = 0.58 N*m (rounding only).
    forms = [
        _PAPER_FS,
        'system_friction = { slope = "-0.0044 N*m/K", at_32F = "0.58 N*m" }',
        'system_friction = { slope = "-0.0044 N*m/K", at = "25 degC", value = "0.47 N*m" }',
    ]
    laws = [parse_config(_with_laws(f)).system.load.system_friction for f in forms]
    for law in laws:
        assert isinstance(law, LinearTemperatureLaw)
        assert law.slope == -0.0044
        assert law.at_0c == pytest.approx(0.58, abs=1e-15)


@pytest.mark.parametrize(
    ("law", "message"),
    [
        (
            '{ slope = "-0.0044 N*m/K", at_0C = "0.58 N*m", at_32F = "0.58 N*m" }',
            "load.system_friction: give one reference value, not at_0C and at_32F",
        ),
        (
            '{ slope = "-0.0044 N*m/K", at = "77 degF" }',
            "load.system_friction: missing value: at needs it",
        ),
        (
            '{ slope = "-0.0044 N*m/K", at = "77 N*m", value = "0.47 N*m" }',
            "load.system_friction.at: '77 N*m' has the wrong dimension; expected a temperature",
        ),
    ],
)
def test_friction_law_reference_errors_name_the_field(law: str, message: str) -> None:
    from ecdsim.config import ConfigError, parse_config

    with pytest.raises(ConfigError) as caught:
        parse_config(_with_laws(f"system_friction = {law}"))
    assert message in str(caught.value)


# --- the command line ----------------------------------------------------------------------


def _us_config(tmp_path: Any, output: str | None = None) -> Any:
    text = _PAPER_TEXT.replace(
        'temperatures = ["-40 degC", "25 degC", "100 degC"]',
        'temperatures = ["-40 degF", "77 degF", "212 degF"]',
    )
    assert "77 degF" in text
    if output is not None:
        text += f'\n[output]\nunits = "{output}"\n'
    path = tmp_path / "us.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _legend_texts(ax: Any) -> list[str]:
    """The legend entries of a matplotlib axes (it must have a legend)."""
    legend = ax.get_legend()
    assert legend is not None
    return [t.get_text() for t in legend.get_texts()]


def _ydata(line: Any) -> list[float]:
    return [float(v) for v in line.get_ydata()]


def _xdata(line: Any) -> list[float]:
    return [float(v) for v in line.get_xdata()]


def _run(*args: str) -> Any:
    from typer.testing import CliRunner

    from ecdsim.cli.app import app

    return CliRunner().invoke(app, list(args), env={"COLUMNS": "200"})


def _row(stdout: str, first: str) -> list[str]:
    """The cells of the table row whose first cell is ``first``."""
    for line in stdout.splitlines():
        cells = [c.strip() for c in line.strip("│┃ ").split("│")]
        if cells and cells[0] == first:
            return cells
    raise AssertionError(f"no row {first!r} in:\n{stdout}")


def test_deploy_table_in_us_units(tmp_path: Any) -> None:
    result = _run("deploy", str(_us_config(tmp_path)), "--units", "us", "--wide")
    assert result.exit_code == 0, result.output
    assert "[degF]" in result.stdout
    assert "[in*lbf*s/rad]" in result.stdout
    assert "[lbf*in]" in result.stdout
    assert "degC" not in result.stdout
    assert "N*m" not in result.stdout
    # The config's -40, 77, 212 degF come back as written, not as -39.99999999999997.
    row = _row(result.stdout, "77")
    # ECD table at 77 degF = 25 degC, by hand (paper section 6):
    # BD_T = 1.3e-4 N*m*s/rad = 1.3e-4 / 0.1129848290276167 = 0.0011506 in*lbf*s/rad;
    # BECD = 23.65272 N*m*s/rad -> 209.3 in*lbf*s/rad; FS = 0.47 N*m -> 4.160 lbf*in
    # (4 significant digits: 4.160, its trailing zero kept so the column aligns).
    assert row[1:2] == ["0.001151"]
    assert "209.3" in row
    assert "4.160" in row
    assert _row(result.stdout, "-40")[0] == "-40"
    assert _row(result.stdout, "212")[0] == "212"


def test_demo_in_us_units(tmp_path: Any) -> None:
    # The demo prints results too: the paper example (degC config) shown in US units.
    # 25 degC = 77 degF; BECD = 23.65272 N*m*s/rad -> 209.3 in*lbf*s/rad (as above).
    result = _run("demo", "--out", str(tmp_path / "demo"), "--units", "us", "--wide")
    assert result.exit_code == 0, result.output
    assert "[degF]" in result.stdout
    assert "209.3" in _row(result.stdout, "77")
    bad = _run("demo", "--out", str(tmp_path / "demo"), "--units", "metric")
    assert bad.exit_code == 2
    assert "--units" in bad.output


def test_deploy_units_from_config_and_option_wins(tmp_path: Any) -> None:
    path = _us_config(tmp_path, output="us")
    result = _run("deploy", str(path))
    assert result.exit_code == 0, result.output
    assert "[degF]" in result.stdout
    result = _run("deploy", str(path), "--units", "si")
    assert result.exit_code == 0, result.output
    assert "[degF]" not in result.stdout
    assert "[degC]" in result.stdout
    # -40 degF is -40 degC; 77 degF is 25 degC; 212 degF is 100 degC.
    assert _row(result.stdout, "25")[0] == "25"


def test_deploy_json_stays_si_and_records_units(tmp_path: Any) -> None:
    import json

    result = _run("deploy", str(_us_config(tmp_path)), "--units", "us", "--json")
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    assert document["display_units"] == "us"
    # SI keys and SI numbers: BECD at 25 degC is 23.65272 N*m*s/rad (paper section 6:
    # BT_T = 1.638e-4 N*m*s/rad times 380^2 = 23.65272), rel 1e-9 for the degF round trip.
    case = document["cases"][1]
    assert case["damping_rate_Nms_per_rad"] == pytest.approx(23.65272, rel=1e-9)


def test_bad_units_option_exits_2_naming_it(tmp_path: Any) -> None:
    result = _run("deploy", str(_us_config(tmp_path)), "--units", "imperial")
    assert result.exit_code == 2
    assert result.output.strip() == (
        "error: --units: 'imperial' is not a unit system; expected 'si' or 'us'"
    )
    result = _run("deploy", str(_us_config(tmp_path, output="imperial")))
    assert result.exit_code == 2
    assert "output.units: 'imperial' is not a unit system; expected 'si' or 'us'" in (result.output)


def test_us_plots_are_labelled_in_us_units(tmp_path: Any) -> None:
    from ecdsim.config import load_config
    from ecdsim.deployment import predict
    from ecdsim.plotting import plot_deployment, plot_torque_speed

    config = load_config(_us_config(tmp_path))
    prediction = predict(config.system, config.temperatures, ("exact",))
    fig = plot_torque_speed(prediction, units="us")
    ax = fig.axes[0]
    assert ax.get_ylabel() == "ECD reaction torque [lbf*in]"
    labels = _legend_texts(ax)
    assert labels[1].startswith("77 degF: BECD 209 in*lbf*s/rad, FECD 4.73 lbf*in")
    # The 77 degF line starts at FECD_25 = N * FT_T = 380 * 1.407e-3 = 0.53466 N*m (paper
    # section 6), 0.53466 / 0.11298483 = 4.7322 lbf*in; rel 1e-4 covers that rounding.
    assert _ydata(ax.get_lines()[2])[0] == pytest.approx(4.7322, rel=1e-4)
    fig = plot_deployment(prediction, units="us")
    labels = _legend_texts(fig.axes[0])
    assert labels == [
        "-40 degF, exact quasi-static",
        "77 degF, exact quasi-static",
        "212 degF, exact quasi-static",
    ]


def test_report_in_us_units(tmp_path: Any) -> None:
    import re

    out = tmp_path / "report.html"
    result = _run("report", str(_us_config(tmp_path, output="us")), "-o", str(out))
    assert result.exit_code == 0, result.output
    html = out.read_text(encoding="utf-8")
    assert "<th>T [degF]</th>" in html
    assert "<th>BECD [in*lbf*s/rad]</th>" in html
    # The components row at 77 degF, 6 significant digits: BECD 23.65272 N*m*s/rad is
    # 23.65272 / 0.1129848290276167 = 209.3442 in*lbf*s/rad; FS 0.47 N*m is 4.159851 lbf*in.
    row = re.search(r'<tr data-case="1"><td class="num">77</td>(.*?)</tr>', html, re.S)
    assert row is not None
    assert ">209.344<" in row.group(1)
    assert ">4.15985<" in row.group(1)
    # Inputs in the display system too: the analysis temperatures read back as written.
    assert "[-40, 77, 212]" in html
    # --units si wins over the config's [output] units.
    result = _run("report", str(_us_config(tmp_path, output="us")), "-o", str(out), "--units", "si")
    assert result.exit_code == 0, result.output
    assert "<th>T [degC]</th>" in out.read_text(encoding="utf-8")


def test_api_report_and_app_default_units() -> None:
    response = client.post("/api/report", json={"config": _degf_config(), "units": "us"})
    assert response.status_code == 200
    assert "<th>T [degF]</th>" in response.text
    # ecdsim app --units us: the system of requests that do not choose one.
    us_client = TestClient(create_app(units="us"), base_url="http://localhost")
    assert us_client.get("/api/example").json()["display_units"] == "us"
    small = {"config": _degf_config(), "time_points": 2, "sweep_points": 0}
    assert us_client.post("/api/deploy", json=small).json()["display_units"] == "us"
    assert (
        us_client.post("/api/deploy", json={**small, "units": "si"}).json()["display_units"] == "si"
    )


def test_fit_drop_test_in_us_units() -> None:
    import json

    from tests.conftest import ROOT

    data = str(ROOT / "examples" / "drop_test.csv")
    si = json.loads(_run("fit", "drop-test", data, "--json").stdout)
    result = _run("fit", "drop-test", data, "--units", "us", "--wide")
    assert result.exit_code == 0, result.output
    assert "T_ref = 77 degF" in result.stdout
    friction = si["temperature_laws"]["friction"]
    at_0c, slope = friction["at_0C_Nm"], friction["slope_Nm_per_K"]
    # The FECD line in US units: the value at 32 degF (= 0 degC) in lbf*in, and the slope
    # per degF: N*m/K / 1.8 per degF-per-K / 0.1129848290276167 N*m per lbf*in; the table
    # prints 5 significant digits.
    lines = [line for line in result.stdout.splitlines() if "at 32 degF [lbf*in]" in line]
    assert len(lines) == 1
    assert f"{at_0c / LBF_IN_NM:.5g}" in lines[0]
    lines = [line for line in result.stdout.splitlines() if "slope [lbf*in/degF]" in line]
    assert f"{slope / 1.8 / LBF_IN_NM:.5g}" in lines[0]
    us = json.loads(_run("fit", "drop-test", data, "--json", "--units", "us").stdout)
    assert us["display_units"] == "us"
    assert us["temperature_laws"] == si["temperature_laws"]  # JSON stays SI


def test_montecarlo_tables_in_us_units(tmp_path: Any) -> None:
    import json

    require("pyarrow")
    from tests.conftest import ROOT

    config = ROOT / "examples" / "paper_cc16_tolerances.toml"
    common = ["-n", "64", "--no-plot", "--no-progress", "--overwrite"]
    out = str(tmp_path / "mc")
    result = _run("montecarlo", str(config), "--out", out, "--units", "us", *common)
    assert result.exit_code == 0, result.output
    # -40, 25, 100 degC are -40, 77, 212 degF; times stay in s.
    assert "[degF]" in result.stdout
    assert "77 degF" in result.stdout  # the sensitivity columns
    assert _row(result.stdout, "77")[0] == "77"
    assert "degC" not in result.stdout
    result = _run("montecarlo", str(config), "--out", out, "--units", "us", "--json", *common)
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    assert document["display_units"] == "us"
    assert [c["temperature_C"] for c in document["cases"]] == [-40.0, 25.0, 100.0]


def test_size_and_compare_fluid_in_us_units(tmp_path: Any) -> None:
    import json

    from tests.conftest import ROOT

    examples = ROOT / "examples"
    sizing, catalogue = str(examples / "sizing.toml"), str(examples / "catalogue.toml")
    result = _run("size", sizing, "--catalog", catalogue, "--units", "us", "--wide")
    assert result.exit_code == 0, result.output
    # The requirements at -40, 25, 100 degC read -40, 77, 212 degF; the input torque limit
    # 4 N*m is 4 / 0.1129848290276167 = 35.4030 lbf*in (6 digits: 35.403).
    assert "-40, 77, 212" in result.stdout
    assert "35.403 lbf*in" in result.stdout
    assert "[lbm]" in result.stdout  # the mass column
    assert "ECD input torque <= 35.4 lbf*in" in result.stdout  # 4 N*m, 4 digits
    assert "N*m" not in result.stdout
    assert "[lbf*in at the ECD input]" in result.stdout
    document = json.loads(
        _run("size", sizing, "--catalog", catalogue, "--units", "us", "--json").stdout
    )
    assert document["display_units"] == "us"

    fluid = str(examples / "fluid.toml")
    result = _run("compare-fluid", fluid, "--units", "us", "--wide")
    assert result.exit_code == 0, result.output
    assert "matched at 77 degF" in result.stdout
    assert "[lbf*in]" in result.stdout  # the shock columns
    si = json.loads(_run("compare-fluid", fluid, "--json").stdout)
    # The fluid damper's engagement shock at 25 degC (issue 14 item 8: about 134 N*m in the
    # shipped example), in lbf*in: the JSON's SI value / 0.1129848290276167, 4 digits.
    case = next(c for c in si["cases"] if c["temperature_C"] == 25.0)
    shock = case["fluid"]["engagement_torque_Nm"]
    assert shock == pytest.approx(134.3, abs=0.05)
    assert f"{shock / LBF_IN_NM:.4g}" == "1189"
    assert _row(result.stdout, "77")[-2:] == ["1189", "0"]  # fluid and ECD shock


def test_warnings_in_us_units(tmp_path: Any) -> None:
    from ecdsim.units_display import convert_text

    # By hand: 1.45 N*m / 0.1129848290276167 = 12.8336 lbf*in; 1.343 N*m = 11.8865 lbf*in;
    # -40 degC = -40 degF; 23.65 N*m*s/rad = 209.32 in*lbf*s/rad; rad and s are unchanged.
    text = "drive torque 1.45 N*m < friction 1.343 N*m at -40 degC; BECD 23.65 N*m*s/rad"
    assert convert_text(text, "us") == (
        "drive torque 12.83 lbf*in < friction 11.89 lbf*in at -40 degF; BECD 209.3 in*lbf*s/rad"
    )
    assert convert_text(text, "si") == text
    assert convert_text("stalls at 1.481 rad (84.9 deg) after 3 s", "us") == (
        "stalls at 1.481 rad (84.9 deg) after 3 s"
    )
    # The paper example with end torque 1.2 N*m stalls at -40 degC (docs/json.md: at 1.481
    # rad); the report's stderr line says so in degF.
    path = tmp_path / "stall.toml"
    path.write_text(_PAPER_TEXT.replace('end_torque = "1.58 N*m"', 'end_torque = "1.2 N*m"'))
    result = _run("report", str(path), "-o", str(tmp_path / "r.html"), "--units", "us")
    assert result.exit_code == 0, result.output
    stall_lines = [line for line in result.stderr.splitlines() if "stalls at 1.481 rad" in line]
    assert stall_lines
    assert all("at -40 degF" in line for line in stall_lines)
    assert "degC" not in result.stderr
    assert "at -40 degF" in (tmp_path / "r.html").read_text(encoding="utf-8")


def test_fit_plots_in_us_units() -> None:
    from ecdsim.characterize.droptest import fit_drop_test
    from ecdsim.characterize.plots import plot_parameters, plot_torque_speed
    from tests.conftest import ROOT

    result = fit_drop_test(ROOT / "examples" / "drop_test.csv", 25.0)
    si, us = plot_torque_speed(result, "si").axes[0], plot_torque_speed(result, "us").axes[0]
    assert us.get_ylabel() == "drive torque [lbf*in]"
    # Same points, torque divided by 0.1129848290276167 N*m per lbf*in (rounding only).
    np_si, np_us = _ydata(si.get_lines()[0]), _ydata(us.get_lines()[0])
    assert list(np_us) == pytest.approx([y / LBF_IN_NM for y in np_si], rel=1e-12)
    fits = result.fits
    fig = plot_parameters(
        [f.temperature for f in fits],
        [f.line.slope for f in fits],
        [f.line.intercept for f in fits],
        result.laws,
        "us",
    )
    assert fig.axes[1].get_xlabel() == "temperature [degF]"
    assert fig.axes[0].get_ylabel() == "BECD [in*lbf*s/rad]"
    # The per-temperature points sit at -40, 77, 212 degF (the CSV's -40, 25, 100 degC).
    points = [_xdata(line) for line in fig.axes[1].get_lines() if len(_xdata(line)) == 3]
    assert points  # the error bars (and their caps) at the fitted temperatures
    assert sorted(points[0]) == pytest.approx([-40.0, 77.0, 212.0], abs=1e-9)


def test_montecarlo_plot_legends_in_us_units() -> None:
    import numpy as np

    from ecdsim.montecarlo.plots import plot_cdf, plot_histogram

    # Two temperatures, -40 and 100 degC: -40 and 212 degF in the legends.
    samples = {-40.0: np.array([1.0, 2.0, 3.0]), 100.0: np.array([2.0, 3.0, np.inf])}
    histogram = plot_histogram(samples, "deployment time [s]", "t", units="us")
    assert _legend_texts(histogram.axes[0]) == ["-40 degF", "212 degF (33 % stall)"]
    labels = _legend_texts(plot_cdf(samples, "deployment time [s]", "t", "us").axes[0])
    assert labels == ["-40 degF", "212 degF"]


def test_deploy_warnings_in_us_units(tmp_path: Any) -> None:
    # The paper example with end torque 1.2 N*m stalls at -40 degC (1.481 rad, docs/json.md);
    # in US units the warning names -40 degF; --json keeps the SI sentence.
    path = tmp_path / "stall.toml"
    path.write_text(_PAPER_TEXT.replace('end_torque = "1.58 N*m"', 'end_torque = "1.2 N*m"'))
    result = _run("deploy", str(path), "--units", "us")
    assert result.exit_code == 0, result.output
    stall_lines = [line for line in result.stderr.splitlines() if "stalls at 1.481 rad" in line]
    assert stall_lines
    assert all("at -40 degF" in line for line in stall_lines)
    result = _run("deploy", str(path), "--units", "us", "--json")
    import json

    messages = [w["message"] for w in json.loads(result.stdout)["warnings"]]
    assert any("at -40 degC" in m for m in messages)


def test_app_refuses_a_bad_units_option_before_serving() -> None:
    result = _run("app", str(PAPER_CONFIG), "--units", "metric")
    assert result.exit_code == 2
    assert result.output.strip() == (
        "error: --units: 'metric' is not a unit system; expected 'si' or 'us'"
    )
