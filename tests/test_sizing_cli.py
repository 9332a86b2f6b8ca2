"""``ecdsim size`` and ``ecdsim compare-fluid``: JSON structure, tables, plots, and exit
code 2 with one-line errors for user mistakes."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim import __version__
from ecdsim.cli.app import app
from tests import hand
from tests.conftest import PAPER_CONFIG, ROOT, SavedFigures
from tests.helptext import assert_options, read_help, run_example

runner = CliRunner()
SIZING = ROOT / "examples" / "sizing.toml"
CATALOGUE = ROOT / "examples" / "catalogue.toml"
FLUID = ROOT / "examples" / "fluid.toml"
CC16 = ["--damper", "CDA Cc-16 damper", "--gearbox", "CDA Cc-16 gearbox"]


def test_size_json_structure() -> None:
    result = runner.invoke(app, ["size", str(SIZING), "--catalog", str(CATALOGUE), "--json", *CC16])
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    assert document["ecdsim_version"] == __version__
    assert document["config"] == str(SIZING)
    assert document["catalogue"] == str(CATALOGUE)
    assert document["temperatures_C"] == [-40.0, 25.0, 100.0]
    assert document["requirements"]["max_deployment_time_s"] == 60.0
    assert document["requirements"]["torque_margin"]["factors_applied"] is False
    candidates = document["candidates"]
    assert [c["rank"] for c in candidates] == list(range(1, len(candidates) + 1))
    (cc16,) = [c for c in candidates if c["gearbox"] == "CDA Cc-16 gearbox" and
               c["damper"] == "CDA Cc-16 damper"]  # fmt: skip
    times = [case["deployment_time_s"] for case in cc16["cases"]]
    assert times == pytest.approx([hand.exact_time(t) for t in (-40.0, 25.0, 100.0)], rel=1e-12)
    assert cc16["passed"] is True
    for check in cc16["checks"].values():
        assert set(check) == {"name", "label", "margin", "passed", "cannot_start",
                              "temperature_C", "value", "unit", "margins", "values"}  # fmt: skip
    intervals = document["ratio_intervals"]
    assert intervals["damper"] == "CDA Cc-16 damper"
    (interval,) = intervals["intervals"]
    assert interval["low"] < 380.0 < interval["high"]
    assert intervals["catalogue_ratios"] == [{"ratio": 380.0, "feasible": True}]


def test_size_tables_and_plots(tmp_path: Path, saved_figures: SavedFigures) -> None:
    out = tmp_path / "plots"
    result = runner.invoke(
        app, ["size", str(SIZING), "--catalog", str(CATALOGUE), "--plot", str(out)]
    )
    assert result.exit_code == 0, result.output
    assert "Candidates, ranked" in result.stdout
    assert "Gear ratios N meeting the requirements" in result.stdout
    assert "illustrative, not vendor data" in result.stdout
    assert "no uncertainty factors applied" in result.stdout
    assert f"{hand.exact_time(-40.0):.4g}" in result.stdout  # Cc-16 at -40 degC: 48.13 s
    for name in ("sizing_time_vs_temperature.png", "ratio_margins.png"):
        assert (out / name).read_bytes().startswith(b"\x89PNG")
    (times,) = saved_figures.axes("sizing_time_vs_temperature.png")
    assert times.get_title() == "Deployment time over temperature, best-ranked candidates"
    assert times.get_xlabel() == "temperature [degC]"
    assert times.get_ylabel() == "exact deployment time [s]"
    legend = saved_figures.legend(times)
    assert "#3 CDA Cc-16 damper + CDA Cc-16 gearbox 380:1" in legend  # vendor data: no tag
    demo = [entry for entry in legend if "Demo" in entry]
    assert demo
    assert all(entry.endswith("(illustrative, not vendor data)") for entry in demo)
    (cc16,) = [line for line in times.get_lines() if "CDA Cc-16 gearbox" in str(line.get_label())]
    temperature, seconds = (np.asarray(v, dtype=float) for v in cc16.get_data())
    # The requirements' range, and the paper's example at every temperature by hand.
    assert (temperature[0], temperature[-1]) == (-40.0, 100.0)
    expected = [hand.exact_time(float(t)) for t in temperature]
    np.testing.assert_allclose(seconds, expected, rtol=1e-12)  # the same closed form
    (margins,) = saved_figures.axes("ratio_margins.png")
    assert margins.get_xlabel() == "gear ratio N [-]"
    assert margins.get_ylabel() == "margin, >= 0 where met [-] (clipped to +-1.5)"
    assert margins.get_title().endswith("the requirements that limit the gear ratio")
    # Issue 26 item 7: the requirements in words, those at the interval's ends said so,
    # the green band and the catalogue ratios in the legend, the never-binding named.
    legend = [t.get_text() for t in margins.figure.legends[0].get_texts()]
    assert "deployment time >= 10 s (sets an end)" in legend
    assert "deployment time <= 60 s (sets an end)" in legend
    assert "no stall" in legend
    assert not [entry for entry in legend if "_" in entry]  # no code names
    (band,) = [entry for entry in legend if entry.startswith("meets every requirement")]
    # The best-ranked pair (illustrative): the band is its interval of the JSON, to 4 digits.
    document = json.loads(
        runner.invoke(app, ["size", str(SIZING), "--catalog", str(CATALOGUE), "--json"]).stdout
    )
    (interval,) = document["ratio_intervals"]["intervals"]
    assert band == f"meets every requirement: N {interval['low']:.4g} to {interval['high']:.4g}"
    assert "catalogue ratio, meets every requirement" in legend  # its 500:1
    assert "catalogue ratio, misses a requirement" in legend  # its 100:1 to 400:1
    (note,) = [entry for entry in legend if entry.startswith("met at every N")]
    assert "ECD input torque <= 4 N*m" in note.replace("\n", " ")
    drawn = [line.get_label() for line in margins.get_lines() if line.get_linestyle() == "-"]
    assert "ECD input torque <= 4 N*m" not in drawn  # never binds: not drawn


def test_ratio_intervals_in_words(tmp_path: Path) -> None:
    """The interval table never prints an end of the scanned range as a bound."""
    pair = ["--damper", "CDA Cc-16 damper", "--gearbox", "CDA Cc-16 gearbox"]
    result = runner.invoke(
        app, ["size", str(SIZING), "--catalog", str(CATALOGUE), *pair], env={"COLUMNS": "200"}
    )
    assert result.exit_code == 0, result.output
    table = result.stdout.split("Gear ratios N meeting the requirements")[1]
    rows = {
        cells[0]: cells[1:]
        for line in table.splitlines()
        if line.startswith("│")
        for cells in [[c.strip() for c in line.strip("│").split("│")]]
    }
    # The Cc-16's exact roots (docs/sizing.md), to 4 digits, with what sets each end.
    assert rows["all requirements"] == [
        "313.7 to 408.2",
        "low: deployment time >= 10 s; high: deployment time <= 60 s",
    ]
    assert rows["deployment time >= 10 s"][0] == ">= 313.7"
    assert rows["deployment time <= 60 s"][0] == "<= 408.2"
    assert rows["ECD input torque <= 4 N*m"][0] == "no bound in the scanned range"
    # 533.4 = (1.58 - FS(-40)) / FT(-40) (docs/sizing.md): an upper bound only.
    assert rows["no stall"][0] == "<= 533.4"
    cells = " ".join(" ".join(row) for row in rows.values())
    assert "10 to" not in cells  # the scan's ends are named in the title only
    assert "5000" not in cells


def test_compare_fluid_json_and_plot(tmp_path: Path, saved_figures: SavedFigures) -> None:
    out = tmp_path / "plots"
    result = runner.invoke(app, ["compare-fluid", str(FLUID), "--json", "--plot", str(out)])
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    assert document["config"] == str(FLUID)
    assert document["fluid_damper"]["matched_coefficient"] == pytest.approx(
        hand.becd(25.0), rel=1e-12
    )
    temps = [c["temperature_C"] for c in document["cases"]]
    assert temps == [-40.0, 0.0, 25.0, 60.0, 100.0]
    case = document["cases"][0]
    assert set(case["ecd"]) == set(case["fluid"]) == {
        "deadband_rad", "damped_time_s", "free_time_s", "engage_speed_rad_s",
        "total_time_s", "end_speed_rad_s", "stalled", "engagement_torque_Nm",
        "damped_time_paper_s",
    }  # fmt: skip
    assert case["ecd"]["damped_time_s"] == pytest.approx(hand.exact_time(-40.0), rel=1e-12)
    # The paper's method too (issue 28: the fluid model in every quasi-static method).
    assert case["ecd"]["damped_time_paper_s"] == pytest.approx(hand.paper_time(-40.0), rel=1e-12)
    assert (out / "ecd_vs_fluid.png").read_bytes().startswith(b"\x89PNG")
    assert "wrote" in result.stderr
    top, bottom = saved_figures.axes("ecd_vs_fluid.png")
    assert top.get_title() == "ECD against a fluid damper matched at 25 degC"
    assert top.get_ylabel() == "deployment time [s]"
    assert bottom.get_xlabel() == "temperature [degC]"
    assert bottom.get_ylabel() == "damping [N*m*(s/rad)^n]"
    assert saved_figures.legend(top) == ["ECD", document["fluid_damper"]["name"]]
    # Units in the legend: the two dampings have different units when n != 1.
    assert saved_figures.legend(bottom) == ["ECD: BECD_T [N*m*s/rad]", "fluid: c(T) (n = 1)"]
    ecd_time, ecd_damping = top.get_lines()[0], bottom.get_lines()[0]
    temperature = np.asarray(ecd_time.get_xdata(), dtype=float)
    assert (temperature[0], temperature[-1]) == (-40.0, 100.0)
    # The ECD side is the paper's example: Eq. 1-3 and the exact time by hand.
    exact = np.array([hand.exact_time(float(t)) for t in temperature])
    np.testing.assert_allclose(np.asarray(ecd_time.get_ydata(), dtype=float), exact, rtol=1e-12)
    becd = np.array([hand.becd(float(t)) for t in temperature])
    np.testing.assert_allclose(np.asarray(ecd_damping.get_ydata(), dtype=float), becd, rtol=1e-12)


def test_compare_fluid_table() -> None:
    result = runner.invoke(app, ["compare-fluid", str(FLUID)])
    assert result.exit_code == 0, result.output
    assert "ECD against" in result.stdout
    assert "viscosity data: illustrative, not vendor data" in result.stdout


def user_error(args: list[str]) -> str:
    result = runner.invoke(app, args)
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    assert result.stdout == ""
    return result.stderr


def test_size_user_errors_exit_2(tmp_path: Path) -> None:
    no_section = user_error(["size", str(PAPER_CONFIG), "--catalog", str(CATALOGUE)])
    assert f"error: {PAPER_CONFIG}: no [requirements] section" in no_section
    bad = tmp_path / "bad.toml"
    bad.write_text(CATALOGUE.read_text().replace('"5e-4 N*m"', '"5e-4 N"', 1))
    message = user_error(["size", str(SIZING), "--catalog", str(bad)])
    assert f"error: {bad}: damper #2 'Demo damper S': coulomb_friction:" in message
    missing = user_error(["size", str(SIZING), "--catalog", str(tmp_path / "none.csv")])
    assert "catalogue file not found" in missing
    unknown = user_error(
        ["size", str(SIZING), "--catalog", str(CATALOGUE), "--damper", "Nope", "--gearbox", "X"]
    )
    assert "error: --damper: no damper 'Nope'" in unknown
    assert "error: --gearbox: no gearbox 'X'" in unknown
    config = tmp_path / "req.toml"
    config.write_text(
        SIZING.read_text().replace('max_end_speed = "0.1 rad/s"', "max_end_speed = 3")
    )
    units = user_error(["size", str(config), "--catalog", str(CATALOGUE)])
    assert "requirements.max_end_speed: 3 has no unit" in units


def test_compare_fluid_user_errors_exit_2(tmp_path: Path) -> None:
    no_section = user_error(["compare-fluid", str(PAPER_CONFIG)])
    assert "no [fluid_damper] section" in no_section
    wide = tmp_path / "wide.toml"
    wide.write_text(FLUID.read_text().replace('deadband = "15 deg"', 'deadband = "100 deg"'))
    assert "not shorter than the travel" in user_error(["compare-fluid", str(wide)])
    hot = tmp_path / "hot.toml"
    hot.write_text(FLUID.read_text().replace('"100 degC"]', '"400 degC"]'))
    assert "damping_temperature_coefficient" in user_error(["compare-fluid", str(hot)])


def test_plot_to_unwritable_place_exits_2(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    message = user_error(["compare-fluid", str(FLUID), "--plot", str(blocker)])
    assert "cannot write plots" in message


@pytest.mark.parametrize(
    ("command", "options"),
    [
        (
            "size",
            {
                "--catalog": None,
                "--json": None,
                "--plot": None,
                "--damper": None,
                "--gearbox": None,
                "--fail-on": None,
                "--units": None,
                "--wide": None,
                "--plain": None,
                "--help": None,
            },
        ),
        (
            "compare-fluid",
            {
                "--method": "-m",
                "--json": None,
                "--plot": None,
                "--units": None,
                "--wide": None,
                "--plain": None,
                "--help": None,
            },
        ),
    ],
)
def test_help_has_an_example(
    command: str, options: dict[str, str | None], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # The documented options (docs/sizing.md), each described; the example runs as printed.
    screen = read_help(runner, app, [command])
    assert_options(screen, options)
    assert screen.example[0] == command
    run_example(runner, app, screen, tmp_path, monkeypatch)


def test_size_shows_torque_margin_per_temperature_and_unknown_masses() -> None:
    # The shipped example (damping at 0.005 rad/s, no factors): the Cc-16's torque margin
    # at each temperature, by hand at the end of travel, TM = Te / (FECD + FS + BECD w) - 1:
    # 0.06348 at -40 degC, 0.407 at 25, 1.243 at 100 (docs/sizing.md section 5).
    result = runner.invoke(app, ["size", str(SIZING), "--catalog", str(CATALOGUE), *CC16])
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("Torque margin TM"))
    rows = [line for line in lines[start:] if line.startswith("│")][:3]
    for row, t in zip(rows, (-40.0, 25.0, 100.0), strict=True):
        cells = [c.strip() for c in row.strip("│").split("│")]
        speed = 0.005
        expected = hand.TE / (hand.fecd(t) + hand.fs(t) + hand.becd(t) * speed) - 1.0
        assert float(cells[0]) == t
        assert cells[1] == "90"  # the end of travel, 1.57 rad
        assert float(cells[3]) == pytest.approx(hand.fecd(t), rel=5e-4)  # 4 digits printed
        assert float(cells[4]) == pytest.approx(hand.fs(t), rel=5e-4)
        assert float(cells[-1]) == pytest.approx(expected, rel=5e-4)
    # A Cc-16 part with a Demo part: no mass known, shown as '-' and explained.
    assert "mass '-': unknown" in " ".join(result.stdout.split())
    document = json.loads(
        runner.invoke(
            app, ["size", str(SIZING), "--catalog", str(CATALOGUE), "--json", *CC16]
        ).stdout
    )
    (cc16,) = [c for c in document["candidates"] if c["damper"] == "CDA Cc-16 damper" and
               c["gearbox"] == "CDA Cc-16 gearbox"]  # fmt: skip
    case = cc16["cases"][0]
    assert case["cannot_start"] is False
    assert case["torque_margin"]["resistive_Nm"]["ecd_friction"] == pytest.approx(
        hand.fecd(-40.0), rel=1e-12
    )
    assert case["torque_margin"]["margin"] == pytest.approx(
        hand.TE / (hand.fecd(-40.0) + hand.fs(-40.0) + hand.becd(-40.0) * 0.005) - 1.0, rel=1e-12
    )
    masses = [c["mass_kg"] for c in document["candidates"] if c["passed"]]
    assert masses[-1] is None  # the unknown mass ranks after the known ones
    assert all(m is not None for m in masses[:-1])
