"""The vectorised CSV reader agrees with the row-by-row one (issue 12, item 8).

A plain file (no quotes) is read in blocks by NumPy; any file with a quote goes through
the csv module row by row, the reference here. Both must give the same rows, values and
report for a file full of problems, at any block size.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from ecdsim.characterize import csvdata
from ecdsim.characterize.droptest import DROP_TEST_COLUMNS
from tests.conftest import ROOT

HEADER = "temperature [degC],mass [g],radius [mm],angle [deg],time [s],note"
ROWS = [
    "25,3000,50,180,80.9,a",
    "",  # blank line: no data
    "25,4500,50,180,45.2,",
    "25,abc,50,180,31.4,x",  # not a number
    "25,6000,50,180,,y",  # empty
    "25,7500,50,180,nan,z",  # not finite
    "25,9000,50,180,-3,z",  # out of range: time <= 0
    "25,3000,50,180,80.9,b",  # repeats the first row (the note is not read)
    "25,10500,50",  # too few cells
    "25,10500,50,180,16.3,w,extra",  # an extra non-empty cell
    "-400,3000,50,180,80.9,t",  # below absolute zero
    "100,3000,50,180,48.8,",
    " 100 , 4500 , 50 , 180 , 29.0 ,",  # spaces around cells
    ",,,,,",  # only separators: blank
    "100,6000,50,180,20.7,",
    "100,7500,50,180,1e308,",  # finite, but beyond the magnitudes ecdsim accepts
]


def _read(path: Path) -> csvdata.Table:
    return csvdata.read_table(path, DROP_TEST_COLUMNS)


@pytest.mark.parametrize("block", [1, 3, 4, 1000])
def test_block_reader_equals_row_by_row_reader(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, block: int
) -> None:
    plain = tmp_path / "plain.csv"
    plain.write_text("\n".join([HEADER, *ROWS]) + "\n")
    quoted = tmp_path / "quoted.csv"  # one quoted header cell: the csv-module path
    quoted.write_text("\n".join([HEADER.replace(",note", ',"note"'), *ROWS]) + "\n")
    assert csvdata._plain(plain.read_text())
    assert not csvdata._plain(quoted.read_text())
    monkeypatch.setattr(csvdata, "BLOCK_LINES", block)
    fast, reference = _read(plain), _read(quoted)
    assert fast.rows.tolist() == reference.rows.tolist()
    assert fast.rows.tolist() == [2, 4, 13, 14, 16]  # by hand from ROWS (header = row 1)
    for key in reference.values:
        np.testing.assert_array_equal(fast.values[key], reference.values[key])
    assert [b.message() for b in fast.bad_rows] == [b.message() for b in reference.bad_rows]
    assert [b.row for b in fast.bad_rows] == [5, 6, 7, 8, 9, 10, 11, 12, 17]
    assert "outside the magnitudes ecdsim accepts" in fast.bad_rows[-1].reason


def test_windows_line_ends_are_plain(tmp_path: Path) -> None:
    path = tmp_path / "crlf.csv"
    path.write_bytes(("\r\n".join([HEADER, *ROWS]) + "\r\n").encode())
    assert csvdata._plain(path.read_bytes().decode())
    assert _read(path).rows.tolist() == [2, 4, 13, 14, 16]


def test_first_equal_row_against_a_dictionary() -> None:
    # The reference: a dict of tuples in file order, as the row-by-row reader did.
    rng = np.random.default_rng(7)
    array = rng.integers(0, 3, size=(500, 3)).astype(float)
    array[rng.random(500) < 0.1, 0] = -0.0  # -0.0 equals 0.0
    seen: dict[tuple[float, ...], int] = {}
    expected = [seen.setdefault(tuple(row), i) for i, row in enumerate(array.tolist())]
    assert csvdata._first_equal_row(array).tolist() == expected


def test_json_points_compute_the_correction_once(monkeypatch: pytest.MonkeyPatch) -> None:
    # The JSON of a temperature once recomputed the whole correction column for every
    # point (quadratic: a 1,000,000-row log took minutes); it must be computed once.
    from ecdsim.characterize import droptest

    table = droptest.read_drop_test(ROOT / "examples" / "drop_test.csv")
    fit = droptest.reduce_drop_test(table).fits[0]
    calls = 0
    original = droptest.TemperatureFit.correction

    def counted(self: droptest.TemperatureFit) -> Any:
        nonlocal calls
        calls += 1
        return original.fget(self)  # type: ignore[attr-defined]

    monkeypatch.setattr(droptest.TemperatureFit, "correction", property(counted))
    document = fit.to_dict()
    assert len(document["points"]) == fit.rows.size == 6  # 6 masses at -40 degC
    assert calls <= 2  # the points' column, and the max of it in the summary
