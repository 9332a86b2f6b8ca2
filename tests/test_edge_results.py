"""Results at the edges of the parameter space (issue 12, items 4 and 7).

An input whose derived quantities overflow is named in a one-line error; a damping rate
so small that the speed overflows is a flagged "not solved" case, not an infinite
number; a mechanism that cannot start reports no speed it never reached.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.config import parse_config
from ecdsim.deployment import ModelDomainError, predict
from ecdsim.model import DeploymentSystem
from tests import hand
from tests.conftest import PAPER_CONFIG

runner = CliRunner()
PAPER = PAPER_CONFIG.read_text()


def _with_gearbox(**changes: Any) -> DeploymentSystem:
    """The paper example with gearbox fields replaced, built past the config's limits."""
    system = parse_config(PAPER).system
    gearbox = dataclasses.replace(system.ecd.gearbox, **changes)
    return dataclasses.replace(system, ecd=dataclasses.replace(system.ecd, gearbox=gearbox))


@pytest.mark.parametrize(
    ("line", "new", "key"),
    [
        ("ratio = 380", "ratio = 1e200", "gearbox.ratio"),
        ("damping_fraction = 0.26 ", "damping_fraction = 1e308 ", "gearbox.damping_fraction"),
        ('start_torque = "3.73 N*m"', 'start_torque = "1e308 N*m"', "load.start_torque"),
        ("ratio = 380", "ratio = 2e-160", "gearbox.ratio"),
    ],
)
def test_extreme_inputs_are_refused_by_name(tmp_path: Path, line: str, new: str, key: str) -> None:
    # At the edge: magnitudes outside 1e-30..1e30 (SI) are refused before any product of
    # them (BT_T * N**2, Eq. 3) can overflow or underflow.
    assert line in PAPER
    config = tmp_path / "extreme.toml"
    config.write_text(PAPER.replace(line, new))
    result = runner.invoke(app, ["deploy", str(config), "--json"])
    assert result.exit_code == 2
    (message,) = result.stderr.strip().splitlines()
    assert f"{key}: " in message
    assert "is outside the magnitudes ecdsim accepts (1e-30 to 1e+30 in SI units, or 0)" in message


@pytest.mark.parametrize(
    ("changes", "key"),
    [
        ({"ratio": 1e200}, "gearbox.ratio"),
        ({"damping_fraction": 1e308}, "gearbox.damping_fraction"),
    ],
)
def test_overflowing_models_are_named_by_predict(changes: dict[str, float], key: str) -> None:
    # Past the config (a model built in code): predict still names the input.
    with pytest.raises(ModelDomainError) as info:
        predict(_with_gearbox(**changes), [25.0])
    assert info.value.key == key
    assert "overflow to infinity" in str(info.value)


def test_subnormal_damping_is_not_solved_rather_than_infinite() -> None:
    # N = 2e-160 (a model built in code): BECD = BT * N^2 = 1.638e-4 * 4e-320, a subnormal
    # ~5e-324, so the Eq. 5 speed 3.73 / 5e-324 overflows. Flagged, and the JSON valid.
    prediction = predict(_with_gearbox(ratio=2e-160), [25.0])
    case = prediction.to_dict()["cases"][0]
    assert 0.0 < case["damping_rate_Nms_per_rad"] < 1e-300
    assert case["exact"]["solved"] is False
    assert case["paper"]["solved"] is False
    assert "Infinity" not in json.dumps(prediction.to_dict())


def test_a_rising_spring_that_cannot_start_reaches_no_speed() -> None:
    # Start torque 0.5 N*m is below the 25 degC friction FECD + FS = 1.0047 N*m: it cannot
    # start, although the end torque (3 N*m) would drive it at (3 - 1.0047) / BECD.
    text = PAPER.replace('start_torque = "3.73 N*m"', 'start_torque = "0.5 N*m"').replace(
        'end_torque = "1.58 N*m"', 'end_torque = "3 N*m"'
    )
    config = parse_config(text)
    prediction = predict(config.system, [25.0])
    friction = hand.fecd(25.0) + hand.fs(25.0)
    assert 0.5 < friction < 3.0  # the premise of the case
    for solution in prediction.solutions.values():
        assert bool(solution.stalled[0])
        assert float(solution.stall_angle[0]) == 0.0
        assert float(solution.max_speed[0]) == 0.0


def test_a_falling_spring_that_stalls_keeps_its_start_speed_as_peak() -> None:
    # End torque 1.2 N*m below the -40 degC friction: stalls mid-travel; the peak speed
    # is the start speed (Ts - F) / BECD, reached at release (hand.py, Eq. 8).
    text = PAPER.replace('end_torque = "1.58 N*m"', 'end_torque = "1.2 N*m"')
    config = parse_config(text)
    prediction = predict(config.system, [-40.0])
    expected = (hand.TS - hand.fecd(-40.0) - hand.fs(-40.0)) / hand.becd(-40.0)
    for solution in prediction.solutions.values():
        assert bool(solution.stalled[0])
        assert float(solution.max_speed[0]) == pytest.approx(expected, rel=1e-12)
