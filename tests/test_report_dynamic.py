"""Issue 26 item 6: the report shows what ``ecdsim deploy`` prints for the dynamic method
(latch speed and kinetic energy, the damper's peak temperature, its figures), the ground
test's gravity torque in the chosen units, methods in words and a plain Warnings line."""

from __future__ import annotations

import json
import math
from html import unescape
from pathlib import Path

from typer.testing import CliRunner

from ecdsim.cli.app import app
from tests.conftest import ROOT
from tests.test_report_requirements import table

runner = CliRunner()
GROUND = ROOT / "examples" / "paper_cc16_ground_test.toml"
# 1 lbf*in and 1 in*lbf in N*m and J, from the exact definitions (lbm, g_n, inch).
LBF_IN = 0.45359237 * 9.80665 * 0.0254


def _report(tmp_path: Path, *extra: str) -> str:
    out = tmp_path / "r.html"
    result = runner.invoke(app, ["report", str(GROUND), "-o", str(out), *extra])
    assert result.exit_code == 0, result.output
    return out.read_text(encoding="utf-8")


def _deploy() -> dict:  # type: ignore[type-arg]
    result = runner.invoke(app, ["deploy", str(GROUND), "--json"])
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)  # type: ignore[no-any-return]


def test_dynamic_results_and_figures_in_us_units(tmp_path: Path) -> None:
    html = _report(tmp_path, "--units", "us")
    document = _deploy()
    end = table(html, "dynamic-end").rows
    assert end[0] == ["T [degF]", "outcome", "latch speed [rad/s]", "KE at latch [in*lbf]"]
    for row, case in zip(end[1:], document["cases"], strict=True):
        dyn = case["dynamic"]
        assert row[0] == f"{case['temperature_C'] * 1.8 + 32:.4g}"
        assert row[1] == "latched"
        # 4 significant digits, as deploy prints them: half a unit in the 4th digit.
        assert math.isclose(float(row[2]), dyn["end_speed_rad_s"], rel_tol=5.1e-4)
        assert math.isclose(float(row[3]), dyn["end_kinetic_energy_J"] / LBF_IN, rel_tol=5.1e-4)
    damper = table(html, "dynamic-damper").rows
    assert damper[0][:2] == ["T [degF]", "peak damper T [degF]"]
    for row, case in zip(damper[1:], document["cases"], strict=True):
        peak = case["dynamic"]["max_damper_temperature_C"] * 1.8 + 32.0
        assert math.isclose(float(row[1]), peak, rel_tol=5.1e-4)
    assert 'id="figure-dynamic_angle"' in html
    assert 'id="figure-dynamic_speed"' in html
    assert 'id="figure-dynamic_heating"' in html  # [damper.thermal]: the damper heats
    words = " ".join(unescape(html).split())
    # The gravity torque at release and at the latch, in lbf*in (6 digits).
    ground = document["ground_test"]
    for key in ("torque_at_release_Nm", "torque_at_latch_Nm"):
        assert f"{ground[key] / LBF_IN:.6g} lbf*in" in words
    assert f"{ground['torque_at_release_Nm']:.6g} N*m" not in words
    assert "Inputs (US customary units, as validated)" in words


def test_methods_in_words_and_no_none_line(tmp_path: Path) -> None:
    words = " ".join(unescape(_report(tmp_path)).split())
    assert "paper (paper" not in words
    assert "paper: the paper's Eq. 8-13 (the mean of the start and end speeds)" in words
    assert "dynamic: the equation of motion in time (inertia, stiction, end stop)" in words
    assert "None:" not in words
    assert "No warning: checked for stall" in words
    assert "rel. = (method − exact) / exact" in words
