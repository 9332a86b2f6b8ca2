"""Drive-test reduction (issue 28, item 4), against hand calculations.

The bench reads spring - friction opening and spring + friction closing, so on exact data
the reduction must return the spring and the friction typed here, the available torque
``min(spring - friction)`` and, over temperature, the friction line that made the data.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim.characterize.drivetest import fit_drive_test
from ecdsim.cli.app import app
from ecdsim.config import load_config
from tests.conftest import ROOT
from tests.test_qualification_examples import DRIVE_TEST

runner = CliRunner()
# Interpolation and least squares of exact linear data: rounding only.
TIGHT = 1e-9


def write_test(
    tmp_path: Path,
    temperatures: tuple[float, ...] = (25.0,),
    opening_step: float = 2.0,
    closing_step: float = 3.0,
    offset: float = 0.0,
    spring: Callable[[float], float] = lambda phi: 3.73 - 2.15 * phi / 90.0,
    friction: Callable[[float, float], float] = lambda phi, t: (
        (0.58 - 0.0044 * t) * (1.0 + 0.002 * phi)
    ),
) -> Path:
    """A drive test without noise: opening then closing, each run on its own grid."""
    rows = ["temperature [degC],angle [deg],torque [N*m]"]
    for t in temperatures:
        up = np.arange(0.0, 90.0 + 1e-9, opening_step)
        down = np.arange(90.0, -1e-9, -closing_step)
        for phi in map(float, up):
            rows.append(f"{t!r},{phi + offset!r},{float(spring(phi) - friction(phi, t))!r}")
        for phi in map(float, down):
            rows.append(f"{t!r},{phi + offset!r},{float(spring(phi) + friction(phi, t))!r}")
    path = tmp_path / "drive.csv"
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


def test_exact_data_give_the_spring_friction_and_available_torque(tmp_path: Path) -> None:
    # Runs on different grids (2 and 3 deg) and a bench angle offset of 5 deg: a linear
    # spring and a linear friction interpolate exactly, the angle is counted from 5 deg.
    result = fit_drive_test(write_test(tmp_path, offset=5.0))
    (curves,) = result.curves
    assert curves.start_angle == pytest.approx(math.radians(5.0), rel=TIGHT)
    assert curves.travel == pytest.approx(math.radians(90.0), rel=TIGHT)
    phi = np.degrees(curves.angle)
    np.testing.assert_allclose(curves.spring, 3.73 - 2.15 * phi / 90.0, rtol=TIGHT)
    np.testing.assert_allclose(curves.friction, 0.47 * (1.0 + 0.002 * phi), rtol=TIGHT)
    assert curves.start_torque.value == pytest.approx(3.73, rel=TIGHT)
    assert curves.end_torque.value == pytest.approx(1.58, rel=TIGHT)
    # The opening torque is smallest at the end: 1.58 - 0.47 * 1.18.
    assert curves.available == pytest.approx(1.58 - 0.47 * 1.18, rel=TIGHT)
    assert curves.available_angle == pytest.approx(math.radians(90.0), rel=TIGHT)
    assert curves.linear_deviation < 1e-12


def test_the_friction_line_over_temperature_is_recovered(tmp_path: Path) -> None:
    path = write_test(tmp_path, (-40.0, 25.0, 100.0), friction=lambda phi, t: 0.58 - 0.0044 * t)
    result = fit_drive_test(path)
    assert result.friction_law is not None
    at_0c, slope = result.friction_law.parameters
    assert slope.value == pytest.approx(-0.0044, rel=TIGHT)
    assert at_0c.value == pytest.approx(0.58, rel=TIGHT)
    available, at_t, _ = result.available
    assert available == pytest.approx(1.58 - 0.756, rel=TIGHT)
    assert at_t == -40.0


def test_a_curved_spring_becomes_a_table(tmp_path: Path) -> None:
    # A spring with a 0.3 N*m bow: the line misses it by more than 2 %, so the -o file
    # holds the table, whose rows are the spring at equal steps of the travel.
    def bowed(phi: float) -> float:
        return 3.73 - 2.15 * phi / 90.0 + 0.3 * math.sin(math.pi * phi / 90.0)

    path = write_test(tmp_path, opening_step=1.0, closing_step=1.0, spring=bowed)
    result = fit_drive_test(path)
    assert result.curves[0].linear_deviation > 0.02
    out = tmp_path / "hinge.toml"
    done = runner.invoke(app, ["fit", "drive-test", str(path), "-o", str(out)])
    assert done.exit_code == 0, done.output
    config = load_config(out)
    spec = config.spec.load
    assert spec.spring_table is not None
    # Rows at 7.5 deg steps fall between the 1 deg grid's points, where linear
    # interpolation errs by at most h^2/8 max|T''| = 0.3 (pi/90)^2 / 8 N*m (h = 1 deg).
    bound = 0.3 * (math.pi / 90.0) ** 2 / 8.0
    for angle, torque in spec.spring_table:
        assert torque == pytest.approx(bowed(math.degrees(angle)), abs=bound)
    assert "warning: at 25 degC the spring departs from its straight line" in done.stderr
    assert "PLACEHOLDER" in out.read_text(encoding="utf-8")


def test_the_example_recovers_the_papers_spring_and_friction() -> None:
    # examples/drive_test.csv: the paper's spring and FS_T with 0.005 N*m reading noise.
    result = fit_drive_test(DRIVE_TEST)
    for curves in result.curves:
        low, high = curves.start_torque.ci95 or (0.0, 0.0)
        assert low <= 3.73 <= high
        low, high = curves.end_torque.ci95 or (0.0, 0.0)
        assert low <= 1.58 <= high
        # The mean friction over the grid: FS_T exactly in the data (sin sums to 0 over
        # the symmetric grid), 0.005 N*m noise / sqrt(2 * 46) on it.
        assert curves.mean_friction.value == pytest.approx(
            0.58 - 0.0044 * curves.temperature, abs=4 * 0.005 / math.sqrt(92)
        )
    law = result.friction_law
    assert law is not None
    at_0c, slope = law.parameters
    assert slope.ci95 is not None
    assert at_0c.ci95 is not None
    assert slope.ci95[0] <= -0.0044 <= slope.ci95[1]
    assert at_0c.ci95[0] <= 0.58 <= at_0c.ci95[1]


def test_the_output_config_is_ready_for_the_budget(tmp_path: Path) -> None:
    out = tmp_path / "hinge.toml"
    config = ROOT / "examples" / "paper_cc16_budget.toml"
    done = runner.invoke(
        app, ["fit", "drive-test", str(DRIVE_TEST), "--config", str(config), "-o", str(out),
              "--json"],
    )  # fmt: skip
    assert done.exit_code == 0, done.output
    document = json.loads(done.stdout)
    available = document["available_torque"]["value_Nm"]
    loaded = load_config(out)
    assert loaded.spec.budget is not None
    assert loaded.spec.budget.available == pytest.approx(available, rel=1e-6)
    assert loaded.spec.budget.exclude == ["system_friction"]
    assert loaded.spec.load.start_torque == pytest.approx(
        document["temperatures"][1]["start_torque_Nm"], rel=1e-5
    )
    # The budget from the written file: FS_T left out (the available torque is net of
    # it), the factored sum by hand at -40 degC (design phase: known 1.2, unknown 2).
    shown = runner.invoke(app, ["margin", str(out), "--json", "-T", "-40"])
    assert shown.exit_code == 0, shown.output
    design = next(p for p in json.loads(shown.stdout)["phases"] if p["phase"] == "design")
    case = design["cases"][0]
    names = [t["name"] for t in case["torques"]]
    assert not any("FS_T" in n for n in names)
    expected = sum(t["factor"] * t["value_Nm"] for t in case["torques"])
    assert case["factored_sum_Nm"] == pytest.approx(expected, rel=1e-12)
    assert case["margin"] == pytest.approx(available / expected - 1.0, rel=1e-9)


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("angle [deg],torque [N*m]\n0,1\n", "no temperature could be reduced"),
        ("angle [deg]\n0\n1\n", "missing column 'torque_Nm' (or 'torque [unit]')"),
        (
            "angle [deg],torque [N*s]\n0,1\n",
            "column 'torque [N*s]': unit 'N*s' has the wrong dimension",
        ),
        (
            "angle [deg],torque [N*m]\n0,1\n10,0.9\n20,0.8\n",
            "the closing run has fewer than two distinct angles",
        ),
    ],
)
def test_bad_drive_tests_are_one_line_errors(tmp_path: Path, text: str, fragment: str) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(text, encoding="utf-8")
    done = runner.invoke(app, ["fit", "drive-test", str(path)])
    assert done.exit_code == 2, done.output
    assert fragment in done.stderr
    assert all(line.startswith(("error: ", "warning: ")) for line in done.stderr.splitlines())


def test_bad_options(tmp_path: Path) -> None:
    done = runner.invoke(app, ["fit", "drive-test", str(DRIVE_TEST), "--spring", "curved"])
    assert done.exit_code == 2
    assert "--spring: 'curved' is not a spring form" in done.stderr


def test_the_help_and_its_example(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from tests.helptext import assert_options, read_help, run_example

    screen = read_help(runner, app, ["fit", "drive-test"])
    assert_options(
        screen,
        {"--json": None, "--plot": None, "--output": "-o", "--config": None, "--spring": None,
         "--units": None, "--wide": None, "--plain": None, "--help": None},
    )  # fmt: skip
    run_example(runner, app, screen, tmp_path, monkeypatch)
    assert (tmp_path / "hinge.toml").is_file()


def test_the_plot(tmp_path: Path) -> None:
    done = runner.invoke(app, ["fit", "drive-test", str(DRIVE_TEST), "--plot", str(tmp_path)])
    assert done.exit_code == 0, done.output
    assert (tmp_path / "drive_test.png").read_bytes().startswith(b"\x89PNG")
