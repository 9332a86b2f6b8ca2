"""The command line, in process (CliRunner) and as the installed console script."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim import __version__
from ecdsim.cli.app import app
from tests import hand
from tests.conftest import PAPER_CONFIG, ROOT, SavedFigures
from tests.helptext import assert_options, read_help, run_example
from tests.test_characterize_synthetic import paper_trace

runner = CliRunner()


def test_deploy_json_is_stable_and_correct() -> None:
    result = runner.invoke(app, ["deploy", str(PAPER_CONFIG), "--json"])
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    assert document["ecdsim_version"] == __version__
    assert [c["temperature_C"] for c in document["cases"]] == [-40.0, 25.0, 100.0]
    for case in document["cases"]:
        t = case["temperature_C"]
        assert case["damping_rate_Nms_per_rad"] == pytest.approx(hand.becd(t), rel=1e-12)
        assert case["friction_Nm"] == pytest.approx(hand.fecd(t), rel=1e-12)
        assert case["system_friction_Nm"] == pytest.approx(hand.fs(t), rel=1e-12)
        assert case["paper"]["deployment_time_s"] == pytest.approx(hand.paper_time(t), rel=1e-12)
        assert case["exact"]["deployment_time_s"] == pytest.approx(hand.exact_time(t), rel=1e-12)
        for method in ("paper", "exact"):
            assert set(case[method]) >= {
                "deployment_time_s",
                "start_speed_rad_s",
                "end_speed_rad_s",
                "stalled",
                "stall_angle_rad",
            }
            assert case[method]["stalled"] is False
            assert case[method]["stall_angle_rad"] is None
        diff = case["difference"]["deployment_time_s"]
        assert diff == pytest.approx(hand.paper_time(t) - hand.exact_time(t), rel=1e-9)
    assert document["warnings"] == []


def test_deploy_table_output() -> None:
    result = runner.invoke(app, ["deploy", str(PAPER_CONFIG)])
    assert result.exit_code == 0, result.output
    # Exact time at 25 degC to 4 significant digits: 26.86 s (hand.exact_time).
    assert f"{hand.exact_time(25.0):.4g}" in result.stdout
    assert f"{hand.paper_time(-40.0):.4g}" in result.stdout
    assert "BECD" in result.stdout
    # The unit sits on a header line of its own (the tables fit 80 columns).
    assert "[degC]" in result.stdout


def test_temperature_and_method_overrides() -> None:
    result = runner.invoke(
        app, ["deploy", str(PAPER_CONFIG), "--json", "-T", "0", "-T", "323.15 K", "-m", "exact"]
    )
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    # 323.15 K - 273.15 is 50 degC up to float rounding of the offset (1e-12 degC).
    assert [c["temperature_C"] for c in document["cases"]] == pytest.approx([0.0, 50.0], abs=1e-12)
    assert document["methods"] == ["exact"]
    assert "paper" not in document["cases"][0]


def test_stall_warning_goes_to_stderr_and_json(tmp_path: Path) -> None:
    config = tmp_path / "stall.toml"
    # End torque 0.5 N*m is below the total friction at every temperature
    # (F = 1.343, 1.005, 0.614 N*m at -40, 25, 100 degC by tests/hand.py).
    config.write_text(PAPER_CONFIG.read_text().replace('"1.58 N*m"', '"0.5 N*m"'))
    result = runner.invoke(app, ["deploy", str(config), "--json"])
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)  # stdout holds the JSON alone
    assert all(c["exact"]["stalled"] for c in document["cases"])
    assert all(c["exact"]["deployment_time_s"] is None for c in document["cases"])
    assert {w["code"] for w in document["warnings"]} == {"stall"}
    assert "warning: [exact] stalls at" in result.stderr


@pytest.mark.parametrize(
    ("replace", "fragment"),
    [
        (("ratio = 380", "ratio = -380"), "gearbox.ratio: -380 must be > 0"),
        (('"1.57 rad"', '"1.57 N*m"'), "load.travel: '1.57 N*m' has the wrong dimension"),
        (("[gearbox]", "[gearbox]\nspeed = 3"), "gearbox.speed: unknown key"),
        (("title =", "title = = "), "not valid TOML"),
    ],
)
def test_bad_config_exits_2_without_traceback(
    tmp_path: Path, replace: tuple[str, str], fragment: str
) -> None:
    config = tmp_path / "bad.toml"
    config.write_text(PAPER_CONFIG.read_text().replace(*replace, 1))
    result = runner.invoke(app, ["deploy", str(config)])
    assert result.exit_code == 2
    assert f"error: {config}: {fragment}" in result.stderr
    assert "Traceback" not in result.output
    assert result.stdout == ""


def test_bad_arguments_exit_2(tmp_path: Path) -> None:
    missing = runner.invoke(app, ["deploy", str(tmp_path / "none.toml")])
    assert missing.exit_code == 2
    assert "config file not found" in missing.stderr
    bad = runner.invoke(app, ["deploy", str(PAPER_CONFIG), "-T", "warm", "-m", "guess"])
    assert bad.exit_code == 2
    assert "--temperature: 'warm'" in bad.stderr
    assert "--method: 'guess' is not a method" in bad.stderr
    domain = runner.invoke(app, ["deploy", str(PAPER_CONFIG), "-T", "400"])
    assert domain.exit_code == 2
    assert "damping_temperature_coefficient" in domain.stderr


PAPER_TITLE = "CDA Cc-16 test deployment (paper section 6)"  # examples/paper_cc16.toml
METHOD_LABELS = {"paper": "paper (Eq. 8-13)", "exact": "exact quasi-static"}


def assert_deployment_plots(figures: SavedFigures) -> None:
    """The two deploy plots of the paper example show the paper's numbers, by hand."""
    (angle,) = figures.axes("angle_vs_time.png")
    assert " ".join(angle.get_title().split()) == f"{PAPER_TITLE}: angle against time"
    assert angle.get_xlabel() == "time since release [s]"
    assert angle.get_ylabel() == "deployed angle [deg]"
    temperatures = (-40.0, 25.0, 100.0)
    assert figures.legend(angle) == [
        f"{t:g} degC, {METHOD_LABELS[m]}" for m in ("paper", "exact") for t in temperatures
    ]
    lines = {str(line.get_label()): line for line in angle.get_lines()}
    for t in temperatures:
        times, degrees = (
            np.asarray(v) for v in lines[f"{t:g} degC, exact quasi-static"].get_data()
        )
        # The axis runs to 1.1 times the slowest deployment (exact, -40 degC, by hand).
        assert times[-1] == pytest.approx(1.1 * hand.exact_time(-40.0), rel=1e-12)
        # The exact curve is the closed form phi(t) = (a/k)(1 - exp(-k t/B)), by hand;
        # 1e-9 covers the evaluation of the same formula in another arrangement.
        expected = np.degrees(paper_trace(t, times))
        np.testing.assert_allclose(degrees, expected, rtol=1e-9, atol=1e-9)
        assert degrees[-1] == pytest.approx(np.degrees(hand.TRAVEL), rel=1e-12)  # latched
    (torque,) = figures.axes("torque_vs_speed.png")
    assert " ".join(torque.get_title().split()) == f"{PAPER_TITLE}: ECD torque against speed"
    assert torque.get_xlabel() == "input shaft speed [rad/s]"
    assert torque.get_ylabel() == "ECD reaction torque [N*m]"
    assert figures.legend(torque) == [
        *(
            f"{t:g} degC: BECD {hand.becd(t):.3g} N*m*s/rad, FECD {hand.fecd(t):.3g} N*m"
            for t in temperatures
        ),
        # The dots of the operating range are explained (issue 26 item 10).
        "operating range: end (latch) to start speed, exact method",
    ]
    # One line per temperature; the "_"-labelled ones mark the operating range.
    reaction_lines = [line for line in torque.get_lines() if str(line.get_label())[:1] != "_"]
    assert len(reaction_lines) == 3
    for line in reaction_lines:
        t = float(str(line.get_label()).split(" degC")[0])
        speed, reaction = (np.asarray(v) for v in line.get_data())
        # Eq. 5 inverted, T = FECD_T + BECD_T omega (Eq. 1-4 by hand): rounding only.
        np.testing.assert_allclose(reaction, hand.fecd(t) + hand.becd(t) * speed, rtol=1e-12)


def test_plots_are_written(tmp_path: Path, saved_figures: SavedFigures) -> None:
    result = runner.invoke(app, ["deploy", str(PAPER_CONFIG), "--plot", str(tmp_path / "p")])
    assert result.exit_code == 0, result.output
    for name in ("angle_vs_time.png", "torque_vs_speed.png"):
        data = (tmp_path / "p" / name).read_bytes()
        assert data.startswith(b"\x89PNG")
    assert not list((tmp_path / "p").glob(".*.tmp"))  # no temporary file left behind
    assert sorted(saved_figures.figures) == ["angle_vs_time.png", "torque_vs_speed.png"]
    assert_deployment_plots(saved_figures)


def test_plot_to_unwritable_place_exits_2(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    result = runner.invoke(app, ["deploy", str(PAPER_CONFIG), "--plot", str(blocker)])
    assert result.exit_code == 2
    assert "cannot write plots" in result.stderr


def test_demo_writes_plots(tmp_path: Path, saved_figures: SavedFigures) -> None:
    result = runner.invoke(app, ["demo", "--out", str(tmp_path / "demo")])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "demo" / "angle_vs_time.png").read_bytes().startswith(b"\x89PNG")
    assert f"{hand.exact_time(100.0):.4g}" in result.stdout
    # The demo is the paper example: the same two figures, the same hand numbers.
    assert_deployment_plots(saved_figures)


def test_help_and_version(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # The commands and options of the README and docs/config.md, each described, and each
    # screen's example run exactly as printed.
    top = read_help(runner, app, [])
    assert set(top.commands) == {
        "deploy",
        "demo",
        "size",
        "compare-fluid",
        "montecarlo",
        "sweep",
        "repeat",
        "export-fmu",
        "report",
        "app",
        "fit",
        "margin",
        "reliability",
        "precompile",
    }
    assert_options(top, {"--version": None, "--help": None})
    run_example(runner, app, top, tmp_path / "top", monkeypatch)
    assert (tmp_path / "top" / "plots" / "angle_vs_time.png").is_file()
    deploy = read_help(runner, app, ["deploy"])
    assert_options(
        deploy,
        {
            "--json": None,
            "--plot": None,
            "--temperature": "-T",
            "--method": "-m",
            "--timeseries": None,
            "--fail-on": None,
            "--units": None,
            "--wide": None,
            "--plain": None,
            "--help": None,
        },
    )
    assert "paper, exact, dynamic" in deploy.options["--method"]  # every registered solver
    shown = json.loads(run_example(runner, app, deploy, tmp_path / "deploy", monkeypatch).stdout)
    assert [c["temperature_C"] for c in shown["cases"]] == [-40.0, 25.0, 100.0]
    demo = read_help(runner, app, ["demo"])
    assert_options(
        demo, {"--out": None, "--wide": None, "--plain": None, "--units": None, "--help": None}
    )
    run_example(runner, app, demo, tmp_path / "demo", monkeypatch)
    assert (tmp_path / "demo" / "ecdsim-demo" / "angle_vs_time.png").is_file()
    version = runner.invoke(app, ["--version"])
    assert version.stdout.strip() == f"ecdsim {__version__}"


MONTECARLO_OPTIONS: dict[str, str | None] = {
    "--samples": "-n",
    "--method": "-m",
    "--workers": None,
    "--scheduler": None,
    "--out": None,
    "--resume": None,
    "--overwrite": None,
    "--json": None,
    "--seed": None,
    "--sampling": None,
    "--chunk-size": None,
    "--temperature": "-T",
    "--plot": None,
    "--no-plot": None,
    "--progress": None,
    "--units": None,
    "--wide": None,
    "--plain": None,
    "--help": None,
}


@pytest.mark.parametrize(
    ("command", "options", "example"),
    [
        (
            "montecarlo",
            MONTECARLO_OPTIONS,
            ["montecarlo", "examples/paper_cc16_tolerances.toml", "--samples", "100000"],
        ),
        (
            "report",
            {"--output": "-o", "--pdf": None, "--temperature": "-T", "--method": "-m"}
            | {"--fail-on": None, "--units": None, "--help": None},
            ["report", "examples/paper_cc16.toml", "-o", "report.html", "--pdf"],
        ),
        (
            "app",
            {"--host": None, "--port": None, "--units": None, "--help": None},
            ["app", "examples/paper_cc16.toml"],
        ),
        # run in tests/test_numba_setup.py (from a read-only copy of the package)
        ("precompile", {"--help": None}, ["precompile"]),
    ],
)
def test_help_of_the_other_commands(
    command: str, options: dict[str, str | None], example: list[str]
) -> None:
    # Their examples are not run here: a 100 000-sample study, a PDF through Chromium and
    # a server are exercised by test_montecarlo_run, test_report and test_webapp_e2e.
    screen = read_help(runner, app, [command])
    assert_options(screen, options)
    assert screen.example == example
    assert all((ROOT / word).is_file() for word in example if word.startswith("examples/"))


def installed_command() -> Path:
    """The console script installed beside this interpreter (make test installs it)."""
    path = Path(sys.executable).parent / "ecdsim"
    assert path.exists(), f"ecdsim console script not installed next to {sys.executable}"
    return path


def test_installed_command_json() -> None:
    env = {**os.environ, "COLUMNS": "200"}
    done = subprocess.run(
        [installed_command(), "deploy", str(PAPER_CONFIG), "--json"],
        capture_output=True,
        text=True,
        check=False,
        env=env,
    )
    assert done.returncode == 0, done.stderr
    document = json.loads(done.stdout)
    assert document["cases"][1]["exact"]["deployment_time_s"] == pytest.approx(
        hand.exact_time(25.0), rel=1e-12
    )


def test_installed_command_bad_config(tmp_path: Path) -> None:
    config = tmp_path / "bad.toml"
    config.write_text(PAPER_CONFIG.read_text().replace('"1.3e-4 N*m*s/rad"', '"1.3e-4 N*m"'))
    done = subprocess.run(
        [installed_command(), "deploy", str(config)], capture_output=True, text=True, check=False
    )
    assert done.returncode == 2
    assert "damper.damping_rate: '1.3e-4 N*m' has the wrong dimension" in done.stderr
    assert "Traceback" not in done.stderr


def test_help_does_not_import_heavy_modules() -> None:
    code = (
        "import sys, ecdsim.cli.app as a\n"
        "heavy = [m for m in ('numpy', 'scipy', 'matplotlib', 'pint', 'pydantic') "
        "if m in sys.modules]\n"
        "print(','.join(heavy))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == ""


def test_python_dash_m() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "ecdsim", "--version"], capture_output=True, text=True, check=True
    )
    assert done.stdout.strip() == f"ecdsim {__version__}"


@pytest.mark.parametrize(
    "arguments",
    [
        ["margin"],
        ["compare-fluid"],
        ["export-fmu", "--out", "unused.fmu"],
        ["size", "--catalog", "examples/catalogue.toml"],
        ["repeat", "-n", "3", "--cool-down", "60 s"],
    ],
    ids=lambda arguments: arguments[0],
)
def test_single_hinge_commands_name_the_commands_that_take_a_wing_file(
    arguments: list[str],
) -> None:
    # One message for every command that takes only a single hinge's file (margin had said
    # the wing file was "neither a torque budget nor a deployment config").
    wing = ROOT / "examples" / "wing_cc16_three_panel.toml"
    result = CliRunner().invoke(app, [arguments[0], str(wing), *arguments[1:]])
    assert result.exit_code == 2, result.output
    assert result.stderr.strip().splitlines() == [
        f"error: {wing}: wing: this is a wing file (docs/wing.md); `ecdsim deploy`, "
        "`report`, `sweep` and `montecarlo` take it, this command takes a single hinge's file"
    ]


def test_top_level_help_lists_each_command_summary_as_one_paragraph() -> None:
    # typer's rich mode kept the docstring's line breaks in the command list, so at any
    # width the summaries of deploy and export-fmu broke mid-sentence ("(model exchange
    # and" / "co-simulation, ..."). At 250 columns each summary is one line of the list.
    screen = read_help(CliRunner(), app, [], has_example=True)
    assert screen.commands["deploy"].startswith(
        "Predict deployment time, speeds and stall at each temperature (paper Eq. 1-13); "
        "a wing file: each hinge's latching"
    )
    assert "(model exchange and co-simulation, in C;" in screen.commands["export-fmu"]
