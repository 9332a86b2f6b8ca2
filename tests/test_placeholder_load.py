"""Issue 26 item 2: a fitted config with a placeholder load is flagged by every command
until the load is edited, and the file carries no float noise."""

from __future__ import annotations

import json
import re
import tomllib
from pathlib import Path

import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from tests.conftest import ROOT, messages

runner = CliRunner()
DROP_TEST = ROOT / "examples" / "drop_test.csv"
WARNING = "PLACEHOLDER LOAD ([load] placeholder = true)"


@pytest.fixture
def fitted(tmp_path: Path) -> Path:
    out = tmp_path / "fitted.toml"
    result = runner.invoke(app, ["fit", "drop-test", str(DROP_TEST), "-o", str(out)])
    assert result.exit_code == 0, result.output
    return out


def _edited(fitted: Path) -> Path:
    """The user's edit: a real spring and travel, and the mark deleted."""
    text = fitted.read_text(encoding="utf-8")
    text = re.sub(r"^placeholder = true.*\n", "", text, flags=re.MULTILINE)
    text = text.replace('start_torque = "5.15762 N*m"', 'start_torque = "3.73 N*m"')
    text = text.replace('end_torque = "5.15762 N*m"', 'end_torque = "1.58 N*m"')
    edited = fitted.with_name("edited.toml")
    edited.write_text(text, encoding="utf-8")
    return edited


def test_the_file_marks_its_load_and_has_no_float_noise(fitted: Path) -> None:
    text = fitted.read_text(encoding="utf-8")
    load = tomllib.loads(text)["load"]
    assert load["placeholder"] is True
    assert load["travel"] == "90 deg"  # not "1.5707963267948966 rad"
    # The largest bench torque of examples/drop_test.csv, to 6 significant digits.
    assert load["start_torque"] == load["end_torque"] == "5.15762 N*m"
    # No number anywhere in the file with more than 8 significant digits (float noise).
    digits = [m.group(0) for m in re.finditer(r"\d+\.\d{9,}", text)]
    assert not digits, digits


def test_deploy_flags_every_output_until_the_load_is_edited(fitted: Path) -> None:
    result = runner.invoke(app, ["deploy", str(fitted)], env={"COLUMNS": "80"})
    assert result.exit_code == 0, result.output
    assert any(WARNING in line for line in messages(result.stderr))
    assert "Deployment: PLACEHOLDER LOAD: not your mechanism's deployment" in result.stdout
    as_json = runner.invoke(app, ["deploy", str(fitted), "--json"])
    assert json.loads(as_json.stdout)["placeholder_load"] is True
    edited = _edited(fitted)
    clean = runner.invoke(app, ["deploy", str(edited)])
    assert clean.exit_code == 0, clean.output
    assert "PLACEHOLDER" not in clean.stdout + clean.stderr
    assert "placeholder_load" not in json.loads(
        runner.invoke(app, ["deploy", str(edited), "--json"]).stdout
    )


def test_report_sweep_and_repeat_flag_it_too(fitted: Path, tmp_path: Path) -> None:
    report = runner.invoke(app, ["report", str(fitted), "-o", str(tmp_path / "r.html")])
    assert report.exit_code == 0, report.output
    assert any(WARNING in line for line in messages(report.stderr))
    html = (tmp_path / "r.html").read_text(encoding="utf-8")
    assert 'id="placeholder-load"' in html
    sweep = runner.invoke(
        app,
        ["sweep", str(fitted), "--vary", "gearbox.ratio=1,2", "-o", str(tmp_path / "s.csv")],
    )
    assert sweep.exit_code == 0, sweep.output
    assert any(WARNING in line for line in messages(sweep.stderr))
    clean = runner.invoke(app, ["report", str(_edited(fitted)), "-o", str(tmp_path / "c.html")])
    assert 'id="placeholder-load"' not in (tmp_path / "c.html").read_text(encoding="utf-8")
    assert "PLACEHOLDER" not in clean.stderr
