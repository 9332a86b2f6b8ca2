"""ecdsim sweep (issue 17 item 4): factorial and Latin hypercube designs, the tidy table.

Asserted numbers come from the paper's equations typed by hand (Eq. 1-4, 8-11, with the
gear ratio and start torque as parameters), not from ecdsim.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

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
    code, _, stderr = _run("--vary", "gearbox.ratio=300,400", "--plot", "x.png", "--output", "z")
    assert code == 2
    assert "--output 'z'" in stderr


def test_plot(tmp_path: Path) -> None:
    png = tmp_path / "sweep.png"
    code, _, stderr = _run(
        "--vary", "gearbox.ratio=200:600:9", "--vary", "load.start_torque=3.2,3.73",
        "-o", str(tmp_path / "s.csv"), "--plot", str(png), "--output", "end_speed_rad_s",
    )  # fmt: skip
    assert code == 0, stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


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
            "--output": None,
            "--json": None,
            "--help": None,
        },
    )
    run_example(runner, app, screen, tmp_path, monkeypatch)
    rows = list(csv.DictReader(io.StringIO((tmp_path / "sweep.csv").read_text("utf-8"))))
    assert len(rows) == 21 * 3 * 3 * 2  # ratios x torques x temperatures x methods
    assert (tmp_path / "sweep.png").read_bytes().startswith(b"\x89PNG")
