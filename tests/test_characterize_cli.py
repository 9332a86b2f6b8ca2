"""``ecdsim fit``: exit codes, JSON, warnings, plots, in process."""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim import __version__
from ecdsim.characterize.droptest import fit_drop_test
from ecdsim.characterize.plots import plot_parameters, plot_torque_speed
from ecdsim.cli.app import USER_ERROR, app
from tests.conftest import PAPER_CONFIG, ROOT, SavedFigures
from tests.helptext import assert_options, read_help, run_example
from tests.test_characterize_synthetic import G, Truth, drop_csv, drop_points, paper_trace

runner = CliRunner()
EXAMPLE = ROOT / "examples" / "drop_test.csv"
TRACE = ROOT / "examples" / "deployment_trace.csv"
PNG = b"\x89PNG\r\n\x1a\n"


def good_rows() -> list[str]:
    points = drop_points(Truth(), [-40.0, 25.0, 100.0], [2.0, 4.0, 6.0, 8.0])
    return drop_csv(points, inertia_column=False).splitlines()


def write(tmp_path: Path, lines: list[str]) -> Path:
    path = tmp_path / "data.csv"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def test_fit_help_lists_both_commands(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # The commands and options of docs/characterize.md, each described; each example
    # runs as printed.
    group = read_help(runner, app, ["fit"], has_example=False)  # each command shows one
    # drive-test and fluid-damper: tests/test_drive_test.py, tests/test_fluid_power_law.py.
    assert set(group.commands) == {"drop-test", "trace", "drive-test", "fluid-damper"}
    common = {"--json": None, "--plot": None, "--output": "-o", "--reference-temperature": None}
    common |= {"--strict": None, "--units": None, "--wide": None, "--plain": None, "--help": None}
    drop = read_help(runner, app, ["fit", "drop-test"])
    assert_options(drop, {**common, "--config": None, "--noise": None})
    run_example(runner, app, drop, tmp_path / "drop", monkeypatch)
    assert (tmp_path / "drop" / "plots" / "torque_vs_speed_fit.png").is_file()
    trace = read_help(runner, app, ["fit", "trace"])
    assert_options(trace, {**common, "--config": None, "--fit-spring": None, "--temperature": "-T"})
    run_example(runner, app, trace, tmp_path / "trace", monkeypatch)


def test_the_example_drop_test_fits_with_tables_and_plots(
    tmp_path: Path, saved_figures: SavedFigures
) -> None:
    result = runner.invoke(app, ["fit", "drop-test", str(EXAMPLE), "--plot", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "BECD" in result.stdout
    assert "[N*m*s/rad]" in result.stdout  # the unit on a header line of its own
    assert "Laws over temperature" in result.stdout
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == [
        "drop_test_residuals.png",
        "parameters_vs_temperature.png",
        "torque_vs_speed_fit.png",
    ]
    for path in tmp_path.iterdir():
        assert path.read_bytes()[:8] == PNG
    temperatures = (-40.0, 25.0, 100.0)
    (torque,) = saved_figures.axes("torque_vs_speed_fit.png")
    assert (torque.get_xlabel(), torque.get_ylabel()) == ("speed [rad/s]", "drive torque [N*m]")
    assert torque.get_title() == "Drop test: torque against speed"
    legend = saved_figures.legend(torque)
    assert [entry.split(": BECD ")[0] for entry in legend] == [f"{t:g} degC" for t in temperatures]
    assert all(entry.endswith(" N*m") and " N*m*s/rad, FECD " in entry for entry in legend)
    # The points' torques are the CSV's m g r - rig friction, by hand (grams, millimetres).
    with EXAMPLE.open(encoding="utf-8") as stream:
        rows = list(csv.DictReader(stream))
    points = [line for line in torque.get_lines() if str(line.get_label()).startswith("_")]
    assert len(points) == 3
    for t, line in zip(temperatures, points, strict=True):
        drive = [
            float(r["mass [g]"]) / 1000 * G * float(r["radius [mm]"]) / 1000 - 0.02
            for r in rows
            if float(r["temperature [degC]"]) == t
        ]
        np.testing.assert_allclose(np.asarray(line.get_ydata(), float), drive, rtol=1e-12)
    (residuals,) = saved_figures.axes("drop_test_residuals.png")
    assert residuals.get_ylabel() == "residual torque [N*m]"
    assert saved_figures.legend(residuals) == [f"{t:g} degC" for t in temperatures]
    for line in residuals.get_lines()[:3]:
        # Least-squares residuals of a line with an intercept sum to zero (normal equations).
        assert abs(float(np.sum(np.asarray(line.get_ydata(), float)))) < 1e-12
    damping, friction = saved_figures.axes("parameters_vs_temperature.png")
    assert damping.get_ylabel() == "BECD [N*m*s/rad]"
    assert (friction.get_xlabel(), friction.get_ylabel()) == ("temperature [degC]", "FECD [N*m]")
    assert saved_figures.legend(damping) == ["linear law", "resistivity law", "per temperature"]
    assert saved_figures.legend(friction) == ["line", "per temperature"]


def test_json_output(tmp_path: Path) -> None:
    result = runner.invoke(app, ["fit", "drop-test", str(EXAMPLE), "--json"])
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    assert document["ecdsim_version"] == __version__
    assert [e["temperature_C"] for e in document["temperatures"]] == [-40.0, 25.0, 100.0]
    assert document["bad_rows"] == []
    assert document["parameter_file"] is None
    # The example is drawn from a linear law (Truth: BECD = 24 (1 - 0.004 (T - 25)),
    # tests/test_characterize_synthetic.py). The resistivity law makes 1/BECD linear in T;
    # through the true values 1/BECD bends: at 25 degC it misses the chord of its -40 and
    # 100 degC values by 8.8 % (by hand below), over eight times the largest relative 95 %
    # half-width of the per-temperature values (1.0 %). A best fit spreads that miss over
    # the three points, still about three half-widths at each: only the linear law fits.
    truth = Truth()
    inverse = {t: 1.0 / truth.damping(t) for t in (-40.0, 25.0, 100.0)}
    chord = inverse[-40.0] + (inverse[100.0] - inverse[-40.0]) * 65.0 / 140.0
    bend = chord / inverse[25.0] - 1.0
    assert bend == pytest.approx(0.0884, abs=1e-4)
    widths = [
        (e["damping_rate_ci95_Nms_per_rad"][1] - e["damping_rate_ci95_Nms_per_rad"][0])
        / 2
        / e["damping_rate_Nms_per_rad"]
        for e in document["temperatures"]
    ]
    assert bend > 8.0 * max(widths)
    comparison = document["temperature_laws"]["comparison"]
    assert comparison["better"] == "linear"
    assert comparison["delta_aic"] < -2.0  # AIC(linear) - AIC(resistivity), Burnham-Anderson


def test_the_noise_model_is_chosen_on_the_command_line(tmp_path: Path) -> None:
    # The default is the torque-noise line; --noise timing fits log t instead, and says
    # so in the table's title, in the JSON document (top level and per temperature) and
    # in the parameter file's header.
    default = runner.invoke(app, ["fit", "drop-test", str(EXAMPLE), "--json"])
    timing = runner.invoke(app, ["fit", "drop-test", str(EXAMPLE), "--json", "--noise", "timing"])
    assert default.exit_code == 0, default.output
    assert timing.exit_code == 0, timing.output
    documents = {"torque": json.loads(default.stdout), "timing": json.loads(timing.stdout)}
    for name, document in documents.items():
        assert document["noise_model"] == name
        assert {e["noise_model"] for e in document["temperatures"]} == {name}
    for entry in documents["torque"]["temperatures"]:
        assert entry["residual_std_Nm"] > 0.0
        assert entry["relative_time_std"] is None
    for entry in documents["timing"]["temperatures"]:
        assert entry["residual_std_Nm"] is None
        # The example's scatter is a 0.01 N*m weighing error (docs section 9); seen as a
        # relative time error it is 0.01 / (torque - FECD), with torques of 1.43 to
        # 5.2 N*m and FECD 0.36 to 0.66 N*m at most 0.01 / (1.43 - 0.66) = 1.3 %.
        assert 0.0 < entry["relative_time_std"] < 0.013
        assert entry["speed_noise_bias"] is None
    output = tmp_path / "fitted.toml"
    args = ["fit", "drop-test", str(EXAMPLE), "--noise", "timing", "-o", str(output)]
    table = runner.invoke(app, args)
    assert table.exit_code == 0, table.output
    assert "--noise timing" in " ".join(table.stdout.split())  # the title wraps at 80 columns
    header = output.read_text(encoding="utf-8").splitlines()[0]
    assert header.endswith(": ecdsim fit drop-test --noise timing")


@dataclass(frozen=True)
class ResistivityTruth(Truth):
    """BECD = b_ref / (1 - c (T - t_ref)): the resistivity law with alpha = -c."""

    def damping(self, t: float) -> float:
        return self.b_ref / (1.0 - self.c * (t - self.t_ref))


@pytest.mark.parametrize(
    ("truth", "temperatures", "better"),
    [
        (Truth(), [-40.0, 25.0, 100.0], "linear"),
        (ResistivityTruth(), [-40.0, 25.0, 100.0], "resistivity"),
        (ResistivityTruth(), [-40.0, 100.0], None),  # two points: both laws pass through
    ],
    ids=["linear", "resistivity", "two-temperatures"],
)
def test_json_names_the_law_the_data_were_drawn_from(
    tmp_path: Path, truth: Truth, temperatures: list[float], better: str | None
) -> None:
    # Noise-free drops: the true law fits to round-off, the other misses by percents.
    points = drop_points(truth, temperatures, [2.0, 4.0, 6.0, 8.0])
    path = write(tmp_path, drop_csv(points, inertia_column=False).splitlines())
    result = runner.invoke(app, ["fit", "drop-test", str(path), "--json"])
    assert result.exit_code == 0, result.output
    comparison = json.loads(result.stdout)["temperature_laws"]["comparison"]
    assert comparison["better"] == better


def test_bad_rows_are_reported_and_the_rest_fitted(tmp_path: Path) -> None:
    lines = good_rows()
    lines[2] = lines[2].rsplit(",", 2)[0] + ",-5.0,0.0"  # a negative time
    lines.append(lines[3])  # a repeated row
    path = write(tmp_path, lines)
    result = runner.invoke(app, ["fit", "drop-test", str(path), "--json"])
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    assert [b["row"] for b in document["bad_rows"]] == [3, len(lines)]
    assert document["excluded_rows"] == [3, len(lines)]
    assert "warning: row 3, column 'time_s': '-5.0' must be > 0" in result.stderr
    assert f"warning: row {len(lines)}: " in result.stderr
    strict = runner.invoke(app, ["fit", "drop-test", str(path), "--strict"])
    assert strict.exit_code == USER_ERROR
    assert "error: --strict" in strict.stderr


def test_nothing_usable_exits_2_with_every_bad_row(tmp_path: Path) -> None:
    lines = ["temperature_C,mass_kg,radius_m,angle_rad,time_s", "25,2,0.05,3,abc", "25,,0.05,3,4"]
    result = runner.invoke(app, ["fit", "drop-test", str(write(tmp_path, lines))])
    assert result.exit_code == USER_ERROR
    assert result.stderr.splitlines()[-3:] == [
        f"error: {tmp_path / 'data.csv'}: row 2, column 'time_s': 'abc' is not a number; "
        "row excluded",
        f"error: {tmp_path / 'data.csv'}: row 3, column 'mass_kg': '' is empty; row excluded",
        f"error: {tmp_path / 'data.csv'}: no usable data row remains",
    ]
    assert "Traceback" not in result.output


def test_unknown_unit_exits_2_naming_the_column(tmp_path: Path) -> None:
    lines = ["temperature_C,mass [lbz],radius_m,angle_rad,time_s", "25,2,0.05,3,4"]
    result = runner.invoke(app, ["fit", "drop-test", str(write(tmp_path, lines))])
    assert result.exit_code == USER_ERROR
    assert "column 'mass [lbz]': unit 'lbz' is not a unit pint knows; expected a mass" in (
        result.stderr
    )


def test_every_temperature_failing_exits_2(tmp_path: Path) -> None:
    header = good_rows()[0]
    lines = [header, "25,2.0,0.05,3.0,10.0,0.0", "60,4.0,0.05,3.0,5.0,0.0"]
    result = runner.invoke(app, ["fit", "drop-test", str(write(tmp_path, lines))])
    assert result.exit_code == USER_ERROR
    assert "error: not fitted: 25 degC (rows 2): fewer than two distinct speeds" in result.stderr
    assert "error: no temperature could be fitted" in result.stderr


def test_one_temperature_failing_is_reported_and_the_rest_fitted(tmp_path: Path) -> None:
    lines = [*good_rows(), "60,4.0,0.05,3.0,5.0,0.0"]
    path = write(tmp_path, lines)
    result = runner.invoke(app, ["fit", "drop-test", str(path), "--json"])
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    assert [f["temperature_C"] for f in document["failed_temperatures"]] == [60.0]
    assert "error: not fitted: 60 degC" in result.stderr
    assert runner.invoke(app, ["fit", "drop-test", str(path), "--strict"]).exit_code == 2


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["fit", "drop-test", "missing.csv"], "data file not found: missing.csv"),
        (
            ["fit", "drop-test", str(EXAMPLE), "--config", "missing.toml"],
            "--config: config file not found",
        ),
        (
            ["fit", "drop-test", str(EXAMPLE), "--reference-temperature", "-300"],
            "--reference-temperature: '-300 degC' is below absolute zero",
        ),
        (
            ["fit", "drop-test", str(EXAMPLE), "--noise", "speed"],
            "--noise: unknown noise model 'speed'; choose one of: torque, timing",
        ),
        (
            ["fit", "trace", str(TRACE), "--config", str(PAPER_CONFIG), "-T", "-400"],
            "--temperature: '-400 degC' is below absolute zero",
        ),
    ],
)
def test_user_errors_exit_2(args: list[str], message: str) -> None:
    result = runner.invoke(app, args)
    assert result.exit_code == USER_ERROR
    assert message in result.stderr
    assert "Traceback" not in result.output


def test_an_unwritable_parameter_file_exits_2(tmp_path: Path) -> None:
    folder = tmp_path / "taken"
    folder.mkdir()
    result = runner.invoke(app, ["fit", "drop-test", str(EXAMPLE), "-o", str(folder)])
    assert result.exit_code == USER_ERROR
    assert f"error: -o {folder}: cannot write" in result.stderr


def test_trace_command(tmp_path: Path, saved_figures: SavedFigures) -> None:
    args = ["fit", "trace", str(TRACE), "--config", str(PAPER_CONFIG)]
    result = runner.invoke(app, [*args, "--plot", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "Trace fit" in result.stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "parameters_vs_temperature.png",
        "trace_fit.png",
        "trace_residuals.png",
    ]
    temperatures = (-40.0, 25.0, 100.0)
    (fitted,) = saved_figures.axes("trace_fit.png")
    assert (fitted.get_xlabel(), fitted.get_ylabel()) == ("time since release [s]", "angle [deg]")
    legend = [f"{t:g} degC, fitted (exact solution)" for t in temperatures]
    assert saved_figures.legend(fitted) == legend
    curves = [line for line in fitted.get_lines() if str(line.get_label()) in legend]
    assert len(curves) == 3
    for line in curves:
        t = float(str(line.get_label()).split(" degC")[0])
        times = np.asarray(line.get_xdata(), float)
        truth = np.degrees(paper_trace(t, times))
        # The example is the paper's deployment plus 0.1 deg noise: a least-squares curve
        # lies within 5 noise sigmas of the truth (no fitted value's standard error
        # exceeds the noise's, as no leverage exceeds 1).
        assert np.max(np.abs(np.asarray(line.get_ydata(), float) - truth)) < 0.5
    (residuals,) = saved_figures.axes("trace_residuals.png")
    assert residuals.get_ylabel() == "residual angle [deg]"
    assert saved_figures.legend(residuals) == [f"{t:g} degC" for t in temperatures]
    values = np.concatenate(
        [np.asarray(line.get_ydata(), float) for line in residuals.get_lines()[:3]]
    )
    # Their rms is the 0.1 deg noise: relative standard error 1/sqrt(2 dof), dof = n - 6.
    rms = float(np.sqrt(np.mean(values**2)))
    assert rms == pytest.approx(0.1, rel=5.0 / math.sqrt(2 * (values.size - 6)))
    document = json.loads(runner.invoke(app, [*args, "--json", "--fit-spring"]).stdout)
    assert document["mode"] == "spring"
    assert (
        document["spring"]["start_torque_ci95_Nm"][0]
        < 3.73
        < document["spring"]["start_torque_ci95_Nm"][1]
    )
    missing = runner.invoke(app, ["fit", "trace", str(TRACE)])
    assert missing.exit_code == USER_ERROR  # --config is required


def test_a_trace_that_cannot_be_fitted_exits_2(tmp_path: Path) -> None:
    config = tmp_path / "table.toml"
    config.write_text(
        PAPER_CONFIG.read_text().replace(
            'start_torque = "3.73 N*m"\nend_torque = "1.58 N*m"',
            'spring_table = [["0 rad", "3.73 N*m"], ["1.57 rad", "1.58 N*m"]]',
        )
    )
    args = ["fit", "trace", str(TRACE), "--config", str(config), "--fit-spring"]
    result = runner.invoke(app, args)
    assert result.exit_code == USER_ERROR
    assert "needs a linear spring" in result.stderr


def test_figures_have_a_line_and_points_per_temperature() -> None:
    result = fit_drop_test(EXAMPLE)
    figure = plot_torque_speed(result)
    (axes,) = figure.axes
    assert len(axes.lines) == 2 * len(result.fits)  # points and line per temperature
    assert result.laws is not None
    fits = result.fits
    parameters = plot_parameters(
        [f.temperature for f in fits],
        [f.line.slope for f in fits],
        [f.line.intercept for f in fits],
        result.laws,
    )
    top, bottom = parameters.axes
    laws = [line.get_label() for line in top.lines if str(line.get_label()).endswith(" law")]
    assert laws == ["linear law", "resistivity law"]
    assert len(top.collections) >= 2  # their confidence bands (plus the error bars)
    assert [line.get_label() for line in bottom.lines if line.get_label() == "line"] == ["line"]
