"""Catalogues: the shipped example holds the paper's Cc-16 data, CSV equals TOML, and a
malformed entry gets one clear line naming the entry and the field."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from ecdsim.config import ConfigError
from ecdsim.sizing.catalogue import (
    DamperEntry,
    GearboxEntry,
    load_catalogue,
    parse_csv_catalogue,
    parse_toml_catalogue,
)
from tests.conftest import ROOT

EXAMPLE = ROOT / "examples" / "catalogue.toml"


def test_example_holds_the_papers_cc16_data_exactly() -> None:
    catalogue = load_catalogue(EXAMPLE)
    damper = catalogue.damper("CDA Cc-16 damper")
    gearbox = catalogue.gearbox("CDA Cc-16 gearbox")
    # Paper section 6, typed from the paper: BD, FD, FL_T, N, BG/BD, FG, mass, size.
    assert damper.damper.damping_rate == 1.3e-4
    assert damper.damper.coulomb_friction == 7.9e-4
    assert damper.damper.lubrication_friction(0.0) == pytest.approx(2.2e-4, rel=1e-15)
    assert damper.damper.lubrication_friction(100.0) == pytest.approx(
        -2.12e-6 * 100 + 2.2e-4, rel=1e-12
    )
    assert damper.damper.damping_temperature_coefficient == -0.004  # section 2.1
    assert damper.damper.reference_temperature == 25.0
    assert gearbox.ratios == (380.0,)
    assert gearbox.damping_fraction == 0.26
    assert gearbox.coulomb_friction == 4.5e-4
    assert damper.mass == pytest.approx(0.185, rel=1e-15)
    assert damper.length == pytest.approx(0.063, rel=1e-15)
    assert damper.diameter == pytest.approx(0.025, rel=1e-15)
    assert "section 6" in damper.source
    assert not damper.illustrative
    assert not gearbox.illustrative
    # Every other entry is labelled as invented.
    others: list[DamperEntry | GearboxEntry] = [d for d in catalogue.dampers if d is not damper]
    others += [g for g in catalogue.gearboxes if g is not gearbox]
    assert others
    for entry in others:
        assert entry.source == "illustrative, not vendor data"
        assert entry.illustrative


GOOD = """
[[damper]]
name = "D1"
source = "test"
damping_rate = "1e-4 N*m*s/rad"
coulomb_friction = "5e-4 N*m"
lubrication_friction = { slope = "-2e-6 N*m/K", at_0C = "1e-4 N*m" }
max_linear_speed = "3000 rad/s"
mass = "70 g"

[[gearbox]]
name = "G1"
source = "test"
ratios = [100, 250]
damping_rate = "2e-5 N*m*s/rad"
coulomb_friction = "4e-4 N*m"
max_output_torque = "10 N*m"
efficiency = 0.7
lost_motion = "0.25 deg"
mass = "0.05 kg"
"""

GOOD_CSV = """kind,name,source,damping_rate [N*m*s/rad],coulomb_friction [N*m],\
lubrication_slope [N*m/K],lubrication_at_0C [N*m],max_linear_speed [rad/s],mass [kg],\
ratios,max_output_torque [N*m],efficiency,lost_motion [deg]
damper,D1,test,1e-4,5e-4,-2e-6,1e-4,3000,70 g,,,,
gearbox,G1,test,2e-5,4e-4,,,,0.05,100;250,10,0.7,0.25
"""


def test_csv_reads_the_same_catalogue_as_toml() -> None:
    from_toml = parse_toml_catalogue(GOOD, "t.toml")
    from_csv = parse_csv_catalogue(GOOD_CSV, "t.csv")
    assert from_csv.dampers == from_toml.dampers
    assert from_csv.gearboxes == from_toml.gearboxes
    gearbox = from_csv.gearbox("G1")
    assert gearbox.lost_motion == pytest.approx(math.radians(0.25), rel=1e-12)
    assert from_csv.damper("D1").mass == pytest.approx(0.07, rel=1e-12)  # "70 g" cell


@pytest.mark.parametrize(
    ("replace", "message"),
    [
        (('"1e-4 N*m*s/rad"', '"1e-4 N*m"'),
         "damper #1 'D1': damping_rate: '1e-4 N*m' has the wrong dimension"),
        (('coulomb_friction = "5e-4 N*m"\n', ""),
         "damper #1 'D1': coulomb_friction: missing; expected a torque"),
        (("ratios = [100, 250]", "ratios = [100, -250]"),
         "gearbox #1 'G1': ratios.1: -250 must be > 0"),
        (("efficiency = 0.7", "efficiency = 1.7"), "gearbox #1 'G1': efficiency: 1.7 must be"),
        (("lost_motion", "backlash"), "gearbox #1 'G1': backlash: unknown field"),
        (('damping_rate = "2e-5 N*m*s/rad"', 'damping_rate = "2e-5 N*m*s/rad"\n'
          "damping_fraction = 0.2"), "gearbox #1 'G1': (entry): give exactly one of"),
        (('source = "test"\ndamping_rate = "1e-4', 'source = " "\ndamping_rate = "1e-4'),
         "damper #1 'D1': source: source must say where the data come from"),
    ],
)  # fmt: skip
def test_malformed_entry_is_named(replace: tuple[str, str], message: str) -> None:
    with pytest.raises(ConfigError) as raised:
        parse_toml_catalogue(GOOD.replace(*replace, 1), "cat.toml")
    lines = raised.value.problems
    assert any(line.startswith(message) for line in lines), lines
    assert str(raised.value).startswith("cat.toml: ")


def test_every_problem_of_every_entry_is_listed() -> None:
    text = GOOD + GOOD.replace('"D1"', '"D2"').replace('"G1"', '"G2"').replace(
        '"5e-4 N*m"', '"lots"'
    ).replace('"4e-4 N*m"', '"-4e-4 N*m"')
    with pytest.raises(ConfigError) as raised:
        parse_toml_catalogue(text)
    lines = raised.value.problems
    assert any(line.startswith("damper #2 'D2': coulomb_friction:") for line in lines)
    assert any(line.startswith("gearbox #2 'G2': coulomb_friction:") for line in lines)
    assert len(lines) == 2


def test_malformed_csv_row_is_named() -> None:
    bad = GOOD_CSV.replace("damper,D1,test,1e-4", "damper,D1,test,1e-4 N*m")
    with pytest.raises(ConfigError) as raised:
        parse_csv_catalogue(bad, "cat.csv")
    assert raised.value.problems[0].startswith(
        "damper (row 2) 'D1': damping_rate: '1e-4 N*m' has the wrong dimension"
    )
    wrong_kind = GOOD_CSV.replace("gearbox,G1", "gear,G1")
    with pytest.raises(ConfigError, match=r"gear \(row 3\) 'G1': kind must be"):
        parse_csv_catalogue(wrong_kind)
    # A gearbox column filled in on a damper row is an unknown field for a damper.
    mixed = GOOD_CSV.replace("70 g,,,,", "70 g,100,,,")
    with pytest.raises(ConfigError, match=r"damper \(row 2\) 'D1': ratios: unknown field"):
        parse_csv_catalogue(mixed)


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        (GOOD + GOOD.split("[[gearbox]]")[0], "name repeats damper #1"),
        (GOOD.split("[[gearbox]]")[0], "lists no gearbox"),
        ("[[gearbox]]" + GOOD.split("[[gearbox]]")[1], "lists no damper"),
        (GOOD + "\n[extra]\nx = 1\n", "extra: unknown key"),
        ("damper = 3", "expected an array of tables"),
        ("x = ", "not valid TOML"),
    ],
)
def test_catalogue_level_problems(text: str, fragment: str) -> None:
    with pytest.raises(ConfigError) as raised:
        parse_toml_catalogue(text)
    assert any(fragment in line for line in raised.value.problems), raised.value.problems


def test_file_problems(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="catalogue file not found"):
        load_catalogue(tmp_path / "none.toml")
    other = tmp_path / "cat.json"
    other.write_text("{}")
    with pytest.raises(ConfigError, match="expected .toml or .csv"):
        load_catalogue(other)
    csv = tmp_path / "cat.csv"
    csv.write_text(GOOD_CSV)
    assert load_catalogue(csv).source == str(csv)
    with pytest.raises(ConfigError, match="missing the 'kind' column"):
        parse_csv_catalogue("name,source\nD,x\n")
