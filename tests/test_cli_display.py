"""Terminal output an engineer can read and act on (issue 14 items 2 to 5).

- item 2: every command's tables fit 80 columns on the shipped examples; ``--wide`` shows
  what was hidden; ``--plain`` has no box-drawing characters; a wide terminal is used;
- item 3: the dynamic method's results are in the deploy tables, "no" stall only when
  nothing stalls or sticks, and ``--plot`` writes its plots with events marked;
- item 4: "cannot start: drive torque X < friction Y at T", and ``--fail-on`` exit codes;
- item 5: help without ``<bool>`` or ``list[...]`` type noise.

Numbers asserted come from the paper's inputs by hand (the friction sums, the stall angle
of a linear spring, the kinetic energy 1/2 J v^2), with tolerances from the tables'
four significant digits.
"""

from __future__ import annotations

import math
import re
import shutil
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner, Result

from ecdsim.cli.app import app
from tests import hand
from tests.conftest import ROOT, messages

runner = CliRunner()
BOX = re.compile("[\u2500-\u257f]")  # box-drawing characters
DYNAMIC = ROOT / "examples" / "paper_cc16_dynamic.toml"

# The paper's Cc-16 at -40 degC (examples/paper_cc16*.toml), by hand:
# FT = FD + FG + FL = 7.9e-4 + 4.5e-4 + (-2.12e-6 * -40 + 2.2e-4) = 1.5448e-3 N*m,
# FECD = N * FT = 380 * 1.5448e-3 = 0.587024 N*m, FS = -0.0044 * -40 + 0.58 = 0.756 N*m.
FRICTION_M40 = 380 * (7.9e-4 + 4.5e-4 + (-2.12e-6 * -40.0 + 2.2e-4)) + (-0.0044 * -40.0 + 0.58)


def _run(args: list[str], columns: int = 80) -> Result:
    return runner.invoke(app, args, env={"COLUMNS": str(columns)})


def _variant(tmp_path: Path, name: str, **replace: str) -> Path:
    """examples/paper_cc16_dynamic.toml with some lines replaced."""
    text = DYNAMIC.read_text(encoding="utf-8")
    for old, new in replace.items():
        assert old in text, old
        text = text.replace(old, new)
    path = tmp_path / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _stall(tmp_path: Path) -> Path:
    # End torque 1.2 N*m < FECD + FS at -40 degC: the spring runs down to the friction.
    return _variant(tmp_path, "stall", **{'end_torque = "1.58 N*m"': 'end_torque = "1.2 N*m"'})


def _no_start(tmp_path: Path) -> Path:
    # Start torque 1.2 N*m < FECD + FS = 1.343 N*m at -40 degC: no motion at release.
    return _variant(
        tmp_path,
        "nostart",
        **{
            'start_torque = "3.73 N*m"': 'start_torque = "1.2 N*m"',
            'end_torque = "1.58 N*m"': 'end_torque = "1.0 N*m"',
        },
    )


def _rebounding(tmp_path: Path) -> Path:
    """Rebounds (restitution 0.4), lost motion (3 deg) and self-heating (0.5 J/K)."""
    return _variant(
        tmp_path,
        "rebound",
        **{
            "restitution = 0.0 ": "restitution = 0.4 ",
            'lost_motion = "0 deg"': 'lost_motion = "3 deg"',
            'inertia = "5 kg*m^2"': 'inertia = "200 kg*m^2"',
            "static_friction_factor = 1.0 ": (
                'static_friction_factor = 1.0\n[damper.thermal]\nheat_capacity = "0.5 J/K"\n#'
            ),
        },
    )


# ---------------------------------------------------------------------------- item 2


def _commands(folder: Path) -> list[list[str]]:
    """Every command that prints results, on every shipped example it takes, as run from
    ``folder`` holding a copy of examples/ (relative paths: short, like a user's)."""
    shutil.copytree(ROOT / "examples", folder / "examples")
    tomls = sorted(p.name for p in (folder / "examples").glob("*.toml"))
    # A catalogue and a torque budget are not deployment configs (a wing file is: deploy
    # solves it, docs/wing.md).
    not_configs = ("catalogue.toml", "torque_budget.toml")
    runs = [["deploy", f"examples/{name}"] for name in tomls if name not in not_configs]
    return [
        *runs,
        ["demo", "--out", "demo"],
        ["size", "examples/sizing.toml", "--catalog", "examples/catalogue.toml"],
        ["compare-fluid", "examples/fluid.toml"],
        ["fit", "drop-test", "examples/drop_test.csv"],
        ["fit", "trace", "examples/deployment_trace.csv", "--config", "examples/paper_cc16.toml"],
        ["montecarlo", "examples/paper_cc16_tolerances.toml", "-n", "256", "--out", "mc"]
        + ["--no-plot", "--no-progress", "--overwrite"],
        ["report", "examples/paper_cc16.toml", "-o", "r.html"],
        # The qualification commands (docs/qualification.md).
        ["margin", "examples/torque_budget.toml"],
        ["margin", "examples/paper_cc16_budget.toml"],
        ["compare-fluid", "examples/fluid_measured.toml"],
        ["fit", "fluid-damper", "examples/fluid_bench.csv"],
        ["fit", "drive-test", "examples/drive_test.csv"],
        ["reliability", "weibull", "examples/life_test.csv"],
        ["reliability", "demonstrated", "--runs", "59", "--failures", "1"],
    ]


@pytest.mark.parametrize("plain", [False, True], ids=["boxes", "plain"])
def test_every_command_fits_80_columns(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, plain: bool
) -> None:
    monkeypatch.chdir(tmp_path)
    for args in _commands(tmp_path):
        extra = ["--plain"] if plain and args[0] not in ("report",) else []
        result = _run([*args, *extra])
        assert result.exit_code == 0, (args, result.output)
        lines = result.stdout.splitlines()
        assert max((len(line) for line in lines), default=0) <= 80, (args, result.stdout)
        if plain:
            assert not BOX.search(result.stdout), (args, result.stdout)


def test_size_and_compare_fluid_are_no_longer_forced_wide() -> None:
    # They printed 162 and 166 columns whatever the terminal (issue 14 item 2).
    size = _run(["size", "examples/sizing.toml", "--catalog", "examples/catalogue.toml"])
    fluid = _run(["compare-fluid", "examples/fluid.toml"])
    for result in (size, fluid):
        assert result.exit_code == 0, result.output
        assert max(len(line) for line in result.stdout.splitlines()) <= 80
        assert "(--wide)" in result.stdout  # hidden columns are named, not dropped silently


def test_a_hidden_column_is_named_and_wide_shows_it() -> None:
    narrow = _run(["deploy", str(DYNAMIC)])
    assert narrow.exit_code == 0, narrow.output
    assert "not shown at 80 columns: paper - exact [s] (--wide)" in narrow.stdout
    assert "paper -" not in narrow.stdout.split("not shown")[0]
    assert "rel." in narrow.stdout  # the paper's relative difference stays
    wide = _run(["deploy", str(DYNAMIC), "--wide"])
    assert wide.exit_code == 0, wide.output
    assert "paper -" in wide.stdout
    assert "not shown" not in wide.stdout
    assert max(len(line) for line in wide.stdout.splitlines()) > 80


def test_a_wide_terminal_is_used() -> None:
    # COLUMNS=200: the whole deploy table fits, nothing is hidden, nothing squeezed.
    result = _run(["deploy", str(DYNAMIC)], columns=200)
    assert result.exit_code == 0, result.output
    assert "paper -" in result.stdout
    assert "not shown" not in result.stdout


def test_plain_output_is_aligned_text() -> None:
    result = _run(["deploy", "examples/paper_cc16.toml", "--plain"])
    assert result.exit_code == 0, result.output
    assert not BOX.search(result.stdout)
    lines = result.stdout.splitlines()
    # The deployment rows line up under their headers: "-40" ends where "[degC]" ends.
    header = next(i for i, line in enumerate(lines) if line.startswith("Deployment"))
    unit_line = next(line for line in lines[header:] if "[degC]" in line)
    row = next(line for line in lines[header:] if line.lstrip().startswith("-40"))
    assert row.index("-40") + 3 == unit_line.index("[degC]") + len("[degC]")
    # Exact time at -40 degC, 48.13 s (hand.exact_time), in that row.
    assert f"{hand.exact_time(-40.0):.4g}" in row.split()


# ---------------------------------------------------------------------------- item 3


def _rows(stdout: str, title: str) -> dict[str, list[str]]:
    """The plain table after ``title``: temperature -> its cells (split on 2+ spaces)."""
    lines = stdout.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(title))
    rows: dict[str, list[str]] = {}
    for line in lines[start + 1 :]:
        if not line.strip() or not line[:1].isspace() and not line.lstrip()[:1].isdigit():
            if rows:
                break
            continue
        cells = re.split(r"\s{2,}", line.strip())
        if re.fullmatch(r"-?\d+(\.\d+)?", cells[0]):
            rows[cells[0]] = cells[1:]
        elif rows:
            break
    return rows


def test_dynamic_table_shows_latch_speed_and_energy() -> None:
    result = _run(["deploy", str(DYNAMIC), "--plain"])
    assert result.exit_code == 0, result.output
    rows = _rows(result.stdout, "Dynamic method: end of travel")
    assert set(rows) == {"-40", "25", "100"}
    # Moment of inertia at the hinge: load 5 kg*m^2 plus the rotor reflected through the
    # gearbox, 2e-7 * 380^2 = 0.02888 kg*m^2 (the config's comment).
    inertia = 5.0 + 2e-7 * 380.0**2
    for cells in rows.values():
        outcome, speed, energy = cells[0], float(cells[1]), float(cells[2])
        assert outcome == "latched"
        # KE = 1/2 J v^2; both printed to 4 significant digits (5e-4 relative each,
        # doubled for v^2): 2e-3 relative covers the rounding.
        assert energy == pytest.approx(0.5 * inertia * speed**2, rel=2e-3)
    note = " ".join(result.stdout.split())
    assert "no impacts" in note
    assert "never stuck" in note
    assert "no self-heating" in note


def test_stall_column_says_where_the_mechanism_stops(tmp_path: Path) -> None:
    result = _run(["deploy", str(_stall(tmp_path)), "--plain"])
    assert result.exit_code == 0, result.output
    deployment = _rows(result.stdout, "Deployment")
    # Linear spring 3.73 -> 1.2 N*m over 1.57 rad meets the friction 1.343024 N*m at
    # (3.73 - 1.343024) / ((3.73 - 1.2) / 1.57) = 1.48125 rad: every method agrees,
    # given in degrees as in the plots, the explorer and the warnings (issue 26 item 4).
    angle = (3.73 - FRICTION_M40) / ((3.73 - 1.2) / 1.57)
    assert deployment["-40"][-1] == f"at {math.degrees(angle):.3g} deg"
    assert deployment["25"][-1] == "no"
    dynamic = _rows(result.stdout, "Dynamic method: end of travel")
    assert dynamic["-40"][0] == "creeps to rest"  # the approach to rest is asymptotic
    # stuck at [deg] to 4 significant digits; then "inf" s (never exactly at rest).
    assert float(dynamic["-40"][3]) == pytest.approx(math.degrees(angle), rel=5e-4)
    assert dynamic["-40"][4] == "inf"


def test_cannot_start_in_table_and_warning(tmp_path: Path) -> None:
    result = _run(["deploy", str(_no_start(tmp_path)), "--plain"])
    assert result.exit_code == 0, result.output
    assert _rows(result.stdout, "Deployment")["-40"][-1] == "cannot start"
    assert _rows(result.stdout, "Dynamic method: end of travel")["-40"][0] == "cannot start"
    expected = f"cannot start: drive torque 1.2 N*m < friction {FRICTION_M40:.4g} N*m at -40 degC"
    assert pytest.approx(1.343024, abs=1e-9) == FRICTION_M40  # the sum above, by hand
    warnings = [line for line in messages(result.stderr) if "cannot start" in line]
    assert len(warnings) == 3  # paper, exact, dynamic (static factor 1: the same friction)
    assert all(expected in line for line in warnings), warnings


def test_the_dynamic_method_quotes_its_breakaway_friction(tmp_path: Path) -> None:
    # Static factor 1.5 and a 1.45 N*m start: the kinetic friction 1.343 N*m is overcome
    # (the quasi-static methods start) but not the breakaway 1.5 * 1.343024 = 2.0145 N*m.
    path = _variant(
        tmp_path,
        "breakaway",
        **{
            'start_torque = "3.73 N*m"': 'start_torque = "1.45 N*m"',
            'end_torque = "1.58 N*m"': 'end_torque = "1.0 N*m"',
            "static_friction_factor = 1.0 ": "static_friction_factor = 1.5 ",
        },
    )
    result = _run(["deploy", str(path), "-T", "-40"])
    assert result.exit_code == 0, result.output
    lines = [line for line in messages(result.stderr) if "cannot start" in line]
    breakaway = 1.5 * FRICTION_M40
    assert lines == [
        f"warning: [dynamic] cannot start: drive torque 1.45 N*m < friction {breakaway:.4g} N*m "
        "at -40 degC (at release)"
    ]


def test_rebounds_lost_motion_and_heating_are_shown(tmp_path: Path) -> None:
    import json

    path = _rebounding(tmp_path)
    table = _run(["deploy", str(path), "--plain"])
    assert table.exit_code == 0, table.output
    assert max(len(line) for line in table.stdout.splitlines()) <= 80
    end = _rows(table.stdout, "Dynamic method: end of travel")
    damper = _rows(table.stdout, "Dynamic method: damper")
    document = json.loads(_run(["deploy", str(path), "--json"]).stdout)
    for case in document["cases"]:
        d = case["dynamic"]
        t = f"{case['temperature_C']:g}"
        assert end[t][0] == "settled"
        assert int(end[t][3]) == d["impacts"] > 0
        assert float(end[t][4]) == pytest.approx(d["rebound_speed_rad_s"], rel=5e-4)
        assert float(damper[t][0]) == pytest.approx(d["engagement_time_s"], rel=5e-4)
        # The damper warms: its peak is above the ambient temperature.
        assert float(damper[t][1]) > case["temperature_C"]


def test_dynamic_plots_are_written_with_events(tmp_path: Path) -> None:
    import json

    import numpy as np

    from ecdsim.cli.common import load_run, predict_run
    from ecdsim.plotting_dynamic import (
        dynamic_result,
        events_by_kind,
        plot_damper_temperature,
        plot_dynamic,
    )

    plain = _run(["deploy", str(DYNAMIC), "--plot", str(tmp_path / "plain")])
    assert plain.exit_code == 0, plain.output
    names = sorted(p.name for p in (tmp_path / "plain").iterdir())
    assert "dynamic_angle_vs_time.png" in names
    assert "dynamic_speed_vs_time.png" in names
    assert "dynamic_damper_temperature.png" not in names  # no heating modelled
    path = _rebounding(tmp_path)
    heated = _run(["deploy", str(path), "--plot", str(tmp_path / "heated")])
    assert heated.exit_code == 0, heated.output
    assert (tmp_path / "heated" / "dynamic_damper_temperature.png").is_file()

    prediction = predict_run(load_run(path, None, None))
    result = dynamic_result(prediction)
    assert result is not None
    # One impact marker per impact the result counts, in each case.
    document = json.loads(_run(["deploy", str(path), "--json"]).stdout)
    counted = [c["dynamic"]["impacts"] for c in document["cases"]]
    marked = events_by_kind(result)["impact"]
    assert [sum(1 for row in marked if row[0] == j) for j in range(len(counted))] == counted
    for figure, ylabel in (
        (plot_dynamic(prediction, "angle"), "deployed angle [deg]"),
        (plot_dynamic(prediction, "speed"), "load speed [rad/s]"),
        (plot_damper_temperature(prediction), "damper temperature above ambient [K]"),
    ):
        ax = figure.axes[0]
        assert ax.get_title()
        assert ax.get_xlabel() == "time since release [s]"
        assert ax.get_ylabel() == ylabel
        legend = ax.get_legend()
        assert legend is not None
        assert len(legend.get_texts()) >= 3
    legend = plot_dynamic(prediction, "angle").axes[0].get_legend()
    assert legend is not None
    labels = [t.get_text() for t in legend.get_texts()]
    assert "impact on a stop (rebounds)" in labels
    assert "settles on the end stop" in labels
    assert "damper engages (lost motion closed)" in labels
    # The damper engages once the 3 deg lost motion closes: marked at 3 deg.
    engage = events_by_kind(result)["engage"]
    assert np.degrees([row[2] for row in engage]) == pytest.approx([3.0] * 3, rel=1e-9)


# ---------------------------------------------------------------------------- item 4


def test_fail_on_stall(tmp_path: Path) -> None:
    ok = _run(["deploy", "examples/paper_cc16.toml", "--fail-on", "stall"])
    assert ok.exit_code == 0, ok.output
    stalls = _run(["deploy", str(_stall(tmp_path)), "--fail-on", "stall"])
    assert stalls.exit_code == 1, stalls.output
    assert "Deployment" in stalls.stdout  # the results are printed first
    fails = [line for line in stalls.stderr.splitlines() if line.startswith("fail:")]
    assert "fail: stall: the exact method stalls at -40 degC" in fails
    assert "fail: stall: the dynamic method stalls at -40 degC" in fails


def test_fail_on_requirements(tmp_path: Path) -> None:
    # examples/sizing.toml: 10 s <= t <= 60 s from -40 to 100 degC. The exact times by
    # hand, 48.13 s at -40 degC and 15.41 s at 100 degC, are inside; a 30 s maximum is
    # missed at -40 degC only (25 degC: 26.86 s).
    assert 10.0 < hand.exact_time(100.0) < hand.exact_time(-40.0) < 60.0
    assert hand.exact_time(25.0) < 30.0 < hand.exact_time(-40.0)
    ok = _run(["deploy", "examples/sizing.toml", "--fail-on", "stall,requirements"])
    assert ok.exit_code == 0, ok.output
    text = (ROOT / "examples" / "sizing.toml").read_text(encoding="utf-8")
    strict = tmp_path / "strict.toml"
    strict.write_text(text.replace('"60 s"', '"30 s"'), encoding="utf-8")
    for args in (
        ["deploy", str(strict), "--fail-on", "requirements"],
        ["deploy", str(strict), "--fail-on", "stall", "--fail-on", "requirements"],
        ["report", str(strict), "-o", str(tmp_path / "r.html"), "--fail-on", "requirements"],
    ):
        result = _run(args)
        assert result.exit_code == 1, (args, result.output)
        fails = [line for line in result.stderr.splitlines() if line.startswith("fail:")]
        assert fails == ["fail: requirements: deployment time <= 30 s missed at -40 degC"]
    assert (tmp_path / "r.html").is_file()  # the report is written before the exit code


def test_size_fail_on_the_chosen_candidate() -> None:
    base = ["size", "examples/sizing.toml", "--catalog", "examples/catalogue.toml"]
    best = _run([*base, "--fail-on", "requirements,stall"])
    assert best.exit_code == 0, best.output  # the best-ranked candidate passes
    # Demo damper L on the 380:1 gearbox: too slow at -40 degC (the table: t > 60 s).
    chosen = ["--damper", "Demo damper L", "--gearbox", "CDA Cc-16 gearbox"]
    failing = _run([*base, *chosen, "--fail-on", "requirements"])
    assert failing.exit_code == 1, failing.output
    fails = [line for line in failing.stderr.splitlines() if line.startswith("fail:")]
    assert any("deployment time <= 60 s missed (worst at -40 degC)" in f for f in fails), fails


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["deploy", "examples/paper_cc16.toml", "--fail-on", "stal"],
            "error: --fail-on: 'stal' is not a condition; expected stall, requirements or both",
        ),
        (
            ["size", "examples/sizing.toml", "--catalog", "examples/catalogue.toml"]
            + ["--fail-on", "stall,margin"],
            "error: --fail-on: 'margin' is not a condition",
        ),
        (
            ["deploy", "examples/paper_cc16.toml", "--fail-on", "requirements"],
            "error: --fail-on requirements: examples/paper_cc16.toml has no [requirements]",
        ),
    ],
)
def test_fail_on_bad_values_exit_2_with_one_line(args: list[str], message: str) -> None:
    result = _run(args)
    assert result.exit_code == 2, result.output
    assert result.stdout == ""  # refused before anything is computed
    lines = result.stderr.splitlines()
    assert len(lines) == 1, lines
    assert lines[0].startswith(message), lines
    assert "Traceback" not in result.output


# ---------------------------------------------------------------------------- item 5


def _all_commands() -> list[list[str]]:
    """Every command and group, as the arguments before ``--help``."""
    found: list[list[str]] = [[]]

    def walk(group: object, prefix: list[str]) -> None:
        for name, command in getattr(group, "commands", {}).items():
            found.append([*prefix, name])
            walk(command, [*prefix, name])

    walk(typer.main.get_command(app), [])
    return found


def test_help_has_no_type_noise() -> None:
    commands = _all_commands()
    assert ["deploy"] in commands
    assert ["fit", "drop-test"] in commands
    for args in commands:
        result = runner.invoke(app, [*args, "--help"], env={"COLUMNS": "250"})
        assert result.exit_code == 0, (args, result.output)
        assert "<bool>" not in result.stdout, args
        assert "list[" not in result.stdout, args
        # nor a Python type beside a named argument or option (CONFIG <path>, PORT <int>)
        assert not re.search(r"<(path|str|int|float)>", result.stdout), args
        assert "Example: ecdsim" in result.stdout, args  # one example on every screen
    deploy = runner.invoke(app, ["deploy", "--help"], env={"COLUMNS": "250"}).stdout
    assert re.search(r"--temperature\s+-T\s+TEMP\s", deploy)
    assert re.search(r"--method\s+-m\s+METHOD\s", deploy)
    assert re.search(r"--fail-on\s+WHAT\s", deploy)


def test_report_says_cannot_start(tmp_path: Path) -> None:
    # The report's deployment table words a stall as deploy's table does: at -40 degC
    # the drive 1.2 N*m < 1.343 N*m friction (by hand, FRICTION_M40) for every method.
    out = tmp_path / "r.html"
    result = _run(["report", str(_no_start(tmp_path)), "-o", str(out)])
    assert result.exit_code == 0, result.output
    html = out.read_text(encoding="utf-8")
    assert html.count("<td>cannot start</td>") == 3  # paper, exact, dynamic at -40 degC
    assert "<td>at 0 rad</td>" not in html
