"""ecdsim sweep (issue 17 item 4): factorial and Latin hypercube designs, the tidy table.

Asserted numbers come from the paper's equations typed by hand (Eq. 1-4, 8-11, with the
gear ratio and start torque as parameters), not from ecdsim.
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.sweeps import SweepError, design, parse_vary
from tests.conftest import require

ROOT = Path(__file__).resolve().parent.parent
PAPER = ROOT / "examples" / "paper_cc16.toml"


def friction(t: float, ratio: float) -> float:
    """FECD_T + FS_T by hand (Eq. 2, 4 and the paper's FS_T) at gear ratio ``ratio``."""
    fd, fg = 7.9e-4, 4.5e-4
    return (fd + (-2.12e-6 * t + 2.2e-4) + fg) * ratio + (-0.0044 * t + 0.58)


def paper_time(t: float, ratio: float, ts: float) -> float:
    """Eq. 1-4 and 8-11 of the paper's section 6 by hand, at gear ratio ``ratio``."""
    bd = 1.3e-4
    becd = (bd * (1.0 - 0.004 * (t - 25.0)) + 0.26 * bd) * ratio**2
    friction_ = friction(t, ratio)
    ws = (ts - friction_) / becd
    we = (1.58 - friction_) / becd
    return 1.57 / ((ws + we) / 2.0)


def _run(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, ["sweep", str(PAPER), *args])
    return result.exit_code, result.stdout, result.stderr


def test_full_factorial_table_matches_the_hand_calculation(tmp_path: Path) -> None:
    out = tmp_path / "s.csv"
    code, stdout, stderr = _run(
        "--vary", "gearbox.ratio=200:600:5",
        "--vary", "load.start_torque=3.73,30 lbf*in",
        "-m", "paper", "-o", str(out),
    )  # fmt: skip
    assert code == 0, stderr
    assert "10 points, 30 rows" in stdout
    rows = list(csv.DictReader(io.StringIO(out.read_text(encoding="utf-8"))))
    assert len(rows) == 5 * 2 * 3  # ratios x torques x the config's 3 temperatures
    lbf_in = 0.45359237 * 9.80665 * 0.0254  # N*m, exact definitions
    seen = set()
    for row in rows:
        ratio = float(row["gearbox.ratio"])
        ts = float(row["load.start_torque_Nm"])
        assert ts == pytest.approx(3.73) or ts == pytest.approx(30 * lbf_in, rel=1e-12)
        t = float(row["temperature_C"])
        assert row["method"] == "paper"
        if friction(t, ratio) >= 1.58:  # the spring's end torque: it stalls before the end
            assert row["stalled"] == "True"
            assert row["deployment_time_s"] == ""  # no time (inf in ecdsim, empty in CSV)
            continue
        assert row["stalled"] == "False"
        # Same equations, different arithmetic order: 1e-12.
        assert float(row["deployment_time_s"]) == pytest.approx(paper_time(t, ratio, ts), rel=1e-12)
        seen.add((ratio, round(ts, 6)))
    assert {r for r, _ in seen} == {200.0, 300.0, 400.0, 500.0, 600.0}


def test_parquet_holds_the_same_table(tmp_path: Path) -> None:
    pq = require("pyarrow.parquet")
    args = ["--vary", "gearbox.ratio=300,380", "-T", "25", "-m", "exact"]
    assert _run(*args, "-o", str(tmp_path / "s.csv"))[0] == 0
    assert _run(*args, "-o", str(tmp_path / "s.parquet"))[0] == 0
    table = pq.read_table(tmp_path / "s.parquet").to_pylist()
    rows = list(csv.DictReader(io.StringIO((tmp_path / "s.csv").read_text(encoding="utf-8"))))
    assert [r["deployment_time_s"] for r in table] == [float(r["deployment_time_s"]) for r in rows]


def test_latin_hypercube_fills_each_stratum_once_and_repeats_with_its_seed() -> None:
    varies = [parse_vary("gearbox.ratio=200:600:2"), parse_vary("load.inertia=1,5,20,40")]
    points = design(varies, latin=8, seed=3)
    assert len(points) == 8
    ratios = sorted(p["gearbox.ratio"][1] for p in points)
    # One point in each of the 8 equal strata of 200..600 (width 50), by construction.
    assert [int((r - 200.0) // 50.0) for r in ratios] == list(range(8))
    # List values: 8 strata over 4 values, each value twice.
    inertias = sorted(p["load.inertia"][1] for p in points)
    assert inertias == [1.0, 1.0, 5.0, 5.0, 20.0, 20.0, 40.0, 40.0]
    assert design(varies, latin=8, seed=3) == points
    assert design(varies, latin=8, seed=4) != points


def test_latin_from_the_cli_with_units(tmp_path: Path) -> None:
    out = tmp_path / "lhs.csv"
    code, stdout, stderr = _run(
        "--vary", "load.start_torque=30:40:2 lbf*in", "--latin", "4", "--seed", "7",
        "-T", "25", "-m", "paper", "-o", str(out),
    )  # fmt: skip
    assert code == 0, stderr
    rows = list(csv.DictReader(io.StringIO(out.read_text(encoding="utf-8"))))
    lbf_in = 0.45359237 * 9.80665 * 0.0254
    torques = sorted(float(r["load.start_torque_Nm"]) / lbf_in for r in rows)
    # Strata of 2.5 lbf*in over 30..40 (converted back by hand): one point each.
    assert [int((x - 30.0) // 2.5) for x in torques] == [0, 1, 2, 3]


@pytest.mark.parametrize(
    ("vary", "needle"),
    [
        ("gearbox.ratio=200:600:x", "--vary gearbox.ratio: the count 'x'"),
        ("gearbox.ratio=200:600:1", "--vary gearbox.ratio: the count '1'"),
        ("gearbox.ratio=", "--vary gearbox.ratio: no values"),
        ("gearbox.ratio", "--vary 'gearbox.ratio'"),
        ("load.inertia=a,b", "--vary load.inertia: 'a' is not a number"),
        ("load.inertia=1:2", "--vary load.inertia: '1:2' is not START:STOP:N"),
        ("load.inertia=5 N*m", "--vary load.inertia:"),
        ("load.inertia=-1,5", "--vary: load.inertia:"),
        ("gearbox.nope=1,2", "--vary: gearbox.nope: unknown key"),
    ],
)
def test_bad_vary_is_one_line_exit_2(vary: str, needle: str, tmp_path: Path) -> None:
    code, stdout, stderr = _run("--vary", vary, "-o", str(tmp_path / "x.csv"))
    assert code == 2
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    assert needle in lines[0]
    assert not (tmp_path / "x.csv").exists()


def test_duplicate_key_and_bad_output() -> None:
    with pytest.raises(SweepError, match="given more than once"):
        design([parse_vary("gearbox.ratio=1,2"), parse_vary("gearbox.ratio=3,4")])
    code, _, stderr = _run("--vary", "gearbox.ratio=300,400", "--plot", "x", "--column", "z")
    assert code == 2
    assert "--column 'z'" in stderr
    code, _, stderr = _run("--vary", "gearbox.ratio=300,400", "--plot", "x", "--plot-method", "q")
    assert code == 2
    assert "--plot-method 'q': not run" in stderr


def test_plot_old_forms_still_work_with_a_note(tmp_path: Path) -> None:
    """Before issue 26 --plot took a PNG file and --output named the column: both still
    work for a deprecation period, each with a note on stderr."""
    png = tmp_path / "sweep.png"
    code, stdout, stderr = _run(
        "--vary", "gearbox.ratio=200:600:9", "--vary", "load.start_torque=3.2,3.73",
        "-o", str(tmp_path / "s.csv"), "--plot", str(png), "--output", "end_speed_rad_s",
    )  # fmt: skip
    assert code == 0, stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    said = " ".join(stderr.split())  # notes wrap at the terminal's width
    assert "--output is deprecated: it is --column now" in said
    assert "a file name is deprecated; --plot takes a folder" in said
    assert f"wrote {png}" in stdout


def test_plot_takes_a_folder(tmp_path: Path) -> None:
    code, stdout, stderr = _run(
        "--vary", "gearbox.ratio=200:600:3", "-o", str(tmp_path / "s.csv"),
        "--plot", str(tmp_path / "plots"), "--column", "end_speed_rad_s",
    )  # fmt: skip
    assert code == 0, stderr
    written = tmp_path / "plots" / "sweep_end_speed_rad_s.png"
    assert written.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"wrote {written}" in stdout
    assert not stderr


def exact_time(t: float, ratio: float, ts: float) -> float:
    """The exact quasi-static time by hand: with a linear spring the speed is linear in
    the angle (Eq. 5), so t = travel * ln(ws / we) / (ws - we), ws and we by Eq. 8-9."""
    bd = 1.3e-4
    becd = (bd * (1.0 - 0.004 * (t - 25.0)) + 0.26 * bd) * ratio**2
    ws = (ts - friction(t, ratio)) / becd
    we = (1.58 - friction(t, ratio)) / becd
    return 1.57 * math.log(ws / we) / (ws - we)


def _sweep(*varies: str, methods: tuple[str, ...] = ("paper", "exact")) -> Any:
    import tomllib

    from ecdsim.sweeps import run_sweep

    parsed = [parse_vary(v) for v in varies]
    raw = tomllib.loads(PAPER.read_text(encoding="utf-8"))
    return run_sweep(raw, str(PAPER), parsed, design(parsed), None, methods)


def test_plot_draws_the_exact_method_one_line_per_level_stalls_marked() -> None:
    """Issue 26 item 1: the plot's data series, read back from the figure, are the exact
    method's times (by hand), one line per start torque in a panel per temperature, and
    the ratios where the -40 degC deployment stalls are crosses, not gaps."""
    result = _sweep("gearbox.ratio=200:600:21", "load.start_torque=3.2,3.73,4.2")
    fig = result.plot()
    assert "by the exact method" in " ".join(fig.get_suptitle().split())
    axes = [ax for ax in fig.axes if ax.get_title()]
    assert [ax.get_title() for ax in axes] == ["T = -40 degC", "T = 25 degC", "T = 100 degC"]
    ratios = np.linspace(200.0, 600.0, 21)
    for ax, temp in zip(axes, (-40.0, 25.0, 100.0), strict=True):
        lines = [line for line in ax.get_lines() if line.get_linestyle() == "-"]
        assert [line.get_label() for line in lines] == ["3.2 N*m", "3.73 N*m", "4.2 N*m"]
        for line, ts in zip(lines, (3.2, 3.73, 4.2), strict=True):
            x = np.asarray(line.get_xdata(), dtype=float)
            y = np.asarray(line.get_ydata(), dtype=float)
            np.testing.assert_allclose(x, ratios)
            # A stall (least spring torque 1.58 N*m at most the friction) is no point.
            deploys = np.array([friction(temp, n) for n in ratios]) < 1.58
            assert np.all(np.isnan(y[~deploys]))
            hand = [exact_time(temp, n, ts) for n in ratios[deploys]]
            # The exact solver's own accuracy is ~1e-12 relative; the hand formula's
            # rounding is far smaller: 1e-9 leaves room for neither to matter.
            np.testing.assert_allclose(y[deploys], hand, rtol=1e-9)
        crosses = [line for line in ax.get_lines() if line.get_marker() == "x"]
        stalled = ratios[np.array([friction(temp, n) for n in ratios]) >= 1.58]
        if temp == -40.0:
            # 533.4 = (1.58 - FS(-40)) / FT(-40): 540 to 600, for each start torque.
            np.testing.assert_allclose(stalled, [540.0, 560.0, 580.0, 600.0])
            assert len(crosses) == 3
            for line in crosses:
                np.testing.assert_allclose(np.asarray(line.get_xdata(), dtype=float), stalled)
        else:
            assert stalled.size == 0
            assert not crosses
    # The point: N = 380, 3.73 N*m, -40 degC is 48.13 s (exact), not the paper's 34.
    line = [ln for ln in axes[0].get_lines() if ln.get_label() == "3.73 N*m"][0]
    at = int(np.flatnonzero(np.isclose(line.get_xdata(), 380.0))[0])
    assert abs(float(line.get_ydata()[at]) - 48.13) < 0.005
    legend = fig.legends[0]
    assert legend.get_title().get_text() == "load.start_torque"
    assert "x at the top: stalls (no deployment)" in [t.get_text() for t in legend.get_texts()]


def test_plot_method_and_units_can_be_chosen() -> None:
    result = _sweep("gearbox.ratio=300:400:3")
    fig = result.plot(method="paper", units="us")
    assert "by the paper method" in " ".join(fig.get_suptitle().split())
    (ax,) = fig.axes
    labels = [line.get_label() for line in ax.get_lines()]
    assert labels == ["-40 degF", "77 degF", "212 degF"]  # one line per temperature
    y = np.asarray(ax.get_lines()[0].get_ydata(), dtype=float)
    np.testing.assert_allclose(y, [paper_time(-40.0, n, 3.73) for n in (300, 350, 400)],
                               rtol=1e-12)  # fmt: skip
    with pytest.raises(KeyError, match="'dynamic' is not a method of this sweep"):
        result.plot(method="dynamic")


def test_plot_of_a_latin_hypercube_is_points_against_each_key() -> None:
    import tomllib

    from ecdsim.sweeps import run_sweep

    parsed = [parse_vary("gearbox.ratio=200:700:11"), parse_vary("load.end_torque=1,2")]
    raw = tomllib.loads(PAPER.read_text(encoding="utf-8"))
    result = run_sweep(raw, str(PAPER), parsed, design(parsed, latin=30, seed=1), None, None)
    fig = result.plot()
    assert "every point" in " ".join(fig.get_suptitle().split())
    panels = [ax for ax in fig.axes if ax.get_xlabel()]
    assert [ax.get_xlabel() for ax in panels] == ["gearbox.ratio", "load.end_torque [N*m]"]
    dots = [ln for ln in panels[0].get_lines() if ln.get_marker() == "o"]
    assert len(dots) == 3  # one colour per temperature
    drawn = sum(int(np.isfinite(np.asarray(ln.get_ydata(), dtype=float)).sum()) for ln in dots)
    crosses = sum(
        np.asarray(ln.get_xdata()).size for ln in panels[0].get_lines() if ln.get_marker() == "x"
    )
    assert drawn + crosses == 30 * 3  # every point is drawn or marked as a stall


def test_help_lists_the_options_and_its_example_runs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from tests.helptext import assert_options, read_help, run_example

    runner = CliRunner()
    screen = read_help(runner, app, ["sweep"])
    assert_options(
        screen,
        {
            "--vary": None,
            "--out": "-o",
            "--latin": None,
            "--seed": None,
            "--temperature": "-T",
            "--method": "-m",
            "--plot": None,
            "--column": None,
            "--json": None,
            "--plot-method": None,
            "--units": None,
            "--help": None,
        },
    )
    run_example(runner, app, screen, tmp_path, monkeypatch)
    rows = list(csv.DictReader(io.StringIO((tmp_path / "sweep.csv").read_text("utf-8"))))
    assert len(rows) == 21 * 3 * 3 * 2  # ratios x torques x temperatures x methods
    png = tmp_path / "plots" / "sweep_deployment_time_s.png"
    assert png.read_bytes().startswith(b"\x89PNG")
