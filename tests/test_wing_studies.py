"""Sweeps and Monte Carlo over a wing file's keys (issue 25 item 7; docs/wing.md, studies).

Every figure a study reports is checked against the wing's solver run directly on a file
written with the same value (the text edited here, not by ecdsim's key setter): the study
must set the key it names, in the unit it says, and gather what the solver returns.
"""

from __future__ import annotations

import csv
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.config.loader import parse_toml
from ecdsim.config.wing_schema import load_wing_config, parse_wing_config
from ecdsim.montecarlo import wing as wing_study
from ecdsim.wing.solver import deploy_wing

ROOT = Path(__file__).resolve().parents[1]
# Three undamped hinges in 1 g: breakaways, the root and outer latch, the middle sticks
# (a solve takes milliseconds).
BASE = ROOT / "validation" / "configs" / "wing_three_panel_stick_slip_ground_test.toml"
TOLERANCES = """
[tolerances]
seed = 11
[tolerances.quantities]
"wing.panels[2].mass" = { distribution = "normal", sigma = "4 %" }
"wing.hinges[0].friction.at_0C" = { distribution = "uniform", plus_minus = "0.05 N*m" }
"""


def _edited(text: str, panel_mass: float | None = None, root_friction: float | None = None) -> str:
    """The base file's text with the third panel's mass [kg] and the root hinge's
    friction at 0 degC [N*m] replaced, by editing the lines themselves."""
    if panel_mass is not None:
        masses = [m.start() for m in re.finditer(r'^mass = "1\.0 kg"$', text, re.M)]
        at = masses[2]
        text = text[:at] + f'mass = "{panel_mass!r} kg"' + text[at + len('mass = "1.0 kg"') :]
    if root_friction is not None:
        old = 'friction = { slope = "0 N*m/K", at_0C = "1.3 N*m" }'
        assert text.count(old) == 1
        text = text.replace(
            old, f'friction = {{ slope = "0 N*m/K", at_0C = "{root_friction!r} N*m" }}'
        )
    return text


def _direct(text: str) -> dict[str, float]:
    config = parse_wing_config(text, "edited.toml")
    case = deploy_wing(config.wing, [25.0], rtol=config.rtol).cases[0]
    out = {"stuck": float(len(case.stuck_hinges))}
    for latch in case.latches:
        out[f"hinge_{latch.hinge}_latch_time_s"] = latch.time
        out[f"hinge_{latch.hinge}_latch_speed_rad_s"] = latch.speed
    return out


def test_sweep_value_is_the_direct_solve_of_the_edited_file(tmp_path: Path) -> None:
    out = tmp_path / "sweep.csv"
    result = CliRunner().invoke(
        app,
        [
            "sweep",
            str(BASE),
            "--vary",
            "wing.panels[2].mass=0.8,1.2",
            "--vary",
            "wing.hinges[0].friction.at_0C=1.25 N*m",
            "-o",
            str(out),
        ],
    )
    assert result.exit_code == 0, result.output
    rows = list(csv.DictReader(out.read_text().splitlines()))
    assert [r["wing.panels[2].mass_kg"] for r in rows] == ["0.8", "1.2"]
    assert {r["wing.hinges[0].friction.at_0C_Nm"] for r in rows} == {"1.25"}
    text = BASE.read_text()
    for row, mass in zip(rows, (0.8, 1.2), strict=True):
        direct = _direct(_edited(text, panel_mass=mass, root_friction=1.25))
        # The same solver on the same numbers: equal to rounding (1e-12 relative).
        for name in (
            "hinge_0_latch_time_s",
            "hinge_0_latch_speed_rad_s",
            "hinge_2_latch_speed_rad_s",
        ):
            assert float(row[name]) == pytest.approx(direct[name], rel=1e-12)
        assert float(row["stuck_hinges"]) == direct["stuck"] == 1.0
        assert row["hinge_1_stuck"] == "True"
        assert row["latched"] == "False"
        assert row["deployment_time_s"] == ""  # NaN: the middle hinge never latches
    # ...and the varied mass matters: the outer latch differs between the two points.
    assert float(rows[0]["hinge_2_latch_speed_rad_s"]) != float(
        rows[1]["hinge_2_latch_speed_rad_s"]
    )


@pytest.mark.parametrize(
    ("vary", "message"),
    [
        ("wing.panels[5].mass=1", "wing.panels[5].mass: wing.panels has no entry 5 (3 entries)"),
        ("wing.hinges[0].colour=1", "wing.hinges[0].colour: not a quantity of a wing file"),
        ("gearbox.ratio=200", "gearbox.ratio: not a key of a wing file"),
        ("wing.panels[0].mass=-1", "wing.panels[0].mass: '-1.0 kg' must be > 0"),
    ],
)
def test_sweep_refuses_a_bad_wing_key_in_one_line(vary: str, message: str) -> None:
    result = CliRunner().invoke(app, ["sweep", str(BASE), "--vary", vary, "--json"])
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, lines
    assert message in lines[0]


def _study(samples: int, seed: int | None = None) -> wing_study.WingStudy:
    text = BASE.read_text() + TOLERANCES
    config = parse_wing_config(text, str(BASE))
    return wing_study.run(config, parse_toml(text, "study"), samples, seed=seed)


def test_monte_carlo_is_reproducible_and_its_mean_is_the_direct_solves() -> None:
    study = _study(12)
    again = _study(12)
    assert study.seed == again.seed == 11
    assert json.dumps(study.summary()) == json.dumps(again.summary())
    other = _study(12, seed=12)
    assert not np.array_equal(other.values, study.values)
    # The samples' values follow the tolerances: each within its reach about the nominal.
    assert np.all(np.abs(study.values[:, 0] - 1.0) <= 6 * 0.04 + 1e-12)
    assert np.all(np.abs(study.values[:, 1] - 1.3) <= 0.05 + 1e-12)
    text = BASE.read_text()
    direct = [
        _direct(_edited(text, panel_mass=float(m), root_friction=float(f))) for m, f in study.values
    ]
    case = study.summary()["cases"][0]
    for j in (0, 2):
        name = f"hinge_{j}_latch_speed_rad_s"
        mean = float(np.mean([d[name] for d in direct]))
        # The same solves: the mean to rounding (1e-12 relative).
        assert case["hinges"][j]["latch_speed_rad_s"]["mean"] == pytest.approx(mean, rel=1e-12)
    assert case["hinges"][1]["stuck"]["count"] == sum(1 for d in direct if d["stuck"] == 1.0)
    assert case["not_latched"]["count"] == 12  # the middle hinge sticks in every sample
    assert math.isinf(study.column("deployment_time_s", 25.0)[0])


def test_monte_carlo_cli_writes_its_table_and_summary(tmp_path: Path) -> None:
    config = tmp_path / "wing.toml"
    config.write_text(BASE.read_text() + TOLERANCES)
    out = tmp_path / "run"
    result = CliRunner().invoke(
        app, ["montecarlo", str(config), "-n", "6", "--out", str(out), "--json"]
    )
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert summary["samples"] == 6
    assert summary["seed"] == 11
    assert json.loads((out / "summary.json").read_text()) == summary
    rows = list(csv.DictReader((out / "samples.csv").read_text().splitlines()))
    assert len(rows) == 6
    assert "wing.panels[2].mass_kg" in rows[0]
    assert (out / "plots" / "latch_speed_hinge_0.png").stat().st_size > 0


@pytest.mark.parametrize(
    ("tolerance", "message"),
    [
        (
            '"wing.panels[2].mass" = { distribution = "uniform", plus_minus = "1.5 kg" }',
            "tolerances.quantities.wing.panels[2].mass.plus_minus = '1.5 kg': the uniform "
            "spread reaches -0.5",
        ),
        (
            '"wing.hinges[0].latch.stiffness" = { distribution = "normal", sigma = "1 %" }',
            "tolerances.quantities.wing.hinges[0].latch.stiffness: not set in the file",
        ),
        (
            '"wing.panels[2].mass" = { distribution = "normal", sigma = "1 N*m" }',
            "has the wrong dimension",
        ),
    ],
)
def test_monte_carlo_refuses_bad_tolerances_in_one_line(
    tmp_path: Path, tolerance: str, message: str
) -> None:
    config = tmp_path / "wing.toml"
    config.write_text(BASE.read_text() + "\n[tolerances]\n[tolerances.quantities]\n" + tolerance)
    result = CliRunner().invoke(
        app, ["montecarlo", str(config), "-n", "4", "--out", str(tmp_path / "o")]
    )
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, lines
    assert message in lines[0]


def test_montecarlo_refuses_the_single_hinge_run_options(tmp_path: Path) -> None:
    config = tmp_path / "wing.toml"
    config.write_text(BASE.read_text() + TOLERANCES)
    result = CliRunner().invoke(
        app, ["montecarlo", str(config), "-n", "4", "--workers", "2", "--resume", "-m", "paper"]
    )
    assert result.exit_code == 2
    assert len(result.stderr.strip().splitlines()) == 3


def test_the_base_file_is_unchanged_by_a_study() -> None:
    # The key setter copies the document: the file's own wing is the nominal one.
    text = BASE.read_text() + TOLERANCES
    before = load_wing_config(BASE).wing
    _study(2)
    assert parse_wing_config(text, "again").wing == before


def test_a_wing_key_given_to_a_single_hinge_sweep_is_named() -> None:
    paper = ROOT / "examples" / "paper_cc16.toml"
    result = CliRunner().invoke(
        app, ["sweep", str(paper), "--vary", "wing.panels[0].mass=1", "--json"]
    )
    assert result.exit_code == 2
    assert result.stderr.strip() == (
        f"error: --vary wing.panels[0].mass: a wing file's key path, but {paper} is a single "
        "hinge's file (its keys: gearbox.ratio, load.inertia, ...; docs/config.md)"
    )
