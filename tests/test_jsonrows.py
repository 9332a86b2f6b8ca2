"""The streaming JSON writer: the same document as json.dumps, whatever the block size."""

from __future__ import annotations

import io
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim import jsonrows
from ecdsim.cli.app import app
from ecdsim.jsonrows import RowTable, iter_json, write_json

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def _document() -> dict[str, Any]:
    first = RowTable(
        {
            "row": np.array([2, 3, 5]),
            "x": np.array([0.1, math.nan, -1e-300]),
            "flag": np.array([True, False, True]),
        }
    )
    return {
        "title": "two tables, one empty, nested at different depths",
        "temperatures": [
            {"temperature_C": -40.0, "points": first},
            {"temperature_C": 25.0, "points": RowTable({"row": np.array([], dtype=int)})},
        ],
        "deeper": {"still": {"points": RowTable({"y": np.arange(7) / 3.0})}},
        "after": [1, 2],
    }


def _plain(value: Any) -> Any:
    """The document with each table replaced by its records: what json.dumps would see."""
    if isinstance(value, RowTable):
        return value.records()
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_plain(v) for v in value]
    return value


@pytest.mark.parametrize("block_rows", [1, 2, 3, 16_384])
def test_streamed_text_reads_back_as_the_records(
    block_rows: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Several block sizes, so that rows split across blocks are joined correctly.
    monkeypatch.setattr(jsonrows, "BLOCK_ROWS", block_rows)
    document = _document()
    text = "".join(iter_json(document))
    assert json.loads(text) == _plain(document)
    # NaN is written as null (JSON has no NaN), floats keep their repr exactly
    assert json.loads(text)["temperatures"][0]["points"][1]["x"] is None
    assert json.loads(text)["deeper"]["still"]["points"][1]["y"] == 1.0 / 3.0


def test_records_turn_nan_into_none_and_keep_types() -> None:
    records = RowTable({"a": np.array([1.5, math.nan]), "b": np.array([1, 2])}).records()
    assert records == [{"a": 1.5, "b": 1}, {"a": None, "b": 2}]
    assert isinstance(records[1]["b"], int)


def test_infinity_is_refused_inside_and_outside_tables() -> None:
    with pytest.raises(ValueError, match="'x'"):
        "".join(iter_json({"p": RowTable({"x": np.array([1.0, math.inf])})}))
    with pytest.raises(ValueError, match="JSON compliant"):
        "".join(iter_json({"v": math.inf}))


def test_columns_of_unequal_length_are_refused() -> None:
    with pytest.raises(ValueError, match="differ in length"):
        RowTable({"a": np.arange(2), "b": np.arange(3)}).records()


def test_write_json_ends_with_a_newline() -> None:
    out = io.StringIO()
    write_json({"p": RowTable({"a": np.arange(2)})}, out.write)
    assert out.getvalue().endswith("]\n}\n")
    assert json.loads(out.getvalue()) == {"p": [{"a": 0}, {"a": 1}]}


def test_fit_drop_test_json_lists_every_point_as_the_library_does() -> None:
    # The CLI streams the points; what it prints must read back as the library's own
    # records-form document (the other keys checked in test_characterize_droptest.py).
    from ecdsim.characterize.droptest import fit_drop_test

    csv = EXAMPLES / "drop_test.csv"
    result = CliRunner().invoke(app, ["fit", "drop-test", str(csv), "--json"])
    assert result.exit_code == 0, result.output
    printed = json.loads(result.stdout)
    expected = fit_drop_test(csv, reference_temperature=25.0).to_dict()
    for got, want in zip(printed["temperatures"], expected["temperatures"], strict=True):
        assert got["points"] == want["points"]
        assert len(got["points"]) == got["n_points"]


def test_repeated_values_keep_their_exact_text_including_the_sign_of_zero() -> None:
    # A column of few distinct values takes the format-each-value-once path; -0.0 and
    # 0.0 compare equal but are written differently by json.dumps, and must stay so.
    values = np.array([0.0, -0.0, math.nan, 1.5, 0.1] * 8)
    text = "".join(iter_json({"p": RowTable({"v": values, "k": np.arange(40) % 2 == 0})}))
    assert text.count('"v": -0.0') == 8
    assert text.count('"v": 0.0') == 8
    assert text.count('"v": null') == 8
    assert text.count('"v": 0.1') == 8
    read = json.loads(text)["p"]
    assert [math.copysign(1.0, r["v"]) for r in read[:2]] == [1.0, -1.0]
    assert [r["k"] for r in read[:3]] == [True, False, True]


def test_a_log_with_many_bad_rows_lists_twenty_and_counts_the_rest(tmp_path: Path) -> None:
    # 25 exact repeats of one row: 20 listed on stderr, the other 5 counted in one line,
    # and all 25 in the JSON document.
    lines = (EXAMPLES / "drop_test.csv").read_text().splitlines()
    log = tmp_path / "repeats.csv"
    log.write_text("\n".join([*lines, *([lines[1]] * 25)]) + "\n")
    result = CliRunner().invoke(app, ["fit", "drop-test", str(log), "--json"])
    assert result.exit_code == 0, result.output
    listed = [line for line in result.stderr.splitlines() if "repeats row 2 exactly" in line]
    assert len(listed) == 20
    assert "warning: 5 more rows with problems not shown" in result.stderr
    assert len(json.loads(result.stdout)["bad_rows"]) == 25
