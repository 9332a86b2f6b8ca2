"""``ecdsim report WING.toml``: the wing section's numbers are those of ``deploy --json``
(issue 25 items 4 and 6; docs/wing.md, report), in the report's units, with the figures
inline and nothing fetched from the network."""

from __future__ import annotations

import json
from html.parser import HTMLParser
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.report.builder import DATA_ELEMENT_ID

ROOT = Path(__file__).resolve().parents[1]
STICK_SLIP = ROOT / "validation" / "configs" / "wing_three_panel_stick_slip_ground_test.toml"
ONE_PANEL = ROOT / "validation" / "configs" / "wing_one_panel.toml"
# Table cells show 6 significant digits: rounding is at most half a unit in the 6th digit.
CELL_REL = 5.1e-6
# 1 N*m in lbf*in: 1 / (4.4482216152605 N/lbf * 0.0254 m/in), by hand.
LBF_IN_PER_NM = 1.0 / (4.4482216152605 * 0.0254)
runner = CliRunner()


class _Page(HTMLParser):
    """The cells with data-case and data-key (and their row's data-hinge), the embedded
    JSON, every src/href, the warnings' codes."""

    def __init__(self) -> None:
        super().__init__()
        self.cells: dict[tuple[int, int | None, str], str] = {}
        self.refs: list[str] = []
        self.warnings: list[str] = []
        self.data = ""
        self._hinge: int | None = None
        self._cell: tuple[int, int | None, str] | None = None
        self._in_data = False

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = dict(attrs)
        self.refs += [str(a[k]) for k in ("src", "href") if a.get(k)]
        if tag == "tr":
            self._hinge = int(str(a["data-hinge"])) if a.get("data-hinge") else None
        if tag == "td" and a.get("data-key"):
            self._cell = (int(str(a["data-case"])), self._hinge, str(a["data-key"]))
            self.cells[self._cell] = ""
        if tag == "div" and a.get("class") == "warn":
            self.warnings.append(str(a.get("data-code")))
        self._in_data = tag == "script" and a.get("id") == DATA_ELEMENT_ID

    def handle_endtag(self, tag: str) -> None:
        self._cell = None if tag == "td" else self._cell
        self._in_data = False if tag == "script" else self._in_data

    def handle_data(self, data: str) -> None:
        if self._cell is not None:
            self.cells[self._cell] += data.strip()
        if self._in_data:
            self.data += data


def _report(tmp_path: Path, config: Path, *options: str) -> _Page:
    out = tmp_path / "report.html"
    result = runner.invoke(app, ["report", str(config), "-o", str(out), *options])
    assert result.exit_code == 0, result.output
    page = _Page()
    page.feed(out.read_text(encoding="utf-8"))
    return page


def _deploy(config: Path, *options: str) -> dict[str, Any]:
    result = runner.invoke(app, ["deploy", str(config), "--json", *options])
    assert result.exit_code == 0, result.output
    document: dict[str, Any] = json.loads(result.stdout)
    return document


def test_wing_section_is_deploy_json(tmp_path: Path) -> None:
    page = _report(tmp_path, STICK_SLIP)
    document = _deploy(STICK_SLIP)
    assert all(ref.startswith("data:image/png;base64,") for ref in page.refs)
    assert len(page.refs) == 2  # the hinge angles, one shape strip (one temperature)
    hinges = document["hinges"]
    for i, case in enumerate(document["cases"]):
        latches = {latch["hinge"]: latch for latch in case["latches"]}
        for j, name in enumerate(hinges):
            cell = page.cells[(i, j, "latch_time_s")]
            if name in case["stuck_hinges"]:
                assert cell == "stuck"
                assert page.cells[(i, j, "latch_speed_rad_s")] == "-"
                continue
            latch = latches[name]
            assert float(cell) == pytest.approx(latch["time_s"], rel=CELL_REL)
            speed = float(page.cells[(i, j, "latch_speed_rad_s")])
            assert speed == pytest.approx(latch["speed_rad_s"], rel=CELL_REL)
            energy = float(page.cells[(i, j, "kinetic_energy_J")])
            assert energy == pytest.approx(latch["kinetic_energy_J"], rel=CELL_REL)
            assert page.cells[(i, j, "peak_torque_Nm")] == "-"  # rigid latches
            final = float(page.cells[(i, j, "final_angle_rad")])
            assert final == pytest.approx(case["final_angle_rad"][name], rel=CELL_REL)
        # No deployment (the middle hinge sticks): said, and warned about.
        assert case["deployment_time_s"] is None
        assert page.cells[(i, None, "deployment_time_s")] == "does not deploy"
        error = float(page.cells[(i, None, "energy_balance_error")])
        assert error == pytest.approx(case["energy_balance_error"], rel=0.06)  # 2 digits
        spring = float(page.cells[(i, None, "spring_work")])
        assert spring == pytest.approx(sum(case["energy_J"]["spring_work"].values()), rel=CELL_REL)
    assert page.warnings == ["stuck"]
    embedded = json.loads(page.data)["wing"]
    assert embedded["display_units"] == "si"
    assert [c["latches"] for c in embedded["cases"]] == [c["latches"] for c in document["cases"]]


def test_peak_damper_temperature_and_us_units(tmp_path: Path) -> None:
    # A heated damper (a 0.5 J/K rotor, 40 K/W to ambient: it warms by degrees) on the
    # one-panel wing: the report gives its peak temperature, the JSON's, in degF with
    # --units us, and the latch's energy and torques in US units.
    config = tmp_path / "heated.toml"
    text = ONE_PANEL.read_text()
    heat = (
        '\n[wing.ecds.cc16.damper.thermal]\nheat_capacity = "0.5 J/K"\n'
        'thermal_resistance = "40 K/W"\n'
    )
    config.write_text(
        text.replace("\n[wing.ecds.cc16.gearbox]", heat + "\n[wing.ecds.cc16.gearbox]")
    )
    document = _deploy(config, "-T", "-40")
    peak = document["cases"][0]["peak_damper_temperature_C"]["root"]
    assert peak > -40.0 + 0.5
    page = _report(tmp_path, config, "-T", "-40", "--units", "us")
    shown = float(page.cells[(0, 0, "peak_damper_temperature_C")])
    assert shown == pytest.approx(peak * 9.0 / 5.0 + 32.0, rel=CELL_REL)
    latch = document["cases"][0]["latches"][0]
    energy = float(page.cells[(0, 0, "kinetic_energy_J")])
    assert energy == pytest.approx(latch["kinetic_energy_J"] * LBF_IN_PER_NM, rel=CELL_REL)


def test_wing_report_refuses_single_hinge_options(tmp_path: Path) -> None:
    result = runner.invoke(
        app, ["report", str(STICK_SLIP), "-o", str(tmp_path / "r.html"), "--fail-on", "stall"]
    )
    assert result.exit_code == 2
    assert result.stderr.strip() == "error: --fail-on: not taken with a wing file (docs/wing.md)"
    assert not (tmp_path / "r.html").exists()


def test_compliant_latch_peak_torque_in_us_units(tmp_path: Path) -> None:
    # wing_two_panel_latches: a compliant root latch (its peak torque) and a rebounding
    # rigid outer latch (no torque): the cell is the JSON's peak in lbf*in.
    config = ROOT / "validation" / "configs" / "wing_two_panel_latches.toml"
    document = _deploy(config, "-T", "25")
    page = _report(tmp_path, config, "-T", "25", "--units", "us")
    hinges = document["hinges"]
    for latch in document["cases"][0]["latches"]:
        j = hinges.index(latch["hinge"])
        cell = page.cells[(0, j, "peak_torque_Nm")]
        if latch["peak_torque_Nm"] is None:
            assert cell == "-"
        else:
            expected = latch["peak_torque_Nm"] * LBF_IN_PER_NM
            assert float(cell) == pytest.approx(expected, rel=CELL_REL)
    assert any(latch["peak_torque_Nm"] for latch in document["cases"][0]["latches"])


LOSSY = ROOT / "validation" / "configs" / "wing_two_panel_lossy_gear.toml"


def test_a_lossy_gear_and_lost_motion_have_their_energy_columns(tmp_path: Path) -> None:
    # The lossy-gear case with lost motion added: the account's gear loss and lost-motion
    # catch are columns of their own, each the JSON's per-hinge lines summed; a wing
    # without either shows neither (the stick-slip case above).
    text = LOSSY.read_text(encoding="utf-8")
    anchor = "efficiency = { forward = 0.7, backward = 0.6 }"
    assert anchor in text
    config = tmp_path / "lossy_slack.toml"
    config.write_text(text.replace(anchor, f'{anchor}\nlost_motion = "3 deg"'), "utf-8")
    page = _report(tmp_path, config, "-T", "25")
    document = _deploy(config, "-T", "25")
    (case,) = document["cases"]
    for key in ("gear_loss", "engagement_loss"):
        total = sum(case["energy_J"][key].values())
        assert total > 0.0  # both effects act in this case
        assert float(page.cells[(0, None, key)]) == pytest.approx(total, rel=CELL_REL)
    plain = _report(tmp_path / "plain", STICK_SLIP)
    assert not any(key in ("gear_loss", "engagement_loss") for (_, _, key) in plain.cells)
