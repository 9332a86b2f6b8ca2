"""Hostile and careless input at the config edge (issue 12, items 1, 2, 3 and 5).

Unit strings follow a grammar (pint would evaluate them), nesting is bounded before it
is walked, every field is type-checked before use, no pattern is quadratic, and an error
line quotes at most about 80 characters of a bad value. Each case ends in one clear
message and exit code 2, never a traceback.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.config import ConfigError, parse_config
from ecdsim.config.loader import MAX_NESTING, nesting_depth
from ecdsim.config.units import MAX_QUANTITY_LENGTH, MAX_QUOTED, TORQUE, QuantityError
from tests.conftest import PAPER_CONFIG, ROOT

runner = CliRunner()
PAPER = PAPER_CONFIG.read_text()
START = 'start_torque = "3.73 N*m"'


def _problems(text: str) -> list[str]:
    with pytest.raises(ConfigError) as info:
        parse_config(text)
    return info.value.problems


@pytest.mark.parametrize(
    "unit",
    ["N*m/0", "N*m*0**-1", "deg**999999", "__import__('os')", "(N*m)", "N*m + 1", "N*m; 2"],
)
def test_unit_expressions_are_parsed_not_evaluated(unit: str) -> None:
    problems = _problems(PAPER.replace(START, f'start_torque = "3.73 {unit}"'))
    assert len(problems) == 1, problems
    assert problems[0].startswith("load.start_torque: ")
    assert "is not a unit expression" in problems[0]


@pytest.mark.parametrize(
    ("text", "si"),
    [
        # Hand conversions: 1 in*lbf = 0.0254 m * 4.4482216152605 N; 1 ozf = lbf / 16.
        ("3.73 N*m", 3.73),
        ("3.73 N m", 3.73),
        ("1 in*lbf", 0.0254 * 4.4482216152605),
        ("16 in * ozf", 0.0254 * 4.4482216152605),
        ("1 kN*mm", 1.0),
    ],
)
def test_the_grammar_keeps_every_ordinary_unit(text: str, si: float) -> None:
    assert TORQUE.parse(text) == pytest.approx(si, rel=1e-12)  # exact unit factors


def test_unit_grammar_applies_to_csv_headers(tmp_path: Path) -> None:
    rows = (ROOT / "examples" / "drop_test.csv").read_text().splitlines()
    for bad in ("[1/0]", "[deg**999999]", "[__import__('os')]"):
        csv = tmp_path / "bad.csv"
        csv.write_text("\n".join([rows[0].replace("angle [deg]", f"angle {bad}"), *rows[1:]]))
        result = runner.invoke(app, ["fit", "drop-test", str(csv)])
        assert result.exit_code == 2, result.output
        assert "Traceback" not in result.output
        assert "angle" in result.stderr


@pytest.mark.parametrize("depth", [40, 500, 5000])
def test_deep_nesting_is_refused_cleanly(depth: int) -> None:
    text = PAPER + "\n[extra]\nx = " + "[" * depth + "]" * depth + "\n"
    problems = _problems(text)
    assert problems == [f"nested too deeply (at most {MAX_NESTING} levels of tables and lists)"]


def test_nesting_depth_counts_without_recursion() -> None:
    deep: list[object] = []
    node = deep
    for _ in range(100_000):  # far past Python's recursion limit
        child: list[object] = []
        node.append(child)
        node = child
    assert nesting_depth(deep) == MAX_NESTING + 1  # stops counting past the limit
    assert nesting_depth({"a": {"b": [1, 2]}, "c": 3}) == 3


def test_wrong_types_are_reported_not_raised() -> None:
    text = PAPER.replace(
        'temperatures = ["-40 degC", "25 degC", "100 degC"]',
        'temperatures = ["25 degC"]\nmethods = [["exact"]]',
    )
    problems = _problems(text)
    assert problems == [
        "analysis.methods[0]: ['exact'] is not a method; expected one of "
        "['dynamic', 'exact', 'paper']"
    ]


def test_long_values_are_refused_and_quoted_briefly(tmp_path: Path) -> None:
    huge = "3" * 1_000_000
    config = tmp_path / "huge.toml"
    config.write_text(PAPER.replace(START, f'start_torque = "{huge} N*m"'))
    result = runner.invoke(app, ["deploy", str(config)])
    assert result.exit_code == 2
    (line,) = result.stderr.strip().splitlines()
    assert f"at most {MAX_QUANTITY_LENGTH} characters" in line
    # The quote is cut to MAX_QUOTED characters plus a note of the full length; the rest
    # of the line names the file, the key and the expected unit.
    assert len(line) < MAX_QUOTED + 300
    assert f"({len(huge) + len(' N*m')} characters)" in line


def test_long_tolerance_spreads_are_refused() -> None:
    text = (ROOT / "examples" / "paper_cc16_tolerances.toml").read_text()
    assert 'plus_minus = "' in text
    long_digits = "1" * 100_000 + "x %"
    problems = _problems(text.replace('plus_minus = "', f'plus_minus = "{long_digits}', 1))
    assert any(f"at most {MAX_QUANTITY_LENGTH} characters" in p for p in problems), problems


def test_number_pattern_splits_a_digit_run_one_way() -> None:
    # The old pattern \d+\.?\d* can split "111...1" at any of n places, which makes a
    # failed match quadratic; the new one has exactly one way, so a non-matching
    # 150-character run is refused by the grammar, not by a timeout.
    with pytest.raises(QuantityError, match="does not start with a finite number|unit"):
        TORQUE.parse("1" * 150 + "x")


# --- issue 23: the Python API's crashers, fixed where configs are read -------------------


def _nested(depth: int) -> dict[str, object]:
    top: dict[str, object] = {}
    node = top
    for _ in range(depth):
        child: dict[str, object] = {}
        node["a"] = child
        node = child
    return top


def _api_problems(*args: object, **kwargs: object) -> list[str]:
    import ecdsim

    with pytest.raises(ConfigError) as info:
        ecdsim.load(*args, **kwargs)  # type: ignore[arg-type]
    return info.value.problems


def test_a_mapping_nested_5000_deep_is_a_config_error_not_a_recursion_error() -> None:
    # RecursionError (copy.deepcopy) before; files and HTTP bodies stop at MAX_NESTING.
    too_deep = f"nested too deeply (at most {MAX_NESTING} levels of tables and lists)"
    assert _api_problems(_nested(5000)) == [f"config: {too_deep}"]
    # A deep override is refused by the API's own reading of its overrides (naming the
    # key), and by the config layer for any other caller of apply_overrides.
    (line,) = _api_problems(PAPER_CONFIG, overrides={"load.extra": _nested(5000)})
    assert line.startswith("overrides: load.extra.a.a.a")
    from ecdsim.config.overrides import OverrideError, apply_overrides

    with pytest.raises(OverrideError) as info:
        apply_overrides(tomllib.loads(PAPER), {"load.extra": _nested(5000)})
    assert info.value.problems == [f"load.extra: {too_deep}"]
    with pytest.raises(OverrideError) as info:
        apply_overrides(_nested(5000), {})
    assert info.value.problems == [f"config: {too_deep}"]


@pytest.mark.parametrize(
    ("key", "value", "shown"),
    [
        ("gearbox.ratio", 10**400, "1" + "0" * 76 + "... (401 characters)"),
        ("load.start_torque", -(10**400), "-1" + "0" * 75 + "... (402 characters)"),
        ("gearbox.ratio", 10**5000, "an integer of 5001 digits"),  # too long to write out
    ],
    ids=["10**400", "-10**400", "10**5000"],
)
def test_an_integer_beyond_float64_is_a_config_error_naming_the_key(
    key: str, value: int, shown: str
) -> None:
    # OverflowError (int too large to convert to float) before.
    problems = _api_problems(PAPER_CONFIG, overrides={key: value})
    assert problems == [
        f"{key} = {shown}: is outside the magnitudes ecdsim accepts (1e-30 to 1e+30 in SI "
        "units, or 0)"
    ]
    # The same integer inside a mapping is read by the config's own fields.
    document = tomllib.loads(PAPER)
    document["gearbox"]["ratio"] = value
    (line,) = _api_problems(document)
    assert line == (
        f"gearbox.ratio: {shown} is outside the magnitudes ecdsim accepts (1e-30 to 1e+30 in "
        "SI units, or 0); expected a dimensionless number (a plain number, e.g. 380)"
    )


def test_an_override_key_that_is_not_a_string_is_named() -> None:
    from ecdsim.config.overrides import OverrideError, apply_overrides

    with pytest.raises(OverrideError) as info:
        apply_overrides(tomllib.loads(PAPER), {1: 2})  # type: ignore[dict-item]
    assert info.value.problems == ["1: not a config key (expected e.g. gearbox.ratio)"]


@pytest.mark.parametrize("rtol", ["1e-30", "0", "9e-14", "0.2"])
def test_an_integrator_tolerance_it_cannot_meet_is_refused(rtol: str) -> None:
    # rtol = 1e-30 was accepted and the dynamic method stopped at 1e-13 s ("horizon").
    text = PAPER.replace("[analysis]", f"[analysis]\nrtol = {rtol}")
    why = " (below it the integrator chases float64 round-off)" if float(rtol) < 1e-13 else ""
    assert _problems(text) == [
        f"analysis.rtol: {rtol} must be in [1e-13, 0.1]{why}; expected a dimensionless number "
        "(a plain number, e.g. 380)"
    ]


@pytest.mark.parametrize("rtol", ["1e-13", "0.1"])
def test_the_tolerance_bounds_are_accepted(rtol: str) -> None:
    parse_config(PAPER.replace("[analysis]", f"[analysis]\nrtol = {rtol}"))


def test_the_library_sweep_design_applies_the_seed_rule_too() -> None:
    from ecdsim.sweeps import SweepError, design, parse_vary

    with pytest.raises(SweepError) as info:
        design([parse_vary("gearbox.ratio=300:400:3")], 5, -1)
    assert info.value.problems == [
        "--seed -1: expected a whole number from 0 to 9223372036854775807 (2**63 - 1)"
    ]
    assert len(design([parse_vary("gearbox.ratio=300:400:3")], 5, 2**63 - 1)) == 5


def test_the_api_reads_a_file_with_a_4400_digit_integer_as_one_line(tmp_path: Path) -> None:
    # ecdsim.load read files with tomllib directly: int() refused the digit run with a bare
    # ValueError naming no line. It now reads through the loader's parse_toml, as the CLI.
    path = tmp_path / "long.toml"
    path.write_text(PAPER.replace("ratio = 380", "ratio = " + "3" * 4400, 1))
    (line,) = _api_problems(path)
    assert "an integer of 4,400 digits" in line
    assert "ratio" in line
