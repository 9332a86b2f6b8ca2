"""What ``ecdsim size`` tells (issue 14, item 7): the recommendation first with its reason,
margins at each temperature with their definitions, unknown masses as '-' with a note.

The catalogues here hold the paper's Cc-16 damper and gearbox data (section 6) under
several gearbox names and masses, so that the performance of each candidate is the
paper's, known by hand (tests/hand.py), and only the masses decide the ranking.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from tests import hand
from tests.conftest import ROOT

runner = CliRunner()
SIZING = ROOT / "examples" / "sizing.toml"

DAMPER = """
[[damper]]
name = "Cc-16 damper"
source = "CDA InterCorp, 'Eddy Current Damper Simulation and Modeling', section 6"
damping_rate = "1.3e-4 N*m*s/rad"
reference_temperature = "25 degC"
damping_temperature_coefficient = "-0.004 / K"
coulomb_friction = "7.9e-4 N*m"
lubrication_friction = { slope = "-2.12e-6 N*m/K", at_0C = "2.2e-4 N*m" }
mass = "0.1 kg"
"""


def gearbox(name: str, ratio: int, mass: str | None) -> str:
    text = f"""
[[gearbox]]
name = "{name}"
source = "CDA InterCorp, 'Eddy Current Damper Simulation and Modeling', section 6"
ratios = [{ratio}]
damping_fraction = 0.26
coulomb_friction = "4.5e-4 N*m"
"""
    return text + (f'mass = "{mass}"\n' if mass else "")


def catalogue(tmp_path: Path, *gearboxes: str) -> Path:
    path = tmp_path / "catalogue.toml"
    path.write_text('title = "test"\n' + DAMPER + "".join(gearboxes), encoding="utf-8")
    return path


def size(tmp_path: Path, *gearboxes: str, extra: tuple[str, ...] = ()) -> tuple[str, dict]:  # type: ignore[type-arg]
    path = catalogue(tmp_path, *gearboxes)
    table = runner.invoke(
        app, ["size", str(SIZING), "--catalog", str(path), *extra], env={"COLUMNS": "200"}
    )
    assert table.exit_code == 0, table.output
    as_json = runner.invoke(app, ["size", str(SIZING), "--catalog", str(path), "--json", *extra])
    assert as_json.exit_code == 0, as_json.output
    return table.stdout, json.loads(as_json.stdout)


def words(text: str) -> str:
    return " ".join(text.split())


# The Cc-16 at 380:1 meets examples/sizing.toml at -40/25/100 degC (times 48.13/26.86/
# 15.41 s in [10, 60] s, paper section 6); at 100:1 BECD falls by (100/380)^2 = 0.069, so
# the time at 100 degC is about 15.41 * 0.069 = 1.07 s < 10 s: it fails.
LIGHT = gearbox("Light", 380, "0.05 kg")
HEAVY = gearbox("Heavy", 380, "0.09 kg")
UNKNOWN = gearbox("Unknown", 380, None)
FAST = gearbox("Fast", 100, "0.01 kg")


def test_the_lightest_passing_candidate_is_recommended_first(tmp_path: Path) -> None:
    stdout, document = size(tmp_path, FAST, HEAVY, UNKNOWN, LIGHT)
    lines = stdout.splitlines()
    # The answer before any table: Light (0.1 + 0.05 kg) against Heavy (0.1 + 0.09 kg).
    assert lines[0].startswith("Recommended: #1 Cc-16 damper + Light 380:1: meets every")
    first = words(stdout.split("┏")[0])
    assert "meets every requirement at -40, 25, 100 degC; mass 0.15 kg" in first
    assert (
        "Why first: the lightest of the 3 that pass: 0.15 kg against 0.19 kg for "
        "#2 Cc-16 damper + Heavy 380:1." in first
    )
    # The torque margin decides the smallest margin at -40 degC: Te / (FECD + FS +
    # BECD * 0.005) - 1 = 0.0635 by hand (docs/sizing.md section 5), shown as +6.3 %.
    expected = hand.TE / (hand.fecd(-40.0) + hand.fs(-40.0) + hand.becd(-40.0) * 0.005) - 1
    assert f"smallest margin {100 * expected:+.1f} % (torque margin >= 0, at -40 degC)" in first
    assert document["recommendation"][0].startswith("Recommended: #1 Cc-16 damper + Light")
    # Unknown mass: '-' in the mass column (not 'unknown'), ranked after every known one,
    # and a note says why.
    row = next(line for line in lines if "Unknown 380:1" in line)
    cells = [c.strip() for c in row.strip("│").split("│")]
    assert cells[:4] == ["3", "Cc-16 damper + Unknown 380:1", "yes", "-"]
    assert "mass '-': unknown (not in the catalogue" in words(stdout)


def test_margins_at_each_temperature_with_their_definitions(tmp_path: Path) -> None:
    stdout, document = size(tmp_path, LIGHT)
    lines = stdout.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("Requirements for #1"))
    rule = next(i for i in range(start, len(lines)) if lines[i].startswith("┡"))
    header = lines[rule - 1]  # the headers' last line (units above sit on their own)
    assert [c.strip() for c in header.strip("┃").split("┃")][:5] == [
        "requirement",
        "result",
        "-40 degC",
        "25 degC",
        "100 degC",
    ]
    rows = {}
    for line in lines[start:]:
        if line.startswith("└"):
            break
        if line.startswith("│"):
            cells = [c.strip() for c in line.strip("│").split("│")]
            rows[cells[0]] = cells
    # By hand from the paper's exact times: t <= 60 s: 60 / t - 1; t >= 10 s: 1 - 10 / t.
    times = [hand.exact_time(t) for t in (-40.0, 25.0, 100.0)]
    assert rows["deployment time <= 60 s"][2:5] == [f"{100 * (60 / t - 1):+.1f} %" for t in times]
    assert rows["deployment time >= 10 s"][2:5] == [f"{100 * (1 - 10 / t):+.1f} %" for t in times]
    # No stall: (least spring torque Te - (FECD + FS)) / (FECD + FS).
    stall = [
        (hand.TE - hand.fecd(t) - hand.fs(t)) / (hand.fecd(t) + hand.fs(t))
        for t in (-40.0, 25.0, 100.0)
    ]
    assert rows["no stall"][2:5] == [f"{100 * m:+.1f} %" for m in stall]
    text = stdout.split("margin, >= 0 where met")[1]
    assert "deployment time <= 60 s: t_max / t - 1" in text
    assert "deployment time >= 10 s: 1 - t_min / t" in text
    assert "no stall: (least spring torque - friction) / friction" in text
    # JSON: each check's margin at every temperature, in the requirement temperatures' order.
    (candidate,) = document["candidates"]
    check = candidate["checks"]["max_deployment_time"]
    assert check["margins"] == pytest.approx([60 / t - 1 for t in times], rel=1e-9)
    assert check["values"] == pytest.approx(times, rel=1e-9)


def test_the_reason_when_masses_do_not_decide(tmp_path: Path) -> None:
    # Only one passes.
    stdout, _ = size(tmp_path, FAST, UNKNOWN)
    assert "Why first: the only one of the 2 candidates that meets every requirement." in words(
        stdout
    )
    # A known mass ranks before an unknown one, whatever the margins.
    stdout, _ = size(tmp_path, UNKNOWN, HEAVY)
    assert (
        "Why first: the only one of the 2 that pass with a known mass; "
        "#2 Cc-16 damper + Unknown 380:1 and the others have no known mass ('-')."
    ) in words(stdout)
    # Identical candidates: nothing but the name separates them, and that is said.
    stdout, _ = size(tmp_path, UNKNOWN, gearbox("Unknown 2", 380, None))
    assert "the two are ordered by name" in words(stdout)
    assert "no passing candidate has a known mass" in words(stdout)


def test_no_passing_candidate_says_so_first(tmp_path: Path) -> None:
    stdout, document = size(tmp_path, FAST)
    # At 100 degC the 100:1 time is about 1.07 s (see above): t >= 10 s fails there.
    assert stdout.startswith("No candidate meets every requirement at -40, 25, 100 degC.")
    assert "Closest: #1 Cc-16 damper + Fast 100:1" in words(stdout)
    assert "(deployment time >= 10 s, at 100 degC)" in words(stdout)
    assert document["recommendation"][0].startswith("No candidate meets every requirement")
