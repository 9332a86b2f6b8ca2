"""CSV reading: unit-bearing headers, and every class of bad data reported, none dropped."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from ecdsim.characterize.csvdata import read_table
from ecdsim.characterize.droptest import DROP_TEST_COLUMNS, read_drop_test
from ecdsim.config import ConfigError

HEADER = "temperature_C,mass_kg,radius_m,angle_rad,time_s"
GOOD = ["25,2.0,0.05,3.14,20.0", "25,4.0,0.05,3.14,9.0", "25,6.0,0.05,3.14,6.0"]


def write(tmp_path: Path, lines: list[str], name: str = "data.csv") -> Path:
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def test_si_headers_are_read_as_si(tmp_path: Path) -> None:
    table = read_table(write(tmp_path, [HEADER, *GOOD]), DROP_TEST_COLUMNS)
    assert table.rows.tolist() == [2, 3, 4]  # the header is row 1, as in a spreadsheet
    assert table.values["mass"].tolist() == [2.0, 4.0, 6.0]
    assert table.bad_rows == ()
    assert not table.has("rig_friction")


def test_bracket_units_are_converted_to_si(tmp_path: Path) -> None:
    # 77 degF = 25 degC; 2000 g = 2 kg; 50 mm = 0.05 m; 180 deg = pi rad; 0.5 min = 30 s;
    # 10 N*cm = 0.1 N*m; 100 g*cm^2 = 1e-5 kg*m^2 (hand conversions).
    header = (
        "temperature [degF],mass [g],radius [mm],angle [deg],time [min],rig_friction [N*cm],"
        "rig inertia [g*cm^2]"
    )
    table = read_table(write(tmp_path, [header, "77,2000,50,180,0.5,10,100"]), DROP_TEST_COLUMNS)
    v = table.values
    # Each value passes through one pint conversion factor: a few ulp at most.
    assert v["temperature"][0] == pytest.approx(25.0, rel=1e-12)
    assert v["mass"][0] == pytest.approx(2.0, rel=1e-12)
    assert v["radius"][0] == pytest.approx(0.05, rel=1e-12)
    assert v["angle"][0] == pytest.approx(math.pi, rel=1e-12)
    assert v["time"][0] == pytest.approx(30.0, rel=1e-12)
    assert v["rig_friction"][0] == pytest.approx(0.1, rel=1e-12)
    assert v["rig_inertia"][0] == pytest.approx(1e-5, rel=1e-12)


def test_temperature_headers_may_say_c_or_kelvin(tmp_path: Path) -> None:
    header = "temperature [C],mass_kg,radius_m,angle_rad,time_s"
    table = read_table(write(tmp_path, [header, "25,2,0.05,3,20"]), DROP_TEST_COLUMNS)
    assert table.values["temperature"][0] == 25.0
    header = "temperature [K],mass_kg,radius_m,angle_rad,time_s"
    table = read_table(write(tmp_path, [header, "298.15,2,0.05,3,20"]), DROP_TEST_COLUMNS)
    assert table.values["temperature"][0] == pytest.approx(25.0, abs=1e-12)


def test_unknown_unit_names_the_column_and_the_expected_dimension(tmp_path: Path) -> None:
    header = "temperature_C,mass [blorp],radius_m,angle_rad,time_s"
    with pytest.raises(ConfigError) as info:
        read_table(write(tmp_path, [header, *GOOD]), DROP_TEST_COLUMNS)
    first = info.value.problems[0]
    assert "'mass [blorp]'" in first
    assert "'blorp' is not a unit pint knows" in first
    assert "expected a mass in kg" in first
    # The column is reported once, not also as missing.
    assert not any("missing column 'mass_kg'" in p for p in info.value.problems)


def test_wrong_dimension_names_the_column(tmp_path: Path) -> None:
    header = "temperature_C,mass_kg,radius [s],angle_rad,time_s"
    with pytest.raises(ConfigError) as info:
        read_table(write(tmp_path, [header, *GOOD]), DROP_TEST_COLUMNS)
    assert "column 'radius [s]': unit 's' has the wrong dimension; expected a length in m" in str(
        info.value
    )


def test_missing_columns_are_all_listed(tmp_path: Path) -> None:
    with pytest.raises(ConfigError) as info:
        read_table(write(tmp_path, ["temperature_C,mass_kg", "25,2"]), DROP_TEST_COLUMNS)
    text = str(info.value)
    for name in ("radius_m", "angle_rad", "time_s"):
        assert f"missing column '{name}'" in text
    assert "columns found: 'temperature_C', 'mass_kg'" in text


def test_a_column_given_twice_is_an_error(tmp_path: Path) -> None:
    header = "temperature_C,mass_kg,mass [g],radius_m,angle_rad,time_s"
    with pytest.raises(ConfigError, match="both give the mass"):
        read_table(write(tmp_path, [header, "25,2,2000,0.05,3,20"]), DROP_TEST_COLUMNS)


def test_a_unit_name_with_brackets_is_an_error(tmp_path: Path) -> None:
    header = "temperature_C,mass_kg [g],radius_m,angle_rad,time_s"
    with pytest.raises(ConfigError, match="already carries a unit"):
        read_table(write(tmp_path, [header, *GOOD]), DROP_TEST_COLUMNS)


def test_unknown_columns_are_ignored_with_a_note(tmp_path: Path) -> None:
    table = read_table(
        write(tmp_path, [HEADER + ",operator", *(g + ",ann" for g in GOOD)]), DROP_TEST_COLUMNS
    )
    assert table.notes == ("column 'operator' is not used; ignored",)
    assert table.rows.size == 3


def test_semicolon_files_get_a_hint(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="seems to use ';'"):
        read_table(write(tmp_path, [HEADER.replace(",", ";"), "25;2;0.05;3;20"]), DROP_TEST_COLUMNS)


@pytest.mark.parametrize(
    ("cell", "reason"),
    [
        ("abc", "is not a number"),
        ("", "is empty"),
        ("nan", "is not a finite number"),
        ("NaN", "is not a finite number"),
        ("inf", "is not a finite number"),
        ("0", "must be > 0"),
        ("-3.5", "must be > 0"),
    ],
)
def test_each_bad_time_is_reported_and_its_row_excluded(
    tmp_path: Path, cell: str, reason: str
) -> None:
    lines = [HEADER, GOOD[0], f"25,3.0,0.05,3.14,{cell}", *GOOD[1:]]
    table = read_table(write(tmp_path, lines), DROP_TEST_COLUMNS)
    assert table.rows.tolist() == [2, 4, 5]  # row 3 excluded, every other row kept
    (bad,) = table.bad_rows
    assert (bad.row, bad.column, bad.value) == (3, "time_s", cell)
    assert reason in bad.reason
    assert table.excluded_rows == [3]
    assert bad.message().startswith(f"row 3, column 'time_s': {cell!r} ")


def test_every_bad_cell_of_every_bad_row_is_listed(tmp_path: Path) -> None:
    lines = [
        HEADER,
        GOOD[0],
        "25,x,0.05,3.14,-1",  # two bad cells in one row
        "-300,2.0,0.05,3.14,20",  # below absolute zero
        "25,2.0,0.05",  # too few cells
        GOOD[1],
        "25,2.0,-0.05,3.14,20",  # negative radius
        GOOD[2],
    ]
    table = read_table(write(tmp_path, lines), DROP_TEST_COLUMNS)
    found = [(b.row, b.column) for b in table.bad_rows]
    assert found == [
        (3, "mass_kg"),
        (3, "time_s"),
        (4, "temperature_C"),
        (5, None),
        (7, "radius_m"),
    ]
    assert table.excluded_rows == [3, 4, 5, 7]
    assert table.rows.tolist() == [2, 6, 8]
    assert "below absolute zero" in table.bad_rows[2].reason
    assert "has 3 cells, the header 5" in table.bad_rows[3].reason


def test_duplicate_rows_are_reported_and_the_first_kept(tmp_path: Path) -> None:
    lines = [HEADER, GOOD[0], GOOD[1], GOOD[0], GOOD[2], "25, 2.0 ,0.05,3.14,20.0"]
    table = read_table(write(tmp_path, lines), DROP_TEST_COLUMNS)
    assert table.rows.tolist() == [2, 3, 5]
    assert [(b.row, b.reason) for b in table.bad_rows] == [
        (4, "repeats row 2 exactly"),
        (6, "repeats row 2 exactly"),  # same numbers, other spacing: still a repeat
    ]


def test_blank_lines_and_trailing_empty_cells_are_not_data(tmp_path: Path) -> None:
    lines = [HEADER, "", GOOD[0] + ",", "  ,  ,", GOOD[1], GOOD[2]]
    table = read_table(write(tmp_path, lines), DROP_TEST_COLUMNS)
    assert table.rows.size == 3
    assert table.bad_rows == ()


def test_a_byte_order_mark_is_accepted(tmp_path: Path) -> None:
    path = tmp_path / "bom.csv"
    path.write_bytes(("\ufeff" + "\n".join([HEADER, *GOOD]) + "\n").encode("utf-8"))
    assert read_table(path, DROP_TEST_COLUMNS).rows.size == 3


def test_nothing_usable_raises_with_the_full_report(tmp_path: Path) -> None:
    lines = [HEADER, "25,2.0,0.05,3.14,0", "25,abc,0.05,3.14,5"]
    with pytest.raises(ConfigError) as info:
        read_table(write(tmp_path, lines), DROP_TEST_COLUMNS)
    assert info.value.problems == [
        "row 2, column 'time_s': '0' must be > 0 (it is 0 s in SI); row excluded",
        "row 3, column 'mass_kg': 'abc' is not a number; row excluded",
        "no usable data row remains",
    ]


def test_header_only_and_empty_files(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="no usable data row remains"):
        read_table(write(tmp_path, [HEADER]), DROP_TEST_COLUMNS)
    empty = tmp_path / "empty.csv"
    empty.write_text("", encoding="utf-8")
    with pytest.raises(ConfigError, match="no header row"):
        read_table(empty, DROP_TEST_COLUMNS)


def test_unreadable_files(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="data file not found"):
        read_table(tmp_path / "nope.csv", DROP_TEST_COLUMNS)
    with pytest.raises(ConfigError, match="is a folder"):
        read_table(tmp_path, DROP_TEST_COLUMNS)
    latin = tmp_path / "latin.csv"
    latin.write_bytes(b"temperature [\xb0C],mass_kg\n")
    with pytest.raises(ConfigError, match="not UTF-8"):
        read_table(latin, DROP_TEST_COLUMNS)


def test_a_mass_too_light_to_beat_the_rig_friction_is_excluded(tmp_path: Path) -> None:
    # 0.01 kg * 9.80665 m/s**2 * 0.05 m = 0.0049033 N*m; minus 0.01 N*m rig friction
    # leaves -0.0050967 N*m: this mass cannot turn the damper.
    header = HEADER + ",rig_friction_Nm"
    lines = [header, *(g + ",0.01" for g in GOOD), "25,0.01,0.05,3.14,50,0.01"]
    table = read_drop_test(write(tmp_path, lines))
    (bad,) = table.bad_rows
    assert bad.row == 5
    assert bad.column == "rig_friction_Nm"
    assert "drive torque m*g*r - rig_friction = -0.005097 N*m <= 0" in bad.reason
    assert np.array_equal(table.rows, [2, 3, 4])
