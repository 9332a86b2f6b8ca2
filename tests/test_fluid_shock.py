"""compare-fluid reports the engagement shock torque of both dampers (issue 14, item 8).

At the end of its deadband a damper engages at the speed the undamped load has reached,
so its torque jumps to coefficient x engagement speed: the paper's argument for the ECD
(section 3.4: a fluid damper has 15 deg or more of deadband, an ECD 0.25 deg at most).
Checked by hand: the free motion J w^2 / 2 = work of (spring - FS_T) over the deadband,
with the paper's linear spring (Ts = 3.73, Te = 1.58 N*m over 1.57 rad) and FS_T.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from tests import hand
from tests.conftest import ROOT

runner = CliRunner()
FLUID = ROOT / "examples" / "fluid.toml"
INERTIA = 0.05  # kg*m^2, examples/fluid.toml's load_inertia


def engage_speed(t: float, deadband_deg: float) -> float:
    """Speed at the end of a free deadband [rad/s], by hand (see the module docstring)."""
    d = math.radians(deadband_deg)
    slope = (hand.TS - hand.TE) / hand.TRAVEL  # the spring's torque falls linearly
    work = (hand.TS - hand.fs(t)) * d - slope * d**2 / 2.0
    return math.sqrt(2.0 * work / INERTIA)


def test_the_fluid_dampers_shock_at_25_degC_is_134_Nm() -> None:
    result = runner.invoke(app, ["compare-fluid", str(FLUID), "--json"])
    assert result.exit_code == 0, result.output
    cases = {c["temperature_C"]: c for c in json.loads(result.stdout)["cases"]}
    case = cases[25.0]
    # Matched at 25 degC: the fluid's coefficient is BECD_25 = 23.65 N*m*s/rad (Eq. 1-4),
    # engaging at sqrt(2 * 0.8065 J / 0.05 kg*m^2) = 5.680 rad/s after 15 deg:
    # 23.65 * 5.680 = 134.3 N*m (the "about 134 N*m").
    speed = engage_speed(25.0, 15.0)
    assert speed == pytest.approx(5.680, abs=5e-4)
    expected = hand.becd(25.0) * speed
    assert expected == pytest.approx(134.3, abs=0.05)
    # The free motion is integrated by quadrature at rtol 1e-12: 1e-9 covers it.
    assert case["fluid"]["engagement_torque_Nm"] == pytest.approx(expected, rel=1e-9)
    # The ECD has no lost motion in the example: it engages at rest, no shock.
    assert case["ecd"]["engagement_torque_Nm"] == 0.0
    # At -40 degC the fluid is 4x as viscous as when matched: c(-40) * w(-40).
    cold = cases[-40.0]
    shock = cold["fluid_coefficient"] * engage_speed(-40.0, 15.0)
    assert cold["fluid"]["engagement_torque_Nm"] == pytest.approx(shock, rel=1e-9)


def test_the_table_shows_both_shocks_and_says_what_they_are() -> None:
    result = runner.invoke(app, ["compare-fluid", str(FLUID)], env={"COLUMNS": "80"})
    assert result.exit_code == 0, result.output
    rows = {}
    for line in result.stdout.splitlines():
        cells = [c.strip() for c in line.strip("│").split("│")]
        if line.startswith("│") and cells[0] in {"-40", "0", "25", "60", "100"}:
            rows[cells[0]] = cells
    # The two shock columns are the last two, kept at 80 columns.
    assert rows["25"][-2:] == [f"{hand.becd(25.0) * engage_speed(25.0, 15.0):.4g}", "0"]
    words = " ".join(result.stdout.split())
    header = [line for line in result.stdout.splitlines() if line.startswith("┃")]
    assert [c.strip() for c in header[0].strip("┃").split("┃")][-2:] == ["fluid shock", "ECD shock"]
    assert [c.strip() for c in header[1].strip("┃").split("┃")][-2:] == ["[N*m]", "[N*m]"]
    assert "coefficient x engagement speed" in words
    assert "the ECD's lost motion is 0 deg, so it engages at rest" in words


def test_an_ecd_with_lost_motion_has_a_small_shock(tmp_path: Path) -> None:
    # The paper's largest ECD lost motion, 0.25 deg (section 3.4): w = 0.754 rad/s at
    # 25 degC, a shock of BECD_25 * w = 17.8 N*m, against the fluid's 134 N*m.
    text = FLUID.read_text(encoding="utf-8").replace(
        'coulomb_friction = "4.5e-4 N*m"                    # FG',
        'coulomb_friction = "4.5e-4 N*m"\nlost_motion = "0.25 deg"',
    )
    assert 'lost_motion = "0.25 deg"' in text
    config = tmp_path / "fluid.toml"
    config.write_text(text, encoding="utf-8")
    result = runner.invoke(app, ["compare-fluid", str(config), "--json"])
    assert result.exit_code == 0, result.output
    (case,) = [c for c in json.loads(result.stdout)["cases"] if c["temperature_C"] == 25.0]
    expected = hand.becd(25.0) * engage_speed(25.0, 0.25)
    assert expected == pytest.approx(17.83, abs=0.01)
    assert case["ecd"]["engagement_torque_Nm"] == pytest.approx(expected, rel=1e-9)


def test_without_inertia_no_shock_is_claimed(tmp_path: Path) -> None:
    text = FLUID.read_text(encoding="utf-8")
    text = "\n".join(line for line in text.splitlines() if not line.startswith("load_inertia"))
    config = tmp_path / "fluid.toml"
    config.write_text(text, encoding="utf-8")
    result = runner.invoke(app, ["compare-fluid", str(config), "--json"])
    assert result.exit_code == 0, result.output
    for case in json.loads(result.stdout)["cases"]:
        assert case["fluid"]["engagement_torque_Nm"] is None
        assert case["ecd"]["engagement_torque_Nm"] is None
    table = runner.invoke(app, ["compare-fluid", str(config)])
    assert "shock [N*m]" not in table.stdout
    assert "the engagement shock are not computed" in " ".join(table.stdout.split())
