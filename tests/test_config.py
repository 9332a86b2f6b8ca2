"""The TOML configuration: units at the edge, and one clear message per problem."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from ecdsim.config import ConfigError, load_config, parse_config
from ecdsim.config.units import (
    ANGLE,
    DAMPING,
    PER_KELVIN,
    SPEED,
    TEMPERATURE,
    TORQUE,
    QuantityError,
)
from tests import hand
from tests.conftest import PAPER_CONFIG

PAPER_TEXT = PAPER_CONFIG.read_text()


def replace_line(key: str, new: str, text: str = PAPER_TEXT) -> str:
    """The paper config with the first line starting with ``key =`` replaced."""
    pattern = re.compile(rf"^{re.escape(key)} = .*$", re.MULTILINE)
    assert pattern.search(text), key
    return pattern.sub(new, text, count=1)


def problems_of(text: str) -> list[str]:
    with pytest.raises(ConfigError) as info:
        parse_config(text, "test.toml")
    return info.value.problems


def test_paper_config_gives_paper_constants() -> None:
    config = load_config(PAPER_CONFIG)
    assert config.temperatures == (-40.0, 25.0, 100.0)
    state = config.system.ecd.at(25.0)
    assert float(state.ecd_damping_rate) == pytest.approx(hand.becd(25.0), rel=1e-12)
    assert float(state.ecd_friction) == pytest.approx(hand.fecd(25.0), rel=1e-12)
    assert config.methods == ("paper", "exact")
    assert len(config.sha256) == 64


@pytest.mark.parametrize(
    ("kind", "text", "expected"),
    [
        (TORQUE, "12 in*ozf", 12 * 0.0254 * 0.27801385095378125),  # 1 ozf = 0.278014 N
        (TORQUE, "1 kN*mm", 1.0),
        (DAMPING, "1.3e-4 N*m*s/rad", 1.3e-4),
        (DAMPING, "1 mN*m*s/rad", 1e-3),
        (ANGLE, "90 deg", 1.5707963267948966),
        (ANGLE, "0.25 turn", 1.5707963267948966),
        (TEMPERATURE, "25 degC", 25.0),
        (TEMPERATURE, "298.15 K", 25.0),
        (TEMPERATURE, "-40 degF", -40.0),
        (TEMPERATURE, "233.15 K", -40.0),
        (SPEED, "1800 rpm", 188.49555921538757),  # 1800 * 2 pi / 60
        (SPEED, "30 turn/s", 188.49555921538757),
        (PER_KELVIN, "-0.004 / K", -0.004),
        (PER_KELVIN, "-0.004 / degC", -0.004),  # degC in a rate is a difference
        (PER_KELVIN, "-0.4 percent/K", -0.004),
    ],
)
def test_units_are_converted_to_si(kind: object, text: str, expected: float) -> None:
    from ecdsim.config.units import Kind

    assert isinstance(kind, Kind)
    # Unit conversion factors are exact decimal definitions: 1e-12 covers float rounding.
    assert kind.parse(text) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize(
    ("kind", "value", "fragment"),
    [
        (TORQUE, "3.73", "has no unit"),
        (TORQUE, 3.73, "has no unit"),
        (TORQUE, "3.73 N*m*s", "wrong dimension"),
        (TORQUE, "3.73 blorgs", "unit pint does not know"),
        (TORQUE, "inf N*m", "finite number"),
        (TORQUE, "N*m", "finite number"),
        (TORQUE, True, "not a number"),
        (TORQUE, ["3 N*m"], "not a quantity"),
        (TEMPERATURE, "25", "has no unit"),
        (SPEED, "30 Hz", "ambiguous"),  # pint would read 30 rad/s, not 2*pi*30
        (ANGLE, "50 %", "ambiguous"),  # pint would read 0.5 rad
    ],
)
def test_bad_quantities(kind: object, value: object, fragment: str) -> None:
    from ecdsim.config.units import Kind

    assert isinstance(kind, Kind)
    with pytest.raises(QuantityError, match=fragment) as info:
        kind.parse(value)
    assert kind.unit in str(info.value)  # every message names the expected unit


@pytest.mark.parametrize(
    ("key", "line", "expected"),
    [
        # wrong dimension
        (
            "damping_rate",
            'damping_rate = "1.3e-4 N*m"',
            "damper.damping_rate: '1.3e-4 N*m' has the wrong dimension; expected a damping rate "
            "in N*m*s/rad",
        ),
        # negative damping
        (
            "damping_rate",
            'damping_rate = "-1.3e-4 N*m*s/rad"',
            "damper.damping_rate: '-1.3e-4 N*m*s/rad' must be >= 0",
        ),
        # negative ratio
        ("ratio", "ratio = -380", "gearbox.ratio: -380 must be > 0"),
        # zero travel
        ("travel", 'travel = "0 deg"', "load.travel: '0 deg' must be > 0; expected an angle"),
        # non-finite
        ("start_torque", 'start_torque = "nan N*m"', "load.start_torque: 'nan N*m'"),
        ("start_torque", "start_torque = inf", "load.start_torque: inf has no unit"),
        # unknown key
        ("ratio", "ratio = 380\nratoi = 380", "gearbox.ratoi: unknown key (known keys here: "),
        # below absolute zero
        (
            "temperatures",
            'temperatures = ["-300 degC"]',
            "analysis.temperatures[0]: '-300 degC' is below absolute zero",
        ),
        # unknown method
        (
            "temperatures",
            'temperatures = ["25 degC"]\nmethods = ["magic"]',
            "analysis.methods[0]: 'magic' is not a method",
        ),
        # both gearbox damping forms
        (
            "damping_fraction",
            'damping_fraction = 0.26\ndamping_rate = "3e-5 N*m*s/rad"',
            "gearbox: give exactly one of damping_fraction",
        ),
        # half a friction law
        (
            "lubrication_friction",
            'lubrication_friction = { slope = "-2.12e-6 N*m/K" }',
            "damper.lubrication_friction: missing at_0C",
        ),
    ],
)
def test_each_bad_config_class_has_one_clear_message(key: str, line: str, expected: str) -> None:
    problems = problems_of(replace_line(key, line))
    assert len(problems) == 1, problems
    assert problems[0].startswith(expected), problems[0]


def test_missing_keys_name_the_expected_unit() -> None:
    text = replace_line("coulomb_friction", "", PAPER_TEXT)  # the damper's FD
    text = replace_line("travel", "", text)
    problems = problems_of(text)
    assert problems == [
        "damper.coulomb_friction: missing; expected a torque in N*m or compatible units, "
        "e.g. '3.73 N*m'",
        "load.travel: missing; expected an angle in rad or compatible units, e.g. '1.57 rad'",
    ]


def test_every_problem_is_reported_at_once() -> None:
    text = replace_line("ratio", "ratio = 0")
    text = replace_line("damping_rate", 'damping_rate = "1 m"', text)
    text = replace_line("travel", 'travel = "1.57 N*m"', text)
    assert len(problems_of(text)) == 3


def test_missing_sections_and_bad_toml() -> None:
    assert problems_of("") == ["damper: missing", "gearbox: missing", "load: missing"]
    bad = problems_of("[damper\n")
    assert len(bad) == 1
    assert bad[0].startswith("not valid TOML")


def test_wrong_type_of_section() -> None:
    head, _ = PAPER_TEXT.split("[analysis]")
    problems = problems_of("analysis = 5\n" + head)
    assert len(problems) == 1
    assert problems[0].startswith("analysis = 5:"), problems


def test_missing_file_is_a_config_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="not found"):
        load_config(tmp_path / "nope.toml")


@pytest.mark.parametrize(
    ("end", "travel", "radians"),
    [("1.57 rad", "1.57 rad", 1.57), ("90 deg", "90 deg", math.pi / 2.0)],
    ids=["rad", "deg"],
)
def test_spring_table_config(end: str, travel: str, radians: float) -> None:
    # A two-point table ending exactly at the travel is the linear spring of Eq. 7. (A
    # table ending at 90 deg = 1.5708 rad with the paper's 1.57 rad travel is not: the
    # torque at the travel is then 1.5811 N*m, and the time 7.1e-4 shorter.)
    text = replace_line("start_torque", "")
    text = replace_line(
        "end_torque", f'spring_table = [["0 deg", "3.73 N*m"], ["{end}", "1.58 N*m"]]', text
    )
    text = replace_line("travel", f'travel = "{travel}"', text)
    config = parse_config(text)
    assert config.system.load.travel == pytest.approx(radians, rel=1e-15)  # pint: exact pi/180
    from ecdsim.deployment import predict

    result = predict(config.system, [25.0]).solutions["exact"]
    # Log-mean form against the hand ln form: the same closed form, rounding only (1e-12,
    # as in test_solvers).
    expected = hand.exact_time(25.0, travel=radians)
    assert result.deployment_time[0] == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize(
    ("table", "fragment"),
    [
        ('[["0.1 rad", "3 N*m"], ["2 rad", "1 N*m"]]', "must start at angle 0"),
        ('[["0 rad", "3 N*m"], ["1 rad", "1 N*m"]]', "before the travel"),
        ('[["0 rad", "3 N*m"]]', "at least two"),
        ('[["0 rad", "3 N*m"], ["2 rad", "-1 N*m"]]', "must be >= 0"),
    ],
)
def test_bad_spring_tables(table: str, fragment: str) -> None:
    text = replace_line("start_torque", "")
    text = replace_line("end_torque", f"spring_table = {table}", text)
    problems = problems_of(text)
    assert len(problems) == 1
    assert fragment in problems[0]
    assert problems[0].startswith("load")


def test_friction_table_config() -> None:
    text = replace_line(
        "system_friction",
        'system_friction = { table = [["-40 degC", "0.756 N*m"], ["100 degC", "0.14 N*m"]] }',
    )
    config = parse_config(text)
    # Two points on the paper's line: the table reproduces FS_T = -0.0044 T + 0.58.
    law = config.system.load.system_friction
    assert float(law(25.0)) == pytest.approx(0.47, rel=1e-12)
    both = replace_line(
        "system_friction",
        'system_friction = { slope = "-0.0044 N*m/K", at_0C = "0.58 N*m", '
        'table = [["0 degC", "1 N*m"], ["1 degC", "1 N*m"]] }',
    )
    assert "not both" in problems_of(both)[0]


def test_temperature_in_other_units_lands_exactly_on_degc() -> None:
    # A friction table in degF must not make an analysis at -40 degC look extrapolated:
    # -40 degF is -40 degC, though pint's conversion lands a few ulp away.
    assert TEMPERATURE.parse("-40 degF") == pytest.approx(-40.0, abs=1e-12)
    text = replace_line(
        "system_friction",
        'system_friction = { table = [["-40 degF", "0.756 N*m"], ["212 degF", "0.14 N*m"]] }',
    )
    from ecdsim.deployment import predict

    config = parse_config(text)
    prediction = predict(config.system, config.temperatures)
    assert not [w for w in prediction.warnings if w.code == "table_extrapolation"]
