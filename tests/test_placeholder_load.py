"""Issue 26 item 2: a fitted config with a placeholder load is flagged by every command
until the load is edited, and the file carries no float noise."""

from __future__ import annotations

import html
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


# ----------------------------------------------------------------- the notebook API


def test_the_notebook_api_flags_it_as_the_command_line_does(fitted: Path) -> None:
    """load, deploy, sweep and size warn with the command line's text, pointing at the
    caller's line; the results' repr, HTML table and to_dict() carry the flag."""
    import ecdsim
    from ecdsim.config.placeholder import TITLE, PlaceholderLoadWarning, warning_text

    expected = warning_text(str(fitted))
    cli = runner.invoke(app, ["deploy", str(fitted), "--json"])
    assert f"warning: {expected}" in messages(cli.stderr)  # the command line's line
    with pytest.warns(PlaceholderLoadWarning) as caught:
        ecdsim.load(fitted)
    assert [str(w.message) for w in caught] == [expected]
    assert caught[0].filename == __file__  # the user's line, not ecdsim's
    with pytest.warns(PlaceholderLoadWarning) as caught:
        result = ecdsim.deploy(fitted)
    assert [str(w.message) for w in caught] == [expected]
    assert caught[0].filename == __file__
    assert result.placeholder_load is True
    assert f"'{result.config.system.name}' ({TITLE})" in repr(result)
    page = result._repr_html_()
    assert page.startswith('<p role="alert"')
    assert html.escape(expected) in page.split("<table>")[0]
    document = result.to_dict()
    assert document["placeholder_load"] is True
    # the very document of `ecdsim deploy --json`
    assert json.loads(json.dumps(document, allow_nan=False)) == json.loads(cli.stdout)

    with pytest.warns(PlaceholderLoadWarning) as caught:
        swept = ecdsim.sweep(fitted, {"gearbox.ratio": [1, 2]}, temperatures=25, methods="exact")
    assert caught[0].filename == __file__
    assert swept.placeholder_load is True
    assert TITLE in repr(swept)
    assert swept._repr_html_().startswith('<p role="alert"')


def test_size_flags_a_placeholder_load_and_a_real_load_is_silent() -> None:
    import ecdsim
    from ecdsim.config.placeholder import TITLE, PlaceholderLoadWarning

    sizing = ROOT / "examples" / "sizing.toml"
    catalogue = ROOT / "examples" / "catalogue.toml"
    with pytest.warns(PlaceholderLoadWarning):
        sized = ecdsim.size(sizing, catalogue, overrides={"load.placeholder": True})
    assert sized.placeholder_load is True
    assert repr(sized).startswith(f"<SizeResults ({TITLE}) ")
    assert sized._repr_html_().startswith('<p role="alert"')
    # The same file with a real load: no warning (the suite turns any into an error).
    real = ecdsim.size(sizing, catalogue)
    assert real.placeholder_load is False
    assert "PLACEHOLDER" not in repr(real) + real._repr_html_()


def test_an_edited_load_is_not_flagged_by_the_api(fitted: Path) -> None:
    import ecdsim

    for clean in (
        ecdsim.deploy(_edited(fitted)),
        # an override can drop the mark as deleting the line does
        ecdsim.deploy(fitted, overrides={"load.placeholder": None}),
    ):
        assert clean.placeholder_load is False
        assert "PLACEHOLDER" not in repr(clean) + clean._repr_html_()
        assert "placeholder_load" not in clean.to_dict()
    assert "PLACEHOLDER" not in repr(ecdsim.sweep(_edited(fitted), {"gearbox.ratio": [1]}))


# ----------------------------------------------------------------- the FMU export


def _description(fmu: Path) -> str:
    import xml.etree.ElementTree as ET
    import zipfile

    with zipfile.ZipFile(fmu) as archive:
        root = ET.fromstring(archive.read("modelDescription.xml"))
    return root.get("description", "")


def test_export_fmu_flags_it(fitted: Path, tmp_path: Path) -> None:
    from ecdsim.config.placeholder import warning_text
    from ecdsim.fmu import PLACEHOLDER_STOP_TIME

    out = tmp_path / "damper.fmu"
    result = runner.invoke(app, ["export-fmu", str(fitted), "-o", str(out)])
    assert result.exit_code == 0, result.output
    # the line every command prints for this file
    assert messages(result.stderr) == [f"warning: {warning_text(str(fitted))}"]
    assert _description(out).endswith(f"(ecdsim; needs no Python); {PLACEHOLDER_STOP_TIME}")
    edited = runner.invoke(app, ["export-fmu", str(_edited(fitted)), "-o", str(out)])
    assert edited.exit_code == 0, edited.output
    assert edited.stderr == ""
    assert _description(out).endswith("(ecdsim; needs no Python)")


def test_build_fmu_warns_and_the_deployment_fmu_says_so(fitted: Path, tmp_path: Path) -> None:
    from ecdsim.config.placeholder import TITLE, PlaceholderLoadWarning, warning_text
    from ecdsim.fmu import build_fmu

    # The deployment FMU runs the dynamic method, which needs the load's inertia.
    text = fitted.read_text(encoding="utf-8").replace(
        "[load]\n", '[load]\ninertia = "0.5 kg*m^2"\n'
    )
    dynamic = tmp_path / "fitted_dynamic.toml"
    dynamic.write_text(text, encoding="utf-8")
    with pytest.warns(PlaceholderLoadWarning) as caught:
        built = build_fmu(dynamic, tmp_path / "hinge.fmu", deployment=True)
    assert [str(w.message) for w in caught] == [warning_text(str(dynamic))]
    assert caught[0].filename == __file__
    assert _description(built).startswith(f"{TITLE}. Spring-driven deployment with an eddy")
